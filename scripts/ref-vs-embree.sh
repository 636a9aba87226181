#!/usr/bin/env bash
# The reference path tracer against Embree's own tutorial path tracer
# (Debian embree-tools, /usr/bin/pathtracer) on the shared box scene, side by
# side: same image size, samples per pixel, path length and one thread,
# paired and interleaved runs (issue 14).
#
#   scripts/ref-vs-embree.sh [--rounds N] [--spp S] [--size N] [--length L]
#                            [--scene point|area] [GIBENCH]...
#
# The shared scene: Embree's models/cornell_box.obj with its cornell_box.ecs
# (camera, fov 37, point light at (213, 300, 227), intensity 1e5), and for
# us scenes/cornell_box_coarse.gltf, the same 36 triangles divided by 100
# (scenes/README.md), turned here into the same set-up: its ceiling quad no
# longer emits (Embree's obj has it as plain geometry too), a
# KHR_lights_punctual point light at (2.13, 3.00, 2.27) of intensity
# 1e5 / 100^2 and the camera's yfov 37 degrees. So both trace the same rays
# against the same triangles: one shadow ray to the point light and one
# continuation ray per vertex (--scene area keeps our emissive quad instead,
# for reference: one shadow ray to a point sampled on it). Path
# length L: Embree's --max-path-length L (1 = primary ray + shadow ray) and
# our --max-bounces L (1 = direct light) trace the same rays per path.
# Each round runs, in a random order, every program at S spp and at 1 spp;
# the time of S - 1 samples per pixel is the difference, which cancels
# start-up, scene loading and the BVH build for both. Both CPU time (user +
# system, getrusage; less sensitive to other processes) and wall time are
# reported, as medians over the rounds, and the ratio of our samples/s to
# Embree's. Several gibench builds may be given (e.g. before and after);
# each also runs with --traversal robust when it knows the option. The report
# is Markdown on standard output (`make results` keeps it as
# results/reference_speed.md).
# Needs: embree-tools (scripts/install-deps.sh --sources), python3.
set -euo pipefail
cd "$(dirname "$0")/.."
rounds=15 spp=64 size=128 length=3 scene=point
builds=()
while [ $# -gt 0 ]; do
  case "$1" in
    --rounds) rounds=$2; shift 2 ;;
    --spp) spp=$2; shift 2 ;;
    --size) size=$2; shift 2 ;;
    --length) length=$2; shift 2 ;;
    --scene) scene=$2; shift 2 ;;
    -*) echo "ref-vs-embree: unknown option '$1'" >&2; exit 2 ;;
    *) builds+=("$1"); shift ;;
  esac
done
[ ${#builds[@]} -eq 0 ] && builds=(build/release/bin/gibench)
command -v pathtracer >/dev/null || { echo "ref-vs-embree: no pathtracer; install embree-tools (scripts/install-deps.sh --sources)" >&2; exit 2; }
models=$(dpkg -L embree-tools 2>/dev/null | grep '/cornell_box.ecs$' | head -1 | xargs -r dirname)
[ -n "$models" ] && [ -f "$models/cornell_box.obj" ] || { echo "ref-vs-embree: embree-tools has no cornell_box.obj" >&2; exit 2; }
for b in "${builds[@]}"; do
  [ -x "$b" ] || { echo "ref-vs-embree: '$b' is not an executable gibench (make build)" >&2; exit 2; }
done
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cp "$models"/cornell_box.obj "$models"/cornell_box.mtl "$models"/cornell_box.ecs "$tmp"/
cp scenes/cornell_box_coarse.gltf scenes/cornell_box_coarse.bin "$tmp"/
case "$scene" in
  area) ours_scene=$tmp/cornell_box_coarse.gltf ;;
  point)
    ours_scene=$tmp/cornell_box_point.gltf
    python3 - "$tmp" <<'EOF'
import json, math, sys
d = sys.argv[1]
g = json.load(open(d + "/cornell_box_coarse.gltf"))
for m in g["materials"]:
    if m.get("name") == "light":
        m.pop("emissiveFactor", None)
        m.pop("extensions", None)
g["extensionsUsed"] = [e for e in g["extensionsUsed"] if e != "KHR_materials_emissive_strength"] + ["KHR_lights_punctual"]
g.setdefault("extensions", {})["KHR_lights_punctual"] = {
    "lights": [{"name": "ecs_point", "type": "point", "color": [1.0, 1.0, 1.0], "intensity": 10.0}]}
g["nodes"].append({"name": "ecs_point", "translation": [2.13, 3.00, 2.27],
                   "extensions": {"KHR_lights_punctual": {"light": 0}}})
g["scenes"][0]["nodes"].append(len(g["nodes"]) - 1)
g["cameras"][0]["perspective"]["yfov"] = math.radians(37.0)
json.dump(g, open(d + "/cornell_box_point.gltf", "w"), indent=1)
EOF
    ;;
  *) echo "ref-vs-embree: --scene '$scene' is not point or area" >&2; exit 2 ;;
