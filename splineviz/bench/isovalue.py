"""``splineviz bench isovalue``: the isovalue slider against VTK flying edges (issue 12).

For bonsai 256^3 and a 512^3 resample of it (made here, not stored), per spline model: the
time of one isovalue change (``set_isovalue``), the first exact frame after a change (change
plus one frame), a preview frame after a change (change plus one frame at a reduced size),
the frame time while the camera moves, and the peak resident memory. The baseline, measured
in the same run: ``vtkFlyingEdges3D`` at the same isovalues, one offscreen pyvista render of
its mesh (window, upload, draw), frames while the camera moves, and its peak memory.

Every measurement runs in a fresh process, so that each peak RSS is its own (the volume
included) and no cache of one model helps another.
"""

from __future__ import annotations

import os
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from splineviz.bench.memory import peak_rss

#: models of the benchmark
MODELS = ("trilinear", "super-quadratic", "cubic-c1", "to-quadratic")
#: isovalues of the exact-frame changes (bonsai's surface at 40 and neighbours) and of the
#: preview changes (different values, so that every measurement is a real change)
EXACT_ISOS = (40.0, 48.0, 36.0)
PREVIEW_ISOS = (44.0, 52.0, 32.0)
#: camera steps (degrees of azimuth) of the moving-camera frames
AZIMUTH_STEPS = (5.0, 5.0, 5.0, 5.0)


def bonsai_volume(data_dir, n: int):
    """bonsai.vti at ``n``^3 samples (linear resampling when n != 256), same data box.

    Returns
    -------
    data : (n, n, n) float32
    spacing : (3,) float
    """
    from scipy import ndimage

    from splineviz.io.volumes import read_volume

    vol = read_volume(Path(data_dir) / "bonsai.vti")
    data = np.asarray(vol.data, dtype=np.float32)
    spacing = np.asarray(vol.spacing, dtype=np.float64)
    if data.shape != (n, n, n):
        old = np.array(data.shape)
        data = ndimage.zoom(data, n / old, order=1).astype(np.float32, copy=False)
        spacing = spacing * (old - 1) / (np.array(data.shape) - 1)
    return data, spacing


def _rotated(cam, degrees: float):
    """``cam`` turned by ``degrees`` of azimuth about its view-up through the focal point."""
    from splineviz.core.camera import Camera

    a = np.radians(degrees)
    up = np.asarray(cam.view_up, dtype=np.float64)
    up /= np.linalg.norm(up)
    v = np.asarray(cam.position, dtype=np.float64) - cam.focal_point
    # Rodrigues' rotation of the eye offset about the up axis
    v = v * np.cos(a) + np.cross(up, v) * np.sin(a) + up * np.dot(up, v) * (1 - np.cos(a))
    return Camera(np.asarray(cam.focal_point) + v, cam.focal_point, view_up=cam.view_up,
                  view_angle=cam.view_angle)


def _measure_vtk(path, spacing, size):
    """Flying edges + offscreen render of its mesh, in a child process (see module doc)."""
    if not os.environ.get("DISPLAY"):
        # headless: EGL (Mesa) instead of a failing X connection (see ENVIRONMENT.md)
        os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    import pyvista as pv

    from splineviz.bench.raycast import flying_edges
    from splineviz.core.camera import default_camera

    data = np.load(path)
    img = pv.ImageData(dimensions=data.shape, spacing=spacing)
    img.point_data["v"] = data.ravel(order="F")  # VTK: x varies fastest
    del data
    extract = []
    for iso in EXACT_ISOS[::-1]:  # ends at EXACT_ISOS[0], the mesh that is drawn
        mesh, seconds = flying_edges(img, iso)
        extract.append(seconds)
    cam = default_camera(_box(img))
    pl = pv.Plotter(off_screen=True, window_size=size)
    t = time.perf_counter()
    pl.add_mesh(mesh, color=(0.93, 0.78, 0.55), smooth_shading=True)
    pl.camera.position = cam.position
    pl.camera.focal_point = cam.focal_point
    pl.camera.up = cam.view_up
    pl.camera.view_angle = cam.view_angle
    pl.show(auto_close=False)  # first frame: window, upload of the mesh, draw
    first = time.perf_counter() - t
    moving = []
    for step in AZIMUTH_STEPS:
        pl.camera.Azimuth(step)
        t = time.perf_counter()
        pl.ren_win.Render()
        pl.screenshot(return_img=True)  # read back, as the ray caster returns its pixels
        moving.append(time.perf_counter() - t)
    pl.close()
    return {"extract_s": statistics.median(extract), "first_s": first,
            "move_s": statistics.median(moving), "triangles": mesh.n_cells, "rss": peak_rss()}


