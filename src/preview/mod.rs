//! # `gdsky preview`: the sky live in the browser
//!
//! Shader authors iterate by looking. This module serves one page on `127.0.0.1` that runs the
//! converted WGSL in the browser's WebGPU and builds Godot's inspector from the reflection:
//! `hint_range` sliders with their step, `source_color` pickers, bools, ints and vectors,
//! `group_uniforms` as sections and doc comments as tooltips; the sun and the camera move by
//! dragging on the sky, `TIME` plays, pauses and scrubs. When the shader, one of its includes,
//! its scene file or material, or one of its textures changes on disk, the server converts it
//! again and pushes the new state to the page (server-sent events); a shader that no longer
//! converts keeps the last good module on the page with gdsky's located diagnostic over it.
//!
//! What the server answers, and nothing else (it never maps a request path to a file):
//!
//! | path | what |
//! | --- | --- |
//! | `/` | the page |
//! | `/preview.js` | its script |
//! | `/state.json` | the module (WGSL), its reflection, the resources to bind, the scene, the error |
//! | `/material.bin` | the material block's bytes: the shader's defaults with the file's and `--set` values |
//! | `/texture/N` | texture N's texels, as the state lists them |
//! | `/events` | server-sent events: `state` with the new version whenever it changes |
//! | `POST /render` | the page's state (scene, material block) rendered by gdsky on Vulkan: raw f32 RGBA, `X-Width`/`X-Height` |
//!
//! Every request must name the server as its `Host` (`127.0.0.1:PORT` or `localhost:PORT`), so
//! a DNS-rebinding page cannot reach it, and a request that carries an `Origin` must come from
//! the page itself; others get 403. The listener is bound to `127.0.0.1` only.
//!
//! The page computes the built-ins (`SkyBuiltins`: camera basis, lights, time, size) the way
//! `gdsky render` does (skycore's conventions: a light at elevation e and azimuth a points along
//! (cos e sin a, sin e, −cos e cos a); the camera's basis is R_y(yaw)·R_x(pitch)), so its pixels,
//! read back, are comparable with `gdsky render` of the same state (tests/godot/preview.rs).

mod lavapipe;
mod server;
mod state;

pub use server::{Preview, PreviewError};
pub use state::{PageState, load_state};
