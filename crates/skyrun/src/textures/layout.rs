//! Cube maps and 3D textures assembled from image files.
//!
//! **Cube maps** (`samplerCube`) come from six files, one per face in Vulkan's and Godot's
//! layer order +X, −X, +Y, −Y, +Z, −Z, or from one image whose aspect ratio says how the faces
//! are arranged (square faces; the six ratios differ, so none is ambiguous):
//!
//! | aspect | layout | faces |
//! | --- | --- | --- |
//! | 4:3 | horizontal cross | row 0: +Y above +Z; row 1: −X, +Z, +X, −Z; row 2: −Y below +Z |
//! | 3:4 | vertical cross | +Y; −X, +Z, +X; −Y; −Z, the last rotated by 180° |
//! | 6:1, 3:2, 2:3, 1:6 | Godot's cube map importer (`slices/arrangement`: 6×1, 3×2, 2×3, 1×6) | row by row, left to right, in layer order |
//!
//! Godot's own importer (`ResourceImporterLayeredTexture`) cuts only the four grids, each cell
//! taken as is; it has no cross layout. A face image is the face as Vulkan samples it (and
//! Godot uploads it): its top row toward +Y for the four side faces, toward −Z for +Y and +Z
//! for −Y. Laid out that way, the horizontal cross with +Z in the middle is the only cross
//! whose neighbouring faces meet edge to edge without turning a face, which is why it is the
//! common one; the vertical cross folds −Z under −Y and so stores it upside down.
//!
//! **3D textures** (`sampler3D`) come from a list of slice files, front (w = 0) first, or from
//! one image cut into a grid of `columns × rows` slices read row by row, left to right: the
//! layout of Godot's Texture3D importer (`slices/horizontal`, `slices/vertical`, both 8 by
//! default, [`GODOT_VOLUME_GRID`]). Godot resizes a cell that does not fit; here an image whose
//! sides are not multiples of the grid is refused.

use super::{TextureData, TextureError, read_texture};
use std::path::{Path, PathBuf};

/// Godot's default Texture3D import grid: 8 slices across, 8 down.
pub const GODOT_VOLUME_GRID: (u32, u32) = (8, 8);

/// Reads a cube map: six face files (+X, −X, +Y, −Y, +Z, −Z) or one image in a cross or grid
/// layout (the table at the top of `textures/layout.rs`). `srgb` as for [`read_texture`].
///
/// Errors: [`TextureError::Read`] for a file that cannot be read; [`TextureError::Layout`]
/// naming the files for another number of files, faces that are not square or not all of one
/// size and format, an image whose aspect is none of the layouts, six files holding more than
/// [`MAX_ASSEMBLED_BYTES`].
pub fn read_cube(paths: &[PathBuf], srgb: bool) -> Result<TextureData, TextureError> {
    match paths {
        [path] => {
            let image = read_texture(path, srgb)?;
            let (w, h) = (image.width(), image.height());
            let layout = CUBE_LAYOUTS.iter().find(|l| w * l.rows == h * l.columns && w % l.columns == 0);
            let Some(layout) = layout else {
                return Err(TextureError::Layout(format!(
                    "{}: a {w}×{h} image is no cube map layout; one image holds six square faces as a horizontal \
                     cross (4:3), a vertical cross (3:4) or a grid of 6×1, 3×2, 2×3 or 1×6 faces, or give six face \
                     files (+X, −X, +Y, −Y, +Z, −Z)",
                    path.display()
                )));
            };
            let side = w / layout.columns;
            let faces = layout
                .cells
                .iter()
                .map(|&(c, r, turned)| region(&image, c * side, r * side, side, side, turned))
                .collect::<Result<Vec<_>, _>>()
                .map_err(|e| in_file(path, e))?;
            TextureData::cube(&faces).map_err(|e| in_file(path, e))
        }
        [_, _, _, _, _, _] => {
            let faces = read_all(paths, srgb)?;
            let first = &faces[0];
            if first.width() != first.height() {
                return Err(TextureError::Layout(format!(
                    "{}: cube map faces must be square, but it is {}×{}",
                    paths[0].display(),
                    first.width(),
                    first.height()
                )));
            }
            same_size_and_format(&faces, paths, "cube map faces")?;
            TextureData::cube(&faces)
        }
        _ => Err(TextureError::Layout(format!(
            "a cube map is six face files (+X, −X, +Y, −Y, +Z, −Z) or one cross or grid image, but {} files were \
             given: {}",
            paths.len(),
            list(paths)
        ))),
    }
}

