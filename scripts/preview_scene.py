#!/usr/bin/env python3
"""Quick look at a gibench scene: a tiny z-buffer rasterizer (stdlib only).

Reads a .gltf/.glb the way the gibench conventions describe (node TRS,
LINEAR animation, perspective camera looking down local -Z, baseColorFactor,
emissiveFactor x KHR_materials_emissive_strength) and writes a PNG shaded with
a fixed key light plus ambient, emitters shown at their (clipped) radiance.
Not a renderer for results: only for checking framing, orientation, winding
(back faces are drawn magenta) and animation.

Usage: preview_scene.py SCENE OUT.png [--camera N] [--time T] [--size PX]
"""

import argparse
import json
import math
import os
import struct
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from gltf_writer import png_rgb8, quat_rotate, sub, dot, cross, norm  # noqa: E402

CT = {5126: ("f", 4), 5125: ("I", 4), 5123: ("H", 2), 5121: ("B", 1)}
NC = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}


def load(path):
    data = open(path, "rb").read()
    bins = []
    if data[:4] == b"glTF":
        jl = struct.unpack_from("<I", data, 12)[0]
        doc = json.loads(data[20:20 + jl])
        off = 20 + jl
        bl = struct.unpack_from("<I", data, off)[0]
        bins.append(data[off + 8:off + 8 + bl])
    else:
        doc = json.loads(data)
        for b in doc["buffers"]:
            bins.append(open(os.path.join(os.path.dirname(path), b["uri"]), "rb").read())
    return doc, bins


def accessor(doc, bins, i):
    a = doc["accessors"][i]
    v = doc["bufferViews"][a["bufferView"]]
    fmt, size = CT[a["componentType"]]
    n = NC[a["type"]]
    off = v.get("byteOffset", 0) + a.get("byteOffset", 0)
    vals = struct.unpack_from("<%d%s" % (a["count"] * n, fmt), bins[v["buffer"]], off)
    if n == 1:
        return list(vals)
    return [vals[k:k + n] for k in range(0, len(vals), n)]


def slerp(a, b, t):
    d = sum(x * y for x, y in zip(a, b))
    if d < 0:
        b, d = [-x for x in b], -d
    if d > 0.9995:
        r = [x + (y - x) * t for x, y in zip(a, b)]
    else:
        th = math.acos(d)
        s = math.sin(th)
        r = [(math.sin((1 - t) * th) * x + math.sin(t * th) * y) / s for x, y in zip(a, b)]
    l = math.sqrt(sum(x * x for x in r))
    return [x / l for x in r]


def animate(doc, bins, time):
    nodes = doc["nodes"]
    for an in doc.get("animations", []):
        for ch in an["channels"]:
            s = an["samplers"][ch["sampler"]]
            ts = accessor(doc, bins, s["input"])
            vs = accessor(doc, bins, s["output"])
            t = min(max(time, ts[0]), ts[-1])
            k = 0
            while k + 1 < len(ts) - 1 and ts[k + 1] <= t:
                k += 1
            u = 0.0 if ts[k + 1] == ts[k] else (t - ts[k]) / (ts[k + 1] - ts[k])
            u = min(max(u, 0.0), 1.0)
            path = ch["target"]["path"]
            if path == "rotation":
                val = slerp(vs[k], vs[k + 1], u)
            else:
                val = [x + (y - x) * u for x, y in zip(vs[k], vs[k + 1])]
            nodes[ch["target"]["node"]][path] = list(val)


def world_nodes(doc):
    """Yields (node, fn(point)->world point, fn(normal)->world normal); TRS only."""
    out = []

    def visit(i, chain):
        nd = doc["nodes"][i]
        chain = chain + [nd]

        def xf(p, chain=chain):
            for n in reversed(chain):
                s = n.get("scale", [1, 1, 1])
                p = (p[0] * s[0], p[1] * s[1], p[2] * s[2])
                p = quat_rotate(n.get("rotation", [0, 0, 0, 1]), p)
                t = n.get("translation", [0, 0, 0])
                p = (p[0] + t[0], p[1] + t[1], p[2] + t[2])
            return p

        def xn(v, chain=chain):
            for n in reversed(chain):
                v = quat_rotate(n.get("rotation", [0, 0, 0, 1]), v)
            return v
        out.append((nd, xf, xn))
        for c in nd.get("children", []):
            visit(c, chain)
    for i in doc["scenes"][doc.get("scene", 0)]["nodes"]:
        visit(i, [])
    return out


