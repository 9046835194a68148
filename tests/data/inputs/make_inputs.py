#!/usr/bin/env python3
"""Makes the small scan in every input format that the reader tests compare
(tests/data/README.md, "inputs/"). Run from this folder: python3 make_inputs.py

The model is made here, not taken from anywhere: an icosphere (an icosahedron subdivided
once: 42 vertices, 80 triangles, radius 1) with unit normals, a colour per vertex (from
its position) and spherical texture coordinates, and a 16 x 16 PNG texture (a 4 x 4
board of flat colours). sphere.ply is the reference every other file must read back as:
  sphere.ply            ascii PLY: x y z nx ny nz red green blue texture_u texture_v,
                        `comment TextureFile sphere.png`
  sphere.obj/.mtl       v x y z r g b, vt, vn, usemtl, map_Kd sphere.png; the second half
                        of the faces with negative (relative) indices
  sphere.stl            binary STL (facet normals from the corners)
  cube_ascii.stl        an ascii STL: a unit cube, 12 facets
  sphere.off            STCNOFF: x y z, nx ny nz, r g b a (floats), s t
  sphere.xyz            x y z nx ny nz r g b (9 columns)
  sphere.pts            Leica PTS: a count line, then x y z intensity r g b
  sphere.gltf/.bin      glTF 2.0: float POSITION, NORMAL, TEXCOORD_0 (v down), COLOR_0
                        (linear), unsigned short indices, the texture as a file; the mesh
                        under two nodes whose transforms cancel (a TRS parent, a matrix
                        child), so the scene's positions are the model's
  sphere.glb            the same in one GLB, the PNG embedded in the BIN chunk
"""
import json
import math
import struct
import zlib

TEX, SQUARES = 16, 4
PALETTE = [(220, 40, 40), (40, 170, 60), (40, 80, 210), (235, 200, 40),
           (200, 60, 200), (40, 200, 210), (245, 140, 30), (250, 250, 250)]


