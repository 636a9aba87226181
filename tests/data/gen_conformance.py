#!/usr/bin/env python3
"""Scenes of the conformance suite (tests/conformance/, `gibench conformance`).

Writes tests/data/conformance/:
  furnace_050.gltf, furnace_080.gltf  a closed emitting sphere (radius 1,
      emission Le = 1, albedo rho = 0.5 / 0.8) seen from its centre. The
      sphere is a geodesic polyhedron (icosahedron split 3 times, 1280
      triangles) with flat faces and flat normals (no shared vertices), front
      faces inside. For any closed polyhedron of uniform emission and albedo
      the radiance is exactly Le (1 + rho + ... + rho^B) after B bounces at
      every point: every hemisphere of a face sees only the inside of the
      polyhedron, so each bounce adds rho times a uniform radiance. The
      faceting therefore costs nothing; smooth normals would tilt the
      shading hemisphere and break the identity.
  dark.gltf           a floor and a box, no light at all
  area.gltf, point.gltf, spot.gltf, directional.gltf, environment.gltf
                      the same lit by one light of one type only
  all.gltf            the same lit by every type (the parameter sweep scene)
  area_point.gltf     area + point light (for methods without distant light)
  one_object_all.gltf, one_object_area_point.gltf
                      the same as one object (one node, one mesh): the
                      parameter sweep's scenes, cheapest for per-object
                      precomputation
  moving.gltf         area.gltf with the box moving over 2 s (rigid motion)
  light_moving.gltf   point.gltf with the point light moving over 2 s
  env/uniform.pfm     a constant white environment map

Run from anywhere: python3 tests/data/gen_conformance.py (deterministic
output; the files are committed).
"""
import math
import os
import struct
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "scripts"))
from gltf_writer import Gltf, Mesh  # noqa: E402

OUT = os.path.join(HERE, "conformance")
GEN = "gibench tests/data/gen_conformance.py"


class Writer(Gltf):
    """The writer, keeping the document's KHR_lights_punctual light list."""

    def _finish(self, buffer_uri):
        doc = super()._finish(buffer_uri)
        if "extensions" in self.doc:
            doc["extensions"] = self.doc["extensions"]
        return doc


def icosphere_flat(r, level):
    t = (1.0 + math.sqrt(5.0)) / 2.0
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
         (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2),
         (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5),
         (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]

    def unit(p):
        n = math.sqrt(sum(c * c for c in p))
        return tuple(r * c / n for c in p)

    tris = [tuple(unit(v[i]) for i in face) for face in f]
    for _ in range(level):
        nxt = []
        for a, b, c in tris:
            ab = unit(tuple((x + y) / 2 for x, y in zip(a, b)))
            bc = unit(tuple((x + y) / 2 for x, y in zip(b, c)))
            ca = unit(tuple((x + y) / 2 for x, y in zip(c, a)))
            nxt += [(a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca)]
        tris = nxt
    m = Mesh()
    for a, b, c in tris:
        # the icosahedron's faces are counter-clockwise seen from outside:
        # reverse them so that the front face is inside, normal inward
        a, b, c = a, c, b
        e1 = [b[i] - a[i] for i in range(3)]
        e2 = [c[i] - a[i] for i in range(3)]
        n = (e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0])
        ln = math.sqrt(sum(x * x for x in n))
        n = tuple(x / ln for x in n)
        centre = [(a[i] + b[i] + c[i]) / 3 for i in range(3)]
        assert sum(n[i] * centre[i] for i in range(3)) < 0, "normal must point inward"
        for p in (a, b, c):
            m.idx.append(m.add_vertex(p, n))
    return m


def furnace(rho, name):
    g = Writer(GEN)
    mat = g.material("emitter", (rho, rho, rho), emission=(1.0, 1.0, 1.0), emission_strength=1.0)
    sphere = g.node("sphere", mesh=g.mesh("sphere", [(icosphere_flat(1.0, 3), mat)]))
    cam = g.camera_node("centre", (0.0, 0.0, 0.0), (0.0, 0.0, -1.0), 70.0, znear=0.01, zfar=10.0)
    g.scene("furnace", [sphere, cam])
    g.write_gltf(os.path.join(OUT, name + ".gltf"), name + ".bin")


def quad(cx, y, cz, hx, hz, down=False):
    m = Mesh()
    ny = -1.0 if down else 1.0
    corners = [(cx - hx, y, cz - hz), (cx + hx, y, cz - hz), (cx + hx, y, cz + hz), (cx - hx, y, cz + hz)]
    ids = [m.add_vertex(p, (0.0, ny, 0.0)) for p in corners]
    # counter-clockwise seen from +y: 0, 3, 2, 1
    if down:
        m.idx += [ids[0], ids[1], ids[2], ids[0], ids[2], ids[3]]
    else:
        m.idx += [ids[0], ids[3], ids[2], ids[0], ids[2], ids[1]]
    return m


def box(h):
    m = Mesh()
    faces = [((1, 0, 0), (0, 1, 0), (0, 0, 1)), ((-1, 0, 0), (0, 0, 1), (0, 1, 0)),
             ((0, 1, 0), (0, 0, 1), (1, 0, 0)), ((0, -1, 0), (1, 0, 0), (0, 0, 1)),
             ((0, 0, 1), (1, 0, 0), (0, 1, 0)), ((0, 0, -1), (0, 1, 0), (1, 0, 0))]
    for n, u, v in faces:
        c = [h * x for x in n]
        ids = []
        for su, sv in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
            p = tuple(c[i] + h * (su * u[i] + sv * v[i]) for i in range(3))
            ids.append(m.add_vertex(p, n))
        m.idx += [ids[0], ids[1], ids[2], ids[0], ids[2], ids[3]]
    return m


