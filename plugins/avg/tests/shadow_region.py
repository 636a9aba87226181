#!/usr/bin/env python3
"""Scores a render's point-light shadow against the reference (avg_point.cmake).

    shadow_region.py TEST.pfm REF.pfm DIRECT.pfm

The shadow region S is where the unshadowed `direct` image is lit (above
0.02) and the reference holds less than a tenth of it: the block hides the
light there. The rest L is compared as a whole. For an image x:
    leak(x) = mean over S of x / mean over S of direct   (black: 0, direct: 1)
    lit(x)  = mean over L of |x - ref| / mean over L of ref  (black: 1, direct: ~0)
    score(x) = max(leak, lit)
so both trivial answers score about 1. Prints the three scores; exits 1 when
the test's score exceeds 1/4 of the better trivial answer's, 2 on a bad
set-up (unreadable files, sizes that differ, fewer than 20 shadow pixels).
"""
import struct
import sys


def read_pfm(path):
    with open(path, "rb") as f:
        kind = f.readline().strip()
        w, h = (int(t) for t in f.readline().split())
        scale = float(f.readline())
        n = 3 if kind == b"PF" else 1 if kind == b"Pf" else 0
        if n == 0:
            raise ValueError("%s: not a PFM file" % path)
        data = f.read(4 * w * h * n)
    v = struct.unpack(("<" if scale < 0 else ">") + "%df" % (w * h * n), data)
    return w, h, [sum(v[n * i:n * i + n]) / n for i in range(w * h)]


def main():
    if len(sys.argv) != 4:
        print("usage: shadow_region.py TEST.pfm REF.pfm DIRECT.pfm", file=sys.stderr)
        return 2
    try:
        imgs = [read_pfm(p) for p in sys.argv[1:]]
    except (OSError, ValueError, struct.error) as e:
        print("shadow_region: %s" % e, file=sys.stderr)
        return 2
    if len({(w, h) for w, h, _ in imgs}) != 1:
        print("shadow_region: the images differ in size", file=sys.stderr)
        return 2
    x, ref, direct = (v for _, _, v in imgs)
    shadow = [i for i in range(len(ref)) if direct[i] > 0.02 and ref[i] < 0.1 * direct[i]]
    lit = [i for i in range(len(ref)) if i not in set(shadow)]
    if len(shadow) < 20 or not lit:
        print("shadow_region: %d shadow pixels (at least 20 needed)" % len(shadow), file=sys.stderr)
        return 2
    d_s = sum(direct[i] for i in shadow)
    r_l = sum(ref[i] for i in lit)

    def score(img):
        leak = sum(img[i] for i in shadow) / d_s
        err = sum(abs(img[i] - ref[i]) for i in lit) / r_l
        return max(leak, err), leak, err

    s_test, s_black, s_direct = score(x), score([0.0] * len(x)), score(direct)
    for name, s in (("test", s_test), ("black", s_black), ("direct", s_direct)):
        print("%-6s score %.4f (shadow leak %.4f, lit error %.4f)" % (name, s[0], s[1], s[2]))
    best = min(s_black[0], s_direct[0])
    print("%d shadow pixels; limit %.4f = 1/4 of the better trivial score" % (len(shadow), best / 4))
    return 0 if s_test[0] <= best / 4 else 1


if __name__ == "__main__":
    sys.exit(main())
