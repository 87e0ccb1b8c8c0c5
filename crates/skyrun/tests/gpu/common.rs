//! What the GPU tests share: skytest's adapter, the converted Freeman sky and spirv-val.

pub use skytest::{converted_freeman, gpu};

/// Runs `spirv-val --target-env vulkan1.1` on `words`; panics with its message if it refuses.
pub fn spirv_val(words: &[u32]) {
    if let Err(message) = skytest::spirv_val(words) {
        panic!("spirv-val refuses the module: {message}");
    }
}
