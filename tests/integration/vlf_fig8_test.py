"""plugins/vlf/fig8.py on a synthetic study folder (ctest python.vlf_fig8).

Writes a runs.csv with a low (perturbed = 0) and a high (perturbed = 4) run
of the label fig8_paper, their image.exr and an 8-bounce reference made
with gibench's own writer, runs the script and checks: the PNG has four
panels of the reference's size with the gaps, the printed MSE of each run
is the one numpy computes from the same images, the difference panel is
|low - reference| x gain (the script's third panel equals the high image
and the fourth is not the low image itself), and a folder without the high
run, or without the reference, is refused with exit 1 and one line.

Usage: PYTHONPATH=build/release/python /usr/bin/python3 vlf_fig8_test.py ROOT OUT
"""

import csv
import os
import re
import shutil
import subprocess
import sys

import numpy as np

import gibench


def write_study(d, with_high=True, with_ref=True):
    shutil.rmtree(d, ignore_errors=True)
    os.makedirs(os.path.join(d, "references"))
    h, w = 12, 16
    y, x = np.mgrid[0:h, 0:w].astype(np.float32)
    ref = np.stack([x / 32, y / 32, (x + y) / 64], axis=2).astype(np.float32) + 0.25
    low = ref.copy()
    low[:, : w // 2, 0] += 0.5          # a wrong left half: MSE 0.25 / 3 / 2
    high = ref + 0.125                    # uniform offset: MSE 0.125²
    if with_ref:
        gibench.write(os.path.join(d, "references", "cornell_glossy_b8_64spp_center.exr"), ref)
        gibench.write(os.path.join(d, "references", "cornell_glossy_b64_64spp_center.exr"), ref * 2)
    runs = [("lowrun", "l=16,perturbed=0", low)]
    if with_high:
        runs.append(("highrun", "l=16,perturbed=4", high))
    with open(os.path.join(d, "runs.csv"), "w", newline="") as fh:
        wr = csv.writer(fh)
        wr.writerow(["run", "scene", "method", "params", "status", "label"])
        wr.writerow(["other", "scenes/cornell_glossy.gltf", "vlf", "l=8,perturbed=0", "ok", "fig8"])
        for run, params, img in runs:
            os.makedirs(os.path.join(d, "runs", run))
            gibench.write(os.path.join(d, "runs", run, "image.exr"), img)
            wr.writerow([run, "scenes/cornell_glossy.gltf", "vlf", params, "ok", "fig8_paper"])
    return ref, low, high


def run(root, d, out):
    return subprocess.run([sys.executable, os.path.join(root, "plugins", "vlf", "fig8.py"), d, "--out", out,
                           "--gain", "2"], capture_output=True, text=True)


def main():
    root, out = sys.argv[1], sys.argv[2]
    fails = []
    d = os.path.join(out, "study")
    ref, low, high = write_study(d)
    png = os.path.join(out, "fig8.png")
    r = run(root, d, png)
    if r.returncode != 0:
        print("FAIL: fig8.py exit %d: %s" % (r.returncode, r.stderr.strip()))
        return 1
    got = dict(re.findall(r"^(low|high): \S+ .*MSE (\S+)$", r.stdout, re.M))
    for name, img in (("low", low), ("high", high)):
        want = float(np.mean((img - ref) ** 2))
        if name not in got or abs(float(got[name]) - want) > 2e-3 * want:
            fails.append("%s MSE %s, numpy %.4g" % (name, got.get(name), want))
    fig = gibench.read(png)
    h, w = ref.shape[:2]
    gap = max(1, w // 32)
    if fig.shape[:2] != (h, 4 * w + 3 * gap):
        fails.append("figure %s, want %d x %d" % (fig.shape[:2], h, 4 * w + 3 * gap))
    else:
        # The PNG is tonemapped (8-bit sRGB): compare the panels with each
        # other through the same writer, not with the linear images.
        tmp = os.path.join(out, "panel.png")
        for i, (name, img) in enumerate((("reference", ref), ("low", low), ("high", high),
                                         ("difference", np.abs(low - ref) * 2))):
            gibench.write(tmp, img)
            want = gibench.read(tmp)
            panel = fig[:, i * (w + gap):i * (w + gap) + w]
            if np.max(np.abs(panel - want)) > 1e-6:
                fails.append("panel %d is not the %s image" % (i, name))
        gibench.write(tmp, low)
        if np.max(np.abs(fig[:, 3 * (w + gap):] - gibench.read(tmp))) < 1e-3:
            fails.append("the difference panel is the low image")
    for kind, args in (("no high run", dict(with_high=False)), ("no reference", dict(with_ref=False))):
        write_study(d, **args)
        r = run(root, d, os.path.join(out, "bad.png"))
        if r.returncode != 1 or len(r.stderr.strip().splitlines()) != 1 or os.path.exists(os.path.join(out, "bad.png")):
            fails.append("%s: exit %d, stderr %r" % (kind, r.returncode, r.stderr))
    for f in fails:
        print("FAIL: " + f)
    if not fails:
        print("ok: fig8.py panels, MSE and refusals")
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())
