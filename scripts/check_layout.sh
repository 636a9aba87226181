#!/usr/bin/env bash
# The tree's shape, as docs/ARCHITECTURE.md describes it, checked so that it
# stays that way (ctest layout.tree):
#   - harness/ has no loose C file: each library lives in its own folder;
#   - no CMakeLists.txt takes files back out of a glob (REMOVE_ITEM);
#   - at most 10 functions of more than 100 lines in core/, harness/,
#     plugins/ and examples/ (universal-ctags counts them), each listed in
#     docs/ARCHITECTURE.md's table "Long functions" with its reason;
#   - at most one source file of more than 1,000 lines, the glTF loader;
#   - README.md at most 500 lines;
#   - libgicore.so (given as $1, optional) loads none of CGAL's GMP/MPFR,
#     qhull or meshoptimizer, directly or through another library (ldd):
#     those link into libgi_algo.so only.
# Usage: scripts/check_layout.sh [path/to/libgicore.so]
# Exit 0 when every rule holds; 1 with one line per broken rule.
set -uo pipefail
cd "$(dirname "$0")/.."
fails=0
fail() { echo "check_layout: $*"; fails=$((fails + 1)); }

loose=$(git ls-files 'harness/*.c' 'harness/*.cpp' 'harness/*.h' | grep -E '^harness/[^/]+$' || true)
[[ -z $loose ]] || fail "loose files in harness/ (each belongs to a library folder): $loose"

removes=$(git grep -l 'REMOVE_ITEM' -- '*CMakeLists.txt' '*.cmake' || true)
[[ -z $removes ]] || fail "REMOVE_ITEM in $removes: name the files a target builds instead"

command -v ctags >/dev/null || { echo "check_layout: universal-ctags is missing (scripts/install-deps.sh)"; exit 1; }
long=$(git ls-files 'core/*.c' 'core/*.cpp' 'harness/*.c' 'harness/*.cpp' 'plugins/*.c' 'plugins/*.cpp' \
           'examples/*.c' |
    xargs ctags --kinds-c=f --kinds-c++=f --fields=+ne -f - 2>/dev/null |
    awk -F'\t' '{l=""; e=""; for (i = 4; i <= NF; i++) { if ($i ~ /^line:/) l = substr($i, 6); if ($i ~ /^end:/) e = substr($i, 5) }
                 if (e != "" && e - l + 1 > 100) print $2 " " $1 " " e - l + 1}' | sort)
count=$(grep -c . <<< "$long")
[[ -n $long ]] || count=0
(( count <= 10 )) || fail "$count functions over 100 lines (at most 10):"$'\n'"$long"
while read -r file fn n; do
    [[ -n ${file:-} ]] || continue
    grep -q "| \`$fn\` |" docs/ARCHITECTURE.md ||
        fail "$file: $fn has $n lines and is not in docs/ARCHITECTURE.md's \"Long functions\" (split it, or say why not there)"
done <<< "$long"

big=$(git ls-files '*.c' '*.h' '*.cpp' '*.py' '*.sh' '*.glsl' '*.comp' '*.js' '*.cmake' | grep -v '^results/' |
    xargs wc -l | awk '$2 != "total" && $1 > 1000 {print $2 " (" $1 ")"}')
others=$(grep -v '^core/src/gltf_shim.cpp ' <<< "$big" || true)
[[ -z $others ]] || fail "files over 1,000 lines besides the glTF loader: $others"

readme=$(wc -l < README.md)
(( readme <= 500 )) || fail "README.md has $readme lines (at most 500: the rest belongs in docs/)"

if [[ -n ${1:-} ]]; then
    needed=$(ldd "$1") || fail "ldd $1 failed"
    bad=$(grep -i -E 'cgal|gmp|mpfr|qhull|meshopt' <<< "$needed" | awk '{print $1}' | paste -sd' ' || true)
    [[ -z $bad ]] || fail "ldd $1 lists $bad (core/algo/ is the only place these link)"
fi
(( fails == 0 )) && echo "check_layout: the tree has the shape docs/ARCHITECTURE.md describes"
exit $(( fails > 0 ))
