"""``splineviz bench raycast``: ray-casting speed against baselines measured in the same run.

For each data set and model: the isovalue change, frame time (median of ``repeats`` renders;
the first classifies what the rays reach), active cells (of a classification of all cells);
and ratios against (a) VTK ``vtkFlyingEdges3D`` plus an
offscreen render of the same isovalue (extraction time and frame time) and (b) the trilinear
OpenCL ray caster. Models without an OpenCL kernel are listed as such rather than timed on
the NumPy path (minutes per frame at 512^2).
"""

from __future__ import annotations

import os
import statistics
import time
from pathlib import Path

from splineviz.compute.raycast import RayCaster, kernel_define
from splineviz.core.camera import default_camera

#: (file, isovalue) pairs of the issue's benchmark
DATASETS = (("bonsai.vti", 40.0), ("engine.vti", 128.0))
MODELS = ("trilinear", "super-quadratic", "cubic-c1", "to-quadratic")


def flying_edges(img, iso: float):
    """``(mesh, seconds)``: the peer's isosurface, vtkFlyingEdges3D with normals, of a
    ``pyvista.ImageData`` with one point array, and the time it took."""
    import pyvista as pv
    from vtkmodules.vtkFiltersCore import vtkFlyingEdges3D

    t = time.perf_counter()
    fe = vtkFlyingEdges3D()
    fe.SetInputData(img)
    fe.SetValue(0, iso)
    fe.ComputeNormalsOn()
    fe.Update()
    return pv.wrap(fe.GetOutput()), time.perf_counter() - t


def _vtk_baseline(volume, iso, camera, size, repeats):
    """(extract_s, n_triangles, first_frame_s, frame_s) of flying edges + offscreen render."""
    if not os.environ.get("DISPLAY"):
        # headless: EGL (Mesa) instead of a failing X connection (see ENVIRONMENT.md)
        os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    import pyvista as pv

    img = pv.ImageData(dimensions=volume.shape, spacing=volume.spacing, origin=volume.origin)
    img.point_data["v"] = volume.data.ravel(order="F")  # VTK: x varies fastest
    mesh, extract = flying_edges(img, iso)
    pl = pv.Plotter(off_screen=True, window_size=size)
    pl.add_mesh(mesh, color=(0.93, 0.78, 0.55), smooth_shading=True)
    pl.camera.position = camera.position
    pl.camera.focal_point = camera.focal_point
    pl.camera.up = camera.view_up
    pl.camera.view_angle = camera.view_angle
    t = time.perf_counter()
    pl.show(auto_close=False)  # first frame: window, upload of the mesh, draw
    first = time.perf_counter() - t
    times = []
    for i in range(repeats):
        pl.camera.azimuth = 0.01 * (i + 1)  # a changed camera forces a real redraw
        t = time.perf_counter()
        pl.ren_win.Render()
        pl.screenshot(return_img=True)  # read back, as the ray caster returns its pixels
        times.append(time.perf_counter() - t)
    pl.close()
    return extract, mesh.n_cells, first, statistics.median(times)


def run_bench(data_dir, size=(512, 512), repeats=3, models=MODELS, datasets=DATASETS,
              device=None, out=print) -> list[dict]:
    """Run the benchmark and print a table; returns the rows."""
    from splineviz.io.volumes import read_volume

    rows = []
    for name, iso in datasets:
        vol = read_volume(Path(data_dir) / name)
        cam = default_camera(vol.bounds)
        extract, ntri, first, vtk_frame = _vtk_baseline(vol, iso, cam, size, repeats)
        tri_frame = None
        for model in models:
            row = {"data": name, "model": model, "iso": iso, "vtk_extract_s": extract,
                   "vtk_triangles": ntri, "vtk_first_frame_s": first, "vtk_frame_s": vtk_frame}
            if kernel_define(model) is None:
                row["note"] = "no OpenCL kernel yet (NumPy path only)"
                rows.append(row)
                continue
            rc = RayCaster(vol, model=model, device=device)
            rc.set_isovalue(iso + 0.25)  # warm-up: builds programs and the scan kernel
            rc.render(cam, (8, 8))
            rc.set_isovalue(iso)
            classify = rc.stats["classify_s"]
            times = []
            for _ in range(repeats):
                rc.render(cam, size)
                times.append(rc.stats["render_s"])
            frame = statistics.median(times)
            rc.classify_all()  # the counts of every cell (frames classify only what they see)
            if model == "trilinear":
                tri_frame = frame
            row.update(classify_s=classify, frame_s=frame, active_cells=rc.stats["active_cells"],
                       active_tets=rc.stats["active_tets"],
                       device=rc.stats["device"],
                       frame_vs_vtk_frame=frame / vtk_frame,
                       classify_vs_vtk_extract=classify / extract,
                       frame_vs_vtk_extract_plus_first=frame / (extract + first),
                       frame_vs_trilinear=frame / tri_frame if tri_frame else None)
            rows.append(row)
    _print_table(rows, size, out)
    return rows


def _fmt(v, spec):
    return "-" if v is None else format(v, spec)


def _print_table(rows, size, out):
    out(f"ray casting at {size[0]}x{size[1]} (median frame times); ratios < 1: ours faster")
    out(f"{'data':11} {'model':15} {'classify s':>10} {'frame s':>8} {'act cells':>9} "
        f"{'act tets':>9} "
        f"{'VTK FE s':>8} {'VTK 1st s':>9} {'VTK frm s':>9} {'cls/FE':>7} {'frm/VTKfrm':>10} "
        f"{'frm/(FE+1st)':>12} {'frm/tri':>7}")
    for r in rows:
        if "note" in r:
            out(f"{r['data']:11} {r['model']:15} {r['note']}")
            continue
        out(f"{r['data']:11} {r['model']:15} {r['classify_s']:10.4f} {r['frame_s']:8.4f} "
            f"{r['active_cells']:9d} {_fmt(r['active_tets'], '9d')} {r['vtk_extract_s']:8.4f} "
            f"{r['vtk_first_frame_s']:9.4f} "
            f"{r['vtk_frame_s']:9.4f} {r['classify_vs_vtk_extract']:7.3f} "
            f"{r['frame_vs_vtk_frame']:10.2f} {r['frame_vs_vtk_extract_plus_first']:12.3f} "
            f"{_fmt(r['frame_vs_trilinear'], '7.2f')}")
    if rows and "device" in rows[0]:
        tris = ", ".join(f"{r['data']} {r['vtk_triangles']}" for r in rows
                         if r["model"] == "trilinear")
        out(f"device: {rows[0]['device']}; VTK triangles: {tris}")
