#!/usr/bin/env python3
"""The held-out scene family of the conformance suite (issue 28, docs/conformance.md).

    scripts/held_out.py --seed N --out DIR

writes into DIR a family of small glTF scenes drawn from the seed N (no method
was tuned on them) and DIR/manifest.json listing each variant with its
properties. The same seed gives the same bytes. Each scene has a camera and
a few hundred triangles, so 32^2 to 64^2 renders are quick:

  ceiling     a closed box of random proportions, single-sided walls facing
              in, a block and a thin panel on the floor, lit only by a small
              area light at a random offset under the ceiling (gap 1 to 8 cm)
  hanging     the same box lit by a double-sided area light hanging tilted in
              the room (it emits from both sides), a double-sided thin panel
  flat        the ceiling scene with no NORMAL anywhere (flat normals), the
              block's corners shared by its faces, the block mirrored by a
              node scale of -1 (negative determinant: its winding is reversed
              and its front faces are still outside)
  inside_out  the box wound outward (normals outward) with doubleSided walls
              seen from inside: back faces lit with reversed normals
  punctual    the box lit by a point light and a spot light (KHR_lights_punctual)
  sky         an open floor with a block and a panel under a smooth random
              environment map, the background visible above the horizon

Properties in the manifest (per variant): lights (area, area_double_sided,
point, spot, environment), double_sided (some material is), emitter_double_sided,
normals (every primitive has NORMAL), mirrored (a node with a negative
determinant), closed (a closed room), background_visible, triangles. The
conformance suite picks the variants a method's caps cover from the scenes
themselves (the same rule as `gibench compare`); the manifest says what each
variant exercises.

A seed is an integer in 0..4294967295; anything else is refused with one line
on stderr and exit status 2.
"""
import argparse
import json
import math
import os
import random
import struct
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "..", "tests", "data"))
sys.path.insert(0, os.path.join(HERE, "..", "tests", "data", "truth"))
from gltf_writer import Mesh  # noqa: E402
from gen_conformance import Writer, box, quad  # noqa: E402
from gen_truth import block_flat, block_shared, drop_normals, outward, room_walls  # noqa: E402

GEN = "gibench scripts/held_out.py"
VARIANTS = ("ceiling", "hanging", "flat", "inside_out", "punctual", "sky")


def r3(rng, lo, hi):
    return round(rng.uniform(lo, hi), 3)


def draw_room(rng):
    """A box of random proportions: half widths, height, and the furniture."""
    p = {"hx": r3(rng, 0.8, 1.6), "hz": r3(rng, 0.8, 1.6), "height": r3(rng, 1.4, 2.6)}
    p["albedo_wall"] = r3(rng, 0.4, 0.8)
    p["albedo_block"] = [r3(rng, 0.2, 0.8) for _ in range(3)]
    p["block"] = [r3(rng, 0.15, 0.4), r3(rng, 0.15, 0.5), r3(rng, 0.15, 0.4)]  # half x, half y, half z
    p["block_at"] = [r3(rng, -0.4, 0.0) * p["hx"], r3(rng, -0.5, 0.1) * p["hz"]]
    p["panel"] = [r3(rng, 0.2, 0.5), r3(rng, 0.3, 0.8)]  # half width, height
    p["panel_at"] = [r3(rng, 0.1, 0.5) * p["hx"], r3(rng, -0.6, -0.2) * p["hz"]]
    p["panel_turn"] = r3(rng, -60.0, 60.0)
    p["lamp_half"] = r3(rng, 0.08, 0.25)
    p["lamp_at"] = [r3(rng, -0.5, 0.5) * p["hx"], r3(rng, -0.5, 0.5) * p["hz"]]
    p["lamp_gap"] = rng.choice([0.01, 0.02, 0.05, 0.08])
    p["lamp_power"] = r3(rng, 15.0, 40.0)
    p["hang_tilt"] = r3(rng, 20.0, 70.0)
    p["hang_y"] = r3(rng, 0.45, 0.75) * p["height"]
    p["point"] = [r3(rng, -0.6, 0.6) * p["hx"], r3(rng, 0.5, 0.85) * p["height"], r3(rng, -0.6, 0.6) * p["hz"]]
    p["spot"] = [r3(rng, -0.6, 0.6) * p["hx"], r3(rng, 0.8, 0.95) * p["height"], r3(rng, -0.6, 0.6) * p["hz"]]
    p["spot_cone"] = r3(rng, 0.4, 0.9)
    p["sun_dir"] = [r3(rng, 0.0, 360.0), r3(rng, 20.0, 70.0)]  # azimuth, elevation in degrees
    p["cam_x"] = r3(rng, -0.3, 0.3) * p["hx"]
    return p


