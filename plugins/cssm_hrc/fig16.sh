#!/bin/sh
# Fig. 16 of the cssm_hrc study (results/cssm_hrc/README.md): the Cornell
# box with n = 0 .. 3 atlas bounces, each against the path-traced reference
# with the same bounce count (pixels get 0 .. n + 1 bounces, so B = n + 1).
# Usage: plugins/cssm_hrc/fig16.sh OUTDIR   (after a release build)
set -eu
out=${1:?usage: plugins/cssm_hrc/fig16.sh OUTDIR}
gib=${GIB:-build/release/bin/gibench}
mkdir -p "$out"
printf '| n | reference bounces B | relMSE | mean luminance difference |\n|---|---|---|---|\n'
for n in 0 1 2 3; do
    B=$((n + 1))
    [ -f "$out/ref_b$B.exr" ] || "$gib" -q reference --scene scenes/cornell_box.gltf --size 64x64 --spp 1024 \
        --max-bounces $B --pixel center --out "$out/ref_b$B.exr"
    "$gib" -q render --scene scenes/cornell_box.gltf --method cssm_hrc --size 64x64 --frames 8 \
        --param atlas=64 --param M=32 --param bounces=$n --out "$out/n$n.exr" --out "$out/n$n.png"
    "$gib" diff "$out/n$n.exr" "$out/ref_b$B.exr" --json > "$out/n$n.json"
    python3 - "$out/n$n.json" $n $B <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
m = d.get("metrics", d)
print("| %s | %s | %.4f | %+.1f %% |" % (sys.argv[2], sys.argv[3], m["relmse"], m.get("mean_lum_diff_pct", float("nan"))))
PY
done
