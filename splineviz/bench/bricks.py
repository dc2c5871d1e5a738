"""``splineviz bench bricks``: out-of-core ray casting in bricks on dask workers (issue 15).

The volume is a lazy gyroid, ``sin x cos y + sin y cos z + sin z cos x`` sampled on ``n^3``
points (``4 n^3`` bytes as float32: 32 GiB at n = 2048), computed per brick on the worker
that renders it, with a pyramid of coarser samplings for the preview. One frame is rendered
on a LocalCluster of 1 worker and one of 2 workers (fresh clusters, no cached bricks); the
table gives the brick counts (total, skipped as empty, culled as hidden, rendered), the
per-brick read / build (upload, octree) / render times and the share of the frame's pixels a
brick casts (its screen footprint, median), the client's compositing time, the
preview time, the wall time, the speed-up of 2 workers over 1 and a projection to N workers
from the per-brick times, with the peak resident memory of the client and its workers.
"""

from __future__ import annotations

import statistics
import threading
import time

import numpy as np

#: periods of the gyroid across the volume (surface detail independent of n)
PERIODS = 6.0
#: isovalue of the benchmark surface (the gyroid is 0 on its minimal surface)
ISOVALUE = 0.3


def gyroid(x, y, z):
    """``sin x cos y + sin y cos z + sin z cos x`` on broadcastable (n,1,1), (1,n,1), (1,1,n)
    coordinate arrays: six 1-D sine/cosine evaluations and products, float32."""
    x, y, z = (np.asarray(v, np.float32) for v in (x, y, z))
    sx, cx, sy, cy, sz, cz = np.sin(x), np.cos(x), np.sin(y), np.cos(y), np.sin(z), np.cos(z)
    out = sx * cy
    out = out + sy * cz
    out += sz * cx
    return out


def gyroid_volume(n: int, chunks: int = 256):
    """The lazy ``n^3`` gyroid (:class:`~splineviz.core.chunked.ChunkedVolume`)."""
    from splineviz.core.chunked import ChunkedVolume

    side = 2.0 * np.pi * PERIODS
    return ChunkedVolume.from_function(gyroid, (n, n, n), ((0.0, side),) * 3, chunks=chunks,
                                       name=f"gyroid {n}^3")


class PeakRSS:
    """Peak of the summed resident memory of this process and its children (the dask
    workers), sampled every ``interval`` seconds in a thread (shared pages count once per
    process: an upper bound)."""

    def __init__(self, interval: float = 0.05):
        import psutil

        self._proc = psutil.Process()
        self.interval = interval
        self.peak = 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def _sample(self) -> int:
        import psutil

        total = 0
        for p in [self._proc, *self._proc.children(recursive=True)]:
            try:
                total += p.memory_info().rss
            except psutil.Error:
                pass
        return total

    def _run(self):
        while not self._stop.is_set():
            self.peak = max(self.peak, self._sample())
            self._stop.wait(self.interval)

    def __enter__(self):
        self._thread.start()
        return self

    def __exit__(self, *exc):
        self._stop.set()
        self._thread.join()
        self.peak = max(self.peak, self._sample())


def measure(n: int, workers: int, model: str = "cubic-c1", size=(1024, 768),
            brick: int = 256, device=None, processes: bool = True) -> dict:
    """One frame of the ``n^3`` gyroid on a fresh LocalCluster of ``workers`` workers.

    Returns
    -------
    dict
        ``wall_s`` (cluster start excluded), ``preview_s``, ``composite_s``, brick counts,
        ``brick_times`` (per rendered brick), ``peak_rss`` bytes, ``hits`` of the frame,
        ``first_stage`` (``"preview"``) and the frame itself.
    """
    from distributed import Client, LocalCluster

    from splineviz.compute.bricked import BrickedRayCaster
    from splineviz.core.camera import default_camera

    vol = gyroid_volume(n, chunks=brick)
    with PeakRSS() as rss:
        with LocalCluster(n_workers=workers, threads_per_worker=1, processes=processes,
                          dashboard_address=":0") as cluster, Client(cluster) as client:
            # warm the workers (imports, OpenCL context and kernel builds) on a tiny volume
            # so that the frame's time is the bricks', not the start-up's
            warm = BrickedRayCaster(gyroid_volume(33, chunks=16), model=model, device=device,
                                    client=client, brick_size=16, cache_bytes=0)
            warm.set_isovalue(ISOVALUE)
            warm.render(default_camera(warm.volume.bounds), size=(32, 24))
            rc = BrickedRayCaster(vol, model=model, device=device, client=client,
                                  brick_size=brick, cache_bytes=0)
            rc.set_isovalue(ISOVALUE)
            cam = default_camera(vol.bounds)
            t = time.perf_counter()
            stages = []
            for stage, _, _, shown in rc.frames(cam, size):
                if not stages or stages[-1] != stage:
                    stages.append(stage)
                frame = shown
            wall = time.perf_counter() - t
            stats = dict(rc.stats)
    return {"n": n, "workers": workers, "model": model, "size": tuple(size),
            "wall_s": wall, "preview_s": stats.get("preview_s"),
            "composite_s": stats["composite_s"], "bricks": stats["bricks"],
            "bricks_empty": stats["bricks_empty"], "bricks_culled": stats["bricks_culled"],
            "bricks_rendered": stats["bricks_rendered"], "brick_times": stats["brick_times"],
            "peak_rss": rss.peak, "hits": int(frame.hit.sum()), "first_stage": stages[0],
            "frame": frame}


