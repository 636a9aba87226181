#!/usr/bin/env bash
# Regenerates everything under scenes/ (except README.md) from packaged sources
# (and the stress-case scenes under scenes/stress/, which need no inputs:
# scripts/make_stress_scenes.py):
#   Debian embree-tools   .../embree3/models/cornell_box.obj
#   Debian blender-data   .../studiolights/world/forest.exr  (CC0)
#   Debian openimageio-tools  oiiotool (downsizes the environment map)
#   npm bunny@1.0.1, teapot@1.0.0  (installed into a temporary directory)
# Needs python3 (stdlib only), node and npm.  Install the Debian packages with
#   scripts/install-deps.sh --sources
# Usage: scripts/make-scenes.sh [OUTDIR]   (default: scenes/ next to scripts/)
set -euo pipefail

here=$(cd "$(dirname "$0")" && pwd)
out=${1:-"$here/../scenes"}
mkdir -p "$out/env"
out=$(cd "$out" && pwd)

ENV_NAME=forest
BUNNY_VERSION=1.0.1
TEAPOT_VERSION=1.0.0

find_pkg_file() {  # package, path suffix
  local f
  f=$(dpkg -L "$1" 2>/dev/null | grep -E "$2\$" | head -n1 || true)
  if [ -z "$f" ] || [ ! -f "$f" ]; then
    echo "make-scenes.sh: $2 not found; install Debian package $1 (scripts/install-deps.sh --sources)" >&2
    exit 2
  fi
  echo "$f"
}
for tool in python3 node npm oiiotool; do
  command -v "$tool" >/dev/null || { echo "make-scenes.sh: $tool is missing" >&2; exit 2; }
done

obj=$(find_pkg_file embree-tools /cornell_box.obj)
hdr=$(find_pkg_file blender-data "/studiolights/world/$ENV_NAME.exr")

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
(cd "$tmp" && npm init -y >/dev/null 2>&1 &&
   npm install --no-audit --no-fund --silent "bunny@$BUNNY_VERSION" "teapot@$TEAPOT_VERSION" >/dev/null)
NODE_PATH="$tmp/node_modules" node -e '
  const b = require("bunny"), t = require("teapot");
  process.stdout.write(JSON.stringify({
    bunny: {positions: b.positions, cells: b.cells},
    teapot: {positions: t.positions, cells: t.cells}}));' > "$tmp/meshes.json"

# Environment map: 1024x512 float -> 512x256 half, box filter (keeps the mean),
# negative DWA ringing clamped to 0, lossless zip, deterministic attributes.
oiiotool "$hdr" --resize:filter=box 512x256 --clamp:min=0 \
  --eraseattrib "Exif:ImageHistory" --nosoftwareattrib \
  --attrib ImageDescription "Blender studiolight $ENV_NAME.exr (CC0, Greg Zaal / HDRI Haven), box-filtered to 512x256, equirectangular, linear RGB" \
  -d half --compression zip -o "$out/env/$ENV_NAME.exr"

python3 "$here/make_scenes.py" --cornell-obj "$obj" --meshes-json "$tmp/meshes.json" \
  --env-name "$ENV_NAME" --out "$out"
python3 "$here/make_stress_scenes.py" --out "$out/stress"
