#!/usr/bin/env python3
"""Derives plugins/cssm_hrc/data/cornell_moving2.gltf (+ cornell_moving2.bin,
self-contained: the bytes of cornell_moving.bin and the box's) from
scenes/cornell_moving.gltf: the same moving Cornell box (its bunny loops
across the front of the floor) with a second moving rigid object, a
0.5 x 0.5 x 0.5 white box that loops over the back-left part of the floor
in 4 s, turning +90 degrees about +Y per second. cssm_hrc's test of two
moving objects (Ritschel et al. 2008 §3.3) uses it; it lives in
the plugin's data/, not scenes/, because every method's conformance run renders
every scene of scenes/. The path is checked
here: the box's footprint (its turned square) keeps more than 0.1 from the
walls, the tall block's footprint and the bunny's path band at every
1/100 s. Python 3 stdlib only.

Usage: plugins/cssm_hrc/data/make_cornell_moving2.py [OUTDIR]   (default: plugins/cssm_hrc/data/)
"""
import json
import math
import os
import struct
import sys

SIDE = 0.5
TIMES = [0.0, 1.0, 2.0, 3.0, 4.0]
PATH = [(0.9, 0.0, 3.3), (1.9, 0.0, 3.4), (1.8, 0.0, 4.6), (0.8, 0.0, 4.5), (0.9, 0.0, 3.3)]


def quat_y(deg):
    a = math.radians(deg) / 2
    return (0.0, math.sin(a), 0.0, math.cos(a))


def box_mesh(s):
    """24 vertices (flat normals), 12 triangles, outward, counter-clockwise."""
    h = s / 2
    faces = [((1, 0, 0), [(h, 0, -h), (h, s, -h), (h, s, h), (h, 0, h)]),
             ((-1, 0, 0), [(-h, 0, h), (-h, s, h), (-h, s, -h), (-h, 0, -h)]),
             ((0, 1, 0), [(-h, s, -h), (-h, s, h), (h, s, h), (h, s, -h)]),
             ((0, -1, 0), [(-h, 0, h), (-h, 0, -h), (h, 0, -h), (h, 0, h)]),
             ((0, 0, 1), [(h, 0, h), (h, s, h), (-h, s, h), (-h, 0, h)]),
             ((0, 0, -1), [(-h, 0, -h), (-h, s, -h), (h, s, -h), (h, 0, -h)])]
    pos, nor, idx = [], [], []
    for n, quad in faces:
        a, b, c = quad[0], quad[1], quad[2]
        u = [b[i] - a[i] for i in range(3)]
        v = [c[i] - a[i] for i in range(3)]
        cr = (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])
        if sum(cr[i] * n[i] for i in range(3)) < 0:
            quad = quad[::-1]
        base = len(pos)
        pos += quad
        nor += [n] * 4
        idx += [base, base + 1, base + 2, base, base + 2, base + 3]
    return pos, nor, idx


def footprint(t):
    k = min(int(t), len(PATH) - 2)
    u = t - k
    tr = [PATH[k][i] + (PATH[k + 1][i] - PATH[k][i]) * u for i in range(3)]
    a = math.radians(90.0 * t)
    h = SIDE / 2
    return [(tr[0] + x * math.cos(a) + z * math.sin(a), tr[2] - x * math.sin(a) + z * math.cos(a))
            for x, z in ((-h, -h), (h, -h), (h, h), (-h, h))]


