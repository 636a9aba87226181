#!/usr/bin/env python3
"""Temporal flicker of implicit_vis under deformation (issue 11; Dong et al.
2007, Sec. 5.1: "temporal aliasing when objects undergo deformations").

The deforming Cornell box (scenes/cornell_deform.gltf, its short block
morphing over 4 s) at frames t_i = T0 + i / FPS, i = 0 .. FRAMES - 1:

  M_i  implicit_vis (`gibench render --time t_i`; the method keeps no state
       from frame to frame except the hierarchy, built at the rest pose, so
       a render at t_i is the animation's frame at t_i);
  A_i  the path-traced reference at t_i (seed 1), and
  B_i  a second one with another seed (seed 2), same samples.

Per pair of successive frames, on luminance, every value divided by the
mean luminance of the A frames:

  change      mean |X_{i+1} - X_i| for X = M, A: how much the image moves;
  flicker     mean |(M_{i+1} - M_i) - (A_{i+1} - A_i)|: the part of the
              method's frame-to-frame change that the reference does not
              have (its own noise in A included);
  ref noise   mean |(B_{i+1} - B_i) - (A_{i+1} - A_i)|: how much two
              references' frame-to-frame changes disagree: the reference's
              own frame-to-frame noise, the floor below which flicker cannot
              be told from the reference's noise;
  ratio       flicker / ref noise (about 1 or less: not measurable at this
              reference's noise; well above 1: flicker);
  static      mean |M_i - A_i| (the still error, which does not flicker;
              for the frozen image, implicit_vis's frame 0 against A_i);
  still px    mean |X_{i+1} - X_i| over the pixels whose reference (mean of
              A and B) varies by less than 2 % of the mean luminance over
              the whole sequence: change where nothing changes, i.e. flicker
              away from the deforming object, for X = M and for the
              references themselves (their noise).

Two trivial answers beside it: a frozen image (M_i = M_0 for every i: no
change at all, so its flicker is the reference's own change), and a second
method (default the unshadowed `direct` plugin, --other) measured the same
way.

Writes OUT/flicker.csv (one row per pair and method) and prints a Markdown
table. Stdlib only; images go through .pfm.

Usage: plugins/implicit_vis/flicker.py OUT [--gibench build/release/bin/gibench]
       [--frames 9] [--fps 10] [--t0 0] [--size 64] [--spp 256]
       [--param k=v]... [--other direct]
"""

import argparse
import csv
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
from gi_run import luminance, read_pfm, run  # noqa: E402


def read_luminance(path):
    """The luminance of a PFM image, or its one channel."""
    _, _, c, data = read_pfm(path)
    return list(data) if c == 1 else luminance(data)


