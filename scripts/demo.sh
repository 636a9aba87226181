#!/usr/bin/env bash
# The demo behind `make demo`: renders the Cornell box with every installed
# method (today: the direct-light baseline) and writes a small report.
#   scripts/demo.sh GIBENCH OUTDIR
set -euo pipefail
gibench=${1:?usage: demo.sh GIBENCH OUTDIR}
out=${2:?usage: demo.sh GIBENCH OUTDIR}
scene=scenes/cornell_box.gltf
size=${DEMO_SIZE:-256x256}
frames=${DEMO_FRAMES:-8}
mkdir -p "$out"

"$gibench" methods > "$out/methods.txt"
methods=$("$gibench" methods --json | sed -n 's/^ *"id": *"\([a-z0-9_]*\)".*/\1/p')
report="$out/report.md"
{
  echo "# gibench demo: $scene at $size, $frames frames"
  echo
  echo "Made by \`make demo\` (scripts/demo.sh) on $(date -u +%Y-%m-%d). Radiance images are"
  echo "linear EXR; the PNGs are tonemapped (exposure 0, sRGB)."
  echo
} > "$report.tmp"
for m in $methods; do
  echo "demo: rendering $scene with $m ($size, $frames frames)" >&2
  "$gibench" render --scene "$scene" --method "$m" --size "$size" --frames "$frames" \
    --out "$out/cornell_$m.exr" --out "$out/cornell_$m.png" --timings "$out/cornell_$m.json"
  renderer=$(sed -n 's/^ *"gl_renderer": *"\(.*\)",*$/\1/p' "$out/cornell_$m.json")
  {
    echo "## $m"
    echo
    echo "![$m](cornell_$m.png)"
    echo
    echo "GL renderer: $renderer. Files: cornell_$m.exr, cornell_$m.png; timings and stats:"
    echo
    echo '```json'
    cat "$out/cornell_$m.json"
    echo '```'
    echo
  } >> "$report.tmp"
done
mv "$report.tmp" "$report"
echo "demo: wrote $report" >&2
