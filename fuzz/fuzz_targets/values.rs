//! Feeds arbitrary text to the value parser behind every `--set NAME=VALUE` (and a scene file's
//! and a material's values) for every uniform type a sky shader can have. Any panic is a bug: a
//! value parses to a constant of its type or is refused with a message.
#![no_main]

use gdshader::check::types::{Scalar, Type};

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let scalars = [Scalar::Bool, Scalar::Int, Scalar::UInt, Scalar::Float];
    let mut types: Vec<Type> = scalars.iter().map(|s| Type::Scalar(*s)).collect();
    for s in scalars {
        for n in 2..=4 {
            types.push(Type::Vector(s, n));
        }
    }
    types.extend((2..=4).map(Type::Matrix));
    types.push(Type::Array(Box::new(Type::Scalar(Scalar::Float)), 3));
    types.push(Type::Array(Box::new(Type::Vector(Scalar::Float, 3)), 2));
    for ty in &types {
        if let Ok(value) = gdshader::values::parse_value(ty, text) {
            // What parses is finite and of its type: printing it back must not panic either.
            let _ = format!("{value:?}");
        }
    }
});
