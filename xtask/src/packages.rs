//! The Debian packages each command needs, which of them are missing, and installing those.
//!
//! What is installed is asked of dpkg (`dpkg-query -W`), not guessed from files. Installing goes
//! through `apt-get` (found on PATH): directly as root, else through `sudo`. Without apt-get (not
//! Debian or Ubuntu) nothing can be checked or installed, and the package names are printed.

use std::collections::BTreeSet;
use std::io::IsTerminal;
use std::process::{Command, Stdio};

use crate::{Failure, find_on_path, say};

/// What a command needs the machine to have.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Task {
    /// `cargo xtask demo`: a Vulkan adapter.
    Demo,
    /// `cargo xtask test`: everything the test suite runs.
    Test,
}

/// Packages installed together, for one reason.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Group {
    pub packages: &'static [&'static str],
    /// Why the command needs them, as printed when they are installed.
    pub why: &'static str,
}

/// Lavapipe (in mesa-vulkan-drivers) and the loader: both commands render.
const VULKAN: Group = Group {
    packages: &["mesa-vulkan-drivers", "libvulkan1"],
    why: "gdsky renders on Vulkan; lavapipe, Mesa's CPU driver, is the adapter where there is no GPU",
};

const TOOLCHAIN: Group =
    Group { packages: &["build-essential"], why: "a C compiler for build scripts (a benchmark dependency compiles C)" };

const SPIRV_TOOLS: Group = Group {
    packages: &["spirv-tools"],
    why: "the conversion tests run `spirv-val` on every SPIR-V module gdsky writes",
};

const CHROMIUM: Group = Group {
    packages: &["chromium"],
    why: "it runs the Godot oracle (Godot 4.6's Web export, headless) that the parity tests compare against",
};

const NODE: Group = Group {
    packages: &["nodejs", "npm"],
    why: "Node.js drives Chromium for the Godot oracle, and npm fetches the oracle's parts",
};

/// What each package is, for a machine without apt-get, whose package manager names them otherwise.
pub fn describe(package: &str) -> &'static str {
    match package {
        "mesa-vulkan-drivers" => "Mesa's Vulkan drivers, with lavapipe (a CPU Vulkan driver)",
        "libvulkan1" => "the Vulkan loader",
        "build-essential" => "a C compiler, make and the C library headers",
        "spirv-tools" => "the SPIR-V tools (spirv-val)",
        "chromium" => "the Chromium browser",
        "nodejs" => "Node.js (18 or newer)",
        "npm" => "npm, Node.js's package manager",
        _ => "",
    }
}

/// The groups `task` needs. Node.js is needed only when `node` or `npm` is not on PATH: a
/// Node.js installed otherwise (nvm, NodeSource) is used as it is.
pub fn groups(task: Task, node_and_npm_on_path: bool) -> Vec<Group> {
    match task {
        Task::Demo => vec![VULKAN],
        Task::Test => {
            let mut groups = vec![TOOLCHAIN, SPIRV_TOOLS, VULKAN];
            // A Chromium the user points the oracle at (SKYORACLE_CHROMIUM) replaces Debian's.
            if !std::env::var_os("SKYORACLE_CHROMIUM").is_some_and(|p| crate::is_executable(std::path::Path::new(&p))) {
                groups.push(CHROMIUM);
            }
            if !node_and_npm_on_path {
                groups.push(NODE);
            }
            groups
        }
    }
}

/// The packages of `wanted` that dpkg does not report installed, in `wanted`'s order.
/// `dpkg_output` is `dpkg-query -W --showformat='${Package}\t${Status}\n' PACKAGE...`'s output: a
/// line per package dpkg knows (one per architecture for a multi-arch package), whose status
/// ends in `installed` when it is (`install ok installed`, `hold ok installed`). Packages dpkg
/// has never seen have no line (dpkg-query says so on stderr and exits 1).
pub fn missing<'a>(wanted: &[&'a str], dpkg_output: &str) -> Vec<&'a str> {
    let installed: BTreeSet<&str> = dpkg_output
        .lines()
        .filter_map(|line| {
            let (package, status) = line.split_once('\t')?;
            (status.split_whitespace().nth(2) == Some("installed")).then_some(package.trim())
        })
        .collect();
    wanted.iter().copied().filter(|p| !installed.contains(p)).collect()
}

/// Whether `/etc/os-release`'s text names Ubuntu or a derivative of it.
pub fn is_ubuntu(os_release: &str) -> bool {
    os_release.lines().any(|line| {
        let line = line.trim();
        let value = |key: &str| line.strip_prefix(key).map(|v| v.trim_matches('"').to_ascii_lowercase());
        value("ID=").is_some_and(|v| v == "ubuntu")
            || value("ID_LIKE=").is_some_and(|v| v.split(' ').any(|w| w == "ubuntu"))
    })
}

