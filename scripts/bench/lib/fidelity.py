"""Phase fidelity: the published levels against the fidelity anchor, meshoptimizer 1.3.

Per method of ctx.fidelity_methods ("default": the default config; octree, segment,
cluster: `-s lod.method=M`, each method alone) and per input of ctx.fidelity_inputs: one
`scanlod run` (2 threads, a fresh work folder, stopped after ctx.fidelity_timeout seconds)
with the default config plus `[export] budgets` = pP:N for each P of ctx.fidelity_budgets,
N = P % of the input's triangles. The level each budget published (report.json: its
`file`, a level equal to an earlier one is published under that one's name) is measured
by `scanlod compare INPUT LEVEL` (ctx.compare_samples area samples, the export's own
setting), and so are the anchors at that level's triangle count, each from the whole
input: meshoptimizer 1.3.0 `simplifyWithUpdate` and `simplify` (peers/meshopt_js.mjs,
npm; flags Prune, no error limit) and meshoptimizer 0.18 `meshopt_simplify`
(peers/meshopt_lod.c, Debian). The build's time and peak memory come from its
timings.json (the stages' child processes), its wall time from the harness.

The anchors' figures depend only on the input (its bytes), the count and the peers'
settings: they are kept in ctx.peer_cache (BUILD/bench-results/fidelity-peers.json)
across runs. A run measures them afresh unless ctx.reuse_peers, which takes a cached
figure at the same count, else at the nearest cached count within 1 % (the pair says
which count), and runs the peers only for the rest.
Writes RESULTS/fidelity.json after every input.
"""
import datetime
import hashlib
import json
import os
import shutil
import sys
import time

import stats
from common import Collection, Ctx, Timeout, compare, log, meshopt, run, run_json

DEFAULT_INPUTS = ["armadillo_86kf", "bun_zipper", "dragon_100kf", "fandisk", "igea",
                  "lucy_100kf", "nefertiti", "rocker_arm", "usnm_1145291"]
DEFAULT_BUDGETS = [1, 2, 5, 10, 20, 50]
REUSE_TOLERANCE = 0.01
JS_FLAGS = ["Prune"]
JS_TARGET_ERROR = "1e10"
PEERS = ("update", "simplify", "mo18")
JS_FUNCTION = {"simplifyWithUpdate": "update", "simplify": "simplify"}


def sha1(path):
    h = hashlib.sha1()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def input_facts(ctx, name):
    """Triangles and topology of the input itself (compare it with itself)."""
    ply = ctx.input_ply(name)
    d = run_json([ctx.scanlod, "compare", ply, ply, "--samples", 1000, "--json"])
    t = d["b_topology"]
    return {"triangles": d["a_triangles"], "watertight": t["watertight"],
            "boundary_edges": t["boundary_edges"], "components": t.get("components"),
            "largest_area": t.get("largest_component_area_fraction"), "sha1": sha1(ply)}


