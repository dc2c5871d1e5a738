"""``splineviz bench renderers``: cell projection (OpenGL, thesis §6.1) against the ray
caster (OpenCL, §6.2), frame time against the number of relevant tetrahedra.

Surfaces: spheres of radius n/3 in distance fields of n^3 samples, so the relevant
tetrahedra grow as n^2 (about 10^4 at n = 16). Per size: the classification time of the
relevant tets, the median frame time of each renderer over ``repeats`` frames from an
orbiting camera after a first, unmeasured one (program builds, uploads), at ``size``.
Cell projection runs on whatever OpenGL VTK finds (Mesa llvmpipe on machines without a GPU);
the ray caster on the OpenCL device ``device`` (the NumPy path where none exists).

The thesis (§6.1.3) found cell projection faster for small surfaces (up to a few hundred
thousand relevant tets) and the image-based caster faster for large ones, both on a GPU;
the closing note says where the crossover lies here, if inside the sizes measured.
"""

from __future__ import annotations

import statistics
import time

import numpy as np

from splineviz.bench.memory import peak_rss
from splineviz.compute.raycast import RayCaster
from splineviz.core.camera import Camera
from splineviz.core.splines import build_spline
from splineviz.core.volume import Volume

#: volume sizes: 6e3 to 1.0e7 relevant tets (648^3: 1.0e7 tets, about 100 bytes a tet in
#: the drawn geometry; the classification's float64 coefficients dominate the peak)
SIZES = (16, 32, 64, 128, 256, 512, 648)


def sphere_volume(n: int) -> tuple[Volume, float]:
    """Distance to the centre sampled at n^3 points (float32), and the isovalue n / 3."""
    x = np.arange(n, dtype=np.float32) - np.float32((n - 1) / 2)
    x2 = x * x
    return Volume(np.sqrt(x2[:, None, None] + x2[None, :, None] + x2[None, None, :])), n / 3.0


def orbit(volume: Volume, k: int, frames: int) -> Camera:
    """Camera ``k`` of ``frames`` on a circle around the data box."""
    b = np.asarray(volume.bounds)
    c = b.mean(axis=1)
    r = 1.6 * np.linalg.norm(b[:, 1] - b[:, 0])
    a = 2 * np.pi * k / max(frames, 1)
    eye = c + r * np.array([np.cos(a), np.sin(a), 0.5]) / np.sqrt(1.25)
    return Camera(eye, c, view_up=(0, 0, 1), view_angle=35.0)


def _median_time(render, volume, repeats: int) -> float:
    render(orbit(volume, 0, repeats + 1))
    times = []
    for k in range(1, repeats + 1):
        t = time.perf_counter()
        render(orbit(volume, k, repeats + 1))
        times.append(time.perf_counter() - t)
    return statistics.median(times)


def run_renderers_bench(sizes=SIZES, model: str = "cubic-c1", size=(512, 512),
                        repeats: int = 3, device=None) -> list[dict]:
    """Print and return one row per volume size (see module)."""
    from splineviz.render.cell_projection import CellProjectionLayer, OffscreenCellProjection

    rows = []
    print(f"bench renderers: {model}, {size[0]}x{size[1]}, median of {repeats} frames")
    print(f"{'n':>5} {'tets':>10} {'classify s':>11} {'cell proj s':>12} "
          f"{'ray cast s':>11} {'ratio':>7} {'peak GB':>8}")
    for n in sizes:
        vol, iso = sphere_volume(n)
        spline = build_spline(vol, model)
        t = time.perf_counter()
        layer = CellProjectionLayer(spline, iso)
        classify = time.perf_counter() - t
        with OffscreenCellProjection(layer, size) as view:
            t_cp = _median_time(view.render, vol, repeats)
        rc = RayCaster(vol, model=model, device=device)
        rc.set_isovalue(iso)
        t_rc = _median_time(lambda cam, rc=rc: rc.render(cam, size), vol, repeats)
        # the process's high-water mark: the sizes grow, so it is this size's
        row = {"n": n, "tets": len(layer.tets), "classify_s": classify,
               "cell_projection_s": t_cp, "raycast_s": t_rc, "path": rc.stats.get("path"),
               "peak_rss": peak_rss()}
        rows.append(row)
        print(f"{n:>5} {row['tets']:>10} {classify:>11.3f} {t_cp:>12.3f} {t_rc:>11.3f} "
              f"{t_rc / t_cp:>7.2f} {row['peak_rss'] / 2**30:>8.2f}")
    faster = [r["n"] for r in rows if r["cell_projection_s"] < r["raycast_s"]]
    cross = next((r for r in rows if r["cell_projection_s"] >= r["raycast_s"]), None)
    if faster and cross is not None:
        note = (f"crossover between {max(faster)}^3 and {cross['n']}^3 "
                f"(~{cross['tets']:.0e} relevant tets)")
    elif faster:
        note = "cell projection faster at every size measured"
    else:
        note = "the ray caster faster at every size measured"
    print(f"note: {note}; ray caster path {rows[-1]['path'] if rows else '-'}; the thesis "
          "(§6.1.3, GPU) puts the crossover at a few hundred thousand relevant tets")
    return rows
