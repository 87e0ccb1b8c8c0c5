#!/usr/bin/env bash
# Downloads the corpus shaders (tests/corpus/*.toml name each one's repository, path and commit)
# from their own repositories into DIR, named as their sidecars, for
#   GDSKY_CORPUS_DIR=DIR cargo test --test godot corpus -- --ignored
# The shaders are not kept in gdsky's repository; see docs/corpus.md. Needs curl and network.
set -euo pipefail
dir=${1:?usage: bash scripts/fetch-corpus.sh DIR}
root=$(cd "$(dirname "$0")/.." && pwd)
mkdir -p "$dir"
field() { sed -n "s/^$1 = \"\(.*\)\"$/\1/p" "$2" | head -n 1; }
failed=0
for sidecar in "$root"/tests/corpus/*.toml; do
  name=$(basename "$sidecar" .toml)
  repo=$(field repo "$sidecar"); path=$(field path "$sidecar"); commit=$(field commit "$sidecar")
  slug=${repo#https://github.com/}
  base="https://raw.githubusercontent.com/$slug/$commit"
  if ! curl -fsSL "$base/$path" -o "$dir/$name.gdshader"; then
    echo "fetch-corpus: $name: cannot download $base/$path" >&2; failed=1; continue
  fi
  # Includes: `"relative/name" = "local file"` lines under [includes], relative to the shader.
  sed -n '/^\[includes\]/,/^\[/p' "$sidecar" | sed -n 's/^"\(.*\)" = "\(.*\)"$/\1 \2/p' |
    while read -r relative local; do
      curl -fsSL "$base/$(dirname "$path")/$relative" -o "$dir/$local" ||
        { echo "fetch-corpus: $name: cannot download include $relative" >&2; exit 1; }
    done || failed=1
done
count=$(ls "$dir"/*.gdshader 2>/dev/null | wc -l)
echo "fetch-corpus: $count shaders in $dir"
exit $failed