/// Reads a 3D texture: slice files front to back, or one image cut into `grid` (columns,
/// rows; [`GODOT_VOLUME_GRID`] when `None`) slices row by row. `srgb` as for [`read_texture`].
///
/// Errors: [`TextureError::Read`] for a file that cannot be read; [`TextureError::Layout`]
/// naming the files for slices not all of one size and format, an image whose sides are not
/// multiples of the grid, a side over [`super::MAX_VOLUME_SIDE`], slices holding more than
/// [`MAX_ASSEMBLED_BYTES`].
pub fn read_volume(paths: &[PathBuf], grid: Option<(u32, u32)>, srgb: bool) -> Result<TextureData, TextureError> {
    match paths {
        [] => Err(TextureError::Layout("a 3D texture needs at least one file".into())),
        [path] => {
            let image = read_texture(path, srgb)?;
            let (columns, rows) = grid.unwrap_or(GODOT_VOLUME_GRID);
            let (w, h) = (image.width(), image.height());
            if columns == 0 || rows == 0 || w % columns != 0 || h % rows != 0 {
                return Err(TextureError::Layout(format!(
                    "{}: a {w}×{h} image does not split into {columns}×{rows} equal slices{}",
                    path.display(),
                    if grid.is_none() { " (Godot's default grid; give another as PATH@COLUMNSxROWS)" } else { "" }
                )));
            }
            let (sw, sh) = (w / columns, h / rows);
            let slices = (0..rows)
                .flat_map(|r| (0..columns).map(move |c| (c, r)))
                .map(|(c, r)| region(&image, c * sw, r * sh, sw, sh, false))
                .collect::<Result<Vec<_>, _>>()
                .map_err(|e| in_file(path, e))?;
            TextureData::volume(&slices).map_err(|e| in_file(path, e))
        }
        _ => {
            let slices = read_all(paths, srgb)?;
            same_size_and_format(&slices, paths, "3D texture slices")?;
            TextureData::volume(&slices).map_err(|e| TextureError::Layout(format!("{}: {e}", list(paths))))
        }
    }
}

/// Most texel bytes a cube map or 3D texture assembled from several files may hold: 2 GiB (six
/// 4096² faces of 32-bit floats are 1.5 GiB, 128 slices of 2048² 8-bit texels 2 GiB). Files
/// are read one by one and the total checked after each, so a stack of large slices is refused
/// before it exhausts memory.
pub const MAX_ASSEMBLED_BYTES: u64 = 2 << 30;

/// Reads every file in order, refusing the set once its texels pass [`MAX_ASSEMBLED_BYTES`]:
/// first from the headers of all files ([`super::decoded_bytes`]), before any is decoded; then,
/// for files whose header did not tell, after each read.
fn read_all(paths: &[PathBuf], srgb: bool) -> Result<Vec<TextureData>, TextureError> {
    let claimed: u64 = paths.iter().filter_map(|p| super::decoded_bytes(p)).sum();
    if claimed > MAX_ASSEMBLED_BYTES {
        return Err(TextureError::Layout(format!(
            "{}: the {} files' headers claim {} MiB of texels, more than one texture may hold ({} MiB); nothing was \
             decoded",
            list(paths),
            paths.len(),
            claimed >> 20,
            MAX_ASSEMBLED_BYTES >> 20
        )));
    }
    let mut total = 0u64;
    let mut layers = Vec::with_capacity(paths.len());
    for path in paths {
        let layer = read_texture(path, srgb)?;
        total += layer.bytes().len() as u64;
        if total > MAX_ASSEMBLED_BYTES {
            return Err(TextureError::Layout(format!(
                "{}: the {} files hold more than {} MiB of texels by this one, more than one texture may hold",
                path.display(),
                paths.len(),
                MAX_ASSEMBLED_BYTES >> 20
            )));
        }
        layers.push(layer);
    }
    Ok(layers)
}

/// One single-image cube layout: grid size in faces, and each face's cell (column, row,
/// turned by 180°) in layer order.
struct CubeLayout {
    columns: u32,
    rows: u32,
    cells: [(u32, u32, bool); 6],
}

