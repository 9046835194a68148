#!/usr/bin/env python3
"""Makes cow_textured.ply and cow_texture.png (tests/data/README.md, "Made here").

The geometry is tests/data/scans/cow.ply unchanged (CGAL's cow, credited there). The
texture is drawn here: an 8 x 8 board of flat squares in 8 saturated colours, 256 x 256
pixels, so that a picture of the textured model can be checked colour by colour. Each
vertex gets per-vertex texture coordinates (texture_u, texture_v) by a planar projection
along z (a side view of the cow: u from x, v from y, OpenGL convention, v = 0 at the
bottom), so both flanks show the board. Run from this folder: python3 make_cow_textured.py
"""
import struct
import zlib

PALETTE = [(220, 40, 40), (40, 170, 60), (40, 80, 210), (235, 200, 40),
           (200, 60, 200), (40, 200, 210), (245, 140, 30), (250, 250, 250)]
SIZE, SQUARES = 256, 8


def board():
    rows = []
    for y in range(SIZE):
        row = bytearray()
        for x in range(SIZE):
            i, j = x * SQUARES // SIZE, y * SQUARES // SIZE
            row += bytes(PALETTE[(i + 3 * j) % len(PALETTE)])
        rows.append(bytes(row))
    return rows


def write_png(path, rows):
    raw = b"".join(b"\0" + r for r in rows)
    chunk = lambda t, d: struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d))
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n")
        f.write(chunk(b"IHDR", struct.pack(">IIBBBBB", SIZE, SIZE, 8, 2, 0, 0, 0)))
        f.write(chunk(b"IDAT", zlib.compress(raw, 9)))
        f.write(chunk(b"IEND", b""))


def main():
    data = open("../scans/cow.ply", "rb").read()
    body = data[data.index(b"end_header\n") + 11:]
    nv, nf = 2904, 5804
    v = [struct.unpack_from("<3f", body, 12 * i) for i in range(nv)]
    faces = body[12 * nv:]
    lo = [min(p[k] for p in v) for k in range(3)]
    hi = [max(p[k] for p in v) for k in range(3)]
    with open("cow_textured.ply", "wb") as f:
        f.write(b"ply\nformat binary_little_endian 1.0\n"
                b"comment tests/data/scans/cow.ply with a texture made here (make_cow_textured.py)\n"
                b"comment TextureFile cow_texture.png\n"
                b"element vertex %d\nproperty float x\nproperty float y\nproperty float z\n"
                b"property float texture_u\nproperty float texture_v\n"
                b"element face %d\nproperty list uchar int vertex_indices\nend_header\n" % (nv, nf))
        for p in v:
            u = (p[0] - lo[0]) / (hi[0] - lo[0])
            t = (p[1] - lo[1]) / (hi[1] - lo[1])
            f.write(struct.pack("<5f", p[0], p[1], p[2], u, t))
        f.write(faces)
    write_png("cow_texture.png", board())


if __name__ == "__main__":
    main()
