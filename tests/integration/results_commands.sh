#!/usr/bin/env bash
# scripts/regenerate_results.sh covers every committed study: its dry run
# names a `gibench study ... --out results/<dir>` command for each folder
# under results/ that has a README.md, runs nothing, and refuses an
# unknown study with exit 2 and one line.
# Usage: results_commands.sh ROOT
set -u
root=$1
cd "$root" || exit 1
out=$(scripts/regenerate_results.sh --dry-run) || { echo "FAIL: dry run exit $?"; exit 1; }
fails=0
for d in results/*/; do
    d=${d%/}
    [[ -f $d/README.md ]] || continue
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
