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
bad=()
for f in "${files[@]}"; do
    "$cf" --dry-run -Werror "$f" >/dev/null 2>&1 || bad+=("$f")
done
if (( ${#bad[@]} > 0 )); then
    echo "check_format: ${#bad[@]} of ${#files[@]} files differ from .clang-format (scripts/check_format.sh --fix):"
    printf '  %s\n' "${bad[@]}"
    exit 1
fi
echo "check_format: ${#files[@]} files formatted as .clang-format says"
