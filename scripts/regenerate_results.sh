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
# Each paper's study and tables script live in its plugin folder
# (plugins/<id>/study.json, tables.py); the cross-method ones in
# harness/studies/. Steps done by hand and described in the study's README
# (avg's VPL region dumps and speed table, cssm_hrc's Fig. 16) are not part
# of this script. vlf's Fig. 8 image is plugins/vlf/fig8.py's, from the
# study's EXR images (the gibench Python module next to the binary).
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
    echo "+ $script results/$study $* > results/$study/tables.md"
    if [[ $dry == 0 ]]; then
        "$script" "results/$study" "$@" > "results/$study/tables.md.tmp"
        mv "results/$study/tables.md.tmp" "results/$study/tables.md"
    fi
}
# study NAME FILE: the study FILE afresh into results/NAME.
study() {
    run "$G" study "$2" --out "results/$1" --jobs 1 --fresh
}

for s in "${studies[@]}"; do
    case $s in
    csm)
        study csm plugins/csm/study.json
        tables plugins/csm/tables.py csm ;;
    csm_local)
        study csm_local plugins/csm/study_local.json
        tables plugins/csm/tables.py csm_local ;;
    avg)
        study avg plugins/avg/study.json
        tables plugins/avg/tables.py avg "$G" --measure ;;
    cssm_hrc)
        study cssm_hrc plugins/cssm_hrc/study.json
        tables plugins/cssm_hrc/tables.py cssm_hrc ;;
    implicit_vis)
        study implicit_vis plugins/implicit_vis/study.json
        tables plugins/implicit_vis/tables.py implicit_vis ;;
    vlf)
        study vlf plugins/vlf/study.json
        run env PYTHONPATH="$(dirname "$G")/../python" /usr/bin/python3 plugins/vlf/fig8.py results/vlf \
            --label fig8_paper --out results/vlf/fig8_paper.png
        tables plugins/vlf/tables.py vlf ;;
    compare_all)
        study compare_all harness/studies/compare_all.json
        run scripts/trivial_scores.py results/compare_all --gibench "$G"
        tables harness/studies/compare_all_tables.py compare_all ;;
    stress)
        study stress harness/studies/stress.json
        run scripts/trivial_scores.py results/stress --gibench "$G"
        tables harness/studies/stress_tables.py stress ;;
    *)
        echo "regenerate_results.sh: unknown study '$s' (one of: ${all[*]})" >&2
        exit 2 ;;
    esac
done
