#!/bin/bash
# The GPU bundle (issue 30, scripts/gpu/bundle.sh) checked without a GPU:
# built into a temporary folder, under 48 MiB; every bundled ELF resolves
# each NEEDED library inside the bundle or from the list a GPU node gives
# (nothing else from /usr/lib or /lib); then the bundle's gibench, with a
# cleared environment and no path into the build or the sources, renders,
# makes a reference, and bench.sh runs in its tiny mode under a time limit.
#   gpu_bundle_test.sh SOURCE_DIR BUILD_DIR OUT_DIR
set -euo pipefail
src=$1 build=$2 out=$3
fail() {
    echo "FAIL: $*" >&2
    exit 1
}
mkdir -p "$out"
work=$(mktemp -d "$out/gpu_bundle.XXXXXX")
trap 'rm -rf "$work"' EXIT
b=$work/bundle

BUILD=$build bash "$src/scripts/gpu/bundle.sh" "$b" || fail "bundle.sh failed"
size=$(du -sb "$b" | cut -f1)
((size < 48 * 1024 * 1024)) || fail "bundle is $size bytes, not under 48 MiB"
for f in gibench bench.sh bin/gibench bin/gi-gunzip EXPECTED_FROM_NODE MANIFEST \
    lib/libgicore.so lib/libembree3.so.3.gz scenes/cornell_box.gltf; do
    [[ -e $b/$f ]] || fail "bundle lacks $f"
done
ls "$b"/plugins/gimethod_*.so >/dev/null || fail "bundle has no plugins"

# The libraries a node gives: the glibc family, the C++ runtime, libglvnd.
allowed=" libc.so.6 libm.so.6 libpthread.so.0 libdl.so.2 librt.so.1 ld-linux-x86-64.so.2
 libstdc++.so.6 libgcc_s.so.1 libEGL.so.1 libOpenGL.so.0 libGLdispatch.so.0 libGLX.so.0 libGL.so.1 "
