#!/bin/bash
# The bundle's gibench (copied to DIR/gibench by scripts/gpu/bundle.sh).
#
# Finds everything relative to itself, checks that the node gives the
# libraries the bundle leaves out (EXPECTED_FROM_NODE), unpacks Embree once
# into a cache folder outside the bundle, then runs bin/gibench.
set -euo pipefail

here=$(cd "$(dirname "$(readlink -f "${BASH_SOURCE[0]}")")" && pwd)

# Where the dynamic loader would find a library: the cache of ldconfig, the
# folders of LD_LIBRARY_PATH and the usual system folders.
ld_cache=""
for ldc in /sbin/ldconfig /usr/sbin/ldconfig; do
    if [[ -x $ldc ]]; then
        ld_cache=$("$ldc" -p 2>/dev/null || true)
        break
    fi
done
node_has() {
    local name=$1 d
    # a here-string, not a pipe: grep -q's early exit would SIGPIPE ldconfig
    grep -q "^[[:space:]]*$name " <<<"$ld_cache" && return 0
    local IFS=:
    for d in ${LD_LIBRARY_PATH:-} /lib/x86_64-linux-gnu /usr/lib/x86_64-linux-gnu /lib64 \
        /usr/lib64 /lib /usr/lib /usr/local/nvidia/lib64 /usr/local/nvidia/lib; do
        [[ -n $d && -e $d/$name ]] && return 0
    done
    return 1
}

missing=()
glvnd_missing=()
while read -r name kind; do
    [[ -z $name || $name == \#* ]] && continue
    if ! node_has "$name"; then
        if [[ $kind == glvnd ]]; then glvnd_missing+=("$name"); else missing+=("$name"); fi
    fi
done <"$here/EXPECTED_FROM_NODE"
if ((${#missing[@]})); then
    echo "gibench bundle: this node lacks ${missing[*]} (the bundle expects them from the node; see EXPECTED_FROM_NODE)" >&2
    exit 127
fi
if command -v getconf >/dev/null 2>&1; then
    glibc=$(getconf GNU_LIBC_VERSION 2>/dev/null | awk '{print $2}')
    need=$(cat "$here/GLIBC_MIN")
    if [[ -n $glibc && $(printf '%s\n%s\n' "$need" "$glibc" | sort -V | head -1) != "$need" ]]; then
        echo "gibench bundle: glibc $glibc on this node, the bundle needs $need or newer" >&2
        exit 127
    fi
fi
extra=""
if ((${#glvnd_missing[@]})); then
    # libglvnd is small and the bundle carries a copy for nodes without it
    # (the NVIDIA driver's EGL vendor library still comes from the node)
    [[ -n ${GIBENCH_BUNDLE_QUIET:-} ]] ||
        echo "gibench bundle: the node lacks ${glvnd_missing[*]}; using the bundle's libglvnd" >&2
    extra="$here/lib/glvnd"
fi
# The NVIDIA container layout keeps the vendor file outside glvnd's search path.
if [[ -z ${__EGL_VENDOR_LIBRARY_FILENAMES:-}${__EGL_VENDOR_LIBRARY_DIRS:-} ]] &&
    ! compgen -G "/usr/share/glvnd/egl_vendor.d/*.json" >/dev/null &&
    ! compgen -G "/etc/glvnd/egl_vendor.d/*.json" >/dev/null &&
    compgen -G "/usr/local/nvidia/share/glvnd/egl_vendor.d/*.json" >/dev/null; then
    export __EGL_VENDOR_LIBRARY_DIRS=/usr/local/nvidia/share/glvnd/egl_vendor.d
fi

# Embree, unpacked once per bundle build into a folder outside the bundle
# (the bundle itself may be read-only and keeps its size).
id=$(cat "$here/lib/embree.id")
cache=${GIBENCH_BUNDLE_CACHE:-${TMPDIR:-/tmp}}/gibench-bundle-$id
if [[ ! -e $cache/libembree3.so.3 ]]; then
    mkdir -p "$cache"
    "$here/bin/gi-gunzip" "$here/lib/libembree3.so.3.gz" "$cache/libembree3.so.3"
fi
export LD_LIBRARY_PATH="$cache${extra:+:$extra}${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
export GIBENCH_PLUGIN_DIR="$here/plugins"
exec "$here/bin/gibench" "$@"
