"""Benchmark: curvature of isosurfaces from the spline at the ray hits vs. ParaView's way
(issue 14).

Fields sampled at 64^3: the distance fields of a sphere (radius 0.6) and a torus (radii 0.6 and
0.25) on [-1, 1]^3, and Marschner-Lobb at its isovalue 0.5. Per spline model, a frame is ray
cast (the OpenCL caster, or the NumPy reference for models without a kernel) and the mean and
Gaussian curvature at every hit are computed from the model's gradient and Hessian
(:mod:`splineviz.core.curvature`, what "colour by curvature" shows). ParaView's way: a
flying-edges mesh of the same samples and ``vtkCurvatures`` at its vertices. Both are compared
with the analytic curvatures of the field's level set through the same points (exact
derivatives of the closed forms). vtkCurvatures' mean-curvature sign follows the mesh
orientation: it is aligned with the analytic sign first. Errors are absolute, in units of
1 / (domain half-width); the table gives median and 90th percentile.

Run: ``python -m splineviz.bench.curvature [--size 64] [--pixels 160]``
"""

from __future__ import annotations

import argparse
import time

import numpy as np


def _fields():
    from splineviz.core import jet
    from splineviz.core.testfunctions import TestFunction, ml

    def sphere(x, y, z):
        return jet.sqrt(x**2 + y**2 + z**2)

    def torus(x, y, z):
        return jet.sqrt((jet.sqrt(x**2 + y**2) - 0.6) ** 2 + z**2)

    dom = ((-1.0, 1.0),) * 3
    return [(TestFunction("sphere", sphere, dom), 0.6),
            (TestFunction("torus", torus, dom), 0.25),
            (ml, 0.5)]


def analytic(f, points):
    """Analytic mean and Gaussian curvature of the level sets of ``f`` at ``(N, 3)`` points."""
    from splineviz.core.curvature import principal_curvatures

    d = f.derivatives(points[:, 0], points[:, 1], points[:, 2])
    k1, k2 = principal_curvatures(d.g, d.h)
    return 0.5 * (k1 + k2), k1 * k2


def _errors(mean, gauss, exact_mean, exact_gauss):
    ok = np.isfinite(mean) & np.isfinite(gauss) & np.isfinite(exact_mean) & \
        np.isfinite(exact_gauss)
    em = np.abs(mean[ok] - exact_mean[ok])
    eg = np.abs(gauss[ok] - exact_gauss[ok])
    return (np.median(em), np.percentile(em, 90), np.median(eg), np.percentile(eg, 90),
            int(ok.sum()))


def spline_row(f, vol, iso, model, pixels):
    import splineviz as sv
    from splineviz.core.curvature import spline_curvatures

    cam = sv.Camera((2.2, -3.1, 1.7), (0, 0, 0), view_up=(0, 0, 1), view_angle=30.0)
    t0 = time.perf_counter()
    rc = sv.RayCaster(vol, model=model)
    rc.set_isovalue(iso)
    frame = rc.render(cam, size=(pixels, pixels))
    pts = frame.position[frame.hit]
    t_cast = time.perf_counter() - t0
    t0 = time.perf_counter()
    spline = sv.build_spline(vol, model)
    k1, k2 = spline_curvatures(spline, pts)
    t_curv = time.perf_counter() - t0
    em, eg = analytic(f, pts)
    path = rc.stats.get("path", "?")
    return _errors(0.5 * (k1 + k2), k1 * k2, em, eg), f"{path}, {t_cast:.1f}+{t_curv:.1f} s"


def mesh_row(f, vol, iso):
    import pyvista as pv

    grid = pv.ImageData(dimensions=vol.shape, spacing=vol.spacing, origin=vol.origin)
    grid.point_data["f"] = vol.data.ravel(order="F")
    t0 = time.perf_counter()
    mesh = grid.contour([iso], scalars="f", method="flying_edges")
    mean = np.asarray(mesh.curvature("mean"))
    gauss = np.asarray(mesh.curvature("gaussian"))
    t = time.perf_counter() - t0
    pts = np.asarray(mesh.points, dtype=np.float64)
    em, eg = analytic(f, pts)
    ok = np.isfinite(em) & np.isfinite(mean)
    if np.median(mean[ok] * em[ok]) < 0:  # vtkCurvatures' sign follows the orientation
        mean = -mean
    return _errors(mean, gauss, em, eg), f"vtk, {t:.2f} s"


def main(argv=None):
    import splineviz as sv
    from splineviz.plugins import ensure_loaded

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, default=64)
    ap.add_argument("--pixels", type=int, default=160)
    ap.add_argument("--models", nargs="+", default=["trilinear", "super-quadratic", "cubic-c1",
                                                    "to-quadratic", "tricubic-bspline"])
    args = ap.parse_args(argv)
    ensure_loaded()
    print("| field | method | hits/vertices | mean: median | mean: p90 | Gaussian: median "
          "| Gaussian: p90 | how, time |")
    print("|---|---|---|---|---|---|---|---|")
    for f, iso in _fields():
        vol = sv.Volume.from_function(f, (args.size,) * 3, f.domain)
        rows = [(m, *spline_row(f, vol, iso, m, args.pixels)) for m in args.models]
        rows.append(("vtkCurvatures on flying edges", *mesh_row(f, vol, iso)))
        for name, (mm, m90, gm, g90, n), how in rows:
            print(f"| {f.name} | {name} | {n} | {mm:.4f} | {m90:.4f} | {gm:.4f} | {g90:.4f} "
                  f"| {how} |", flush=True)


if __name__ == "__main__":
    main()
