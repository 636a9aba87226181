#!/usr/bin/env python3
"""Issue 33: a study's relative paths resolve from the study file's folder
(or its "base" key, or the current folder for a study on standard input),
whatever folder the command runs in; HDR-FLIP is in `diff` and in a study's
runs.csv.

study_paths_test.py GIBENCH ROOT OUTDIR:
- a study copied next to its own scene ("box.gltf") runs from another
  folder and finds it; its runs.csv has hdr_flip_full with a value, and its
  records name the scene as the study does;
- "base": "../mine" from a sibling folder, and "-" (standard input) with
  paths from the current folder, plan the same scene; a saved view named
  "view:v.json" next to the study is found from another folder;
- a missing scene is refused with exit 2 and one line naming the study
  file and the path as resolved;
- `diff --json` of the committed HDR pair (tests/data/flip) gives NVIDIA's
  HDR-FLIP (FLIP v1.6, tests/data/flip/reference.json) within 5e-5 and its
  exposures within 1e-3 stops; the text output has the hdr_flip line.
On the code before issue 33 the study is refused (its scene is looked up
from the current folder), and diff has no hdr_flip.
"""
import csv
import json
import os
import shutil
import subprocess
import sys

gib, root, out = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2]), os.path.abspath(sys.argv[3])
shutil.rmtree(out, ignore_errors=True)
for d in ("mine", "studies", "elsewhere"):
    os.makedirs(os.path.join(out, d))
fails = []


def check(ok, what):
    if not ok:
        fails.append(what)
        print("FAIL: " + what)


def run(args, cwd, stdin=None):
    return subprocess.run([gib, "-q"] + args, cwd=cwd, input=stdin, capture_output=True, text=True,
                          timeout=120)


for f in ("cornell_box_coarse.gltf", "cornell_box_coarse.bin"):
    shutil.copy(os.path.join(root, "scenes", f), os.path.join(out, "mine", f))
os.rename(os.path.join(out, "mine", "cornell_box_coarse.gltf"), os.path.join(out, "mine", "box.gltf"))
tiny = {"size": [8, 8], "frames": 1, "warmup": 0, "reference": {"spp": 4, "max_bounces": 1},
        "methods": [{"method": "direct", "params": {"light_samples": 1}}]}
box = os.path.join(out, "mine", "box.gltf")

# 1. the study next to its scene, run from another folder
with open(os.path.join(out, "mine", "s.json"), "w") as f:
    json.dump(dict(tiny, name="mine", scenes=["box.gltf"]), f)
p = run(["study", os.path.join(out, "mine", "s.json"), "--out", os.path.join(out, "res")],
        os.path.join(out, "elsewhere"))
check(p.returncode == 0, "the study next to its scene, run from elsewhere: exit %d: %s"
      % (p.returncode, p.stderr.strip()))
if p.returncode == 0:
    with open(os.path.join(out, "res", "runs.csv")) as f:
        rows = list(csv.DictReader(f))
    check(len(rows) == 1 and "hdr_flip_full" in rows[0] and "flip_full" in rows[0],
          "runs.csv lacks hdr_flip_full (or flip_full): %s" % (list(rows[0]) if rows else "no rows"))
    if rows and rows[0].get("hdr_flip_full"):
        v = float(rows[0]["hdr_flip_full"])
        check(0.0 < v < 1.0, "hdr_flip_full %g is not in (0, 1)" % v)
    else:
        check(False, "runs.csv has no hdr_flip_full value")
    check(rows and rows[0]["scene"] == "box.gltf",
          "the record's scene is %r, not the study's name for it" % (rows[0]["scene"] if rows else None))

# 2. "base", and a study on standard input
with open(os.path.join(out, "studies", "b.json"), "w") as f:
    json.dump(dict(tiny, name="based", base="../mine", scenes=["box.gltf"]), f)
p = run(["study", os.path.join(out, "studies", "b.json"), "--dry-run"], root)
check(p.returncode == 0 and ("reference box: %s " % box) in p.stdout,
      "\"base\": \"../mine\" does not plan %s: exit %d\n%s%s" % (box, p.returncode, p.stdout, p.stderr))
