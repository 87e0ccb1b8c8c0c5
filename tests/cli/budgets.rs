//! Work and size budgets at the edges of what the GPU stack holds (issue #22, item 1): arrays
//! within one SPIR-V instruction, uniform blocks within one uniform binding. Each is a located
//! error in the user's terms, before anything is written, in well under a second — not a panic
//! in naga's SPIR-V reader (a 64-byte shader used to crash `convert` after 10 s) or a driver's
//! message at `render`.

use crate::common::{gdsky, scratch, text};

fn convert(name: &str, source: &str) -> (std::process::Output, std::path::PathBuf) {
    let dir = scratch("budgets", name);
    let shader = dir.join(format!("{name}.gdshader"));
    std::fs::write(&shader, source).expect("write");
    let out = dir.join("out");
    let o = gdsky(&["convert", shader.to_str().expect("utf-8"), "-o", out.to_str().expect("utf-8")]);
    (o, out)
}

#[test]
fn an_array_longer_than_one_spirv_instruction_holds_is_refused_at_its_size() {
    let (o, out) = convert("spirv_words", "shader_type sky;uniform float U[65536];void sky(){COLOR.x=U[0];}\n");
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    let said = text(&o);
    assert!(said.contains("E501") && said.contains("spirv_words.gdshader:1:33") && said.contains("65532"), "{said}");
    assert!(!out.exists(), "nothing is written");
}

/// 5,000 one-line functions, each called once (342 KB): naga's SPIR-V reader would build an
/// expression for every constant in every function to re-read the module (16 million at 4,000
/// functions, 880 MB; 2.6 GB at 5,000 before the budget). Refused by the budget instead, with
/// nothing written; 2,000 functions (4 million) still convert.
#[test]
fn a_module_too_large_for_the_spirv_reread_is_refused_by_its_budget() {
    let many = |n: usize| {
        let mut source = String::from("shader_type sky;\n");
        for i in 0..n {
            source += &format!("float f{i}(float x) {{ return x * {i}.0 + sin(x); }}\n");
        }
        source += "void sky() {\n    float a = 0.0;\n";
        for i in 0..n {
            source += &format!("    a += f{i}(a);\n");
        }
        source + "    COLOR = vec3(a);\n}\n"
    };
    let (o, out) = convert("reread_budget", &many(5000));
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    let said = text(&o);
    assert!(
        said.contains("cannot write this shader as SPIR-V")
            && said.contains("5005 functions")
            && said.contains("budget"),
        "{said}"
    );
    assert!(!out.exists(), "nothing is written");
    let (o, out) = convert("reread_within_budget", &many(2000));
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    assert!(out.join("reread_within_budget.spv").is_file());
}

#[test]
fn a_uniform_block_larger_than_a_binding_is_refused_at_its_largest_uniform() {
    let (o, out) = convert(
        "binding",
        "shader_type sky;\nuniform vec3 tint = vec3(1.0);\nuniform float U[4097];\nvoid sky(){COLOR = tint * U[0];}\n",
    );
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    let said = text(&o);
    assert!(said.contains("E600") && said.contains("binding.gdshader:3:15"), "{said}");
    assert!(said.contains("65552 bytes") && said.contains("`U`"), "{said}");
    assert!(!out.exists(), "nothing is written");
    // One element fewer fits: the bound is the binding's, not a guess.
    let (o, _) = convert("binding_fits", "shader_type sky;\nuniform float U[4096];\nvoid sky(){COLOR.x = U[0];}\n");
    assert!(o.status.success(), "{}", text(&o));
}

