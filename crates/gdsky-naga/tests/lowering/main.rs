//! The lowering's suite, one binary: every valid test shader lowered, validated and snapshotted
//! (`lower`), the f64 evaluation (`f64`), the fuzz corpus replayed (`fuzz_corpus`), the optimising
//! stage and specialisation (`opt`), which uniforms a module reads (`uniforms_read`) and WGSL's
//! own limits (`wgsl_limits`).

mod f64;
mod fuzz_corpus;
mod lower;
mod opt;
mod uniforms_read;
mod wgsl_limits;

/// `source` checked as `test.gdshader`; panics unless the front end accepts it.
fn front(source: &str) -> gdshader::FrontendOutput {
    let front = gdshader::check_source("test.gdshader", source.as_bytes().to_vec(), None, &mut gdshader::FsLoader);
    assert!(front.shader.is_some(), "{:?}", front.diagnostics);
    front
}
