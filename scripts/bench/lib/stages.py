"""Phase 1: scanlod stage by stage, 1 vs 2 threads, beside the OpenVDB remesh.

Each repetition, for each input: a fresh `scanlod run` (work, output and logs removed
first) at 1 and at 2 threads with `-s export.fidelity=false` (the fidelity measurement is
the benchmark's, not the conversion's; Table 1 comes from the reference build), read from
the published timings.json; then OpenVDB meshToVolume + volumeToMesh (adaptivity 0) at
scanlod's leaf size, at 1 and 2 threads (signed; and unsigned on open scans). The order
of the thread counts alternates between repetitions so drift does not favour one.
Writes RESULTS/stages.json: {item: {"scanlod": {threads: [timings per rep]},
"vdb": {variant: {threads: [{"seconds", "peak_rss_kb", ...} per rep]}}}}.
"""
import sys

from common import Collection, Ctx, log, vdb

OVERRIDES = ["export.fidelity=false"]


def main():
    ctx = Ctx(sys.argv[1])
    models = ctx.load("models")
    out = {name: {"scanlod": {"1": [], "2": []}, "vdb": {}} for name in ctx.models}
    for rep in range(ctx.reps):
        order = ["1", "2"] if rep % 2 == 0 else ["2", "1"]
        for name in ctx.models:
            m = models[name]
            c = Collection(ctx.scratch_dir("stages", name), name, ctx.input_ply(name))
            for t in order:
                log("stages: %s rep %d/%d, %s thread(s)" % (name, rep + 1, ctx.reps, t))
                out[name]["scanlod"][t].append(c.run(ctx, t, OVERRIDES))
            c.clean()
            variants = ["signed"] + (["unsigned"] if m["open"] else [])
            for v in variants:
                for t in order:
                    d = vdb(ctx, ctx.input_ply(name), c.path("vdb.ply"), m["leaf_size"],
                            0.0, v == "unsigned", t)
                    keep = {k: d[k] for k in ("seconds", "to_volume_seconds",
                                              "to_mesh_seconds", "peak_rss_kb",
                                              "triangles", "active_voxels")}
                    out[name]["vdb"].setdefault(v, {"1": [], "2": []})[t].append(keep)
        ctx.save("stages", out)   # after every repetition: a partial run still reports
    ctx.save("stages", out)


if __name__ == "__main__":
    main()
