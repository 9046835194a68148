"""Phase shapes: `scanlod plan` against the run on hostile shapes (issue 34 item 5).

The plan's cost lines are fitted on smooth surfaces; a scan of thin slivers or a triangle
soup needs many times their samples per triangle, and the plan reads such a scan's
geometry to see it (cli/plan_shape.c). Per shape, `gen_surface` makes it (slivers:
--aspect 16, triangles 16 times longer than wide; soup: --soup, triangles that share no
vertex), `scanlod plan --json` and one `scanlod run` at 2 threads (default config but
export.fidelity=false) follow, and the item's peak RSS, time and samples are set against
the plan's. Full: 500,000 slivers and a 20,000-triangle soup (the sizes of issue 34);
quick: 100,000 and 5,000.
Writes RESULTS/shapes.json: {"shapes": [{"name", "args", "triangles", "plan", "samples",
"stages"}]}.
"""
import json
import sys

from common import Collection, Ctx, log, run

FULL = [("slivers", ["--aspect", "16"], 500000), ("soup", ["--soup"], 20000)]
QUICK = [("slivers", ["--aspect", "16"], 100000), ("soup", ["--soup"], 5000)]


def main():
    ctx = Ctx(sys.argv[1])
    out = {"shapes": []}
    for name, args, triangles in (QUICK if ctx.quick else FULL):
        c = Collection(ctx.scratch_dir("shapes", name), name)
        gen = json.loads(run([ctx.tool("gen_surface"), "--triangles", triangles] + args +
                             ["-o", c.ply]))
        overrides = ["export.fidelity=false"]
        plan = json.loads(run([ctx.scanlod, "plan", c.config, "--threads", "2", "--json",
                               "-s", overrides[0]]))["items"][0]
        log("shapes: %s, %d triangles" % (name, gen["triangles"]))
        stages = c.run(ctx, 2, overrides)
        with open(c.path("out", c.item_id, "report.json")) as f:
            samples = json.load(f)["stages"]["samples"]["samples"]
        out["shapes"].append({"name": name, "args": args, "triangles": gen["triangles"],
                              "plan": plan, "samples": samples, "stages": stages})
        c.clean()
        ctx.save("shapes", out)
    ctx.save("shapes", out)


if __name__ == "__main__":
    main()
