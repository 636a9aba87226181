#!/usr/bin/env python3
"""Glossy test scenes without mirrors (tests of methods with GI_CAP_GLOSSY
but not GI_CAP_MIRROR, e.g. plugins/implicit_vis).

Writes plugins/implicit_vis/data/:
  glossy_floor.gltf   a 4 x 4 floor of glossy Phong material (albedo 0.25,
      ks 0.6, exponent 30), tessellated 32 x 32, with a diffuse box
      (0.5 wide, tessellated 4 x 4 per face) on it and a 0.6 x 0.6 area
      light (tessellated 3 x 3, radiance 10) 1.5 above it, facing down;
      the camera looks at the floor so that the light's glossy highlight
      and the box's shadow are both in view.
  glossy_punctual.gltf  the same floor and box, lit by a point light
      (intensity 3) and a spot light (intensity 5, cone 0.4 / 0.8 rad)
      pointing down instead of the area light: the punctual lights'
      highlights and shadows.
  glossy_env.gltf     the same floor and box under an environment only
      (env/sectors.pfm: 0.2 everywhere but eight alternating longitude
      sectors of radiance 2 at 30-75 degrees above and below the horizon),
      seen from above so that every pixel is floor or box.

Run from anywhere: python3 plugins/implicit_vis/data/gen_glossy.py (deterministic output;
the files are committed).
"""
import math
import os
import struct
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "..", "scripts"))
from gltf_writer import Gltf, Mesh  # noqa: E402

OUT = HERE
GEN = "gibench plugins/implicit_vis/data/gen_glossy.py"


def grid(origin, u, v, nu, nv, normal):
    """A planar patch origin + s u + t v (s, t in [0, 1]) split into
    nu x nv cells, counter-clockwise seen from the side of `normal`."""
    m = Mesh()
    ids = {}
    for j in range(nv + 1):
        for i in range(nu + 1):
            p = tuple(origin[k] + u[k] * i / nu + v[k] * j / nv for k in range(3))
            ids[i, j] = m.add_vertex(p, normal)
    cr = (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])
    ccw = sum(cr[k] * normal[k] for k in range(3)) > 0
    for j in range(nv):
        for i in range(nu):
            a, b, c, d = ids[i, j], ids[i + 1, j], ids[i + 1, j + 1], ids[i, j + 1]
            m.idx += [a, b, c, a, c, d] if ccw else [a, c, b, a, d, c]
    return m


def merge(parts):
    m = Mesh()
    for p in parts:
        base = m.nverts
        for k in range(p.nverts):
            m.add_vertex(tuple(p.pos[3 * k:3 * k + 3]), tuple(p.nrm[3 * k:3 * k + 3]))
        m.idx += [base + i for i in p.idx]
    return m


def box(cx, cz, h, n):
    """An axis-aligned cube of half size h standing on y = 0 at (cx, cz)."""
    faces = []
    for ax in range(3):
        for sgn in (1.0, -1.0):
            nrm = [0.0, 0.0, 0.0]
            nrm[ax] = sgn
            a1, a2 = (ax + 1) % 3, (ax + 2) % 3
            o = [0.0, 0.0, 0.0]
            o[ax] = sgn * h
            o[a1] = -h
            o[a2] = -h
            u = [0.0, 0.0, 0.0]
            u[a1] = 2 * h
            v = [0.0, 0.0, 0.0]
            v[a2] = 2 * h
            o = (o[0] + cx, o[1] + h, o[2] + cz)
            faces.append(grid(o, u, v, n, n, tuple(nrm)))
    return merge(faces)


def glossy_floor():
    g = Gltf(GEN)
    m_floor = g.material("glossy_floor", (0.25, 0.25, 0.25), ks=(0.6, 0.6, 0.6), exponent=30.0)
    m_box = g.material("box", (0.7, 0.5, 0.3))
    m_lamp = g.material("lamp", (0.0, 0.0, 0.0), emission=(1.0, 1.0, 1.0), emission_strength=10.0)
    floor = grid((-2.0, 0.0, -2.0), (4.0, 0.0, 0.0), (0.0, 0.0, 4.0), 32, 32, (0.0, 1.0, 0.0))
    lamp = grid((-0.3, 1.5, -1.1), (0.6, 0.0, 0.0), (0.0, 0.0, 0.6), 3, 3, (0.0, -1.0, 0.0))
    nodes = [g.node("floor", mesh=g.mesh("floor", [(floor, m_floor)])),
             g.node("box", mesh=g.mesh("box", [(box(0.7, -0.3, 0.25, 4), m_box)])),
             g.node("lamp", mesh=g.mesh("lamp", [(lamp, m_lamp)]))]
    nodes.append(g.camera_node("camera", (0.0, 1.2, 3.0), (0.0, 0.0, -0.5), 50.0, znear=0.05, zfar=50.0))
    g.scene("glossy_floor", nodes)
    g.write_gltf(os.path.join(OUT, "glossy_floor.gltf"), "glossy_floor.bin")


