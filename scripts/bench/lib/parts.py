"""Phase parts: one large scan built by three local workers as parts (docs/engine.md,
"Parts"), one of them killed -9 inside a part, against one process without parts.

The largest of ctx.sizes that fits the time budget (20M triangles in the full run): a
`gen_surface` torus, run once by one `scanlod run` at 2 threads (fidelity off), then, in a
second collection on the same PLY with [queue] part_mb set for 6 parts, by `scanlod run`
and two `scanlod worker`s at 1 thread each (2 cores for 3 processes). The third process is
killed -9 while it holds a samples part; the other two reclaim that part and finish.
Recorded: both wall times, the samples stage of each (the split one: the join and every
part, from timings.json), how many times each part started (the logs), the exit codes,
and whether every artifact and published file of the item is byte-identical between the
two (files starting with '_' or '.', and timings.json, left out).
Writes RESULTS/parts.json.
"""
import glob
import hashlib
import json
import os
import re
import signal
import subprocess
import sys
import time

from common import Collection, Ctx, log, run


def digest(root, skip):
    """{relative path: sha256} of the regular files under root, minus skip(name)."""
    out = {}
    for d, dirs, files in os.walk(root):
        dirs[:] = [x for x in dirs if not x.startswith(".")]
        for f in files:
            if skip(f):
                continue
            p = os.path.join(d, f)
            with open(p, "rb") as fh:
                out[os.path.relpath(p, root)] = hashlib.sha256(fh.read()).hexdigest()
    return out


def tree(c):
    work = digest(c.path("work", "artifacts"), lambda f: f.startswith(("_", ".")))
    # the item's published folder (the collection's summaries name its own input folder)
    out = digest(c.path("out", c.item_id), lambda f: f == "timings.json" or f.startswith("."))
    return work, out


def held_part(c, pid):
    """The samples part ticket pid holds, or None."""
    for t in glob.glob(c.path("work", "queue", "samples", "claimed", "*#part-*")):
        try:
            with open(t) as f:
                if "pid=%d\n" % pid in f.read():
                    return os.path.basename(t)
        except OSError:
            pass
    return None


def main():
    ctx = Ctx(sys.argv[1])
    out = {"skipped": None}
    target = max(ctx.sizes)
    growth = ctx.load("growth") or {}
    done = [r for r in growth.get("sizes", []) if r["target"] == target and r["reps"]]
    if done:   # 2 runs of about the growth run's time
        predicted = 2.2 * sum(s["seconds"] for s in done[0]["reps"][0].values())
        left = ctx.deadline - time.time()
        if predicted > left:
            out["skipped"] = ("predicted %.0f s at %d triangles, %.0f s left of the run's "
                              "time budget" % (predicted, target, max(0, left)))
            log("parts: skipped: " + out["skipped"])
            ctx.save("parts", out)
            return
    name = "surface_%d" % target
    whole = Collection(ctx.scratch_dir("parts", "whole"), name)
    gen = json.loads(run([ctx.tool("gen_surface"), "--triangles", target, "-o", whole.ply]))
    ply_bytes = os.path.getsize(whole.ply)
    split = Collection(ctx.scratch_dir("parts", "split"), name)
    if not os.path.exists(split.ply):
        os.link(whole.ply, split.ply)
    part_mb = ply_bytes / 6.0 / 1048576.0 * 1.001   # 6 parts
    with open(split.config, "a") as f:
        f.write("[queue]\npart_mb = %.6f\n" % part_mb)
    overrides = ["export.fidelity=false"]
    out.update({"triangles": gen["triangles"], "ply_bytes": ply_bytes, "part_mb": part_mb})

    log("parts: %d triangles, one process" % gen["triangles"])
    t0 = time.time()
    out["whole_stages"] = whole.run(ctx, 2, overrides)
    out["whole_seconds"] = time.time() - t0

    log("parts: the same, run + 2 workers (+1 killed -9 in a part)")
    split.clean()
    cmd = lambda verb: [ctx.scanlod, verb, split.config, "--threads", "1", "-q",
                        "-s", overrides[0]]
    t0 = time.time()
    procs = [subprocess.Popen(cmd("run"), cwd=split.root, stdout=subprocess.DEVNULL,
                              stderr=subprocess.PIPE, text=True),
             subprocess.Popen(cmd("worker"), cwd=split.root, stdout=subprocess.DEVNULL,
                              stderr=subprocess.PIPE, text=True)]
    ready = split.path("work", "queue", "samples", "ready")
    while not glob.glob(os.path.join(ready, "*#part-*")):
        if any(p.poll() is not None for p in procs):
            raise RuntimeError("parts: a worker ended before the parts were queued")
        time.sleep(0.05)
    victim = subprocess.Popen(cmd("worker"), cwd=split.root, stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL)
    held = None
    while held is None and victim.poll() is None:
        held = held_part(split, victim.pid)
        time.sleep(0.05)
    if held:
        time.sleep(2.0)   # well inside the part (a 20M part takes tens of seconds)
        still = held_part(split, victim.pid) == held
        os.kill(victim.pid, signal.SIGKILL)
        out["killed"] = {"part": held, "inside": still}
        log("parts: killed the third worker in %s%s" % (held, "" if still else
                                                         " (it had finished it)"))
    victim.wait()
    out["exit_codes"] = [p.wait() for p in procs]
    out["split_seconds"] = time.time() - t0
    rc = subprocess.run(cmd("run"), cwd=split.root, capture_output=True, text=True)
    out["after"] = {"exit": rc.returncode, "stdout": rc.stdout.strip()[-200:]}
    with open(split.path("out", split.item_id, "timings.json")) as f:
        out["split_timings"] = json.load(f)["stages"]
    starts = {}
    for path in glob.glob(split.path("logs", "*.log")):
        with open(path) as f:
            for m in re.finditer(r"start part (\d+) of (\d+)", f.read()):
                starts.setdefault(m.group(1), []).append(os.path.basename(path))
    out["part_starts"] = starts
    a, b = tree(whole), tree(split)
    out["identical"] = {"artifacts": a[0] == b[0], "published": a[1] == b[1],
                        "artifact_files": len(a[0]), "published_files": len(a[1]),
                        "differ": [k for n in (0, 1) for k in sorted(set(a[n]) | set(b[n]))
                                   if a[n].get(k) != b[n].get(k)][:10]}
    log("parts: identical: %s" % out["identical"])
    ctx.save("parts", out)
    if all(out["identical"][k] for k in ("artifacts", "published")):
        whole.clean()
        split.clean()
    os.remove(split.ply)
    os.remove(whole.ply)


if __name__ == "__main__":
    main()
