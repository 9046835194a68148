"""The benchmark's PNG plots, drawn by gnuplot (pngcairo) from a results folder.

usage: plots.py RESULTS_DIR OUT_DIR
Writes error_vs_triangles.png, stage_times.png, extract_cost.png, growth.png (each only
when its phase has results). Data files and gnuplot scripts go to a temporary folder.
"""
import math
import os
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import headline  # noqa: E402
import stats  # noqa: E402

TERM = 'set terminal pngcairo size %d,%d font "sans,11" linewidth 1.5\n'
COLORS = {"scanlod": "#1f77b4", "uniform": "#9467bd", "meshopt": "#ff7f0e",
          "finest": "#d62728", "vdb": "#2ca02c"}


def write(path, rows):
    with open(path, "w") as f:
        for r in rows:
            f.write(" ".join("NaN" if c is None else str(c) for c in r) + "\n")


def gnuplot(script, tmp, name):
    p = os.path.join(tmp, name + ".gp")
    with open(p, "w") as f:
        f.write(script)
    subprocess.run(["gnuplot", p], check=True)


def grid(n):
    cols = n if n <= 2 else 2
    return int(math.ceil(n / float(cols))), cols


def error_plot(lod, oc, tmp, out):
    names = list(lod)
    rows, cols = grid(len(names))
    s = TERM % (640 * cols, 460 * rows + 40)
    s += 'set output "%s"\n' % os.path.join(out, "error_vs_triangles.png")
    s += ('set multiplot layout %d,%d title "RMS distance to the input at equal triangle '
          'counts (lower is better)"\n' % (rows, cols))
    s += ('set logscale xy\nset grid\nset key bottom left box opaque font ",9"\n'
          'set xlabel "triangles (log)"\nset ylabel "RMS error (% of bbox diagonal, log)"\n'
          'set format x "%.0s%c"\nset format y "%g"\n')
    for name in names:
        series = {"scanlod": [], "meshopt": [], "vdb": [], "uniform": [], "finest": []}
        for e in lod[name]["equal_counts"]:
            if e.get("meshopt_finest"):
                series["finest"].append((e["triangles"], 100 * e["meshopt_finest"]["rms"]))
            for k in ("scanlod", "meshopt", "vdb"):
                if k == "meshopt" and e[k].get("is_input"):
                    continue   # the input itself: no simplification, RMS 0
                series[k].append((e[k]["triangles"], 100 * e[k]["rms"]))
        lo = min(x[0] for k in ("scanlod", "meshopt", "vdb") for x in series[k])
        for r in (oc or {}).get("levels", {}).get(name, []):
            if r["triangles"] >= lo / 2:
                series["uniform"].append((r["triangles"], 100 * r["scanlod"]["rms"]))
        for k, v in series.items():
            write(os.path.join(tmp, "err_%s_%s.dat" % (name, k)), sorted(v))
        vdb_label = "OpenVDB adaptive%s" % (" (unsigned)" if lod[name]["equal_counts"][0]
                                            ["vdb"].get("unsigned") else "")
        ys = [y for v in series.values() for _, y in v if y > 0]
        s += 'set yrange [%g:%g]\n' % (min(ys) / 30.0, max(ys) * 2.0)   # room for the key
        s += 'set title "%s"\n' % name.replace("_", "\\\\_")
        s += "plot " + ", ".join(
            '"%s" using 1:2 with linespoints pt %d ps 1.2 lc rgb "%s" title "%s"'
            % (os.path.join(tmp, "err_%s_%s.dat" % (name, k)), pt, COLORS[k], title)
            for k, pt, title in (("scanlod", 7, "scanlod LOD (adaptive)"),
                                 ("uniform", 6, "scanlod uniform octree level"),
                                 ("meshopt", 5, "meshoptimizer simplify of the input"),
                                 ("finest", 4, "meshoptimizer of scanlod's finest"),
                                 ("vdb", 9, vdb_label)) if series[k]) + "\n"
    s += "unset multiplot\n"
    gnuplot(s, tmp, "error")


def stage_plot(h, tmp, out):
    data = os.path.join(tmp, "stages.dat")
    rows = [["input"] + stats.STAGES]
    for name, per in h["stages"].items():
        for t in ("1", "2"):
            label = "%s\\n%s thr" % (name.replace("_", "\\\\_"), t)
            rows.append(['"%s"' % label] + [per[s][t]["seconds"]["median"]
                                             if s in per else 0 for s in stats.STAGES])
    write(data, rows)
    n = len(rows) - 1
    s = TERM % (max(900, 110 * n + 260), 600)
    s += 'set output "%s"\n' % os.path.join(out, "stage_times.png")
    s += ('set title "scanlod wall time per stage (median), 1 and 2 threads"\n'
          'set style data histograms\nset style histogram rowstacked\n'
          'set style fill solid 0.85 border -1\nset boxwidth 0.7\n'
          'set ylabel "wall time (s)"\nset grid ytics\nset key outside right top\n'
          'set xtics nomirror font ",9"\nset yrange [0:*]\nset bmargin 5\n')
    s += 'plot for [i=2:%d] "%s" using i:xtic(1) title columnheader(i)\n' % (
        len(stats.STAGES) + 1, data)
    gnuplot(s, tmp, "stages")


