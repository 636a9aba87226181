#!/usr/bin/env bash
# Every tracked C and C++ file is formatted as .clang-format says (ctest
# layout.format). The formatting depends on clang-format's version, so the
# check uses Debian 12's, clang-format 14 (scripts/install-deps.sh installs
# it); format a file with `clang-format-14 -i FILE`, or the tree with
# `scripts/check_format.sh --fix`.
# Exit 0 when every file is formatted; 1 listing those that are not.
set -uo pipefail
cd "$(dirname "$0")/.."
cf=$(command -v clang-format-14 || true)
if [[ -z $cf ]]; then
    echo "check_format: clang-format-14 is missing (scripts/install-deps.sh installs Debian's clang-format)" >&2
    exit 1
fi
mapfile -t files < <(git ls-files '*.c' '*.h' '*.cpp')
if [[ ${1:-} == --fix ]]; then
    "$cf" -i "${files[@]}"
    exit 0
fi
# One clang-format process for all files (a process per file costs 40 s);
# the files that differ are read back from its diagnostics.
out=$("$cf" --dry-run -Werror "${files[@]}" 2>&1 >/dev/null)
rc=$?
mapfile -t bad < <(grep -oE '^[^:]+:[0-9]+:[0-9]+: error' <<<"$out" | cut -d: -f1 | sort -u)
if (( rc != 0 && ${#bad[@]} == 0 )); then
    echo "check_format: clang-format-14 failed: ${out%%$'\n'*}" >&2
    exit 1
fi
if (( ${#bad[@]} > 0 )); then
    echo "check_format: ${#bad[@]} of ${#files[@]} files differ from .clang-format (scripts/check_format.sh --fix):"
    printf '  %s\n' "${bad[@]}"
    exit 1
fi
echo "check_format: ${#files[@]} files formatted as .clang-format says"
