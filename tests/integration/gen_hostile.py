#!/usr/bin/python3
"""Crafted tiny inputs that declare huge sizes (issue 32 item 10), written
at test time by input_limits.cmake: OUT/huge.exr (a 600-byte EXR header
declaring 8,000,000 x 32 float pixels, no pixel data) and OUT/big_tex.gltf
(one small but valid 8192 x 8192 1-bit PNG, all black, listed as two images, each
used by a material: 2 x 8192^2 texels, twice the scene limit).
usage: gen_hostile.py OUT"""
import os
import struct
import sys
import zlib


def attr(name, typ, value):
    return name.encode() + b"\0" + typ.encode() + b"\0" + struct.pack("<i", len(value)) + value


def huge_exr(path, width=8000000, height=32):
    chlist = b"R\0" + struct.pack("<iB3xii", 2, 0, 1, 1) + b"\0"  # FLOAT, 1x1 sampling
    box = struct.pack("<iiii", 0, 0, width - 1, height - 1)
    header = (struct.pack("<ii", 20000630, 2) + attr("channels", "chlist", chlist) +
              attr("compression", "compression", b"\0") + attr("dataWindow", "box2i", box) +
              attr("displayWindow", "box2i", box) + attr("lineOrder", "lineOrder", b"\0") +
              attr("pixelAspectRatio", "float", struct.pack("<f", 1.0)) +
              attr("screenWindowCenter", "v2f", struct.pack("<ff", 0, 0)) +
              attr("screenWindowWidth", "float", struct.pack("<f", 1.0)) + b"\0")
    offsets = b"".join(struct.pack("<Q", len(header) + 8 * height) for _ in range(height))
    with open(path, "wb") as f:
        f.write(header + offsets)


def chunk(kind, data):
    return (struct.pack(">I", len(data)) + kind + data +
            struct.pack(">I", zlib.crc32(kind + data) & 0xffffffff))


def black_png(path, side):
    raw = zlib.compressobj(9)
    row = b"\0" * (side // 8 + 1)  # filter byte 0, then 1-bit grey 0 (least to inflate)
    body = b"".join(raw.compress(row) for _ in range(side)) + raw.flush()
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", side, side, 1, 0, 0, 0, 0)) +
                chunk(b"IDAT", body) + chunk(b"IEND", b""))


def big_texture_scene(path, png):
    # one triangle, two materials with a texture each, each texture its own image
    pos = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0)
    uv = struct.pack("<6f", 0, 0, 1, 0, 0, 1)
    data = (pos + uv).hex()
    gltf = """{"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0, 1]}],
 "nodes": [{"mesh": 0}, {"mesh": 1}],
 "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "material": 0}]},
            {"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "material": 1}]}],
 "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}},
               {"pbrMetallicRoughness": {"baseColorTexture": {"index": 1}}}],
 "textures": [{"source": 0}, {"source": 1}],
 "images": [{"uri": "%s"}, {"uri": "%s"}],
 "buffers": [{"byteLength": 60, "uri": "data:application/octet-stream;base64,%s"}],
 "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                 {"buffer": 0, "byteOffset": 36, "byteLength": 24}],
 "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                "min": [0, 0, 0], "max": [1, 1, 0]},
               {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2"}]}
""" % (png, png, __import__("base64").b64encode(bytes.fromhex(data)).decode())
    with open(path, "w") as f:
        f.write(gltf)


def main():
    out = sys.argv[1]
    os.makedirs(out, exist_ok=True)
    huge_exr(os.path.join(out, "huge.exr"))
    black_png(os.path.join(out, "black8192.png"), 8192)
    big_texture_scene(os.path.join(out, "big_tex.gltf"), "black8192.png")


if __name__ == "__main__":
    main()
