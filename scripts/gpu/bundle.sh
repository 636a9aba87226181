#!/bin/bash
# scripts/gpu/bundle.sh DIR: a relocatable gibench for a GPU node (docs/gpu.md).
#
# DIR gets the binary, the method plugins, the shared libraries a bare GPU
# node lacks (rpath $ORIGIN-relative, stripped), the scenes and bench.sh.
# The node must give what EXPECTED_FROM_NODE lists (glibc, libstdc++,
# libglvnd and the NVIDIA EGL vendor library); the launcher DIR/gibench
# checks that at start. Left out on purpose: the report's charts module
# (VTK, hundreds of MiB) and the OpenImageIO module; both are loaded only
# when asked for and fail with a one-line message.
#   BUILD=build/release (default) names the build to take.
set -euo pipefail

die() {
    echo "bundle.sh: $*" >&2
    exit 1
}
[[ $# -eq 1 ]] || die "usage: scripts/gpu/bundle.sh DIR"
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
build=${BUILD:-$root/build/release}
limit_mib=48
out=$1
for t in patchelf strip readelf ldd gzip cc; do
    command -v "$t" >/dev/null || die "needs $t (scripts/install-deps.sh installs it)"
done
for f in bin/gibench lib/libgicore.so lib/libgi_algo.so; do
    [[ -f $build/$f ]] || die "no $build/$f: build first (cmake --build --preset release)"
done
plugins=("$build"/plugins/gimethod_*.so)
[[ -f ${plugins[0]} ]] || die "no method plugins in $build/plugins"
if [[ -e $out && -n $(ls -A "$out") ]]; then
    die "$out exists and is not empty"
fi

# The libraries a GPU node gives (kind "glvnd": the bundle carries a copy
# for nodes without libglvnd, used only when the node has none).
node_libs="libc.so.6 libm.so.6 libpthread.so.0 libdl.so.2 librt.so.1 ld-linux-x86-64.so.2
libstdc++.so.6 libgcc_s.so.1 libEGL.so.1 libOpenGL.so.0 libGLdispatch.so.0 libGLX.so.0 libGL.so.1"
glvnd_libs="libEGL.so.1 libOpenGL.so.0 libGLdispatch.so.0"
is_node_lib() { [[ " ${node_libs//$'\n'/ } " == *" $1 "* ]]; }

mkdir -p "$(dirname "$out")"
tmp=$(mktemp -d "${out%/}.tmp.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$tmp"/{bin,lib/glvnd,plugins,bench}

cp "$build/bin/gibench" "$tmp/bin/"
cp "$build/lib/libgicore.so" "$build/lib/libgi_algo.so" "$tmp/lib/"
cp "${plugins[@]}" "$tmp/plugins/"

# Every library the ELFs above load, found with ldd (transitively), that
# the node does not give and the build did not make.
elfs=("$tmp/bin/gibench" "$tmp"/lib/*.so "$tmp"/plugins/*.so)
declare -A seen=()
while read -r name path; do
    [[ -n ${seen[$name]:-} ]] && continue
    seen[$name]=1
    is_node_lib "$name" && continue
    [[ -e $tmp/lib/$name ]] && continue
    [[ $path == /* ]] || die "ldd cannot resolve $name"
    cp -L "$path" "$tmp/lib/$name"
done < <(LD_LIBRARY_PATH="$build/lib" ldd "${elfs[@]}" |
    awk '$2 == "=>" {print $1, $3} $2 == "=>" && $3 == "not" {print $1, "missing"}')

for name in $glvnd_libs; do
    # awk reads to the end: an early exit would kill ldconfig with SIGPIPE (pipefail)
    path=$(/sbin/ldconfig -p | awk -v n="$name" '$1 == n && /x86-64/ && !p {p = $NF} END {print p}')
    [[ -n $path ]] || die "no $name here to carry as the fallback libglvnd"
    cp -L "$path" "$tmp/lib/glvnd/$name"
done

# Size: everything stripped; Embree (most of it) travels gzipped.
for f in "$tmp"/bin/gibench "$tmp"/lib/*.so* "$tmp"/lib/glvnd/* "$tmp"/plugins/*.so; do
    chmod u+w "$f"
    strip --strip-unneeded "$f"
done
# shellcheck disable=SC2016 # $ORIGIN is for the dynamic loader, not the shell
patchelf --set-rpath '$ORIGIN/../lib' "$tmp/bin/gibench" "$tmp"/plugins/*.so
for f in "$tmp"/lib/*.so* "$tmp"/lib/glvnd/*; do
    # shellcheck disable=SC2016
    patchelf --set-rpath '$ORIGIN' "$f"
done
[[ -f $tmp/lib/libembree3.so.3 ]] || die "libembree3.so.3 was not among the libraries"
sha256sum "$tmp/lib/libembree3.so.3" | cut -c1-16 >"$tmp/lib/embree.id"
gzip -n -6 "$tmp/lib/libembree3.so.3"
cc -std=c17 -O2 -s -o "$tmp/bin/gi-gunzip" "$root/scripts/gpu/gunzip.c" \
    "$(cc -print-file-name=libz.a)"

# The oldest glibc the ELFs can run on: the newest GLIBC_ symbol version.
find "$tmp/bin" "$tmp/lib" "$tmp/plugins" -type f ! -name '*.gz' ! -name '*.id' -print0 |
    xargs -0 objdump -T |
    grep -o 'GLIBC_[0-9][0-9.]*' | sed 's/GLIBC_//' | sort -V | tail -1 >"$tmp/GLIBC_MIN"
{
    echo "# libraries this bundle expects from the GPU node (name, kind)"
    for name in libc.so.6 libm.so.6 libstdc++.so.6 libgcc_s.so.1; do echo "$name system"; done
    for name in $glvnd_libs; do echo "$name glvnd"; done
} >"$tmp/EXPECTED_FROM_NODE"

cp "$root/scripts/gpu/launcher.sh" "$tmp/gibench"
cp "$root/scripts/gpu/bench.sh" "$tmp/bench.sh"
# the bench studies name their scenes from their "base", the tree's root
# (../../.. from scripts/gpu/bench/), which is .. from the bundle's bench/
for j in "$root"/scripts/gpu/bench/*.json; do
    sed 's|"base": "../../.."|"base": ".."|' "$j" >"$tmp/bench/$(basename "$j")"
done
chmod +x "$tmp/gibench" "$tmp/bench.sh"
mkdir -p "$tmp/scenes"
(cd "$root/scenes" && tar --exclude=./stress -cf - .) | (cd "$tmp/scenes" && tar -xf -)
commit=$(git -C "$root" rev-parse --short=12 HEAD 2>/dev/null || echo unknown)
{
    echo "gibench GPU bundle, commit $commit, made $(date -u +%Y-%m-%dT%H:%MZ) by scripts/gpu/bundle.sh"
    echo "run: ./gibench --version -v    benchmark: ./bench.sh --out DIR --limit-s 420"
    echo "needs from the node: glibc $(cat "$tmp/GLIBC_MIN")+, see EXPECTED_FROM_NODE"
    echo "left out: the report's charts (VTK) and the OpenImageIO module"
} >"$tmp/README.txt"
(cd "$tmp" && find . -type f -printf '%s %P\n' | sort -k2) >"$tmp/MANIFEST"

size=$(du -sb "$tmp" | cut -f1)
((size <= limit_mib * 1024 * 1024)) || die "bundle is $size bytes, over $limit_mib MiB"
mkdir -p "$out"
rmdir "$out"
mv "$tmp" "$out"
trap - EXIT
echo "bundle.sh: $out, $((size / 1024)) KiB"
