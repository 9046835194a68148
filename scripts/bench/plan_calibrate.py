#!/usr/bin/env python3
"""Fits `scanlod plan`'s cost model (cli/plan.c) on this machine's own runs.

    scripts/bench/plan_calibrate.py [--build build] [--sizes 100000,300000,1000000]
                                    [--methods octree,cluster,segment] [--out DIR]
                                    [--shapes 200000,20000]

For every method and size: a gen_surface torus of that many triangles, one `scanlod run`
at 2 threads with fidelity off and one with fidelity on (the export stage's cost differs),
per stage wall seconds and peak RSS from the published timings.json, and the work and
published bytes. Then per stage a least-squares line seconds = a + b * N/1e6 and
MB = c + d * N/1e6 (N = triangles), printed as the C table cli/plan.c holds, with each
run's plan/measured ratio under the fitted model. Copy the table in by hand: the model is
source, reviewed like code. Takes about 10 minutes at the default sizes on 2 cores.

--shapes SLIVERS,SOUP (issue 34): instead, the octree stages' k and share (cli/plan.c):
one run each of gen_surface --aspect 16 at SLIVERS triangles and --soup at SOUP, and per
stage the share of d that follows the samples (from the slivers, whose scattered share is
about 0) and k (from the soup, about 1) that would make the plan's current line meet the
measured peak, beside the plan's own ratio. About 5 minutes at 200000,20000.
"""
import re
import argparse
import json
import os
import shutil
import subprocess
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "lib"))
from common import tree_bytes  # noqa: E402


# The whole pipeline's 1 -> 2 thread speed-up (docs/benchmarks.md section 1: 1.2-1.4).
QUIET_SPEEDUP = 1.3


def run(cmd, cwd=None):
    p = subprocess.run([str(c) for c in cmd], cwd=cwd, stdout=subprocess.PIPE,
                       stderr=subprocess.PIPE, text=True)
    if p.returncode != 0:
        raise SystemExit("%s: exit %d: %s" % (" ".join(map(str, cmd)), p.returncode,
                                               p.stderr[-800:]))
    return p.stdout


def fit(xs, ys):
    """Least squares y = a + b x; a kept >= 0 (a stage never takes negative time)."""
    n = len(xs)
    mx, my = sum(xs) / n, sum(ys) / n
    sxx = sum((x - mx) ** 2 for x in xs)
    b = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sxx if sxx else 0.0
    a = my - b * mx
    if a < 0:
        a, b = 0.0, sum(x * y for x, y in zip(xs, ys)) / sum(x * x for x in xs)
    return a, b


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--build", default="build")
    ap.add_argument("--sizes", default="100000,300000,1000000")
    ap.add_argument("--methods", default="octree,cluster,segment")
    ap.add_argument("--out", default=None, help="scratch folder (default BUILD/plan-calibrate)")
    ap.add_argument("--shapes", default=None, help="SLIVERS,SOUP triangles: fit k and share")
    args = ap.parse_args()
    scanlod = os.path.abspath(os.path.join(args.build, "cli", "scanlod"))
    gen = os.path.abspath(os.path.join(args.build, "scripts", "bench", "gen_surface"))
    root = os.path.abspath(args.out or os.path.join(args.build, "plan-calibrate"))
    if args.shapes:
        return fit_shapes(scanlod, gen, root, [int(x) for x in args.shapes.split(",")])
    sizes = [int(s) for s in args.sizes.split(",")]
    samples = {}   # stage key -> [(N/1e6, seconds, MB)]
    disk = []      # (N/1e6, work MB, published MB)
    runs = []
    for method in args.methods.split(","):
        for size in sizes:
            d = os.path.join(root, "%s_%d" % (method, size))
            shutil.rmtree(d, ignore_errors=True)
            os.makedirs(os.path.join(d, "in"))
            ply = os.path.join(d, "in", "surface.ply")
            tris = json.loads(run([gen, "--triangles", size, "-o", ply]))["triangles"]
            with open(os.path.join(d, "run.ini"), "w") as f:
                f.write("[run]\ninput = in\nwork = work\noutput = out\nlogs = logs\n"
                        "[lod]\nmethod = %s\n" % method)
            for fidelity in ("false", "true"):
                for sub in ("work", "out", "logs"):
                    shutil.rmtree(os.path.join(d, sub), ignore_errors=True)
                sys.stderr.write("plan_calibrate: %s %d triangles, fidelity %s\n"
                                 % (method, tris, fidelity))
                overrides = ["-s", "export.fidelity=" + fidelity]
                run([scanlod, "run", os.path.join(d, "run.ini"), "--threads", "2", "-q"]
                    + overrides)
                with open(os.path.join(d, "out", "surface.ply", "timings.json")) as f:
                    stages = json.load(f)["stages"]
                x = tris / 1e6
                for name, t in stages.items():
                    key = "export+fidelity" if name == "export" and fidelity == "true" else name
                    if name == "export" or fidelity == "false":
                        samples.setdefault(key, []).append(
                            (x, t["seconds"], t["peak_rss_kb"] / 1024.0, t["cpu_seconds"]))
                if fidelity == "false":
                    disk.append((x, tree_bytes(os.path.join(d, "work")) / 1e6,
                                 tree_bytes(os.path.join(d, "out", "surface.ply")) / 1e6))
                plan = json.loads(run([scanlod, "plan", os.path.join(d, "run.ini"),
                                       "--threads", "2", "--json"] + overrides))["items"][0]
                runs.append((method, tris, fidelity, plan, stages))
            shutil.rmtree(d, ignore_errors=True)
    # Time as {a, b, e}: a line (e = 1) through wall seconds, and beside it the same fit of
    # CPU seconds / QUIET_SPEEDUP, what the wall time would be on a quiet machine: a busy
    # one stretches wall time, not CPU time. Memory as {c, d, f}: a line (f = 1).
    print("static const stage_cost mesh_costs[] = {  /* wall-clock fit */")
    for key, rows in samples.items():
        xs = [r[0] for r in rows]
        a, b = fit(xs, [r[1] for r in rows])
        c, dd = fit(xs, [r[2] for r in rows])
        qa, qb = fit(xs, [r[3] / QUIET_SPEEDUP for r in rows])
        print('    {"%s", %.3g, %.3g, 1, %.3g, %.3g, 1, K, SHARE},  /* from CPU: %.3g, %.3g */'
              % (key, a, b, c, dd, qa, qb))
    print("/* K and SHARE: keep the current ones, or refit them with --shapes */")
    print("};")
    xs = [r[0] for r in disk]
    wa, wb = fit(xs, [r[1] for r in disk])
    pa, pb = fit(xs, [r[2] for r in disk])
    print("static const double work_mb[2] = {%.3g, %.3g}, published_mb[2] = {%.3g, %.3g};"
          % (wa, wb, pa, pb))
    print("\nthe plan before this fit, against each run (ratio = plan / measured):")
    for method, tris, fidelity, plan, stages in runs:
        secs = sum(t["seconds"] for t in stages.values())
        peak = max(t["peak_rss_kb"] for t in stages.values()) / 1024.0
        print("  %-8s %9d fidelity %-5s  memory %.2f  time %.2f" %
              (method, tris, fidelity, plan["peak_rss_mb"] / peak, plan["seconds"] / secs))


