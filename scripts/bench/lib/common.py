"""Runners shared by the benchmark phases: scanlod collections, extract, compare, peers.

Every phase is `python3 lib/PHASE.py CONTEXT.json`; the context (written by run.sh) names
the build, the data, the scratch and results folders and the run's settings.
"""
import json
import os
import shutil
import signal
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import stats  # noqa: E402


class Ctx:
    def __init__(self, path):
        with open(path) as f:
            c = json.load(f)
        self.__dict__.update(c)
        self.scanlod = os.path.join(self.build, "cli", "scanlod")
        self.bench = os.path.join(self.build, "scripts", "bench")

    def tool(self, name):
        return os.path.join(self.bench, name)

    def input_ply(self, name):
        return os.path.join(self.data, name + ".ply")

    def scratch_dir(self, *parts):
        d = os.path.join(self.scratch, *parts)
        os.makedirs(d, exist_ok=True)
        return d

    def save(self, phase, obj):
        path = os.path.join(self.results, phase + ".json")
        tmp = path + ".tmp"
        with open(tmp, "w") as f:
            json.dump(obj, f, indent=1, sort_keys=True)
        os.replace(tmp, path)

    def load(self, phase):
        path = os.path.join(self.results, phase + ".json")
        if not os.path.exists(path):
            return None
        with open(path) as f:
            return json.load(f)


def log(msg):
    sys.stderr.write("[bench %s] %s\n" % (time.strftime("%H:%M:%S"), msg))
    sys.stderr.flush()


class Timeout(RuntimeError):
    pass


def run(cmd, check=True, timeout=None):
    """Run a command; returns stdout. Raises with stderr on failure when check. With a
    timeout (seconds) the command runs in a process group of its own, which is stopped
    (SIGTERM, then SIGKILL 10 s later) when the time is up: Timeout is raised."""
    cmd = [str(c) for c in cmd]
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         start_new_session=timeout is not None)
    try:
        out, err = p.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        for sig, wait in ((signal.SIGTERM, 10), (signal.SIGKILL, None)):
            try:
                os.killpg(p.pid, sig)
            except ProcessLookupError:
                break
            try:
                p.communicate(timeout=wait)
                break
            except subprocess.TimeoutExpired:
                continue
        raise Timeout("%s: stopped after %g s" % (" ".join(cmd), timeout))
    if check and p.returncode != 0:
        raise RuntimeError("%s: exit %d: %s" % (" ".join(cmd), p.returncode,
                                                 err.strip()[-500:]))
    return out


def tree_bytes(root):
    """Bytes of the regular files under root (links not followed)."""
    total = 0
    for d, _, files in os.walk(root):
        for f in files:
            p = os.path.join(d, f)
            if not os.path.islink(p):
                total += os.path.getsize(p)
    return total


def run_json(cmd):
    return json.loads(run(cmd))


class Collection:
    """A one-item collection: DIR/in/ITEM.ply and DIR/run.ini; work, out, logs beside."""

    def __init__(self, root, item, source=None):
        self.root, self.item = root, item
        self.item_id = item + ".ply"  # the engine's item id: the input's path in the tree
        os.makedirs(os.path.join(root, "in"), exist_ok=True)
        self.ply = os.path.join(root, "in", self.item_id)
        if source and not os.path.exists(self.ply):
            shutil.copyfile(source, self.ply)
        self.config = os.path.join(root, "run.ini")
        with open(self.config, "w") as f:
            f.write("[run]\ninput = in\nwork = work\noutput = out\nlogs = logs\n")

    def path(self, *parts):
        return os.path.join(self.root, *parts)

    def clean(self):
        for d in ("work", "out", "logs"):
            shutil.rmtree(self.path(d), ignore_errors=True)

    def artifact(self, stage, name):
        return self.path("work", "artifacts", stage, self.item_id, name)

    def run(self, ctx, threads, overrides=(), fresh=True, timeout=None):
        """`scanlod run` on the collection; returns the published timings per stage.
        Raises Timeout when it runs longer than timeout seconds."""
        if fresh:
            self.clean()
        cmd = [ctx.scanlod, "run", self.config, "--threads", threads, "-q"]
        for o in overrides:
            cmd += ["-s", o]
        run(cmd, timeout=timeout)
        return stats.load_timings(self.path("out", self.item_id, "timings.json"))

    def run_until(self, ctx, stage, threads, overrides=()):
        """Run until STAGE has committed, then stop the run (SIGTERM to its process
        group: the engine exits 75, 'incomplete'). Returns _stats.json per stage so far."""
        self.clean()
        cmd = [ctx.scanlod, "run", self.config, "--threads", str(threads), "-q"]
        for o in overrides:
            cmd += ["-s", o]
        record = self.artifact(stage, "record")
        p = subprocess.Popen(cmd, cwd=self.root, start_new_session=True,
                             stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        while p.poll() is None and not os.path.exists(record):
            time.sleep(0.05)
        if p.poll() is None:
            os.killpg(p.pid, signal.SIGTERM)
        _, err = p.communicate()
        if not os.path.exists(record):
            raise RuntimeError("scanlod run stopped before %s: %s" % (stage, err[-500:]))
        out = {}
        for s in stats.STAGES:
            f = self.artifact(s, "_stats.json")
            if os.path.exists(f):
                with open(f) as fh:
                    out[s] = json.load(fh)
            if s == stage:
                break
        return out

    def report(self):
        with open(self.path("out", self.item_id, "report.json")) as f:
            return json.load(f)


def compare(ctx, reference, candidate):
    """Fidelity of candidate against reference (fractions of the reference's diagonal)."""
    return stats.fidelity(run_json([ctx.scanlod, "compare", reference, candidate,
                                    "--samples", ctx.compare_samples, "--json"]))


def extract(ctx, source, out, *args):
    """`scanlod extract SOURCE ARGS -o OUT` -> parsed counts and generation seconds."""
    return stats.parse_extract(run([ctx.scanlod, "extract", source] + list(args) +
                                   ["-o", out]))


def vdb(ctx, ply, out, voxel, adaptivity=0.0, unsigned=False, threads=2):
    cmd = [ctx.tool("vdb_remesh"), ply, "-o", out, "--voxel", repr(voxel),
           "--adaptivity", adaptivity, "--threads", threads]
    if unsigned:
        cmd.append("--unsigned")
    d = run_json(cmd)
    d["seconds"] = d["to_volume_seconds"] + d["to_mesh_seconds"]
    return d


def meshopt(ctx, ply, targets, prefix=None):
    cmd = [ctx.tool("meshopt_lod"), ply, "--targets", ",".join(str(int(t)) for t in targets)]
    if prefix:
        cmd += ["-o", prefix]
    return run_json(cmd)


def input_facts(ctx, name):
    """Input triangle count and whether the scan is open (has boundary edges)."""
    ply = ctx.input_ply(name)
    d = run_json([ctx.scanlod, "compare", ply, ply, "--samples", 1000, "--json"])
    return {"triangles": d["a_triangles"],
            "open": (d["b_topology"]["boundary_edges"] or 0) > 0,
            "diagonal": d["diagonal"]}
