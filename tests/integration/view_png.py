#!/usr/bin/env python3
"""Pixel checks of gibench view's window shots for integration.view_panels
(stdlib only): a PNG decoder for gi's 8-bit RGB/RGBA PNGs and three checks,
each printing one line and exiting 1 when it fails.

  view_png.py same A.png B.png                 A equals B (max |d| <= 1/255)
  view_png.py zoom A.png B.png Z PX PY         A(x, y) = B(PX + x / Z, PY + y / Z)
  view_png.py split A.png L.png R.png X0 X1    A = L left of column X0, A = R right of X1
  view_png.py close X Y RTOL                   two numbers within relative RTOL
"""
import struct
import sys
import zlib


def read_png(path):
    data = open(path, "rb").read()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        sys.exit(f"{path}: not a PNG")
    pos, idat = 8, b""
    while pos < len(data):
        ln, tag = struct.unpack_from(">I4s", data, pos)
        body = data[pos + 8:pos + 8 + ln]
        if tag == b"IHDR":
            w, h, depth, ctype = struct.unpack_from(">IIBB", body)
            if depth != 8 or ctype not in (2, 6):
                sys.exit(f"{path}: not 8-bit RGB or RGBA")
            bpp = 3 if ctype == 2 else 4
        elif tag == b"IDAT":
            idat += body
        pos += 12 + ln
    raw, stride, rows, prev = zlib.decompress(idat), w * bpp, [], bytearray(w * bpp)
    for y in range(h):
        f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - bpp] if i >= bpp else 0
            b, c = prev[i], prev[i - bpp] if i >= bpp else 0
            if f == 1:
                line[i] = (line[i] + a) & 255
            elif f == 2:
                line[i] = (line[i] + b) & 255
            elif f == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append([tuple(line[x * bpp:x * bpp + 3]) for x in range(w)])
        prev = line
    return w, h, rows


def diff(p, q):
    return max(abs(a - b) for a, b in zip(p, q))


def main():
    cmd, args = sys.argv[1], sys.argv[2:]
    if cmd == "close":
        x, y, rtol = (float(s) for s in args)
        ok = abs(x - y) <= rtol * max(abs(x), abs(y))
        print(f"close: {x!r} and {y!r}: {'within' if ok else 'not within'} relative {rtol}")
        sys.exit(0 if ok else 1)
    a = read_png(args[0])
    if cmd == "same":
        b = read_png(args[1])
        if a[:2] != b[:2]:
            sys.exit(f"same: sizes {a[:2]} and {b[:2]} differ")
        d = max(diff(a[2][y][x], b[2][y][x]) for y in range(a[1]) for x in range(a[0]))
        print(f"same: max |d| {d}/255")
        sys.exit(0 if d <= 1 else 1)
    if cmd == "zoom":
        b = read_png(args[1])
        z, px, py = float(args[2]), float(args[3]), float(args[4])
        d, d_unzoomed = 0, 0
        for y in range(a[1]):
            for x in range(a[0]):
                bx, by = int(px + (x + 0.5) / z), int(py + (y + 0.5) / z)
                d = max(d, diff(a[2][y][x], b[2][by][bx]))
                d_unzoomed = max(d_unzoomed, diff(a[2][y][x], b[2][y][x]))
        print(f"zoom: max |d| {d}/255 against the zoomed batch image, {d_unzoomed}/255 unzoomed")
        sys.exit(0 if d <= 1 and d_unzoomed > 16 else 1)
    if cmd == "split":
        left, right = read_png(args[1]), read_png(args[2])
        x0, x1 = int(args[3]), int(args[4])
        dl = max(diff(a[2][y][x], left[2][y][x]) for y in range(a[1]) for x in range(x0))
        dr = max(diff(a[2][y][x], right[2][y][x]) for y in range(a[1]) for x in range(x1, a[0]))
        # the right side must not also be the left method's image
        dlr = max(diff(a[2][y][x], left[2][y][x]) for y in range(a[1]) for x in range(x1, a[0]))
        print(f"split: left max |d| {dl}/255, right {dr}/255; right against the left method {dlr}/255")
        sys.exit(0 if dl <= 1 and dr <= 1 and dlr > 16 else 1)
    sys.exit(f"unknown check {cmd}")


if __name__ == "__main__":
    main()
