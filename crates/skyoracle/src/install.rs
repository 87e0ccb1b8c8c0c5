//! Where the oracle's parts are, and exactly which are missing.

use std::fmt;
use std::path::{Path, PathBuf};

/// The command that installs every part, run from the repository root.
pub const INSTALL_COMMAND: &str = "bash scripts/install-oracle.sh";

/// Where Debian's package puts Chromium. `SKYORACLE_CHROMIUM` overrides it.
const CHROMIUM: &str = "/usr/bin/chromium";

/// The oracle's parts, all present.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Installation {
    /// The repository root given to [`Installation::find`].
    pub root: PathBuf,
    /// `ROOT/.oracle`: the Godot export (`godot/`) and `node_modules/playwright-core`.
    pub oracle_dir: PathBuf,
    /// The `node` executable.
    pub node: PathBuf,
    /// The Chromium executable.
    pub chromium: PathBuf,
}

/// One absent part of the oracle.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum MissingPart {
    /// No Chromium executable at this path (Debian: `apt-get install -y chromium`).
    Chromium(PathBuf),
    /// No `node` on PATH (or at `SKYORACLE_NODE`).
    Node,
    /// The Godot Web export's `index.wasm` or `index.js` is not at this path.
    GodotExport(PathBuf),
    /// playwright-core's `package.json` is not at this path.
    PlaywrightCore(PathBuf),
}

impl fmt::Display for MissingPart {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Chromium(p) => write!(f, "the chromium browser ({} not found)", p.display()),
            Self::Node => write!(f, "node (Node.js 18 or newer, not found on PATH)"),
            Self::GodotExport(p) => write!(f, "the Godot 4.6 Web export ({} not found)", p.display()),
            Self::PlaywrightCore(p) => write!(f, "the npm package playwright-core ({} not found)", p.display()),
        }
    }
}

/// The oracle is not installed: every missing part, and how to install them.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Missing {
    /// The repository root that was searched.
    pub root: PathBuf,
    /// What is absent (never empty).
    pub parts: Vec<MissingPart>,
}

impl Missing {
    /// The command that installs the missing parts ([`INSTALL_COMMAND`]).
    pub fn install_command(&self) -> &'static str {
        INSTALL_COMMAND
    }
}

impl fmt::Display for Missing {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "the Godot oracle is not installed: missing ")?;
        for (i, part) in self.parts.iter().enumerate() {
            if i > 0 {
                write!(f, "; ")?;
            }
            write!(f, "{part}")?;
        }
        write!(f, ". Install it with `{INSTALL_COMMAND}` in {} (as root, for apt-get)", self.root.display())
    }
}

impl std::error::Error for Missing {}

impl Installation {
    /// Finds the oracle's parts for the repository at `root`.
    pub fn find(root: &Path) -> Result<Self, Missing> {
        // Canonical, so that messages name the directory plainly (not `crates/x/../..`).
        let root = &root.canonicalize().unwrap_or_else(|_| root.to_path_buf());
        let oracle_dir = root.join(".oracle");
        let mut parts = Vec::new();

        let chromium = std::env::var_os("SKYORACLE_CHROMIUM").map_or_else(|| PathBuf::from(CHROMIUM), PathBuf::from);
        if !is_executable(&chromium) {
            parts.push(MissingPart::Chromium(chromium.clone()));
        }
        let node = std::env::var_os("SKYORACLE_NODE").map(PathBuf::from).or_else(|| on_path("node"));
        if node.as_deref().is_none_or(|n| !is_executable(n)) {
            parts.push(MissingPart::Node);
        }
        for file in ["index.wasm", "index.js"] {
            let path = oracle_dir.join("godot").join(file);
            if !path.is_file() {
                parts.push(MissingPart::GodotExport(path));
                break;
            }
        }
        let playwright = oracle_dir.join("node_modules/playwright-core/package.json");
        if !playwright.is_file() {
            parts.push(MissingPart::PlaywrightCore(playwright));
        }

        match node {
            Some(node) if parts.is_empty() => Ok(Self { root: root.to_path_buf(), oracle_dir, node, chromium }),
            _ => Err(Missing { root: root.to_path_buf(), parts }),
        }
    }
}

fn is_executable(path: &Path) -> bool {
    use std::os::unix::fs::PermissionsExt;
    path.metadata().is_ok_and(|m| m.is_file() && m.permissions().mode() & 0o111 != 0)
}

fn on_path(name: &str) -> Option<PathBuf> {
    std::env::split_paths(&std::env::var_os("PATH")?).map(|dir| dir.join(name)).find(|p| is_executable(p))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_empty_root_lists_the_export_and_playwright() {
        let root = std::env::temp_dir().join(format!("skyoracle-missing-{}", std::process::id()));
        let missing = Installation::find(&root).expect_err("nothing is installed there");
        assert!(missing.parts.iter().any(|p| matches!(p, MissingPart::GodotExport(_))));
        assert!(missing.parts.iter().any(|p| matches!(p, MissingPart::PlaywrightCore(_))));
        let text = missing.to_string();
        assert!(text.contains("index.wasm") && text.contains(INSTALL_COMMAND), "{text}");
    }
}
