//! One whole convert of the Freeman sky, stage by stage, for a profiler (callgrind counts
//! instructions deterministically on a shared machine): `cargo build --release -p gdsky-naga
//! --example convert_profile`, then `valgrind --tool=callgrind target/release/examples/convert_profile`.
//! Repeats the convert `N` times (the first argument, default 20) so that one-time set-up is small;
//! `convert_profile N glsl` runs the bench's other side, naga's GLSL path, instead;
//! `convert_profile time N FILE…` times each file's convert (median and fastest of N).

use gdshader::Loader;

const FREEMAN: &str = include_str!("../../../fixtures/freeman_sky.gdshader");
const FREEMAN_GLSL: &str = include_str!("../benches/freeman_sky.frag.glsl");

struct NoIncludes;

impl Loader for NoIncludes {
    fn load(&mut self, path: &std::path::Path) -> std::io::Result<Vec<u8>> {
        Err(std::io::Error::new(std::io::ErrorKind::NotFound, path.display().to_string()))
    }
}

/// The bench's other side: naga's GLSL front end, validator and back ends on a GLSL port.
fn glsl(n: usize) {
    let mut bytes = 0;
    for _ in 0..n {
        let options = naga::front::glsl::Options::from(naga::ShaderStage::Fragment);
        let Ok(module) = naga::front::glsl::Frontend::default().parse(&options, FREEMAN_GLSL) else {
            eprintln!("the GLSL port does not parse");
            std::process::exit(1);
        };
        let Ok(info) = gdsky_naga::validator().validate(&module) else {
            eprintln!("the GLSL port does not validate");
            std::process::exit(1);
        };
        let flags = naga::back::wgsl::WriterFlags::empty();
        bytes += naga::back::wgsl::write_string(&module, &info, flags).map(|w| w.len()).unwrap_or(0);
        let options =
            naga::back::spv::Options { lang_version: (1, 3), fake_missing_bindings: true, ..Default::default() };
        bytes += naga::back::spv::write_vec(&module, &info, &options, None).map(|s| s.len()).unwrap_or(0);
    }
    println!("{n} GLSL converts, {bytes} bytes out");
}

/// WGSL and SPIR-V of a lowered shader, each re-read and validated: their bytes.
fn convert_lowered(lowered: &gdsky_naga::Lowered) -> usize {
    gdsky_naga::to_wgsl(lowered).map(|w| w.len()).unwrap_or(0)
        + gdsky_naga::to_spirv(lowered).map(|s| s.len()).unwrap_or(0)
}

/// One whole convert of `source` (its includes refused), as `gdsky convert` emits.
fn convert(name: &str, source: &str) -> usize {
    let front = gdshader::check_source(name, source.as_bytes().to_vec(), None, &mut NoIncludes);
    let Ok(lowered) = gdsky_naga::lower(&front, &gdsky_naga::LowerOptions::default()) else {
        eprintln!("{name} does not convert");
        std::process::exit(1);
    };
    convert_lowered(&lowered)
}

/// `convert_profile time N FILE…`: each file converted N times, the median and the fastest in
/// milliseconds.
fn time(n: usize, files: &[String]) {
    for file in files {
        let Ok(source) = std::fs::read_to_string(file) else {
            eprintln!("cannot read {file}");
            std::process::exit(1);
        };
        let mut times: Vec<f64> = (0..n.max(1))
            .map(|_| {
                let started = std::time::Instant::now();
                std::hint::black_box(convert(file, &source));
                started.elapsed().as_secs_f64() * 1e3
            })
            .collect();
        times.sort_by(f64::total_cmp);
        println!(
            "{file}: median {:.3} ms, fastest {:.3} ms ({} bytes)",
            times[times.len() / 2],
            times[0],
            source.len()
        );
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.get(1).map(String::as_str) == Some("time") {
        let n = args.get(2).and_then(|a| a.parse().ok()).unwrap_or(50);
        return time(n, &args[3.min(args.len())..]);
    }
    let n: usize = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(20);
    if args.get(2).map(String::as_str) == Some("glsl") {
        return glsl(n);
    }
    let mut bytes = 0;
    for _ in 0..n {
        let front = gdshader::check_source("freeman_sky.gdshader", FREEMAN.as_bytes().to_vec(), None, &mut NoIncludes);
        let Ok(lowered) = gdsky_naga::lower(&front, &gdsky_naga::LowerOptions::default()) else {
            eprintln!("the Freeman sky does not convert");
            std::process::exit(1);
        };
        bytes += convert_lowered(&lowered);
    }
    println!("{n} converts, {bytes} bytes out");
}
