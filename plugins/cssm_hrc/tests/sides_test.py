#!/usr/bin/env python3
"""The cssm_hrc plugin and glTF's doubleSided (issue 28), through gibench.

sides_test.py GIBENCH ROOT OUT

A closed emitting sphere (Le = 1, rho = 0.5) wound outward with
doubleSided: true (tests/data/truth/sphere_out_ds.gltf), seen from its
centre: its back faces (inside) are lit with reversed normals. 16 x 16
pixels, atlas 16^2, M = 8 (bounces = 3: paths of up to 4 bounces, so every
pixel must be Le (1 + rho + ... + rho^4) = 1.9375). The image's mean must
be within 2 % of 1.9375 and at most 1/4 of the error of the better trivial
answer: black (-100 %) and the unshadowed `direct` method (its image of
the same scene). Before the back sides had texels (base code) it gave
1.000 (emission only). The inward single-sided furnace is cssm_furnace's
(cssm_tests) and the conformance suite's.
"""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "..", "scripts"))
from gi_run import read_pfm, run  # noqa: E402

EXPECT = 1.0 * sum(0.5 ** k for k in range(5))  # 1.9375


def mean(path):
    d = read_pfm(path)[3]
    return sum(d) / len(d)


def main(gib, root, out):
    os.makedirs(out, exist_ok=True)
    ok = True
    for rel in ("tests/data/truth/sphere_out_ds.gltf",):
        scene = os.path.join(root, rel)
        name = os.path.splitext(os.path.basename(rel))[0]
        img, dimg = os.path.join(out, name + "_cssm.pfm"), os.path.join(out, name + "_direct.pfm")
        run([gib, "render", "--scene", scene, "--method", "cssm_hrc", "--size", "16x16", "--out", img,
             "--param", "atlas=16", "--param", "M=8", "--no-cache"])
        run([gib, "render", "--scene", scene, "--method", "direct", "--size", "16x16", "--out", dimg])
        e = abs(mean(img) / EXPECT - 1)
        ed = abs(mean(dimg) / EXPECT - 1)
        trivial = min(1.0, ed)  # black is off by 100 %
        print("%s: cssm_hrc %.4f (expected %.4f, %+.2f %%); direct %.4f (%+.2f %%), black -100 %%"
              % (rel, mean(img), EXPECT, 100 * (mean(img) / EXPECT - 1), mean(dimg),
                 100 * (mean(dimg) / EXPECT - 1)))
        if not (e <= 0.02 and e <= 0.25 * trivial):
            print("FAIL: %s off by more than 2 %% or not 4 x closer than the better trivial answer" % rel)
            ok = False
    if not ok:
        sys.exit(1)
    print("PASS")


if __name__ == "__main__":
    if len(sys.argv) != 4:
        sys.exit("usage: sides_test.py GIBENCH ROOT OUT")
    main(*sys.argv[1:4])