esac

REF_SCENE_KIND=$scene python3 - "$tmp" "$rounds" "$spp" "$size" "$length" "$ours_scene" "${builds[@]}" <<'EOF'
import json, os, random, resource, statistics, subprocess, sys, time

tmp, rounds, spp, size, length = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4]), int(sys.argv[5])
ours_scene = sys.argv[6]
builds = sys.argv[7:]

def run(argv, cwd=None):
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    p = subprocess.run(argv, cwd=cwd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if p.returncode != 0:
        sys.exit("ref-vs-embree: %s failed (%d): %s" % (" ".join(argv), p.returncode, p.stderr.decode(errors="replace").strip()))
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)

def embree(s):
    return (["pathtracer", "-c", "cornell_box.ecs", "--size", str(size), str(size), "--threads", "1",
             "--spp", str(s), "--max-path-length", str(length), "-o", os.path.join(tmp, "embree.tga")], tmp)

def ours(b, s, traversal, tag):
    argv = [b, "reference", "--scene", ours_scene, "--size", "%dx%d" % (size, size),
            "--spp", str(s), "--max-bounces", str(length), "--threads", "1",
            "--out", os.path.join(tmp, tag + ".exr"), "--stats", os.path.join(tmp, tag + ".json")]
    if traversal:
        argv += ["--traversal", traversal]
    return (argv, None)

def knows_traversal(b):
    p = subprocess.run([b, "reference", "--traversal", "robust"], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    return b"unknown argument" not in p.stderr

programs = [("embree pathtracer", embree)]
for i, b in enumerate(builds):
    label = "gibench[%d]" % i
    if knows_traversal(b):
        programs.append((label + " fast", lambda s, b=b, i=i: ours(b, s, "fast", "g%df%d" % (i, s))))
        programs.append((label + " robust", lambda s, b=b, i=i: ours(b, s, "robust", "g%dr%d" % (i, s))))
    else:
        programs.append((label, lambda s, b=b, i=i: ours(b, s, None, "g%d%d" % (i, s))))

jobs = [(k, s) for k in range(len(programs)) for s in (1, spp)]
for k, s in jobs:  # one untimed run each (page cache)
    run(*programs[k][1](s))
wall = {j: [] for j in jobs}
cpu = {j: [] for j in jobs}
render_s = {k: [] for k in range(len(programs))}
rng = random.Random(14)
for _ in range(rounds):
    order = list(jobs)
    rng.shuffle(order)
    for k, s in order:
        argv, cwd = programs[k][1](s)
        w, c = run(argv, cwd)
        wall[(k, s)].append(w)
        cpu[(k, s)].append(c)
        if k > 0 and s == spp:
            st = json.load(open(argv[argv.index("--stats") + 1]))
            render_s[k].append(st["render_seconds"])

samples = (spp - 1) * size * size
load = os.getloadavg()
print("# Reference speed against Embree's tutorial path tracer\n")
print("Made by `scripts/ref-vs-embree.sh --rounds %d --spp %d --size %d --length %d --scene %s %s`: "
      "%dx%d, %d against 1 spp (the difference cancels start-up, loading and the BVH build), path length %d, "
      "1 thread, %d interleaved rounds, medians; ours on %s. Load average at the end: %.1f, %.1f, %.1f.\n"
      % (rounds, spp, size, length, os.environ.get("REF_SCENE_KIND", "?"),
         " ".join(builds), size, size, spp, length, rounds, os.path.basename(ours_scene), load[0], load[1], load[2]))
for i, b in enumerate(builds):
    print("- gibench[%d] = `%s`" % (i, b))
print("\n| program | Msamples/s (CPU) | Msamples/s (wall) | ratio to Embree, CPU (wall) | own render_seconds at %d spp (Msamples/s) |" % spp)
print("|---|---:|---:|---:|---:|")
rates = {}
for k, (name, _) in enumerate(programs):
    # per round: (time at spp) - (time at 1 spp) of the same round
    dc = statistics.median(a - b for a, b in zip(cpu[(k, spp)], cpu[(k, 1)]))
    dw = statistics.median(a - b for a, b in zip(wall[(k, spp)], wall[(k, 1)]))
    rates[k] = (samples / dc / 1e6, samples / dw / 1e6)
for k, (name, _) in enumerate(programs):
    rc, rw = rates[k]
    own = "–"
    if k > 0:
        med = statistics.median(render_s[k])
        own = "%.3f" % (spp * size * size / med / 1e6)
    print("| %s | %.3f | %.3f | %.2f× (%.2f×) | %s |" % (name, rc, rw, rc / rates[0][0], rw / rates[0][1], own))
EOF