def panel_mesh(half_w, height, turn_deg, flip):
    """A thin panel: one vertical quad (two triangles), normal +z before the
    turn; flip winds it the other way (front face -z)."""
    m = Mesh()
    c, s = math.cos(math.radians(turn_deg)), math.sin(math.radians(turn_deg))
    n = (s, 0.0, c) if not flip else (-s, 0.0, -c)
    pts = [(-half_w, 0.0), (half_w, 0.0), (half_w, height), (-half_w, height)]
    ids = [m.add_vertex((x * c, y, -x * s), n) for x, y in pts]
    m.idx += [ids[0], ids[1], ids[2], ids[0], ids[2], ids[3]] if not flip else \
        [ids[0], ids[2], ids[1], ids[0], ids[3], ids[2]]
    return m


def tilted_quad(half, tilt_deg):
    """A square quad tilted about x by tilt_deg from facing down."""
    m = quad(0.0, 0.0, 0.0, half, half, down=True)
    c, s = math.cos(math.radians(tilt_deg)), math.sin(math.radians(tilt_deg))
    out = Mesh()
    for i in range(m.nverts):
        x, y, z = m.pos[3 * i:3 * i + 3]
        nx, ny, nz = m.nrm[3 * i:3 * i + 3]
        out.add_vertex((x, y * c - z * s, y * s + z * c), (nx, ny * c - nz * s, ny * s + nz * c))
    out.idx = list(m.idx)
    return out


def mirrored_x(m):
    """m reflected in x with its winding reversed: placed under a node of
    scale (-1, 1, 1) it is the original mesh again, fronts outside."""
    o = Mesh()
    for i in range(m.nverts):
        x, y, z = m.pos[3 * i:3 * i + 3]
        nx, ny, nz = m.nrm[3 * i:3 * i + 3]
        o.add_vertex((-x, y, z), (-nx, ny, nz))
    for t in range(0, len(m.idx), 3):
        o.idx += [m.idx[t], m.idx[t + 2], m.idx[t + 1]]
    return o


def emitter(g, name, power, double_sided):
    mat = g.material(name, (0.0, 0.0, 0.0), emission=(1.0, 1.0, 1.0), emission_strength=power)
    if double_sided:
        g.doc["materials"][mat]["doubleSided"] = True  # the writer refuses two-sided emitters
    return mat


def camera(g, p, open_sky=False):
    if open_sky:
        return g.camera_node("camera", (p["cam_x"], 1.1, 2.4), (0.0, 0.5, 0.0), 60.0, znear=0.02, zfar=50.0)
    eye = (p["cam_x"], 0.55 * p["height"], p["hz"] - 0.05)
    target = (-0.3 * p["cam_x"], 0.4 * p["height"], -p["hz"])
    return g.camera_node("camera", eye, target, 75.0, znear=0.01, zfar=20.0)


