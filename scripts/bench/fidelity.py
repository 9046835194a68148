#!/usr/bin/env python3
"""Quick fidelity harness: the octree's levels against meshopt_simplify at equal counts.

    scripts/bench/fidelity.py [--build DIR] [--work DIR] [--inputs a,b,..]
                              [--budgets 1,2,5,10,20,50] [--samples N] [-s key=value ..]
                              [--label NAME] [--json OUT.json] [--keep]

Per input (../shared/data/NAME.ply, or $SCANLOD_SHARED_DATA): one `scanlod run` with the
default config and the -s overrides; then, at P % of the *input's* triangles for each
budget P, `scanlod extract --triangles N` and `meshopt_simplify` of the input to the
count the cut landed on, both measured by `scanlod compare` against the input
(symmetric RMS and Hausdorff, % of the diagonal; connected parts and the largest one's
share of the area). Also the finest level (`--lod-percent 100`) and every level the
export stage published (report.json: triangles, parts, the largest part's area share),
and the build's stage table (wall seconds, peak RSS from timings.json).

Prints one table per input and the medians; --json writes everything. Meant for
iterating on one change at a time (a few minutes for the 7 benchmark inputs on 2 cores).
The benchmark's phase fidelity (lib/fidelity.py, `run.sh --phases fidelity`) measures the
published budget levels instead, against meshoptimizer 1.3 (the anchor, docs/fidelity.md).
"""
import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile

here = os.path.dirname(os.path.abspath(__file__))
root = os.path.dirname(os.path.dirname(here))
DEFAULT_INPUTS = ["armadillo_86kf", "bun_zipper", "dragon_100kf", "fandisk", "igea",
                  "lucy_100kf", "rocker_arm"]


def run(cmd):
    p = subprocess.run([str(c) for c in cmd], stdout=subprocess.PIPE,
                       stderr=subprocess.PIPE, text=True)
    if p.returncode != 0:
        raise RuntimeError("%s: exit %d: %s" % (" ".join(map(str, cmd)), p.returncode,
                                                 p.stderr.strip()[-800:]))
    return p.stdout


def compare(scanlod, ref, ply, samples):
    d = json.loads(run([scanlod, "compare", ref, ply, "--samples", samples, "--json"]))
    t = d["b_topology"]
    return {"triangles": d["b_triangles"], "rms": 100 * d["rms"],
            "hausdorff": 100 * d["hausdorff"], "watertight": t["watertight"],
            "boundary_edges": t["boundary_edges"], "nonmanifold_edges": t["nonmanifold_edges"],
            "components": t.get("components"),
            "largest_area": t.get("largest_component_area_fraction")}


def build_model(scanlod, ply, work, overrides):
    """One `scanlod run` of a one-item collection; returns (model, report, timings)."""
    name = os.path.basename(ply)
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(os.path.join(work, "in"))
    os.symlink(os.path.abspath(ply), os.path.join(work, "in", name))
    conf = os.path.join(work, "run.ini")
    with open(conf, "w") as f:
        f.write("[run]\ninput = in\nwork = work\noutput = out\nlogs = logs\n")
    cmd = [scanlod, "run", conf, "--threads", "2", "-q"]
    for o in overrides:
        cmd += ["-s", o]
    run(cmd)
    out = os.path.join(work, "out", name)
    with open(os.path.join(out, "report.json")) as f:
        report = json.load(f)
    with open(os.path.join(out, "timings.json")) as f:
        timings = json.load(f)["stages"]
    return os.path.join(out, "model.slod"), report, timings, out


def extract(scanlod, model, out, *args):
    text = run([scanlod, "extract", model] + [str(a) for a in args] + ["-o", out])
    return text


def measure_input(a, name):
    ref = os.path.join(a.data, name + ".ply")
    scanlod = os.path.join(a.build, "cli", "scanlod")
    meshopt = os.path.join(a.build, "scripts", "bench", "meshopt_lod")
    work = os.path.join(a.work, name)
    model, report, timings, outdir = build_model(scanlod, ref, work, a.set)
    info = json.loads(run([scanlod, "compare", ref, ref, "--samples", 1000, "--json"]))
    n_in = info["a_triangles"]
    res = {"input": name, "input_triangles": n_in,
           "input_open": info["b_topology"]["boundary_edges"] > 0,
           "input_largest_area": info["b_topology"].get("largest_component_area_fraction"),
           "input_components": info["b_topology"].get("components"),
           "stages": {s: {"seconds": v.get("seconds"), "peak_rss_kb": v.get("peak_rss_kb")}
                      for s, v in timings.items()}}
    finest = os.path.join(work, "finest.ply")
    extract(scanlod, model, finest, "--lod-percent", 100)
    res["finest"] = compare(scanlod, ref, finest, a.samples)
    res["published"] = [{k: lv.get(k) for k in ("name", "triangles", "components",
                                                 "largest_component_area_fraction",
                                                 "watertight", "rms", "hausdorff")}
                        for lv in report.get("stages", {}).get("export", {}).get("levels", [])]
    rows = []
    for p in a.budgets:
        n = max(8, int(round(p / 100.0 * n_in)))
        ply = os.path.join(work, "cut_%g.ply" % p)
        extract(scanlod, model, ply, "--triangles", n)
        ours = compare(scanlod, ref, ply, a.samples)
        mo = json.loads(run([meshopt, ref, "--targets", str(ours["triangles"]), "-o",
                             os.path.join(work, "mo_%g" % p)]))
        theirs = compare(scanlod, ref, mo["levels"][0]["output"], a.samples)
        rows.append({"percent": p, "budget": n, "scanlod": ours, "meshopt": theirs,
                     "rms_ratio": ours["rms"] / theirs["rms"] if theirs["rms"] > 0 else None,
                     "hausdorff_ratio": ours["hausdorff"] / theirs["hausdorff"]
                     if theirs["hausdorff"] > 0 else None})
    res["budgets"] = rows
    if not a.keep:
        shutil.rmtree(os.path.join(work, "work"), ignore_errors=True)
    return res


