"""Minimal deterministic glTF 2.0 writer used by make_scenes.py (stdlib only).

Writes .gltf + external .bin or a single .glb.  Every accessor gets its own
4-byte-aligned bufferView; POSITION and animation-input accessors carry
min/max computed from the float32-rounded values, as the Khronos validator
requires.  Output is byte-identical for identical input.
"""

import array
import base64
import json
import math
import struct
import sys

FLOAT = 5126
USHORT = 5123
UINT = 5125
ARRAY_BUFFER = 34962
ELEMENT_ARRAY_BUFFER = 34963
NCOMP = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}


def _f32(values):
    a = array.array("f", values)
    if sys.byteorder != "little":
        a.byteswap()
    return a


def _le_bytes(a):
    if sys.byteorder != "little":
        a = array.array(a.typecode, a)
        a.byteswap()
    return a.tobytes()


class Mesh:
    """Triangle soup with shared vertices: flat lists pos/nrm/uv and idx."""

    def __init__(self, textured=False):
        self.pos = []
        self.nrm = []
        self.uv = [] if textured else None
        self.idx = []

    @property
    def nverts(self):
        return len(self.pos) // 3

    @property
    def ntris(self):
        return len(self.idx) // 3

    def add_vertex(self, p, n, uv=None):
        self.pos.extend(p)
        self.nrm.extend(n)
        if self.uv is not None:
            self.uv.extend(uv if uv is not None else (0.0, 0.0))
        return self.nverts - 1

    def transformed(self, fn_pos):
        m = Mesh(self.uv is not None)
        for i in range(self.nverts):
            p = fn_pos(self.pos[3 * i:3 * i + 3])
            m.pos.extend(p)
        m.nrm = list(self.nrm)
        m.uv = None if self.uv is None else list(self.uv)
        m.idx = list(self.idx)
        return m


