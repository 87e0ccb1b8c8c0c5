fn main() {
    if let Err(err) = gdsky::build::compile("../../fixtures/freeman_sky.gdshader") {
        panic!("{err}");
    }
}
