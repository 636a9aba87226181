#!/usr/bin/env python3
"""The vlf paper's Fig. 8 from a study's output: reference | low | high | difference.

Mortensen et al. 2007, Fig. 8: the specular Cornell box rendered by a path
tracer (a), by VLF with fixed directions only ("low quality", b) and with
perturbed directions ("high quality", c); the paper subtracts (a) from (b)
and reports the MSE. This script reads a study folder written by
    gibench study plugins/vlf/study.json --out DIR
picks the two runs of one label on cornell_glossy.gltf (perturbed = 0 is
"low", perturbed > 0 is "high"), the study's reference of the same scene
(the 8-bounce one, vlf's bounce-matched reference, or --bounces B), and
writes one PNG of four panels side by side, all tonemapped alike by
gibench's own writer (linear radiance, --exposure stops, sRGB):

    reference | low | high | |low - reference| x --gain

It prints the MSE (linear radiance over all pixels, the paper's measure)
of low and high against that reference. Needs the study's EXR images
(not committed) and the gibench Python module:

    PYTHONPATH=build/release/python /usr/bin/python3 plugins/vlf/fig8.py DIR \\
        --label fig8_paper --out results/vlf/fig8_paper.png

Exit status: 0 written; 1 a run or the reference is missing; 2 bad usage.
"""

import argparse
import csv
import glob
import os
import sys


def fail(msg, code=1):
    print("fig8.py: " + msg, file=sys.stderr)
    sys.exit(code)


def params(s):
    return dict(kv.split("=", 1) for kv in (s or "").split(",") if "=" in kv)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("dir", help="the study's output folder")
    ap.add_argument("--label", default="fig8_paper", help="the study entry holding the low and high runs")
    ap.add_argument("--scene", default="cornell_glossy", help="scene name (file name without extension)")
    ap.add_argument("--bounces", type=int, default=8, help="the reference's bounce limit (vlf's matched: 8)")
    ap.add_argument("--out", required=True, help="the PNG to write")
    ap.add_argument("--exposure", type=float, default=0.0, help="stops before tonemapping, every panel")
    ap.add_argument("--gain", type=float, default=10.0, help="the difference panel's scale")
    a = ap.parse_args()
    if not a.out.endswith(".png"):
        fail("--out must name a .png file", 2)
    try:
        import numpy as np
        import gibench
    except ImportError as e:
        fail(f"{e} (run with PYTHONPATH=build/release/python /usr/bin/python3)", 2)

    runs_csv = os.path.join(a.dir, "runs.csv")
    if not os.path.isfile(runs_csv):
        fail(f"{runs_csv}: no such file")
    with open(runs_csv, newline="") as fh:
        rows = [r for r in csv.DictReader(fh) if r["label"] == a.label and r["status"] == "ok"
                and os.path.splitext(os.path.basename(r["scene"]))[0] == a.scene]
    low = [r for r in rows if params(r["params"]).get("perturbed", "0") == "0"]
    high = [r for r in rows if params(r["params"]).get("perturbed", "0") != "0"]
    if len(low) != 1 or len(high) != 1:
        fail(f"{runs_csv}: label {a.label} on {a.scene} needs one run with perturbed = 0 and one with "
             f"perturbed > 0 (found {len(low)} and {len(high)})")
    refs = sorted(glob.glob(os.path.join(a.dir, "references", f"{a.scene}_b{a.bounces}_*spp*.exr")))
    refs = [f for f in refs if "_conv_" not in os.path.basename(f)]
    if not refs:
        fail(f"{a.dir}/references: no {a.scene}_b{a.bounces}_*spp*.exr (the EXRs are not committed: run the study)")

    ref = gibench.read(refs[0])
    imgs = []
    for r in (low[0], high[0]):
        path = os.path.join(a.dir, "runs", r["run"], "image.exr")
        if not os.path.isfile(path):
            fail(f"{path}: no such file (the EXRs are not committed: run the study)")
        img = gibench.read(path)
        if img.shape != ref.shape:
            fail(f"{path}: {img.shape[1]}x{img.shape[0]} against the reference's {ref.shape[1]}x{ref.shape[0]}")
        imgs.append(img)
    diff = np.abs(imgs[0] - ref) * a.gain
    h, w = ref.shape[:2]
    gap = max(1, w // 32)
    panels = [ref, imgs[0], imgs[1], diff]
    out = np.ones((h, 4 * w + 3 * gap, 3), dtype=np.float32)
    for i, p in enumerate(panels):
        out[:, i * (w + gap):i * (w + gap) + w] = p
    tmp = a.out + ".tmp.png"
    gibench.write(tmp, out, exposure=a.exposure)
    os.replace(tmp, a.out)
    print(f"reference: {os.path.relpath(refs[0], a.dir)}")
    for name, r, img in (("low", low[0], imgs[0]), ("high", high[0], imgs[1])):
        p = params(r["params"])
        mse = float(np.mean((img - ref) ** 2))
        print(f"{name}: {r['run']} (l={p.get('l')}, perturbed={p.get('perturbed', '0')}): MSE {mse:.3g}")
    print(f"wrote {a.out}: {4 * w + 3 * gap}x{h}, panels reference | low | high | |low - reference| x {a.gain:g}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
