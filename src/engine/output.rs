//! Images out: the format follows the file's extension, and where they go is checked before any
//! work is done.

use super::Error;
use std::path::Path;

/// The image formats gdsky writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    /// OpenEXR, RGBA 32-bit float, linear radiance, row 0 at the top: exact.
    Exr,
    /// PNG, 8-bit sRGB, tone mapped as `render --png` is (Bruneton's demo tone map): to look at.
    Png,
}

impl ImageFormat {
    /// The format `path`'s extension names (`.exr`, `.png`, either case); anything else is wrong
    /// input that names both.
    pub fn of(path: &Path) -> Result<ImageFormat, Error> {
        match path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
            Some("exr") => Ok(ImageFormat::Exr),
            Some("png") => Ok(ImageFormat::Png),
            _ => Err(Error::input(format!(
                "{}: the output format follows the extension: `.exr` (linear f32) or `.png` (tone-mapped preview)",
                path.display()
            ))),
        }
    }
}

/// Checks, before any work, that an image can be written at `path`: a known extension, an
/// existing directory (commands that write one image do not create folders: a typo in `-o` is
/// reported, not turned into a new folder), not a directory or a special file.
pub fn check_image_output(path: &Path) -> Result<ImageFormat, Error> {
    // Where it goes first (a directory, a device, a missing folder: the environment), then what
    // the name asks for.
    skycore::io::check_output(path)
        .map_err(|err| Error::environment(format!("cannot write {}: {err}", path.display())))?;
    ImageFormat::of(path)
}

/// Writes `image` at `path` in the format of its extension, atomically; returns what to say
/// about it (`wrote out.exr (256x128 RGBA f32)`).
pub fn write_image(image: &skyrun::Image, path: &Path) -> Result<String, Error> {
    let failed = |err: skyrun::ImageError| Error::environment(err);
    match ImageFormat::of(path)? {
        ImageFormat::Exr => {
            skyrun::write_exr(path, image).map_err(failed)?;
            Ok(format!("wrote {} ({}x{} RGBA f32)", path.display(), image.width, image.height))
        }
        ImageFormat::Png => {
            skyrun::write_png_preview(path, image, skyrun::DEFAULT_EXPOSURE, skyrun::DEFAULT_WHITE).map_err(failed)?;
            Ok(format!("wrote {} ({}x{} 8-bit sRGB preview)", path.display(), image.width, image.height))
        }
    }
}

/// Checks, before any work, an output folder and the files an engine will write into it: the
/// folder exists or, with `create`, can be created; each file that exists there can be replaced.
pub fn check_output_dir(dir: &Path, create: bool, files: &[&str]) -> Result<(), Error> {
    skycore::io::check_output_dir(dir, create)
        .map_err(|err| Error::environment(format!("cannot write into {}: {err}", dir.display())))?;
    if dir.is_dir() {
        for file in files {
            let path = dir.join(file);
            skycore::io::check_output(&path)
                .map_err(|err| Error::environment(format!("cannot write {}: {err}", path.display())))?;
        }
    }
    Ok(())
}

/// Refuses, before any work, an output that is one of the command's inputs (through any link) or
/// that is named twice: the write would destroy the input, or one output would replace the other.
/// Wrong input naming both.
pub fn check_outputs_apart(outputs: &[&Path], inputs: &[&Path]) -> Result<(), Error> {
    for (i, out) in outputs.iter().enumerate() {
        if let Some(input) = inputs.iter().find(|input| skycore::io::same_file(out, input)) {
            return Err(Error::input(format!(
                "{} is an input of this command ({}): gdsky does not write over its inputs; choose another output",
                out.display(),
                input.display()
            )));
        }
        let twice = outputs[..i].iter().any(|o| o == out || skycore::io::same_file(o, out));
        if twice {
            return Err(Error::input(format!("{} is named as two outputs of this command", out.display())));
        }
    }
    Ok(())
}

/// Creates an output folder (when the outputs are ready, after [`check_output_dir`]).
pub fn create_output_dir(dir: &Path) -> Result<(), Error> {
    skycore::io::create_output_dir(dir)
        .map_err(|err| Error::environment(format!("cannot create {}: {err}", dir.display())))
}

/// Writes `bytes` to `path` with the one safe, atomic writer; the error names the file.
pub fn write_file(path: &Path, bytes: &[u8]) -> Result<(), Error> {
    skycore::io::write_atomically(path, bytes)
        .map_err(|err| Error::environment(format!("cannot write {}: {err}", path.display())))
}

/// Opens the best Vulkan adapter and notes which one, or says why there is none (a wrong
/// environment: the message names the package that provides lavapipe).
pub fn open_gpu(progress: &dyn super::Progress) -> Result<skyrun::Gpu, Error> {
    let gpu = skyrun::Gpu::new().map_err(Error::environment)?;
    progress.note(&format!("adapter: {}", gpu.adapter_info()));
    Ok(gpu)
}
