"""The segment method's benchmark (issue 12): bench_segment.sh drives it.

usage: segment.py run ROOT BUILD DATA SCRATCH RESULTS.json QUICK "PARTS" ["MODELS" [BASELINE [ESTIMATE]]]
       segment.py report RESULTS.json [MORE.json ...] DOCS_DIR   (parts the first lacks: from the others)
       segment.py remeasure ROOT BUILD DATA SCRATCH RESULTS.json

MODELS (optional, "" for all): the fidelity inputs (and VSA's, where they meet); a run with
them is partial and its report goes under the full run's tables ("segment-update" markers).
BASELINE (optional): another scanlod binary (the code before a change), timed in the speed
part alternately with this one on the same inputs. ESTIMATE "0": no `--search-samples 0` rows.
Every timed command also has its CPU time (user + system, from the kernel), which a shared
machine disturbs far less than the wall time.

remeasure: the fidelity rows of a run stopped during its fidelity part, measured again
from the levels it left in SCRATCH (its simplify and meshopt times are then unknown).
A run saves its results after every fidelity row, so a stopped run keeps what it did.
"""
import datetime
import json
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile

SAMPLES = 200000
BUDGETS = [2, 5, 10, 20, 50]
PAPER_MODELS = ["cow", "fandisk", "rocker_arm"]
FIDELITY_MODELS = ["fandisk", "rocker_arm", "armadillo_86kf", "bun_zipper", "dragon_100kf", "igea"]
FINEST_MODELS = ["fandisk", "rocker_arm", "armadillo_86kf", "bun_zipper"]
FINEST_BUDGETS = [5, 10, 20]
VSA_MODELS = ["fandisk", "rocker_arm", "armadillo_86kf"]
BUNDLED = {"cow", "fandisk", "rocker_arm"}
# inputs that are not watertight themselves (`scanlod compare X X --json`, b_topology)
NOT_WATERTIGHT = {"bun_zipper": "no (open input)",
                  "dragon_100kf": "no (input: 1 non-manifold edge, kept)"}


def log(msg):
    sys.stderr.write("[bench segment %s] %s\n" % (datetime.datetime.now().strftime("%H:%M:%S"), msg))
    sys.stderr.flush()


def run(cmd, cwd=None):
    p = subprocess.run([str(c) for c in cmd], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                       text=True, cwd=cwd)
    if p.returncode != 0:
        raise RuntimeError("%s: exit %d: %s" % (" ".join(map(str, cmd)), p.returncode,
                                                 p.stderr.strip()[-400:]))
    return p.stdout


def run_json(cmd):
    return json.loads(run(cmd))


def children_cpu():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def run_json_cpu(cmd):
    """run_json and the CPU seconds (user + system) the command took."""
    t = children_cpu()
    d = run_json(cmd)
    return d, children_cpu() - t