class Gltf:
    def __init__(self, generator, copyright_text=None):
        self.doc = {"asset": {"version": "2.0", "generator": generator}}
        if copyright_text:
            self.doc["asset"]["copyright"] = copyright_text
        self.bin = bytearray()
        self.ext_used = set()

    # -- low level ---------------------------------------------------------
    def _list(self, key):
        return self.doc.setdefault(key, [])

    def _view(self, data, target=None):
        while len(self.bin) % 4:
            self.bin.append(0)
        view = {"buffer": 0, "byteOffset": len(self.bin), "byteLength": len(data)}
        if target is not None:
            view["target"] = target
        self.bin.extend(data)
        views = self._list("bufferViews")
        views.append(view)
        return len(views) - 1

    def float_accessor(self, values, type_, target=ARRAY_BUFFER, minmax=False, name=None):
        n = NCOMP[type_]
        a = _f32(values)
        count = len(a) // n
        assert count * n == len(a) and count > 0
        acc = {"bufferView": self._view(_le_bytes(a), target), "componentType": FLOAT,
               "count": count, "type": type_}
        if minmax:
            acc["min"] = [min(a[i::n]) for i in range(n)]
            acc["max"] = [max(a[i::n]) for i in range(n)]
        if name:
            acc["name"] = name
        accs = self._list("accessors")
        accs.append(acc)
        return len(accs) - 1

    def index_accessor(self, idx, nverts):
        if nverts <= 65535:
            a, ct = array.array("H", idx), USHORT
        else:
            a, ct = array.array("I", idx), UINT
        assert max(idx) < nverts
        acc = {"bufferView": self._view(_le_bytes(a), ELEMENT_ARRAY_BUFFER),
               "componentType": ct, "count": len(idx), "type": "SCALAR"}
        accs = self._list("accessors")
        accs.append(acc)
        return len(accs) - 1

    # -- scene objects -----------------------------------------------------
    def material(self, name, albedo, ks=(0.0, 0.0, 0.0), exponent=1.0, mirror=False,
                 emission=None, emission_strength=1.0, texture=None, double_sided=False):
        for c in range(3):
            assert albedo[c] + ks[c] <= 1.0 + 1e-9, (name, "albedo + ks > 1")
        pbr = {"baseColorFactor": [float(albedo[0]), float(albedo[1]), float(albedo[2]), 1.0],
               "metallicFactor": 0.0, "roughnessFactor": 1.0}
        if texture is not None:
            pbr["baseColorTexture"] = {"index": texture}
        mat = {"name": name, "pbrMetallicRoughness": pbr}
        if double_sided:
            assert emission is None, "emitters are one-sided"
            mat["doubleSided"] = True
        if emission is not None:
            assert all(0.0 <= e <= 1.0 for e in emission)
            mat["emissiveFactor"] = [float(e) for e in emission]
            mat["extensions"] = {"KHR_materials_emissive_strength":
                                 {"emissiveStrength": float(emission_strength)}}
            self.ext_used.add("KHR_materials_emissive_strength")
        mat["extras"] = {"gibench": {"phong": {"ks": [float(k) for k in ks],
                                               "exponent": float(exponent)},
                                     "mirror": bool(mirror)}}
        mats = self._list("materials")
        mats.append(mat)
        return len(mats) - 1

    def png_texture(self, png_bytes, name, embed_glb=True, wrap_repeat=True):
        img = {"name": name, "mimeType": "image/png", "bufferView": self._view(png_bytes)}
        imgs = self._list("images")
        imgs.append(img)
        wrap = 10497 if wrap_repeat else 33071
        samplers = self._list("samplers")
        samplers.append({"magFilter": 9728, "minFilter": 9729, "wrapS": wrap, "wrapT": wrap})
        texs = self._list("textures")
        texs.append({"sampler": len(samplers) - 1, "source": len(imgs) - 1})
        return len(texs) - 1

    def mesh(self, name, parts, weights=None):
        """parts: list of (Mesh, material index). A Mesh with .targets (a list
        of {"POSITION": flat displacements, "NORMAL": flat displacements})
        gets glTF morph targets; `weights` are the mesh's default weights."""
        prims = []
        for m, mat in parts:
            attrs = {"POSITION": self.float_accessor(m.pos, "VEC3", minmax=True),
                     "NORMAL": self.float_accessor(m.nrm, "VEC3")}
            if m.uv is not None:
                attrs["TEXCOORD_0"] = self.float_accessor(m.uv, "VEC2")
            prim = {"attributes": attrs, "indices": self.index_accessor(m.idx, m.nverts),
                    "material": mat, "mode": 4}
            targets = getattr(m, "targets", None)
            if targets:
                prim["targets"] = [
                    {k: self.float_accessor(t[k], "VEC3", minmax=(k == "POSITION"))
                     for k in ("POSITION", "NORMAL") if k in t} for t in targets]
            prims.append(prim)
        meshes = self._list("meshes")
        mesh = {"name": name, "primitives": prims}
        if weights is not None:
            mesh["weights"] = [float(w) for w in weights]
        meshes.append(mesh)
        return len(meshes) - 1

    def node(self, name, mesh=None, camera=None, translation=None, rotation=None,
             extras=None):
        nd = {"name": name}
        if mesh is not None:
            nd["mesh"] = mesh
        if camera is not None:
            nd["camera"] = camera
        if translation is not None and any(abs(t) > 0 for t in translation):
            nd["translation"] = [_clean(t) for t in translation]
        if rotation is not None and abs(rotation[3] - 1.0) > 1e-12:
            nd["rotation"] = [_clean(r) for r in rotation]
        if extras:
            nd["extras"] = extras
        nodes = self._list("nodes")
        nodes.append(nd)
        return len(nodes) - 1

    def camera_node(self, name, eye, target, yfov_deg, up=(0.0, 1.0, 0.0),
                    znear=0.01, zfar=1000.0):
        cams = self._list("cameras")
        cams.append({"name": name, "type": "perspective",
                     "perspective": {"aspectRatio": 1.0, "yfov": math.radians(yfov_deg),
                                     "znear": znear, "zfar": zfar}})
        q = look_at_quat(eye, target, up)
        return self.node(name, camera=len(cams) - 1, translation=eye, rotation=q)

    def point_light_node(self, name, intensity, color=(1.0, 1.0, 1.0), translation=None):
        """A KHR_lights_punctual point light (intensity x color = radiant
        intensity, W/sr, no range) on its own node."""
        ext = self.doc.setdefault("extensions", {}).setdefault("KHR_lights_punctual",
                                                                {"lights": []})
        ext["lights"].append({"name": name, "type": "point",
                              "color": [float(c) for c in color],
                              "intensity": float(intensity)})
        self.ext_used.add("KHR_lights_punctual")
        nd = self.node(name, translation=translation)
        self.doc["nodes"][nd]["extensions"] = {
            "KHR_lights_punctual": {"light": len(ext["lights"]) - 1}}
        return nd

    def animation(self, name, channels):
        """channels: list of (node, path, times, flat values)."""
        samplers, chans = [], []
        time_acc = {}
        for node, path, times, values in channels:
            key = tuple(times)
            if key not in time_acc:
                time_acc[key] = self.float_accessor(times, "SCALAR", target=None, minmax=True)
            typ = {"rotation": "VEC4", "weights": "SCALAR"}.get(path, "VEC3")
            out = self.float_accessor(values, typ, target=None)
            samplers.append({"input": time_acc[key], "interpolation": "LINEAR", "output": out})
            chans.append({"sampler": len(samplers) - 1, "target": {"node": node, "path": path}})
        anims = self._list("animations")
        anims.append({"name": name, "channels": chans, "samplers": samplers})

    def scene(self, name, nodes, extras=None):
        sc = {"name": name, "nodes": list(nodes)}
        if extras:
            sc["extras"] = extras
        self.doc["scenes"] = [sc]
        self.doc["scene"] = 0

    # -- output ------------------------------------------------------------
    def _finish(self, buffer_uri):
        while len(self.bin) % 4:
            self.bin.append(0)
        buf = {"byteLength": len(self.bin)}
        if buffer_uri:
            buf["uri"] = buffer_uri
        self.doc["buffers"] = [buf]
        if self.ext_used:
            self.doc["extensionsUsed"] = sorted(self.ext_used)
        order = ["asset", "extensionsUsed", "extensions", "scene", "scenes", "nodes", "cameras", "meshes",
                 "materials", "textures", "samplers", "images", "animations", "accessors",
                 "bufferViews", "buffers"]
        return {k: self.doc[k] for k in order if k in self.doc}

    def write_gltf(self, path, bin_name):
        doc = self._finish(bin_name)
        with open(path, "w", encoding="utf-8") as f:
            f.write(json_dumps(doc))
            f.write("\n")
        import os
        with open(os.path.join(os.path.dirname(path), bin_name), "wb") as f:
            f.write(self.bin)

    def write_glb(self, path):
        doc = self._finish(None)
        js = json_dumps(doc).encode("utf-8")
        while len(js) % 4:
            js += b" "
        total = 12 + 8 + len(js) + 8 + len(self.bin)
        with open(path, "wb") as f:
            f.write(struct.pack("<III", 0x46546C67, 2, total))
            f.write(struct.pack("<II", len(js), 0x4E4F534A))
            f.write(js)
            f.write(struct.pack("<II", len(self.bin), 0x004E4942))
            f.write(self.bin)