def _box(img):
    """((xmin, xmax), (ymin, ymax), (zmin, zmax)) of a pyvista ImageData."""
    b = img.bounds
    return ((b[0], b[1]), (b[2], b[3]), (b[4], b[5]))


def _measure_caster(path, spacing, model, size, preview, device):
    """One model's isovalue changes, frames and memory, in a child process."""
    from splineviz.compute.raycast import RayCaster
    from splineviz.core.camera import default_camera
    from splineviz.core.volume import Volume

    vol = Volume(np.load(path), spacing=spacing)
    cam = default_camera(vol.bounds)
    t = time.perf_counter()
    rc = RayCaster(vol, model=model, device=device)
    setup = time.perf_counter() - t
    # warm-up: programs built (and pocl's work-group code for both frame sizes)
    rc.set_isovalue(EXACT_ISOS[-1] + 1.0)
    rc.render(cam, size)
    rc.render(cam, preview)
    change, first, prev = [], [], []
    for iso in EXACT_ISOS:
        t = time.perf_counter()
        rc.set_isovalue(iso)
        change.append(time.perf_counter() - t)
        rc.render(cam, size)
        first.append(time.perf_counter() - t)
    cubes = rc.stats["active_cells"]
    for iso in PREVIEW_ISOS:
        t = time.perf_counter()
        rc.set_isovalue(iso)
        rc.render(cam, preview)
        prev.append(time.perf_counter() - t)
    rc.set_isovalue(EXACT_ISOS[0])
    rc.render(cam, size)
    moving = []
    for step in AZIMUTH_STEPS:
        cam = _rotated(cam, step)
        t = time.perf_counter()
        rc.render(cam, size)
        moving.append(time.perf_counter() - t)
    return {"setup_s": setup, "change_s": statistics.median(change),
            "first_s": statistics.median(first), "preview_s": statistics.median(prev),
            "move_s": statistics.median(moving), "visible_cells": cubes,
            "path": rc.stats["path"], "device": rc.stats["device"], "rss": peak_rss()}


def _child(conn, func, args):
    try:
        conn.send(("ok", func(*args)))
    except Exception as exc:  # reported in the table, the other rows still run
        conn.send(("error", f"{type(exc).__name__}: {exc}"))
    conn.close()


def _in_process(func, args, timeout):
    """``func(*args)`` in a fresh spawned process: (result dict) or {"error": reason}."""
    import multiprocessing as mp

    ctx = mp.get_context("spawn")
    parent, child = ctx.Pipe(duplex=False)
    p = ctx.Process(target=_child, args=(child, func, args))
    p.start()
    child.close()
    if parent.poll(timeout):
        status, value = parent.recv()
    else:
        status, value = "error", f"timed out after {timeout:.0f} s"
    p.join(5)
    if p.is_alive():
        p.kill()
        p.join()
    return value if status == "ok" else {"error": value}


