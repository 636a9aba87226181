#!/usr/bin/env bash
# Installs the Debian packages gibench needs that are missing on this machine.
# As root it runs apt-get; otherwise it prints the exact command and exits 2.
#   scripts/install-deps.sh            build, test and run dependencies
#   scripts/install-deps.sh --sources  also the packages the scene-conversion
#                                      scripts read (embree-tools, blender-data)
#                                      and scripts/ref-vs-embree.sh runs (embree-tools)
set -eu

pkgs=(
  build-essential cmake ninja-build pkg-config clang libclang-rt-14-dev
  # make test's checks of the tree: formatting (scripts/check_format.sh, Debian's
  # clang-format 14) and its shape (scripts/check_layout.sh counts functions with ctags)
  clang-format universal-ctags
  libembree-dev
  # EXR (OpenEXR) and PNG writing (libpng) in the core; every other image
  # format through the OpenImageIO module, loaded only when needed
  libopenexr-dev libpng-dev
  libopenimageio-dev openimageio-tools
  libtinygltf-dev nlohmann-json3-dev libstb-dev
  libvtk9-dev fonts-dejavu-core
  libglfw3-dev libepoxy-dev
  libegl-dev libgl-dev libegl-mesa0 libgl1-mesa-dri libglx-mesa0
  # An X server for headless tests of the GLFW viewer; the charts do not need it
  # (VTK draws through EGL, see harness/report/charts.cpp).
  xvfb xauth
  # gibench view's panels beside the image (harness/view/view_panels.cpp): Dear ImGui
  # with its GLFW and OpenGL 3 backends, a static libimgui.a
  libimgui-dev
  libjson-c-dev libxxhash-dev
  # plugins/vlf: the spherical triangulation of the direction set
  libqhull-dev
  # gi/algo/simplify.h: lower-detail geometry (avg's VPL shadow maps)
  libmeshoptimizer-dev
  # gi/algo/remesh.h: isotropic re-meshing (implicit_vis's re-meshing option)
  libcgal-dev
  # scripts/*.py (the results tables, their test integration.results_tables;
  # the bash completion, scripts/gen-completion.py, which `make` installs)
  python3 bash-completion
  # The Python API (python/gibench, docs/python.md): numpy for Debian's /usr/bin/python3
  python3-numpy
  # its tests under pytest (tests/python, ctest python.*)
  python3-pytest
  # gibench.study() / study_runs() return a DataFrame with it (tests/python/test_method.py)
  python3-pandas
  # the tutorial notebook (examples/python) run by its test: plots (Agg) and nbclient
  python3-matplotlib
  python3-nbformat python3-nbclient python3-ipykernel
  # The report page in a real browser (tests/integration/report_browser.cmake):
  # Debian's Chromium, driven by playwright-core from npm (tests/browser/).
  chromium
  # Studies on a cluster (gibench study --slurm) and their test, a one-node
  # Slurm brought up by hand (tests/integration/slurm_test.sh)
  slurm-wlm munge
  # scripts/gpu/bundle.sh (the GPU bundle): $ORIGIN rpaths, strip, readelf, static zlib
  patchelf binutils zlib1g-dev
)
# npm for the browser test (and the scene-conversion scripts); a machine that
# already has a Node.js with npm (not from Debian) keeps it.
command -v npm >/dev/null 2>&1 || pkgs+=(nodejs npm)
if [ "${1:-}" = "--sources" ]; then
  # npm (above) also runs the glTF validator and fetches the bunny and teapot meshes.
  pkgs+=(embree-tools blender-data)
elif [ $# -gt 0 ]; then
  echo "install-deps.sh: unknown option '$1' (use --sources or nothing)" >&2
  exit 2
fi

missing=()
for p in "${pkgs[@]}"; do
  status=$(dpkg-query -W -f='${Status}' "$p" 2>/dev/null || true)
  case "$status" in
    *" installed") ;;
    *) missing+=("$p") ;;
  esac
done
[ ${#missing[@]} -eq 0 ] && exit 0

cmd="apt-get install -y --no-install-recommends ${missing[*]}"
if [ "$(id -u)" -ne 0 ]; then
  echo "install-deps.sh: missing packages; run as root:" >&2
  echo "  apt-get update && $cmd" >&2
  exit 2
fi
echo "install-deps.sh: installing ${missing[*]}" >&2
export DEBIAN_FRONTEND=noninteractive
apt-get update -qq
# shellcheck disable=SC2086
$cmd