def project(result: dict, workers: int) -> float:
    """Seconds of the same frame on ``workers`` workers, from the per-brick times: the brick
    work spread evenly (at least the longest brick), plus the client's preview and
    compositing, which do not shrink with workers."""
    per = [t["read_s"] + t["build_s"] + t["render_s"] for t in result["brick_times"]]
    work = max(sum(per) / workers, max(per, default=0.0))
    return work + (result["preview_s"] or 0.0) + result["composite_s"]


def run_bricks_bench(n: int = 512, model: str = "cubic-c1", size=(1024, 768),
                     brick: int = 128, workers=(1, 2), device=None, out=print) -> list[dict]:
    """Run the benchmark and print its table; returns one result per worker count."""
    results = [measure(n, w, model, size, brick, device) for w in workers]
    _print(results, out)
    return results


def _print(results, out) -> None:
    gib = 2.0**30
    r0 = results[0]
    out(f"bricked ray casting: gyroid {r0['n']}^3 float32 ({4 * r0['n'] ** 3 / gib:.1f} GiB "
        f"lazy), model {r0['model']}, {r0['size'][0]}x{r0['size'][1]}")
    out(f"{'workers':>7} {'bricks':>6} {'empty':>5} {'culled':>6} {'rendered':>8} "
        f"{'read ms':>8} {'build ms':>8} {'render ms':>9} {'pixels %':>8} {'composite s':>11} "
        f"{'preview s':>9} {'wall s':>7} {'peak RSS GiB':>12}")
    for r in results:
        t = r["brick_times"]

        def med(key, t=t):
            return 1e3 * statistics.median([b[key] for b in t]) if t else 0.0

        frame = r["size"][0] * r["size"][1]
        share = 100 * statistics.median([b["pixels"] / frame for b in t]) if t else 0.0
        out(f"{r['workers']:>7} {r['bricks']:>6} {r['bricks_empty']:>5} "
            f"{r['bricks_culled']:>6} {r['bricks_rendered']:>8} {med('read_s'):>8.0f} "
            f"{med('build_s'):>8.0f} {med('render_s'):>9.0f} {share:>8.1f} "
            f"{r['composite_s']:>11.2f} {(r['preview_s'] or 0):>9.2f} {r['wall_s']:>7.1f} "
            f"{r['peak_rss'] / gib:>12.2f}")
    by = {r["workers"]: r for r in results}
    if 1 in by and 2 in by:
        out(f"speed-up 2 workers / 1 worker: {by[1]['wall_s'] / by[2]['wall_s']:.2f}x "
            "(one machine: the workers share its cores, and each brick's OpenCL kernels "
            "already use all of them)")
    # the fewest workers' per-brick times: those of workers not sharing their cores
    base = results[0]
    proj = ", ".join(f"{w}: {project(base, w):.1f} s" for w in (1, 2, 4, 8, 16, 64))
    out(f"projected from the per-brick times of {base['workers']} worker(s), for N workers "
        f"each on its own cores: {proj}")
    per = [b["read_s"] + b["build_s"] + b["render_s"] for b in base["brick_times"]]
    if per:
        parts = {k: sum(b[k] for b in base["brick_times"]) / sum(per)
                 for k in ("read_s", "build_s", "render_s")}
        out("where the brick time goes: " + ", ".join(
            f"{k[:-2]} {100 * v:.0f} %" for k, v in parts.items())
            + f"; client compositing {base['composite_s']:.2f} s and preview "
            f"{(base['preview_s'] or 0):.2f} s do not scale with workers, and neither does "
            f"the longest brick ({max(per):.2f} s); each brick casts its screen footprint "
            f"only, so its render time shrinks with the brick")
