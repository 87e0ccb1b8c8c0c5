//! `gdsky::testing::assert_matches_godot` (feature `testing`, on under `cargo test --workspace`)
//! on a Godot material with a generated noise texture: gdsky's render of the default camera
//! views against Godot's, through the oracle, within `Tolerance::godot`.

#[test]
fn noise_clouds_material_matches_godot_through_the_testing_api() {
    gdsky::testing::assert_matches_godot(
        "fixtures/godot_project/materials/noise_clouds.tres",
        &gdsky::testing::View::default_cameras(),
    );
}
