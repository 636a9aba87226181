#!/usr/bin/env python3
"""Test data of FLIP against NVIDIA's reference implementation (PROVENANCE.md).

Writes the LDR image pairs of tests/data/flip/: each image as an 8-bit sRGB
PNG (what NVIDIA's tool reads for LDR-FLIP) and as a PFM of the same pixels
decoded to linear RGB (what gibench reads: its FLIP tonemaps at exposure 0,
clamping and sRGB-encoding, which gives the PNG's values back). With
--flip FLIP_TOOL it also runs NVIDIA's tool on every pair (and on the HDR
pair render_*.exr, HDR-FLIP) and writes reference.json with the means, and
the per-pixel LDR-FLIP map of one pair as a PFM. Stdlib only.

usage: make_flip_data.py OUT_DIR [--flip PATH/TO/flip]
"""
import json
import math
import os
import re
import struct
import subprocess
import sys
import zlib

W = H = 32


def srgb_decode(y):
    return y / 12.92 if y <= 0.04045 else ((y + 0.055) / 1.055) ** 2.4


def lcg(seed):
    state = seed
    while True:
        state = (state * 6364136223846793005 + 1442695040888963407) % (1 << 64)
        yield (state >> 33) / float(1 << 31)


def clamp8(v):
    return max(0, min(255, int(round(v))))


def pair_noise():
    rnd = lcg(7)
    ref, test = [], []
    for y in range(H):
        for x in range(W):
            c = (40 + 180 * x / (W - 1), 60 + 150 * y / (H - 1), 200 - 120 * (x + y) / (2 * W - 2))
            ref.append(tuple(clamp8(v) for v in c))
            test.append(tuple(clamp8(v + 60 * (next(rnd) - 0.5)) for v in c))
    return ref, test


def pair_edges():
    ref, test = [], []
    for y in range(H):
        for x in range(W):
            inside = (x - 15.5) ** 2 + (y - 15.5) ** 2 < 81
            stripe = (x // 4) % 2
            ref.append((220, 40, 30) if inside else ((240, 240, 240) if stripe else (20, 20, 60)))
            inside_t = (x - 16.5) ** 2 + (y - 15.5) ** 2 < 81  # one pixel right
            stripe_t = ((x + 1) // 4) % 2
            test.append((200, 70, 30) if inside_t else ((240, 240, 240) if stripe_t else (20, 20, 60)))
    return ref, test


def pair_dark():
    rnd = lcg(11)
    ref, test = [], []
    for y in range(H):
        for x in range(W):
            v = 8 + 24 * math.sin(x * 0.4) * math.sin(y * 0.3) ** 2
            ref.append((clamp8(v), clamp8(v * 0.8), clamp8(v * 1.3)))
            n = 6 * (next(rnd) - 0.5)
            test.append((clamp8(v + n + 3), clamp8(v * 0.8 + n), clamp8(v * 1.3 + n)))
    return ref, test


def write_png(path, px):
    raw = b"".join(b"\x00" + bytes(v for p in px[y * W:(y + 1) * W] for v in p) for y in range(H))
    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data))
    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", W, H, 8, 2, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b"")
    with open(path, "wb") as f:
        f.write(png)


def write_pfm(path, rows, w, h):
    """rows: h rows (top first) of w (r, g, b) floats; PFM stores bottom first."""
    with open(path, "wb") as f:
        f.write(b"PF\n%d %d\n-1.0\n" % (w, h))
        for row in reversed(rows):
            f.write(b"".join(struct.pack("<3f", *p) for p in row))


def read_png_gray(path):
    """The first channel of an 8-bit PNG (NVIDIA's grey error map), rows top first."""
    data = open(path, "rb").read()
    pos, idat, w = 8, b"", 0
    while pos < len(data):
        n, tag = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + n]
        if tag == b"IHDR":
            w, h, depth, ctype = struct.unpack(">IIBB", body[:10])
            chans = {0: 1, 2: 3, 4: 2, 6: 4}[ctype]
            assert depth == 8
        elif tag == b"IDAT":
            idat += body
        pos += 12 + n
    raw, stride, rows, prev = zlib.decompress(idat), w * chans, [], bytearray(w * chans)
    for y in range(h):
        ft, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - chans] if i >= chans else 0
            b, c = prev[i], prev[i - chans] if i >= chans else 0
            if ft == 1:
                line[i] = (line[i] + a) & 255
            elif ft == 2:
                line[i] = (line[i] + b) & 255
            elif ft == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif ft == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append([line[x * chans] for x in range(w)])
        prev = line
    return rows


def run_flip(tool, ref, test, extra, out_dir, basename):
    cmd = [tool, "-r", ref, "-t", test, "-v", "2", "-nm", "-nexm", "-d", out_dir, "-b", basename] + extra
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    mean = float(re.search(r"Mean:\s*([0-9.eE+-]+)", out).group(1))
    return cmd, out, mean


def main():
    out = sys.argv[1]
    tool = sys.argv[sys.argv.index("--flip") + 1] if "--flip" in sys.argv else None
    os.makedirs(out, exist_ok=True)
    pairs = {"noise": pair_noise(), "edges": pair_edges(), "dark": pair_dark()}
    for name, (ref, test) in pairs.items():
        for role, px in (("ref", ref), ("test", test)):
            write_png(os.path.join(out, f"{name}_{role}.png"), px)
            rows = [[tuple(srgb_decode(v / 255.0) for v in px[y * W + x]) for x in range(W)] for y in range(H)]
            write_pfm(os.path.join(out, f"{name}_{role}.pfm"), rows, W, H)
    if not tool:
        return
    result = {"tool": "NVIDIA FLIP v1.6 (flip, C++ CPU tool)", "ppd": "default (67.0206...)", "ldr": {}, "hdr": {}}
    tmp = os.path.join(out, "tmp")
    os.makedirs(tmp, exist_ok=True)
    for name in pairs:
        cmd, text, mean = run_flip(tool, os.path.join(out, f"{name}_ref.png"), os.path.join(out, f"{name}_test.png"),
                                   [], tmp, name)
        result["ldr"][name] = {"mean": mean, "command": " ".join(os.path.basename(c) if c.endswith(".png") else c
                                                                 for c in cmd[1:])}
        if name == "edges":
            grey = read_png_gray(os.path.join(tmp, name + ".png"))
            write_pfm(os.path.join(out, "edges_flip_map.pfm"), [[(v / 255.0,) * 3 for v in row] for row in grey],
                      len(grey[0]), len(grey))
    hdr_ref, hdr_test = os.path.join(out, "render_ref.exr"), os.path.join(out, "render_test.exr")
    if os.path.exists(hdr_ref):
        cmd, text, mean = run_flip(tool, hdr_ref, hdr_test, [], tmp, "render")
        exposures = re.findall(r"(Start exposure|Stop exposure|Number of exposures):\s*([0-9.eE+-]+)", text)
        result["hdr"]["render"] = {"mean": mean, "command": "flip -r render_ref.exr -t render_test.exr",
                                   "exposures": dict(exposures)}
    for f in os.listdir(tmp):
        os.remove(os.path.join(tmp, f))
    os.rmdir(tmp)
    with open(os.path.join(out, "reference.json"), "w") as f:
        json.dump(result, f, indent=1, sort_keys=True)
        f.write("\n")


if __name__ == "__main__":
    main()