def mean_abs(xs):
    return sum(abs(x) for x in xs) / len(xs)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out")
    ap.add_argument("--gibench", default=os.environ.get("GIB", "build/release/bin/gibench"))
    ap.add_argument("--scene", default="scenes/cornell_deform.gltf")
    ap.add_argument("--frames", type=int, default=9)
    ap.add_argument("--fps", type=float, default=10.0)
    ap.add_argument("--t0", type=float, default=0.0)
    ap.add_argument("--size", type=int, default=64)
    ap.add_argument("--spp", type=int, default=256)
    ap.add_argument("--bounces", type=int, default=4, help="reference bounces (implicit_vis: direct + 3)")
    ap.add_argument("--param", action="append", default=[], help="implicit_vis parameter k=v")
    ap.add_argument("--other", default="direct", help="a second method measured the same way ('' for none)")
    a = ap.parse_args()
    if a.frames < 2:
        raise SystemExit("--frames must be at least 2")
    os.makedirs(a.out, exist_ok=True)
    size = "%dx%d" % (a.size, a.size)
    times = [a.t0 + i / a.fps for i in range(a.frames)]
    methods = [("implicit_vis", [x for p in a.param for x in ("--param", p)])]
    if a.other:
        methods.append((a.other, ["--frames", "4"]))
    img = {}
    for i, t in enumerate(times):
        for seed in (1, 2):
            p = os.path.join(a.out, "ref_s%d_%02d.pfm" % (seed, i))
            if not os.path.exists(p):
                run([a.gibench, "-q", "reference", "--scene", a.scene, "--size", size, "--spp", str(a.spp),
                     "--max-bounces", str(a.bounces), "--seed", str(seed), "--time-of-scene", "%.6g" % t,
                     "--out", p])
            img[("ref%d" % seed, i)] = read_luminance(p)
        for m, extra in methods:
            p = os.path.join(a.out, "%s_%02d.pfm" % (m, i))
            run([a.gibench, "-q", "render", "--scene", a.scene, "--method", m, "--size", size, "--time", "%.6g" % t,
                 "--out", p] + extra)
            img[(m, i)] = read_luminance(p)
    norm = sum(sum(img[("ref1", i)]) / len(img[("ref1", i)]) for i in range(a.frames)) / a.frames
    npx = len(img[("ref1", 0)])
    seq = [[0.5 * (img[("ref1", i)][p] + img[("ref2", i)][p]) for i in range(a.frames)] for p in range(npx)]
    still = [p for p in range(npx) if max(seq[p]) - min(seq[p]) < 0.02 * norm]

    def still_change(key, i):
        X0, X1 = img[(key, i)], img[(key, i + 1)]
        return sum(abs(X1[p] - X0[p]) for p in still) / max(1, len(still)) / norm

    rows = []
    for i in range(a.frames - 1):
        A0, A1, B0, B1 = img[("ref1", i)], img[("ref1", i + 1)], img[("ref2", i)], img[("ref2", i + 1)]
        dA = [y - x for x, y in zip(A0, A1)]
        dB = [y - x for x, y in zip(B0, B1)]
        noise = mean_abs([b - r for b, r in zip(dB, dA)]) / norm
        rows.append({
            "method": "frozen image", "t0": "%.4g" % times[i], "t1": "%.4g" % times[i + 1],
            "change_method": 0.0, "change_ref": mean_abs(dA) / norm, "flicker": mean_abs(dA) / norm,
            "ref_noise": noise, "static_error": mean_abs([x - y for x, y in zip(img[("implicit_vis", 0)], A0)]) / norm,
            "still_px_change": 0.0, "still_px_ref": still_change("ref1", i),
        })
        for m, _ in methods:
            M0, M1 = img[(m, i)], img[(m, i + 1)]
            dM = [y - x for x, y in zip(M0, M1)]
            rows.append({
                "method": m, "t0": "%.4g" % times[i], "t1": "%.4g" % times[i + 1],
                "change_method": mean_abs(dM) / norm, "change_ref": mean_abs(dA) / norm,
                "flicker": mean_abs([x - y for x, y in zip(dM, dA)]) / norm, "ref_noise": noise,
                "static_error": mean_abs([x - y for x, y in zip(M0, A0)]) / norm,
                "still_px_change": still_change(m, i), "still_px_ref": still_change("ref1", i),
            })
    with open(os.path.join(a.out, "flicker.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        for r in rows:
            w.writerow({k: ("%.5g" % v if isinstance(v, float) else v) for k, v in r.items()})
    print("Scene %s, %s, frames t = %s s, reference %d spp %d bounces (seeds 1 and 2); values relative to the "
          "reference's mean luminance %.4g; still pixels: %d of %d.\n" % (
        a.scene, size, ", ".join("%.3g" % t for t in times), a.spp, a.bounces, norm, len(still), npx))
    print("| method | t | change (method) | change (reference) | flicker | reference noise | ratio | still error "
          "| change on still px (method / reference) |")
    print("|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print("| %s | %s → %s | %.4f | %.4f | %.4f | %.4f | %.2f | %.4f | %.4f / %.4f |" % (
            r["method"], r["t0"], r["t1"], r["change_method"], r["change_ref"], r["flicker"], r["ref_noise"],
            r["flicker"] / r["ref_noise"] if r["ref_noise"] > 0 else float("nan"), r["static_error"],
            r["still_px_change"], r["still_px_ref"]))
    for m in [x for x, _ in methods] + ["frozen image"]:
        rs = [r for r in rows if r["method"] == m]
        fl = sum(r["flicker"] for r in rs) / len(rs)
        nz = sum(r["ref_noise"] for r in rs) / len(rs)
        ch = sum(r["change_method"] for r in rs) / len(rs)
        cr = sum(r["change_ref"] for r in rs) / len(rs)
        print("| **%s, mean** | | %.4f | %.4f | %.4f | %.4f | %.2f | %.4f | %.4f / %.4f |" % (
            m, ch, cr, fl, nz, fl / nz if nz > 0 else float("nan"), sum(r["static_error"] for r in rs) / len(rs),
            sum(r["still_px_change"] for r in rs) / len(rs), sum(r["still_px_ref"] for r in rs) / len(rs)))


if __name__ == "__main__":
    main()
