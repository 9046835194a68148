#!/usr/bin/env python3
"""Checks a published collection (OUTPUT of `scanlod run`) against what the export stage
promises (docs/formats.md "Published per item"), item by item:

- report.json: input counts, and per level name, k, triangles, vertices, watertight, edge
  counts, and (with fidelity) RMS <= Hausdorff, both finite and >= 0;
- every level's PLY says in its header the vertex and face counts the report gives, and its
  GLB and PNG exist when the config asks for them; a level whose mesh is another's
  ("file" names that level) has no files of its own but that level's;
- timings.json: wall and CPU seconds and peak RSS for every stage;
- summary.json lists every item's report; summary.md has each item's section with one
  table row per level (matching the report) and links to thumbnails that exist.

Usage: check_outputs.py OUTPUT ITEM... [--formats=ply,glb] [--thumbnails] [--fidelity]
Prints one line per failed expectation and "N passed, N failed"; exit 1 on any failure."""
import json
import math
import os
import re
import sys

passed = 0
failed = 0


def check(ok, what):
    global passed, failed
    if ok:
        passed += 1
    else:
        failed += 1
        print("FAIL: " + what, file=sys.stderr)


def md_text(s):
    """core/markdown.c sl_md_text."""
    out = ""
    for c in s:
        if c in "\n\r":
            out += " "
        else:
            out += ("\\" if c in "\\`*_[]<>|~" else "") + c
    return out


def md_link(s):
    """core/markdown.c sl_md_link."""
    out = ""
    for c in s:
        if ord(c) < 0x20 or ord(c) == 0x7f:
            out += "%%%02X" % ord(c)
        else:
            out += ("\\" if c in "<>\\" else "") + c
    return out


def ply_counts(path):
    """(vertices, faces) from a PLY header."""
    counts = {}
    with open(path, "rb") as f:
        for raw in f:
            line = raw.decode("ascii", "replace").strip()
            if line == "end_header":
                break
            m = re.match(r"element (\w+) (\d+)", line)
            if m:
                counts[m.group(1)] = int(m.group(2))
    return counts.get("vertex"), counts.get("face")


def check_item(out, item, formats, thumbnails, fidelity, summary_md):
    folder = os.path.join(out, item)
    report = json.load(open(os.path.join(folder, "report.json")))
    check(report.get("item") == item, f"{item}: report names the item")
    stages = report.get("stages", {})
    rng = stages.get("range", {})
    check(rng.get("input_vertices", 0) > 0 and rng.get("input_faces", -1) >= 0,
          f"{item}: input counts reported")
    export = stages.get("export", {})
    levels = export.get("levels", [])
    check(len(levels) > 0, f"{item}: levels reported")
    # No level above the finest the method draws or the input (the scan at the top).
    finest = max(export.get("triangles_finest", 0), export.get("input_triangles", 0))
    for lv in levels:
        name = lv.get("name", "?")
        tri, ver = lv.get("triangles", -1), lv.get("vertices", -1)
        check(0 <= tri <= finest, f"{item}/{name}: triangles {tri} within the finest {finest}")
        check(0 <= ver <= 3 * tri, f"{item}/{name}: vertices {ver} within 3 x triangles")
        check(isinstance(lv.get("watertight"), bool) and "boundary_edges" in lv and
              "nonmanifold_edges" in lv, f"{item}/{name}: topology reported")
        check(lv.get("watertight") == (lv.get("boundary_edges") == 0 and
                                       lv.get("nonmanifold_edges") == 0 and tri > 0),
              f"{item}/{name}: watertight agrees with the edge counts")
        if tri == 0:
            check(lv.get("file") is None, f"{item}/{name}: no triangles, no files")
            continue
        own = lv.get("file")
        check(own in {l.get("name") for l in levels}, f"{item}/{name}: its files are a level's ({own})")
        if own != name:
            check(not any(os.path.exists(os.path.join(folder, f"{name}.{e}")) for e in ("ply", "glb", "png")),
                  f"{item}/{name}: no files of its own (the same mesh as {own})")
        if fidelity:
            rms, hd = lv.get("rms"), lv.get("hausdorff")
            check(rms is not None and hd is not None and math.isfinite(rms) and
                  math.isfinite(hd) and 0 <= rms <= hd, f"{item}/{name}: RMS {rms} <= Hausdorff {hd}")
        if "ply" in formats:
            v, f = ply_counts(os.path.join(folder, own + ".ply"))
            check((v, f) == (ver, tri), f"{item}/{own}.ply: header counts {(v, f)} = report {(ver, tri)}")
        if "glb" in formats:
            check(os.path.getsize(os.path.join(folder, own + ".glb")) > 0, f"{item}/{own}.glb written")
        png = os.path.join(folder, own + ".png")
        if thumbnails:
            check(os.path.isfile(png) and open(png, "rb").read(8) == b"\x89PNG\r\n\x1a\n",
                  f"{item}/{own}.png is a PNG")
            check(f"(<{md_link(item)}/{md_link(own)}.png>)" in summary_md,
                  f"summary.md shows {item}/{own}.png")
        row = f"| {md_text(name)} | {md_text(lv.get('method', '?'))} | {tri} | {ver} |"
        check(row in summary_md, f"summary.md has the row {row}")
    check(f"### {md_text(item)}\n" in summary_md, f"summary.md has a section for {item}")
    timings = json.load(open(os.path.join(folder, "timings.json")))
    for stage in report.get("stages", {}):
        t = timings.get("stages", {}).get(stage, {})
        check(t.get("seconds", -1) >= 0 and t.get("cpu_seconds", -1) >= 0 and
              t.get("peak_rss_kb", 0) > 0, f"{item}: timings.json has {stage} seconds and peak RSS")
        # where the stage's time went, by the phases it reports progress in: wall and CPU
        # seconds each, from the stage's start ("start") to its end, inside its own seconds
        phases = t.get("detail", {}).get("phases", {})
        wall = sum(p[0] for p in phases.values() if len(p) == 2)
        check("start" in phases and all(len(p) == 2 and p[0] >= 0 and p[1] >= 0 for p in phases.values())
              and wall <= t.get("seconds", 0) + 0.05 and wall >= 0.5 * t.get("seconds", 0) - 0.05,
              f"{item}: timings.json gives {stage}'s phases, within its {t.get('seconds')} s: {phases}")
        named = {"priority": ["priority: order", "priority: write"], "crack": ["crack: transitions", "crack: write"]}
        check(all(n in phases for n in named.get(stage, [])),
              f"{item}: {stage}'s phases name its steps: {sorted(phases)}")
    return report


def main(argv):
    args = [a for a in argv[1:] if not a.startswith("--")]
    formats = "ply"
    for a in argv[1:]:
        if a.startswith("--formats="):
            formats = a.split("=", 1)[1]
    thumbnails = "--thumbnails" in argv
    fidelity = "--fidelity" in argv
    out, items = args[0], args[1:]
    summary_md = open(os.path.join(out, "summary.md")).read()
    summary = json.load(open(os.path.join(out, "summary.json")))
    listed = {r.get("item"): r for r in summary.get("items", [])}
    for item in items:
        report = check_item(out, item, formats.split(","), thumbnails, fidelity, summary_md)
        check(listed.get(item) == report, f"summary.json carries {item}'s report")
    check(summary.get("items_published") == len(listed), "summary.json counts its items")
    print(f"{passed} passed, {failed} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
