#!/usr/bin/env python3
"""Where a model.slod's bytes are: one row per section (docs/formats.md, "model.slod").

    scripts/bench/slod_sections.py MODEL.slod [--ply INPUT.ply] [--markdown]

Reads format 2 (plain body) and format 3 (the body in packed parts: the stored size of
each part beside its plain size). --ply adds the model/PLY ratio."""
import argparse
import os
import struct
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
    stored = None
    if version == 3:
        count = struct.unpack_from("<I", body, 4)[0]
        table = [struct.unpack_from("<QQBBHI", body, 8 + 24 * i) for i in range(count)]
        stored = [t[1] for t in table]
        plain_size = sum(t[0] for t in table)
        # The plain body is only needed for the counts: its first parts suffice, but the
        # sizes come from the table, so rebuild them from the plain sizes instead.
        raw_sizes = [t[0] for t in table]
    elif version != 2:
        sys.exit(f"{a.model}: format version {version} (this script reads 2 and 3)")
    if stored is None:
        rows, counts = sections(body)
    else:
        rows = [(f"part {i}", 0, s) for i, s in enumerate(raw_sizes)]
        counts = {}
        names = os.environ.get("SLOD_PART_NAMES")
        if names:
            rows = [(nm, 0, s) for nm, s in zip(names.split(","), raw_sizes)]
    total_plain = sum(r[2] for r in rows) + 32
    ply = os.path.getsize(a.ply) if a.ply else None
    if a.markdown:
        print("| section | bytes | share |" + (" stored | ratio |" if stored else ""))
        print("|---|---:|---:|" + ("---:|---:|" if stored else ""))
    for i, (name, _, size) in enumerate(rows):
        share = 100.0 * size / total_plain
        extra = ""
        if stored:
            extra = f" {stored[i]:>12} {size / max(stored[i], 1):6.1f}x"
        if a.markdown:
            extra = extra.split()
            print(f"| {name} | {size} | {share:.1f} % |" +
                  (f" {extra[0]} | {extra[1]} |" if stored else ""))
        else:
            print(f"{name:24} {size:>12} {share:5.1f} %{extra}")
    print(f"file {len(data)} bytes (plain {total_plain})" +
          (f", PLY {ply} bytes: model/PLY {len(data) / ply:.2f}, plain/PLY {total_plain / ply:.2f}"
           if ply else "") + (f"; {counts}" if counts else ""))


if __name__ == "__main__":
    main()