def decode_png_rgb8(data):
    import zlib
    pos, w, h, idat = 8, 0, 0, b""
    while pos < len(data):
        ln, tag = struct.unpack_from(">I4s", data, pos)
        body = data[pos + 8:pos + 8 + ln]
        if tag == b"IHDR":
            w, h, depth, ctype = struct.unpack_from(">IIBB", body)
            if depth != 8 or ctype != 2:
                return None
        elif tag == b"IDAT":
            idat += body
        pos += 12 + ln
    raw = zlib.decompress(idat)
    stride = 3 * w
    rows = []
    for y in range(h):
        if raw[y * (stride + 1)] != 0:
            return None
        rows.append(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
    return w, h, rows


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("scene")
    ap.add_argument("out")
    ap.add_argument("--camera", type=int, default=0, help="index into the scene's camera nodes")
    ap.add_argument("--time", type=float, default=None)
    ap.add_argument("--size", type=int, default=256)
    ap.add_argument("--cull", action="store_true", help="skip back faces instead of magenta")
    ap.add_argument("--eye", help="override the camera: x,y,z (with --target)")
    ap.add_argument("--target", help="x,y,z looked at")
    a = ap.parse_args()
    doc, bins = load(a.scene)
    if a.time is not None:
        animate(doc, bins, a.time)
    nodes = world_nodes(doc)
    camn = [(nd, xf, xn) for nd, xf, xn in nodes if "camera" in nd][a.camera]
    cam = doc["cameras"][camn[0]["camera"]]["perspective"]
    eye = camn[1]((0.0, 0.0, 0.0))
    fwd = norm(camn[2]((0.0, 0.0, -1.0)))
    up = norm(camn[2]((0.0, 1.0, 0.0)))
    if a.eye:
        eye = tuple(float(v) for v in a.eye.split(","))
        fwd = norm(sub(tuple(float(v) for v in a.target.split(",")), eye))
        helper = (0.0, 1.0, 0.0) if abs(fwd[1]) < 0.99 else (0.0, 0.0, -1.0)
        up = norm(cross(cross(fwd, helper), fwd))
    right = cross(fwd, up)
    W = H = a.size
    f = 1.0 / math.tan(cam["yfov"] / 2)
    aspect = cam.get("aspectRatio", 1.0)
    zbuf = [[math.inf] * W for _ in range(H)]
    has_env = "environment" in (doc["scenes"][0].get("extras", {}).get("gibench", {}))
    bg = (0.35, 0.45, 0.6) if has_env else (0.0, 0.0, 0.0)
    img = [[bg] * W for _ in range(H)]
    key = norm((0.4, 1.0, 0.3))
    textures = {}
    for nd, xf, xn in nodes:
        if "mesh" not in nd:
            continue
        for prim in doc["meshes"][nd["mesh"]]["primitives"]:
            mat = doc["materials"][prim["material"]]
            pbr = mat["pbrMetallicRoughness"]
            albedo = pbr["baseColorFactor"][:3]
            tex = None
            if "baseColorTexture" in pbr:
                ti = pbr["baseColorTexture"]["index"]
                if ti not in textures:
                    im = doc["images"][doc["textures"][ti]["source"]]
                    v = doc["bufferViews"][im["bufferView"]]
                    o = v.get("byteOffset", 0)
                    textures[ti] = decode_png_rgb8(bins[v["buffer"]][o:o + v["byteLength"]])
                tex = textures[ti]
            strength = mat.get("extensions", {}).get("KHR_materials_emissive_strength", {}) \
                .get("emissiveStrength", 1.0)
            emis = [e * strength for e in mat.get("emissiveFactor", [0, 0, 0])]
            mirror = mat.get("extras", {}).get("gibench", {}).get("mirror", False)
            P = [xf(p) for p in accessor(doc, bins, prim["attributes"]["POSITION"])]
            N = [xn(n) for n in accessor(doc, bins, prim["attributes"]["NORMAL"])]
            UV = accessor(doc, bins, prim["attributes"]["TEXCOORD_0"]) \
                if tex and "TEXCOORD_0" in prim["attributes"] else None
            idx = accessor(doc, bins, prim["indices"])
            # camera space
            C = []
            for p in P:
                d = sub(p, eye)
                C.append((dot(d, right), dot(d, up), dot(d, fwd)))
            for t in range(0, len(idx), 3):
                i0, i1, i2 = idx[t:t + 3]
                c0, c1, c2 = C[i0], C[i1], C[i2]
                if min(c0[2], c1[2], c2[2]) < 1e-3:
                    continue
                sx = [(W / 2) * (1 + f / aspect * c[0] / c[2]) for c in (c0, c1, c2)]
                sy = [(H / 2) * (1 - f * c[1] / c[2]) for c in (c0, c1, c2)]
                area = (sx[1] - sx[0]) * (sy[2] - sy[0]) - (sx[2] - sx[0]) * (sy[1] - sy[0])
                if area == 0:
                    continue
                back = area > 0   # counter-clockwise on screen (y down) => front
                if back and a.cull:
                    continue
                x0, x1 = max(0, int(min(sx))), min(W - 1, int(max(sx)) + 1)
                y0, y1 = max(0, int(min(sy))), min(H - 1, int(max(sy)) + 1)
                gn = norm(cross(sub(P[i1], P[i0]), sub(P[i2], P[i0])))
                for y in range(y0, y1 + 1):
                    py = y + 0.5
                    for x in range(x0, x1 + 1):
                        px = x + 0.5
                        w0 = ((sx[1] - px) * (sy[2] - py) - (sx[2] - px) * (sy[1] - py)) / area
                        w1 = ((sx[2] - px) * (sy[0] - py) - (sx[0] - px) * (sy[2] - py)) / area
                        w2 = 1 - w0 - w1
                        if w0 < 0 or w1 < 0 or w2 < 0:
                            continue
                        # perspective-correct depth
                        iz = w0 / c0[2] + w1 / c1[2] + w2 / c2[2]
                        z = 1 / iz
                        if z >= zbuf[y][x]:
                            continue
                        zbuf[y][x] = z
                        if back:
                            img[y][x] = (1.0, 0.0, 1.0)
                            continue
                        n = [(w0 * N[i0][k] / c0[2] + w1 * N[i1][k] / c1[2]
                              + w2 * N[i2][k] / c2[2]) * z for k in range(3)]
                        n = norm(n) if any(n) else gn
                        col = albedo
                        if UV:
                            u = (w0 * UV[i0][0] / c0[2] + w1 * UV[i1][0] / c1[2]
                                 + w2 * UV[i2][0] / c2[2]) * z
                            v = (w0 * UV[i0][1] / c0[2] + w1 * UV[i1][1] / c1[2]
                                 + w2 * UV[i2][1] / c2[2]) * z
                            tw, th, rows = tex
                            tx = int((u % 1.0) * tw) % tw
                            ty = int((v % 1.0) * th) % th
                            s = rows[ty][3 * tx:3 * tx + 3]
                            col = [albedo[k] * (s[k] / 255.0) ** 2.2 for k in range(3)]
                        if mirror:
                            col = (0.6, 0.7, 0.8)
                        shade = 0.25 + 0.75 * max(0.0, dot(n, key))
                        img[y][x] = tuple(min(1.0, col[k] * shade + emis[k] / 17.0)
                                          for k in range(3))

    def px(x, y):
        return tuple(int(255 * min(1.0, max(0.0, c)) ** (1 / 2.2) + 0.5) for c in img[y][x])
    with open(a.out, "wb") as fo:
        fo.write(png_rgb8(W, H, px))


if __name__ == "__main__":
    main()
