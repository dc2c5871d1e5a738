"""Benchmark: value + gradient of every spline model at 10^6 random points of a 256^3 volume.

Issue 3 acceptance: the type-6 splines compute coefficients on demand (no per-tetrahedron
array, which would be ~12 GB for 256^3 cubics), stay under 2 GB of memory and within 5x the
time of ``scipy.ndimage.map_coordinates(order=3)`` (which includes its B-spline prefilter) on
the same points. Each model runs in a fresh subprocess so that its peak resident memory is
its own; the baseline is measured in the same subprocess, so the printed ratio is same-run.

Run: ``python -m splineviz.bench.evaluate [--size 256] [--points 1000000]
[--models cubic-c1 super-quadratic ...]``
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import time

import numpy as np


def run_one(model: str, size: int, n_points: int) -> dict:
    """Time one model and the map_coordinates baseline in this process."""
    from scipy import ndimage

    import splineviz as sv

    rng = np.random.default_rng(0)
    data = rng.random((size, size, size), dtype=np.float32)
    pts = rng.uniform(0, size - 1, (n_points, 3))
    rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0  # MiB (Linux: KiB)

    t0 = time.perf_counter()
    ndimage.map_coordinates(data, pts.T, order=3)
    t_base = time.perf_counter() - t0

    spline = sv.build_spline(sv.Volume(data), model=model)
    t0 = time.perf_counter()
    value, grad = spline.value_gradient(pts)  # includes one-time setup (ghost layer)
    t_model = time.perf_counter() - t0
    assert value.shape == (n_points,) and grad.shape == (n_points, 3)
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    return {"model": model, "time_s": t_model, "baseline_s": t_base,
            "ratio": t_model / t_base, "peak_rss_mib": peak, "rss_after_data_mib": rss0}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, default=256)
    ap.add_argument("--points", type=int, default=1_000_000)
    ap.add_argument("--models", nargs="*",
                    default=["cubic-c1", "super-quadratic", "to-quadratic", "trilinear"])
    ap.add_argument("--one", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.one:
        print(json.dumps(run_one(args.one, args.size, args.points)))
        return 0
    print(f"value+gradient at {args.points} random points of a {args.size}^3 volume; "
          "baseline scipy.ndimage.map_coordinates(order=3) in the same process")
    print(f"{'model':16s} {'time s':>8s} {'base s':>8s} {'ratio':>6s} {'peak MiB':>9s}")
    for model in args.models:
        proc = subprocess.run(
            [sys.executable, "-m", "splineviz.bench.evaluate", "--one", model,
             "--size", str(args.size), "--points", str(args.points)],
            capture_output=True, text=True)
        if proc.returncode != 0:
            last = (proc.stderr.strip().splitlines() or ["failed"])[-1]
            print(f"{model:16s} not measured: {last}")
            continue
        r = json.loads(proc.stdout.strip().splitlines()[-1])
        print(f"{model:16s} {r['time_s']:8.2f} {r['baseline_s']:8.2f} {r['ratio']:6.2f} "
              f"{r['peak_rss_mib']:9.0f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
