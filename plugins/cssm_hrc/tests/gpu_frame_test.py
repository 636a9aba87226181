#!/usr/bin/env python3
"""The HRC bounces solved every frame with jitter (bounces_every=frame,
issue 29), GPU against C, through gibench.

gpu_frame_test.py GIBENCH ROOT OUT SCENE

cssm_hrc with bounces_every=frame (the default) re-solves its n bounces in
every frame, the senders of each bounce jittered with the frame's streams
(§4.5 applied to the atlas' gathers). On SCENE (relative to ROOT) at
32 x 32, atlas 32^2, M = 8, the maps built once (a fresh cache directory
under OUT), against the path-traced reference (Embree, 1024 spp, 4
bounces, pixel centres). Passes when
  - the GPU run (gather=gpu, bounces_on=gpu) ran both compute passes
    (stats gather_gpu and bounces_gpu 1) and the C run (gather=cpu,
    bounces_on=cpu) neither;
  - the two agree far below their error after 4 frames: relMSE(gpu, cpu)
    at most 1/100 of the smaller relMSE to the reference, and so do their
    texel radiances (debug buffer `atlas`) after 2 frames (the second
    frame's streams: a pass that ignored the frame would differ);
  - each frame's bounces draw anew: the texel radiances after 1 and after
    2 frames differ (relMSE above 1e-6), and with jitter=false they are
    equal (0);
  - the progressive average approaches the reference: relMSE after 16
    frames at most 0.9 x after 1 frame, after 4 at most after 1;
  - both 4-frame images beat the trivial answers on the same data:
    relMSE at most 1/2 of the better of black and the unshadowed `direct`.
"""
import json
import os
import shutil
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "..", "scripts"))
from gi_run import run  # noqa: E402
from gpu_gather_test import SIZE, finish, relmse, write_black  # noqa: E402

GPU = ["--param", "gather=gpu", "--param", "bounces_on=gpu"]
CPU = ["--param", "gather=cpu", "--param", "bounces_on=cpu"]


def render(gib, scene, out, name, frames, where, extra=(), buffer=None):
    img, tim = os.path.join(out, name + ".pfm"), os.path.join(out, name + ".json")
    args = [gib, "-q", "render", "--scene", scene, "--method", "cssm_hrc", "--size", SIZE,
            "--frames", str(frames), "--param", "M=8", "--param", "bounces_every=frame"]
    args += list(where) + list(extra) + ["--out", img]
    if buffer:
        run(args + ["--buffer", buffer])
        return img, {}
    run(args + ["--timings", tim])
    with open(tim) as f:
        return img, json.load(f)["stats"]


def main(gib, root, out, rel):
    shutil.rmtree(out, ignore_errors=True)
    os.makedirs(out)
    os.environ["GIBENCH_CACHE"] = os.path.join(out, "cache")
    scene = os.path.join(root, rel)
    ref, dimg, black = (os.path.join(out, n + ".pfm") for n in ("ref", "direct", "black"))
    run([gib, "-q", "reference", "--scene", scene, "--out", ref, "--size", SIZE, "--spp", "1024",
         "--max-bounces", "4", "--pixel", "center"])
    run([gib, "-q", "render", "--scene", scene, "--method", "direct", "--size", SIZE, "--out", dimg])
    write_black(black)
    trivial = min(relmse(gib, black, ref), relmse(gib, dimg, ref))

    gpu, s_gpu = render(gib, scene, out, "gpu4", 4, GPU)
    cpu, s_cpu = render(gib, scene, out, "cpu4", 4, CPU)
    e_gpu, e_cpu, e_pair = relmse(gib, gpu, ref), relmse(gib, cpu, ref), relmse(gib, gpu, cpu)
    a_gpu = render(gib, scene, out, "gpu_atlas2", 2, GPU, buffer="atlas")[0]
    a_cpu = render(gib, scene, out, "cpu_atlas2", 2, CPU, buffer="atlas")[0]
    a_gpu1 = render(gib, scene, out, "gpu_atlas1", 1, GPU, buffer="atlas")[0]
    e_atlas, e_fresh = relmse(gib, a_gpu, a_cpu), relmse(gib, a_gpu, a_gpu1)
    fixed = [render(gib, scene, out, "fixed_atlas%d" % f, f, GPU, ("--param", "jitter=false"),
                    buffer="atlas")[0] for f in (1, 2)]
    e_fixed = relmse(gib, fixed[0], fixed[1])
    e1 = relmse(gib, render(gib, scene, out, "gpu1", 1, GPU)[0], ref)
    e16 = relmse(gib, render(gib, scene, out, "gpu16", 16, GPU)[0], ref)
    print("%s: relMSE to the reference gpu %.4g, cpu %.4g (4 frames), gpu to cpu %.3g (image), "
          "%.3g (texels, frame 2); texels frame 1 to 2: %.3g (jitter), %.3g (jitter=false); "
          "gpu 1 / 4 / 16 frames %.4g / %.4g / %.4g; better trivial %.4g"
          % (rel, e_gpu, e_cpu, e_pair, e_atlas, e_fresh, e_fixed, e1, e_gpu, e16, trivial))
    fails = []
    if (s_gpu.get("gather_gpu"), s_gpu.get("bounces_gpu")) != (1, 1):
        fails.append("the GPU run did not run both passes: %s" % s_gpu)
    if (s_cpu.get("gather_gpu"), s_cpu.get("bounces_gpu")) != (0, 0):
        fails.append("the C run ran a pass: %s" % s_cpu)
    if not max(e_pair, e_atlas) <= 0.01 * min(e_gpu, e_cpu):
        fails.append("the GPU and C paths differ by more than 1/100 of the images' error")
    if not e_fresh > 1e-6:
        fails.append("the second frame's bounces drew the first frame's senders")
    if e_fixed != 0:
        fails.append("without jitter the bounces differ between frames")
    if not (e16 <= 0.9 * e1 and e_gpu <= e1):
        fails.append("the frames' average does not approach the reference")
    if not max(e_gpu, e_cpu) <= 0.5 * trivial:
        fails.append("not 2 x closer to the reference than black and `direct`")
    finish(fails)


if __name__ == "__main__":
    if len(sys.argv) != 5:
        sys.exit("usage: gpu_frame_test.py GIBENCH ROOT OUT SCENE")
    main(*sys.argv[1:5])
