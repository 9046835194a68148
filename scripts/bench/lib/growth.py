"""Phase 4: cost growth on synthetic closed surfaces (gen_surface) of ctx.sizes triangles.

Each size: a fresh `scanlod run` (2 threads, default config but export.fidelity=false),
per stage wall time and peak RSS from timings.json; ctx.reps repetitions up to
ctx.growth_full_reps_max triangles, one above (a 20M-triangle run takes minutes). A size
whose predicted time (the previous size's, scaled by the size ratio ^ 1.2) would pass the
run's deadline (ctx.deadline, epoch seconds) is skipped and recorded as skipped, with why.
Before the first repetition, `scanlod plan` of the same collection and overrides is kept
beside the measurement ("plan": its item), and after each the work and published bytes
("disk"), so the report can set the pre-flight estimate against what the run took.
Writes RESULTS/growth.json: {"sizes": [{"target", "triangles", "reps": [timings], "plan",
"disk": [{"work_bytes", "published_bytes"}]}],
"skipped": [{"target", "reason"}]}.
"""
import json
import os
import sys
import time

import stats
from common import Collection, Ctx, log, run, tree_bytes


def main():
    ctx = Ctx(sys.argv[1])
    out = {"sizes": [], "skipped": []}
    prev = None   # (triangles, seconds of one run)
    for target in ctx.sizes:
        reps = ctx.reps if target <= ctx.growth_full_reps_max else 1
        if prev:
            predicted = reps * prev[1] * (target / float(prev[0])) ** 1.2
            left = ctx.deadline - time.time()
            if predicted > left:
                why = ("predicted %.0f s for %d run(s) at %d triangles, %.0f s left of the "
                       "run's time budget" % (predicted, reps, target, max(0, left)))
                log("growth: skipping %d: %s" % (target, why))
                out["skipped"].append({"target": target, "reason": why})
                continue
        name = "surface_%d" % target
        c = Collection(ctx.scratch_dir("growth", name), name)
        gen = json.loads(run([ctx.tool("gen_surface"), "--triangles", target, "-o", c.ply]))
        row = {"target": target, "triangles": gen["triangles"],
               "ply_bytes": os.path.getsize(c.ply), "reps": [], "disk": []}
        overrides = ["export.fidelity=false"]
        plan_cmd = [ctx.scanlod, "plan", c.config, "--threads", "2", "--json"]
        for o in overrides:
            plan_cmd += ["-s", o]
        row["plan"] = json.loads(run(plan_cmd))["items"][0]
        for rep in range(reps):
            log("growth: %d triangles rep %d/%d" % (gen["triangles"], rep + 1, reps))
            t0 = time.time()
            row["reps"].append(c.run(ctx, 2, overrides))
            prev = (gen["triangles"], time.time() - t0)
            row["disk"].append({"work_bytes": tree_bytes(c.path("work")),
                                "published_bytes": tree_bytes(c.path("out", c.item_id))})
        row["stages"] = stats.stage_record(row["reps"])
        out["sizes"].append(row)
        c.clean()
        os.remove(c.ply)
        ctx.save("growth", out)
    ctx.save("growth", out)


if __name__ == "__main__":
    main()
