#!/usr/bin/env python3
"""Debug buffers (plugin ABI 1.3, issue 33) through the CLI, at 32x32 on the
Cornell box with small precomputation settings:

- every paper plugin declares at least two buffers (`gibench methods ID
  --json`), and each one is written (`render --buffer`), finite and not
  constant;
- checks that make them mean what they say: csm's visibility is in [0, 1],
  dark pixels of it are dark in the csm image where the unshadowed `direct`
  method lights them (and lit ones lit), which a constant 1 (no shadows,
  the `direct` answer) or 0 (black) fails; csm's segments are >= 1 wherever
  a shadow query was made; avg's voxels cover every pixel the avg image
  shows geometry in; avg's VPLs splat onto the picture;
- an unknown name fails with exit 2, a one-line error listing the buffers,
  and writes no file;
- fake plugins (FAKEDIR, tests/unit/fake_plugin.c): one built for ABI 1.2
  has no buffers ("buffers: none"); one whose buffers break the contract is
  refused with one line and no file (a screen-space buffer of the wrong
  size, NaN, a failing call, also beside a good buffer), and its good ones
  are written at their sizes.

  debug_buffers_test.py GIBENCH ROOT OUTDIR FAKEDIR
"""
import json
import math
import os
import struct
import subprocess
import sys

gib, root, out, fakedir = sys.argv[1:5]
os.makedirs(out, exist_ok=True)
scene = os.path.join(root, "scenes/cornell_box.gltf")
# small settings: each render well under the test's budget, no cache needed
PARAMS = {
    "csm": ["N=4", "M=32", "N_local=2", "M_local=32"],
    "avg": ["grid=32", "vpls=256"],
    "cssm_hrc": ["atlas=16", "M=8"],
    "vlf": ["l=64", "N=16", "density=6", "iterations=4"],
    "implicit_vis": ["N=8"],
    "direct": [],
}
PAPERS = ["csm", "cssm_hrc", "implicit_vis", "vlf", "avg"]
fails = 0


def fail(msg):
    global fails
    fails += 1
    print("FAIL: " + msg)


def read_pfm(path):
    with open(path, "rb") as f:
        assert f.readline().strip() == b"PF"
        w, h = map(int, f.readline().split())
        scale = float(f.readline())
        n = w * h * 3
        v = struct.unpack(("<" if scale < 0 else ">") + "f" * n, f.read(4 * n))
    # PFM rows run bottom to top; only per-pixel relations matter here
    return w, h, [v[3 * i] * 0.2126 + v[3 * i + 1] * 0.7152 + v[3 * i + 2] * 0.0722
                  for i in range(w * h)]


def render(method, name, buffers=None, extra=()):
    path = os.path.join(out, name + ".pfm")
    args = [gib, "-q", "render", "--scene", scene, "--method", method, "--size", "32x32",
            "--no-cache", "--out", path]
    for p in PARAMS.get(method, []):
        args += ["--param", p]
    if buffers:
        args += ["--buffer", ",".join(buffers)]
    r = subprocess.run(args + list(extra), capture_output=True, text=True)
    return r, path


def render_buffers(method, names):
    # the image of the same run beside the buffers (--frames-out, one frame)
    frame = os.path.join(out, method + "_img_%d.pfm")
    r, path = render(method, method + "_buf", names, ["--frames-out", frame])
    if r.returncode != 0:
        fail("%s --buffer %s: exit %d: %s" % (method, ",".join(names), r.returncode, r.stderr))
        return {}
    got = {}
    for n in names:
        p = path[:-4] + "." + n + ".pfm" if len(names) > 1 else path
        if not os.path.exists(p):
            fail("%s: %s not written" % (method, p))
            continue
        w, h, v = read_pfm(p)
        if (method, n) in screen and (w, h) != (32, 32):
            fail("%s %s: %dx%d, not 32x32" % (method, n, w, h))
        if not all(math.isfinite(x) for x in v):
            fail("%s %s: non-finite values" % (method, n))
        if max(v) - min(v) <= 1e-6:
            fail("%s %s: constant %g" % (method, n, v[0]))
        got[n] = v
    return got


def image(method):
    """The method's image: the buffer run's frame, or (direct) a render."""
    path = os.path.join(out, method + "_img_0.pfm")
    if method == "direct":
        r, path = render(method, method + "_img")
        if r.returncode != 0:
            fail("%s: exit %d: %s" % (method, r.returncode, r.stderr))
            return None
    return read_pfm(path)[2] if os.path.exists(path) else None


def mean(v):
    return sum(v) / len(v)


