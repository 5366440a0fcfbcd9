#!/usr/bin/env python3
"""Vectorised projection and back-projection from Python: points per second of hovs.Camera.project and unproject
for the polynomial and unified models of a calibration, on all cores (the module releases the GIL and spreads
the rows over TBB's threads).

Usage: PYTHONPATH=build/python python3 python/bench/projection.py CALIBRATION_DIR [--points N] [--repeats R]
       [--out results/benchmarks/python_projection.json]
CALIBRATION_DIR holds a `hovs calibrate` output (calibration.json, unified.yaml). The JSON records the date,
commit, CPU model and every library version with the rates (median of the repeats).
"""

import argparse
import datetime
import json
import os
import pathlib
import platform
import statistics
import subprocess
import time

import numpy as np

import hovs


def cpu_model():
    try:
        for line in pathlib.Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def commit():
    try:
        root = pathlib.Path(__file__).resolve().parents[2]
        return subprocess.run(["git", "-C", str(root), "describe", "--always", "--dirty"], capture_output=True,
                              text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def rate(fn, arg, repeats):
    fn(arg[:1000])  # warm-up: thread pool, page faults of the outputs
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        fn(arg)
        times.append(time.perf_counter() - t)
    return len(arg) / statistics.median(times)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("calibration")
    ap.add_argument("--points", type=int, default=10_000_000)
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--out")
    a = ap.parse_args()
    cal = pathlib.Path(a.calibration)
    cameras = {"polynomial": hovs.load_camera(str(cal / "calibration.json"), model="polynomial"),
               "unified": hovs.load_camera(str(cal / "unified.yaml"))}
    rng = np.random.default_rng(a.seed)
    rows = []
    for name, cam in cameras.items():
        # Points whose pixels lie in the calibrated field, at 0.5 to 20 m.
        px = rng.uniform([0, 0], [cam.width - 1, cam.height - 1], size=(a.points * 3, 2))
        rays, valid = cam.unproject(px)
        rays, px = rays[valid][: a.points], px[valid][: a.points]
        points = rays * rng.uniform(0.5, 20, size=(len(rays), 1))
        r_project = rate(cam.project, points, a.repeats)
        r_unproject = rate(cam.unproject, px, a.repeats)
        rows.append({"model": name, "points": len(points), "project_points_per_s": r_project,
                     "unproject_points_per_s": r_unproject})
        print(f"{name:10s} project {r_project / 1e6:7.1f} M points/s   unproject {r_unproject / 1e6:7.1f} M points/s"
              f"   ({len(points)} points, median of {a.repeats})")
    context = {"date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
               "commit": commit(), "cpu_model": cpu_model(), "num_cpus": os.cpu_count(),
               "python": platform.python_version(), "numpy": np.__version__, "versions": hovs.versions(),
               "calibration": str(cal), "seed": a.seed, "repeats": a.repeats}
    if a.out:
        pathlib.Path(a.out).write_text(json.dumps({"context": context, "benchmarks": rows}, indent=1) + "\n")


if __name__ == "__main__":
    main()
