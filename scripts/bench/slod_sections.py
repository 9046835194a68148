#!/usr/bin/env python3
"""Where a model.slod's bytes are: one row per section (docs/formats.md, "model.slod").

    scripts/bench/slod_sections.py MODEL.slod [--ply INPUT.ply] [--markdown]

Reads format 2 (plain body) and formats 3 to 5 (the body in packed pieces: each section's
plain and stored bytes; needs the zstd command for the two header pieces; 4 is 3 without the
node errors and areas; 5 stores every section in LOD order, 4 bytes a node, the crossing
ids coded, with the surface counts and checked pieces). --ply adds the
model/PLY ratio."""
import argparse
import os
import struct
import subprocess
import sys

OCTREE_HEADER = 288
LOD_HEADER = 24


def sections(body):
    """(name, offset, size) of every section of a plain (format 2) body."""
    depth, n, cc, colour, ncc = struct.unpack_from("<IIIIQ", body, 0)
    vc, flags = struct.unpack_from("<II", body, 272)
    col = 4 if colour else 0
    out, at = [], 0

    def add(name, size):
        nonlocal at
        out.append((name, at, size))
        at += size

    add("octree header", OCTREE_HEADER)
    add("nodes", 32 * n)
    add("node crossings", 4 * ncc)
    add("crossing positions", 12 * cc)
    if col:
        add("crossing colours", 4 * cc)
    if flags & 1:
        add("vertex ranges", 4 * (n + 1))
        add("qef vertex positions", 12 * vc)
        if col:
            add("qef vertex colours", 4 * vc)
        if not flags & 2:  # model format 4 leaves them out (flag 2)
            add("node errors", 4 * n)
            add("node areas", 4 * n)
    e, n2, nbc, tc = struct.unpack_from("<IIQQ", body, at)
    add("LOD header", LOD_HEADER)
    add("LOD array", 4 * e)
    add("accumulation", 8 * (e + 1))
    add("error after", 4 * (e + 1))
    add("neighbour masks", 4 * n)
    add("neighbour bases", 4 * n)
    add("neighbour indices", 4 * nbc)
    add("transition bases", 4 * n)
    add("transition words", 4 * tc)
    if at != len(body):
        sys.exit(f"body of {len(body)} bytes, sections add up to {at}")
    return out, dict(nodes=n, crossings=cc, vertices=vc, expansions=e)


def piece_bytes(body, entry, at):
    """The plain bytes of a piece that is stored as is or in a zstd frame with no filter."""
    plain, stored, codec, filt = struct.unpack_from("<QQBB", body, entry)
    data = body[at:at + stored]
    if codec == 1:
        data = subprocess.run(["zstd", "-d", "-c", "-q"], input=data, capture_output=True,
                              check=True).stdout
    if filt != 0:
        sys.exit("a header piece with a filter: not what format 3 writes")
    return data


def packed_sections(body, version):
    """(name, plain bytes, stored bytes) per section of a packed (format 3 to 5) body: the
    pieces are cut per section, in the plain body's order (the neighbour table left out)."""
    count = struct.unpack_from("<I", body, 4)[0]
    entries = [8 + 24 * i for i in range(count)]
    offsets, at = [], 8 + 24 * count
    for e in entries:
        offsets.append(at)
        at += struct.unpack_from("<Q", body, e + 8)[0]
    head = piece_bytes(body, entries[0], offsets[0])
    depth, n, cc, colour, ncc = struct.unpack_from("<IIIIQ", head, 0)
    vc, flags = struct.unpack_from("<II", head, 272)
    col = 4 if colour else 0
    node_bytes = 4 if version >= 5 else 32
    names = [("octree header", OCTREE_HEADER), ("nodes", node_bytes * n), ("node crossings", 4 * ncc),
             ("crossing positions", 12 * cc)]
    if col:
        names.append(("crossing colours", 4 * cc))
    if flags & 1:
        names += [("vertex ranges", 4 * (n + 1)), ("qef vertex positions", 12 * vc)]
        if col:
            names.append(("qef vertex colours", 4 * vc))
        if not flags & 2:  # model format 4 leaves them out (flag 2)
            names += [("node errors", 4 * n), ("node areas", 4 * n)]
    rows, k = [], 0

    def take(name, size):
        nonlocal k
        stored = 0
        left = size
        while left > 0:
            plain, st = struct.unpack_from("<QQ", body, entries[k])
            left -= plain
            stored += st
            k += 1
        rows.append((name, size, stored))

    for name, size in names:
        take(name, size)
    lod = piece_bytes(body, entries[k], offsets[k])
    e, _, nbc, tc = struct.unpack_from("<IIQQ", lod, 0)
    lod_sections = [("LOD header", LOD_HEADER if version < 5 else 64), ("LOD array", 4 * e),
                    ("accumulation", 8 * (e + 1)), ("error after", 4 * (e + 1))]
    if version >= 5:
        lod_sections.append(("surface counts", 4 * (e + 1)))
    for name, size in lod_sections + [("transition bases", 4 * n),
                                      ("transition words", 4 * tc)]:
        take(name, size)
    rows.append(("neighbour table (rebuilt on reading)", 0, 0))
    return rows


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("model")
    ap.add_argument("--ply")
    ap.add_argument("--markdown", action="store_true")
    a = ap.parse_args()
    data = open(a.model, "rb").read()
    if data[:8] != b"SLODMODL":
        sys.exit(f"{a.model}: not a model.slod")
    version = struct.unpack_from("<I", data, 8)[0]
    body = data[32:]
    if version in (3, 4, 5):
        rows = packed_sections(body, version)
    elif version == 2:
        rows = [(name, size, size) for name, _, size in sections(body)[0]]
    else:
        sys.exit(f"{a.model}: format version {version} (this script reads 2 to 5)")
    plain = sum(r[1] for r in rows)
    ply = os.path.getsize(a.ply) if a.ply else None
    if a.markdown:
        print("| section | plain bytes | stored bytes | share of the file |")
        print("|---|---:|---:|---:|")
    for name, size, stored in rows:
        share = 100.0 * stored / len(data)
        if a.markdown:
            print(f"| {name} | {size} | {stored} | {share:.1f} % |")
        else:
            print(f"{name:38} {size:>12} {stored:>12} {share:5.1f} %")
    print(f"file {len(data)} bytes (plain body {plain})" +
          (f", PLY {ply} bytes: model/PLY {len(data) / ply:.2f}" if ply else ""))


if __name__ == "__main__":
    main()