def run_isovalue_bench(data_dir, sizes=(256, 512), models=MODELS, size=(512, 512),
                       preview=(128, 128), device=None, timeout=600.0, out=print) -> list[dict]:
    """Run the benchmark and print its table; returns one dict per (volume size, model).

    Parameters
    ----------
    data_dir : folder holding bonsai.vti
    sizes : volume sizes n (n^3 samples; 256 is bonsai itself)
    models : spline models
    size, preview : (width, height) of the exact and the preview frames
    device : OpenCL device preference (see ``SPLINEVIZ_DEVICE``)
    timeout : seconds allowed per measurement (process)
    """
    rows = []
    with tempfile.TemporaryDirectory(prefix="splineviz-bench-") as tmp:
        for n in sizes:
            data, spacing = bonsai_volume(data_dir, n)
            path = str(Path(tmp) / f"bonsai{n}.npy")
            np.save(path, data)
            nbytes = data.nbytes
            del data
            vtk = _in_process(_measure_vtk, (path, spacing, size), timeout)
            for model in models:
                r = _in_process(_measure_caster, (path, spacing, model, size, preview, device),
                                timeout)
                r.update(n=n, model=model, volume_bytes=nbytes, vtk=vtk)
                if "error" not in r and "error" not in vtk:
                    r.update(change_vs_fe=r["change_s"] / vtk["extract_s"],
                             first_vs_fe_first=r["first_s"] / (vtk["extract_s"] + vtk["first_s"]),
                             move_vs_vtk=r["move_s"] / vtk["move_s"],
                             rss_vs_vtk=r["rss"] / vtk["rss"])
                rows.append(r)
            os.remove(path)
    _print_table(rows, size, preview, out)
    return rows


def _print_table(rows, size, preview, out):
    gib = 2.0**30
    out(f"isovalue changes on bonsai; exact frames {size[0]}x{size[1]}, previews "
        f"{preview[0]}x{preview[1]}; ratios against vtkFlyingEdges3D (+ offscreen render) "
        f"in the same run, < 1: ours faster/smaller")
    out(f"{'n^3':>4} {'model':15} {'change s':>9} {'/FE':>6} {'1st exact s':>11} "
        f"{'/(FE+1st)':>9} {'preview s':>9} {'move s':>7} {'/VTK':>6} {'RSS GiB':>7} "
        f"{'/VTK':>5} {'/vol':>5}")
    shown = set()
    for r in rows:
        vtk = r["vtk"]
        if r["n"] not in shown:
            shown.add(r["n"])
            if "error" in vtk:
                out(f"{r['n']:4d} {'VTK':15} {vtk['error']}")
            else:
                out(f"{r['n']:4d} {'VTK FE+render':15} {vtk['extract_s']:9.4f} {'':6} "
                    f"{vtk['extract_s'] + vtk['first_s']:11.3f} {'':9} {'':9} "
                    f"{vtk['move_s']:7.3f} {'':6} {vtk['rss'] / gib:7.2f} {'':5} "
                    f"{vtk['rss'] / r['volume_bytes']:5.1f}  ({vtk['triangles']} triangles)")
        if "error" in r:
            out(f"{r['n']:4d} {r['model']:15} {r['error']}")
            continue
        ratio = {k: f"{r[k]:.3f}" if k in r else "-"
                 for k in ("change_vs_fe", "first_vs_fe_first", "move_vs_vtk", "rss_vs_vtk")}
        out(f"{r['n']:4d} {r['model']:15} {r['change_s']:9.5f} {ratio['change_vs_fe']:>6} "
            f"{r['first_s']:11.3f} {ratio['first_vs_fe_first']:>9} {r['preview_s']:9.3f} "
            f"{r['move_s']:7.3f} {ratio['move_vs_vtk']:>6} {r['rss'] / gib:7.2f} "
            f"{ratio['rss_vs_vtk']:>5} {r['rss'] / r['volume_bytes']:5.1f}")
    devices = {r["device"] for r in rows if "device" in r}
    if devices:
        out(f"device: {', '.join(sorted(devices))}")
