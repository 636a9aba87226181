#!/usr/bin/env bash
# scripts/regenerate_results.sh covers every committed study: its dry run
# names a `gibench study ... --out results/<dir>` command for each folder
# under results/ that has a README.md, runs nothing, and refuses an
# unknown study with exit 2 and one line. results/gpu/ is the exception:
# it is made on a GPU node by scripts/gpu/bench.sh (docs/gpu.md), which its
# README must name.
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
exit $((fails > 0))
