"""Phase 0: one reference build per input with the default config (fidelity on, 2 threads).

Its published report.json gives Table 1 (LOD levels with RMS/Hausdorff) and the leaf
size the OpenVDB peer must match; its model.slod, lod100.ply and octree.slot feed the
octree and LOD phases. Kept in SCRATCH/models/ITEM/ until the run ends.
Writes RESULTS/models.json: {item: {input facts, leaf_size, depth, report, paths}}.
"""
import os
import sys

from common import Collection, Ctx, input_facts, log, meshopt, vdb


def meshopt_version(v):
    """MESHOPTIMIZER_VERSION is major * 1000 + minor * 10: 180 is 0.18."""
    return "%d.%d" % (v // 1000, (v % 1000) // 10) if isinstance(v, int) else str(v)


def main():
    ctx = Ctx(sys.argv[1])
    out = {}
    for name in ctx.models:
        log("models: reference build of %s" % name)
        c = Collection(ctx.scratch_dir("models", name), name, ctx.input_ply(name))
        timings = c.run(ctx, 2)
        rep = c.report()
        st = rep["stages"]
        facts = input_facts(ctx, name)
        out[name] = {
            "input_triangles": facts["triangles"],
            "open": facts["open"],
            "diagonal": facts["diagonal"],
            "leaf_size": st["samples"]["leaf_size"],
            "depth": st["samples"]["depth"],
            "samples": st["samples"]["samples"],
            "finest_triangles": st["export"]["triangles_finest"],
            "levels": st["export"]["levels"],
            "timings": timings,
            "slod": c.path("out", c.item_id, "model.slod"),
            "finest_ply": c.path("out", c.item_id, "lod100.ply"),
            "octree": c.artifact("merge", "octree.slot"),
        }
        for key in ("slod", "finest_ply", "octree"):
            if not os.path.exists(out[name][key]):
                raise RuntimeError("%s: no %s at %s" % (name, key, out[name][key]))
    # The peers' versions, from one tiny run each.
    probe = ctx.input_ply(ctx.models[0])
    out["_versions"] = {
        "openvdb": vdb(ctx, probe, os.path.join(ctx.scratch, "probe.ply"),
                       out[ctx.models[0]]["leaf_size"] * 8)["version"],
        "meshoptimizer": meshopt_version(meshopt(ctx, probe, [1000])["version"])}
    ctx.save("models", out)


if __name__ == "__main__":
    main()
