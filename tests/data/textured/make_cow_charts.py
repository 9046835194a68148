#!/usr/bin/env python3
"""Makes cow_charts.obj, cow_charts.mtl and cow_charts.png (tests/data/README.md, "Made
here"): a textured scan whose texture is an atlas of charts with seams, as photogrammetry
software writes them, for the tests of texture coordinates projected from the input's.

The geometry is tests/data/scans/cow.ply unchanged (CGAL's cow, credited there). Each
triangle goes to one of six charts by the axis its normal points along most (+x, -x, +y,
-y, +z, -z); a chart's texture coordinates are the planar projection of its triangles'
corners along that axis, scaled into one tile of a 3 x 2 atlas (128 x 128 pixels a tile,
8 pixels of margin). So a vertex on the border of two charts has two texture coordinates
(the OBJ's `f v/vt` corners differ): 2,904 vertices, more texture coordinates. The atlas
is drawn in each chart's plane: a board of squares 1/8 of the cow's extent wide, each
chart in its own two colours, so a picture of a level shows the wrong chart's colours
wherever a triangle reads across a seam. Run from this folder: python3 make_cow_charts.py
"""
import struct
import zlib

TILE, MARGIN, COLS, ROWS = 128, 8, 3, 2
COLOURS = [((220, 40, 40), (250, 200, 190)), ((40, 170, 60), (190, 240, 190)),
           ((40, 80, 210), (190, 200, 250)), ((235, 200, 40), (120, 90, 20)),
           ((200, 60, 200), (250, 200, 250)), ((40, 200, 210), (20, 80, 90))]
SQUARES = 8  # squares across the cow's largest extent


def read_cow():
    data = open("../scans/cow.ply", "rb").read()
    body = data[data.index(b"end_header\n") + 11:]
    nv, nf = 2904, 5804
    v = [struct.unpack_from("<3f", body, 12 * i) for i in range(nv)]
    at, f = 12 * nv, []
    for _ in range(nf):
        assert body[at] == 3
        f.append(struct.unpack_from("<3i", body, at + 1))
        at += 13
    return v, f


def chart_of(v, tri):
    a, b, c = (v[i] for i in tri)
    e1 = [b[k] - a[k] for k in range(3)]
    e2 = [c[k] - a[k] for k in range(3)]
    n = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]]
    axis = max(range(3), key=lambda k: abs(n[k]))
    return 2 * axis + (n[axis] < 0)


def plane(chart, p):
    """The chart's two plane coordinates of point p (the axes other than its own)."""
    axis = chart // 2
    return [p[k] for k in range(3) if k != axis]


def main():
    v, f = read_cow()
    lo = [min(p[k] for p in v) for k in range(3)]
    hi = [max(p[k] for p in v) for k in range(3)]
    extent = max(hi[k] - lo[k] for k in range(3))
    inner = TILE - 2 * MARGIN
    width, height = COLS * TILE, ROWS * TILE

    def to_uv(chart, p):
        axis = chart // 2
        a, b = plane(chart, p)
        ka, kb = [k for k in range(3) if k != axis]
        x = (chart % COLS) * TILE + MARGIN + (a - lo[ka]) / extent * inner
        y = (chart // COLS) * TILE + MARGIN + (b - lo[kb]) / extent * inner
        return x / width, 1 - y / height  # OpenGL convention: v up

    uvs, corners = {}, []
    for tri in f:
        ch = chart_of(v, tri)
        row = []
        for i in tri:
            key = (i, ch)
            if key not in uvs:
                uvs[key] = (len(uvs), to_uv(ch, v[i]))
            row.append((i, uvs[key][0]))
        corners.append(row)
    with open("cow_charts.obj", "w") as out:
        out.write("# tests/data/scans/cow.ply with a six-chart atlas made here (make_cow_charts.py)\n"
                  "mtllib cow_charts.mtl\n")
        for p in v:
            out.write("v %.6f %.6f %.6f\n" % p)
        for _, (u, t) in sorted(uvs.values()):
            out.write("vt %.6f %.6f\n" % (u, t))
        out.write("usemtl charts\n")
        for row in corners:
            out.write("f " + " ".join("%d/%d" % (i + 1, t + 1) for i, t in row) + "\n")
    with open("cow_charts.mtl", "w") as out:
        out.write("newmtl charts\nKd 1 1 1\nmap_Kd cow_charts.png\n")
    rows = []
    for y in range(height):
        row = bytearray()
        for x in range(width):
            chart = (y // TILE) * COLS + x // TILE
            # the board in the chart's plane: squares of extent / SQUARES
            a = ((x % TILE) - MARGIN) / inner * SQUARES
            b = ((y % TILE) - MARGIN) / inner * SQUARES
            row += bytes(COLOURS[chart][(int(a // 1) + int(b // 1)) % 2])
        rows.append(bytes(row))
    raw = b"".join(b"\0" + r for r in rows)
    chunk = lambda t, d: struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d))
    with open("cow_charts.png", "wb") as out:
        out.write(b"\x89PNG\r\n\x1a\n")
        out.write(chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)))
        out.write(chunk(b"IDAT", zlib.compress(raw, 9)))
        out.write(chunk(b"IEND", b""))


if __name__ == "__main__":
    main()
