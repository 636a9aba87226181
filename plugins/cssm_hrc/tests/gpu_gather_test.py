#!/usr/bin/env python3
"""gather=gpu against gather=cpu (issue 29), through gibench.

gpu_gather_test.py GIBENCH ROOT OUT SCENE [NAME=VALUE ...]

The per-pixel final gather of cssm_hrc as a compute pass
(shaders/cssm_gather.comp, the GLSL twin of final_gather.c / hrc.c /
cssm.c's look-up) and the C gather, on SCENE (relative to ROOT) at 32 x 32,
4 jittered frames, atlas 32^2 (the default), M = 8, the maps built once (a fresh cache
directory under OUT), the parameters given after SCENE added to both runs
(mode=texels: texel mode, whose per-texel glossy gather is the pass,
shaders/cssm_bounce.comp with CSSM_GLOSSY 1, the twin of
final_gather.c's cssm_texel_gather; its stat texel_gather_gpu is checked
instead of gather_gpu). Passes when
  - the GPU run ran the compute pass (stat gather_gpu 1) and the C run did
    not (gather_gpu 0);
  - the two images agree far below their noise: relMSE(gpu, cpu) at most
    1/100 of the smaller of relMSE(gpu, reference) and relMSE(cpu,
    reference) (the same numbers in the same order give ~1e-15; a wrong
    look-up, bound or jitter in the twin gives 1e-2 and more);
  - both beat the trivial answers on the same data: relMSE to the
    reference (Embree, 256 spp, 4 bounces: the method's paths of 0 .. n + 1
    = 4 bounces) at most 1/2 of the better of black and the unshadowed
    `direct` method.
"""
import json
import os
import shutil
import struct
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "..", "scripts"))
from gi_run import run  # noqa: E402

SIZE = "32x32"


def relmse(gib, test, ref):
    return json.loads(run([gib, "diff", "--json", test, ref]))["relmse"]


def write_black(path):
    w, h = (int(x) for x in SIZE.split("x"))
    with open(path, "wb") as f:
        f.write(b"PF\n%d %d\n-1.0\n" % (w, h))
        f.write(struct.pack("<%df" % (3 * w * h), *([0.0] * (3 * w * h))))


def truth(gib, scene, out):
    """The reference (Embree, 256 spp, 4 bounces) and the better of the two
    trivial answers' relMSE to it (black, the unshadowed `direct`)."""
    ref, dimg, black = (os.path.join(out, n + ".pfm") for n in ("ref", "direct", "black"))
    run([gib, "-q", "reference", "--scene", scene, "--out", ref, "--size", SIZE, "--spp", "256",
         "--max-bounces", "4"])
    run([gib, "-q", "render", "--scene", scene, "--method", "direct", "--size", SIZE, "--out", dimg])
    write_black(black)
    return ref, min(relmse(gib, black, ref), relmse(gib, dimg, ref))


def finish(fails):
    for f in fails:
        print("FAIL: " + f)
    if fails:
        sys.exit(1)
    print("PASS")


def render(gib, scene, out, name, gather, cache, extra=(), stat="gather_gpu"):
    img, tim = os.path.join(out, name + ".pfm"), os.path.join(out, name + ".json")
    os.environ["GIBENCH_CACHE"] = cache
    params = [a for p in extra for a in ("--param", p)]
    run([gib, "-q", "render", "--scene", scene, "--method", "cssm_hrc", "--size", SIZE, "--frames", "4",
         "--param", "M=8", "--param", "gather=" + gather] + params + ["--out", img,
         "--timings", tim])
    with open(tim) as f:
        return img, json.load(f)["stats"].get(stat)


def main(gib, root, out, rel, *extra):
    shutil.rmtree(out, ignore_errors=True)
    os.makedirs(out)
    cache = os.path.join(out, "cache")
    scene = os.path.join(root, rel)
    ref, trivial = truth(gib, scene, out)
    stat = "texel_gather_gpu" if "mode=texels" in extra else "gather_gpu"
    gpu, on_gpu = render(gib, scene, out, "gpu", "gpu", cache, extra, stat)
    cpu, on_cpu = render(gib, scene, out, "cpu", "cpu", cache, extra, stat)
    e_gpu, e_cpu, e_pair = relmse(gib, gpu, ref), relmse(gib, cpu, ref), relmse(gib, gpu, cpu)
    print("%s: relMSE gpu %.4g, cpu %.4g to the reference; gpu to cpu %.3g; better trivial %.4g"
          % (rel, e_gpu, e_cpu, e_pair, trivial))
    fails = []
    if on_gpu != 1 or on_cpu != 0:
        fails.append("stat %s %s (gpu) and %s (cpu), expected 1 and 0" % (stat, on_gpu, on_cpu))
    if not e_pair <= 0.01 * min(e_gpu, e_cpu):
        fails.append("the two gathers differ by more than 1/100 of their error")
    if not max(e_gpu, e_cpu) <= 0.5 * trivial:
        fails.append("not 2 x closer to the reference than black and `direct`")
    finish(fails)


if __name__ == "__main__":
    if len(sys.argv) < 5:
        sys.exit("usage: gpu_gather_test.py GIBENCH ROOT OUT SCENE [NAME=VALUE ...]")
    main(*sys.argv[1:])