def _clean(x, digits=9):
    """Rounded to `digits` decimals, without negative zero (tidy JSON)."""
    x = round(float(x), digits)
    return 0.0 if x == 0 else x


def json_dumps(doc):
    """Pretty JSON, but numeric arrays on one line (keeps files short)."""
    text = json.dumps(doc, indent=1, sort_keys=False)
    # collapse arrays that contain only numbers
    import re
    pat = re.compile(r"\[\s*(-?[0-9][-+0-9.eE]*(?:,\s*-?[0-9][-+0-9.eE]*)*)\s*\]")
    return pat.sub(lambda m: "[" + ", ".join(s.strip() for s in m.group(1).split(",")) + "]",
                   text)


def png_rgb8(width, height, pixel_fn):
    """Encode an RGB8 PNG with zlib; pixel_fn(x, y) -> (r, g, b) ints."""
    import zlib
    raw = bytearray()
    for y in range(height):
        raw.append(0)
        for x in range(width):
            raw.extend(pixel_fn(x, y))

    def chunk(tag, data):
        c = struct.pack(">I", len(data)) + tag + data
        return c + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)

    ihdr = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr)
            + chunk(b"IDAT", zlib.compress(bytes(raw), 9)) + chunk(b"IEND", b""))


# -- small vector helpers ----------------------------------------------------
def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def add(a, b):
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def scale(a, s):
    return (a[0] * s, a[1] * s, a[2] * s)


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def norm(a):
    l = math.sqrt(dot(a, a))
    return (a[0] / l, a[1] / l, a[2] / l)


