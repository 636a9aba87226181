#!/usr/bin/env python3
"""Writes plugins/csm/data/csm_cross.glb: two boxes on a ground plane that
shadow each other under two local lights (the csm plugin's multi-object
test, Ritschel et al. 2007 §4.6):
  - box A (1 x 2 x 1, tall) at x in [-1.5, -0.5], box B (1 x 1 x 1) at
    x in [0.5, 1.5], both on the ground (y = 0), 8 x 8 quads per face;
  - a linear light: an emissive bar 3 long (along z) and 0.1 wide at
    (-3, 2.5, 0), facing down and toward +x: A shadows B's -x face;
  - a point light (KHR_lights_punctual) at (3, 1.5, 0): B shadows the lower
    part of A's +x face;
  - the ground, 8 x 8, 16 x 16 quads, is planar (a receiver-only candidate).
csm_cross_moved.glb is the same with the point light at (3, 2, 0.5): the
csm cache must key cube maps on the light's geometry.
Run: python3 plugins/csm/data/gen_csm_cross.py (deterministic output)."""
import math
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "..", "scripts"))
import gltf_writer as gw  # noqa: E402


class Writer(gw.Gltf):
    def _finish(self, buffer_uri):
        doc = super()._finish(buffer_uri)
        if "extensions" in self.doc:
            doc["extensions"] = self.doc["extensions"]
        return doc


def quad(m, p, u, v, n_u, n_v):
    n = gw.norm(gw.cross(u, v))
    base = m.nverts
    for j in range(n_v + 1):
        for i in range(n_u + 1):
            q = gw.add(p, gw.add(gw.scale(u, i / n_u), gw.scale(v, j / n_v)))
            m.add_vertex(q, n)
    for j in range(n_v):
        for i in range(n_u):
            a = base + j * (n_u + 1) + i
            b, c, d = a + 1, a + n_u + 2, a + n_u + 1
            m.idx.extend([a, b, c, a, c, d])


def box(x0, x1, y0, y1, z0, z1, n=8):
    m = gw.Mesh()
    dx, dy, dz = x1 - x0, y1 - y0, z1 - z0
    quad(m, (x1, y0, z1), (0, 0, -dz), (0, dy, 0), n, n)   # +x
    quad(m, (x0, y0, z0), (0, 0, dz), (0, dy, 0), n, n)    # -x
    quad(m, (x0, y1, z0), (0, 0, dz), (dx, 0, 0), n, n)    # +y
    quad(m, (x0, y0, z0), (dx, 0, 0), (0, 0, dz), n, n)    # -y
    quad(m, (x0, y0, z1), (dx, 0, 0), (0, dy, 0), n, n)    # +z
    quad(m, (x1, y0, z0), (-dx, 0, 0), (0, dy, 0), n, n)   # -z
    return m


def write(name, point_light):
    g = Writer("gibench plugins/csm/data/gen_csm_cross.py")
    white = g.material("white", (0.7, 0.7, 0.7))
    grey = g.material("grey", (0.5, 0.5, 0.5))
    light = g.material("light", (0.0, 0.0, 0.0), emission=(1.0, 1.0, 1.0), emission_strength=20.0)
    ground = gw.Mesh()
    quad(ground, (-4, 0, -4), (0, 0, 8), (8, 0, 0), 16, 16)
    bar = gw.Mesh()
    L, w = 3.0, 0.1
    u = (0.0, 0.0, L)
    v = gw.scale((-1.0 / math.sqrt(2), -1.0 / math.sqrt(2), 0.0), w)
    quad(bar, gw.sub((-3.0, 2.5, 0.0), gw.add(gw.scale(u, 0.5), gw.scale(v, 0.5))), u, v, 1, 1)
    nodes = [
        g.node("ground", mesh=g.mesh("ground", [(ground, grey)])),
        g.node("box_a", mesh=g.mesh("box_a", [(box(-1.5, -0.5, 0, 2, -0.5, 0.5), white)])),
        g.node("box_b", mesh=g.mesh("box_b", [(box(0.5, 1.5, 0, 1, -0.5, 0.5), white)])),
        g.node("bar_light", mesh=g.mesh("bar_light", [(bar, light)])),
    ]
    g.doc["extensions"] = {"KHR_lights_punctual": {"lights": [
        {"name": "point", "type": "point", "color": [1.0, 1.0, 1.0], "intensity": 30.0}]}}
    g.ext_used.add("KHR_lights_punctual")
    pl = g.node("point_light", translation=point_light)
    g.doc["nodes"][pl]["extensions"] = {"KHR_lights_punctual": {"light": 0}}
    nodes.append(pl)
    nodes.append(g.camera_node("camera", (0.5, 4.0, 7.0), (0.0, 0.7, 0.0), 45.0))
    g.scene("csm_cross", nodes)
    g.write_glb(os.path.join(HERE, name))


def main():
    write("csm_cross.glb", (3.0, 1.5, 0.0))
    write("csm_cross_moved.glb", (3.0, 2.0, 0.5))


if __name__ == "__main__":
    main()