def room(name, lights, box_track=None, light_track=None, one_object=False):
    """lights: subset of area, point, spot, directional, environment.
    one_object: floor, box and lamp are primitives of one mesh on one node
    (one object: what per-object precomputation costs least on)."""
    g = Writer(GEN)
    m_floor = g.material("floor", (0.6, 0.6, 0.6))
    m_box = g.material("box", (0.7, 0.5, 0.3))
    if one_object:
        parts = [(quad(0, 0, 0, 2.0, 2.0), m_floor), (box(0.3).transformed(lambda p: (p[0], p[1] + 0.3, p[2])), m_box)]
        if "area" in lights:
            m_lamp = g.material("lamp", (0.0, 0.0, 0.0), emission=(1.0, 1.0, 1.0), emission_strength=8.0)
            parts.append((quad(0, 2.0, 0, 0.4, 0.4, down=True), m_lamp))
        nodes = [g.node("everything", mesh=g.mesh("everything", parts))]
        lights = [k for k in lights if k != "area"]
    else:
        nodes = [g.node("floor", mesh=g.mesh("floor", [(quad(0, 0, 0, 2.0, 2.0), m_floor)]))]
        nb = g.node("box", mesh=g.mesh("box", [(box(0.3), m_box)]), translation=(0.0, 0.3, 0.0))
        nodes.append(nb)
    if "area" in lights:
        m_lamp = g.material("lamp", (0.0, 0.0, 0.0), emission=(1.0, 1.0, 1.0), emission_strength=8.0)
        nodes.append(g.node("lamp", mesh=g.mesh("lamp", [(quad(0, 2.0, 0, 0.4, 0.4, down=True), m_lamp)])))
    punctual, light_nodes = [], []
    if "point" in lights:
        punctual.append({"name": "bulb", "type": "point", "color": [1, 1, 1], "intensity": 6.0})
        light_nodes.append(("bulb", (0.8, 1.5, 0.6), None))
    if "spot" in lights:
        punctual.append({"name": "cone", "type": "spot", "intensity": 8.0,
                         "spot": {"innerConeAngle": 0.4, "outerConeAngle": 0.8}})
        s45 = math.sin(math.pi / 4)
        light_nodes.append(("cone", (-0.5, 1.8, 0.4), (-s45, 0.0, 0.0, s45)))  # pointing down
    if "directional" in lights:
        punctual.append({"name": "sun", "type": "directional", "intensity": 2.0})
        a = -math.radians(60.0)  # light travels down -z rotated toward -y
        light_nodes.append(("sun", (0.0, 0.0, 0.0), (math.sin(a / 2), 0.0, 0.0, math.cos(a / 2))))
    if punctual:
        g.doc["extensions"] = {"KHR_lights_punctual": {"lights": punctual}}
        g.ext_used.add("KHR_lights_punctual")
        for k, (nm, pos, rot) in enumerate(light_nodes):
            nd = g.node(nm + "_node", translation=pos, rotation=rot if rot else (0.0, 0.0, 0.0, 1.0))
            g.doc["nodes"][nd]["extensions"] = {"KHR_lights_punctual": {"light": k}}
            nodes.append(nd)
            if light_track and nm == "bulb":
                g.animation("bulb_moves", [(nd, "translation", [0.0, 2.0],
                                            [0.8, 1.5, 0.6, -0.9, 0.6, -0.5])])
    if box_track:
        g.animation("box_moves", [(nb, "translation", [0.0, 2.0], [0.0, 0.3, 0.0, 1.0, 0.3, 0.6])])
    nodes.append(g.camera_node("camera", (0.0, 2.6, 3.2), (0.0, 0.3, 0.0), 50.0, znear=0.05, zfar=50.0))
    extras = None
    if "environment" in lights:
        extras = {"gibench": {"environment": {"uri": "env/uniform.pfm", "intensity": 1.0, "rotation_deg": 0.0}}}
    g.scene(name, nodes, extras=extras)
    g.write_gltf(os.path.join(OUT, name + ".gltf"), name + ".bin")


def uniform_pfm(path):
    w, h = 8, 4
    data = b"".join(struct.pack("<fff", 1.0, 1.0, 1.0) for _ in range(w * h))
    with open(path, "wb") as f:
        f.write(b"PF\n%d %d\n-1.0\n" % (w, h) + data)


def main():
    os.makedirs(os.path.join(OUT, "env"), exist_ok=True)
    uniform_pfm(os.path.join(OUT, "env", "uniform.pfm"))
    furnace(0.5, "furnace_050")
    furnace(0.8, "furnace_080")
    room("dark", [])
    for kind in ("area", "point", "spot", "directional", "environment"):
        room(kind, [kind])
    room("all", ["area", "point", "spot", "directional", "environment"])
    room("area_point", ["area", "point"])
    room("one_object_all", ["area", "point", "spot", "directional", "environment"], one_object=True)
    room("one_object_area_point", ["area", "point"], one_object=True)
    room("moving", ["area"], box_track=True)
    room("light_moving", ["point"], light_track=True)


if __name__ == "__main__":
    main()
