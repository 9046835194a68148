"""Parsing and statistics of the benchmark harness (pure functions, no I/O but files read).

Everything the harness computes from raw figures lives here, so that
tests/bench/test_bench_harness.sh can check it on canned inputs without a build.
"""
import json
import math
import re
import statistics

# the default method's stages in run order (segment and cluster: their own phases)
STAGES = ["range", "samples", "merge", "priority", "crack", "refine", "export"]


def summary(values):
    """{"median", "min", "max", "n"} of a list of numbers (None entries skipped)."""
    vals = [float(v) for v in values if v is not None]
    if not vals:
        return {"median": None, "min": None, "max": None, "n": 0}
    return {"median": statistics.median(vals), "min": min(vals), "max": max(vals),
            "n": len(vals)}


def median(values):
    return summary(values)["median"]


def pair_ratios(numerators, denominators):
    """Ratio of run i to run i (pairs measured in the same repetition)."""
    return [a / b for a, b in zip(numerators, denominators)
            if a is not None and b is not None and b > 0]


def load_timings(path):
    """timings.json -> {stage: {"seconds", "cpu_seconds", "peak_rss_kb", "threads"}}."""
    with open(path) as f:
        return json.load(f)["stages"]


def stage_record(samples_by_stage):
    """[{stage: record}, ...] (one per repetition) -> {stage: {field: summary}}."""
    out = {}
    for stage in STAGES:
        rows = [rep[stage] for rep in samples_by_stage if stage in rep]
        if not rows:
            continue
        out[stage] = {key: summary([r.get(key) for r in rows])
                      for key in ("seconds", "cpu_seconds", "peak_rss_kb")}
    return out


EXTRACT_RE = re.compile(
    r"(?P<triangles>\d+) triangles, (?P<vertices>\d+) vertices"
    r"(?:, max error (?P<max_error>[-+0-9.eE]+|inf|nan))?"
    r"(?:, generated in (?P<seconds>[-+0-9.eE]+) s)?"
    r"(?:, then (?P<repeat>\d+) more in median (?P<warm>[-+0-9.eE]+) s)?")


def parse_extract(text):
    """One line of `scanlod extract` -> {"triangles", "vertices", "seconds", "expansions"}.

    Model extraction: "expansions K of T: N triangles, V vertices, max error E,
    generated in X s[, then R more in median W s (min M s)] -> out.ply" (X: the first
    extraction in the process, "seconds"; W: the warm median, "warm_seconds"); octree levels: "level L: N triangles, V vertices -> out".
    """
    m = EXTRACT_RE.search(text)
    if not m:
        raise ValueError("unrecognised extract output: %r" % text.strip()[:200])
    out = {"triangles": int(m.group("triangles")), "vertices": int(m.group("vertices")),
           "seconds": float(m.group("seconds")) if m.group("seconds") else None,
           "warm_seconds": float(m.group("warm")) if m.group("warm") else None}
    e = re.search(r"expansions (\d+) of (\d+)", text)
    if e:
        out["expansions"] = int(e.group(1))
    return out


def fidelity(compare_json):
    """The figures the tables use from `scanlod compare --json`: B's triangles, the
    symmetric RMS and Hausdorff (fractions of A's diagonal), B's topology (boundary
    edges, watertight, connected parts and the largest part's share of B's area)."""
    d = compare_json if isinstance(compare_json, dict) else json.loads(compare_json)
    topo = d.get("b_topology", {})
    return {"triangles": d["b_triangles"], "rms": d["rms"], "hausdorff": d["hausdorff"],
            "boundary_edges": topo.get("boundary_edges"),
            "watertight": topo.get("watertight"), "components": topo.get("components"),
            "largest_area": topo.get("largest_component_area_fraction")}


# --- the fidelity anchor (lib/fidelity.py) ---------------------------------------------
ANCHOR_RATIO = 1.5      # an RMS ratio ours / simplifyWithUpdate above this is counted
BUDGET_TOLERANCE = 0.01  # |count - budget| / budget beyond this is a budget miss
PART_FLOOR = 0.99       # the largest part's area share below this is a part lost


def budget_targets(triangles, percents):
    """[(percent, name, count)]: P % of the input's triangles as the named budget pP
    (at least 1 triangle)."""
    return [(p, "p%g" % p, max(1, int(round(p / 100.0 * triangles)))) for p in percents]


def budget_setting(targets):
    """The `levels.budgets` value of budget_targets: "p1:129,p2:259,..."."""
    return ",".join("%s:%d" % (name, n) for _, name, n in targets)


def budget_error(count, budget):
    return abs(count - budget) / float(budget) if budget else None


def ratio(a, b):
    return a / b if a is not None and b else None


