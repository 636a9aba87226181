#!/bin/sh
# Fuzzes the study-file reader (tests/fuzz/fuzz_study.c, harness/study/cmd_study.c
# study_check) with libFuzzer, at length; `make test` runs the same target
# for seconds through tests/fuzz/fuzz_driver.c (unit.fuzz_study_brief).
#
# usage: scripts/fuzz-study.sh [SECONDS]        (default 60)
#   BUILD=dir   build directory (default build-fuzz); the corpus grows in
#               BUILD/fuzz/study_corpus across runs, seeded from every
#               committed study (harness/studies/, plugins/*/study*.json),
#               tests/fuzz/study_seeds/ and tests/data/studies/
#
# Configures a clang build with GIBENCH_FUZZ=ON and ASan + UBSan (the
# plugins are built too: the reader checks method names against them),
# fuzzes for SECONDS, then minimises every crash, leak or timeout input and
# copies it to tests/data/studies/fuzz-<hash>.json, for a test once fixed.
set -eu
root=$(cd "$(dirname "$0")/.." && pwd)
secs=${1:-60}
build=${BUILD:-$root/build-fuzz}

CC=clang CXX=clang++ cmake -S "$root" -B "$build" -G Ninja -DGIBENCH_FUZZ=ON \
    -DGIBENCH_SANITIZE=ON -DCMAKE_BUILD_TYPE= -DCMAKE_C_FLAGS="-O1 -g" \
    -DCMAKE_CXX_FLAGS="-O1 -g" >/dev/null  # asserts stay on
cmake --build "$build" --target fuzz_study gimethod_direct gimethod_csm gimethod_avg -j2

fuzzer=$build/fuzz/fuzz_study
corpus=$build/fuzz/study_corpus
artifacts=$build/fuzz/study_artifacts
mkdir -p "$corpus" "$artifacts"
for f in "$root"/harness/studies/*.json "$root"/tests/fuzz/study_seeds/*.json "$root"/tests/data/studies/*.json; do
    [ -f "$f" ] && cp -n "$f" "$corpus/" 2>/dev/null || true
done
# the papers' studies share the name study.json: each gets its plugin's name
for f in "$root"/plugins/*/study*.json; do
    [ -f "$f" ] && cp -n "$f" "$corpus/$(basename "$(dirname "$f")")-$(basename "$f")" 2>/dev/null || true
done

status=0
"$fuzzer" "$corpus" -dict="$root/tests/fuzz/study.dict" -max_total_time="$secs" \
    -max_len=16384 -timeout=20 -rss_limit_mb=4096 -artifact_prefix="$artifacts/" \
    -close_fd_mask=2 -print_final_stats=1 2>"$build/fuzz/study-last-run.log" || status=$?
grep -E '^#[0-9]+:|INFO: (fuzzed|exiting)|ERROR|SUMMARY' "$build/fuzz/study-last-run.log" | tail -n 8

found=0
for a in "$artifacts"/crash-* "$artifacts"/leak-* "$artifacts"/timeout-*; do
    [ -f "$a" ] || continue
    min=$a.min
    "$fuzzer" -minimize_crash=1 -runs=20000 -exact_artifact_path="$min" "$a" >/dev/null 2>&1 || true
    [ -s "$min" ] || cp "$a" "$min"
    hash=$(sha1sum "$min" | cut -c1-12)
    dest=$root/tests/data/studies/fuzz-$hash.json
    cp "$min" "$dest"
    echo "new input: $dest (from $(basename "$a")); add a test for it after the fix"
    found=$((found + 1))
    mv "$a" "$a.done"
done
echo "fuzzed ${secs}s; $found new input(s); fuzzer exit status $status"