def check_path(g):
    """Clearance from walls, the tall block's box and the bunny's band."""
    nodes = {n["name"]: n for n in g["nodes"]}
    acc = g["accessors"]
    tb = nodes["tall_block"]
    mesh = g["meshes"][tb["mesh"]]["primitives"][0]["attributes"]["POSITION"]
    lo = [acc[mesh]["min"][i] + tb["translation"][i] for i in range(3)]
    hi = [acc[mesh]["max"][i] + tb["translation"][i] for i in range(3)]
    bunny_zmax = 1.75 + 0.62  # the bunny's path reaches z 1.75, its footprint radius < 0.62
    clear = 1e9
    for s in range(401):
        for x, z in footprint(4.0 * s / 400):
            c = min(x - 0.0, 5.496 - x, 5.592 - z, z - bunny_zmax,
                    max(lo[0] - x, x - hi[0], lo[2] - z, z - hi[2]))
            clear = min(clear, c)
    assert clear > 0.1, "second moving object too close to something: %.3f" % clear
    return clear


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    scenes = os.path.join(here, "..", "..", "..", "scenes")
    out = sys.argv[1] if len(sys.argv) > 1 else here
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(scenes, "cornell_moving.gltf")) as f:
        g = json.load(f)
    assert len(g["buffers"]) == 1
    with open(os.path.join(scenes, g["buffers"][0]["uri"]), "rb") as f:
        original = f.read()
    clear = check_path(g)
    pos, nor, idx = box_mesh(SIDE)
    blob = bytearray(original)  # one buffer: the original's bytes, then the box's

    def view(data, target=None):
        while len(blob) % 4:
            blob.append(0)
        v = {"buffer": 0, "byteOffset": len(blob), "byteLength": len(data)}
        if target:
            v["target"] = target
        blob.extend(data)
        g["bufferViews"].append(v)
        return len(g["bufferViews"]) - 1

    def accessor(data, ctype, count, typ, target=None, **extra):
        a = {"bufferView": view(data, target), "componentType": ctype, "count": count, "type": typ}
        a.update(extra)
        g["accessors"].append(a)
        return len(g["accessors"]) - 1

    flat = lambda vs: [c for v in vs for c in v]
    p_acc = accessor(struct.pack("<%df" % (3 * len(pos)), *flat(pos)), 5126, len(pos), "VEC3", 34962,
                     min=[min(p[i] for p in pos) for i in range(3)], max=[max(p[i] for p in pos) for i in range(3)])
    n_acc = accessor(struct.pack("<%df" % (3 * len(nor)), *flat(nor)), 5126, len(nor), "VEC3", 34962)
    i_acc = accessor(struct.pack("<%dH" % len(idx), *idx), 5123, len(idx), "SCALAR", 34963)
    t_acc = accessor(struct.pack("<%df" % len(TIMES), *TIMES), 5126, len(TIMES), "SCALAR",
                     min=[TIMES[0]], max=[TIMES[-1]])
    tr_acc = accessor(struct.pack("<%df" % (3 * len(PATH)), *flat(PATH)), 5126, len(PATH), "VEC3")
    rots = [quat_y(90.0 * t) for t in TIMES]
    r_acc = accessor(struct.pack("<%df" % (4 * len(rots)), *flat(rots)), 5126, len(rots), "VEC4")
    g["meshes"].append({"name": "moving_box", "primitives": [
        {"attributes": {"POSITION": p_acc, "NORMAL": n_acc}, "indices": i_acc, "material": 0, "mode": 4}]})
    g["nodes"].append({"name": "moving_box", "mesh": len(g["meshes"]) - 1,
                       "translation": list(PATH[0])})
    node = len(g["nodes"]) - 1
    g["scenes"][0]["nodes"].append(node)
    g["scenes"][0]["name"] = "cornell_moving2"
    g["animations"].append({"name": "box_path", "channels": [
        {"sampler": 0, "target": {"node": node, "path": "translation"}},
        {"sampler": 1, "target": {"node": node, "path": "rotation"}}], "samplers": [
        {"input": t_acc, "interpolation": "LINEAR", "output": tr_acc},
        {"input": t_acc, "interpolation": "LINEAR", "output": r_acc}]})
    g["buffers"][0] = {"byteLength": len(blob), "uri": "cornell_moving2.bin"}
    g["asset"]["generator"] = "gibench plugins/cssm_hrc/data/make_cornell_moving2.py (from cornell_moving.gltf)"
    with open(os.path.join(out, "cornell_moving2.bin"), "wb") as f:
        f.write(blob)
    with open(os.path.join(out, "cornell_moving2.gltf"), "w") as f:
        json.dump(g, f, indent=1)
        f.write("\n")
    print("cornell_moving2.gltf: second moving object, clearance %.3f" % clear)


if __name__ == "__main__":
    main()
