//! `gdsky render --debanding none|godot` (Godot's sky debanding for `use_debanding` shaders) and
//! `--sky-coords exact|godot46` (Godot 4.6's approximate SKY_COORDS): options of Godot's sky
//! wrapper, applied by lowering the shader again.

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

/// The values of `--sky-coords`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, ValueEnum)]
pub enum SkyCoordsArg {
    /// `atan2(d.x, −d.z) / 2π` and `acos(d.y) / π`, exact, as Godot 4.3–4.5 (the default).
    #[default]
    Exact,
    /// Godot 4.6's polynomial `atan2_approx`/`acos_approx` (v off the exact value by up to
    /// 2.9e-3): what Godot 4.6, and so the oracle, computes; a texture of independent texels
    /// sampled at SKY_COORDS (hashed stars) then lands on the texels Godot 4.6 picks.
    Godot46,
}

/// Lowers `loaded` again with Godot's debanding when `mode` is `godot` and the shader declares
/// `use_debanding`, and with Godot 4.6's SKY_COORDS when `coords` says so and the shader reads
/// SKY_COORDS; otherwise leaves it as it is. Diagnostics printed, exit 1.
pub fn apply(loaded: &mut LoadedShader, mode: DebandingArg, coords: SkyCoordsArg) -> Result<(), ExitCode> {
    let declared = loaded.front.shader.as_ref().is_some_and(|s| s.render_modes.iter().any(|m| m == "use_debanding"));
    let debanding = mode == DebandingArg::Godot && declared;
    let reads_coords = loaded.front.shader.as_ref().is_some_and(|s| s.builtins_used.contains("SKY_COORDS"));
    let godot46 = coords == SkyCoordsArg::Godot46 && reads_coords;
    if !debanding && !godot46 {
        return Ok(());
    }
    let fail = |d: Vec<gdsky::Diagnostic>| {
        let color = std::io::stderr().is_terminal() && std::env::var_os("NO_COLOR").is_none();
        eprint!("{}", render_human(&loaded.front.db, &d, color));
        ExitCode::from(1)
    };
    let lowered = gdsky_naga::lower_for_godot(
        &loaded.front,
        &loaded.baked,
        &loaded.overrides,
        if debanding { gdsky_naga::Debanding::Godot } else { gdsky_naga::Debanding::None },
        if godot46 { gdsky_naga::SkyCoords::Godot46 } else { gdsky_naga::SkyCoords::Exact },
    )
    .map_err(fail)?;
    let wgsl = gdsky_naga::to_wgsl(&lowered).map_err(|err| fail(vec![err.diagnostic(&loaded.front)]))?;
    (loaded.lowered, loaded.wgsl) = (lowered, wgsl);
    Ok(())
}
