use std::path::Path;

#[test]
fn freeman_sky_lowers_and_validates() {
    let front =
        gdshader::check_file(Path::new("../../fixtures/freeman_sky.gdshader")).expect("readable");
    let lowered = match gdsky_naga::lower(&front) {
        Ok(l) => l,
        Err(diags) => panic!("{}", gdshader::diag::render_human(&front.db, &diags, false)),
    };
    let wgsl = gdsky_naga::to_wgsl(&lowered).expect("wgsl");
    assert!(wgsl.contains("fn sky()"));
    let spv = gdsky_naga::to_spirv(&lowered).expect("spv");
    assert!(!spv.is_empty());
}