class Bench:
    def __init__(self, root, build, data, scratch, quick, models=None, baseline=None,
                 estimate=True):
        self.root, self.build, self.data, self.scratch = root, build, data, scratch
        self.quick = quick
        self.models, self.baseline, self.estimate = models, baseline, estimate
        self.scanlod = os.path.join(build, "cli", "scanlod")
        self.peer = lambda n: os.path.join(build, "scripts", "bench", n)
        self.reps = 1 if quick else 3
        self.checkpoint = lambda part, rows: None

    def ply(self, name):
        if name in BUNDLED:
            return os.path.join(self.root, "tests", "data", "scans", name + ".ply")
        return os.path.join(self.data, name + ".ply")

    def tmp(self, *parts):
        p = os.path.join(self.scratch, *parts)
        os.makedirs(os.path.dirname(p), exist_ok=True)
        return p

    def compare(self, a, b):
        d = run_json([self.scanlod, "compare", a, b, "--samples", SAMPLES, "--json"])
        return {"triangles": d["b_triangles"], "rms": d["rms"], "hausdorff": d["hausdorff"],
                "watertight": d["b_topology"]["watertight"],
                "nonmanifold_edges": d["b_topology"]["nonmanifold_edges"]}

    def simplify(self, src, out, args, binary=None):
        d, cpu = run_json_cpu([binary or self.scanlod, "simplify", src, "--method", "segment",
                               "-o", out, "--json"] + list(args))
        d["cpu_seconds"] = cpu
        return d

    def meshopt(self, src, n, prefix):
        d, cpu = run_json_cpu([self.peer("meshopt_lod"), src, "--targets", n, "-o", prefix])
        lv = d["levels"][0]
        lv["cpu_seconds"] = cpu  # the whole process: reading, welding, every target
        return lv, "%s_%d.ply" % (prefix, n)

    def octree_model(self, name):
        """model.slod of a one-item collection built with the default config."""
        root = self.tmp("octree", name, "x")[:-2]
        os.makedirs(os.path.join(root, "in"), exist_ok=True)
        src = os.path.join(root, "in", name + ".ply")
        if not os.path.exists(src):
            shutil.copyfile(self.ply(name), src)
        cfg = os.path.join(root, "run.ini")
        with open(cfg, "w") as f:
            f.write("[run]\ninput = in\nwork = work\noutput = out\nlogs = logs\n"
                    "[lod]\nmethod = octree\n[levels]\npercents = 100\nbudgets =\ntop = method\noversample = 1\n"
                    "[refine]\ncollapse = false\nfit = false\n[export]\nformats = ply\nthumbnail_size = 0\n"
                    "fidelity = false\n")
        model = os.path.join(root, "out", name + ".ply", "model.slod")
        if not os.path.exists(model):
            run([self.scanlod, "run", cfg, "-q"])
        return model

    def extract(self, model, args, out):
        run([self.scanlod, "extract", model] + list(args) + ["-o", out])
        return out


# --- the parts ---------------------------------------------------------------------------

def part_paper(b):
    rows = []
    for m in PAPER_MODELS:
        for dseg in (80, 50):
            for db in (20, 60):
                for rule, alpha in (("paper", -1.5), ("near", -1.5), ("near", 1.5)):
                    out = b.tmp("paper", "%s_%d_%d_%s_%g.ply" % (m, dseg, db, rule, alpha))
                    s = b.simplify(b.ply(m), out, ["--rule", rule, "--alpha", alpha,
                                                   "--delta-seg", dseg, "--delta-b", db])
                    seg = s["segment"]
                    c = b.compare(b.ply(m), out)
                    rows.append({"model": m, "delta_seg": dseg, "delta_b": db, "rule": rule,
                                 "alpha": alpha, "segments": seg["segments"],
                                 "vertices": seg["input_vertices"],
                                 "removed": seg["removed_vertices"],
                                 "removed_boundary": seg["removed_boundary"],
                                 "removed_interior": seg["removed_interior"],
                                 "percent": seg["removed_percent"],
                                 "patches_kept": seg["patches_kept"],
                                 "triangles": s["triangles"], "rms": c["rms"],
                                 "hausdorff": c["hausdorff"], "watertight": c["watertight"]})
                    log("paper %s dseg %d db %d %s %g: %d segments, %d removed (%.1f %%)"
                        % (m, dseg, db, rule, alpha, seg["segments"], seg["removed_vertices"],
                           seg["removed_percent"]))
    return rows


