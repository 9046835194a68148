"""Describe the machine and the code under test: RESULTS/machine.json.

usage: machine.py CONTEXT.json
"""
import datetime
import os
import platform
import subprocess
import sys

from common import Ctx


def sh(cmd, default=""):
    try:
        return subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                              text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return default


def lscpu_field(field):
    for line in sh(["lscpu"]).splitlines():
        if line.startswith(field + ":"):
            return line.split(":", 1)[1].strip()
    return None


def main():
    ctx = Ctx(sys.argv[1])
    mem_kb = None
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemTotal:"):
                    mem_kb = int(line.split()[1])
    except OSError:
        pass
    os_name = platform.system()
    try:
        with open("/etc/os-release") as f:
            for line in f:
                if line.startswith("PRETTY_NAME="):
                    os_name = line.split("=", 1)[1].strip().strip('"')
    except OSError:
        pass
    root = ctx.repo
    commit = sh(["git", "-C", root, "rev-parse", "--short", "HEAD"], "unknown")
    dirty = sh(["git", "-C", root, "status", "--porcelain", "--untracked-files=no"])
    ctx.save("machine", {
        "nproc": int(sh(["nproc"], "0") or 0),
        "cpu_model": lscpu_field("Model name"),
        "memory_gib": round(mem_kb / 1048576.0, 1) if mem_kb else None,
        "os": os_name,
        "kernel": platform.release(),
        "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
        "commit": commit + (" (with uncommitted changes)" if dirty else ""),
        "compiler": sh(["cc", "--version"]).splitlines()[0] if sh(["cc", "--version"]) else None,
        "gnuplot": sh(["gnuplot", "--version"]),
        "mode": "quick" if ctx.quick else "full",
        "load_start": list(os.getloadavg()),
        "settings": {k: getattr(ctx, k) for k in
                     ("models", "lod_models", "reps", "extract_reps", "sizes",
                      "depth_input", "depths", "depth_reps", "budgets", "curve_extra",
                      "compare_samples", "vdb_search_steps", "minutes")},
    })


if __name__ == "__main__":
    main()