def icosphere():
    t = (1 + 5 ** 0.5) / 2
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t),
         (0, -1, -t), (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
         (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
         (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    v = [unit(p) for p in v]
    mid = {}

    def middle(a, b):
        key = (min(a, b), max(a, b))
        if key not in mid:
            v.append(unit([(x + y) / 2 for x, y in zip(v[a], v[b])]))
            mid[key] = len(v) - 1
        return mid[key]
    faces = []
    for a, b, c in f:
        ab, bc, ca = middle(a, b), middle(b, c), middle(c, a)
        faces += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
    # Coordinates rounded to 6 decimals, so every text format holds them exactly as written.
    v = [tuple(round(x, 6) for x in p) for p in v]
    return v, faces


def unit(p):
    n = math.sqrt(sum(x * x for x in p))
    return [x / n for x in p]


def attributes(v):
    normals = [tuple(round(x, 6) for x in unit(p)) for p in v]
    colors = [tuple(int(round((x + 1) / 2 * 255)) for x in p) for p in v]
    uvs = [(round(0.5 + math.atan2(p[2], p[0]) / (2 * math.pi), 6),
            round(0.5 + math.asin(max(-1, min(1, p[1]))) / math.pi, 6)) for p in v]
    return normals, colors, uvs


def png(rows, width, height):
    raw = b"".join(b"\0" + r for r in rows)
    chunk = lambda tag, data: (struct.pack(">I", len(data)) + tag + data +
                               struct.pack(">I", zlib.crc32(tag + data) & 0xffffffff))
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def texture():
    rows = []
    for y in range(TEX):
        row = bytearray()
        for x in range(TEX):
            i, j = x * SQUARES // TEX, y * SQUARES // TEX
            row += bytes(PALETTE[(i + 3 * j) % len(PALETTE)])
        rows.append(bytes(row))
    return png(rows, TEX, TEX)


def fmt(x):
    return ("%.6f" % x).rstrip("0").rstrip(".") if x != 0 else "0"


def write_ply(v, f, n, c, uv):
    with open("sphere.ply", "w", newline="\n") as out:
        out.write("ply\nformat ascii 1.0\ncomment made by make_inputs.py\n"
                  "comment TextureFile sphere.png\n")
        out.write("element vertex %d\nproperty float x\nproperty float y\nproperty float z\n"
                  "property float nx\nproperty float ny\nproperty float nz\n"
                  "property uchar red\nproperty uchar green\nproperty uchar blue\n"
                  "property float texture_u\nproperty float texture_v\n" % len(v))
        out.write("element face %d\nproperty list uchar int vertex_indices\nend_header\n" % len(f))
        for p, q, col, t in zip(v, n, c, uv):
            out.write(" ".join(map(fmt, p + q)) + " %d %d %d " % col + " ".join(map(fmt, t)) + "\n")
        for a in f:
            out.write("3 %d %d %d\n" % a)


def write_obj(v, f, n, c, uv):
    with open("sphere.mtl", "w", newline="\n") as out:
        out.write("# made by make_inputs.py\nnewmtl skin\nKd 1 1 1\nmap_Kd sphere.png\n")
    with open("sphere.obj", "w", newline="\n") as out:
        out.write("# made by make_inputs.py\nmtllib sphere.mtl\no sphere\n")
        for p, col in zip(v, c):
            out.write("v " + " ".join(map(fmt, p)) + " " + " ".join(fmt(x / 255) for x in col) + "\n")
        for t in uv:
            out.write("vt " + " ".join(map(fmt, t)) + "\n")
        for q in n:
            out.write("vn " + " ".join(map(fmt, q)) + "\n")
        out.write("usemtl skin\ns off\n")
        for k, a in enumerate(f):
            if k < len(f) // 2:
                out.write("f " + " ".join("%d/%d/%d" % (i + 1, i + 1, i + 1) for i in a) + "\n")
            else:  # relative: -1 is the last vertex defined so far
                out.write("f " + " ".join("%d/%d/%d" % ((i - len(v),) * 3) for i in a) + "\n")


def facet_normal(a, b, c):
    u = [y - x for x, y in zip(a, b)]
    w = [y - x for x, y in zip(a, c)]
    return unit([u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]])


def write_stl(v, f):
    with open("sphere.stl", "wb") as out:
        out.write(b"binary STL of sphere.ply, made by make_inputs.py".ljust(80, b" "))
        out.write(struct.pack("<I", len(f)))
        for a in f:
            p = [v[i] for i in a]
            out.write(struct.pack("<12fH", *facet_normal(*p), *p[0], *p[1], *p[2], 0))
    cube = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]
    quads = [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)]
    with open("cube_ascii.stl", "w", newline="\n") as out:
        out.write("solid cube\n")
        for q in quads:
            for tri in ((q[0], q[1], q[2]), (q[0], q[2], q[3])):
                p = [cube[i] for i in tri]
                out.write("  facet normal %s\n    outer loop\n" % " ".join(map(fmt, facet_normal(*p))))
                for x in p:
                    out.write("      vertex %s\n" % " ".join(map(fmt, x)))
                out.write("    endloop\n  endfacet\n")
        out.write("endsolid cube\n")


def write_off(v, f, n, c, uv):
    with open("sphere.off", "w", newline="\n") as out:
        out.write("STCNOFF\n# made by make_inputs.py\n%d %d 0\n" % (len(v), len(f)))
        for p, q, col, t in zip(v, n, c, uv):
            out.write(" ".join(map(fmt, p + q)) + " " + " ".join(fmt(x / 255) for x in col)
                      + " 1 " + " ".join(map(fmt, t)) + "\n")
        for a in f:
            out.write("3 %d %d %d\n" % a)


def write_points(v, n, c):
    with open("sphere.xyz", "w", newline="\n") as out:
        for p, q, col in zip(v, n, c):
            out.write(" ".join(map(fmt, p + q)) + " %d %d %d\n" % col)
    with open("sphere.pts", "w", newline="\n") as out:
        out.write("%d\n" % len(v))
        for k, (p, col) in enumerate(zip(v, c)):
            out.write(" ".join(map(fmt, p)) + " %d %d %d %d\n" % (((k * 37) % 2048 - 1024,) + col))