def part_fidelity(b):
    rows = []
    models = b.models or (FIDELITY_MODELS[:2] if b.quick else FIDELITY_MODELS)
    for m in models:
        src = b.ply(m)
        model = b.octree_model(m)
        for pct in BUDGETS:
            out = b.tmp("fid", "%s_%d.ply" % (m, pct))
            s = b.simplify(src, out, ["--ratio", pct / 100.0])
            n = s["triangles"]
            seg = b.compare(src, out)
            lv, mo_out = b.meshopt(src, n, b.tmp("fid", "mo_%s_%d" % (m, pct)))
            mo = b.compare(src, mo_out)
            oc_out = b.extract(model, ["--triangles", n], b.tmp("fid", "oc_%s_%d.ply" % (m, pct)))
            oc = b.compare(src, oc_out)
            rows.append({"model": m, "percent": pct, "input_triangles": s["input_triangles"],
                         "segment": seg, "meshopt": mo, "octree": oc,
                         "segments": s["segment"]["segments"],
                         "seconds": s["simplify_seconds"], "meshopt_seconds": lv["seconds"],
                         "cpu_seconds": s["cpu_seconds"], "over_budget": s["segment"]["over_budget"]})
            b.checkpoint("fidelity", rows)
            log("fidelity %s %d %%: %d triangles, RMS %.3g vs meshopt %.3g (%.2fx), octree %.3g"
                % (m, pct, n, seg["rms"], mo["rms"], seg["rms"] / mo["rms"], oc["rms"]))
    return rows


def part_finest(b):
    rows = []
    models = FINEST_MODELS[:2] if b.quick else FINEST_MODELS
    for m in models:
        src = b.ply(m)
        model = b.octree_model(m)
        finest = b.extract(model, ["--lod-percent", "100"], b.tmp("finest", m + "_finest.ply"))
        for pct in FINEST_BUDGETS:
            n_in = run_json([b.scanlod, "compare", src, src, "--samples", 1000, "--json"])["b_triangles"]
            oc_out = b.extract(model, ["--triangles", int(n_in * pct / 100)],
                               b.tmp("finest", "oc_%s_%d.ply" % (m, pct)))
            oc = b.compare(src, oc_out)
            out = b.tmp("finest", "seg_%s_%d.ply" % (m, pct))
            s = b.simplify(finest, out, ["--triangles", oc["triangles"]])
            seg = b.compare(src, out)
            rows.append({"model": m, "percent": pct, "octree": oc, "segment_on_finest": seg})
            log("finest %s %d %%: octree %d tris RMS %.3g, segment on finest %d tris RMS %.3g"
                % (m, pct, oc["triangles"], oc["rms"], seg["triangles"], seg["rms"]))
    return rows


