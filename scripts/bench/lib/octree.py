"""Phase 2 (issue 4): uniform octree levels against OpenVDB; memory per octree depth.

Fidelity: for each input and level L = 0 (leaf) .. depth of the reference build's
octree.slot, `scanlod extract --level L` and `scanlod compare` against the input; beside
it OpenVDB meshToVolume + volumeToMesh at adaptivity 0 with voxel = the cell size of that
level (leaf_size * 2^L; L = 0 is scanlod's leaf), signed, plus the unsigned variant on
open scans. Levels stop at the first with fewer than 32 triangles.
Memory: on ctx.depth_input at each of ctx.depths, `-s octree.depth=N`, run until merge
has committed (the later stages are not needed), peak RSS and wall time of samples and
merge from their _stats.json, ctx.depth_reps times.
Writes RESULTS/octree.json.
"""
import json
import os
import sys

from common import Collection, Ctx, compare, extract, log, vdb


def levels(ctx, name, m, work):
    rows = []
    ref = ctx.input_ply(name)
    for level in range(0, m["depth"] + 1):
        ply = os.path.join(work, "level%d.ply" % level)
        e = extract(ctx, m["octree"], ply, "--level", level)
        if e["triangles"] < 32:
            break
        cell = m["leaf_size"] * 2 ** level
        row = {"level": level, "cell_size": cell, "triangles": e["triangles"],
               "vertices": e["vertices"], "scanlod": compare(ctx, ref, ply), "vdb": {}}
        variants = ["signed"] + (["unsigned"] if m["open"] else [])
        for v in variants:
            vply = os.path.join(work, "vdb_%s_%d.ply" % (v, level))
            try:
                d = vdb(ctx, ref, vply, cell, 0.0, v == "unsigned", 2)
                row["vdb"][v] = compare(ctx, ref, vply) if d["triangles"] else None
            except RuntimeError as err:   # a peer that fails is a result, not a crash
                log("octree: vdb %s level %d failed: %s" % (v, level, err))
                row["vdb"][v] = None
        rows.append(row)
        log("octree: %s level %d: %d triangles" % (name, level, e["triangles"]))
    return rows


def depth_sweep(ctx):
    name = ctx.depth_input
    c = Collection(ctx.scratch_dir("depth", name), name, ctx.input_ply(name))
    rows = []
    for depth in ctx.depths:
        reps = []
        for rep in range(ctx.depth_reps):
            log("octree: %s depth %d rep %d/%d" % (name, depth, rep + 1, ctx.depth_reps))
            st = c.run_until(ctx, "merge", 2, ["octree.depth=%d" % depth,
                                               "export.fidelity=false"])
            with open(c.artifact("samples", "report.json")) as f:
                sr = json.load(f)
            st["samples_count"] = sr["samples"]
            st["leaf_size"] = sr["leaf_size"]
            reps.append(st)
        rows.append({"depth": depth, "reps": reps})
        c.clean()
    return {"input": name, "rows": rows}


def main():
    ctx = Ctx(sys.argv[1])
    models = ctx.load("models")
    out = {"levels": {}, "depths": None}
    for name in ctx.models:
        out["levels"][name] = levels(ctx, name, models[name],
                                     ctx.scratch_dir("octree", name))
        ctx.save("octree", out)
    out["depths"] = depth_sweep(ctx)
    ctx.save("octree", out)


if __name__ == "__main__":
    main()