def lerp(a, b, t):
    return (a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t, a[2] + (b[2] - a[2]) * t)


def quat_from_matrix(m):
    """m: rows of a 3x3 rotation matrix -> (x, y, z, w) unit quaternion, w >= 0."""
    tr = m[0][0] + m[1][1] + m[2][2]
    if tr > 0:
        s = math.sqrt(tr + 1.0) * 2
        w, x, y, z = 0.25 * s, (m[2][1] - m[1][2]) / s, (m[0][2] - m[2][0]) / s, (m[1][0] - m[0][1]) / s
    elif m[0][0] > m[1][1] and m[0][0] > m[2][2]:
        s = math.sqrt(1.0 + m[0][0] - m[1][1] - m[2][2]) * 2
        w, x, y, z = (m[2][1] - m[1][2]) / s, 0.25 * s, (m[0][1] + m[1][0]) / s, (m[0][2] + m[2][0]) / s
    elif m[1][1] > m[2][2]:
        s = math.sqrt(1.0 + m[1][1] - m[0][0] - m[2][2]) * 2
        w, x, y, z = (m[0][2] - m[2][0]) / s, (m[0][1] + m[1][0]) / s, 0.25 * s, (m[1][2] + m[2][1]) / s
    else:
        s = math.sqrt(1.0 + m[2][2] - m[0][0] - m[1][1]) * 2
        w, x, y, z = (m[1][0] - m[0][1]) / s, (m[0][2] + m[2][0]) / s, (m[1][2] + m[2][1]) / s, 0.25 * s
    if w < 0:
        x, y, z, w = -x, -y, -z, -w
    l = math.sqrt(x * x + y * y + z * z + w * w)
    return (x / l, y / l, z / l, w / l)


def look_at_quat(eye, target, up=(0.0, 1.0, 0.0)):
    """Rotation taking the camera's local -Z to (target - eye) and +Y towards up."""
    f = norm(sub(target, eye))
    r = norm(cross(f, up))
    u = cross(r, f)
    z = scale(f, -1.0)
    # columns are the local axes expressed in world space
    m = [[r[0], u[0], z[0]], [r[1], u[1], z[1]], [r[2], u[2], z[2]]]
    return quat_from_matrix(m)


def quat_axis_angle(axis, angle_rad):
    a = norm(axis)
    s = math.sin(angle_rad / 2)
    return (a[0] * s, a[1] * s, a[2] * s, math.cos(angle_rad / 2))


def quat_rotate(q, v):
    x, y, z, w = q
    u = (x, y, z)
    t = scale(cross(u, v), 2.0)
    return add(add(v, scale(t, w)), cross(u, t))
