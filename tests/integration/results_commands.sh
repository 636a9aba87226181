#!/usr/bin/env bash
# scripts/regenerate_results.sh covers every committed study: its dry run
# names a `gibench study ... --out results/<dir>` command for each folder
# under results/ that has a README.md, runs nothing, and refuses an
# unknown study with exit 2 and one line. results/gpu/ is the exception:
# it is made on a GPU node by scripts/gpu/bench.sh (docs/gpu.md), which its
# README must name. A real run (in a scratch tree, with a stand-in gibench)
# records each finished study's time in results/regenerate_times.csv, one
# line per study, and a failed study records nothing; run folders of runs
# the study no longer has are removed.
# Usage: results_commands.sh ROOT
set -u
root=$1
cd "$root" || exit 1
out=$(scripts/regenerate_results.sh --dry-run) || { echo "FAIL: dry run exit $?"; exit 1; }
fails=0
for d in results/*/; do
    d=${d%/}
    [[ -f $d/README.md ]] || continue
    if [[ $d == results/gpu ]]; then
        if grep -q "scripts/gpu/bench.sh" "$d/README.md"; then
            echo "ok: $d (made by scripts/gpu/bench.sh on a GPU node)"
        else
            echo "FAIL: $d/README.md does not name scripts/gpu/bench.sh"
            fails=$((fails + 1))
        fi
        continue
    fi
    if ! grep -q -- "--out $d --jobs" <<< "$out"; then
        echo "FAIL: no study command for $d"
        fails=$((fails + 1))
    else
        echo "ok: $d"
    fi
done
err=$(scripts/regenerate_results.sh --dry-run no_such_study 2>&1 >/dev/null)
rc=$?
if [[ $rc != 2 || $(wc -l <<< "$err") != 1 ]]; then
    echo "FAIL: unknown study: exit $rc, stderr '$err'"
    fails=$((fails + 1))
fi

# The time record, in a scratch copy of the script's tree.
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$tmp/scripts" "$tmp/plugins/csm" "$tmp/results/csm_local"
cp scripts/regenerate_results.sh "$tmp/scripts/"
printf '#!/bin/sh\necho "tables of $1"\n' > "$tmp/plugins/csm/tables.py"
printf '#!/bin/sh\nexit 0\n' > "$tmp/ok"
printf '#!/bin/sh\nexit 3\n' > "$tmp/bad"
chmod +x "$tmp/plugins/csm/tables.py" "$tmp/ok" "$tmp/bad"
mkdir -p "$tmp/results/csm_local/runs/kept" "$tmp/results/csm_local/runs/stale"
printf 'run,scene\nkept,scenes/x.gltf\n' > "$tmp/results/csm_local/runs.csv"
GIBENCH=$tmp/ok "$tmp/scripts/regenerate_results.sh" csm_local csm_local > /dev/null 2>&1
rc=$?
if [[ ! -d $tmp/results/csm_local/runs/kept || -d $tmp/results/csm_local/runs/stale ]]; then
    echo "FAIL: the run folder of a run the study no longer has was not removed, or a run's was"
    fails=$((fails + 1))
else
    echo "ok: run folders of runs the study no longer has are removed"
fi
times_csv=$tmp/results/regenerate_times.csv
if [[ $rc != 0 || ! -f $times_csv || $(head -n 1 "$times_csv") != study,date,commit,wall_s,cpu_s,cores ||
      $(grep -c '^csm_local,' "$times_csv") != 1 || $(wc -l < "$times_csv") != 2 ]] ||
   ! grep -Eq '^csm_local,[0-9T:-]+Z,[^,]+,[0-9]+,[0-9]+,[0-9]+$' "$times_csv"; then
    echo "FAIL: time record after two runs (exit $rc):"
    cat "$times_csv" 2>/dev/null
    fails=$((fails + 1))
else
    echo "ok: results/regenerate_times.csv holds one line per study"
fi
before=$(cat "$times_csv")
GIBENCH=$tmp/bad "$tmp/scripts/regenerate_results.sh" csm_local > /dev/null 2>&1
rc=$?
if [[ $rc != 3 || $(cat "$times_csv") != "$before" ]]; then
    echo "FAIL: a failed study: exit $rc (want 3), time record changed: $(cat "$times_csv")"
    fails=$((fails + 1))
else
    echo "ok: a failed study exits with its status and records no time"
fi
exit $((fails > 0))