def print_input(r):
    f = r["finest"]
    print("%s (%d triangles%s): finest %d triangles, RMS %.4f %%, Hausdorff %.3f %%, "
          "parts %s (largest %.4f)" % (r["input"], r["input_triangles"],
                                       ", open" if r["input_open"] else "", f["triangles"],
                                       f["rms"], f["hausdorff"], f["components"],
                                       f["largest_area"] or 0))
    print("  %5s %7s | %8s %8s %5s %7s | %8s %8s %5s | %6s %6s" % (
        "P %", "tris", "RMS", "Haus", "parts", "largest", "mo RMS", "mo Haus", "parts",
        "RMS x", "Haus x"))
    for b in r["budgets"]:
        s, m = b["scanlod"], b["meshopt"]
        print("  %5g %7d | %8.4f %8.3f %5d %7.4f | %8.4f %8.3f %5d | %6.2f %6.2f" % (
            b["percent"], s["triangles"], s["rms"], s["hausdorff"], s["components"],
            s["largest_area"], m["rms"], m["hausdorff"], m["components"],
            b["rms_ratio"] or 0, b["hausdorff_ratio"] or 0))
    pub = ", ".join("%s %d tris %s parts %.4f" % (lv["name"], lv["triangles"] or 0,
                                                  lv["components"],
                                                  lv["largest_component_area_fraction"] or 0)
                    for lv in r["published"] if lv.get("components") is not None)
    if pub:
        print("  published: " + pub)
    st = r["stages"]
    tot = sum(v["seconds"] or 0 for v in st.values())
    rss = max(v["peak_rss_kb"] or 0 for v in st.values())
    print("  build: %.2f s, peak RSS %.0f MB (%s)" % (
        tot, rss / 1024, ", ".join("%s %.2f" % (s, v["seconds"] or 0) for s, v in st.items())))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--build", default=os.path.join(root, "build"))
    ap.add_argument("--work", default=None)
    ap.add_argument("--data", default=os.environ.get("SCANLOD_SHARED_DATA",
                                                     os.path.join(root, "..", "shared", "data")))
    ap.add_argument("--inputs", default=",".join(DEFAULT_INPUTS))
    ap.add_argument("--budgets", default="1,2,5,10,20,50")
    ap.add_argument("--samples", type=int, default=200000)
    ap.add_argument("-s", "--set", action="append", default=[])
    ap.add_argument("--label", default="")
    ap.add_argument("--json", default=None)
    ap.add_argument("--keep", action="store_true")
    a = ap.parse_args()
    a.budgets = [float(x) for x in a.budgets.split(",") if x]
    tmp = None
    if not a.work:
        a.work = tmp = tempfile.mkdtemp(prefix="scanlod-fidelity-")
    results = []
    try:
        for name in [x for x in a.inputs.split(",") if x]:
            r = measure_input(a, name)
            results.append(r)
            print_input(r)
            sys.stdout.flush()
    finally:
        if tmp and not a.keep:
            shutil.rmtree(tmp, ignore_errors=True)
    rr = [b["rms_ratio"] for r in results for b in r["budgets"] if b["rms_ratio"]]
    hr = [b["hausdorff_ratio"] for r in results for b in r["budgets"] if b["hausdorff_ratio"]]
    if rr:
        print("RMS / meshopt: median %.2f, max %.2f, pairs above 3: %d of %d; "
              "Hausdorff / meshopt: median %.2f" % (statistics.median(rr), max(rr),
                                                    sum(1 for x in rr if x > 3), len(rr),
                                                    statistics.median(hr)))
    if a.json:
        with open(a.json, "w") as f:
            json.dump({"label": a.label, "overrides": a.set, "inputs": results}, f, indent=1)


if __name__ == "__main__":
    main()
