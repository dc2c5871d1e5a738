"""Benchmark: spline-isosurface meshes by isotropic remeshing on the spline (issue 31) and by
the advancing front (issue 14) against flying edges.

:func:`run` (``splineviz bench spline-mesh``): per set (the whole tooth at 100.5 and the whole
bonsai at 40.5 by default), in one run: :func:`splineviz.pointcloud.spline_remesh.spline_remesh`
(time, CPU time, stages, peak RSS of the process after it), "Export mesh"'s flying edges,
flying edges + pymeshlab's isotropic remeshing (10 iterations) to the remeshed mesh's vertex
count (the time reference), and flying edges of the spline at twice the remeshed mesh's
triangle count (the Hausdorff reference); measures as below.

:func:`run_front` (``--front-rho``):

For each data set (a 40^3 crop of the bonsai's crown and the whole bonsai at 40.5, tooth at
100.5; cubic-c1 by default) it builds "Export mesh"'s flying-edges mesh (spline samples on the
grid refined twice, vertices moved onto the spline; once only past the export's sample cap,
as for the whole bonsai, which then also gets the twice-refined mesh, sampled slab by slab)
and advancing-front meshes on the spline for a few ``rho``, and prints per mesh: triangles
(and their share of twice-refined flying edges'), time, largest |s - iso| at the vertices over
the data range, mean radius ratio, valence-6 share of interior vertices, the Hausdorff
distance to the exact surface (in grid steps), and the triangles that leave the surface by the
spline mesher's own test (:func:`splineviz.pointcloud.spline_mesh.triangles_on_surface`:
bridges between sheets).

Hausdorff: mesh -> surface from 7 samples per triangle projected onto s = iso by Newton steps,
surface -> mesh from the other mesh's vertices (which lie on the surface). Both leave out
points within 1.5 grid steps of the data box: the front stops about one sample short of the
box faces (flying edges reaches them), and Newton steps keep a point on a box face within that
face, so its distance there is not the distance to the surface.

Run: ``python -m splineviz.bench.spline_mesh [--data DIR] [--sets bonsai-crop bonsai tooth]
[--model cubic-c1] [--edge-length L] [--front-rho 0.3 0.45] [--save DIR]`` (the front on the
whole bonsai: ~20 min of one core and ~8 GB of memory for the three meshes and their measures)
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

#: name -> (file, isovalue, crop as (start index, shape) or None for the whole volume)
SETS = {"bonsai": ("bonsai.vti", 40.5, None),
        # a leafy part of the crown (most isovalue crossings among 40^3 windows in the crown)
        "bonsai-crop": ("bonsai.vti", 40.5, ((128, 168, 32), (40, 40, 40))),
        "tooth": ("tooth.nrrd", 100.5, None)}


def load(data_dir: Path, name: str):
    """The volume of a benchmark set (cropped where the set says) and its isovalue."""
    import splineviz as sv

    fname, iso, crop = SETS[name]
    vol = sv.read_volume(data_dir / fname)
    if crop is not None:
        (i, j, k), (ni, nj, nk) = crop
        vol = sv.Volume(vol.data[i:i + ni, j:j + nj, k:k + nk], vol.spacing,
                        vol.index_to_world(np.array([[i, j, k]]))[0])
    return vol, iso


def flying_edges_refined(spline, iso: float, refine: int = 2):
    """:func:`splineviz.render.extract.spline_isosurface` on the grid refined ``refine`` times
    whatever its size: the spline is sampled one z slab at a time (the export's sample cap
    keeps the whole bonsai at one refinement; all points at once would take ~4 GB there).

    Returns
    -------
    vertices : (V, 3) on s = iso, faces : (F, 3)
    """
    import pyvista as pv

    from splineviz.core.isosurface import project_to_isosurface

    vol = spline.volume
    dims = (np.asarray(vol.shape) - 1) * refine + 1
    spacing = np.asarray(vol.spacing, dtype=np.float64) / refine
    origin = np.asarray(vol.origin, dtype=np.float64)
    x = origin[0] + spacing[0] * np.arange(dims[0])
    y = origin[1] + spacing[1] * np.arange(dims[1])
    xx, yy = np.meshgrid(x, y)  # (ny, nx): VTK's point order, x fastest
    plane = np.stack([xx.ravel(), yy.ravel(), np.zeros(xx.size)], axis=1)
    values = np.empty((dims[2], dims[1] * dims[0]))
    for k in range(dims[2]):
        plane[:, 2] = origin[2] + spacing[2] * k
        values[k] = spline.evaluate(plane)
    grid = pv.ImageData(dimensions=dims, spacing=spacing, origin=origin)
    grid.point_data["values"] = values.ravel()
    mesh = grid.contour([iso], scalars="values", method="flying_edges")
    pts, _normals = project_to_isosurface(spline, np.asarray(mesh.points), iso)
    return pts, mesh.faces.reshape(-1, 4)[:, 1:]


def _interior(spline, points, margin):
    lo = np.array([b[0] for b in spline.bounds]) + margin
    hi = np.array([b[1] for b in spline.bounds]) - margin
    return np.all((points > lo) & (points < hi), axis=1)


#: points per chunk of the Hausdorff measurement (the whole bonsai's meshes have millions)
CHUNK = 1_000_000


def measure(spline, iso, vertices, faces, other_vertices):
    """Quality and accuracy of one mesh of ``s = iso`` (see the module notes)."""
    from splineviz.pointcloud.quality import (
        distance_to_mesh,
        edge_face_counts,
        radius_ratios,
        surface_samples,
        valences,
    )
    from splineviz.pointcloud.spline_mesh import project_onto, triangles_on_surface

    step = float(np.min(spline.volume.spacing))
    lo, hi = spline.volume.finite_range
    edges, counts = edge_face_counts(faces)
    val = valences(len(vertices), edges)
    inner = np.ones(len(vertices), dtype=bool)
    inner[np.unique(edges[counts == 1])] = False
    samples = surface_samples(vertices, faces, per_face=4)
    # a point on a face of the data box is projected within that face: its distance is not
    # the distance to the surface
    samples = samples[_interior(spline, samples, 1.5 * step)]
    forward = np.concatenate([np.linalg.norm(part - project_onto(spline, part, iso, 10)[0],
                                             axis=1)
                              for part in np.array_split(samples, len(samples) // CHUNK + 1)])
    other = other_vertices[_interior(spline, other_vertices, 1.5 * step)]
    backward = np.concatenate([distance_to_mesh(part, vertices, faces)
                               for part in np.array_split(other, len(other) // CHUNK + 1)])
    return {"triangles": len(faces),
            "on_surface": float(np.abs(spline.evaluate(vertices) - iso).max() / (hi - lo)),
            "radius_ratio": float(radius_ratios(vertices, faces).mean()),
            "valence6": float(np.mean(val[inner] == 6)),
            "hausdorff": float(max(forward.max(), backward.max()) / step),
            "to_surface_max": float(forward.max() / step),
            "from_surface_max": float(backward.max() / step),
            "off_surface": int(np.sum(~triangles_on_surface(spline, iso, vertices[faces])))}


def _peak_rss_gib() -> float:
    """Peak resident memory of this process so far (GiB)."""
    from splineviz.bench.memory import peak_rss

    return peak_rss() / 2**30


def _timed(fn, *args, **kwargs):
    t0, c0 = time.perf_counter(), time.process_time()
    out = fn(*args, **kwargs)
    return out, time.perf_counter() - t0, time.process_time() - c0


def pymeshlab_remesh(vertices, faces, n_vertices: int, iterations: int = 10):
    """pymeshlab's isotropic remeshing of a mesh to about ``n_vertices`` vertices (the target
    edge length from the area: an equilateral mesh of A / V has about twice as many faces as
    vertices, each of area sqrt(3)/4 L^2); ``None`` without pymeshlab."""
    try:
        import pymeshlab
    except ImportError:
        return None
    tri = vertices[faces]
    area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]),
                                axis=1).sum()
    length = np.sqrt(area / n_vertices * 2.0 / np.sqrt(3.0))
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertices, faces))
    ms.meshing_isotropic_explicit_remeshing(iterations=iterations,
                                            targetlen=pymeshlab.PureValue(length))
    m = ms.current_mesh()
    return np.asarray(m.vertex_matrix(), dtype=np.float64), np.asarray(m.face_matrix())


def run(data_dir: Path, name: str, model: str, edge_length: float | None = None,
        save: Path | None = None):
    """Mesh one set with :func:`~splineviz.pointcloud.spline_remesh.spline_remesh` (first,
    so that the peak RSS after it is the mesher's on top of the loaded data), flying edges of
    the export, flying edges + pymeshlab's isotropic remeshing to the same vertex count, and
    flying edges at twice the remeshed mesh's triangle count (the Hausdorff reference); print
    the table and return its rows ``[(label, seconds, measures)]``."""
    import splineviz as sv
    from splineviz.core.isosurface import project_to_isosurface
    from splineviz.pointcloud.spline_remesh import GRID_FRACTION, flying_edges_start, spline_remesh
    from splineviz.render.extract import spline_isosurface

    vol, iso = load(data_dir, name)
    spline = sv.build_spline(vol, model)
    spline.evaluate(np.zeros((1, 3)))  # build the padded data before timing
    step = float(np.min(vol.spacing))
    rss0 = _peak_rss_gib()
    stages = {}
    (v, f, _n), t_ours, c_ours = _timed(spline_remesh, spline, iso, edge_length=edge_length,
                                        timings=stages)
    rss = _peak_rss_gib()
    print(f"{name}: remeshed on the spline, {len(f)} triangles in {t_ours:.1f} s "
          f"(CPU {c_ours:.1f} s; stages " + ", ".join(f"{k} {t:.1f} s" for k, t in stages.items())
          + f"); peak RSS {rss:.2f} GiB (after loading {rss0:.2f} GiB)", flush=True)
    fe, t_fe, c_fe = _timed(spline_isosurface, spline, iso)
    fe_v = np.asarray(fe.points, dtype=np.float64)
    fe_f = fe.faces.reshape(-1, 4)[:, 1:]
    rows = [("remesh on the spline", t_ours, c_ours, (v, f)),
            ("flying edges (export)", t_fe, c_fe, (fe_v, fe_f))]
    pml, t_pml, c_pml = _timed(pymeshlab_remesh, fe_v, fe_f, len(v))
    if pml is None:
        print("pymeshlab is not installed: no flying edges + isotropic remeshing row")
    else:
        rows.append(("flying edges + pymeshlab remeshing", t_fe + t_pml, c_fe + c_pml, pml))
    # flying edges with twice our triangles: triangle counts go as the grid step^-2
    length = step if edge_length is None else edge_length
    v0, f0 = flying_edges_start(spline, iso, GRID_FRACTION * length)
    h = GRID_FRACTION * length * np.sqrt(len(f0) / (2.0 * len(f)))
    (v2, f2), t2, c2 = _timed(flying_edges_start, spline, iso, h)
    # its vertices onto the spline, as the export's
    (v2, _n2), t_p, c_p = _timed(project_to_isosurface, spline, v2, iso)
    t2, c2 = t2 + t_p, c2 + c_p
    rows.append((f"flying edges at 2x triangles (step {h / step:.2f})", t2, c2, (v2, f2)))
    if save is not None:
        for label, *_r, (mv, mf) in rows:
            np.savez(save / f"{name}-{label.split(' (')[0].replace(' ', '-')}.npz",
                     vertices=mv, faces=mf)
    print(f"\n{name} {vol.shape} ({model}, iso {iso:g}); Hausdorff in grid steps; surface ->"
          " mesh samples: the vertices of flying edges at 2x (for it: the remeshed mesh's)")
    print("| mesh | vertices | triangles | time s | CPU s | x FE+pymeshlab | "
          "max abs(s-iso)/range | mean radius ratio | valence-6 | Hausdorff | "
          "mesh->surface | surface->mesh | off-surface triangles |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    t_ref = t_fe + t_pml if pml is not None else float("nan")
    out = []
    for label, t, c, (mv, mf) in rows:
        other = v if label.startswith("flying edges at 2x") else v2
        m = measure(spline, iso, mv, mf, other)
        out.append((label, t, m))
        print(f"| {label} | {len(mv)} | {m['triangles']} | {t:.1f} | {c:.1f} | "
              f"{t / t_ref:.2f} | {m['on_surface']:.1e} | {m['radius_ratio']:.3f} | "
              f"{m['valence6']:.1%} | {m['hausdorff']:.4f} | {m['to_surface_max']:.4f} | "
              f"{m['from_surface_max']:.4f} | {m['off_surface']} |", flush=True)
    print(f"peak RSS of the remeshing on the spline: {rss:.2f} GiB", flush=True)
    return out


def run_front(data_dir: Path, name: str, model: str, rhos, save: Path | None = None):
    """Mesh one set with flying edges and the front (one per ``rho``), print the table (and
    the front's stage times) and return its rows ``[(label, seconds, measures)]``, flying
    edges first; ``save``: a folder for the meshes (``.npz``)."""
    import splineviz as sv
    from splineviz.pointcloud.spline_mesh import spline_front_mesh
    from splineviz.render.extract import MAX_SAMPLES, spline_isosurface

    vol, iso = load(data_dir, name)
    spline = sv.build_spline(vol, model)
    spline.evaluate(np.zeros((1, 3)))  # build the padded data before timing
    t0, c0 = time.perf_counter(), time.process_time()
    fe = spline_isosurface(spline, iso)
    t_fe, c_fe = time.perf_counter() - t0, time.process_time() - c0
    fe_v = np.asarray(fe.points, dtype=np.float64)
    fe_f = fe.faces.reshape(-1, 4)[:, 1:]
    # past the export's sample cap (the whole bonsai) its mesh is refined once only: the
    # twice-refined one too, the reference of the smaller sets
    refined = np.prod((np.asarray(spline.volume.shape) - 1) * 2 + 1) > MAX_SAMPLES
    if refined:
        t0, c0 = time.perf_counter(), time.process_time()
        fe2_v, fe2_f = flying_edges_refined(spline, iso, 2)
        t_fe2, c_fe2 = time.perf_counter() - t0, time.process_time() - c0
    fronts, stages = [], []
    for rho in rhos:
        t0, c0 = time.perf_counter(), time.process_time()
        stages.append({})
        v, f, _n = spline_front_mesh(spline, iso, rho=rho, timings=stages[-1])
        fronts.append((rho, v, f, time.perf_counter() - t0, time.process_time() - c0))
        print(f"{name} front rho={rho:g}: {len(f)} triangles in {fronts[-1][3]:.1f} s "
              f"(CPU {fronts[-1][4]:.1f} s; flying edges {len(fe_f)} in {t_fe:.1f} s, "
              f"CPU {c_fe:.1f} s)", flush=True)
        if save is not None:
            np.savez(save / f"{name}-front-{rho:g}.npz", vertices=v, faces=f)
    if save is not None:
        np.savez(save / f"{name}-fe.npz", vertices=fe_v, faces=fe_f)
        if refined:
            np.savez(save / f"{name}-fe2.npz", vertices=fe2_v, faces=fe2_f)
    # the surface -> mesh samples of the fronts: the vertices of the finest flying edges
    reference = fe2_v if refined else fe_v
    rows = [("flying edges x1 (export)" if refined else "flying edges x2", t_fe, c_fe,
             measure(spline, iso, fe_v, fe_f, fronts[0][1]))]
    if refined:
        rows.append(("flying edges x2", t_fe2, c_fe2,
                     measure(spline, iso, fe2_v, fe2_f, fronts[0][1])))
    rows += [(f"front rho={rho:g}", t, c, measure(spline, iso, v, f, reference))
             for rho, v, f, t, c in fronts]
    print(f"\n{name} {spline.volume.shape} ({model}, iso {iso:g})")
    # wall and CPU seconds: on a loaded machine the CPU time is the one-core figure
    print("| mesh | triangles | of FE x2 | time s | CPU s | max abs(s-iso)/range "
          "| mean radius ratio | valence-6 | Hausdorff (grid steps) | mesh->surface "
          "| surface->mesh | off-surface triangles |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    n_fe = rows[1 if refined else 0][3]["triangles"]  # shares of flying edges x2
    for label, t, c, m in rows:
        print(f"| {label} | {m['triangles']} | {m['triangles'] / n_fe:.1%} | {t:.1f} | {c:.1f} | "
              f"{m['on_surface']:.1e} | {m['radius_ratio']:.3f} | {m['valence6']:.1%} | "
              f"{m['hausdorff']:.4f} | {m['to_surface_max']:.4f} | "
              f"{m['from_surface_max']:.4f} | {m['off_surface']} |")
    names = list(stages[0])
    print("\n| front stage times s | " + " | ".join(names) + " |")
    print("|---" * (len(names) + 1) + "|")
    for (rho, *_), times in zip(fronts, stages, strict=True):
        print(f"| rho={rho:g} | " + " | ".join(f"{times[k]:.1f}" for k in names) + " |")
    return [(label, t, m) for label, t, _c, m in rows]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=Path.cwd() / ".." / "shared" / "data" / "volumes",
                    help="volumes folder (default ../shared/data/volumes)")
    ap.add_argument("--sets", nargs="+", default=["tooth", "bonsai"], choices=list(SETS))
    ap.add_argument("--model", default="cubic-c1")
    ap.add_argument("--edge-length", type=float, default=None,
                    help="target edge length of the remeshing (default one grid step)")
    ap.add_argument("--front-rho", nargs="*", type=float, default=[],
                    help="also run the advancing front with these rho (slow: minutes)")
    ap.add_argument("--save", type=Path, help="folder for the meshes (.npz)")
    args = ap.parse_args(argv)
    for name in args.sets:
        run(args.data, name, args.model, args.edge_length, args.save)
        if args.front_rho:
            run_front(args.data, name, args.model, args.front_rho, args.save)


if __name__ == "__main__":
    main()