def mae(a, b):
    return mean([abs(x - y) for x, y in zip(a, b)])


listing = subprocess.run([gib, "methods", "--json"], capture_output=True, text=True, check=True)
methods = json.loads(listing.stdout)
declared = {m["id"]: [b["name"] for b in m.get("buffers", [])] for m in methods}
screen = {(m["id"], b["name"]) for m in methods for b in m.get("buffers", []) if b["space"] == "screen"}
for m in PAPERS:
    if len(declared.get(m, [])) < 2:
        fail("%s declares %d debug buffers, at least 2 wanted" % (m, len(declared.get(m, []))))
bufs = {m: render_buffers(m, declared[m]) for m in PAPERS if len(declared.get(m, [])) >= 2}

direct = image("direct")
csm_img = image("csm")
vis, seg = bufs.get("csm", {}).get("visibility"), bufs.get("csm", {}).get("segments")
if vis and direct and csm_img:
    if min(vis) < 0 or max(vis) > 1:
        fail("csm visibility outside [0, 1]: %g..%g" % (min(vis), max(vis)))
    lit = [i for i in range(len(direct)) if direct[i] > 1e-3]
    dark = [i for i in lit if vis[i] < 0.05]
    bright = [i for i in lit if vis[i] > 0.95]
    # a shadow term explains the csm image: where it says shadow, csm is
    # dark beside direct; where it says lit, csm is as bright
    ok_dark = sum(1 for i in dark if csm_img[i] < 0.25 * direct[i])
    ok_bright = sum(1 for i in bright if csm_img[i] > 0.5 * direct[i])
    print("csm visibility: %d lit pixels, %d in shadow (%d dark in csm), %d lit (%d bright)"
          % (len(lit), len(dark), ok_dark, len(bright), ok_bright))
    if len(dark) < 20 or len(bright) < 20:
        fail("csm visibility: %d shadowed and %d lit pixels, at least 20 each wanted"
             % (len(dark), len(bright)))
    elif ok_dark < 0.85 * len(dark) or ok_bright < 0.9 * len(bright):
        fail("csm visibility disagrees with the csm image: %d/%d dark, %d/%d bright"
             % (ok_dark, len(dark), ok_bright, len(bright)))
if seg and vis and direct:
    # a pixel some light reached through the CSMs made at least one query
    queried = [i for i in range(len(direct)) if direct[i] > 1e-3 and vis[i] > 0.05]
    low = sum(1 for i in queried if seg[i] < 1)
    if low or max(seg) <= 1:
        fail("csm segments: %d queried pixels below 1, max %g" % (low, max(seg)))

avg_img = image("avg")
vox, vpl = bufs.get("avg", {}).get("voxels"), bufs.get("avg", {}).get("vpls")
if vox and avg_img:
    shown = [i for i in range(len(avg_img)) if avg_img[i] > 0]
    missed = sum(1 for i in shown if vox[i] <= 0)
    print("avg voxels: %d of %d geometry pixels without a voxel" % (missed, len(shown)))
    if len(shown) < 100 or missed > 0.02 * len(shown):
        fail("avg voxels miss %d of %d geometry pixels" % (missed, len(shown)))
if vpl:
    splats = sum(1 for x in vpl if x > 0)
    print("avg vpls: %d pixels hold a VPL" % splats)
    if splats < 10:
        fail("avg vpls: only %d pixels hold a VPL" % splats)

cssm_img = image("cssm_hrc")
atlas, ind = bufs.get("cssm_hrc", {}).get("atlas"), bufs.get("cssm_hrc", {}).get("indirect")
if atlas and ind and cssm_img and direct:
    shown = [i for i in range(len(cssm_img)) if cssm_img[i] > 0]
    lit = sum(1 for i in shown if ind[i] > 0)
    ratio = mean(ind) / mean(cssm_img)
    print("cssm_hrc: atlas %d of %d texels lit; indirect on %d of %d pixels, %.3f of the image"
          % (sum(1 for x in atlas if x > 0), len(atlas), lit, len(shown), ratio))
    # in a closed box every surface the camera sees gets light reflected by the
    # others; the indirect is a part of the image, not all of it (nor none)
    if sum(1 for x in atlas if x > 0) < 0.1 * len(atlas):
        fail("cssm_hrc atlas: fewer than 10 % of its texels lit")
    if lit < 0.95 * len(shown) or not 0.05 < ratio < 0.8:
        fail("cssm_hrc indirect: on %d of %d pixels, %.3f of the image" % (lit, len(shown), ratio))

