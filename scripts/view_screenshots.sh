#!/usr/bin/env bash
# The README's pictures of gibench view (docs/images/view_*.png): the scripted
# viewer under Xvfb at 1280x720 (a 940x720 image and the 340-pixel panels
# beside it) on the Cornell box, written by its window-shot script line.
#   scripts/view_screenshots.sh [BUILD_DIR]     (default build/release)
# view_panels.png:  csm with its parameters, frame times, the reference's
#                   progress, the live relMSE and the pixel read-out under the mouse
# view_split.png:   csm left of the divider, direct right (split2), zoomed 2x
# view_buffer.png:  csm's debug buffer "visibility" (its shadow term) in the image region
set -eu
root=$(cd "$(dirname "$0")/.." && pwd)
gib=${1:-$root/build/release}/bin/gibench
out=$root/docs/images
[ -x "$gib" ] || { echo "view_screenshots.sh: no $gib (build it first)" >&2; exit 2; }
command -v xvfb-run >/dev/null || { echo "view_screenshots.sh: xvfb-run is not installed (scripts/install-deps.sh)" >&2; exit 2; }
mkdir -p "$out"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cat >"$tmp/script.txt" <<SCRIPT
wait 2
wait-spp 16
move 520 420
wait 1
window-shot $out/view_panels.png
split2 direct
zoom 2 470 420
wait 1
window-shot $out/view_split.png
split2 none
key Z
source buffer visibility
window-shot $out/view_buffer.png
SCRIPT
xvfb-run -a -s "-screen 0 1400x800x24" "$gib" -q view --scene "$root/scenes/cornell_box.gltf" \
    --method csm --size 940x720 --panels on --script "$tmp/script.txt"
ls -l "$out"/view_panels.png "$out"/view_split.png "$out"/view_buffer.png
