#!/usr/bin/env bash
# Regenerates the committed studies under results/: each study afresh
# (references are reused when their key is unchanged) and its tables.
#
#   scripts/regenerate_results.sh [--dry-run] [STUDY...]
#
# STUDY is a folder name under results/, or startup / reference_speed (the
# Markdown reports results/startup.md and results/reference_speed.md);
# default: all of them, in the order below (the five-way comparison at
# 128x128 and 256x256 before 64x64, so that the 64x64 folder's tables set
# the three sizes side by side; start-up and reference speed last). --dry-run
# prints the commands without running them. GIBENCH names the binary
# (default build/release/bin/gibench; `make results` builds it first).
# Each paper's study and tables script live in its plugin folder
# (plugins/<id>/study.json, tables.py); the cross-method ones in
# harness/studies/. Steps done by hand and described in the study's README
# (avg's VPL region dumps and speed table, cssm_hrc's Fig. 16) are not part
# of this script. vlf's Fig. 8 image is plugins/vlf/fig8.py's, from the
# study's EXR images (the gibench Python module next to the binary).
# After each study, results/STUDY/changes.md: what the rerun changed against
# the committed runs.csv (scripts/results_changes.py, base HEAD).
# Each finished study's wall and CPU time (of its commands, in seconds) goes
# into results/regenerate_times.csv, one line per study, replacing the
# study's earlier line: the time `make results` takes on this machine.
# Exit status: that of the first command that fails; 2 on an unknown study.
set -euo pipefail
cd "$(dirname "$0")/.."
G=${GIBENCH:-build/release/bin/gibench}
dry=0
if [[ ${1:-} == --dry-run ]]; then
    dry=1
    shift
fi
all=(csm csm_local avg cssm_hrc implicit_vis vlf compare_all_128 compare_all_256 compare_all stress startup
     reference_speed)
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
# study NAME FILE: the study FILE afresh into results/NAME, and the run
# folders of runs the study no longer has (an earlier run id) removed.
study() {
    run "$G" study "$2" --out "results/$1" --jobs 1 --fresh
    [[ $dry == 0 && -f results/$1/runs.csv ]] || return 0
    local keep r
    keep=$(cut -d, -f1 "results/$1/runs.csv" | tail -n +2)
    for r in "results/$1"/runs/*/; do
        [[ -d $r ]] || continue
        if ! grep -qxF "$(basename "$r")" <<< "$keep"; then
            echo "+ rm -r $r (not a run of the study any more)"
            rm -r "$r"
        fi
    done
}

# child_cpu VAR: VAR = seconds of user and system CPU time of this shell's
# finished children so far (bash's `times`, run in this shell: in a command
# substitution it would count the subshell's children only).
cpu_tmp=$(mktemp)
trap 'rm -f "$cpu_tmp"' EXIT
child_cpu() {
    times > "$cpu_tmp"
    printf -v "$1" '%s' "$(tail -n 1 "$cpu_tmp" |
        awk '{ for (i = 1; i <= 2; i++) { split($i, a, /[ms]/); t += a[1] * 60 + a[2] } print t }')"
}
# record STUDY WALL CPU: the study's line of results/regenerate_times.csv
# (the time `make results` takes, per study, on this machine) replaced.
record() {
    local f=results/regenerate_times.csv
    {
        echo "study,date,commit,wall_s,cpu_s,cores"
        [[ ! -f $f ]] || tail -n +2 "$f" | grep -v "^$1," || true
        printf '%s,%s,%s,%s,%s,%s\n' "$1" "$(date -u +%Y-%m-%dT%H:%MZ)" "$(git rev-parse --short HEAD 2>/dev/null || echo ?)" \
            "$2" "$3" "$(nproc)"
    } > "$f.tmp"
    mv "$f.tmp" "$f"
}

for s in "${studies[@]}"; do
    t0=$(date +%s.%N)
    child_cpu c0
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
        tables plugins/cssm_hrc/tables.py cssm_hrc --measure ;;
    implicit_vis)
        study implicit_vis plugins/implicit_vis/study.json
        tables plugins/implicit_vis/tables.py implicit_vis ;;
    vlf)
        study vlf plugins/vlf/study.json
        run env PYTHONPATH="$(dirname "$G")/../python" /usr/bin/python3 plugins/vlf/fig8.py results/vlf \
            --label fig8_paper --out results/vlf/fig8_paper.png
        tables plugins/vlf/tables.py vlf ;;
    compare_all_128 | compare_all_256)
        study "$s" "harness/studies/$s.json"
        run scripts/trivial_scores.py "results/$s" --gibench "$G"
        tables harness/studies/compare_all_tables.py "$s" ;;
    compare_all)
        # 64x64, with the other sizes' studies beside it where they were run
        study compare_all harness/studies/compare_all.json
        run scripts/trivial_scores.py results/compare_all --gibench "$G"
        sizes=()
        for z in 128 256; do
            [[ ! -f results/compare_all_$z/runs.csv ]] || sizes+=(--size-dir "results/compare_all_$z")
        done
        [[ ${#sizes[@]} == 0 ]] || sizes+=(--chart results/compare_all/speedup_vs_size.svg)
        tables harness/studies/compare_all_tables.py compare_all "${sizes[@]}" ;;
    stress)
        study stress harness/studies/stress.json
        run scripts/trivial_scores.py results/stress --gibench "$G"
        tables harness/studies/stress_tables.py stress ;;
    startup | reference_speed)
        # results/startup.md, results/reference_speed.md: start-up time and
        # the reference's speed against Embree's tutorial path tracer
        # (embree-tools: scripts/install-deps.sh --sources), Markdown
        # reports that results/README.md quotes
        if [[ $s == startup ]]; then
            cmd=(python3 scripts/startup_time.py --runs 20 "now=$G")
        else
            cmd=(scripts/ref-vs-embree.sh --rounds 12 "$G")
        fi
        echo "+ ${cmd[*]} > results/$s.md"
        if [[ $dry == 0 ]]; then
            "${cmd[@]}" > "results/$s.md.tmp"
            mv "results/$s.md.tmp" "results/$s.md"
        fi ;;
    *)
        echo "regenerate_results.sh: unknown study '$s' (one of: ${all[*]})" >&2
        exit 2 ;;
    esac
    # what the rerun changed against the committed run (results/STUDY/changes.md)
    if [[ -f results/$s/README.md ]] && git cat-file -e "HEAD:results/$s/runs.csv" 2> /dev/null; then
        echo "+ scripts/results_changes.py results/$s > results/$s/changes.md"
        if [[ $dry == 0 ]]; then
            python3 scripts/results_changes.py "results/$s" > "results/$s/changes.md.tmp"
            mv "results/$s/changes.md.tmp" "results/$s/changes.md"
        fi
    fi
    child_cpu c1
    [[ $dry == 1 ]] || record "$s" "$(awk -v a="$(date +%s.%N)" -v b="$t0" 'BEGIN { printf "%.0f", a - b }')" \
        "$(awk -v a="$c1" -v b="$c0" 'BEGIN { printf "%.0f", a - b }')"
done
