#!/usr/bin/env bash
# The check that a refactoring changed no image: every method renders every
# shipped scene with this tree's build and with a base build, and each pair
# of images is compared (rmse 0 means bit-identical). A method that refuses
# a scene (its caps do not cover it) must refuse it on both sides with the
# same message.
#
#   scripts/images_unchanged.sh [BASE_REV] [--methods a,b,...] [--scenes all|stress|FILE,...]
#                               [--size WxH] [--frames N]
#
# The base is the gibench binary $GIBENCH_BASE when set; otherwise BASE_REV
# is built in a temporary git worktree (build/release there). This tree must
# be built (make build). Defaults: every method this build lists, every
# scene of scenes/ (--scenes all adds scenes/stress/), 48x48, 3 frames.
# Each side renders with a cache of its own, so no precomputation is shared.
# Exit 0 when every pair is identical; 1 otherwise; 2 on bad usage.
set -euo pipefail
cd "$(dirname "$0")/.."
usage() {
    echo "usage: scripts/images_unchanged.sh [BASE_REV] [--methods a,b] [--scenes all|stress|F,...] [--size WxH] [--frames N]" >&2
    exit 2
}
base="" methods="" scenes_opt="" size=48x48 frames=3
while [[ $# -gt 0 ]]; do
    case $1 in
    --methods) [[ $# -ge 2 ]] || usage; methods=$2; shift 2 ;;
    --scenes) [[ $# -ge 2 ]] || usage; scenes_opt=$2; shift 2 ;;
    --size) [[ $# -ge 2 ]] || usage; size=$2; shift 2 ;;
    --frames) [[ $# -ge 2 ]] || usage; frames=$2; shift 2 ;;
    -*) usage ;;
    *) [[ -z $base ]] || usage; base=$1; shift ;;
    esac
done
here=build/release/bin/gibench
[[ -x $here ]] || { echo "images_unchanged: build this tree first (make build)" >&2; exit 2; }
tmp=$(mktemp -d)
cleanup() {
    [[ -d $tmp/base ]] && git worktree remove --force "$tmp/base" >/dev/null 2>&1
    rm -rf "$tmp"
}
trap cleanup EXIT
if [[ -n ${GIBENCH_BASE:-} ]]; then
    there=$GIBENCH_BASE
    [[ -x $there ]] || { echo "images_unchanged: GIBENCH_BASE=$there is not executable" >&2; exit 2; }
else
    [[ -n $base ]] || usage
    git rev-parse --verify -q "$base^{commit}" >/dev/null || { echo "images_unchanged: no commit '$base'" >&2; exit 2; }
    git worktree add -q --detach "$tmp/base" "$base"
    (cd "$tmp/base" && cmake --preset release >/dev/null && cmake --build --preset release >/dev/null)
    there=$tmp/base/build/release/bin/gibench
fi
if [[ -z $methods ]]; then
    methods=$("$here" methods --json | sed -n 's/^    "id": "\([a-z0-9_]*\)",$/\1/p' | paste -sd,)
fi
case $scenes_opt in
"") scenes=(scenes/*.gltf scenes/*.glb) ;;
all) scenes=(scenes/*.gltf scenes/*.glb scenes/stress/*.gltf) ;;
stress) scenes=(scenes/stress/*.gltf) ;;
*) IFS=, read -r -a scenes <<< "$scenes_opt" ;;
esac
IFS=, read -r -a method_list <<< "$methods"
echo "images_unchanged: $here against $there; ${#method_list[@]} methods x ${#scenes[@]} scenes at $size, $frames frames"
status=0 same=0 na=0
for m in "${method_list[@]}"; do
    for s in "${scenes[@]}"; do
        name=$(basename "${s%.*}")
        for side in here there; do
            bin=${!side}
            rc=0
            GIBENCH_CACHE=$tmp/cache-$side "$bin" -q render --scene "$s" --method "$m" --size "$size" \
                --frames "$frames" --out "$tmp/$side-$m-$name.exr" 2> "$tmp/$side-$m-$name.err" || rc=$?
            echo "$rc" > "$tmp/$side-$m-$name.rc"
        done
        if [[ ! -f $tmp/here-$m-$name.exr && ! -f $tmp/there-$m-$name.exr ]]; then
            if cmp -s "$tmp/here-$m-$name.err" "$tmp/there-$m-$name.err" &&
                cmp -s "$tmp/here-$m-$name.rc" "$tmp/there-$m-$name.rc"; then
                echo "$m $name: refused on both sides alike: $(head -c 160 "$tmp/here-$m-$name.err")"
                na=$((na + 1))
            else
                echo "$m $name: refused differently: here '$(cat "$tmp/here-$m-$name.err")', base '$(cat "$tmp/there-$m-$name.err")'"
                status=1
            fi
            continue
        fi
        if [[ ! -f $tmp/here-$m-$name.exr || ! -f $tmp/there-$m-$name.exr ]]; then
            echo "$m $name: rendered by one side only: here '$(cat "$tmp/here-$m-$name.err")', base '$(cat "$tmp/there-$m-$name.err")'"
            status=1
            continue
        fi
        rmse=$("$here" diff "$tmp/here-$m-$name.exr" "$tmp/there-$m-$name.exr" --json | sed -n 's/.*"rmse": \([^,]*\),.*/\1/p')
        echo "$m $name rmse $rmse"
        if [[ $rmse == 0.0 || $rmse == 0 ]]; then
            same=$((same + 1))
        else
            status=1
        fi
    done
done
echo "images_unchanged: $same identical, $na refused alike, $([[ $status == 0 ]] && echo "no difference" || echo "DIFFERENCES above")"
exit $status
