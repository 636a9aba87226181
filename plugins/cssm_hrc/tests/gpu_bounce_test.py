#!/usr/bin/env python3
"""bounces_on=gpu against bounces_on=cpu (issue 29), through gibench.

gpu_bounce_test.py GIBENCH ROOT OUT SCENE

The HRC bounces' per-texel gathers of cssm_hrc (§4.1.1) as a compute pass
(shaders/cssm_bounce.comp over cssm_traverse.glsl / cssm_lookup.glsl, the
GLSL twins of hrc.c's gather_atlas and cssm.c's look-up) and the C loop,
on SCENE (relative to ROOT) at 32 x 32, 1 frame, atlas 32^2 (the default), M = 4,
the maps built once (a fresh cache directory under OUT);
the final gather runs in C (gather=cpu) in both, so the two differ only
in the texel radiances the bounces leave. Passes when
  - the GPU run ran the pass (stat bounces_gpu 1) and the C run did not;
  - the texel radiances (debug buffer `atlas`) and the images agree far
    below the images' error: relMSE(gpu, cpu) of each at most 1/100 of
    the smaller of relMSE(gpu, reference) and relMSE(cpu, reference) (the
    same numbers in another rounding give ~1e-15; a texel gathering itself,
    a wrong bound or look-up gives 1e-3 and more);
  - both images beat the trivial answers on the same data: relMSE to the
    reference (Embree, 256 spp, 4 bounces) at most 1/2 of the better of
    black and the unshadowed `direct` method.
"""
import json
import os
import shutil
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "..", "scripts"))
from gi_run import run  # noqa: E402
from gpu_gather_test import SIZE, finish, relmse, truth  # noqa: E402


def render(gib, scene, out, where):
    img, tim = os.path.join(out, where + ".pfm"), os.path.join(out, where + ".json")
    atlas = os.path.join(out, where + ".atlas.pfm")
    args = [gib, "-q", "render", "--scene", scene, "--method", "cssm_hrc", "--size", SIZE, "--frames", "1",
            "--param", "M=4", "--param", "gather=cpu", "--param", "bounces_on=" + where]
    run(args + ["--out", img, "--timings", tim])
    run(args + ["--buffer", "atlas", "--out", atlas])
    with open(tim) as f:
        return img, atlas, json.load(f)["stats"].get("bounces_gpu")


def main(gib, root, out, rel):
    shutil.rmtree(out, ignore_errors=True)
    os.makedirs(out)
    os.environ["GIBENCH_CACHE"] = os.path.join(out, "cache")
    scene = os.path.join(root, rel)
    ref, trivial = truth(gib, scene, out)
    gpu, gpu_atlas, on_gpu = render(gib, scene, out, "gpu")
    cpu, cpu_atlas, on_cpu = render(gib, scene, out, "cpu")
    e_gpu, e_cpu = relmse(gib, gpu, ref), relmse(gib, cpu, ref)
    e_pair, e_atlas = relmse(gib, gpu, cpu), relmse(gib, gpu_atlas, cpu_atlas)
    print("%s: relMSE gpu %.4g, cpu %.4g to the reference; gpu to cpu %.3g (image), %.3g (texels); "
          "better trivial %.4g" % (rel, e_gpu, e_cpu, e_pair, e_atlas, trivial))
    fails = []
    if on_gpu != 1 or on_cpu != 0:
        fails.append("stat bounces_gpu %s (gpu) and %s (cpu), expected 1 and 0" % (on_gpu, on_cpu))
    if not max(e_pair, e_atlas) <= 0.01 * min(e_gpu, e_cpu):
        fails.append("the two bounce paths differ by more than 1/100 of the images' error")
    if not max(e_gpu, e_cpu) <= 0.5 * trivial:
        fails.append("not 2 x closer to the reference than black and `direct`")
    finish(fails)


if __name__ == "__main__":
    if len(sys.argv) != 5:
        sys.exit("usage: gpu_bounce_test.py GIBENCH ROOT OUT SCENE")
    main(*sys.argv[1:5])
