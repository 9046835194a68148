"""glb_views.py A.glb B.glb: 0 when every bufferView of A holds the same bytes as B's view
of the same index (for a meshopt view: the compressed stream), and B's primitive has the
same attributes and indices as A's: B is A plus what B adds after (a morph target). Prints
the number of views compared. For the morph tests: weight 0 of a level's GLB is the level
byte for byte."""
import json
import struct
import sys


def load(path):
    d = open(path, "rb").read()
    n = struct.unpack("<I", d[12:16])[0]
    j = json.loads(d[20:20 + n])
    return j, d[28 + n:]


def view_bytes(j, b, i):
    v = j["bufferViews"][i]
    e = v.get("extensions", {}).get("EXT_meshopt_compression")
    if e:
        return b[e["byteOffset"]:e["byteOffset"] + e["byteLength"]]
    return b[v.get("byteOffset", 0):v.get("byteOffset", 0) + v["byteLength"]]


(ja, ba), (jb, bb) = load(sys.argv[1]), load(sys.argv[2])
pa, pb = ja["meshes"][0]["primitives"][0], jb["meshes"][0]["primitives"][0]
same = pa["attributes"] == pb["attributes"] and pa["indices"] == pb["indices"] and \
    pa.get("extensions") == pb.get("extensions") and ja["nodes"] == jb["nodes"] and \
    all(ja["accessors"][i] == jb["accessors"][i] for i in range(len(ja["accessors"])))
views = len(ja["bufferViews"])
same = same and all(view_bytes(ja, ba, i) == view_bytes(jb, bb, i) for i in range(views))
print(views)
sys.exit(0 if same else 1)
