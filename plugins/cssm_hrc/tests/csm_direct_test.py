#!/usr/bin/env python3
"""cssm_hrc's direct=csm (Sec. 4.7 "Direct Light") through the gibench command.

csm_direct_test.py GIBENCH ROOT OUT furnace|cornell

furnace: the conformance furnaces (closed emitting sphere, Le = 1, rho 0.5
         and 0.8) with direct=csm at 32 x 32, 4 frames: the image must be
         Le sum_{k<=4} rho^k (max_bounces 3 + the final gather) with its mean
         within 2 % and every pixel within 5 % (the conformance criterion);
         the black image must fail it.
cornell: the Cornell box at 48 x 48, bounces=0 (direct light only), 8
         frames, direct=csm against the path-traced direct light (max bounces
         1, 256 spp): relMSE (gibench diff) must be below 0.1 x the black
         image's; the data_bytes stat must be the CSSM's bytes plus the
         lights' CSMs'.
"""
import json
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "..", "scripts"))
from gi_run import read_pfm, run  # noqa: E402


def furnace(gib, root, out):
    ok = True
    for name, rho in (("furnace_050", 0.5), ("furnace_080", 0.8)):
        scene = os.path.join(root, "tests/data/conformance", name + ".gltf")
        img = os.path.join(out, name + "_csm.pfm")
        run([gib, "render", "--scene", scene, "--method", "cssm_hrc", "--param", "direct=csm", "--size", "32x32",
             "--frames", "4", "--out", img])
        w, h, _, v = read_pfm(img)
        expect = sum(rho ** k for k in range(5))

        def score(px):
            mean = sum(px) / len(px)
            return mean, max(abs(p / expect - 1) for p in px)

        mean, worst = score([sum(v[3 * i:3 * i + 3]) / 3 for i in range(w * h)])
        bmean, bworst = score([0.0] * (w * h))
        print("%s: mean %.4f, expected %.4f (%+.2f %%), worst pixel %.2f %%" % (name, mean, expect,
              100 * (mean / expect - 1), 100 * worst))
        if abs(bmean / expect - 1) < 0.02 and bworst < 0.05:
            sys.exit("FAIL: the black image passes the check")
        ok = ok and abs(mean / expect - 1) < 0.02 and worst < 0.05
    if not ok:
        sys.exit("FAIL: outside 2 % (mean) / 5 % (pixel)")
    print("PASS")


def cornell(gib, root, out):
    scene = os.path.join(root, "scenes/cornell_box.gltf")
    ref, img = os.path.join(out, "cornell_ref_b1.pfm"), os.path.join(out, "cornell_csm_b0.pfm")
    run([gib, "reference", "--scene", scene, "--out", ref, "--size", "48x48", "--spp", "256", "--max-bounces", "1",
         "--threads", "1"])
    timings = os.path.join(out, "cornell_csm_b0.json")
    run([gib, "render", "--scene", scene, "--method", "cssm_hrc", "--param", "direct=csm", "--param", "bounces=0",
         "--size", "48x48", "--frames", "8", "--out", img, "--timings", timings])
    with open(timings) as f:
        st = json.load(f)["stats"]
    # the memory the comparisons chart: the CSSM and the lights' CSMs
    print("data_bytes %d = cssm_bytes %d + csm_bytes %d" % (st["data_bytes"], st["cssm_bytes"], st["csm_bytes"]))
    if not (st["csm_bytes"] > 0 and st["data_bytes"] == st["cssm_bytes"] + st["csm_bytes"]):
        sys.exit("FAIL: data_bytes does not count the CSSM and the lights' CSMs")
    e = json.loads(run([gib, "diff", img, ref, "--json"]))["relmse"]
    eb = json.loads(run([gib, "diff", "--black", ref, "--json"]))["relmse"]
    print("Cornell box, direct light only: relMSE direct=csm %.4f, black %.4f (%.3f x, must be < 0.1)"
          % (e, eb, e / eb))
    if not e < 0.1 * eb:
        sys.exit("FAIL: not below 0.1 x the black image's relMSE")
    print("PASS")


if __name__ == "__main__":
    if len(sys.argv) != 5 or sys.argv[4] not in ("furnace", "cornell"):
        sys.exit("usage: csm_direct_test.py GIBENCH ROOT OUT furnace|cornell")
    os.makedirs(sys.argv[3], exist_ok=True)
    {"furnace": furnace, "cornell": cornell}[sys.argv[4]](*sys.argv[1:4])
