//! Convert time, side by side in one run: gdsky's whole path on the Freeman sky (preprocess,
//! parse, check, lower, validate, WGSL, SPIR-V) against what a user does today — a hand port to
//! GLSL 450 (`freeman_sky.frag.glsl`) through naga's GLSL front end, the same validator and the
//! same back ends.

use criterion::{Criterion, criterion_group, criterion_main};
use gdshader::Loader;
use std::hint::black_box;

const FREEMAN: &str = include_str!("../../../fixtures/freeman_sky.gdshader");
const FREEMAN_GLSL: &str = include_str!("freeman_sky.frag.glsl");

struct NoIncludes;

impl Loader for NoIncludes {
    fn load(&mut self, path: &std::path::Path) -> std::io::Result<Vec<u8>> {
        Err(std::io::Error::new(std::io::ErrorKind::NotFound, path.display().to_string()))
    }
}

fn gdsky_path(src: &str) -> (String, Vec<u32>) {
    let front = gdshader::check_source("freeman_sky.gdshader", src.as_bytes().to_vec(), None, &mut NoIncludes);
    let lowered = gdsky_naga::lower(&front, &gdsky_naga::LowerOptions::default())
        .unwrap_or_else(|_| panic!("the Freeman sky converts"));
    let wgsl = gdsky_naga::to_wgsl(&lowered).expect("wgsl");
    let spirv = gdsky_naga::to_spirv(&lowered).expect("spirv");
    (wgsl, spirv)
}

fn glsl_path(src: &str) -> (String, Vec<u32>) {
    let module = naga::front::glsl::Frontend::default()
        .parse(&naga::front::glsl::Options::from(naga::ShaderStage::Fragment), src)
        .expect("the GLSL port parses");
    let info = gdsky_naga::validator().validate(&module).expect("the GLSL port validates");
    let wgsl = naga::back::wgsl::write_string(&module, &info, naga::back::wgsl::WriterFlags::empty()).expect("wgsl");
    let options = naga::back::spv::Options { lang_version: (1, 3), fake_missing_bindings: true, ..Default::default() };
    let spirv = naga::back::spv::write_vec(&module, &info, &options, None).expect("spirv");
    (wgsl, spirv)
}

fn convert(c: &mut Criterion) {
    let mut group = c.benchmark_group("convert_freeman_sky");
    group.bench_function("gdsky (.gdshader → naga → WGSL + SPIR-V)", |b| b.iter(|| gdsky_path(black_box(FREEMAN))));
    group.bench_function("naga GLSL front end (GLSL 450 port → WGSL + SPIR-V)", |b| {
        b.iter(|| glsl_path(black_box(FREEMAN_GLSL)))
    });
    group.finish();
    // Where gdsky's time goes, stage by stage.
    let mut stages = c.benchmark_group("gdsky_stages");
    stages.bench_function("front end (preprocess + parse + check)", |b| {
        b.iter(|| {
            gdshader::check_source(
                "freeman_sky.gdshader",
                black_box(FREEMAN).as_bytes().to_vec(),
                None,
                &mut NoIncludes,
            )
        })
    });
    let front = gdshader::check_source("freeman_sky.gdshader", FREEMAN.as_bytes().to_vec(), None, &mut NoIncludes);
    stages.bench_function("lower + validate", |b| {
        b.iter(|| {
            gdsky_naga::lower(black_box(&front), &gdsky_naga::LowerOptions::default())
                .map(|l| l.material_size)
                .unwrap_or(0)
        })
    });
    let lowered =
        gdsky_naga::lower(&front, &gdsky_naga::LowerOptions::default()).unwrap_or_else(|_| panic!("converts"));
    stages.bench_function("WGSL + SPIR-V", |b| {
        b.iter(|| {
            (gdsky_naga::to_wgsl(black_box(&lowered)).map(|w| w.len()), gdsky_naga::to_spirv(&lowered).map(|s| s.len()))
        })
    });
    stages.bench_function("WGSL alone (written, re-read, validated)", |b| {
        b.iter(|| gdsky_naga::to_wgsl(black_box(&lowered)).map(|w| w.len()))
    });
    stages.bench_function("SPIR-V alone (written, re-read, validated)", |b| {
        b.iter(|| gdsky_naga::to_spirv(black_box(&lowered)).map(|s| s.len()))
    });
    stages.finish();
}

criterion_group!(benches, convert);
criterion_main!(benches);
