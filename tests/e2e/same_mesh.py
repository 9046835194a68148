#!/usr/bin/env python3
"""same_mesh.py A.ply B.ply: exit 0 when two binary little-endian PLY meshes have the same
vertex positions and the same triangles, in the same order (normals and colours are not
compared: the export draws normals from each level's faces, a cut from its cells). Prints
what differs otherwise."""
import struct
import sys

SIZES = {"char": "b", "uchar": "B", "short": "h", "ushort": "H", "int": "i", "uint": "I",
         "float": "f", "double": "d", "int8": "b", "uint8": "B", "int16": "h", "uint16": "H",
         "int32": "i", "uint32": "I", "float32": "f", "float64": "d"}


def read(path):
    data = open(path, "rb").read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    elements = []
    for line in data[:end].decode("ascii").splitlines():
        w = line.split()
        if w[0] == "format" and w[1] != "binary_little_endian":
            sys.exit("%s: not binary little-endian" % path)
        if w[0] == "element":
            elements.append((w[1], int(w[2]), []))
        elif w[0] == "property":
            elements[-1][2].append(w[1:])
    at, positions, faces = end, [], []
    for name, count, props in elements:
        for _ in range(count):
            row = {}
            for p in props:
                if p[0] == "list":
                    n = struct.unpack_from("<" + SIZES[p[1]], data, at)[0]
                    at += struct.calcsize(SIZES[p[1]])
                    fmt = "<%d%s" % (n, SIZES[p[2]])
                    row[p[3]] = struct.unpack_from(fmt, data, at)
                    at += struct.calcsize(fmt)
                else:
                    row[p[1]] = struct.unpack_from("<" + SIZES[p[0]], data, at)[0]
                    at += struct.calcsize(SIZES[p[0]])
            if name == "vertex":
                positions.append((row["x"], row["y"], row["z"]))
            elif name == "face":
                faces.append(tuple(row.get("vertex_indices", row.get("vertex_index", ()))))
    return positions, faces


a, b = read(sys.argv[1]), read(sys.argv[2])
if a[0] != b[0]:
    sys.exit("positions differ (%d and %d vertices)" % (len(a[0]), len(b[0])))
if a[1] != b[1]:
    sys.exit("triangles differ (%d and %d)" % (len(a[1]), len(b[1])))
