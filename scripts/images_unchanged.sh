#!/usr/bin/env bash
# Renders methods on the shipped scenes with this tree's build and with the
# build of another commit, and compares each pair of images (rmse 0 means
# bit-identical): the check that a refactoring (the method kit, issue 9)
# left the images as they were.
#   scripts/images_unchanged.sh BASE_REV [METHOD...]     (default: direct csm avg)
# Builds BASE_REV in a temporary git worktree (build/release there); this
# tree must be built (make build). Exit 0 when every pair is identical.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ $# -lt 1 ]; then
  echo "usage: scripts/images_unchanged.sh BASE_REV [METHOD...]" >&2
  exit 2
fi
base=$1; shift
methods=("$@")
[ ${#methods[@]} -eq 0 ] && methods=(direct csm avg)
git rev-parse --verify -q "$base^{commit}" >/dev/null || { echo "images_unchanged: no commit '$base'" >&2; exit 2; }
here=build/release/bin/gibench
[ -x "$here" ] || { echo "images_unchanged: build this tree first (make build)" >&2; exit 2; }
tmp=$(mktemp -d)
trap 'git worktree remove --force "$tmp/base" >/dev/null 2>&1 || true; rm -rf "$tmp"' EXIT
git worktree add -q --detach "$tmp/base" "$base"
(cd "$tmp/base" && cmake --preset release >/dev/null && cmake --build --preset release >/dev/null)
there=$tmp/base/build/release/bin/gibench
status=0
for m in "${methods[@]}"; do
  for s in scenes/cornell_box.gltf scenes/bunny_env.glb scenes/teapot_area.glb scenes/cornell_moving.gltf scenes/u_room.gltf; do
    name=$(basename "${s%.*}")
    for side in here there; do
      bin=${!side}
      GIBENCH_CACHE=$tmp/cache-$side "$bin" -q render --scene "$s" --method "$m" --size 48x48 --frames 3 \
        --out "$tmp/$side-$m-$name.exr" 2>/dev/null || true
    done
    if [ ! -f "$tmp/here-$m-$name.exr" ] || [ ! -f "$tmp/there-$m-$name.exr" ]; then
      echo "$m $name: not rendered by both (see gibench render)"; status=1; continue
    fi
    rmse=$("$here" diff "$tmp/here-$m-$name.exr" "$tmp/there-$m-$name.exr" --json | sed -n 's/.*"rmse": \([^,]*\),.*/\1/p')
    echo "$m $name rmse $rmse"
    [ "$rmse" = "0.0" ] || [ "$rmse" = "0" ] || status=1
  done
done
exit $status
