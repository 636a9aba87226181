#!/usr/bin/env python3
"""Writes the small glTF test scenes of tests/data/valid and the malformed
corpus of tests/data/malformed (one defect per file) with its EXPECTED.txt.

Each malformed file is the minimal valid quad below with exactly one thing
broken; the function that breaks it sits next to the message it must
produce. Files this script does not know (fuzz-*.gltf found by
scripts/fuzz-scene.sh) keep their EXPECTED lines. Run it from anywhere:
    python3 tests/data/gen_scenes.py
"""
import base64
import copy
import json
import math
import os
import struct
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))
VALID = os.path.join(HERE, "valid")
MALFORMED = os.path.join(HERE, "malformed")


# ---- binary helpers -------------------------------------------------------

def floats(values):
    return struct.pack("<%df" % len(values), *values)


def ushorts(values):
    return struct.pack("<%dH" % len(values), *values)


def data_uri(data, mime="application/octet-stream"):
    return "data:%s;base64,%s" % (mime, base64.b64encode(data).decode())


def png(width, height, rows, color_type=6):
    """rows: list of bytes per row (RGBA8 when color_type is 6)."""
    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))
    raw = b"".join(b"\0" + r for r in rows)
    ihdr = struct.pack(">IIBBBBB", width, height, 8, color_type, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(raw)) +
            chunk(b"IEND", b""))


def png16(width, height, rows):
    """RGBA 16-bit PNG; rows: lists of 16-bit values, 4 per pixel."""
    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))
    raw = b"".join(b"\0" + struct.pack(">%dH" % len(r), *r) for r in rows)
    ihdr = struct.pack(">IIBBBBB", width, height, 16, 6, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(raw)) +
            chunk(b"IEND", b""))


def png_header_only(width, height):
    ihdr = struct.pack(">IIBBBBB", width, height, 8, 6, 0, 0, 0)
    body = b"IHDR" + ihdr
    return b"\x89PNG\r\n\x1a\n" + struct.pack(">I", 13) + body + struct.pack(">I", zlib.crc32(body))


class Builder:
    """Collects binary blocks into one buffer and adds views/accessors."""

    def __init__(self, doc):
        self.doc = doc
        self.blob = b""
        doc.setdefault("buffers", [])
        doc.setdefault("bufferViews", [])
        doc.setdefault("accessors", [])

    def view(self, data):
        while len(self.blob) % 4:
            self.blob += b"\0"
        self.doc["bufferViews"].append({"buffer": 0, "byteOffset": len(self.blob),
                                        "byteLength": len(data)})
        self.blob += data
        return len(self.doc["bufferViews"]) - 1

    def accessor(self, data, count, type_, component=5126, **extra):
        acc = {"bufferView": self.view(data), "componentType": component, "count": count,
               "type": type_}
        acc.update(extra)
        self.doc["accessors"].append(acc)
        return len(self.doc["accessors"]) - 1

    def positions(self, pts):
        flat = [c for p in pts for c in p]
        lo = [min(p[k] for p in pts) for k in range(3)]
        hi = [max(p[k] for p in pts) for k in range(3)]
        finite = all(math.isfinite(c) for c in flat)
        extra = {"min": lo, "max": hi} if finite else {}
        return self.accessor(floats(flat), len(pts), "VEC3", **extra)

    def indices(self, idx):
        return self.accessor(ushorts(idx), len(idx), "SCALAR", 5123)

    def finish(self):
        self.doc["buffers"] = [{"byteLength": len(self.blob), "uri": data_uri(self.blob)}]
        return self.doc


QUAD = [(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)]
QUAD_IDX = [0, 1, 2, 0, 2, 3]