/// A shader the driver compiles for minutes (lavapipe: still compiling after 900 s) ends at the
/// driver budget with exit 1, naming the shader, the budget and how to raise it; nothing written.
#[test]
fn a_pipeline_build_past_the_driver_budget_ends_the_command() {
    let dir = scratch("budgets", "driver");
    let shader = dir.join("heavy.gdshader");
    let source = "shader_type sky;\nvoid sky() {\n\tfloat A[60000];\n\tfor (int i = 0; i < 60000; i++) { A[i] = float(i); }\n\tCOLOR.x = A[int(EYEDIR.x * 100.0) + 200];\n}\n";
    std::fs::write(&shader, source).expect("write");
    let out = dir.join("heavy.exr");
    let budget = std::path::Path::new("3");
    let o = crate::common::gdsky_with(
        &["render", shader.to_str().expect("utf-8"), "-o", out.to_str().expect("utf-8"), "--size", "8x4"],
        &[("GDSKY_DRIVER_BUDGET", budget)],
    );
    let said = text(&o);
    assert_eq!(o.status.code(), Some(1), "{said}");
    assert!(said.contains("heavy.gdshader") && said.contains("longer than 3 s, the driver budget"), "{said}");
    assert!(said.contains("GDSKY_DRIVER_BUDGET=SECONDS"), "{said}");
    assert!(!out.exists(), "nothing is written");
}

/// A PNG of a few dozen bytes whose header claims `width`×`height` grey pixels: what a decoder
/// would allocate 4 GiB for before finding the data missing.
fn png_claiming(width: u32, height: u32) -> Vec<u8> {
    let chunk = |kind: &[u8], data: &[u8]| {
        let mut c = (data.len() as u32).to_be_bytes().to_vec();
        c.extend_from_slice(kind);
        c.extend_from_slice(data);
        let mut crc = crc32fast::Hasher::new();
        crc.update(kind);
        crc.update(data);
        c.extend_from_slice(&crc.finalize().to_be_bytes());
        c
    };
    let mut ihdr = width.to_be_bytes().to_vec();
    ihdr.extend_from_slice(&height.to_be_bytes());
    ihdr.extend_from_slice(&[8, 0, 0, 0, 0]); // 8-bit grey, deflate, no filter, no interlace
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    png.extend(chunk(b"IHDR", &ihdr));
    png.extend(chunk(b"IDAT", &[0x78, 0x01, 0x01, 0x00, 0x00, 0xff, 0xff, 0x00, 0x00, 0x00, 0x01]));
    png.extend(chunk(b"IEND", &[]));
    png
}

/// An occluder mask is sampled at the render's size: one whose header claims more than the
/// largest render (here 65535², 4 GiB decoded) is refused from its header, before decoding.
#[test]
fn an_occluder_claiming_a_huge_image_is_refused_from_its_header() {
    let dir = scratch("budgets", "mask");
    let mask = dir.join("huge.png");
    std::fs::write(&mask, png_claiming(65535, 65535)).expect("write");
    let out = dir.join("sky.exr");
    let o = gdsky(&[
        "render",
        "--size",
        "16x8",
        "-o",
        out.to_str().expect("utf-8"),
        "--occluder",
        mask.to_str().expect("utf-8"),
    ]);
    let said = text(&o);
    assert_eq!(o.status.code(), Some(1), "{said}");
    assert!(said.contains("65535x65535") && said.contains("refused before decoding"), "{said}");
    assert!(!out.exists());
}

/// The minor defects of issue #22: each is wrong input with a clear, located message.
#[test]
fn small_inputs_get_clear_messages() {
    let dir = scratch("budgets", "minor");
    // A scene file that is not UTF-8: located at its first bad byte.
    let toml = dir.join("bad.toml");
    std::fs::write(&toml, b"size = [8, 4]\nshader = \"a\xff.gdshader\"\n").expect("write");
    let exr = dir.join("x.exr");
    let o = gdsky(&["render", toml.to_str().expect("utf-8"), "-o", exr.to_str().expect("utf-8")]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("error: ") && text(&o).contains("bad.toml:2:12: not UTF-8"), "{}", text(&o));
    // bake-lut checks every value, whether the table reads the uniform or not.
    let lut = dir.join("lut.exr");
    let o = gdsky(&["bake-lut", "--set", "mie_g_forward=nan", "-o", lut.to_str().expect("utf-8")]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("not a finite number") && !lut.exists(), "{}", text(&o));
}
