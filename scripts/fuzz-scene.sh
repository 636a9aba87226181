#!/bin/sh
# Fuzzes the glTF scene loader (tests/fuzz/fuzz_scene.c) with libFuzzer.
#
# usage: scripts/fuzz-scene.sh [SECONDS]        (default 60)
#   BUILD=dir   build directory (default build-fuzz); the corpus grows in
#               BUILD/fuzz/corpus across runs, seeded from tests/data
#   JOBS=n      parallel fuzzing processes (default 1)
#
# Configures a clang build with GIBENCH_FUZZ=ON and ASan + UBSan, fuzzes for
# SECONDS, then minimises every crash, leak, timeout or out-of-memory input
# and copies it to tests/data/malformed/fuzz-<hash>.gltf (or .glb). Each new
# file needs a line "<file>\t<message substring>" in
# tests/data/malformed/EXPECTED.txt once the bug is fixed; the malformed test
# fails until it has one.
set -eu
root=$(cd "$(dirname "$0")/.." && pwd)
secs=${1:-60}
build=${BUILD:-$root/build-fuzz}
jobs=${JOBS:-1}

CC=clang CXX=clang++ cmake -S "$root" -B "$build" -G Ninja -DGIBENCH_FUZZ=ON \
    -DGIBENCH_SANITIZE=ON -DCMAKE_BUILD_TYPE= -DCMAKE_C_FLAGS="-O1 -g" \
    -DCMAKE_CXX_FLAGS="-O1 -g" >/dev/null  # asserts stay on
cmake --build "$build" --target fuzz_scene -j2

fuzzer=$build/fuzz/fuzz_scene
corpus=$build/fuzz/corpus
artifacts=$build/fuzz/artifacts
mkdir -p "$corpus" "$artifacts"
for f in "$root"/tests/data/valid/*.gltf "$root"/tests/data/valid/*.glb \
         "$root"/tests/data/malformed/*.gltf "$root"/tests/data/malformed/*.glb; do
    [ -f "$f" ] && cp -n "$f" "$corpus/" 2>/dev/null || true
done

status=0
"$fuzzer" "$corpus" -dict="$root/tests/fuzz/gltf.dict" -max_total_time="$secs" \
    -max_len=65536 -timeout=20 -rss_limit_mb=4096 -artifact_prefix="$artifacts/" \
    -fork="$jobs" -ignore_crashes=1 -ignore_ooms=1 -ignore_timeouts=1 \
    -print_final_stats=1 2>"$build/fuzz/last-run.log" || status=$?
grep -E '^#[0-9]+:|INFO: (fuzzed|exiting)|ERROR|SUMMARY' "$build/fuzz/last-run.log" | tail -n 8

found=0
for a in "$artifacts"/crash-* "$artifacts"/leak-* "$artifacts"/timeout-* "$artifacts"/oom-*; do
    [ -f "$a" ] || continue
    min=$a.min
    "$fuzzer" -minimize_crash=1 -runs=20000 -exact_artifact_path="$min" "$a" \
        >/dev/null 2>&1 || true
    [ -s "$min" ] || cp "$a" "$min"
    hash=$(sha1sum "$min" | cut -c1-12)
    ext=gltf
    [ "$(head -c 4 "$min")" = "glTF" ] && ext=glb
    dest=$root/tests/data/malformed/fuzz-$hash.$ext
    cp "$min" "$dest"
    echo "new input: $dest (from $(basename "$a")); add its EXPECTED.txt line after the fix"
    found=$((found + 1))
    mv "$a" "$a.done"
done
echo "fuzzed ${secs}s; $found new input(s); fuzzer exit status $status"
