#!/usr/bin/env bash
# Runs the Khronos glTF validator (npm gltf-validator, installed into a temporary
# directory) on every scene under scenes/ and scenes/stress/ and fails if any
# has an error.  Also
# checks that each environment map a scene names exists.
# Usage: scripts/validate-scenes.sh [SCENEDIR]      VERBOSE=1 also prints infos/hints
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
dir=$(cd "${1:-"$here/../scenes"}" && pwd)
VALIDATOR_VERSION=2.0.0-dev.3.10

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
(cd "$tmp" && npm init -y >/dev/null 2>&1 &&
   npm install --no-audit --no-fund --silent "gltf-validator@$VALIDATOR_VERSION" >/dev/null)

shopt -s nullglob
files=("$dir"/*.gltf "$dir"/*.glb "$dir"/stress/*.gltf "$dir"/stress/*.glb)
[ ${#files[@]} -gt 0 ] || { echo "validate-scenes.sh: no scenes in $dir" >&2; exit 1; }
NODE_PATH="$tmp/node_modules" node "$here/validate_gltf.js" "${files[@]}"

# environment maps referenced from scenes[0].extras.gibench.environment.uri
NODE_PATH="$tmp/node_modules" node -e '
  const fs = require("fs"), path = require("path");
  let bad = 0;
  for (const f of process.argv.slice(1)) {
    let json;
    const b = fs.readFileSync(f);
    if (b.readUInt32LE(0) === 0x46546C67) json = JSON.parse(b.subarray(20, 20 + b.readUInt32LE(12)));
    else json = JSON.parse(b.toString("utf8"));
    const env = (((json.scenes || [])[0] || {}).extras || {}).gibench;
    if (env && env.environment) {
      const p = path.join(path.dirname(f), env.environment.uri);
      if (!fs.existsSync(p)) { console.log(`${path.basename(f)}: missing environment map ${p}`); bad++; }
      else console.log(`${path.basename(f)}: environment ${env.environment.uri} ok`);
    }
  }
  process.exit(bad ? 1 : 0);' "${files[@]}"
echo "validate-scenes.sh: all ${#files[@]} scenes passed"