class Anchors:
    """The anchors' figures per (input, count), through the cache in ctx.peer_cache."""

    def __init__(self, ctx):
        self.ctx = ctx
        self.js = os.path.join(ctx.repo, "scripts", "bench", "peers", "meshopt_js.mjs")
        pkg = os.path.join(ctx.repo, "scripts", "bench", "peers", "npm", "node_modules",
                           "meshoptimizer", "package.json")
        with open(pkg) as f:
            js_version = json.load(f)["version"]
        probe = os.path.join(ctx.repo, "tests", "data", "scans", "cow.ply")
        v = meshopt(ctx, probe, [1000])["version"]   # MESHOPTIMIZER_VERSION: 180 is 0.18
        self.versions = {"meshoptimizer_js": js_version,
                         "meshoptimizer": "%d.%d" % (v // 1000, (v % 1000) // 10)}
        js = "meshoptimizer %s (npm) %%s flags=%s target_error=%s" % (
            js_version, ",".join(JS_FLAGS), JS_TARGET_ERROR)
        self.settings = {"update": js % "simplifyWithUpdate", "simplify": js % "simplify",
                         "mo18": "meshoptimizer %s meshopt_simplify target_error=1"
                         % self.versions["meshoptimizer"]}
        self.cache = {}
        if os.path.exists(ctx.peer_cache):
            with open(ctx.peer_cache) as f:
                self.cache = json.load(f)
        self.ran = self.reused = 0
        self.fresh = set()   # (key, count) measured by this run

    def key(self, digest, peer):
        return "%s %s samples=%d" % (digest, self.settings[peer], self.ctx.compare_samples)

    def save(self):
        tmp = self.ctx.peer_cache + ".tmp"
        with open(tmp, "w") as f:
            json.dump(self.cache, f, indent=0, sort_keys=True)
        os.replace(tmp, self.ctx.peer_cache)

    def measure(self, ref, level):
        row = compare(self.ctx, ref, level["output"])
        row.update({k: level[k] for k in ("target", "reached", "result_error", "seconds")})
        os.remove(level["output"])
        return row

    def at(self, name, facts, counts, work):
        """{count: {peer: figures + "count" (the count it ran at)}}; None for a count
        at or above the input's (nothing to simplify)."""
        ctx, ref = self.ctx, self.ctx.input_ply(name)
        tol = REUSE_TOLERANCE if ctx.reuse_peers else None
        out, todo = {}, {p: set() for p in PEERS}
        for n in counts:
            if n >= facts["triangles"]:
                out[n] = None
                continue
            out[n] = {}
            for p in PEERS:
                key = self.key(facts["sha1"], p)
                # measured earlier in this run (another method landed on the same count)
                hit = ((n, self.cache[key][str(n)]) if (key, n) in self.fresh else
                       stats.cached_at(self.cache.get(key, {}), n, tol) if tol is not None
                       else None)
                if hit:
                    out[n][p] = dict(hit[1], count=hit[0], cached=True)
                    self.reused += 1
                else:
                    todo[p].add(n)
        js = sorted(todo["update"] | todo["simplify"])
        if js:
            d = run_json(["node", self.js, ref, "--targets", ",".join(map(str, js)),
                          "-o", os.path.join(work, "js"), "--flags", ",".join(JS_FLAGS),
                          "--target-error", JS_TARGET_ERROR])
            for lv in d["levels"]:
                self.store(facts, out, JS_FUNCTION[lv["function"]], self.measure(ref, lv))
        if todo["mo18"]:
            mo = meshopt(ctx, ref, sorted(todo["mo18"]), os.path.join(work, "mo18"))
            for lv in mo["levels"]:
                self.store(facts, out, "mo18", self.measure(ref, lv))
        self.save()
        return out

    def store(self, facts, out, peer, row):
        n, key = row["target"], self.key(facts["sha1"], peer)
        self.cache.setdefault(key, {})[str(n)] = row
        self.fresh.add((key, n))
        out[n][peer] = dict(row, count=n, cached=False)
        self.ran += 1


def pair(name, facts, p, budget_name, budget, level, ours, anchors):
    """One row: our level at budget pP against the anchors at its triangle count."""
    a = anchors or {}
    up, si, mo = a.get("update") or {}, a.get("simplify") or {}, a.get("mo18") or {}
    return {"input": name, "percent": p, "name": budget_name, "budget": budget,
            "file": level.get("file", level["name"]), "clamped": level.get("clamped"),
            "triangles": ours["triangles"],
            "budget_error": stats.budget_error(ours["triangles"], budget),
            "ours": ours, "update": up or None, "simplify": si or None, "mo18": mo or None,
            "is_input": anchors is None,
            "rms_ratio": stats.ratio(ours["rms"], up.get("rms")),
            "hausdorff_ratio": stats.ratio(ours["hausdorff"], up.get("hausdorff")),
            "rms_ratio_simplify": stats.ratio(ours["rms"], si.get("rms")),
            "rms_ratio_mo18": stats.ratio(ours["rms"], mo.get("rms"))}


def build(ctx, method, name, facts, anchors):
    """One input with one method: the run, its published budget levels, the pairs."""
    ref = ctx.input_ply(name)
    targets = stats.budget_targets(facts["triangles"], ctx.fidelity_budgets)
    overrides = ["levels.budgets=" + stats.budget_setting(targets), "levels.percents="]
    if method != "default":
        overrides.append("lod.method=" + method)
    c = Collection(ctx.scratch_dir("fidelity", method, name), name, ref)
    item = {"overrides": overrides}
    t0 = time.time()
    try:
        timings = c.run(ctx, 2, overrides, timeout=ctx.fidelity_timeout)
    except Timeout:
        log("fidelity: %s %s stopped after %d s" % (method, name, ctx.fidelity_timeout))
        item.update(status="timeout", wall_seconds=time.time() - t0)
        return item
    except RuntimeError as e:
        log("fidelity: %s %s failed: %s" % (method, name, e))
        item.update(status="failed", error=str(e)[-300:], wall_seconds=time.time() - t0)
        return item
    item.update(status="ok", wall_seconds=time.time() - t0, stages=timings,
                build_seconds=sum(s["seconds"] for s in timings.values()),
                cpu_seconds=sum(s["cpu_seconds"] for s in timings.values()),
                peak_rss_kb=max(s["peak_rss_kb"] for s in timings.values()))
    report = c.report()
    item["method"] = report.get("method")
    levels = {lv["name"]: lv for lv in report["stages"]["export"]["levels"]}
    ours = []
    for p, budget_name, budget in targets:
        lv = levels[budget_name]
        ply = c.path("out", c.item_id, lv.get("file", lv["name"]) + ".ply")
        ours.append((p, budget_name, budget, lv, compare(ctx, ref, ply)))
    shutil.rmtree(c.path("work"), ignore_errors=True)   # the artifacts are not needed now
    counts = sorted({o[4]["triangles"] for o in ours})
    at = anchors.at(name, facts, counts, ctx.scratch_dir("fidelity", "peers", name))
    item["pairs"] = [pair(name, facts, p, bn, b, lv, o, at[o["triangles"]])
                     for p, bn, b, lv, o in ours]
    return item


def git(ctx, *args):
    try:
        return run(["git", "-C", ctx.repo] + list(args)).strip()
    except (OSError, RuntimeError):
        return ""


def main():
    ctx = Ctx(sys.argv[1])
    ctx.fidelity_inputs = ctx.fidelity_inputs or DEFAULT_INPUTS
    ctx.fidelity_budgets = ctx.fidelity_budgets or DEFAULT_BUDGETS
    missing = [n for n in ctx.fidelity_inputs if not os.path.exists(ctx.input_ply(n))]
    if missing:
        raise SystemExit("fidelity: no %s in %s" % (", ".join(missing), ctx.data))
    anchors = Anchors(ctx)
    commit = git(ctx, "rev-parse", "--short", "HEAD") or "unknown"
    if git(ctx, "status", "--porcelain", "--untracked-files=no"):
        commit += " (with uncommitted changes)"
    out = {"commit": commit, "load_start": os.getloadavg()[0],
           "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
           "complete": (sorted(ctx.fidelity_inputs) == sorted(DEFAULT_INPUTS) and
                        sorted(ctx.fidelity_budgets) == sorted(DEFAULT_BUDGETS)),
           "settings": {"inputs": ctx.fidelity_inputs, "budgets": ctx.fidelity_budgets,
                        "methods": ctx.fidelity_methods, "samples": ctx.compare_samples,
                        "threads": 2, "timeout_seconds": ctx.fidelity_timeout,
                        "reuse_peers": ctx.reuse_peers, "peers": anchors.settings,
                        "js_flags": JS_FLAGS, "js_target_error": JS_TARGET_ERROR,
                        "versions": anchors.versions},
           "inputs": {}, "methods": {}}
    for name in ctx.fidelity_inputs:
        out["inputs"][name] = input_facts(ctx, name)
    t_all = time.time()
    for method in ctx.fidelity_methods:
        m = out["methods"][method] = {"items": {}}
        t0 = time.time()
        for name in ctx.fidelity_inputs:
            log("fidelity: %s, %s" % (method, name))
            m["items"][name] = build(ctx, method, name, out["inputs"][name], anchors)
            m["seconds"] = time.time() - t0
            ctx.save("fidelity", out)
        s = stats.anchor_summary([p for it in m["items"].values() for p in it.get("pairs", [])],
                                 out["inputs"])
        log("fidelity: %s: RMS / simplifyWithUpdate median %.2f, max %.2f, %d above %.1fx; "
            "budget misses %d of %d" % (method, s["rms_ratio"]["median"] or 0,
                                        s["rms_ratio"]["max"] or 0, s["rms_above"],
                                        stats.ANCHOR_RATIO, s["budget_misses"], s["pairs"]))
    out["seconds"] = time.time() - t_all
    out["peers_run"], out["peers_reused"] = anchors.ran, anchors.reused
    ctx.save("fidelity", out)


if __name__ == "__main__":
    main()
