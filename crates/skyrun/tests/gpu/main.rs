//! skyrun on a real Vulkan device (lavapipe where there is no GPU): the converted Freeman sky
//! against skyref over the scene matrix, its f64 evaluation and routines, the hand-written port,
//! specialised modules and Godot's sub-passes. Without an adapter the tests fail, they do not
//! skip.

mod common;
mod f64_math;
mod freeman_f64;
mod freeman_lavapipe;
mod freeman_matrix;
mod hand_port;
mod specialize;
mod sub_passes;