def glossy_punctual():
    g = Gltf(GEN)
    m_floor = g.material("glossy_floor", (0.25, 0.25, 0.25), ks=(0.6, 0.6, 0.6), exponent=30.0)
    m_box = g.material("box", (0.7, 0.5, 0.3))
    floor = grid((-2.0, 0.0, -2.0), (4.0, 0.0, 0.0), (0.0, 0.0, 4.0), 32, 32, (0.0, 1.0, 0.0))
    nodes = [g.node("floor", mesh=g.mesh("floor", [(floor, m_floor)])),
             g.node("box", mesh=g.mesh("box", [(box(0.7, -0.3, 0.25, 4), m_box)])),
             g.point_light_node("bulb", 3.0, translation=(0.5, 1.4, -0.5))]
    ext = g.doc["extensions"]["KHR_lights_punctual"]
    ext["lights"].append({"name": "cone", "type": "spot", "color": [1.0, 1.0, 1.0], "intensity": 5.0,
                          "spot": {"innerConeAngle": 0.4, "outerConeAngle": 0.8}})
    s45 = math.sin(math.pi / 4)
    nd = g.node("cone", translation=(-0.6, 1.6, -0.3), rotation=(-s45, 0.0, 0.0, s45))  # pointing down
    g.doc["nodes"][nd]["extensions"] = {"KHR_lights_punctual": {"light": len(ext["lights"]) - 1}}
    nodes.append(nd)
    nodes.append(g.camera_node("camera", (0.0, 1.2, 3.0), (0.0, 0.0, -0.5), 50.0, znear=0.05, zfar=50.0))
    g.scene("glossy_punctual", nodes)
    g.write_gltf(os.path.join(OUT, "glossy_punctual.gltf"), "glossy_punctual.bin")


def sectors_pfm(path):
    """An equirectangular map, symmetric about the horizon (so that either
    row order puts the bright sectors above it)."""
    w, h = 64, 32
    rows = []
    for j in range(h):
        elev = abs(90.0 - (j + 0.5) * 180.0 / h)
        for i in range(w):
            sector = int((i + 0.5) * 8 / w) % 2
            v = 2.0 if 30.0 <= elev <= 75.0 and sector == 0 else 0.2
            rows.append(struct.pack("<fff", v, v, v))
    with open(path, "wb") as f:
        f.write(b"PF\n%d %d\n-1.0\n" % (w, h) + b"".join(rows))


def glossy_env():
    g = Gltf(GEN)
    m_floor = g.material("glossy_floor", (0.25, 0.25, 0.25), ks=(0.6, 0.6, 0.6), exponent=30.0)
    m_box = g.material("box", (0.7, 0.5, 0.3))
    floor = grid((-2.0, 0.0, -2.0), (4.0, 0.0, 0.0), (0.0, 0.0, 4.0), 32, 32, (0.0, 1.0, 0.0))
    nodes = [g.node("floor", mesh=g.mesh("floor", [(floor, m_floor)])),
             g.node("box", mesh=g.mesh("box", [(box(0.7, -0.3, 0.25, 4), m_box)]))]
    nodes.append(g.camera_node("camera", (0.0, 3.0, 1.2), (0.0, 0.0, -0.3), 36.0, znear=0.05, zfar=50.0))
    g.scene("glossy_env", nodes,
            extras={"gibench": {"environment": {"uri": "env/sectors.pfm", "intensity": 1.0, "rotation_deg": 0.0}}})
    g.write_gltf(os.path.join(OUT, "glossy_env.gltf"), "glossy_env.bin")


def main():
    os.makedirs(os.path.join(OUT, "env"), exist_ok=True)
    sectors_pfm(os.path.join(OUT, "env", "sectors.pfm"))
    glossy_floor()
    glossy_punctual()
    glossy_env()


if __name__ == "__main__":
    main()
