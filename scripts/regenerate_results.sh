#!/usr/bin/env bash
# Regenerates the committed studies under results/: each study afresh
# (references are reused when their key is unchanged) and its tables.
#
#   scripts/regenerate_results.sh [--dry-run] [STUDY...]
#
# STUDY is a folder name under results/ (default: all of them, in the order
# below; the five-way comparison and the stress study last). --dry-run
# prints the commands without running them. GIBENCH names the binary
# (default build/release/bin/gibench; `make results` builds it first).
# Steps done by hand and described in the study's README (avg's VPL region
# dumps and speed table, cssm_hrc's Fig. 16) are not part of this script.
# Exit status: that of the first command that fails; 2 on an unknown study.
set -euo pipefail
cd "$(dirname "$0")/.."
G=${GIBENCH:-build/release/bin/gibench}
dry=0
if [[ ${1:-} == --dry-run ]]; then
    dry=1
    shift
fi
all=(csm csm_local avg cssm_hrc implicit_vis vlf compare_all stress)
studies=("$@")
[[ ${#studies[@]} -gt 0 ]] || studies=("${all[@]}")

run() {
    echo "+ $*"
    [[ $dry == 1 ]] || "$@"
}
# tables SCRIPT STUDY [ARGS...]: the study's tables.md, written whole or not at all.
tables() {
    local script=$1 study=$2
    shift 2
    echo "+ scripts/$script results/$study $* > results/$study/tables.md"
    if [[ $dry == 0 ]]; then
        "scripts/$script" "results/$study" "$@" > "results/$study/tables.md.tmp"
        mv "results/$study/tables.md.tmp" "results/$study/tables.md"
    fi
}

for s in "${studies[@]}"; do
    case $s in
    csm | csm_local)
        run "$G" study "harness/studies/$s.json" --out "results/$s" --jobs 1 --fresh
        tables csm_tables.py "$s" ;;
    avg)
        run "$G" study harness/studies/avg.json --out results/avg --jobs 1 --fresh
        tables avg_tables.py avg "$G" --measure ;;
    cssm_hrc)
        run "$G" study harness/studies/cssm_hrc.json --out results/cssm_hrc --jobs 1 --fresh
        tables cssm_hrc_tables.py cssm_hrc ;;
    implicit_vis)
        run "$G" study harness/studies/implicit_vis.json --out results/implicit_vis --jobs 1 --fresh ;;
    vlf)
        run "$G" study harness/studies/vlf.json --out results/vlf --jobs 1 --fresh
        tables vlf_tables.py vlf ;;
    compare_all)
        run "$G" study harness/studies/compare_all.json --out results/compare_all --jobs 1 --fresh
        run scripts/trivial_scores.py results/compare_all --gibench "$G"
        tables compare_all_tables.py compare_all ;;
    stress)
        run "$G" study harness/studies/stress.json --out results/stress --jobs 1 --fresh
        run scripts/trivial_scores.py results/stress --gibench "$G"
        tables stress_tables.py stress ;;
    *)
        echo "regenerate_results.sh: unknown study '$s' (one of: ${all[*]})" >&2
        exit 2 ;;
    esac
done