const CUBE_LAYOUTS: [CubeLayout; 6] = [
    // Horizontal cross.
    CubeLayout {
        columns: 4,
        rows: 3,
        cells: [(2, 1, false), (0, 1, false), (1, 0, false), (1, 2, false), (1, 1, false), (3, 1, false)],
    },
    // Vertical cross: −Z hangs under −Y, upside down.
    CubeLayout {
        columns: 3,
        rows: 4,
        cells: [(2, 1, false), (0, 1, false), (1, 0, false), (1, 2, false), (1, 1, false), (1, 3, true)],
    },
    // Godot's grids, row by row.
    CubeLayout { columns: 6, rows: 1, cells: grid(6) },
    CubeLayout { columns: 3, rows: 2, cells: grid(3) },
    CubeLayout { columns: 2, rows: 3, cells: grid(2) },
    CubeLayout { columns: 1, rows: 6, cells: grid(1) },
];

/// The cells of a grid `columns` wide, row by row.
const fn grid(columns: u32) -> [(u32, u32, bool); 6] {
    let mut cells = [(0, 0, false); 6];
    let mut i = 0;
    while i < 6 {
        cells[i] = (i as u32 % columns, i as u32 / columns, false);
        i += 1;
    }
    cells
}

/// The `w × h` texels of a 2D texture at (x, y), turned by 180° when `turned`.
fn region(image: &TextureData, x: u32, y: u32, w: u32, h: u32, turned: bool) -> Result<TextureData, TextureError> {
    let bpt = image.format().bytes_per_texel() as usize;
    let stride = image.width() as usize * bpt;
    let mut bytes = Vec::with_capacity(w as usize * h as usize * bpt);
    for row in 0..h as usize {
        let row = if turned { h as usize - 1 - row } else { row };
        let start = (y as usize + row) * stride + x as usize * bpt;
        let texels = &image.bytes()[start..start + w as usize * bpt];
        if turned {
            texels.chunks_exact(bpt).rev().for_each(|t| bytes.extend_from_slice(t));
        } else {
            bytes.extend_from_slice(texels);
        }
    }
    TextureData::new(w, h, image.format(), bytes)
}

/// Refuses layers of different sizes or formats, naming the first file and the odd one.
fn same_size_and_format(layers: &[TextureData], paths: &[PathBuf], what: &str) -> Result<(), TextureError> {
    let first = &layers[0];
    for (l, p) in layers.iter().zip(paths).skip(1) {
        if (l.width(), l.height()) != (first.width(), first.height()) {
            return Err(TextureError::Layout(format!(
                "{what} must all have one size: {} is {}×{}, {} is {}×{}",
                paths[0].display(),
                first.width(),
                first.height(),
                p.display(),
                l.width(),
                l.height()
            )));
        }
        if l.format() != first.format() {
            return Err(TextureError::Layout(format!(
                "{what} must all be of one kind: {} is {}, {} is {}",
                paths[0].display(),
                kind(first),
                p.display(),
                kind(l)
            )));
        }
    }
    Ok(())
}

/// What a file decoded to, in words (the formats [`read_texture`] gives).
fn kind(t: &TextureData) -> &'static str {
    if t.format() == super::TexelFormat::Rgba32Float { "OpenEXR (32-bit float)" } else { "8-bit (PNG)" }
}

/// A layout error prefixed by the file it came from.
fn in_file(path: &Path, e: TextureError) -> TextureError {
    TextureError::Layout(format!("{}: {e}", path.display()))
}

