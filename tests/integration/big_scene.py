#!/usr/bin/python3
"""A large scene for the cancellation test (tests/integration/cancel_test.sh):
the Cornell box (scenes/cornell_box_coarse.gltf) with a bumpy heightfield of
2 * n * n triangles over its floor. The bumps make every triangle's plane
its own (methods that merge coplanar triangles get no shortcut).
usage: big_scene.py ROOT OUT.gltf N"""
import json
import os
import random
import sys
from array import array


def main():
    root, out, n = sys.argv[1], sys.argv[2], int(sys.argv[3])
    src = os.path.join(root, "scenes", "cornell_box_coarse.gltf")
    g = json.load(open(src))
    base = open(os.path.join(os.path.dirname(src), g["buffers"][0]["uri"]), "rb").read()
    base += b"\0" * (-len(base) % 4)
    # the floor spans the box's x and z; heights a few centimetres
    rnd = random.Random(1)
    step = 4.9 / n
    pos = array("f")
    for r in range(n + 1):
        for c in range(n + 1):
            pos.extend((0.3 + r * step, 0.02 + 0.01 * rnd.random(), 0.3 + c * step))
    idx = array("I")
    for r in range(n):
        for c in range(n):
            a = r * (n + 1) + c
            idx.extend((a, a + 1, a + n + 1, a + 1, a + n + 2, a + n + 1))
    ys = pos[1::3]
    off_p = len(base)
    off_i = off_p + len(pos) * 4
    blob = base + pos.tobytes() + idx.tobytes()
    name = os.path.splitext(os.path.basename(out))[0] + ".bin"
    g["buffers"] = [{"byteLength": len(blob), "uri": name}]
    nv = len(g["bufferViews"])
    g["bufferViews"] += [
        {"buffer": 0, "byteOffset": off_p, "byteLength": len(pos) * 4, "target": 34962},
        {"buffer": 0, "byteOffset": off_i, "byteLength": len(idx) * 4, "target": 34963},
    ]
    na = len(g["accessors"])
    g["accessors"] += [
        {"bufferView": nv, "componentType": 5126, "count": len(pos) // 3, "type": "VEC3",
         "min": [0.3, min(ys), 0.3], "max": [0.3 + n * step, max(ys), 0.3 + n * step]},
        {"bufferView": nv + 1, "componentType": 5125, "count": len(idx), "type": "SCALAR"},
    ]
    g["meshes"].append({"name": "bumps", "primitives": [
        {"attributes": {"POSITION": na}, "indices": na + 1, "material": 0}]})
    g["nodes"].append({"name": "bumps", "mesh": len(g["meshes"]) - 1})
    g["scenes"][g.get("scene", 0)]["nodes"].append(len(g["nodes"]) - 1)
    with open(os.path.join(os.path.dirname(out) or ".", name), "wb") as f:
        f.write(blob)
    with open(out, "w") as f:
        json.dump(g, f)


if __name__ == "__main__":
    main()