def part_speed(b):
    rows = []
    surface = b.tmp("speed", "surface_2m.ply")
    if not b.quick and not os.path.exists(surface):
        run([b.peer("gen_surface"), "--triangles", 2000000, "-o", surface])
    inputs = [("igea", b.ply("igea"))] + ([] if b.quick else [("surface_2m", surface)])
    for name, src in inputs:
        modes = (("default", []),) + (() if b.quick or not b.estimate
                                       else (("estimate", ["--search-samples", "0"]),))
        for mode, extra in modes:
            t = {k: [] for k in ("seg", "seg_cpu", "mo", "mo_cpu", "base", "base_cpu")}
            n, base_n, base_rms = 0, None, None
            for rep in range(b.reps):  # alternately: the baseline, this build, meshopt
                if b.baseline:
                    base_out = b.tmp("speed", "%s_%s_baseline.ply" % (name, mode))
                    s = b.simplify(src, base_out, ["--ratio", 0.1] + extra, b.baseline)
                    t["base"].append(s["simplify_seconds"])
                    t["base_cpu"].append(s["cpu_seconds"])
                    base_n = s["triangles"]
                out = b.tmp("speed", "%s_%s.ply" % (name, mode))
                s = b.simplify(src, out, ["--ratio", 0.1] + extra)
                n = s["triangles"]
                t["seg"].append(s["simplify_seconds"])
                t["seg_cpu"].append(s["cpu_seconds"])
                lv, _ = b.meshopt(src, n, b.tmp("speed", "mo_" + name))
                t["mo"].append(lv["seconds"])
                t["mo_cpu"].append(lv["cpu_seconds"])
            seg_c = b.compare(src, out)
            med = lambda k: statistics.median(t[k]) if t[k] else None
            row = {"input": name, "mode": mode, "triangles": n, "seconds": med("seg"),
                   "meshopt_seconds": med("mo"), "cpu_seconds": med("seg_cpu"),
                   "meshopt_cpu_seconds": med("mo_cpu"), "rms": seg_c["rms"], "reps": b.reps,
                   "all": t}
            if b.baseline:
                base_rms = b.compare(src, base_out)["rms"]
                row.update({"baseline_seconds": med("base"), "baseline_cpu_seconds": med("base_cpu"),
                            "baseline_triangles": base_n, "baseline_rms": base_rms,
                            "baseline_identical": open(base_out, "rb").read() == open(out, "rb").read()})
            rows.append(row)
            log("speed %s %s: %.2f s (CPU %.2f) vs meshopt %.2f s (CPU %.2f)%s"
                % (name, mode, med("seg"), med("seg_cpu"), med("mo"), med("mo_cpu"),
                   ", baseline %.2f s (CPU %.2f)" % (med("base"), med("base_cpu")) if b.baseline else ""))
    vsa = []
    if os.path.exists(b.peer("vsa_lod")):
        models = VSA_MODELS[:2] if b.quick else VSA_MODELS
        if b.models:
            models = [m for m in models if m in b.models]
        for m in models:
            src = b.ply(m)
            out = b.tmp("vsa", m + "_seg.ply")
            s = b.simplify(src, out, ["--ratio", 0.1])
            n = s["triangles"]
            seg = b.compare(src, out)
            v_out = b.tmp("vsa", m + "_vsa.ply")
            v = run_json([b.peer("vsa_lod"), src, "--triangles", n, "-o", v_out])
            vc = b.compare(src, v_out)
            vsa.append({"model": m, "triangles": n, "seconds": s["simplify_seconds"],
                        "rms": seg["rms"], "watertight": seg["watertight"],
                        "vsa_triangles": v["triangles"], "vsa_proxies": v["proxies"],
                        "vsa_seconds": v["seconds"], "vsa_search_seconds": v["search_seconds"],
                        "vsa_runs": v["runs"], "vsa_rms": vc["rms"],
                        "vsa_watertight": vc["watertight"]})
            log("vsa %s: segment %.2f s, VSA %.2f s (final run), RMS %.3g vs %.3g"
                % (m, s["simplify_seconds"], v["seconds"], seg["rms"], vc["rms"]))
    return {"meshopt": rows, "vsa": vsa}


def machine():
    git = lambda *a: subprocess.run(["git", "-C", ROOT] + list(a), capture_output=True,
                                    text=True).stdout.strip()
    commit = git("rev-parse", "--short", "HEAD") or "unknown"
    if git("status", "--porcelain", "--untracked-files=no"):
        commit += " (with uncommitted changes)"
    return {"date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
            "commit": commit, "cores": os.cpu_count(), "load": os.getloadavg()[0]}


def cmd_run(args):
    global ROOT
    ROOT, build, data, scratch, results, quick, parts = args[:7]
    models = args[7].split() if len(args) > 7 and args[7].strip() else None
    baseline = args[8] if len(args) > 8 and args[8] else None
    estimate = not (len(args) > 9 and args[9] == "0")
    b = Bench(ROOT, build, data, scratch, quick == "1", models, baseline, estimate)
    res = {"machine": machine(), "samples": SAMPLES, "quick": quick == "1"}
    if models:
        res["models"] = models
    if baseline:
        res["baseline"] = baseline
    cache = build and os.path.join(build, "CMakeCache.txt")
    if cache and os.path.exists(cache):
        for line in open(cache):
            if line.startswith("CMAKE_BUILD_TYPE:"):
                res["machine"]["build_type"] = line.split("=", 1)[1].strip()
    if os.path.exists(results):
        res.update(json.load(open(results)))

    def save():
        res["machine"]["load_end"] = os.getloadavg()[0]
        with open(results + ".tmp", "w") as f:
            json.dump(res, f, indent=1)
        os.replace(results + ".tmp", results)

    def checkpoint(part, rows):
        res[part] = rows
        save()
    b.checkpoint = checkpoint
    for part in parts.split():
        log("part %s" % part)
        res[part] = {"paper": part_paper, "fidelity": part_fidelity, "finest": part_finest,
                     "speed": part_speed}[part](b)
        save()


