#!/usr/bin/env python3
"""The hand-made findings of tests/fuzz/corpus/slod from its tiny-error seed (README.md):

    tests/fuzz/make_slod_mutants.py tests/fuzz/corpus/slod

crossing-far-outside  the first crossing's x at 3.4e38 (normals once overflowed)
grid-beyond-limit     a leaf of 1e16 units (beyond SL_OCTREE_MAX_EXTENT)
collapsed-grid        a leaf of 1e-30 at (1, 1, 1), every crossing on the origin or the
                      next float up (the normal scale once overflowed to NaN)
vertex-range-overrun  from tiny-qef: the root's vertex range ending far past the table,
                      the next node's back in it (the reader once read the root's
                      vertices before it saw the ranges out of order)
packed-truncated-frame  from tiny-packed (format 3, runtime/lod_pack.h): its largest frame
                      cut by 9 bytes, the table's stored size with it
packed-size-lie       the same frame declaring one plain byte more than it holds
packed-huge-piece     the same frame declaring 2^38 plain bytes (refused unallocated)
packed-garbage        the same frame's blocks overwritten, its header kept
Rerun after the seeds are regenerated for a new octree format (octree section layout:
runtime/octree_io.h; tiny-packed: SCANLOD_SLOD_SEED_DIR=dir build/tests/test_lod_pack)."""
import math
import os
import struct
import sys

HEADER = 288  # octree section header of format 2
d = sys.argv[1]
seed = open(os.path.join(d, "tiny-error"), "rb").read()
nodes, crossings = struct.unpack_from("<II", seed, 4)[0], struct.unpack_from("<I", seed, 8)[0]
node_crossings = struct.unpack_from("<Q", seed, 16)[0]
positions = HEADER + 32 * nodes + 4 * node_crossings


def write(name, body):
    with open(os.path.join(d, name), "wb") as f:
        f.write(body)


b = bytearray(seed)
struct.pack_into("<f", b, positions, 3.4e38)
write("crossing-far-outside", b)
b = bytearray(seed)
struct.pack_into("<d", b, 24, 1e16)
write("grid-beyond-limit", b)
b = bytearray(seed)
struct.pack_into("<d", b, 24, 1e-30)
struct.pack_into("<ddd", b, 32, 1.0, 1.0, 1.0)
up = struct.unpack("<f", struct.pack("<I", 0x3f800001))[0]  # the next float after 1.0
for i in range(3 * crossings):
    x = struct.unpack_from("<f", seed, positions + 4 * i)[0]
    struct.pack_into("<f", b, positions + 4 * i, up if x > math.floor(x) + 0.5 else 1.0)
write("collapsed-grid", b)

dual = open(os.path.join(d, "tiny-qef"), "rb").read()
n, cc = struct.unpack_from("<II", dual, 4)
colour = 4 if struct.unpack_from("<I", dual, 12)[0] else 0
ncc = struct.unpack_from("<Q", dual, 16)[0]
vertex_first = HEADER + 32 * n + 4 * ncc + (12 + colour) * cc
b = bytearray(dual)
struct.pack_into("<I", b, vertex_first + 4, 0x00ffffff)
write("vertex-range-overrun", b)

# Format 3's packed parts: 8-byte head (magic, piece count), 24-byte entries (u64 plain,
# u64 stored, u8 codec, u8 filter, u16 record, u32 0), then the stored pieces.
packed = open(os.path.join(d, "tiny-packed"), "rb").read()
count = struct.unpack_from("<I", packed, 4)[0]
at, best, best_at = 8 + 24 * count, None, 0
for i in range(count):
    plain, stored, codec = struct.unpack_from("<QQB", packed, 8 + 24 * i)
    if codec == 1 and (best is None or stored > best[2]):
        best, best_at = (i, plain, stored), at
    at += stored
i, plain, stored = best
entry = 8 + 24 * i
b = bytearray(packed)
struct.pack_into("<Q", b, entry + 8, stored - 9)
del b[best_at + stored - 9:best_at + stored]
write("packed-truncated-frame", b)
b = bytearray(packed)
struct.pack_into("<Q", b, entry, plain + 1)
write("packed-size-lie", b)
struct.pack_into("<Q", b, entry, 1 << 38)
write("packed-huge-piece", b)
b = bytearray(packed)
for j in range(12, stored - 4):
    b[best_at + j] = (j * 2654435761 >> 11) & 0xff
write("packed-garbage", b)