/// Makes sure every package `task` needs is installed, installing what is missing with one
/// `apt-get update` and one `apt-get install`. When nothing is missing it says so in one line.
pub fn ensure(task: Task) -> Result<(), Failure> {
    let node_on_path = find_on_path("node").is_some() && find_on_path("npm").is_some();
    let groups = groups(task, node_on_path);
    let wanted: Vec<&str> = groups.iter().flat_map(|g| g.packages.iter().copied()).collect();
    let node_note = if task == Task::Test && node_on_path { "; node and npm are on PATH" } else { "" };

    let Some(dpkg_query) = find_on_path("dpkg-query") else {
        return Err(no_apt(
            &wanted,
            "dpkg-query is not on PATH (not Debian or Ubuntu?), so the system packages cannot be checked or installed",
            task,
        ));
    };
    let output = Command::new(&dpkg_query)
        .arg("-W")
        .arg("--showformat=${Package}\t${Status}\n")
        .args(&wanted)
        .stderr(Stdio::null())
        .output()
        .map_err(|e| Failure::env(format!("cannot run {}: {e}", dpkg_query.display())))?;
    let missing = missing(&wanted, &String::from_utf8_lossy(&output.stdout));
    if missing.is_empty() {
        say(&format!("system packages present: {}{node_note}; nothing to install", wanted.join(" ")));
        return Ok(());
    }

    // Ubuntu has no `chromium` deb (its chromium-browser is a snap): say how to bring one.
    if missing.contains(&"chromium") && is_ubuntu(&std::fs::read_to_string("/etc/os-release").unwrap_or_default()) {
        return Err(Failure::env(
            "Ubuntu ships Chromium only as a snap, which apt-get cannot install here: run \
             `sudo snap install chromium`, then `SKYORACLE_CHROMIUM=/snap/bin/chromium cargo xtask test` \
             (the oracle starts that executable instead of Debian's /usr/bin/chromium)",
        ));
    }
    let Some(apt_get) = find_on_path("apt-get") else {
        return Err(no_apt(
            &missing,
            "apt-get is not on PATH (not Debian or Ubuntu?) to install the missing packages",
            task,
        ));
    };
    let present: Vec<&str> = wanted.iter().copied().filter(|p| !missing.contains(p)).collect();
    if !present.is_empty() {
        say(&format!("present: {}{node_note}", present.join(" ")));
    }
    let prefix = privilege(&missing);
    let verb = if prefix.is_ok() { "installing" } else { "missing" };
    for group in &groups {
        let absent: Vec<&str> = group.packages.iter().copied().filter(|p| missing.contains(p)).collect();
        if !absent.is_empty() {
            say(&format!("{verb} {}: {}", absent.join(" "), group.why));
        }
    }
    let prefix = prefix?;
    let apt = |args: &[&str]| -> Result<(), Failure> {
        let mut argv: Vec<String> = prefix.clone();
        argv.push(apt_get.display().to_string());
        // Wait for another apt or dpkg run to finish rather than fail on its lock.
        argv.extend(["-o", "DPkg::Lock::Timeout=300", "-q"].map(String::from));
        argv.extend(args.iter().map(|s| s.to_string()));
        say(&format!("running: {}", argv.join(" ")));
        let status = Command::new(&argv[0])
            .args(&argv[1..])
            .env("DEBIAN_FRONTEND", "noninteractive")
            .status()
            .map_err(|e| Failure::env(format!("cannot run {}: {e}", argv[0])))?;
        if status.success() {
            Ok(())
        } else {
            Err(Failure::env(format!(
                "`{}` failed ({status}); install these packages and run again: {}",
                argv.join(" "),
                missing.join(" ")
            )))
        }
    };
    apt(&["update"])?;
    let mut install = vec!["install", "-y", "--no-install-recommends"];
    install.extend(missing.iter().copied());
    apt(&install)?;
    say(&format!("installed: {}", missing.join(" ")));
    Ok(())
}

/// How to run apt-get: directly as root; else through `sudo -n` when sudo needs no password,
/// through `sudo` (which asks for it) when there is a terminal to ask on; else an error.
/// `sudo` resets the environment, so `env` passes DEBIAN_FRONTEND through it.
fn privilege(missing: &[&str]) -> Result<Vec<String>, Failure> {
    if effective_uid() == Some(0) {
        return Ok(Vec::new());
    }
    let by_hand = format!("as root: apt-get install -y --no-install-recommends {}", missing.join(" "));
    let Some(sudo) = find_on_path("sudo") else {
        return Err(Failure::env(format!("installing needs root, and sudo is not on PATH; install them {by_hand}")));
    };
    let sudo = sudo.display().to_string();
    let sudo_env = |extra: &[&str]| -> Vec<String> {
        let mut argv = vec![sudo.clone()];
        argv.extend(extra.iter().map(|s| s.to_string()));
        argv.extend(["env".to_string(), "DEBIAN_FRONTEND=noninteractive".to_string()]);
        argv
    };
    let passwordless = Command::new(&sudo)
        .args(["-n", "true"])
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if passwordless {
        Ok(sudo_env(&["-n"]))
    } else if std::io::stdin().is_terminal() {
        say("not root: installing through sudo, which may ask for your password");
        Ok(sudo_env(&[]))
    } else {
        Err(Failure::env(format!(
            "installing needs root; sudo needs a password and there is no terminal to ask for it on: install them {by_hand}"
        )))
    }
}

