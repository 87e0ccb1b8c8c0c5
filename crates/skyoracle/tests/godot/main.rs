//! The oracle against real Godot 4.6, one binary sharing one oracle (`skytest::oracle`): Godot's
//! Web export booted in headless Chromium. Needs `bash scripts/install-oracle.sh`; without it
//! every test fails with the message that says what is missing. `oracle`: what the oracle
//! recovers and its conventions; `debanding`: Godot's dithered store.

mod debanding;
mod oracle;
