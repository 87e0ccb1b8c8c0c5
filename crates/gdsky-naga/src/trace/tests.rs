//! The instrumented module validates and writes as WGSL and SPIR-V, names the right places, and
//! leaves the module it was given as it was.

use super::*;

fn front(name: &str, source: &str) -> FrontendOutput {
    gdshader::check_source(name, source.as_bytes().to_vec(), None, &mut gdshader::FsLoader)
}

const FREEMAN: &str = include_str!("../../../../fixtures/freeman_sky.gdshader");

const PLANTED: &str = "shader_type sky;
float f(float x) { return sqrt(x - 1.0); }
void sky() {
    COLOR = vec3(f(1.0 - EYEDIR.y));
}
";

#[test]
fn instrumented_freeman_validates_and_writes() {
    let front = front("freeman_sky.gdshader", FREEMAN);
    let lowered = crate::lower(&front, &crate::LowerOptions::default()).expect("lowers");
    let traced = instrument(&front, &lowered).expect("instrumented module validates");
    assert!(traced.sites.len() > 20, "{} sites", traced.sites.len());
    for (i, s) in traced.sites.iter().enumerate() {
        assert_eq!(s.id as usize, i + 1);
        assert_eq!(s.file, "freeman_sky.gdshader");
        assert!(!s.snippet.is_empty(), "{s:?}");
    }
    let wgsl = crate::to_wgsl(&traced.lowered).expect("WGSL round-trips");
    assert!(wgsl.contains(SITE_REGISTER), "{wgsl}");
    crate::to_spirv(&traced.lowered).expect("SPIR-V");
    // The Rayleigh density's division is a site, at its place in the file.
    let rayleigh: Vec<&Site> =
        traced.sites.iter().filter(|s| s.snippet == "-altitude / rayleigh_scale_height").collect();
    assert_eq!(rayleigh.len(), 1, "{:#?}", traced.sites);
    assert_eq!((rayleigh[0].line, rayleigh[0].col, rayleigh[0].kind.as_str()), (205, 7, "division"));
    assert_eq!(rayleigh[0].function, "get_optical_depth_at_point");
}

#[test]
fn the_module_given_is_unchanged() {
    let front = front("freeman_sky.gdshader", FREEMAN);
    let lowered = crate::lower(&front, &crate::LowerOptions::default()).expect("lowers");
    let before = crate::to_wgsl(&lowered).expect("WGSL");
    let traced = instrument(&front, &lowered).expect("instruments");
    assert_eq!(crate::to_wgsl(&lowered).expect("WGSL"), before);
    let again = crate::lower(&front, &crate::LowerOptions::default()).expect("lowers");
    assert_eq!(crate::to_wgsl(&again).expect("WGSL"), before, "lowering is deterministic");
    assert!(!before.contains(SITE_REGISTER));
    assert_ne!(crate::to_wgsl(&traced.lowered).expect("WGSL"), before);
}

#[test]
fn planted_sqrt_is_a_site_and_wrapper_code_is_not() {
    let front = front("planted.gdshader", PLANTED);
    let lowered = crate::lower(&front, &crate::LowerOptions::default()).expect("lowers");
    let traced = instrument(&front, &lowered).expect("instruments");
    let names: Vec<(String, &str, &str)> =
        traced.sites.iter().map(|s| (s.location(), s.snippet.as_str(), s.kind.as_str())).collect();
    assert_eq!(
        names,
        [
            ("planted.gdshader:2:32".to_string(), "x - 1.0", "subtraction"),
            ("planted.gdshader:2:27".to_string(), "sqrt(x - 1.0)", "sqrt"),
            ("planted.gdshader:4:20".to_string(), "1.0 - EYEDIR.y", "subtraction"),
        ]
    );
}

#[test]
fn a_macro_site_is_its_invocation() {
    let src = "shader_type sky;\n#define ROOT(v) sqrt(v)\nvoid sky() {\n    COLOR = vec3(ROOT(EYEDIR.y));\n}\n";
    let front = front("macro.gdshader", src);
    let lowered = crate::lower(&front, &crate::LowerOptions::default()).expect("lowers");
    let traced = instrument(&front, &lowered).expect("instruments");
    let sqrt: Vec<&Site> = traced.sites.iter().filter(|s| s.kind == "sqrt").collect();
    assert_eq!(sqrt.len(), 1, "{:#?}", traced.sites);
    assert_eq!((sqrt[0].line, sqrt[0].col), (4, 18), "{:?}", sqrt[0]);
    assert!(sqrt[0].snippet.starts_with("ROOT"), "{:?}", sqrt[0]);
}

#[test]
fn alpha_decodes_to_sites() {
    let front = front("planted.gdshader", PLANTED);
    let traced = instrument(&front, &crate::lower(&front, &crate::LowerOptions::default()).expect("lowers"))
        .expect("instruments");
    assert_eq!(traced.site_of_alpha(0.0), None);
    assert_eq!(traced.site_of_alpha(2.0).map(|s| s.kind.as_str()), Some("sqrt"));
    assert_eq!(traced.site_of_alpha(1.5), None);
    assert_eq!(traced.site_of_alpha(f32::NAN), None);
    assert_eq!(traced.site_of_alpha(1e9), None);
}