def base(with_mesh=True):
    """The minimal valid scene every malformed file starts from."""
    doc = {"asset": {"version": "2.0", "generator": "gibench tests/data/gen_scenes.py"},
           "scene": 0, "scenes": [{"nodes": [0]}],
           "nodes": [{"name": "quad", "mesh": 0}],
           "materials": [{"name": "white",
                          "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1]}}]}
    b = Builder(doc)
    if with_mesh:
        pos = b.positions(QUAD)
        idx = b.indices(QUAD_IDX)
        doc["meshes"] = [{"name": "quad", "primitives": [
            {"attributes": {"POSITION": pos}, "indices": idx, "material": 0}]}]
    return b


def prim(doc):
    return doc["meshes"][0]["primitives"][0]


def pretty(v, indent=0):
    """JSON with one key per line, but scalar lists and small flat objects
    kept on one line so the files stay readable."""
    flat = json.dumps(v, separators=(", ", ": "))
    scalar = lambda x: not isinstance(x, (dict, list))
    if scalar(v) or (isinstance(v, list) and all(scalar(x) for x in v)) or \
            (isinstance(v, dict) and all(scalar(x) for x in v.values()) and len(flat) < 72):
        return flat
    pad = " " * (indent + 1)
    if isinstance(v, dict):
        items = [pad + json.dumps(k) + ": " + pretty(x, indent + 1) for k, x in v.items()]
        return "{\n" + ",\n".join(items) + "\n" + " " * indent + "}"
    return "[\n" + ",\n".join(pad + pretty(x, indent + 1) for x in v) + "\n" + " " * indent + "]"


def write_json(path, doc):
    with open(path, "w") as f:
        f.write(pretty(doc) + "\n")


def glb(doc, bin_data):
    js = json.dumps(doc).encode()
    js += b" " * (-len(js) % 4)
    bin_data += b"\0" * (-len(bin_data) % 4)
    body = struct.pack("<II", len(js), 0x4E4F534A) + js
    if bin_data:
        body += struct.pack("<II", len(bin_data), 0x004E4942) + bin_data
    return struct.pack("<4sII", b"glTF", 2, 12 + len(body)) + body


# ---- valid scenes ---------------------------------------------------------

def valid_quad():
    """Two triangles without normals, a camera looking at them from +Z."""
    b = base()
    doc = b.finish()
    doc["cameras"] = [{"name": "main", "type": "perspective",
                       "perspective": {"yfov": 0.8, "znear": 0.1, "aspectRatio": 1.5}}]
    doc["nodes"].append({"name": "cam", "camera": 0, "translation": [0, 0, 3]})
    doc["scenes"][0]["nodes"] = [0, 1]
    return doc


def to_glb(doc):
    """The same scene as GLB: buffer 0 becomes the BIN chunk and embedded
    images move into buffer views (the loader decodes those itself)."""
    doc = copy.deepcopy(doc)
    blob = bytearray(base64.b64decode(doc["buffers"][0]["uri"].split(",", 1)[1]))
    for image in doc.get("images", []):
        uri = image.get("uri", "")
        if not uri.startswith("data:"):
            continue
        data = base64.b64decode(uri.split(",", 1)[1])
        blob += b"\0" * (-len(blob) % 4)
        doc["bufferViews"].append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(data)})
        blob += data
        image.pop("uri")
        image["bufferView"] = len(doc["bufferViews"]) - 1
        image["mimeType"] = uri[5:uri.index(";")]
    doc["buffers"] = [{"byteLength": len(blob)}]
    return glb(doc, bytes(blob))


def valid_animated():
    """parent (translation 1,0,0; rotation LINEAR 0 -> 90 deg about Y over
    t 0..2) with child (mesh, translation LINEAR keys at t 1,2,3; scale STEP
    keys at t 0,1), plus a static second object."""
    b = base()
    doc = b.doc
    tri = b.positions([(0, 0, 0), (1, 0, 0), (0, 1, 0)])
    tri_idx = b.indices([0, 1, 2])
    doc["meshes"].insert(0, {"name": "tri", "primitives": [
        {"attributes": {"POSITION": tri}, "indices": tri_idx, "material": 0}]})
    doc["meshes"][1]["primitives"][0]["material"] = 0
    s45 = math.sin(math.pi / 4)
    t_rot = b.accessor(floats([0, 2]), 2, "SCALAR")
    v_rot = b.accessor(floats([0, 0, 0, 1, 0, s45, 0, s45]), 2, "VEC4")
    t_tr = b.accessor(floats([1, 2, 3]), 3, "SCALAR")
    v_tr = b.accessor(floats([0, 0, 1, 0, 2, 1, 0, 2, 5]), 3, "VEC3")
    t_sc = b.accessor(floats([0, 1]), 2, "SCALAR")
    v_sc = b.accessor(floats([1, 1, 1, 3, 3, 3]), 2, "VEC3")
    doc["nodes"] = [
        {"name": "parent", "translation": [1, 0, 0], "children": [1]},
        {"name": "child", "mesh": 0, "translation": [0, 0, 1], "scale": [2, 2, 2]},
        {"name": "static", "mesh": 1, "translation": [0, -2, 0]},
    ]
    doc["scenes"] = [{"nodes": [0, 2]}]
    doc["animations"] = [{"name": "move", "samplers": [
        {"input": t_rot, "output": v_rot, "interpolation": "LINEAR"},
        {"input": t_tr, "output": v_tr},
        {"input": t_sc, "output": v_sc, "interpolation": "STEP"}],
        "channels": [
            {"sampler": 0, "target": {"node": 0, "path": "rotation"}},
            {"sampler": 1, "target": {"node": 1, "path": "translation"}},
            {"sampler": 2, "target": {"node": 1, "path": "scale"}}]}]
    return b.finish()


def valid_morph():
    """Morph targets. Mesh 0 'quad' (QUAD, normals +Z) has two targets:
    target 0 POSITION (0, 0, 1) on every vertex with NORMAL (0, 0.5, 0) on
    every vertex; target 1 POSITION (1, 0, 0) on vertex 2 only, no NORMAL.
    mesh.weights [0.25, 0]. Node 0 'morphing' animates its weights LINEAR
    (t 0: [0, 0], t 2: [1, 2]); node 1 'posed' (translation 0,0,-3) uses the
    same mesh with node.weights [0, 1] and no animation; node 2 'rigid'
    (translation 0,-3,0) the plain quad mesh 1 without targets."""
    b = base()
    doc = b.doc
    nrm = b.accessor(floats([0, 0, 1] * 4), 4, "VEC3")
    t0p = b.positions([(0, 0, 1)] * 4)
    t0n = b.accessor(floats([0, 0.5, 0] * 4), 4, "VEC3")
    t1p = b.positions([(0, 0, 0), (0, 0, 0), (1, 0, 0), (0, 0, 0)])
    p = prim(doc)
    p["attributes"]["NORMAL"] = nrm
    p["targets"] = [{"POSITION": t0p, "NORMAL": t0n}, {"POSITION": t1p}]
    doc["meshes"][0]["weights"] = [0.25, 0]
    pos2 = b.positions(QUAD)
    idx2 = b.indices(QUAD_IDX)
    doc["meshes"].append({"name": "plain", "primitives": [
        {"attributes": {"POSITION": pos2}, "indices": idx2, "material": 0}]})
    t_w = b.accessor(floats([0, 2]), 2, "SCALAR", min=[0], max=[2])
    v_w = b.accessor(floats([0, 0, 1, 2]), 4, "SCALAR")
    doc["nodes"] = [{"name": "morphing", "mesh": 0},
                    {"name": "posed", "mesh": 0, "weights": [0, 1], "translation": [0, 0, -3]},
                    {"name": "rigid", "mesh": 1, "translation": [0, -3, 0]}]
    doc["scenes"] = [{"nodes": [0, 1, 2]}]
    doc["animations"] = [{"name": "breathe", "samplers": [
        {"input": t_w, "output": v_w, "interpolation": "LINEAR"}],
        "channels": [{"sampler": 0, "target": {"node": 0, "path": "weights"}}]}]
    return b.finish()


def with_morph(targets, mesh_weights=None, node_weights=None, second_prim_targets=None):
    """targets: list of {attribute: (flat floats, count, type)} for the quad."""
    def fn(doc, b):
        def make(ts):
            out = []
            for t in ts:
                out.append({k: b.accessor(floats(v[0]), v[1], v[2]) for k, v in t.items()})
            return out
        prim(doc)["targets"] = make(targets)
        if mesh_weights is not None:
            doc["meshes"][0]["weights"] = mesh_weights
        if node_weights is not None:
            doc["nodes"][0]["weights"] = node_weights
        if second_prim_targets is not None:
            p2 = dict(prim(doc))
            p2["targets"] = make(second_prim_targets)
            doc["meshes"][0]["primitives"].append(p2)
    return fn


def with_morph_animation(target_count, out_values, out_count, out_type):
    """The quad with `target_count` zero targets and a weights channel."""
    def fn(doc, b):
        if target_count:
            with_morph([{"POSITION": ([0] * 12, 4, "VEC3")}] * target_count)(doc, b)
        t = b.accessor(floats([0, 1]), 2, "SCALAR")
        v = b.accessor(floats(out_values), out_count, out_type)
        doc["animations"] = [{"samplers": [{"input": t, "output": v}],
                              "channels": [{"sampler": 0, "target": {"node": 0, "path": "weights"}}]}]
    return fn


MORPH_ZERO = {"POSITION": ([0] * 12, 4, "VEC3")}


def valid_textured():
    """A quad with float uvs and a 2x2 sRGB texture; Phong and mirror extras;
    a second quad with normalised UNSIGNED_SHORT uvs and given normals."""
    b = base()
    doc = b.doc
    uv = b.accessor(floats([0, 1, 1, 1, 1, 0, 0, 0]), 4, "VEC2")
    prim(doc)["attributes"]["TEXCOORD_0"] = uv
    pos2 = b.positions([(p[0], p[1], -1) for p in QUAD])
    idx2 = b.indices(QUAD_IDX)
    nrm2 = b.accessor(floats([0, 0, 2] * 4), 4, "VEC3")  # not unit: normalised on load
    uv2 = b.accessor(ushorts([0, 0, 65535, 0, 65535, 65535, 0, 65535]), 4, "VEC2", 5123,
                     normalized=True)
    doc["meshes"].append({"name": "mirror_quad", "primitives": [
        {"attributes": {"POSITION": pos2, "NORMAL": nrm2, "TEXCOORD_0": uv2}, "indices": idx2,
         "material": 1}]})
    texels = [bytes([255, 0, 0, 255, 0, 255, 0, 255]),     # red, green
              bytes([0, 0, 255, 255, 128, 128, 128, 255])]  # blue, grey 128
    doc["images"] = [{"name": "checker", "uri": data_uri(png(2, 2, texels), "image/png")}]
    doc["samplers"] = [{"magFilter": 9729, "wrapS": 10497, "wrapT": 10497}]
    doc["textures"] = [{"name": "checker", "source": 0, "sampler": 0}]
    doc["materials"] = [
        {"name": "glossy", "pbrMetallicRoughness": {
            "baseColorFactor": [0.5, 0.5, 0.5, 1], "baseColorTexture": {"index": 0}},
         "extras": {"gibench": {"phong": {"ks": [0.2, 0.3, 0.4], "exponent": 50}}}},
        {"name": "mirror", "doubleSided": True,
         "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1]},
         "extras": {"gibench": {"phong": {"ks": [0.9, 0.9, 0.9], "exponent": 0},
                                "mirror": True}}},
    ]
    doc["nodes"].append({"name": "mirror", "mesh": 1})
    doc["scenes"][0]["nodes"] = [0, 1]
    return b.finish()


def valid_texture16():
    """A quad with a 1x1 16-bit texture (0x8000 grey, alpha 0x4000)."""
    b = base()
    doc = b.doc
    prim(doc)["attributes"]["TEXCOORD_0"] = b.accessor(floats([0.5, 0.5] * 4), 4, "VEC2")
    doc["images"] = [{"uri": data_uri(png16(1, 1, [[0x8000, 0x8000, 0x8000, 0x4000]]),
                                      "image/png")}]
    doc["textures"] = [{"source": 0}]
    doc["materials"][0]["pbrMetallicRoughness"] = {"baseColorFactor": [1, 1, 1, 1],
                                                   "baseColorTexture": {"index": 0}}
    return b.finish()


def valid_lights():
    """Point, spot (pointing down) and directional lights, an emissive quad
    (emissiveFactor x KHR_materials_emissive_strength), a floor without a
    material, and an environment map."""
    b = base()
    doc = b.doc
    floor = b.positions([(-2, 0, 2), (2, 0, 2), (2, 0, -2), (-2, 0, -2)])
    floor_idx = b.indices(QUAD_IDX)
    doc["meshes"].append({"name": "floor", "primitives": [
        {"attributes": {"POSITION": floor}, "indices": floor_idx}]})
    doc["materials"] = [{"name": "lamp", "emissiveFactor": [1, 0.5, 0.25],
                         "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4}},
                         "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1]}}]
    doc["extensionsUsed"] = ["KHR_lights_punctual", "KHR_materials_emissive_strength"]
    doc["extensionsRequired"] = ["KHR_lights_punctual"]
    doc["extensions"] = {"KHR_lights_punctual": {"lights": [
        {"name": "bulb", "type": "point", "color": [1, 0.5, 0.25], "intensity": 10, "range": 20},
        {"name": "cone", "type": "spot", "intensity": 5,
         "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.6}},
        {"type": "directional", "intensity": 2}]}}
    s45 = math.sin(math.pi / 4)
    doc["nodes"] = [
        {"name": "lamp", "mesh": 0, "translation": [0, 3, 0], "rotation": [s45, 0, 0, s45]},
        {"name": "floor", "mesh": 1},
        {"name": "bulb_node", "translation": [0, 3, 0],
         "extensions": {"KHR_lights_punctual": {"light": 0}}},
        {"name": "spot_node", "translation": [1, 2, 0], "rotation": [-s45, 0, 0, s45],
         "extensions": {"KHR_lights_punctual": {"light": 1}}},
        {"name": "sun_node", "extensions": {"KHR_lights_punctual": {"light": 2}}},
    ]
    doc["scenes"] = [{"name": "lit", "nodes": [0, 1, 2, 3, 4], "extras": {"gibench": {
        "environment": {"uri": "env/sky.pfm", "intensity": 2.0, "rotation_deg": 90}}}}]
    return b.finish()


def sky_pfm():
    """4x2 colour PFM, little-endian; bottom row first as PFM stores it."""
    top = [(1, 2, 3), (4, 5, 6), (7, 8, 9), (10, 11, 12)]
    bottom = [(0.5, 0.25, 0.125)] * 4
    data = b"".join(floats(p) for p in bottom + top)
    return b"PF\n4 2\n-1.0\n" + data


# ---- malformed corpus -------------------------------------------------------
# Each entry: file name, expected message substring, function returning the
# document (dict) or raw bytes.

def mutate(fn, with_mesh=True):
    def make():
        b = base(with_mesh)
        doc = b.finish()
        fn(doc, b)
        return doc
    return make


def duplicate_key(second):
    """The base scene with doubleSided on its material, followed by `second`
    (the same key again, in some spelling) in the same object."""
    def make():
        doc = base().finish()
        doc["materials"][0]["doubleSided"] = True
        text = pretty(doc) + "\n"
        assert text.count('"doubleSided": true') == 1
        return text.replace('"doubleSided": true', '"doubleSided": true, ' + second).encode()
    return make


def rebuilt(fn):
    """Like mutate, but the mutation adds data: the buffer is written after."""
    def make():
        b = base()
        fn(b.doc, b)
        return b.finish()
    return make


def set_path(path, value):
    def fn(doc, b):
        node = doc
        for key in path[:-1]:
            node = node[key]
        node[path[-1]] = value
    return fn


def custom_mesh(pos, idx=None, normals=None, uvs=None, mode=None):
    def fn(doc, b):
        p = prim(doc)
        p["attributes"] = {"POSITION": b.accessor(floats([c for v in pos for c in v]), len(pos),
                                                  "VEC3")}
        if idx is None:
            del p["indices"]
        else:
            p["indices"] = b.indices(idx)
        if normals is not None:
            p["attributes"]["NORMAL"] = b.accessor(floats([c for v in normals for c in v]),
                                                   len(normals), "VEC3")
        if uvs is not None:
            p["attributes"]["TEXCOORD_0"] = b.accessor(floats([c for v in uvs for c in v]),
                                                       len(uvs), "VEC2")
        if mode is not None:
            p["mode"] = mode
    return fn


NAN, INF = float("nan"), float("inf")


def with_texture(texture_fields, image):
    def fn(doc, b):
        doc["images"] = [image]
        doc["textures"] = [texture_fields]
        doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = {"index": 0}
    return fn


def with_animation(samplers, channels, data):
    """data: list of (floats, count, type) accessors appended in order."""
    def fn(doc, b):
        first = len(doc["accessors"])
        for values, count, type_ in data:
            b.accessor(floats(values), count, type_)
        for s in samplers:
            s["input"] += first
            s["output"] += first
        doc["animations"] = [{"samplers": samplers, "channels": channels}]
    return fn


def with_light(light, node_light=0):
    def fn(doc, b):
        doc["extensions"] = {"KHR_lights_punctual": {"lights": [light]}}
        doc["nodes"][0]["extensions"] = {"KHR_lights_punctual": {"light": node_light}}
    return fn


def phong(extras, albedo=0.8):
    def fn(doc, b):
        doc["materials"][0]["pbrMetallicRoughness"]["baseColorFactor"] = [albedo] * 3 + [1]
        doc["materials"][0]["extras"] = {"gibench": extras}
    return fn


def many_objects(doc, b):
    doc["nodes"] = [{"mesh": 0} for _ in range(257)]
    doc["scenes"][0]["nodes"] = list(range(257))


def many_materials(doc, b):
    doc["materials"] = [{} for _ in range(4097)]


def node_cycle(doc, b):
    doc["nodes"] = [{"mesh": 0, "children": [1]}, {"children": [0]}]


def two_parents(doc, b):
    doc["nodes"] = [{"mesh": 0, "children": [2]}, {"children": [2]}, {"mesh": 0}]
    doc["scenes"][0]["nodes"] = [0, 1]


def root_is_child(doc, b):
    doc["nodes"] = [{"mesh": 0, "children": [1]}, {"mesh": 0}]
    doc["scenes"][0]["nodes"] = [0, 1]


def deep_extras(doc, b):
    value = 1
    for _ in range(70):
        value = [value]
    doc["extras"] = value


def sparse(doc, b):
    doc["accessors"][0]["sparse"] = {"count": 1, "indices": {"bufferView": 1, "componentType": 5123},
                                     "values": {"bufferView": 0}}


def index_floats(doc, b):
    prim(doc)["indices"] = b.accessor(floats([0, 1, 2]), 3, "SCALAR")


def sheared(doc, b):
    doc["nodes"][0]["matrix"] = [1, 0, 0, 0, 0.5, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]


def duplicate_channel(doc, b):
    t = b.accessor(floats([0, 1]), 2, "SCALAR")
    v = b.accessor(floats([0, 0, 0, 1, 1, 1]), 2, "VEC3")
    doc["animations"] = [{"samplers": [{"input": t, "output": v}], "channels": [
        {"sampler": 0, "target": {"node": 0, "path": "translation"}},
        {"sampler": 0, "target": {"node": 0, "path": "translation"}}]}]


def tex_uvs(doc, b):
    prim(doc)["attributes"]["TEXCOORD_0"] = b.accessor(floats([0, 0] * 4), 4, "VEC2")


def triangle_limit():
    """256 nodes sharing one mesh of 65537 triangles (UNSIGNED_BYTE indices,
    all one degenerate triangle): 16777472 triangles, just past the limit."""
    doc = base(with_mesh=False).doc
    pos = floats([0, 0, 0, 1, 0, 0, 0, 1, 0])
    idx = bytes([0, 1, 2]) * 65537
    blob = pos + idx + b"\0" * (-len(idx) % 4)
    doc["buffers"] = [{"byteLength": len(blob)}]
    doc["bufferViews"] = [{"buffer": 0, "byteLength": len(pos)},
                          {"buffer": 0, "byteOffset": len(pos), "byteLength": len(idx)}]
    doc["accessors"] = [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"},
                        {"bufferView": 1, "componentType": 5121, "count": len(idx), "type": "SCALAR"}]
    doc["meshes"] = [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}]
    doc["nodes"] = [{"mesh": 0} for _ in range(256)]
    doc["scenes"][0]["nodes"] = list(range(256))
    return glb(doc, blob)


def image_view_overrun():
    """textured.glb with the image's buffer view running far past the buffer:
    rejected before any decoder sees the pointer tinygltf computes."""
    doc = valid_textured()
    data = bytearray(to_glb(doc))
    jlen = json_chunk_len(data)
    js = json.loads(bytes(data[20:20 + jlen]))
    view = js["images"][0]["bufferView"]
    js["bufferViews"][view]["byteLength"] = 1 << 30
    return glb(js, bytes(data[20 + jlen + 8:]))


def image_view_garbage():
    """An unused image in a buffer view that is not an image at all."""
    b = base()
    doc = b.doc
    doc["images"] = [{"bufferView": b.view(b"not an image"), "mimeType": "image/png"}]
    doc = b.finish()
    return to_glb(doc)


def bin_past_file():
    """BIN chunk claiming 8 bytes more than the file holds, buffer as long as
    the claim: tinygltf 2.7's own check misses the 8-byte chunk header and
    copies past the end of the input (seen with an instrumented tinygltf)."""
    js = json.dumps({"asset": {"version": "2.0"}, "buffers": [{"byteLength": 68}]}).encode()
    js += b" " * (-len(js) % 4)
    body = struct.pack("<II", len(js), 0x4E4F534A) + js + struct.pack("<II", 68, 0x004E4942)
    body += bytes(60)
    return struct.pack("<4sII", b"glTF", 2, 12 + len(body)) + body


def glb_bytes(mut):
    """Raw GLB bytes of the base scene, then mut(bytearray) -> bytes."""
    def make():
        doc = base().finish()
        blob = base64.b64decode(doc["buffers"][0]["uri"].split(",", 1)[1])
        doc["buffers"] = [{"byteLength": len(blob)}]
        return mut(bytearray(glb(doc, blob)))
    return make


def glb_set32(offset, value):
    def mut(data):
        data[offset:offset + 4] = struct.pack("<I", value)
        return bytes(data)
    return mut


def json_chunk_len(data):
    return struct.unpack("<I", data[12:16])[0]


def glb_bin_too_long(data):
    off = 20 + json_chunk_len(data)
    data[off:off + 4] = struct.pack("<I", struct.unpack("<I", data[off:off + 4])[0] + 4)
    return bytes(data)


CORPUS = [
    # version and extensions
    ("version-1.gltf", "/asset/version: glTF version '1.0' is not supported (need 2.0)",
     mutate(set_path(["asset", "version"], "1.0"))),
    ("version-missing.gltf", "/asset/version: missing or not a string",
     mutate(lambda d, b: d["asset"].pop("version"))),
    ("min-version.gltf", "/asset/minVersion: file needs glTF '2.1'",
     mutate(set_path(["asset", "minVersion"], "2.1"))),
    ("extension-required.gltf",
     "/extensionsRequired/0: extension 'KHR_draco_mesh_compression' is required but not supported",
     mutate(set_path(["extensionsRequired"], ["KHR_draco_mesh_compression"]))),
    # references out of range
    ("ref-mesh.gltf", "/nodes/0/mesh: mesh 5 out of range (1 meshes)",
     mutate(set_path(["nodes", 0, "mesh"], 5))),
    ("ref-accessor.gltf",
     "/meshes/0/primitives/0/attributes/POSITION: accessor 9 out of range (2 accessors)",
     mutate(lambda d, b: prim(d)["attributes"].update(POSITION=9))),
    ("ref-indices.gltf", "primitive indices accessor out of bounds",  # tinygltf's own check
     mutate(lambda d, b: prim(d).update(indices=7))),
    ("ref-bufferview.gltf", "/accessors/0/bufferView: bufferView 7 out of range (2 bufferViews)",
     mutate(set_path(["accessors", 0, "bufferView"], 7))),
    ("ref-buffer.gltf", "/bufferViews/0/buffer: buffer 3 out of range (1 buffers)",
     mutate(set_path(["bufferViews", 0, "buffer"], 3))),
    ("ref-material.gltf", "/meshes/0/primitives/0/material: material 4 out of range (1 materials)",
     mutate(lambda d, b: prim(d).update(material=4))),
    ("ref-texture.gltf",
     "/materials/0/pbrMetallicRoughness/baseColorTexture/index: texture 2 out of range (0 textures)",
     mutate(lambda d, b: d["materials"][0]["pbrMetallicRoughness"].update(
         baseColorTexture={"index": 2}))),
    ("ref-image.gltf", "/textures/0/source: image 3 out of range (0 images)",
     mutate(lambda d, b: d.update(textures=[{"source": 3}]))),
    ("ref-sampler.gltf", "/textures/0/sampler: sampler 5 out of range (0 samplers)",
     mutate(lambda d, b: d.update(textures=[{"sampler": 5}]))),
    ("ref-child.gltf", "/nodes/0/children/0: node 9 out of range (1 nodes)",
     mutate(set_path(["nodes", 0, "children"], [9]))),
    ("ref-camera.gltf", "/nodes/0/camera: camera 2 out of range (0 cameras)",
     mutate(set_path(["nodes", 0, "camera"], 2))),
    ("ref-light.gltf", "/nodes/0/extensions/KHR_lights_punctual/light: light 3 out of range (1 lights)",
     mutate(with_light({"type": "point"}, node_light=3))),
    ("ref-scene-node.gltf", "/scenes/0/nodes/0: node 4 out of range (1 nodes)",
     mutate(set_path(["scenes", 0, "nodes"], [4]))),
    ("ref-default-scene.gltf", "/scene: scene 3 out of range (1 scenes)",
     mutate(set_path(["scene"], 3))),
    ("ref-anim-sampler.gltf", "/animations/0/channels/0/sampler: sampler 2 out of range (1 samplers)",
     rebuilt(with_animation([{"input": 0, "output": 1}],
                            [{"sampler": 2, "target": {"node": 0, "path": "translation"}}],
                            [([0, 1], 2, "SCALAR"), ([0] * 6, 2, "VEC3")]))),
    ("ref-anim-node.gltf", "/animations/0/channels/0/target/node: node 6 out of range (1 nodes)",
     rebuilt(with_animation([{"input": 0, "output": 1}],
                            [{"sampler": 0, "target": {"node": 6, "path": "translation"}}],
                            [([0, 1], 2, "SCALAR"), ([0] * 6, 2, "VEC3")]))),
    # ranges inside buffers (uint64, overflow-checked)
    ("accessor-past-view.gltf",
     "/accessors/0: count 5 x stride 12 past the end of bufferView 0 (48 bytes)",
     mutate(set_path(["accessors", 0, "count"], 5))),
    ("accessor-offset-past-view.gltf",
     "/accessors/0: byteOffset 4 + count 4 x stride 12 past the end of bufferView 0 (48 bytes)",
     mutate(set_path(["accessors", 0, "byteOffset"], 4))),
    ("accessor-count-overflow.gltf",
     "/accessors/0: count 4611686018427387904 x stride 12 past the end of bufferView 0",
     mutate(set_path(["accessors", 0, "count"], 2 ** 62))),
    ("accessor-offset-overflow.gltf",
     "/accessors/0: byteOffset 18446744073709551600 + count 4 x stride 12 past the end",
     mutate(set_path(["accessors", 0, "byteOffset"], 2 ** 64 - 16))),
    ("view-past-buffer.gltf",
     "/bufferViews/1: byteOffset 48 + byteLength 16 past the end of buffer 0 (60 bytes)",
     mutate(set_path(["bufferViews", 1, "byteLength"], 16))),
    ("view-offset-overflow.gltf",
     "/bufferViews/0: byteOffset 18446744073709551615 + byteLength 48 past the end of buffer 0",
     mutate(set_path(["bufferViews", 0, "byteOffset"], 2 ** 64 - 1))),
    # geometry
    ("index-range.gltf",
     "/meshes/0/primitives/0/indices: index 7 (element 2 of accessor 3) >= vertex count 4",
     rebuilt(custom_mesh(QUAD, [0, 1, 7, 0, 2, 3]))),
    ("index-count.gltf", "/meshes/0/primitives/0/indices: index count 5 is not a multiple of 3",
     rebuilt(custom_mesh(QUAD, [0, 1, 2, 0, 2]))),
    ("index-type.gltf", "/accessors/2: indices cannot be SCALAR of FLOAT",
     rebuilt(index_floats)),
    ("non-indexed-count.gltf",
     "/meshes/0/primitives/0: non-indexed primitive has 4 vertices, not a multiple of 3",
     rebuilt(custom_mesh(QUAD))),
    ("mode-lines.gltf",
     "/meshes/0/primitives/0/mode: mode 1 (LINES) is not supported; only triangles (4)",
     mutate(lambda d, b: prim(d).update(mode=1))),
    ("position-missing.gltf", "/meshes/0/primitives/0/attributes: POSITION is missing",
     mutate(lambda d, b: prim(d).update(attributes={"COLOR_0": 0}))),
    ("position-type.gltf", "/accessors/0: POSITION cannot be VEC2 of FLOAT",
     mutate(set_path(["accessors", 0, "type"], "VEC2"))),
    ("position-nan.gltf", "/accessors/2: POSITION element 2 is not finite",
     rebuilt(custom_mesh([(0, 0, 0), (1, 0, 0), (NAN, 1, 0)], [0, 1, 2]))),
    ("normal-inf.gltf", "/accessors/4: NORMAL element 0 is not finite",
     rebuilt(custom_mesh([(0, 0, 0), (1, 0, 0), (0, 1, 0)], [0, 1, 2],
                         normals=[(INF, 0, 1), (0, 0, 1), (0, 0, 1)]))),
    ("uv-nan.gltf", "/accessors/4: TEXCOORD_0 element 1 is not finite",
     rebuilt(custom_mesh([(0, 0, 0), (1, 0, 0), (0, 1, 0)], [0, 1, 2],
                         uvs=[(0, 0), (NAN, 0), (0, 1)]))),
    ("normal-count.gltf",
     "/meshes/0/primitives/0/attributes/NORMAL: accessor 4 has 2 elements but POSITION has 3",
     rebuilt(custom_mesh([(0, 0, 0), (1, 0, 0), (0, 1, 0)], [0, 1, 2],
                         normals=[(0, 0, 1), (0, 0, 1)]))),
    ("accessor-no-bufferview.gltf", "/accessors/0: accessor without a bufferView is not supported",
     mutate(lambda d, b: (d["accessors"][0].pop("bufferView"),
                          d["accessors"][0].update(count=40000000)))),
    ("sparse-accessor.gltf", "/accessors/0/sparse: sparse accessors are not supported",
     mutate(sparse)),
    ("no-triangles.gltf", "/scenes/0: the scene has no triangles",
     mutate(lambda d, b: d["nodes"][0].pop("mesh"))),
    # node graph
    ("node-cycle.gltf", "is its own ancestor (cycle)", mutate(node_cycle)),
    ("node-self-child.gltf", "/nodes/0/children/0: node 0 is its own child (cycle)",
     mutate(set_path(["nodes", 0, "children"], [0]))),
    ("node-two-parents.gltf",
     "/nodes/1/children/0: node 2 already has parent node 0 (a node has at most one parent)",
     mutate(two_parents)),
    ("scene-root-twice.gltf", "/scenes/0/nodes/1: node 0 is listed twice",
     mutate(set_path(["scenes", 0, "nodes"], [0, 0]))),
    ("scene-root-is-child.gltf", "/scenes/0/nodes/1: node 1 is a child of node 0, not a root",
     mutate(root_is_child)),
    ("node-matrix-shear.gltf",
     "/nodes/0/matrix: is not a translation-rotation-scale matrix (it has shear)",
     mutate(sheared)),
    ("node-zero-quaternion.gltf", "/nodes/0/rotation: is not a unit quaternion (length 0)",
     mutate(set_path(["nodes", 0, "rotation"], [0, 0, 0, 0]))),
    # URIs
    ("uri-parent.gltf", "/buffers/0/uri: URI '../outside.bin' leaves the scene directory",
     mutate(set_path(["buffers", 0, "uri"], "../outside.bin"))),
    ("uri-parent-nested.gltf", "/buffers/0/uri: URI 'a/../../outside.bin' leaves the scene directory",
     mutate(set_path(["buffers", 0, "uri"], "a/../../outside.bin"))),
    ("uri-percent-parent.gltf", "/buffers/0/uri: URI '%2e%2e/outside.bin' leaves the scene directory",
     mutate(set_path(["buffers", 0, "uri"], "%2e%2e/outside.bin"))),
    ("uri-absolute.gltf", "/buffers/0/uri: URI '/etc/passwd' is an absolute path",
     mutate(set_path(["buffers", 0, "uri"], "/etc/passwd"))),
    ("uri-percent-absolute.gltf", "/buffers/0/uri: URI '%2fetc/passwd' is an absolute path",
     mutate(set_path(["buffers", 0, "uri"], "%2fetc/passwd"))),
    ("uri-scheme-http.gltf",
     "/buffers/0/uri: URI scheme 'http' is not allowed (only relative paths and data: URIs)",
     mutate(set_path(["buffers", 0, "uri"], "http://example.com/quad.bin"))),
    ("uri-scheme-file.gltf", "/buffers/0/uri: URI scheme 'file' is not allowed",
     mutate(set_path(["buffers", 0, "uri"], "file:///etc/passwd"))),
    ("uri-bad-escape.gltf", "/buffers/0/uri: URI 'quad%zz.bin' has a malformed percent-escape",
     mutate(set_path(["buffers", 0, "uri"], "quad%zz.bin"))),
    ("uri-nul.gltf", "/buffers/0/uri: URI 'quad%00.bin' contains a NUL byte",
     mutate(set_path(["buffers", 0, "uri"], "quad%00.bin"))),
    ("uri-missing.gltf", "/buffers/0/uri: cannot open 'missing.bin': No such file or directory",
     mutate(set_path(["buffers", 0, "uri"], "missing.bin"))),
    ("uri-data-unsupported.gltf",
     "/buffers/0/uri: data URI must be base64 with a glTF MIME type ('data:text/html,hello')",
     mutate(set_path(["buffers", 0, "uri"], "data:text/html,hello"))),
    ("uri-data-empty.gltf", "/images/0/uri: data URI holds no data",
     rebuilt(with_texture({"source": 0}, {"uri": "data:image/png;base64,"}))),
    ("image-empty-file.gltf", "/images/0: image data could not be read from 'empty.png'",
     mutate(lambda d, b: d.update(images=[{"uri": "empty.png"}]))),
    ("image-view-not-png.glb", "/images/0: image is not PNG or JPEG", image_view_garbage),
    ("uri-image-parent.gltf", "/images/0/uri: URI 'img/../../x.png' leaves the scene directory",
     rebuilt(with_texture({"source": 0}, {"uri": "img/../../x.png"}))),
    # limits
    ("too-many-objects.gltf", "/nodes/256: more than 256 objects (nodes with a mesh) in the scene",
     mutate(many_objects)),
    ("too-many-triangles.glb", "/nodes/255: scene exceeds the limit of 16777216 triangles",
     triangle_limit),
    ("too-many-materials.gltf", "/materials: 4097 materials exceed the limit of 4096",
     mutate(many_materials)),
    ("texture-too-large.gltf", "/images/0: image size 9000x16 outside 1..8192",
     rebuilt(with_texture({"source": 0}, {"uri": data_uri(png_header_only(9000, 16), "image/png")}))),
    ("texture-not-png.gltf", "/images/0: image is not PNG or JPEG",
     rebuilt(with_texture({"source": 0}, {"uri": data_uri(b"GIF89a....", "image/png")}))),
    ("texture-no-source.gltf", "/textures/0: has no source image",
     rebuilt(lambda d, b: (tex_uvs(d, b), with_texture({}, {"uri": data_uri(
         png(1, 1, [bytes([1, 2, 3, 255])]), "image/png")})(d, b)))),
    ("json-deep.gltf", "/: JSON nested deeper than 64 levels", mutate(deep_extras)),
    # cameras, lights, materials
    ("camera-ortho.gltf", "/cameras/0: orthographic cameras are not supported",
     mutate(lambda d, b: d.update(cameras=[{"type": "orthographic", "orthographic": {
         "xmag": 1, "ymag": 1, "znear": 0.1, "zfar": 10}}]))),
    ("camera-yfov.gltf", "/cameras/0/perspective/yfov: must lie in (0, pi)",
     mutate(lambda d, b: d.update(cameras=[{"type": "perspective", "perspective": {
         "yfov": 4, "znear": 0.1}}]))),
    ("light-type.gltf", "/extensions/KHR_lights_punctual/lights/0/type: light type 'area' is not supported",
     mutate(with_light({"type": "area"}))),
    ("light-spot-cone.gltf",
     "/extensions/KHR_lights_punctual/lights/0/spot: needs 0 <= innerConeAngle < outerConeAngle <= pi/2",
     mutate(with_light({"type": "spot", "spot": {"innerConeAngle": 0.8, "outerConeAngle": 0.5}}))),
    ("light-intensity.gltf",
     "/extensions/KHR_lights_punctual/lights/0/intensity: must be finite and >= 0",
     mutate(with_light({"type": "point", "intensity": -3}))),
    ("base-color-range.gltf", "/materials/0/pbrMetallicRoughness/baseColorFactor: values must lie in [0, 1]",
     mutate(set_path(["materials", 0, "pbrMetallicRoughness", "baseColorFactor"], [2, 0, 0, 1]))),
    ("emissive-strength.gltf",
     "/materials/0/extensions/KHR_materials_emissive_strength/emissiveStrength: must be a number >= 0",
     mutate(set_path(["materials", 0, "extensions"],
                     {"KHR_materials_emissive_strength": {"emissiveStrength": -1}}))),
    ("phong-ks-range.gltf", "/materials/0/extras/gibench/phong/ks: must be 3 numbers in [0, 1]",
     mutate(phong({"phong": {"ks": [1.5, 0, 0], "exponent": 10}}, albedo=0))),
    ("phong-ks-short.gltf", "/materials/0/extras/gibench/phong/ks: must be 3 numbers in [0, 1]",
     mutate(phong({"phong": {"ks": [0.1, 0.1], "exponent": 10}}))),
    ("phong-exponent.gltf", "/materials/0/extras/gibench/phong/exponent: must be a number >= 0",
     mutate(phong({"phong": {"ks": [0.1, 0.1, 0.1], "exponent": -1}}))),
    ("phong-energy.gltf",
     "/materials/0: albedo + ks = 1.3 in channel 0 exceeds 1 (the material would create energy)",
     mutate(phong({"phong": {"ks": [0.5, 0.1, 0.1], "exponent": 20}}))),
    ("phong-mirror-type.gltf", "/materials/0/extras/gibench/mirror: must be true or false",
     mutate(phong({"mirror": "yes"}))),
    ("phong-mirror-no-ks.gltf", "/materials/0/extras/gibench: mirror needs phong.ks (its reflectance)",
     mutate(phong({"mirror": True}, albedo=0))),
    # animation
    ("anim-cubicspline.gltf",
     "/animations/0/samplers/0/interpolation: CUBICSPLINE interpolation is not supported",
     rebuilt(with_animation([{"input": 0, "output": 1, "interpolation": "CUBICSPLINE"}],
                            [{"sampler": 0, "target": {"node": 0, "path": "translation"}}],
                            [([0, 1], 2, "SCALAR"), ([0] * 18, 6, "VEC3")]))),
    ("anim-times-order.gltf",
     "/accessors/2: animation times not strictly increasing at element 2 (1 after 1)",
     rebuilt(with_animation([{"input": 0, "output": 1}],
                            [{"sampler": 0, "target": {"node": 0, "path": "translation"}}],
                            [([0, 1, 1], 3, "SCALAR"), ([0] * 9, 3, "VEC3")]))),
    ("anim-time-negative.gltf", "/accessors/2: animation time 0 is negative or not finite",
     rebuilt(with_animation([{"input": 0, "output": 1}],
                            [{"sampler": 0, "target": {"node": 0, "path": "scale"}}],
                            [([-1, 1], 2, "SCALAR"), ([1] * 6, 2, "VEC3")]))),
    ("anim-output-count.gltf", "/animations/0/samplers/0/output: output has 3 keys but input has 2",
     rebuilt(with_animation([{"input": 0, "output": 1}],
                            [{"sampler": 0, "target": {"node": 0, "path": "translation"}}],
                            [([0, 1], 2, "SCALAR"), ([0] * 9, 3, "VEC3")]))),
    ("anim-rotation-type.gltf", "/accessors/3: rotation output cannot be VEC3 of FLOAT",
     rebuilt(with_animation([{"input": 0, "output": 1}],
                            [{"sampler": 0, "target": {"node": 0, "path": "rotation"}}],
                            [([0, 1], 2, "SCALAR"), ([0] * 6, 2, "VEC3")]))),
    ("anim-path.gltf", "/animations/0/channels/0/target/path: path 'color' is not supported",
     rebuilt(with_animation([{"input": 0, "output": 1}],
                            [{"sampler": 0, "target": {"node": 0, "path": "color"}}],
                            [([0, 1], 2, "SCALAR"), ([0] * 6, 2, "VEC3")]))),
    ("anim-duplicate.gltf",
     "/animations/0/channels/1: node 0 translation is already animated by another channel",
     rebuilt(duplicate_channel)),
    # morph targets
    ("morph-attribute.gltf",
     "/meshes/0/primitives/0/targets/0/TEXCOORD_0: morph target attribute 'TEXCOORD_0' is not supported",
     rebuilt(with_morph([{"POSITION": ([0] * 12, 4, "VEC3"), "TEXCOORD_0": ([0] * 8, 4, "VEC2")}]))),
    ("morph-empty.gltf", "/meshes/0/primitives/0/targets/0: morph target has no attribute",
     rebuilt(with_morph([{}]))),
    ("morph-type.gltf", "/accessors/2: morph target POSITION cannot be VEC2 of FLOAT",
     rebuilt(with_morph([{"POSITION": ([0] * 8, 4, "VEC2")}]))),
    ("morph-count.gltf",
     "/meshes/0/primitives/0/targets/0/NORMAL: accessor 2 has 3 elements but POSITION has 4",
     rebuilt(with_morph([{"NORMAL": ([0] * 9, 3, "VEC3")}]))),
    ("morph-nan.gltf", "/accessors/2: morph target POSITION element 1 is not finite",
     rebuilt(with_morph([{"POSITION": ([0, 0, 0, 0, NAN, 0] + [0] * 6, 4, "VEC3")}]))),
    ("morph-primitives.gltf",
     "/meshes/0/primitives/1/targets: has 2 morph targets but the mesh's first primitive has 1",
     rebuilt(with_morph([MORPH_ZERO], second_prim_targets=[MORPH_ZERO, MORPH_ZERO]))),
    ("morph-mesh-weights.gltf", "/meshes/0/weights: has 2 weights but the mesh has 1 morph targets",
     rebuilt(with_morph([MORPH_ZERO], mesh_weights=[0.5, 0.5]))),
    ("morph-node-weights.gltf", "/nodes/0/weights: has 1 weights but mesh 0 has 0 morph targets",
     mutate(set_path(["nodes", 0, "weights"], [1.0]))),
    ("morph-anim-no-targets.gltf",
     "/animations/0/channels/0/target/node: node 0 animates morph weights but mesh 0 has no morph targets",
     rebuilt(with_morph_animation(0, [0, 1], 2, "SCALAR"))),
    ("morph-anim-count.gltf",
     "/animations/0/samplers/0/output: weights output has 3 values but 2 keys x 2 morph targets = 4",
     rebuilt(with_morph_animation(2, [0, 1, 0], 3, "SCALAR"))),
    ("morph-anim-type.gltf", "weights output cannot be VEC2 of FLOAT",
     rebuilt(with_morph_animation(1, [0, 1, 0, 1], 2, "VEC2"))),
    ("morph-anim-nan.gltf", "animation value 1 is not finite",
     rebuilt(with_morph_animation(1, [0, INF], 2, "SCALAR"))),
    # environment
    ("env-parent.gltf",
     "/scenes/0/extras/gibench/environment/uri: URI '../sky.pfm' leaves the scene directory",
     mutate(set_path(["scenes", 0, "extras"], {"gibench": {"environment": {"uri": "../sky.pfm"}}}))),
    ("env-missing.gltf",
     "/scenes/0/extras/gibench/environment/uri: cannot read environment map 'nope.pfm'",
     mutate(set_path(["scenes", 0, "extras"], {"gibench": {"environment": {"uri": "nope.pfm"}}}))),
    ("env-intensity.gltf", "/scenes/0/extras/gibench/environment/intensity: must be a number >= 0",
     mutate(set_path(["scenes", 0, "extras"], {"gibench": {"environment": {
         "uri": "sky.pfm", "intensity": "bright"}}}))),
    # a key given twice (tinygltf would keep the last): refused, also when
    # the second is spelt with an escape (json.dumps cannot write either)
    ("json-duplicate-key.gltf", "/materials/0/doubleSided: duplicate key 'doubleSided'",
     duplicate_key('"doubleSided": false')),
    ("json-duplicate-key-escaped.gltf", "/materials/0/doubleSided: duplicate key 'doubleSided'",
     duplicate_key('"double\\u0053ided": false')),
    # tinygltf's own errors, passed through
    ("json-syntax.gltf", "parse error", lambda: b'{"asset": {"version": "2.0"}, "nodes": [,]}\n'),
    ("json-not-object.gltf", "Root element is not a JSON object", lambda: b"[1, 2, 3]\n"),
    # not JSON at all (an OpenEXR header): named as not glTF
    ("not-gltf.gltf", "not a glTF file (neither glTF JSON nor GLB",
     lambda: b"v/1\x01\x02\x00\x00\x00channels\x00chlist\x00"),
    ("accessor-type.gltf", "Unsupported `type` for accessor object",
     mutate(set_path(["accessors", 0, "type"], "VEC7"))),
    # GLB container
    ("glb-version.glb", "GLB: container version 1 is not supported (need 2)",
     glb_bytes(glb_set32(4, 1))),
    ("glb-length.glb", "GLB: header length 4096 does not match", glb_bytes(glb_set32(8, 4096))),
    ("glb-json-chunk.glb", "GLB: JSON chunk of 100000 bytes does not fit",
     glb_bytes(glb_set32(12, 100000))),
    ("glb-chunk-type.glb", "GLB: first chunk is not JSON", glb_bytes(glb_set32(16, 0x12345678))),
    ("glb-bin-overrun.glb", "GLB: BIN chunk of 64 bytes runs past the end", glb_bytes(glb_bin_too_long)),
    ("glb-bin-past-file.glb", "GLB: BIN chunk of 68 bytes runs past the end", bin_past_file),
    ("glb-image-view-overrun.glb",
     "/bufferViews/7: byteOffset 216 + byteLength 1073741824 past the end of buffer 0 (294 bytes)",
     image_view_overrun),
    ("glb-short.glb", "GLB: 12 bytes is shorter than the 20-byte header",
     lambda: struct.pack("<4sII", b"glTF", 2, 12)),
]


def write_all():
    os.makedirs(os.path.join(VALID, "env"), exist_ok=True)
    os.makedirs(MALFORMED, exist_ok=True)
    for name, make in [("quad", valid_quad), ("animated", valid_animated), ("morph", valid_morph),
                       ("textured", valid_textured), ("lights", valid_lights),
                       ("texture16", valid_texture16)]:
        doc = make()
        write_json(os.path.join(VALID, name + ".gltf"), doc)
        with open(os.path.join(VALID, name + ".glb"), "wb") as f:
            f.write(to_glb(doc))
    with open(os.path.join(VALID, "env", "sky.pfm"), "wb") as f:
        f.write(sky_pfm())

    expected_path = os.path.join(MALFORMED, "EXPECTED.txt")
    kept = []
    names = {name for name, _, _ in CORPUS}
    if os.path.exists(expected_path):
        for line in open(expected_path):
            if line.startswith("#") or not line.strip():
                continue
            name = line.split("\t", 1)[0]
            if name not in names:
                kept.append(line.rstrip("\n"))
    lines = ["# Malformed inputs and a substring of the error each must produce.",
             "# <file>\\t<substring>; written by tests/data/gen_scenes.py, except fuzz-* lines."]
    for name, expect, make in CORPUS:
        doc = make()
        path = os.path.join(MALFORMED, name)
        if isinstance(doc, (bytes, bytearray)):
            with open(path, "wb") as f:
                f.write(doc)
        else:
            write_json(path, doc)
        lines.append("%s\t%s" % (name, expect))
    open(os.path.join(MALFORMED, "empty.png"), "wb").close()
    with open(expected_path, "w") as f:
        f.write("\n".join(lines + kept) + "\n")
    print("wrote %d malformed files (+%d kept lines)" % (len(CORPUS), len(kept)))


if __name__ == "__main__":
    write_all()
