#!/bin/sh
# Fig. 12's mean-luminance deficit on the highly glossy Cornell box
# (results/cssm_hrc/README.md, "Fig. 12", issue 34): each candidate cause
# changed alone against the 4-bounce reference (64 x 64, 1024 spp, pixel
# centres; atlas 64^2, M = 32, n = 3, 8 frames), then the deficit split
# into the blocks' pixels and the rest, and the light the blocks send to
# the room in the reference and in cssm_hrc (the scene with both blocks
# black, kd = ks = 0: results/cssm_hrc/scenes/cornell_black_blocks.gltf).
# Usage: plugins/cssm_hrc/fig12_deficit.sh OUTDIR   (after a release build)
set -eu
out=${1:?usage: plugins/cssm_hrc/fig12_deficit.sh OUTDIR}
gib=${GIB:-build/release/bin/gibench}
mkdir -p "$out"
export GIBENCH_CACHE="$out/cache"
S=results/cssm_hrc/scenes/cornell_highly_glossy.gltf
B=results/cssm_hrc/scenes/cornell_black_blocks.gltf
[ -f "$out/ref.pfm" ] || "$gib" -q reference --scene $S --out "$out/ref.pfm" --size 64x64 --spp 1024 --max-bounces 4 --pixel center
[ -f "$out/refb.pfm" ] || "$gib" -q reference --scene $B --out "$out/refb.pfm" --size 64x64 --spp 1024 --max-bounces 4 --pixel center
run() { # name atlas scene [params]
    n=$1 a=$2 sc=$3; shift 3
    "$gib" -q render --scene "$sc" --method cssm_hrc --out "$out/$n.pfm" --size 64x64 --frames 8 \
        --param atlas=$a --param M=32 --param bounces=3 "$@" --timings "$out/$n.json"
}
run base 64 $S
run black 64 $B
run thr0 64 $S --param threshold=0 --param max_cut=65536
run maxcut 64 $S --param max_cut=65536
run atlas32 32 $S
run nojit 64 $S --param jitter=false
run trace 64 $S --param vis=trace
run clamp0 64 $S --param clamp=0.002
python3 - "$out" <<'PY'
import json, struct, sys
d = sys.argv[1]
def lum(p):
    f = open(p, "rb"); assert f.readline().strip() == b"PF"
    w, h = map(int, f.readline().split()); sc = float(f.readline())
    v = struct.unpack(("<" if sc < 0 else ">") + "%df" % (3 * w * h), f.read(12 * w * h))
    return [0.2126 * v[3 * i] + 0.7152 * v[3 * i + 1] + 0.0722 * v[3 * i + 2] for i in range(w * h)]
ref, refb = lum(d + "/ref.pfm"), lum(d + "/refb.pfm")
blk = [b <= 0.0 and r > 0.0 for r, b in zip(ref, refb)]  # the blocks' pixels: black in refb
tot = sum(ref)
part = lambda img, m: sum(x for x, k in zip(img, blk) if k == m)
print("| run | cut (pixels) | mean luminance vs reference | in the blocks' %d pixels | in the rest |" % sum(blk))
print("|---|---|---|---|---|")
for n in ("base", "thr0", "maxcut", "atlas32", "nojit", "trace", "clamp0"):
    t = lum("%s/%s.pfm" % (d, n))
    cut = json.load(open("%s/%s.json" % (d, n)))["stats"]["cut_size_pixels"]
    print("| %s | %.0f | %+.2f %% | %+.2f %% | %+.2f %% |" % (n, cut, 100 * (sum(t) / tot - 1),
          100 * (part(t, True) - part(ref, True)) / tot, 100 * (part(t, False) - part(ref, False)) / tot))
base, black = lum(d + "/base.pfm"), lum(d + "/black.pfm")
print("\nblack blocks: cssm_hrc against its reference %+.2f %%" % (100 * (sum(black) / sum(refb) - 1)))
print("light the blocks add to the room's pixels (share of the image mean): reference %.2f %%, cssm_hrc %.2f %%"
      % (100 * (part(ref, False) - part(refb, False)) / tot, 100 * (part(base, False) - part(black, False)) / tot))
PY