allowed=${allowed//$'\n'/ }
# Embree as the launcher unpacks it, so that its NEEDED are checked too.
emb=$work/embree
mkdir -p "$emb"
"$b/bin/gi-gunzip" "$b/lib/libembree3.so.3.gz" "$emb/libembree3.so.3"
cp "$emb/libembree3.so.3" "$b/lib/" # beside the others for ldd; removed below
checked=0
while IFS= read -r -d '' f; do
    readelf -h "$f" >/dev/null 2>&1 || continue
    checked=$((checked + 1))
    rpath=$(readelf -d "$f" | sed -n 's/.*(RUNPATH).*\[\(.*\)\]/\1/p')
    case $f in */bin/gi-gunzip) ;; *) [[ $rpath == "\$ORIGIN"* ]] || fail "$f: RUNPATH '$rpath' is not \$ORIGIN-relative" ;; esac
    for need in $(readelf -d "$f" | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p'); do
        [[ $allowed == *" $need "* ]] && continue
        [[ -e $b/lib/$need ]] || fail "$f needs $need, neither in the bundle nor from the node"
    done
    # what the loader really picks, with no LD_LIBRARY_PATH: only allowed names outside
    while read -r name arrow path _; do
        [[ $arrow == "=>" ]] || continue
        [[ $path == not ]] && fail "$f: ldd cannot find $name"
        [[ $path == "$b"/* || $allowed == *" $name "* ]] ||
            fail "$f: $name resolves from the system ($path), not from the bundle"
    done < <(env -i ldd "$f")
done < <(find "$b/bin" "$b/lib" "$b/plugins" -type f -print0)
rm "$b/lib/libembree3.so.3"
((checked >= 10)) || fail "only $checked ELF files checked"
grep -q 'libEGL.so.1' "$b/EXPECTED_FROM_NODE" || fail "EXPECTED_FROM_NODE does not name libEGL"

# The bundle alone: a cleared environment, run from elsewhere, Embree's cache in the test's folder.
run() { (cd "$work" && env -i PATH=/usr/bin:/bin HOME=/nonexistent GIBENCH_BUNDLE_CACHE="$work/cache" "$@"); }
run "$b/gibench" -v --version >"$work/version.txt" 2>&1 || fail "gibench --version: $(cat "$work/version.txt")"
grep -q "EGL device: " "$work/version.txt" || fail "no EGL device named: $(cat "$work/version.txt")"
# The launcher's check of the node: a missing system library stops it with
# one line; missing libglvnd makes it use the bundle's copy and say so.
cp "$b/EXPECTED_FROM_NODE" "$work/expected"
echo "libgibench-absent.so.9 system" >>"$b/EXPECTED_FROM_NODE"
rc=0
run "$b/gibench" --version >"$work/miss.txt" 2>&1 || rc=$?
if [[ $rc != 127 || $(wc -l <"$work/miss.txt") != 1 ]] ||
    ! grep -q "lacks libgibench-absent.so.9" "$work/miss.txt"; then
    fail "a missing node library: exit $rc, $(cat "$work/miss.txt")"
fi
cp "$work/expected" "$b/EXPECTED_FROM_NODE"
echo "libgibench-absent.so.9 glvnd" >>"$b/EXPECTED_FROM_NODE"
run "$b/gibench" -v --version >"$work/glvnd.txt" 2>&1 || fail "with the bundle's libglvnd: $(cat "$work/glvnd.txt")"
grep -q "using the bundle's libglvnd" "$work/glvnd.txt" || fail "no note of the bundle's libglvnd"
grep -q "GL renderer: " "$work/glvnd.txt" || fail "no GL context through the bundle's libglvnd"
cp "$work/expected" "$b/EXPECTED_FROM_NODE"
# The device choice: by number (llvmpipe is EGL device 0 here), and a name no
# device has is an error, not a quiet fall back to llvmpipe.
run "$b/gibench" --egl-device 0 -v --version 2>&1 | grep -q "EGL device: device 0 of" ||
    fail "--egl-device 0 did not take EGL device 0"
rc=0
run "$b/gibench" --egl-device no-such-gpu -v --version >"$work/nodev.txt" 2>&1 || rc=$?
if ((rc == 0)) || ! grep -q "no EGL device named like 'no-such-gpu'" "$work/nodev.txt"; then
    fail "--egl-device no-such-gpu: exit $rc, $(cat "$work/nodev.txt")"
fi
run "$b/gibench" -q render --scene "$b/scenes/cornell_box.gltf" --method direct --size 32x32 \
    --out "$work/d.exr" --timings "$work/t.json" || fail "render from the bundle failed"
[[ -s $work/d.exr ]] || fail "render wrote no image"
for k in gl_renderer gl_version gl_vendor egl_device timer; do
    grep -q "\"$k\"" "$work/t.json" || fail "timings lack \"$k\""
done
run "$b/gibench" -q reference --scene "$b/scenes/cornell_box.gltf" --size 32x32 --spp 4 \
    --out "$work/ref.exr" || fail "reference from the bundle failed"
[[ -s $work/ref.exr ]] || fail "reference wrote no image"
run "$b/gibench" -q diff "$work/d.exr" "$work/ref.exr" >/dev/null || fail "diff from the bundle failed"

# Every bench study, at its full size, is one the study loader takes (its
# scenes are relative to the bundle, where bench.sh runs them).
for j in "$b"/bench/*.json; do
    (cd "$b" && env -i PATH=/usr/bin:/bin HOME=/nonexistent GIBENCH_BUNDLE_CACHE="$work/cache" \
        "$b/gibench" -q study "$j" --out "$work/dry" --dry-run) >/dev/null 2>"$work/dry.err" ||
        fail "bench study $(basename "$j") is refused: $(cat "$work/dry.err")"
done

# bench.sh, tiny, two parts: the short one finishes; the limit stops the other cleanly.
rc=0
run "$b/bench.sh" --out "$work/bench" --tiny --limit-s 8 --parts vlf_table1,compare \
    >"$work/bench.log" 2>&1 || rc=$?
((rc == 0)) || fail "bench.sh exit $rc: $(tail -5 "$work/bench.log")"
r=$work/bench/README.md
[[ -f $r ]] || fail "bench.sh wrote no README.md"
grep -q '| vlf_table1 | .* | finished |' "$r" || fail "vlf_table1 did not finish: $(cat "$r")"
[[ -s $work/bench/vlf_table1/runs.csv ]] || fail "no vlf_table1/runs.csv"
grep -q 'llvmpipe' "$r" || fail "README names no renderer"
grep -Eq '\| compare \| .* \| (cut off|skipped)' "$r" || fail "compare was not stopped by the limit: $(cat "$r")"
[[ ! -e $work/bench/compare && ! -e $work/bench/.work ]] || fail "a cut-off part left files"
"$b/bench.sh" --out "$work/bad" --limit-s x >/dev/null 2>&1 && fail "bench.sh took --limit-s x"
# The gpu_paths part's pairs (a hand-made runs.csv: the C gather 4x the
# GPU's frame time) are set side by side with their C/GPU ratio.
mkdir -p "$work/bench/gpu_paths"
printf '%s\n' 'run,scene,method,params,status,frame_ms_median,prepare_ms,relmse_full,speedup_vs_pt' \
    'a,s,cssm_hrc,"gather=cpu,M=8",ok,200,90,0.03,0.5' 'b,s,cssm_hrc,"gather=gpu,M=8",ok,50,30,0.03,2' \
    >"$work/bench/gpu_paths/runs.csv"
# The comparison table from that output (here llvmpipe against llvmpipe).
python3 "$src/scripts/gpu/gpu_table.py" "$work/bench" --results "$src/results" --out "$work/table.md" ||
    fail "gpu_table.py failed"
for want in '^## vlf_table1 (vlf)' '| frame |' '^## compare: not in this bench folder' \
    '^| cssm_hrc | gather=gpu | 50 | 30 | 0.03 | 2 | 4 | 3 |$'; do
    grep -q -- "$want" "$work/table.md" || fail "gpu_table.py wrote no '$want': $(head -20 "$work/table.md")"
done
echo "gpu bundle: $((size / 1024)) KiB, $checked ELF files, render, reference and bench.sh ok"