/// The files, comma-separated.
fn list(paths: &[PathBuf]) -> String {
    paths.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{TexelFormat, TextureShape};

    /// Writes an RGBA8 PNG whose texel (x, y) is `f(x, y)`.
    pub(crate) fn png(path: &Path, w: u32, h: u32, f: impl Fn(u32, u32) -> [u8; 4]) {
        let data: Vec<u8> = (0..h).flat_map(|y| (0..w).map(move |x| (x, y))).flat_map(|(x, y)| f(x, y)).collect();
        let mut bytes = Vec::new();
        let mut encoder = png::Encoder::new(&mut bytes, w, h);
        encoder.set_color(png::ColorType::Rgba);
        encoder.set_depth(png::BitDepth::Eight);
        encoder.write_header().and_then(|mut wr| wr.write_image_data(&data)).expect("encodes");
        std::fs::write(path, bytes).expect("writes");
    }

    #[test]
    fn crosses_and_grids_cut_faces_in_layer_order() {
        let dir = tempfile::tempdir().expect("temp dir");
        // Each 2×2 cell holds (column, row, texel index) so faces and their turn can be read.
        let cell = |x: u32, y: u32| [(x / 2) as u8, (y / 2) as u8, ((y % 2) * 2 + x % 2) as u8, 255];
        // (file, width, height, each face's cell)
        type Case = (&'static str, u32, u32, [(u8, u8); 6]);
        let cases: [Case; 3] = [
            ("h.png", 8, 6, [(2, 1), (0, 1), (1, 0), (1, 2), (1, 1), (3, 1)]),
            ("v.png", 6, 8, [(2, 1), (0, 1), (1, 0), (1, 2), (1, 1), (1, 3)]),
            ("g.png", 4, 6, [(0, 0), (1, 0), (0, 1), (1, 1), (0, 2), (1, 2)]),
        ];
        for (name, w, h, cells) in cases {
            let path = dir.path().join(name);
            png(&path, w, h, cell);
            let cube = read_cube(&[path], false).expect("reads");
            assert_eq!((cube.shape(), cube.width(), cube.layers()), (TextureShape::Cube, 2, 6));
            for (face, (c, r)) in cells.iter().enumerate() {
                let texels = &cube.bytes()[face * 16..face * 16 + 16];
                assert_eq!((texels[0], texels[1]), (*c, *r), "{name} face {face}");
                // −Z of the vertical cross is turned: its first texel is the cell's last.
                let turned = name == "v.png" && face == 5;
                assert_eq!(texels[2], if turned { 3 } else { 0 }, "{name} face {face}");
            }
        }
        let odd = dir.path().join("odd.png");
        png(&odd, 5, 3, cell);
        let err = read_cube(std::slice::from_ref(&odd), false).unwrap_err().to_string();
        assert!(err.contains("odd.png") && err.contains("no cube map layout"), "{err}");
    }

    #[test]
    fn volumes_from_grids_and_slices() {
        let dir = tempfile::tempdir().expect("temp dir");
        let grid = dir.path().join("grid.png");
        png(&grid, 6, 4, |x, y| [(x / 2 + 3 * (y / 2)) as u8, 0, 0, 255]);
        let v = read_volume(std::slice::from_ref(&grid), Some((3, 2)), false).expect("reads");
        assert_eq!((v.shape(), v.width(), v.height(), v.layers()), (TextureShape::D3, 2, 2, 6));
        assert_eq!(v.bytes().chunks(16).map(|s| s[0]).collect::<Vec<_>>(), [0, 1, 2, 3, 4, 5]);
        let err = read_volume(std::slice::from_ref(&grid), None, false).unwrap_err().to_string();
        assert!(err.contains("8×8") && err.contains("grid.png"), "{err}");

        let a = dir.path().join("a.png");
        let b = dir.path().join("b.png");
        png(&a, 2, 2, |_, _| [1, 0, 0, 255]);
        png(&b, 4, 2, |_, _| [2, 0, 0, 255]);
        let err = read_volume(&[a.clone(), b], None, false).unwrap_err().to_string();
        assert!(err.contains("a.png is 2×2") && err.contains("b.png is 4×2"), "{err}");
        let v = read_volume(&[a.clone(), a], None, true).expect("reads");
        assert_eq!((v.layers(), v.format()), (2, TexelFormat::Rgba8UnormSrgb));
    }

    #[test]
    fn a_stack_is_refused_from_its_headers_before_any_file_is_decoded() {
        let dir = tempfile::tempdir().expect("temp dir");
        // Nine files of 41 bytes, each a PNG signature and an IHDR claiming 8192² RGBA (256 MiB
        // decoded): 2.25 GiB in all. Their pixel data is missing, so decoding any of them would
        // fail with another message.
        let mut head = b"\x89PNG\r\n\x1a\n\0\0\0\x0dIHDR".to_vec();
        head.extend_from_slice(&8192u32.to_be_bytes());
        head.extend_from_slice(&8192u32.to_be_bytes());
        head.extend_from_slice(&[8, 6, 0, 0, 0, 0, 0, 0, 0]);
        let paths: Vec<PathBuf> = (0..9).map(|i| dir.path().join(format!("s{i}.png"))).collect();
        for p in &paths {
            std::fs::write(p, &head).expect("writes");
        }
        let err = read_volume(&paths, None, false).expect_err("refused").to_string();
        assert!(err.contains("headers claim 2304 MiB") && err.contains("nothing was decoded"), "{err}");
        // Under the budget, the same files reach the decoder, which refuses the missing data.
        let err = read_volume(&paths[..2], None, false).expect_err("refused").to_string();
        assert!(!err.contains("headers claim"), "{err}");
    }
}