def furniture(g, p, flat=False, panel_double=False, mirror=False):
    m_block = g.material("block", tuple(p["albedo_block"]))
    m_panel = g.material("panel", (0.7, 0.7, 0.7), double_sided=panel_double)
    hx, hy, hz = p["block"]
    blk = block_shared(hx, hy, hz) if flat else block_flat(hx, hy, hz)
    at = (p["block_at"][0], 0.0, p["block_at"][1])
    if mirror:
        nd = g.node("block", mesh=g.mesh("block", [(mirrored_x(blk), m_block)]), translation=at)
        g.doc["nodes"][nd]["scale"] = [-1.0, 1.0, 1.0]
    else:
        nd = g.node("block", mesh=g.mesh("block", [(blk, m_block)]), translation=at)
    # a single-sided panel faces the camera (+z after its turn); a double-sided
    # one is wound the other way, so only its back faces the camera
    pan = panel_mesh(p["panel"][0], p["panel"][1], p["panel_turn"], flip=panel_double)
    np_ = g.node("panel", mesh=g.mesh("panel", [(pan, m_panel)]),
                 translation=(p["panel_at"][0], 0.0, p["panel_at"][1]))
    return [nd, np_]


def sky_pfm(path, rng):
    """A smooth random environment (lat-long, 32 x 16): a sky gradient and a
    soft bright lobe, ground darker."""
    w, h = 32, 16
    az, el = math.radians(rng.uniform(0, 360)), math.radians(rng.uniform(20, 70))
    sun = (math.cos(el) * math.cos(az), math.sin(el), math.cos(el) * math.sin(az))
    tint = (rng.uniform(0.7, 1.0), rng.uniform(0.8, 1.0), 1.0)
    rows = []
    for j in range(h):  # PFM rows bottom to top
        theta = math.pi * (1.0 - (j + 0.5) / h)  # from +y down
        for i in range(w):
            phi = 2 * math.pi * (i + 0.5) / w
            d = (math.sin(theta) * math.cos(phi), math.cos(theta), math.sin(theta) * math.sin(phi))
            lobe = max(0.0, sum(a * b for a, b in zip(d, sun))) ** 8
            base = 0.8 + 0.6 * max(d[1], 0.0) if d[1] > 0 else 0.3
            rows.append(tuple(round(base * t + 3.0 * lobe, 5) for t in tint))
    with open(path, "wb") as f:
        f.write(b"PF\n%d %d\n-1.0\n" % (w, h))
        f.write(b"".join(struct.pack("<fff", *c) for c in rows))


def write(g, out, name, nodes, extras=None):
    g.scene(name, nodes, extras=extras)
    g.write_gltf(os.path.join(out, name + ".gltf"), name + ".bin")


