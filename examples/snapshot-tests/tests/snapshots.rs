//! Golden images: each sky rendered in gdsky's default views (four panoramas with the sun over
//! the day, a camera toward the sun and one toward the zenith) against tests/snapshots/<name>.exr.
//! A change fails with `<name>.new.exr`, `<name>.new.png` and `<name>.diff.png` beside the golden;
//! `UPDATE_SNAPSHOTS=1 cargo test` makes the new render the golden.

#[test]
fn freeman_sky() {
    gdsky::testing::assert_sky_snapshot("freeman_sky", "shaders/freeman_sky.gdshader");
}

/// A Godot material: its values and its generated NoiseTexture2D come with it.
#[test]
fn noise_clouds_material() {
    gdsky::testing::assert_sky_snapshot("noise_clouds", "godot/materials/noise_clouds.tres");
}