def extract_plot(h, lod, tmp, out):
    names = list(h["ladder"])
    s = TERM % (1300, 520)
    s += 'set output "%s"\n' % os.path.join(out, "extract_cost.png")
    s += 'set multiplot layout 1,2 title "LOD extraction from the .slod model (medians)"\n'
    s += ('set logscale x\nset grid\nset key bottom left box opaque\n'
          'set title "time per output triangle (flat = O(m))"\n'
          'set xlabel "budget (% of the finest level\'s triangles, log)"\n'
          'set ylabel "generation time per triangle (ns)"\nset yrange [0:*]\n')
    left, right = [], []   # per-triangle cost; absolute times beside meshopt
    for i, name in enumerate(names):
        f = os.path.join(tmp, "ladder_%s.dat" % name)
        write(f, [(x["percent"], x["ns_per_triangle"], x["triangles"], x["seconds"]["median"],
                   x["meshopt_seconds"]["median"] if x["percent"] < 100 else None)
                  for x in h["ladder"][name]["rows"]])
        label = name.replace("_", "\\\\_")
        left.append('"%s" using 1:2 with linespoints pt 7 lc %d title "%s"' % (f, i + 1, label))
        right.append('"%s" using 3:4 with linespoints pt 7 lc %d title "%s scanlod"'
                     % (f, i + 1, label))
        right.append('"%s" using 3:5 with linespoints pt 4 dt 2 lc %d title "%s meshopt"'
                     % (f, i + 1, label))
    s += "plot " + ", ".join(left) + "\n"
    s += ('set logscale xy\nset title "scanlod extract vs meshopt\\\\_simplify from the '
          'finest mesh"\nset xlabel "output triangles (log)"\nset ylabel "time (s, log)"\n'
          'set yrange [*:*]\nset format y "10^{%L}"\nset format x "%.0s%c"\n'
          'set key bottom right box opaque font ",9"\n')
    s += "plot " + ", ".join(right) + "\nunset multiplot\n"
    gnuplot(s, tmp, "extract")


def growth_plot(h, tmp, out):
    g = h["growth"]
    f = os.path.join(tmp, "growth.dat")
    write(f, [[r["triangles"], r["total"]["median"], r["peak_rss_kb"] / 1024.0] +
              [r["stages"].get(st, {}).get("seconds", {}).get("median", "NaN")
               for st in stats.STAGES] for r in g["rows"]])
    s = TERM % (1300, 520)
    s += 'set output "%s"\n' % os.path.join(out, "growth.png")
    s += ('set multiplot layout 1,2 title "Cost growth on synthetic closed surfaces '
          '(gen\\\\_surface, 2 threads)"\n')
    lo, hi = g["rows"][0]["triangles"] / 2.0, g["rows"][-1]["triangles"] * 2.0
    s += ('set logscale xy\nset grid\nset key bottom right box opaque font ",9"\n'
          'set xlabel "input triangles (log)"\nset format x "%%.0s%%c"\n'
          'set xrange [%g:%g]\n' % (lo, hi))
    slope = g["slopes"]["total time"]
    s += 'set title "wall time (total grows as N^{%.2f})"\nset ylabel "wall time (s, log)"\n' % (
        slope if slope is not None else float("nan"))
    x0, t0 = g["rows"][0]["triangles"], g["rows"][0]["total"]["median"]
    plots = ['"%s" using 1:2 with linespoints pt 7 lw 2.5 lc rgb "black" title "total"' % f,
             '%g * x with lines dt 3 lc rgb "gray40" title "linear (N^1) from the first size"'
             % (t0 / x0)]
    for i, st in enumerate(stats.STAGES):
        plots.append('"%s" using 1:%d with linespoints pt %d lc %d title "%s"'
                     % (f, i + 4, i + 4, i + 1, st))
    s += "plot " + ", ".join(plots) + "\n"
    rs = g["slopes"]["peak RSS"]
    s += ('set key top left\nset title "peak RSS of the largest stage (grows as N^{%.2f})"\n'
          'set ylabel "peak RSS (MB, log)"\n' % (rs if rs is not None else float("nan")))
    r0 = g["rows"][0]["peak_rss_kb"] / 1024.0
    s += ('plot "%s" using 1:3 with linespoints pt 7 lc rgb "black" title "peak RSS", '
          '%g * x with lines dt 3 lc rgb "gray40" title "linear (N^1) from the first size"\n'
          % (f, r0 / x0))
    s += "unset multiplot\n"
    gnuplot(s, tmp, "growth")


def main():
    results, out = sys.argv[1], sys.argv[2]
    os.makedirs(out, exist_ok=True)
    d = headline.load_all(results)
    lod, oc = d["lod"], d["octree"]
    h = headline.derive(d["models"], d["stages"], oc, lod, d["growth"])
    with tempfile.TemporaryDirectory() as tmp:
        if lod:
            error_plot(lod, oc, tmp, out)
            extract_plot(h, lod, tmp, out)
        if h["stages"]:
            stage_plot(h, tmp, out)
        if h["growth"] and h["growth"]["rows"]:
            growth_plot(h, tmp, out)


if __name__ == "__main__":
    main()