p = run(["study", "-", "--dry-run"], out, json.dumps(dict(tiny, name="stdin", scenes=["mine/box.gltf"])))
check(p.returncode == 0 and "reference box: mine/box.gltf " in p.stdout,
      "a study on standard input does not take paths from the current folder: exit %d\n%s%s"
      % (p.returncode, p.stdout, p.stderr))
# its private copy goes under $TMPDIR; one that cannot be made is one line naming it
bad = dict(os.environ, TMPDIR=os.path.join(out, "no_such_dir"))
p = subprocess.run([gib, "-q", "study", "-", "--dry-run"], cwd=out, env=bad, capture_output=True,
                   text=True, timeout=120, input=json.dumps(dict(tiny, name="stdin", scenes=["mine/box.gltf"])))
check(p.returncode == 2 and p.stderr.count("\n") == 1 and "no_such_dir/gibench-study-XXXXXX" in p.stderr
      and "No such file or directory" in p.stderr,
      "an unusable TMPDIR for a study on standard input: exit %d: %s" % (p.returncode, p.stderr))

# a saved view ("camera": "view:FILE") is found the same way
view = {"gibench_view": 1, "scene": box, "method": "direct", "params": [], "width": 8, "height": 8,
        "frames": 1, "seed": 1, "time": 0, "exposure": 0, "nodes": [],
        "camera": {"eye": [4.5, 3.5, -6.0], "forward": [-0.25, -0.1, 1.0], "up": [0, 1, 0], "yfov": 0.7,
                   "znear": 0.01, "zfar": 100}}
with open(os.path.join(out, "mine", "v.json"), "w") as f:
    json.dump(view, f)
with open(os.path.join(out, "mine", "view.json"), "w") as f:
    json.dump(dict(tiny, name="view", scenes=["box.gltf"], camera="view:v.json"), f)
p = run(["study", os.path.join(out, "mine", "view.json"), "--dry-run"], os.path.join(out, "elsewhere"))
check(p.returncode == 0, "\"camera\": \"view:v.json\" next to the study: exit %d: %s"
      % (p.returncode, p.stderr.strip()))

# 3. a missing scene: one line, the study file and the resolved path
missing = os.path.join(out, "studies", "m.json")
with open(missing, "w") as f:
    json.dump(dict(tiny, name="missing", scenes=["nope.gltf"]), f)
p = run(["study", missing, "--dry-run"], root)
err = p.stderr.strip()
check(p.returncode == 2 and "\n" not in err and missing + ": /scenes/0: " in err
      and os.path.join(out, "studies", "nope.gltf") in err,
      "a missing scene: exit %d, stderr %r" % (p.returncode, err))

# 4. HDR-FLIP in diff against NVIDIA's tool
flip = os.path.join(root, "tests", "data", "flip")
with open(os.path.join(flip, "reference.json")) as f:
    nv = json.load(f)["hdr"]["render"]
p = run(["diff", "--json", os.path.join(flip, "render_test.exr"), os.path.join(flip, "render_ref.exr")], root)
j = json.loads(p.stdout) if p.returncode == 0 else {}
got = j.get("hdr_flip")
check(got is not None and abs(got - nv["mean"]) <= 5e-5,
      "diff --json hdr_flip %s, NVIDIA %s" % (got, nv["mean"]))
ex = nv["exposures"]
check(j.get("hdr_flip_exposures") == int(ex["Number of exposures"])
      and abs((j.get("hdr_flip_start") or 1e9) - float(ex["Start exposure"])) <= 1e-3
      and abs((j.get("hdr_flip_stop") or 1e9) - float(ex["Stop exposure"])) <= 1e-3,
      "diff --json exposures %s..%s (%s), NVIDIA %s" % (j.get("hdr_flip_start"), j.get("hdr_flip_stop"),
                                                          j.get("hdr_flip_exposures"), ex))
p = run(["diff", os.path.join(flip, "render_test.exr"), os.path.join(flip, "render_ref.exr")], root)
check(p.returncode == 0 and "\nhdr_flip   0.0573" in p.stdout, "diff's text lacks hdr_flip:\n" + p.stdout)

print("%d check(s) failed" % len(fails) if fails else "ok")
sys.exit(1 if fails else 0)