def triangles(g):
    return sum(g.doc["accessors"][p["indices"]]["count"] // 3 for m in g.doc["meshes"] for p in m["primitives"])


def room_scene(out, name, p, variant, rng):
    g = Writer(GEN)
    props = {"lights": [], "double_sided": False, "emitter_double_sided": False, "normals": True,
             "mirrored": False, "closed": True, "background_visible": False}
    m_wall = g.material("wall", (p["albedo_wall"],) * 3, double_sided=(variant == "inside_out"))
    walls = room_walls(1.0, 1.0).transformed(lambda q: (q[0] * p["hx"], q[1] * p["height"], q[2] * p["hz"]))
    if variant == "inside_out":
        walls = outward(walls)
        props["double_sided"] = True
    nodes = [g.node("room", mesh=g.mesh("room", [(walls, m_wall)]))]
    nodes += furniture(g, p, flat=(variant == "flat"), panel_double=(variant == "hanging"),
                       mirror=(variant == "flat"))
    props["double_sided"] |= variant == "hanging"
    props["mirrored"] = variant == "flat"
    if variant in ("ceiling", "flat", "inside_out"):
        lamp = quad(0.0, 0.0, 0.0, p["lamp_half"], p["lamp_half"], down=True)
        nodes.append(g.node("lamp", mesh=g.mesh("lamp", [(lamp, emitter(g, "lamp", p["lamp_power"], False))]),
                            translation=(p["lamp_at"][0], p["height"] - p["lamp_gap"], p["lamp_at"][1])))
        props["lights"].append("area")
        props["lamp_gap_m"] = p["lamp_gap"]
    elif variant == "hanging":
        lamp = tilted_quad(p["lamp_half"] * 1.5, p["hang_tilt"])
        nodes.append(g.node("lamp", mesh=g.mesh("lamp", [(lamp, emitter(g, "lamp", 0.5 * p["lamp_power"], True))]),
                            translation=(p["lamp_at"][0], p["hang_y"], p["lamp_at"][1])))
        props["lights"].append("area_double_sided")
        props["emitter_double_sided"] = True
    else:  # punctual
        s45 = math.sin(math.pi / 4)
        g.doc["extensions"] = {"KHR_lights_punctual": {"lights": [
            {"name": "bulb", "type": "point", "color": [1.0, 0.95, 0.9], "intensity": 3.0},
            {"name": "cone", "type": "spot", "intensity": 6.0,
             "spot": {"innerConeAngle": round(0.5 * p["spot_cone"], 3), "outerConeAngle": p["spot_cone"]}}]}}
        g.ext_used.add("KHR_lights_punctual")
        for k, (nm, pos, rot) in enumerate([("bulb", p["point"], None), ("cone", p["spot"], (-s45, 0.0, 0.0, s45))]):
            nd = g.node(nm + "_node", translation=pos, rotation=rot if rot else (0.0, 0.0, 0.0, 1.0))
            g.doc["nodes"][nd]["extensions"] = {"KHR_lights_punctual": {"light": k}}
            nodes.append(nd)
        props["lights"] += ["point", "spot"]
    nodes.append(camera(g, p))
    if variant == "flat":
        drop_normals(g)
        props["normals"] = False
    write(g, out, name, nodes)
    props["triangles"] = triangles(g)
    return props


def sky_scene(out, name, p, rng):
    g = Writer(GEN)
    m_floor = g.material("floor", (p["albedo_wall"],) * 3)
    nodes = [g.node("floor", mesh=g.mesh("floor", [(quad(0, 0, 0, 3.0, 3.0), m_floor)]))]
    nodes += furniture(g, p, panel_double=True)
    nodes.append(camera(g, p, open_sky=True))
    os.makedirs(os.path.join(out, "env"), exist_ok=True)
    sky_pfm(os.path.join(out, "env", name + ".pfm"), rng)
    extras = {"gibench": {"environment": {"uri": "env/" + name + ".pfm", "intensity": 1.0,
                                          "rotation_deg": 0.0}}}
    write(g, out, name, nodes, extras)
    return {"lights": ["environment"], "double_sided": True, "emitter_double_sided": False,
            "normals": True, "mirrored": False, "closed": False, "background_visible": True,
            "triangles": triangles(g)}


def generate(seed, out):
    rng = random.Random(seed)
    p = draw_room(rng)
    os.makedirs(out, exist_ok=True)
    variants = []
    for v in VARIANTS:
        name = "s%d_%s" % (seed, v)
        props = sky_scene(out, name, p, rng) if v == "sky" else room_scene(out, name, p, v, rng)
        variants.append(dict({"name": v, "file": name + ".gltf"}, **props))
    manifest = {"generator": GEN, "seed": seed, "room": p, "variants": variants}
    with open(os.path.join(out, "manifest.json"), "w", encoding="utf-8") as f:
        json.dump(manifest, f, indent=1, sort_keys=True)
        f.write("\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seed", required=True)
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    try:
        seed = int(a.seed, 10)
        if not 0 <= seed <= 0xFFFFFFFF:
            raise ValueError
    except ValueError:
        print("held_out.py: --seed '%s' is not an integer in 0..4294967295" % a.seed, file=sys.stderr)
        return 2
    if os.path.exists(a.out) and not os.path.isdir(a.out):
        print("held_out.py: --out '%s' exists and is not a folder" % a.out, file=sys.stderr)
        return 2
    generate(seed, a.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