def cmd_remeasure(args):
    root, build, data, scratch, results = args
    b = Bench(root, build, data, scratch, False)
    res = json.load(open(results))
    rows, fid = [], os.path.join(scratch, "fid")
    for m in FIDELITY_MODELS:
        for pct in BUDGETS:
            seg_out, oc_out = os.path.join(fid, "%s_%d.ply" % (m, pct)), os.path.join(fid, "oc_%s_%d.ply" % (m, pct))
            mo = [f for f in os.listdir(fid) if f.startswith("mo_%s_%d_" % (m, pct))]
            if not (os.path.exists(seg_out) and os.path.exists(oc_out) and mo):
                continue
            src = b.ply(m)
            seg = b.compare(src, seg_out)
            rows.append({"model": m, "percent": pct, "segment": seg,
                         "meshopt": b.compare(src, os.path.join(fid, mo[0])),
                         "octree": b.compare(src, oc_out), "segments": None, "seconds": None,
                         "meshopt_seconds": None, "remeasured": True})
            log("remeasured %s %d %%: %d triangles" % (m, pct, seg["triangles"]))
    res["fidelity"] = rows
    with open(results + ".tmp", "w") as f:
        json.dump(res, f, indent=1)
    os.replace(results + ".tmp", results)


# --- the report ----------------------------------------------------------------------------

def pct(x):
    return "%.4f %%" % (100 * x)


def ratio(a, b):
    return "%.2f" % (a / b) if b else "-"


def table_paper(rows):
    out = ["| model | delta_seg | segments | delta_b | rule (alpha) | removed vertices | of | removed % "
           "| boundary / interior | triangles | RMS | watertight |",
           "|---|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|---|"]
    for r in rows:
        rule = "eq. 8 as printed (%g)" % r["alpha"] if r["rule"] == "paper" else "near plane (%g)" % r["alpha"]
        out.append("| %s | %d | %d | %d | %s | %d | %d | %.1f | %d / %d | %d | %s | %s |"
                   % (r["model"], r["delta_seg"], r["segments"], r["delta_b"], rule, r["removed"],
                      r["vertices"], r["percent"], r["removed_boundary"], r["removed_interior"],
                      r["triangles"], pct(r["rms"]), "yes" if r["watertight"] else "no"))
    return out


def table_fidelity(rows):
    out = ["| input | budget | triangles | segment RMS | meshopt RMS | segment / meshopt | octree "
           "triangles | octree RMS | segment / octree | segment Hausdorff | meshopt Hausdorff "
           "| watertight | segments | segment s | meshopt s |",
           "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---:|---:|---:|"]
    for r in rows:
        s, m, o = r["segment"], r["meshopt"], r["octree"]
        opt = lambda v, f: "–" if v is None else f % v
        tris = "%d%s" % (s["triangles"], " (over budget)" if r.get("over_budget") else "")
        out.append("| %s | %d %% | %s | %s | %s | **%s** | %d | %s | %s | %s | %s | %s | %s | %s | %s |"
                   % (r["model"], r["percent"], tris, pct(s["rms"]), pct(m["rms"]),
                      ratio(s["rms"], m["rms"]), o["triangles"], pct(o["rms"]),
                      ratio(s["rms"], o["rms"]), pct(s["hausdorff"]), pct(m["hausdorff"]),
                      "yes" if s["watertight"] else NOT_WATERTIGHT.get(r["model"], "no"),
                      opt(r["segments"], "%d"), opt(r["seconds"], "%.2f"),
                      opt(r["meshopt_seconds"], "%.3f")))
    return out