def plan_lines(repo):
    """cli/plan.c's lines: {stage: (c, d, f, k, share)}, and IMAGES_MB."""
    with open(os.path.join(repo, "cli", "plan.c")) as f:
        text = f.read()
    images = float(re.search(r"#define IMAGES_MB ([0-9.]+)", text).group(1))
    lines = {}
    for m in re.finditer(r'\{"([a-z+:]+)", ([^}]*)\}', text):
        v = [float(x) for x in m.group(2).split(",")]
        if len(v) == 8:
            lines[m.group(1)] = (v[3], v[4], v[5], v[6], v[7])
    return lines, images


def fit_shapes(scanlod, gen, root, sizes):
    """Per octree stage, the share (slivers) and k (soup) that meet the measured peaks."""
    lines, images = plan_lines(os.path.dirname(os.path.dirname(os.path.dirname(
        os.path.abspath(__file__)))))
    for name, args, tris in (("slivers", ["--aspect", "16"], sizes[0]),
                             ("soup", ["--soup"], sizes[1])):
        d = os.path.join(root, name)
        shutil.rmtree(d, ignore_errors=True)
        os.makedirs(os.path.join(d, "in"))
        run([gen, "--triangles", tris, "-o", os.path.join(d, "in", name + ".ply")] + args)
        with open(os.path.join(d, "run.ini"), "w") as f:
            f.write("[run]\ninput = in\nwork = work\noutput = out\nlogs = logs\n"
                    "memory_check = false\n[export]\nfidelity = false\n")
        plan = json.loads(run([scanlod, "plan", os.path.join(d, "run.ini"), "--threads", "2",
                               "--json"]))["items"][0]
        sys.stderr.write("plan_calibrate: %s, %d triangles\n" % (name, tris))
        run([scanlod, "run", os.path.join(d, "run.ini"), "--threads", "2", "-q"])
        with open(os.path.join(d, "out", name + ".ply", "timings.json")) as f:
            stages = json.load(f)["stages"]
        n, r = plan["triangles"] / 1e6, plan["shape"]["samples_ratio"]
        sigma = plan["shape"]["scattered"]
        print("%s: samples ratio %.2f, scattered %.3f" % (name, r, sigma))
        for stage, t in stages.items():
            c, dd, f, k, share = lines.get(stage, (0, 0, 1, 0, 0))
            mem = t["peak_rss_kb"] / 1024.0 - (images if stage == "export" else 0)
            y = (mem - c) / dd if dd else 0
            if share <= 0 or y <= 0:
                continue
            if name == "slivers":
                fitted = (y - n ** f) / ((n * r) ** f - n ** f)
                what = "share %.2f (now %.2f)" % (fitted, share)
            else:
                nm = max((y - (1 - share) * n ** f) / share, 1e-9) ** (1 / f)
                what = "k %.2f (now %.2f)" % ((nm / (n * r) - 1) / max(sigma, 1e-9), k)
            print("  %-9s measured %6.0f MB, plan %6.0f MB: %s" %
                  (stage, t["peak_rss_kb"] / 1024.0, plan["stages"][stage]["peak_rss_mb"], what))
        shutil.rmtree(d, ignore_errors=True)


if __name__ == "__main__":
    main()