# vlf and implicit_vis: the buffer is what the image is made of (a diffuse
# scene): closer to the image than the trivial answers, black and direct
for m, name in (("vlf", "diffuse"), ("implicit_vis", "gathered")):
    b, img = bufs.get(m, {}).get(name), image(m)
    if not (b and img and direct):
        continue
    err, err_black, err_direct = mae(b, img), mean([abs(x) for x in img]), mae(direct, img)
    print("%s %s: mean abs difference to the image %.4f (black %.4f, direct %.4f)"
          % (m, name, err, err_black, err_direct))
    # the buffer picks one element per pixel, the image filters over several
    if err > 0.15 * err_black or err > 0.5 * err_direct:
        fail("%s %s: %.4f from the image, more than 0.15 of black's %.4f or 0.5 of direct's %.4f"
             % (m, name, err, err_black, err_direct))
dirn = bufs.get("vlf", {}).get("direction")
if dirn and sum(1 for x in dirn if x > 0) < 0.1 * len(dirn):
    fail("vlf direction: fewer than 10 % of its rays carry light")
links = bufs.get("implicit_vis", {}).get("links")
iv_img = image("implicit_vis")
if links and iv_img:
    shown = [i for i in range(len(iv_img)) if iv_img[i] > 0]
    # a count (the luminance of a grey pixel: the count within rounding)
    linked = sum(1 for i in shown if links[i] >= 0.999 and abs(links[i] - round(links[i])) < 1e-3)
    if linked < 0.95 * len(shown):
        fail("implicit_vis links: %d of %d surface pixels have a whole number >= 1" % (linked, len(shown)))

# an unknown name: exit 2, one line naming the buffers, no file
r, path = render("csm", "unknown", ["visibility", "nosuch"])
line = r.stderr.strip()
if r.returncode != 2 or "\n" in line or "nosuch" not in line or "visibility, segments" not in line:
    fail("unknown buffer: exit %d, '%s'" % (r.returncode, line))
for p in (path, path[:-4] + ".visibility.pfm", path[:-4] + ".nosuch.pfm"):
    if os.path.exists(p):
        fail("unknown buffer: %s was written" % p)
r = subprocess.run([gib, "methods", "csm"], capture_output=True, text=True)
if r.returncode != 0 or "debug buffers" not in r.stdout or "visibility" not in r.stdout:
    fail("methods csm lists no debug buffers")
# the fakes: the contract enforced by the harness (debug_buffer.h)
env = dict(os.environ, GIBENCH_PLUGIN_PATH=fakedir)


def fake(method, names, name):
    path = os.path.join(out, name + ".pfm")
    args = [gib, "-q", "render", "--scene", scene, "--method", method, "--size", "32x32",
            "--out", path, "--buffer", names]
    return subprocess.run(args, capture_output=True, text=True, env=env), path


r = subprocess.run([gib, "methods", "fake_abi12"], capture_output=True, text=True, env=env)
if r.returncode != 0 or "debug buffers" in r.stdout:
    fail("methods fake_abi12: exit %d, '%s'" % (r.returncode, r.stdout))
r, path = fake("fake_abi12", "beyond", "abi12")
if r.returncode != 2 or "no debug buffer 'beyond' (buffers: none)" not in r.stderr or os.path.exists(path):
    fail("fake_abi12 --buffer: exit %d, '%s'" % (r.returncode, r.stderr.strip()))
r, path = fake("fake_buffers", "ramp,tile", "fake_ok")
sizes = [read_pfm(path[:-4] + "." + n + ".pfm")[:2] for n in ("ramp", "tile")
         if os.path.exists(path[:-4] + "." + n + ".pfm")]
if r.returncode != 0 or sizes != [(32, 32), (3, 2)]:
    fail("fake_buffers ramp,tile: exit %d, sizes %s: %s" % (r.returncode, sizes, r.stderr.strip()))
for names, why in (("wrong_size", "is 1x1, a screen-space buffer must be 32x32"),
                   ("nan", "NaN or infinite"), ("ramp,fails", "debug buffer 'fails' failed")):
    r, path = fake("fake_buffers", names, "fake_" + names.replace(",", "_"))
    written = [p for p in os.listdir(out) if p.startswith("fake_" + names.replace(",", "_"))]
    line = r.stderr.strip()
    if r.returncode != 1 or why not in line or "\n" in line or written:
        fail("fake_buffers %s: exit %d, '%s', wrote %s" % (names, r.returncode, line, written))
print("debug_buffers: %s" % ("FAIL" if fails else "ok"))
sys.exit(1 if fails else 0)