def srgb_to_linear(b):
    s = b / 255
    return s / 12.92 if s <= 0.04045 else ((s + 0.055) / 1.055) ** 2.4


def gltf_doc(v, f, n, c, uv, image):
    """The JSON and the binary buffer; `image` = None: the texture is a file."""
    blobs = [struct.pack("<%df" % (3 * len(v)), *sum(v, ())),
             struct.pack("<%df" % (3 * len(v)), *sum(n, ())),
             struct.pack("<%df" % (2 * len(v)), *sum(((t[0], 1 - t[1]) for t in uv), ())),
             struct.pack("<%df" % (3 * len(v)), *(srgb_to_linear(x) for col in c for x in col)),
             struct.pack("<%dH" % (3 * len(f)), *sum(f, ()))]
    if image:
        blobs.append(image)
    views, buf = [], b""
    for b in blobs:
        views.append({"buffer": 0, "byteOffset": len(buf), "byteLength": len(b)})
        buf += b + b"\0" * (-len(b) % 4)
    acc = lambda view, comp, count, typ, **kw: dict(bufferView=view, componentType=comp,
                                                    count=count, type=typ, **kw)
    lo = [min(p[k] for p in v) for k in range(3)]
    hi = [max(p[k] for p in v) for k in range(3)]
    s45 = math.sqrt(0.5)
    # The parent: translate (1, 2, 3) after a quarter turn about y, as TRS; the child: its
    # inverse, as a column-major matrix: R^-1 and -R^-1 (1, 2, 3). R(y, 90) maps x to -z
    # and z to x, so R^-1 maps x to z and z to -x: -R^-1 (1, 2, 3) = (3, -2, -1).
    child = [0, 0, 1, 0, 0, 1, 0, 0, -1, 0, 0, 0, 3, -2, -1, 1]
    doc = {"asset": {"version": "2.0", "generator": "scanlod tests/data/inputs/make_inputs.py"},
           "scene": 0, "scenes": [{"nodes": [0]}],
           "nodes": [{"translation": [1, 2, 3], "rotation": [0, s45, 0, s45], "children": [1]},
                     {"matrix": child, "mesh": 0}],
           "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1,
                                                      "TEXCOORD_0": 2, "COLOR_0": 3},
                                       "indices": 4, "material": 0}]}],
           "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
           "textures": [{"source": 0}],
           "images": [{"bufferView": 5, "mimeType": "image/png"} if image else {"uri": "sphere.png"}],
           "accessors": [acc(0, 5126, len(v), "VEC3", min=lo, max=hi),
                         acc(1, 5126, len(v), "VEC3"), acc(2, 5126, len(v), "VEC2"),
                         acc(3, 5126, len(v), "VEC3"), acc(4, 5123, 3 * len(f), "SCALAR")],
           "bufferViews": views, "buffers": [{"byteLength": len(buf)}]}
    return doc, buf


def write_gltf(v, f, n, c, uv, image):
    doc, buf = gltf_doc(v, f, n, c, uv, None)
    doc["buffers"][0]["uri"] = "sphere.bin"
    with open("sphere.gltf", "w", newline="\n") as out:
        json.dump(doc, out, indent=1)
        out.write("\n")
    with open("sphere.bin", "wb") as out:
        out.write(buf)
    doc, buf = gltf_doc(v, f, n, c, uv, image)
    text = json.dumps(doc, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    with open("sphere.glb", "wb") as out:
        out.write(struct.pack("<III", 0x46546C67, 2, 12 + 8 + len(text) + 8 + len(buf)))
        out.write(struct.pack("<II", len(text), 0x4E4F534A) + text)
        out.write(struct.pack("<II", len(buf), 0x004E4942) + buf)


def main():
    v, f = icosphere()
    n, c, uv = attributes(v)
    image = texture()
    with open("sphere.png", "wb") as out:
        out.write(image)
    write_ply(v, f, n, c, uv)
    write_obj(v, f, n, c, uv)
    write_stl(v, f)
    write_off(v, f, n, c, uv)
    write_points(v, n, c)
    write_gltf(v, f, n, c, uv, image)


if __name__ == "__main__":
    main()
