//! Safe files and bounded input, end to end (issue #10, items 4 and 5): outputs that are devices,
//! FIFOs, directories or symbolic links; output locations checked before any work; inputs that
//! are devices, FIFOs or too large; and flags with non-finite or out-of-range numbers.
//!
//! Exit codes (the CLI contract): 2 for a path that cannot be read or written (missing, not a
//! regular file, over the size limit, an output directory that is missing), 1 for a flag.

use crate::common::{gdsky, scratch, text};
use std::os::unix::fs::{FileTypeExt, symlink};
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn dir(name: &str) -> PathBuf {
    scratch("safe_io", name)
}

fn arg(path: &Path) -> &str {
    path.to_str().expect("UTF-8 path")
}

fn mkfifo(path: &Path) {
    let status = Command::new("mkfifo").arg(path).status().expect("mkfifo runs");
    assert!(status.success(), "mkfifo {}", path.display());
}

fn is_fifo(path: &Path) -> bool {
    std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_fifo())
}

/// Runs `gdsky` with `args`, killing it after 20 s: an input that makes it block or read
/// forever fails the test instead of hanging it.
fn gdsky_with_timeout(args: &[&str]) -> Output {
    let runtime = std::env::temp_dir().join("gdsky-xdg-runtime");
    let _ = std::fs::create_dir_all(&runtime);
    let mut child = Command::new(env!("CARGO_BIN_EXE_gdsky"))
        .args(args)
        .env("XDG_RUNTIME_DIR", runtime)
        .env("NO_COLOR", "1")
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the gdsky binary runs");
    let started = Instant::now();
    while child.try_wait().expect("wait").is_none() {
        if started.elapsed() > Duration::from_secs(20) {
            let _ = child.kill();
            let _ = child.wait();
            panic!("gdsky {args:?} still running after 20 s: it blocks or reads without bound");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.wait_with_output().expect("output")
}

/// The run failed with `code` and a message containing each of `needles`.
#[track_caller]
fn assert_fails(o: &Output, code: i32, needles: &[&str]) {
    assert_eq!(o.status.code(), Some(code), "{}", text(o));
    let stderr = String::from_utf8_lossy(&o.stderr);
    for needle in needles {
        assert!(stderr.contains(needle), "expected {needle:?} in: {stderr}");
    }
}

/// No GPU work happened: the adapter is opened after every check, and says so on stderr.
#[track_caller]
fn assert_no_gpu_work(o: &Output) {
    assert!(!String::from_utf8_lossy(&o.stderr).contains("adapter:"), "{}", text(o));
}

#[test]
fn a_device_output_is_refused_and_left_a_device() {
    // As root this used to replace /dev/full with a regular file.
    let o = gdsky(&["render", "--size", "8x4", "-o", "/dev/full"]);
    assert_fails(&o, 2, &["cannot write /dev/full", "character device", "not a regular file"]);
    assert_no_gpu_work(&o);
    let meta = std::fs::symlink_metadata("/dev/full").expect("/dev/full");
    assert!(meta.file_type().is_char_device(), "/dev/full is no longer a device");
    // The PNG preview and compare's outputs go through the same writer.
    let d = dir("device");
    let o = gdsky(&["reference", "--size", "8x4", "-o", arg(&d.join("x.exr")), "--png", "/dev/full"]);
    assert_fails(&o, 2, &["cannot write /dev/full"]);
    assert!(!d.join("x.exr").exists(), "nothing written when one output is refused");
    let o = gdsky(&["compare", "a.exr", "b.exr", "--heatmap", "/dev/full"]);
    assert_fails(&o, 2, &["cannot write /dev/full"]);
    assert!(std::fs::symlink_metadata("/dev/full").expect("/dev/full").file_type().is_char_device());
}

#[test]
fn a_fifo_output_is_refused_and_left_a_fifo() {
    let d = dir("fifo_out");
    let fifo = d.join("out.exr");
    mkfifo(&fifo);
    let o = gdsky_with_timeout(&["render", "--size", "8x4", "-o", arg(&fifo)]);
    assert_fails(&o, 2, &["FIFO", "not a regular file"]);
    assert_no_gpu_work(&o);
    assert!(is_fifo(&fifo));
    // convert -o DIR with a FIFO named <stem>.spv: refused before converting, nothing written.
    let out = d.join("convert");
    std::fs::create_dir(&out).expect("dir");
    mkfifo(&out.join("freeman_sky.spv"));
    let o = gdsky_with_timeout(&["convert", "fixtures/freeman_sky.gdshader", "-o", arg(&out)]);
    assert_fails(&o, 2, &["freeman_sky.spv", "FIFO"]);
    assert!(is_fifo(&out.join("freeman_sky.spv")));
    let names: Vec<_> = std::fs::read_dir(&out).expect("dir").flatten().map(|e| e.file_name()).collect();
    assert_eq!(names, ["freeman_sky.spv"], "no other output written");
}

#[test]
fn a_directory_output_is_refused() {
    let d = dir("dir_out");
    let target = d.join("x.exr");
    std::fs::create_dir(&target).expect("dir");
    for out in [arg(&target).to_string(), format!("{}/", d.display()), format!("{}/new/", d.display())] {
        let o = gdsky(&["render", "--size", "8x4", "-o", &out]);
        assert_fails(&o, 2, &["cannot write"]);
        assert_no_gpu_work(&o);
    }
    let o = gdsky(&["reference", "--size", "8x4", "-o", arg(&target)]);
    assert_fails(&o, 2, &["is a directory"]);
    assert!(target.is_dir());
    // convert -o FILE: a regular file is not a directory to write into.
    let file = d.join("file");
    std::fs::write(&file, b"keep").expect("write");
    let o = gdsky(&["convert", "fixtures/freeman_sky.gdshader", "-o", arg(&file)]);
    assert_fails(&o, 2, &["not a directory"]);
    assert_eq!(std::fs::read(&file).expect("file"), b"keep");
}

#[test]
fn symlinked_outputs_are_written_through_and_survive() {
    let d = dir("links");
    let runs = d.join("runs");
    std::fs::create_dir(&runs).expect("dir");
    std::fs::write(runs.join("run42.exr"), b"old").expect("write");
    let latest = d.join("latest.exr");
    symlink("runs/run42.exr", &latest).expect("symlink");
    let o = gdsky(&["reference", "--size", "8x4", "-o", arg(&latest)]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(std::fs::symlink_metadata(&latest).expect("link").file_type().is_symlink(), "the link survives");
    let written = std::fs::read(runs.join("run42.exr")).expect("target");
    assert!(written.starts_with(&[0x76, 0x2f, 0x31, 0x01]), "the target holds the new EXR");
    assert_eq!(std::fs::read_dir(&runs).expect("dir").count(), 1, "no temporary file left beside the target");

    // A dangling link to a missing file in an existing directory: the file is created there.
    let next = d.join("next.exr");
    symlink("runs/run43.exr", &next).expect("symlink");
    let o = gdsky(&["reference", "--size", "8x4", "-o", arg(&next)]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(runs.join("run43.exr").is_file());
    assert!(std::fs::symlink_metadata(&next).expect("link").file_type().is_symlink());

    // convert writes through a link too; a link to a device is refused like the device.
    let out = d.join("convert");
    std::fs::create_dir(&out).expect("dir");
    symlink("../runs/sky.wgsl", out.join("freeman_sky.wgsl")).expect("symlink");
    let o = gdsky(&["convert", "fixtures/freeman_sky.gdshader", "-o", arg(&out)]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(std::fs::read_to_string(runs.join("sky.wgsl")).expect("target").contains("fn fs_panorama"));
    let to_device = d.join("null.exr");
    symlink("/dev/null", &to_device).expect("symlink");
    let o = gdsky(&["reference", "--size", "8x4", "-o", arg(&to_device)]);
    assert_fails(&o, 2, &["its link target /dev/null is a character device"]);
    assert!(std::fs::symlink_metadata("/dev/null").expect("/dev/null").file_type().is_char_device());
}

#[test]
fn a_missing_output_directory_fails_before_any_work() {
    let d = dir("missing_dir");
    let out = d.join("no/such/x.exr");
    let o = gdsky(&["render", "--size", "8x4", "-o", arg(&out)]);
    assert_fails(&o, 2, &["no/such does not exist"]);
    assert_no_gpu_work(&o);
    let o = gdsky(&["render", "--size", "8x4", "-o", arg(&d.join("x.exr")), "--png", arg(&out)]);
    assert_fails(&o, 2, &["no/such does not exist"]);
    assert_no_gpu_work(&o);
    // compare checks its outputs before it reads the images (which do not exist either).
    let o = gdsky(&["compare", "missing-a.exr", "missing-b.exr", "--side-by-side", arg(&out)]);
    assert_fails(&o, 2, &["no/such does not exist"]);
    assert!(!String::from_utf8_lossy(&o.stderr).contains("missing-a.exr"), "{}", text(&o));
    // Commands that create their folder check its nearest existing ancestor instead.
    let blocked = d.join("file");
    std::fs::write(&blocked, b"").expect("write");
    let o = gdsky(&["stress", "--quick", "-o", arg(&blocked.join("stress"))]);
    assert_fails(&o, 2, &["not a directory"]);
    assert_no_gpu_work(&o);
    let o = gdsky(&["bench", "-o", arg(&blocked.join("bench"))]);
    assert_fails(&o, 2, &["not a directory"]);
    assert_no_gpu_work(&o);
    let o = gdsky(&["demo", "-o", arg(&blocked)]);
    assert_fails(&o, 2, &["not a directory"]);
    assert_no_gpu_work(&o);
}

#[test]
fn device_and_fifo_inputs_are_refused_promptly() {
    let d = dir("inputs");
    let fifo = d.join("in.gdshader");
    mkfifo(&fifo);
    let out = d.join("x.exr");
    for input in ["/dev/zero", arg(&fifo)] {
        let kind = if input == "/dev/zero" { "character device" } else { "FIFO" };
        for args in [
            vec!["check", input],
            vec!["render", input, "--size", "8x4", "-o", arg(&out)],
            vec!["convert", input, "-o", arg(&d)],
            vec!["compare", input, input],
        ] {
            let o = gdsky_with_timeout(&args);
            assert_fails(&o, 2, &[input, kind, "not a regular file"]);
            assert_no_gpu_work(&o);
        }
    }
    let o = gdsky_with_timeout(&["check", arg(&d)]);
    assert_fails(&o, 2, &["is a directory"]);
    assert!(is_fifo(&fifo) && !out.exists());
}

#[test]
fn over_size_inputs_are_refused_unread() {
    let d = dir("large");
    // Sparse files: cheap to make, and refused from their size without being read.
    let shader = d.join("big.gdshader");
    std::fs::File::create(&shader).and_then(|f| f.set_len(5 << 20)).expect("sparse shader");
    let o = gdsky_with_timeout(&["check", arg(&shader)]);
    assert_fails(&o, 2, &["big.gdshader", "5 MiB, over the 4 MiB limit"]);
    let image = d.join("big.exr");
    std::fs::File::create(&image).and_then(|f| f.set_len(3 << 30)).expect("sparse EXR");
    let o = gdsky_with_timeout(&["compare", arg(&image), arg(&image)]);
    assert_fails(&o, 2, &["big.exr", "3 GiB, over the"]);
    // Just under the shader limit is read (and is not a shader).
    let zeros = d.join("zeros.gdshader");
    std::fs::File::create(&zeros).and_then(|f| f.set_len(4 << 20)).expect("sparse shader");
    let o = gdsky_with_timeout(&["check", arg(&zeros)]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
}

/// Every numeric flag refuses NaN, infinities and out-of-range values with exit 1, naming the
/// flag and the accepted range, before any work.
#[test]
fn non_finite_and_out_of_range_flags_are_refused() {
    let d = dir("flags");
    let out = d.join("x.exr");
    let o_arg = arg(&out);
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["render", "--time", "nan"], "--time"),
        (vec!["render", "--time", "inf"], "--time"),
        (vec!["render", "--time", "1e39"], "--time"),
        (vec!["render", "--time", "-1e39"], "--time"),
        (vec!["render", "--fov", "0"], "--fov"),
        (vec!["render", "--fov", "180"], "--fov"),
        (vec!["render", "--fov", "nan"], "--fov"),
        (vec!["render", "--size", "16384x8"], "--size"),
        (vec!["render", "--size", "8192x4096"], "--size"),
        (vec!["render", "--projection", "cubemap", "--size", "8193x8193"], "--size"),
        (vec!["render", "--sun", "nan,0"], "--sun"),
        (vec!["render", "--sun", "91,0"], "--sun"),
        (vec!["render", "--sun", "10,inf"], "--sun"),
        (vec!["render", "--position", "0,nan,0"], "--position"),
        (vec!["render", "--position", "0,1e39,0"], "--position"),
        (vec!["render", "--yaw", "inf"], "--yaw"),
        (vec!["render", "--yaw", "361"], "--yaw"),
        (vec!["render", "--pitch", "-91"], "--pitch"),
        (vec!["render", "--pitch", "nan"], "--pitch"),
        (vec!["render", "--set", "sun_intensity=nan"], "--set"),
        (vec!["render", "--set", "sun_intensity=inf"], "--set"),
        (vec!["render", "--set", "sun_intensity=1e39"], "--set"),
        (vec!["render", "--set", "view_samples=3000000000"], "--set"),
        (vec!["render", "--set", "ground_color=0,nan,0"], "--set"),
        (vec!["reference", "--set", "sun_intensity=nan"], "--set"),
        (vec!["reference", "--set", "view_samples=-3000000000"], "--set"),
        (vec!["reference", "--time", "nan"], "--time"),
        (vec!["oracle", "--fov", "inf"], "--fov"),
        (vec!["oracle", "--set", "sun_intensity=inf"], "--set"),
    ];
    for (mut args, flag) in cases {
        args.extend(["-o", o_arg]);
        let o = gdsky(&args);
        assert_fails(&o, 1, &[flag]);
        assert_no_gpu_work(&o);
    }
    // Messages say what is accepted.
    let o = gdsky(&["render", "--time", "nan", "-o", o_arg]);
    assert_fails(&o, 1, &["'--time <T>'", "not a finite number", "accepted"]);
    let o = gdsky(&["render", "--fov", "180", "-o", o_arg]);
    assert_fails(&o, 1, &["more than 0 and less than 180 degrees"]);
    let o = gdsky(&["render", "--size", "8192x4096", "-o", o_arg]);
    assert_fails(&o, 1, &["at most 16777216 pixels"]);
    let o = gdsky(&["render", "--set", "sun_intensity=1e39", "-o", o_arg]);
    assert_fails(&o, 1, &["overflows a float"]);
    assert!(!out.exists());

    // convert: the shared value parser's refusal is E603, the user's flag, not gdsky's E601.
    for bad in ["sun_intensity=nan", "sun_intensity=-inf", "sun_intensity=1e39", "view_samples=2147483648"] {
        let o = gdsky(&["convert", "fixtures/freeman_sky.gdshader", "--set", bad, "-o", arg(&d)]);
        assert_fails(&o, 1, &["E603", "--set"]);
        assert!(!String::from_utf8_lossy(&o.stderr).contains("E601"), "{}", text(&o));
    }
    // compare: --max-rel and --floor.
    for (flag, value) in [
        ("--max-rel", "nan"),
        ("--max-rel", "inf"),
        ("--max-rel", "-1"),
        ("--floor", "0"),
        ("--floor", "-1e-4"),
        ("--floor", "nan"),
        ("--floor", "1e39"),
        ("--floor", "1e-50"),
    ] {
        let o = gdsky(&["compare", "a.exr", "b.exr", flag, value]);
        assert_fails(&o, 1, &[flag]);
    }
    // bench: --runs, --truth-samples, --knob, and the scene flags it shares.
    let bench_out = d.join("bench");
    for (args, flag) in [
        (vec!["--runs", "0"], "--runs"),
        (vec!["--runs", "1001"], "--runs"),
        (vec!["--runs", "-1"], "--runs"),
        (vec!["--truth-samples", "0,8"], "--truth-samples"),
        (vec!["--truth-samples", "-5,8"], "--truth-samples"),
        (vec!["--truth-samples", "1024,99999"], "--truth-samples"),
        (vec!["--knob", "view_samples=0,8"], "--knob"),
        (vec!["--knob", "sun_samples=99999"], "--knob"),
        (vec!["--set", "mie_albedo=nan"], "--set"),
        (vec!["--yaw", "nan"], "--yaw"),
        (vec!["--size", "9000x8"], "--size"),
    ] {
        let mut full = vec!["bench", "-o", arg(&bench_out)];
        full.extend(args);
        let o = gdsky(&full);
        assert_fails(&o, 1, &[flag]);
        assert_no_gpu_work(&o);
    }
    assert!(!bench_out.exists());
}

/// An output that is an input (directly or through a link), or one output named twice, is
/// refused before any work (issue #22, item 5): exit 1, the input untouched.
#[test]
fn an_output_over_an_input_is_refused_before_any_work() {
    let dir = dir("output_is_input");
    let shader = dir.join("u.gdshader");
    let source = "shader_type sky;\nvoid sky() { COLOR = vec3(0.2, 0.4, 0.8); }\n";
    std::fs::write(&shader, source).expect("write");
    let link = dir.join("link.exr");
    symlink(&shader, &link).expect("symlink");
    let exr = dir.join("a.exr");
    let made = gdsky(&["render", arg(&shader), "-o", arg(&exr), "--size", "8x4"]);
    assert!(made.status.success(), "{}", text(&made));
    let before = std::fs::read(&exr).expect("a.exr");
    let json = dir.join("u.json");
    std::fs::write(&json, source).expect("write");

    // (`render u.gdshader -o u.gdshader` is refused by its extension already.)
    let cases: Vec<(Vec<&str>, &Path)> = vec![
        (vec!["render", arg(&shader), "-o", arg(&link), "--size", "8x4"], &shader),
        (vec!["compare", arg(&exr), arg(&exr), "--heatmap", arg(&exr)], &exr),
        (vec!["convert", arg(&json), "-o", arg(&dir)], &json),
    ];
    for (args, input) in cases {
        let was = std::fs::read(input).expect("input");
        let out = gdsky(&args);
        let said = text(&out);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {said}");
        assert!(said.contains("gdsky does not write over its inputs"), "{args:?}: {said}");
        assert_eq!(std::fs::read(input).expect("input"), was, "{args:?}: the input is untouched");
    }
    let png = dir.join("p.png");
    let twice = gdsky(&["render", arg(&shader), "-o", arg(&png), "--png", arg(&png), "--size", "8x4"]);
    assert_eq!(twice.status.code(), Some(1), "{}", text(&twice));
    assert!(text(&twice).contains("named as two outputs"), "{}", text(&twice));
    assert_eq!(std::fs::read(&exr).expect("a.exr"), before);
}

/// Six `convert`s of six different shaders, all named `sky.gdshader`, into one folder at once:
/// whichever set lands last, its three files are one run's (the folder is locked while a set is
/// renamed into place). Each shader's uniform has its own name, which the WGSL and the
/// reflection carry, and its green its own constant, which the SPIR-V carries. Without the
/// lock this failed within 9 to 13 rounds (two runs); with it, 200 rounds passed.
#[test]
fn concurrent_converts_into_one_folder_leave_one_whole_set() {
    let green = |i: usize| 0.125 + i as f32 / 8.0;
    let base = dir("concurrent_converts");
    let out = base.join("out");
    std::fs::create_dir_all(&out).expect("out dir");
    let inputs: Vec<PathBuf> = (0..6)
        .map(|i| {
            let folder = base.join(format!("in{i}"));
            std::fs::create_dir_all(&folder).expect("input dir");
            let path = folder.join("sky.gdshader");
            let source = format!(
                "shader_type sky;\nuniform float knob_{i} = 0.5;\nvoid sky() {{ COLOR = vec3(knob_{i}, {}, 0.0); }}\n",
                green(i)
            );
            std::fs::write(&path, source).expect("writes the shader");
            path
        })
        .collect();
    // The SPIR-V has no debug names: it is told by its constant, the f32's bytes.
    let carries = |file: &str, i: usize| {
        let bytes = std::fs::read(out.join(file)).expect("output exists");
        let needle =
            if file.ends_with(".spv") { green(i).to_le_bytes().to_vec() } else { format!("knob_{i}").into_bytes() };
        bytes.windows(needle.len()).any(|w| w == needle)
    };
    for round in 0..60 {
        let children: Vec<std::process::Child> = inputs
            .iter()
            .map(|input| {
                Command::new(env!("CARGO_BIN_EXE_gdsky"))
                    .args(["convert", arg(input), "-o", arg(&out)])
                    .stdout(Stdio::null())
                    .stderr(Stdio::null())
                    .spawn()
                    .expect("the gdsky binary runs")
            })
            .collect();
        for mut child in children {
            assert!(child.wait().expect("waits").success(), "round {round}: a convert failed");
        }
        let winner = (0..6).find(|&i| carries("sky.wgsl", i)).expect("the WGSL is one run's");
        for file in ["sky.spv", "sky.json"] {
            assert!(carries(file, winner), "round {round}: sky.wgsl is knob_{winner}'s, {file} is another run's");
        }
    }
}
