#!/usr/bin/env python3
"""The surface fit's gain (docs/surface-fit.md): per scan and level fraction,

  (a) meshopt_simplify (meshoptimizer 0.18, Debian; peers/meshopt_lod)
  (b) (a) + the surface fit (fit_tool)
  (c) simplifyWithUpdate (meshoptimizer 1.3 JS; peers/meshopt_js.mjs, no flags)
  (d) (c) + the surface fit

each measured by `scanlod compare INPUT LEVEL --samples 200000` (symmetric RMS and
Hausdorff, fractions of the input's diagonal). Prints a markdown table with medians and the
ratios to (c); --json writes every figure.

      scripts/bench/bench_fit.py [--build DIR] [--work DIR] [--inputs a,b,..]
                                 [--fractions 0.01,..] [--fit-args "--spring 0.05"]
                                 [--reuse] [--json OUT.json]

--reuse keeps levels already in --work (only the fits and the measures rerun).
"""
import argparse
import json
import os
import statistics
import subprocess
import sys

here = os.path.dirname(os.path.abspath(__file__))
root = os.path.dirname(os.path.dirname(here))
INPUTS = ["armadillo_86kf", "bun_zipper", "dragon_100kf", "fandisk", "igea", "lucy_100kf",
          "nefertiti", "rocker_arm", "usnm_1145291"]
FRACTIONS = [0.01, 0.02, 0.05, 0.1, 0.2, 0.5]


def run(cmd):
    p = subprocess.run([str(c) for c in cmd], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                       text=True)
    if p.returncode != 0:
        raise RuntimeError("%s: exit %d: %s" % (" ".join(map(str, cmd)), p.returncode,
                                                p.stderr.strip()))
    return p.stdout


def make_levels(a, data, work, name, triangles):
    """meshopt 0.18 and simplifyWithUpdate levels of one input; returns {fraction: paths}."""
    tool = os.path.join(a.build, "scripts/bench/meshopt_lod")
    welded = os.path.join(work, name + "_welded")
    fr = ",".join(str(f) for f in a.fractions)
    out = {}
    for f in a.fractions:
        t = round(f * triangles)
        out[f] = {"a": "%s/%s_018_%d.ply" % (work, name, t),
                  "c": "%s/%s_13_update_%d.ply" % (work, name, t)}
    if a.reuse and all(os.path.exists(p) for v in out.values() for p in v.values()):
        return out
    run([tool, data, "--fractions", fr, "-o", os.path.join(work, name + "_018")])
    run([tool, data, "--fractions", "1", "-o", welded])
    welded_ply = "%s_%d.ply" % (welded, triangles)
    run(["node", os.path.join(here, "peers/meshopt_js.mjs"), welded_ply, "--fractions", fr,
         "-o", os.path.join(work, name + "_13"), "--functions", "update", "--flags", "none"])
    os.remove(welded_ply)
    return out


def compare(a, data, level):
    d = json.loads(run([os.path.join(a.build, "cli/scanlod"), "compare", data, level,
                        "--samples", "200000", "--json"]))
    return {"rms": d["rms"], "hausdorff": d["hausdorff"]}


def fit(a, data, level, out):
    s = json.loads(run([os.path.join(a.build, "scripts/bench/fit_tool"), data, level, "-o", out]
                       + a.fit_args.split()))
    return s


def triangles_of(a, data):
    d = json.loads(run([os.path.join(a.build, "cli/scanlod"), "compare", data, data,
                        "--samples", "1", "--json"]))
    return d["a_triangles"]


def measure_input(a, name):
    data = os.path.join(a.data, name + ".ply")
    rows = []
    levels = make_levels(a, data, a.work, name, triangles_of(a, data))
    for f in a.fractions:
        row = {"input": name, "fraction": f}
        for v, src in (("a", levels[f]["a"]), ("c", levels[f]["c"])):
            fitted = src.replace(".ply", "_fit.ply")
            row[v] = compare(a, data, src)
            row[v + "_fit"] = fit(a, data, src, fitted)
            row["b" if v == "a" else "d"] = compare(a, data, fitted)
        rows.append(row)
        print("%-14s %5.1f%%  " % (name, 100 * f) + "  ".join(
            "%s %.3e/%.3e" % (k, row[k]["rms"], row[k]["hausdorff"]) for k in "abcd"),
            file=sys.stderr, flush=True)
    return rows


def table(rows):
    lines = ["| input | % | (a) RMS | (b) RMS | (c) RMS | (d) RMS | (b)/(c) | (d)/(c) "
             "| (a) H | (b) H | (c) H | (d) H | (b)/(c) H | (d)/(c) H | fit s (b) | fit s (d) |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    cols = {k: [] for k in ("rb", "rd", "hb", "hd")}
    for r in rows:
        rb, rd = r["b"]["rms"] / r["c"]["rms"], r["d"]["rms"] / r["c"]["rms"]
        hb, hd = r["b"]["hausdorff"] / r["c"]["hausdorff"], r["d"]["hausdorff"] / r["c"]["hausdorff"]
        for k, v in (("rb", rb), ("rd", rd), ("hb", hb), ("hd", hd)):
            cols[k].append(v)
        lines.append("| %s | %g | %s | %.2f | %.2f | %s | %.2f | %.2f | %.2f | %.2f |" % (
            r["input"], 100 * r["fraction"],
            " | ".join("%.3e" % r[k]["rms"] for k in "abcd"), rb, rd,
            " | ".join("%.3e" % r[k]["hausdorff"] for k in "abcd"), hb, hd,
            r["a_fit"]["fit_seconds"], r["c_fit"]["fit_seconds"]))
    med = {k: statistics.median(v) for k, v in cols.items()}
    mx = {k: max(v) for k, v in cols.items()}
    medians = [statistics.median(r[k]["rms"] for r in rows) for k in "abcd"]
    hmed = [statistics.median(r[k]["hausdorff"] for r in rows) for k in "abcd"]
    lines.append("| **median** | | %s | **%.2f** | **%.2f** | %s | **%.2f** | **%.2f** | | |" % (
        " | ".join("%.3e" % m for m in medians), med["rb"], med["rd"],
        " | ".join("%.3e" % m for m in hmed), med["hb"], med["hd"]))
    lines.append("| **max** | | | | | | %.2f | %.2f | | | | | %.2f | %.2f | | |" % (
        mx["rb"], mx["rd"], mx["hb"], mx["hd"]))
    return "\n".join(lines)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--build", default=os.path.join(root, "build"))
    p.add_argument("--work", default="/tmp/scanlod-bench-fit")
    p.add_argument("--data", default=os.environ.get("SCANLOD_SHARED_DATA") or
                   os.path.join(os.path.dirname(root), "shared", "data"))
    p.add_argument("--inputs", default=",".join(INPUTS))
    p.add_argument("--fractions", default=",".join(str(f) for f in FRACTIONS))
    p.add_argument("--fit-args", default="")
    p.add_argument("--reuse", action="store_true")
    p.add_argument("--json")
    a = p.parse_args()
    a.fractions = [float(f) for f in a.fractions.split(",")]
    os.makedirs(a.work, exist_ok=True)
    rows = []
    for name in a.inputs.split(","):
        rows += measure_input(a, name)
    print(table(rows))
    if a.json:
        with open(a.json, "w") as f:
            json.dump(rows, f, indent=1)


if __name__ == "__main__":
    main()