def table_finest(rows):
    out = ["| input | octree cut | triangles | octree RMS | segment pass on the finest level: "
           "triangles | its RMS | segment / octree |",
           "|---|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        o, s = r["octree"], r["segment_on_finest"]
        out.append("| %s | %d %% | %d | %s | %d | %s | %s |" % (
            r["model"], r["percent"], o["triangles"], pct(o["rms"]), s["triangles"],
            pct(s["rms"]), ratio(s["rms"], o["rms"])))
    return out


def table_speed(sp):
    rows = sp["meshopt"]
    cpu = any(r.get("cpu_seconds") is not None for r in rows)
    base = any(r.get("baseline_seconds") is not None for r in rows)
    head = "| input | search | triangles | segment s | meshopt_simplify s | segment / meshopt | RMS |"
    rule = "|---|---|---:|---:|---:|---:|---:|"
    if cpu:
        head += " segment CPU s | meshopt_lod CPU s | CPU ratio |"
        rule += "---:|---:|---:|"
    if base:
        head += " before s | before CPU s | before / now (CPU) | before: triangles, RMS | same file |"
        rule += "---:|---:|---:|---:|---|"
    out = [head, rule]
    for r in rows:
        line = "| %s | %s | %d | %.2f | %.3f | %.1f | %s |" % (
            r["input"], "RMS (50000 samples)" if r["mode"] == "default" else "vertex estimate",
            r["triangles"], r["seconds"], r["meshopt_seconds"], r["seconds"] / r["meshopt_seconds"],
            pct(r["rms"]))
        if cpu:
            line += " %.2f | %.2f | %.1f |" % (r["cpu_seconds"], r["meshopt_cpu_seconds"],
                                               r["cpu_seconds"] / r["meshopt_cpu_seconds"])
        if base:
            line += " %.2f | %.2f | %.2f | %d, %s | %s |" % (
                r["baseline_seconds"], r["baseline_cpu_seconds"],
                r["baseline_cpu_seconds"] / r["cpu_seconds"], r["baseline_triangles"],
                pct(r["baseline_rms"]), "yes" if r["baseline_identical"] else "no")
        out.append(line)
    if not sp["vsa"]:
        return out
    out += ["", "| input | triangles | segment s | segment RMS | VSA triangles | VSA proxies | "
            "VSA s (the run at that count) | VSA s (search, %s runs) | VSA / segment | VSA RMS | VSA watertight |" % "n",
            "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|"]
    for r in sp["vsa"]:
        out.append("| %s | %d | %.2f | %s | %d | %d | %.2f | %.1f (%d) | %.1f | %s | %s |" % (
            r["model"], r["triangles"], r["seconds"], pct(r["rms"]), r["vsa_triangles"],
            r["vsa_proxies"], r["vsa_seconds"], r["vsa_search_seconds"], r["vsa_runs"],
            r["vsa_seconds"] / r["seconds"], pct(r["vsa_rms"]),
            "yes" if r["vsa_watertight"] else "no"))
    return out


def plot(rows, dest):
    """RMS against triangles per input: segment, meshopt, octree (log-log)."""
    models = []
    for r in rows:
        if r["model"] not in models:
            models.append(r["model"])
    with tempfile.TemporaryDirectory() as tmp:
        script = ['set terminal pngcairo size 1200,%d font "sans,10" linewidth 1.5' % (300 * ((len(models) + 2) // 3)),
                  'set output "%s"' % dest, "set multiplot layout %d,3" % ((len(models) + 2) // 3),
                  "set logscale xy", "set key top right", "set grid"]
        for m in models:
            path = os.path.join(tmp, m + ".dat")
            with open(path, "w") as f:
                for r in rows:
                    if r["model"] == m:
                        f.write("%d %g %d %g %d %g\n" % (
                            r["segment"]["triangles"], 100 * r["segment"]["rms"],
                            r["meshopt"]["triangles"], 100 * r["meshopt"]["rms"],
                            r["octree"]["triangles"], 100 * r["octree"]["rms"]))
            script += ['set title "%s" noenhanced' % m, 'set xlabel "triangles"', 'set ylabel "RMS, % of diagonal"',
                       'plot "%s" u 1:2 w lp t "segment", "" u 3:4 w lp t "meshopt", "" u 5:6 w lp t "octree"' % path]
        script.append("unset multiplot")
        with open(os.path.join(tmp, "p.gp"), "w") as f:
            f.write("\n".join(script) + "\n")
        subprocess.run(["gnuplot", os.path.join(tmp, "p.gp")], check=True)


def replace_between(path, begin, end, text):
    """The block from `begin` to `end` (markers included) becomes text between the markers,
    or is appended; with text None it is dropped, if it is there."""
    s = open(path).read() if os.path.exists(path) else ""
    if text is None:
        if begin not in s or end not in s:
            return
        s = s[:s.index(begin)].rstrip() + "\n" + s[s.index(end) + len(end):]
    elif begin in s and end in s:
        block = begin + "\n" + text.rstrip() + "\n" + end
        s = s[:s.index(begin)] + block + s[s.index(end) + len(end):]
    else:
        s = s.rstrip() + "\n\n" + begin + "\n" + text.rstrip() + "\n" + end + "\n"
    with open(path + ".tmp", "w") as f:
        f.write(s)
    os.replace(path + ".tmp", path)


def cmd_report(args):
    """report RESULTS.json [MORE.json ...] DOCS: the parts (paper, fidelity, finest, speed)
    a later file has and the first lacks are taken from it (runs made side by side)."""
    results, docs = args[0], args[-1]
    res = json.load(open(results))
    for more in args[1:-1]:
        extra = json.load(open(more))
        for part in ("paper", "fidelity", "finest", "speed"):
            if part in extra and part not in res:
                res[part] = extra[part]
                res.setdefault("part_machine", {})[part] = extra["machine"]
        for key in ("models",):
            if key in extra and key not in res:
                res[key] = extra[key]
        results = results + "` and `" + os.path.basename(more)
    mach = res["machine"]
    head = ("Generated by `scripts/bench/bench_segment.sh` from `%s` (%s, commit %s, %s build, "
            "%s cores, load average %.1f at the start%s); %d area samples per surface in every "
            "`scanlod compare`. RMS and Hausdorff: symmetric, in %% of the input's bounding-box "
            "diagonal.\n" % (os.path.basename(results), mach["date"], mach["commit"],
                              mach.get("build_type", "?"), mach["cores"], mach["load"],
                              ", %.1f at the end" % mach["load_end"] if "load_end" in mach else "",
                              res["samples"]))
    partial = "models" in res  # a run on some inputs: reported under the full run's tables
    if partial:
        head = head.replace("Generated by", "A partial run (fidelity: %s; speed) generated by"
                            % ", ".join(res["models"]), 1)
    sec = ["### Update: the faster search (%s)\n" % mach["date"] if partial else
           "## 6. The segment method (paper 3, issue 12)\n", head]
    for part, pm in sorted(res.get("part_machine", {}).items()):
        sec += ["Its %s part ran at the same time, from the second file: %s, commit %s, load "
                "average %.1f at its start%s.\n" % (part, pm["date"], pm["commit"], pm["load"],
                ", %.1f at its end" % pm["load_end"] if "load_end" in pm else "")]
    if "baseline" in res:
        sec += ["`before` is the same benchmark run with another scanlod binary (`%s`, the code "
                "before the change), alternately with this build on each input.\n"
                % os.path.basename(res["baseline"])]
    if "fidelity" in res:
        sec += ["### Fidelity at equal triangle counts\n",
                "`scanlod simplify --ratio B/100` (default config), then meshopt_simplify to the "
                "count it produced and the octree model's largest cut within it (`scanlod extract "
                "--triangles`). Ratios below 1: the segment method is closer.\n"]
        if any(r.get("remeasured") for r in res["fidelity"]):
            sec += ["This run was stopped during its fidelity part (the machine's two cores were "
                    "shared; dragon_100kf at 2 %% took 6 minutes): the rows are the levels it had "
                    "written, measured again by `segment.py remeasure` with the same %d samples; "
                    "their times are not known (–), the inputs it had not reached are missing.\n"
                    % res["samples"]]
        sec += table_fidelity(res["fidelity"]) + ["", "![RMS against triangles](bench/segment_rms.png)", ""]
        os.makedirs(os.path.join(docs, "bench"), exist_ok=True)
        png = "segment_rms_update.png" if partial else "segment_rms.png"
        if partial:
            sec[-2] = "![RMS against triangles](bench/%s)" % png
        plot(res["fidelity"], os.path.join(docs, "bench", png))
    if "finest" in res:
        sec += ["### The segment method as a pass on the octree's finest level\n",
                "The octree's finest level (`extract --lod-percent 100`) simplified by the segment "
                "method to the triangle count of the octree's own cut at 5, 10 and 20 % of the "
                "input; both measured against the input.\n"]
        if "finest_machine" in res:
            fm = res["finest_machine"]
            sec += ["This part was run on its own (`segment.py run ... 1 finest`, quick: fandisk and "
                    "rocker_arm) at %s, commit %s, load average %.1f.\n" % (fm["date"], fm["commit"], fm["load"])]
        sec += table_finest(res["finest"]) + [""]
    if "speed" in res:
        sec += ["### Speed\n",
                "`simplify_seconds` of `scanlod simplify --ratio 0.1` (segmentation, the level "
                "search and every pass; not reading, cleaning or writing) against meshopt_lod's "
                "time for meshopt_simplify to the same count (after its weld), median of %d runs; "
                "and against CGAL VSA (`vsa_lod --triangles N`), whose figure is the single run "
                "at the proxy count that meets the count (its search runs it several times).\n"
                % (res["speed"]["meshopt"][0]["reps"] if res["speed"]["meshopt"] else 0)]
        if any(r.get("cpu_seconds") is not None for r in res["speed"]["meshopt"]):
            sec += ["CPU s: user + system seconds of the whole process (reading, cleaning and "
                    "writing included; meshopt_lod's with its weld), medians of the same runs: "
                    "a shared machine disturbs them far less than the wall times.\n"]
        sec += table_speed(res["speed"]) + [""]
    os.makedirs(os.path.join(docs, "bench"), exist_ok=True)
    if partial:
        with open(os.path.join(docs, "bench", "segment-update.md"), "w") as f:
            f.write("\n".join(sec).rstrip() + "\n")
        replace_between(os.path.join(docs, "benchmarks.md"), "<!-- segment-update:begin -->",
                        "<!-- segment-update:end -->", "\n".join(sec))
        log("wrote %s/bench/segment-update.md and its part of benchmarks.md" % docs)
        return
    with open(os.path.join(docs, "bench", "segment-section.md"), "w") as f:
        f.write("\n".join(sec).rstrip() + "\n")
    # a full run supersedes a partial one's tables
    for stale in ("segment-update.md", "segment_rms_update.png"):
        if os.path.exists(os.path.join(docs, "bench", stale)):
            os.remove(os.path.join(docs, "bench", stale))
    replace_between(os.path.join(docs, "benchmarks.md"), "<!-- segment-update:begin -->",
                    "<!-- segment-update:end -->", None)
    replace_between(os.path.join(docs, "benchmarks.md"), "<!-- segment:begin -->",
                    "<!-- segment:end -->", "\n".join(sec))
    if "paper" in res:
        replace_between(os.path.join(docs, "segmentation.md"), "<!-- paper-experiment:begin -->",
                        "<!-- paper-experiment:end -->",
                        "\n".join([head] + table_paper(res["paper"])))
    log("wrote %s/bench/segment-section.md and the sections of benchmarks.md, segmentation.md" % docs)


ROOT = None
if __name__ == "__main__":
    if len(sys.argv) < 2 or sys.argv[1] not in ("run", "report", "remeasure"):
        sys.exit(__doc__)
    {"run": cmd_run, "report": cmd_report, "remeasure": cmd_remeasure}[sys.argv[1]](sys.argv[2:])