def cached_at(entries, count, tolerance=0.0):
    """(count used, entry) from {count as str: entry}: the exact count, else (tolerance
    > 0) the nearest cached count within tolerance of it (relative), else None."""
    if str(count) in entries:
        return count, entries[str(count)]
    near = [(abs(int(k) - count), int(k)) for k in entries]
    near = [x for x in near if x[0] <= tolerance * count]
    if not near:
        return None
    k = min(near)[1]
    return k, entries[str(k)]


def anchor_summary(pairs, inputs):
    """The anchor's figures over pairs (rows of lib/fidelity.py; inputs: {name: facts}):
    RMS ratio ours / simplifyWithUpdate (median, max and its pair, pairs above
    ANCHOR_RATIO), Hausdorff ratio median, RMS ratio medians against simplify and
    meshoptimizer 0.18, budget misses beyond BUDGET_TOLERANCE, pairs whose largest part
    holds less than PART_FLOOR of the area where the input's holds at least that, pairs
    not watertight where the input is."""
    rr = [(p["rms_ratio"], p) for p in pairs if p.get("rms_ratio") is not None]
    worst = max(rr, key=lambda x: x[0]) if rr else (None, None)
    part_pairs = [p for p in pairs if (inputs[p["input"]].get("largest_area") or 0) >= PART_FLOOR]
    wt_pairs = [p for p in pairs if inputs[p["input"]].get("watertight")]
    return {
        "pairs": len(pairs),
        "rms_ratio": summary([x[0] for x in rr]),
        "rms_worst": {"input": worst[1]["input"], "percent": worst[1]["percent"]}
        if worst[1] else None,
        "rms_above": sum(1 for x in rr if x[0] > ANCHOR_RATIO),
        "hausdorff_ratio": summary([p.get("hausdorff_ratio") for p in pairs]),
        "rms_ratio_simplify": summary([p.get("rms_ratio_simplify") for p in pairs]),
        "rms_ratio_mo18": summary([p.get("rms_ratio_mo18") for p in pairs]),
        "budget_error": summary([p.get("budget_error") for p in pairs]),
        "budget_misses": sum(1 for p in pairs if (p.get("budget_error") or 0) > BUDGET_TOLERANCE),
        "part_pairs": len(part_pairs),
        "part_losses": sum(1 for p in part_pairs
                           if (p["ours"].get("largest_area") or 0) < PART_FLOOR),
        "watertight_pairs": len(wt_pairs),
        "not_watertight": sum(1 for p in wt_pairs if not p["ours"].get("watertight")),
    }


def loglog_slope(xs, ys):
    """Least-squares slope of log(y) against log(x): y ~ x^slope. None below 2 points."""
    pts = [(math.log(x), math.log(y)) for x, y in zip(xs, ys)
           if x and y and x > 0 and y > 0]
    if len(pts) < 2:
        return None
    mx = sum(p[0] for p in pts) / len(pts)
    my = sum(p[1] for p in pts) / len(pts)
    sxx = sum((p[0] - mx) ** 2 for p in pts)
    if sxx == 0:
        return None
    return sum((p[0] - mx) * (p[1] - my) for p in pts) / sxx


def growth_word(slope):
    if slope is None:
        return "not enough sizes to fit"
    if slope < 0.9:
        return "sub-linear"
    if slope <= 1.15:
        return "about linear"
    return "super-linear"


def closest(candidates, target, key="triangles"):
    """The candidate whose `key` is closest to target (relative); None for an empty list."""
    good = [c for c in candidates if c.get(key)]
    if not good:
        return None
    return min(good, key=lambda c: abs(c[key] - target) / float(target))


def next_adaptivity(tried, target, lo=0.0, hi=1.0):
    """Bisection step for OpenVDB adaptivity: triangle count falls as adaptivity rises.

    tried: {adaptivity: triangles}. Returns the next adaptivity to try, or None when
    the bracket is narrower than 0.01 or the target lies outside what [lo, hi] reaches.
    """
    below = [a for a, n in tried.items() if n >= target]   # too many triangles
    above = [a for a, n in tried.items() if n < target]    # too few
    a_lo = max(below) if below else lo
    a_hi = min(above) if above else hi
    if not above and hi in tried:
        return None          # even the highest adaptivity has too many triangles
    if not below and lo in tried:
        return None          # even adaptivity 0 has too few
    if not above:
        return hi
    if not below:
        return lo
    if a_hi - a_lo < 0.01:
        return None
    return round((a_lo + a_hi) / 2, 4)


def per_triangle(ladder):
    """Extraction ladder rows {"triangles", "seconds"} -> adds "ns_per_triangle";
    returns (rows, max/min ratio of the per-triangle cost)."""
    rows = []
    for r in ladder:
        r = dict(r)
        r["ns_per_triangle"] = (1e9 * r["seconds"] / r["triangles"]
                                if r.get("seconds") and r.get("triangles") else None)
        rows.append(r)
    costs = [r["ns_per_triangle"] for r in rows if r["ns_per_triangle"]]
    ratio = max(costs) / min(costs) if costs else None
    return rows, ratio