/// The process's effective user id: from /proc/self/status, else `id -u`.
fn effective_uid() -> Option<u32> {
    if let Some(uid) = std::fs::read_to_string("/proc/self/status").ok().as_deref().and_then(parse_effective_uid) {
        return Some(uid);
    }
    let output = Command::new("id").arg("-u").stderr(Stdio::null()).output().ok()?;
    String::from_utf8_lossy(&output.stdout).trim().parse().ok()
}

/// The effective uid from /proc/self/status's `Uid:` line (real, effective, saved, filesystem).
pub fn parse_effective_uid(status: &str) -> Option<u32> {
    let line = status.lines().find_map(|l| l.strip_prefix("Uid:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

/// The error for a machine without apt-get: the packages by their Debian names and what each is.
fn no_apt(packages: &[&str], reason: &str, task: Task) -> Failure {
    let width = packages.iter().map(|p| p.len()).max().unwrap_or(0);
    let mut message = format!("{reason}; install these with your package manager (Debian names):");
    for p in packages {
        message.push_str(&format!("\n  {p:width$}  {}", describe(p)));
    }
    let direct = match task {
        Task::Demo => "cargo run --release -- demo",
        Task::Test => "bash scripts/install-oracle.sh && cargo test --workspace --locked",
    };
    message.push_str(&format!("\nthen run `{direct}` directly (it is what this command runs once they are there)."));
    Failure::env(message)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn missing_reads_dpkg_status() {
        let wanted = ["build-essential", "spirv-tools", "mesa-vulkan-drivers", "libvulkan1", "chromium"];
        // dpkg-query prints nothing for packages it has never seen (spirv-tools here).
        let dpkg = "build-essential\tinstall ok installed\n\
                    mesa-vulkan-drivers\tdeinstall ok config-files\n\
                    libvulkan1\tinstall ok installed\n\
                    libvulkan1\tinstall ok installed\n\
                    chromium\tinstall ok unpacked\n";
        assert_eq!(missing(&wanted, dpkg), ["spirv-tools", "mesa-vulkan-drivers", "chromium"]);
    }

    #[test]
    fn missing_accepts_held_and_any_architecture() {
        let wanted = ["libvulkan1", "chromium"];
        let dpkg =
            "libvulkan1\tdeinstall ok not-installed\nlibvulkan1\tinstall ok installed\nchromium\thold ok installed\n";
        assert!(missing(&wanted, dpkg).is_empty());
    }

    #[test]
    fn missing_is_everything_without_dpkg_lines() {
        assert_eq!(missing(&["libvulkan1", "chromium"], ""), ["libvulkan1", "chromium"]);
        assert_eq!(missing(&["npm"], "npm\tunknown ok not-installed\n"), ["npm"]);
    }

    #[test]
    fn groups_per_task() {
        let names = |gs: Vec<Group>| gs.iter().flat_map(|g| g.packages.iter().copied()).collect::<Vec<_>>();
        assert_eq!(names(groups(Task::Demo, false)), ["mesa-vulkan-drivers", "libvulkan1"]);
        assert_eq!(
            names(groups(Task::Test, true)),
            ["build-essential", "spirv-tools", "mesa-vulkan-drivers", "libvulkan1", "chromium"]
        );
        assert_eq!(names(groups(Task::Test, false)).last(), Some(&"npm"));
        for p in names(groups(Task::Test, false)) {
            assert!(!describe(p).is_empty(), "{p} has no description");
        }
    }

    #[test]
    fn ubuntu_and_its_derivatives_are_recognised() {
        assert!(is_ubuntu("NAME=\"Ubuntu\"\nID=ubuntu\nID_LIKE=debian\n"));
        assert!(is_ubuntu("ID=pop\nID_LIKE=\"ubuntu debian\"\n"));
        assert!(!is_ubuntu("PRETTY_NAME=\"Debian GNU/Linux 12 (bookworm)\"\nID=debian\n"));
    }

    #[test]
    fn effective_uid_from_proc_status() {
        let status = "Name:\txtask\nUmask:\t0022\nUid:\t1000\t0\t0\t0\nGid:\t1000\t1000\t1000\t1000\n";
        assert_eq!(parse_effective_uid(status), Some(0));
        assert_eq!(parse_effective_uid("Name:\tx\n"), None);
    }

    #[test]
    fn no_apt_names_each_package() {
        let f = no_apt(&["libvulkan1", "mesa-vulkan-drivers"], "apt-get is not on PATH", Task::Demo);
        assert_eq!(f.code, 2);
        assert!(f.message.contains("\n  libvulkan1           the Vulkan loader"), "{}", f.message);
        assert!(f.message.contains("cargo run --release -- demo"));
    }
}
