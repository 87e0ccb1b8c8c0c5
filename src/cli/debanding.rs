//! `gdsky render --debanding none|godot`: Godot's sky debanding for `use_debanding` shaders.

use super::scene::LoadedShader;
use clap::ValueEnum;
use gdsky::frontend::diag::render_human;
use std::io::IsTerminal;
use std::process::ExitCode;

/// The values of `--debanding`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, ValueEnum)]
pub enum DebandingArg {
    /// The shader's linear COLOR, no noise (the default).
    #[default]
    None,
    /// Where the shader declares `render_mode use_debanding`, add Godot's interleaved-gradient
    /// noise as Godot's sky pass does (±1/255 per channel, a fixed pattern of FRAGCOORD; see
    /// docs/godot.md, "Debanding"). Shaders without `use_debanding` are unchanged.
    Godot,
}

/// Lowers `loaded` again with Godot's debanding when `mode` is `godot` and the shader declares
/// `use_debanding`; otherwise leaves it as it is. Diagnostics printed, exit 1.
pub fn apply(loaded: &mut LoadedShader, mode: DebandingArg) -> Result<(), ExitCode> {
    let declared = loaded.front.shader.as_ref().is_some_and(|s| s.render_modes.iter().any(|m| m == "use_debanding"));
    if mode == DebandingArg::None || !declared {
        return Ok(());
    }
    let fail = |d: Vec<gdsky::Diagnostic>| {
        let color = std::io::stderr().is_terminal() && std::env::var_os("NO_COLOR").is_none();
        eprint!("{}", render_human(&loaded.front.db, &d, color));
        ExitCode::from(1)
    };
    let lowered =
        gdsky_naga::lower_with_options(&loaded.front, &loaded.baked, &loaded.overrides, gdsky_naga::Debanding::Godot)
            .map_err(fail)?;
    let wgsl = gdsky_naga::to_wgsl(&lowered).map_err(|err| fail(vec![err.diagnostic(&loaded.front)]))?;
    (loaded.lowered, loaded.wgsl) = (lowered, wgsl);
    Ok(())
}
