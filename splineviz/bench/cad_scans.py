"""``splineviz bench cad-scans``: our mesher against screened Poisson on range scans of parts
with sharp creases and flat faces (issue 31, part 3).

Shapes (exact triangle meshes, the true surfaces):

* ``box-cylinder``: a box with a cylinder through it, sticking out of two faces (pymeshlab's
  boolean union): convex edges, the cylinder's rims and concave creases where it meets the box;
* ``bracket``: an L of two plates with a round hole through each (union, then differences);
* ``airplane``: pymeshlab's sample mesh (``tests/sample_meshes/airplane.obj``): sharp wing and
  tail edges.

Each is scanned from ``VIEWS`` viewpoints (the corners of a tetrahedron around it, so every
face of a box is seen): a pinhole range scanner casts a square grid of rays at the true mesh
(Open3D's ``RaycastingScene``), keeps the first hits not seen at a grazing angle beyond
``GRAZING_DEG``, and moves each along its ray by Gaussian noise; the scans' noise differs
(``SCAN_NOISE`` times the level), the levels are ``NOISES`` (fractions of the diagonal).  The
grids are sized so the merged cloud has about ``--points`` points.

Methods, each in a child process with its time and peak memory:

* ``ours``: ``sv.remesh`` with default parameters on the points alone;
* ``poisson8``: Open3D screened Poisson, depth 8, normals estimated by Open3D and turned
  towards each point's scanner (as a scanner's software does), the ``TRIM`` quantile of the
  lowest-density vertices dropped.

Measures, against the true surface (:func:`~splineviz.pointcloud.quality.surface_agreement`,
in % of the diagonal where a length): Chamfer distance, F-score at ``FSCORE_AT`` of the
diagonal, normal consistency and Hausdorff distance.  The mesh is measured against the whole
true surface, the true surface's part that some scanner saw against the mesh (an unseen
underside is no hole of the mesh).  The last columns give ours over Poisson and which of
issue 31's targets hold (each measure at least as good as Poisson's, time at most its).

Run: ``splineviz bench cad-scans [--points N] [--shapes a,b] [--noises 0,0.0025]
[--pictures DIR]`` (or ``python -m splineviz.bench.cad_scans``).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from splineviz.bench.remesh import _load_ours, _ours, _poisson, run_peer

SHAPES = ("box-cylinder", "bracket", "airplane")
#: scanner noise levels, Gaussian sigma along the ray in fractions of the diagonal
NOISES = (0.0, 0.0025, 0.005)
#: each scan's noise over the level: the scans of one part differ, their mean is the level
SCAN_NOISE = (0.6, 0.8, 1.2, 1.4)
#: scanner directions from the part's centre: a tetrahedron's corners
VIEWS = np.array([[1.0, 1.0, 1.0], [-1.0, -1.0, 1.0], [-1.0, 1.0, -1.0], [1.0, -1.0, -1.0]])
#: scanner distance from the centre in diagonals
SCAN_DISTANCE = 2.5
#: rays hitting the surface more obliquely than this are lost, as on a real scanner
GRAZING_DEG = 80.0
#: the F-score's distance, a fraction of the diagonal
FSCORE_AT = 0.01
#: the fraction of Poisson's lowest-density vertices dropped
TRIM = 0.05
POISSON_DEPTH = 8
#: the true meshes' triangles are split until no edge is longer than this fraction of the
#: diagonal (the exact distances look at the nearest centroids' triangles)
TRUTH_EDGE = 0.01
#: area-uniform samples of each surface for the measures
SAMPLES = 100000
#: which targets ours should meet against Poisson: (measure, better when larger)
TARGETS = (("chamfer", False), ("fscore", True), ("normal_consistency", True),
           ("hausdorff", False), ("time_s", False))


def _box(lo, hi):
    import pymeshlab

    ms = pymeshlab.MeshSet()
    ms.create_cube(size=1.0)
    m = ms.current_mesh()
    v = m.vertex_matrix()
    v = (v - v.min(axis=0)) / np.ptp(v, axis=0) * (np.subtract(hi, lo)) + lo
    return v, m.face_matrix()


def _cylinder(centre, radius, length, axis, segments=96):
    """A closed cylinder (pymeshlab's cone with equal radii, along y) turned to ``axis``."""
    import pymeshlab

    ms = pymeshlab.MeshSet()
    ms.create_cone(r0=radius, r1=radius, h=length, subdiv=segments)
    m = ms.current_mesh()
    v = m.vertex_matrix()
    order = {"x": [1, 0, 2], "y": [0, 1, 2], "z": [0, 2, 1]}[axis]
    f = m.face_matrix()
    if axis != "y":  # swapping two axes mirrors the mesh: keep the faces outward
        f = f[:, ::-1]
    return v[:, order] + np.asarray(centre, float), f


def _csg(first, *steps):
    """``first`` combined with each ``(op, (V, F))`` of ``steps`` in turn (op: union or
    difference; pymeshlab's libigl booleans)."""
    import pymeshlab

    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(*first))
    for op, mesh in steps:
        current = ms.current_mesh_id()
        ms.add_mesh(pymeshlab.Mesh(*mesh))
        getattr(ms, f"generate_boolean_{op}")(first_mesh=current,
                                              second_mesh=ms.current_mesh_id())
    m = ms.current_mesh()
    return m.vertex_matrix(), m.face_matrix()


def cad_shape(name: str):
    """The true surface of a bench shape: ``(vertices (V, 3), faces (F, 3))``, closed."""
    if name == "box-cylinder":
        return _csg(_box([-1.0, -0.4, -0.6], [1.0, 0.4, 0.6]),
                    ("union", _cylinder([0.35, 0.0, 0.0], 0.32, 1.4, "y")))
    if name == "bracket":
        return _csg(_box([-1.0, 0.0, -0.6], [1.0, 0.3, 0.6]),
                    ("union", _box([-1.0, 0.0, -0.6], [-0.7, 1.2, 0.6])),
                    ("difference", _cylinder([0.3, 0.15, 0.0], 0.25, 1.0, "y")),
                    ("difference", _cylinder([-0.85, 0.75, 0.0], 0.2, 1.0, "x")))
    if name == "airplane":
        import pymeshlab

        ms = pymeshlab.MeshSet()
        ms.load_new_mesh(str(Path(pymeshlab.__file__).parent / "tests" / "sample_meshes"
                             / "airplane.obj"))
        m = ms.current_mesh()
        return m.vertex_matrix(), m.face_matrix()
    raise ValueError(f"unknown shape {name!r}")


def fine_truth(vertices, faces, edge):
    """The same surface with every edge split down to at most ``edge`` (midpoints: the
    geometry is unchanged)."""
    import pymeshlab

    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertices, faces))
    longest = np.linalg.norm(vertices[faces] - vertices[np.roll(faces, 1, axis=1)],
                             axis=2).max()
    ms.meshing_surface_subdivision_midpoint(
        iterations=int(np.ceil(np.log2(max(longest / edge, 1.0)))) + 1,
        threshold=pymeshlab.PureValue(edge))
    m = ms.current_mesh()
    return m.vertex_matrix(), m.face_matrix()


def _diag(vertices):
    return float(np.linalg.norm(np.ptp(vertices, axis=0)))


def _frames(vertices, views=VIEWS):
    """Each scanner's eye ``(S, 3)``, forward/right/up unit axes ``(S, 3)`` each, and the
    tangent of half its field of view (the part's bounding sphere fills the picture)."""
    centre = 0.5 * (vertices.min(axis=0) + vertices.max(axis=0))
    diag = _diag(vertices)
    d = views / np.linalg.norm(views, axis=1, keepdims=True)
    eyes = centre + SCAN_DISTANCE * diag * d
    forward = -d
    helper = np.where(np.abs(forward[:, 2:3]) > 0.9, [[1.0, 0, 0]], [[0, 0, 1.0]])
    right = np.cross(forward, helper)
    right /= np.linalg.norm(right, axis=1, keepdims=True)
    up = np.cross(right, forward)
    half = 0.5 * diag / np.sqrt((SCAN_DISTANCE * diag) ** 2 - (0.5 * diag) ** 2)
    return eyes, forward, right, up, half


def _scene(vertices, faces):
    import open3d as o3d

    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(o3d.core.Tensor(np.asarray(vertices, np.float32)),
                        o3d.core.Tensor(np.asarray(faces, np.uint32)))
    return scene


def _cast(scene, origins, directions):
    """First hits: ``(distance (M,), unit triangle normal (M, 3))``, distance inf on a miss."""
    import open3d as o3d

    rays = np.hstack([origins, directions]).astype(np.float32)
    hit = scene.cast_rays(o3d.core.Tensor(rays))
    return hit["t_hit"].numpy().astype(np.float64), hit["primitive_normals"].numpy()


def range_scans(vertices, faces, n_points, noise, seed=0, views=VIEWS):
    """Simulated range scans of a mesh, merged.

    Parameters
    ----------
    vertices (V, 3), faces (F, 3) : the scanned surface
    n_points : int
        About how many points all scans together should have.
    noise : float
        Gaussian sigma along the ray in fractions of the diagonal (scan ``i`` uses
        ``SCAN_NOISE[i]`` times it).

    Returns
    -------
    points : (N, 3)
    scanners : (N, 3) the eye of the scan each point came from
    """
    vertices = np.asarray(vertices, np.float64)
    scene = _scene(vertices, faces)
    eyes, forward, right, up, half = _frames(vertices, views)
    diag = _diag(vertices)
    rng = np.random.default_rng(seed)

    def grid_scan(i, res):
        s = np.linspace(-half, half, res)
        a, b = (g.ravel() for g in np.meshgrid(s, s))
        dirs = forward[i] + a[:, None] * right[i] + b[:, None] * up[i]
        dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
        t, normal = _cast(scene, np.broadcast_to(eyes[i], dirs.shape), dirs)
        seen = np.isfinite(t) & (np.abs(np.einsum("ij,ij->i", normal, dirs))
                                 > np.cos(np.radians(GRAZING_DEG)))
        return dirs[seen], t[seen]

    probe = 96
    points, scanners = [], []
    for i in range(len(views)):
        # the grid whose hits come nearest the scan's share of the points
        share = len(grid_scan(i, probe)[1]) / probe**2
        res = max(8, int(round(np.sqrt(n_points / len(views) / max(share, 1e-6)))))
        dirs, t = grid_scan(i, res)
        sigma = noise * SCAN_NOISE[i % len(SCAN_NOISE)] * diag
        t = t + rng.normal(scale=sigma, size=t.shape) if sigma > 0 else t
        points.append(eyes[i] + t[:, None] * dirs)
        scanners.append(np.broadcast_to(eyes[i], dirs.shape))
    return np.concatenate(points), np.concatenate(scanners)


def seen_samples(vertices, faces, points, face_ids, views=VIEWS):
    """Which surface samples some scanner saw: ``(M,)`` bool for ``points (M, 3)`` on
    ``faces[face_ids]`` -- inside a scanner's picture, not hidden, not grazing (the rules of
    :func:`range_scans`)."""
    from splineviz.pointcloud.quality import face_normals

    vertices = np.asarray(vertices, np.float64)
    scene = _scene(vertices, faces)
    eyes, forward, right, up, half = _frames(vertices, views)
    normals = face_normals(vertices, np.asarray(faces))[face_ids]
    seen = np.zeros(len(points), dtype=bool)
    for i in range(len(views)):
        to = points - eyes[i]
        dist = np.linalg.norm(to, axis=1)
        dirs = to / dist[:, None]
        depth = dirs @ forward[i]
        inside = (np.abs(dirs @ right[i]) <= half * depth) & (np.abs(dirs @ up[i])
                                                               <= half * depth)
        t, _ = _cast(scene, np.broadcast_to(eyes[i], dirs.shape), dirs)
        visible = t >= dist - 1e-4 * _diag(vertices)
        steep = np.abs(np.einsum("ij,ij->i", normals, dirs)) > np.cos(np.radians(GRAZING_DEG))
        seen |= inside & visible & steep
    return seen


def _poisson_trimmed(points, scanners):
    return _poisson(points, POISSON_DEPTH, TRIM, scanners)


def run_bench(shapes=SHAPES, noises=NOISES, n_points=40000, timeout=300.0, out=sys.stdout,
              pictures=None):
    """Run the benchmark and print its table; returns the row dicts (one per shape, noise
    and method; ``error`` in place of the measures when a method failed)."""
    from splineviz.pointcloud.quality import area_samples, surface_agreement

    rows = []
    if pictures is not None:
        Path(pictures).mkdir(parents=True, exist_ok=True)
    for shape in shapes:
        true_v, true_f = fine_truth(*cad_shape(shape), TRUTH_EDGE * _diag(cad_shape(shape)[0]))
        diag = _diag(true_v)
        t_pts, t_tri = area_samples(true_v, true_f, SAMPLES, seed=1)
        seen = seen_samples(true_v, true_f, t_pts, t_tri)
        for noise in noises:
            pts, eyes = range_scans(true_v, true_f, n_points, noise)
            results = {"ours": run_peer(_ours, (pts,), timeout, _load_ours),
                       f"poisson{POISSON_DEPTH}": run_peer(_poisson_trimmed, (pts, eyes),
                                                           timeout)}
            for method, result in results.items():
                row = {"shape": shape, "noise": noise, "method": method, "points": len(pts)}
                if isinstance(result, str):
                    row["error"] = result
                else:
                    v, f, secs, peak = result
                    m = surface_agreement(v, f, true_v, true_f, FSCORE_AT * diag,
                                          (t_pts[seen], t_tri[seen]), SAMPLES)
                    row.update(m, vertices=len(v), faces=len(f), time_s=secs, peak_rss=peak,
                               chamfer_pct=100 * m["chamfer"] / diag,
                               hausdorff_pct=100 * m["hausdorff"] / diag)
                    if pictures is not None:
                        np.savez(Path(pictures) / f"{shape}-{noise}-{method}.npz", vertices=v,
                                 faces=f, points=pts)
                rows.append(row)
                print(f"  {shape} noise {noise} {method}: done", file=sys.stderr)
    print_table(rows, out)
    return rows


def targets_held(ours: dict, peer: dict) -> list[str]:
    """The measures of :data:`TARGETS` where ``ours`` is at least as good as ``peer``."""
    return [key for key, larger in TARGETS
            if (ours[key] >= peer[key] if larger else ours[key] <= peer[key])]


def print_table(rows, out=sys.stdout):
    """Markdown table, Poisson's row of the same shape and noise as the anchor."""
    anchor = {(r["shape"], r["noise"]): r for r in rows
              if r["method"].startswith("poisson") and "error" not in r}
    head = ("| shape | noise % | method | points | V | Chamfer % | F-score @1 % | normal cons. "
            "| Hausdorff % | time s | peak RSS GiB | CD / P | H / P | t / P | targets held |")
    print(head, file=out)
    print("|" + "---|" * (head.count("|") - 1), file=out)
    names = {"chamfer": "CD", "fscore": "F", "normal_consistency": "NC", "hausdorff": "H",
             "time_s": "t"}
    for r in rows:
        lead = f"| {r['shape']} | {100 * r['noise']:.2f} | {r['method']} | {r['points']} |"
        if "error" in r:
            print(f"{lead} {r['error']} |" + " |" * 10, file=out)
            continue
        a = anchor.get((r["shape"], r["noise"]))
        if a is not None and a is not r:
            held = targets_held(r, a)
            verdict = " ".join(names[k] if k in held else f"not {names[k]}"
                               for k, _ in TARGETS)
            ratios = (f"{r['chamfer'] / a['chamfer']:.2f} | {r['hausdorff'] / a['hausdorff']:.2f}"
                      f" | {r['time_s'] / a['time_s']:.2f}")
        else:
            verdict, ratios = "", " | | "
        print(f"{lead} {r['vertices']} | {r['chamfer_pct']:.4f} | {r['fscore']:.4f} | "
              f"{r['normal_consistency']:.4f} | {r['hausdorff_pct']:.3f} | {r['time_s']:.2f} | "
              f"{r['peak_rss'] / 2**30:.2f} | {ratios} | {verdict} |", file=out)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--points", type=int, default=40000)
    p.add_argument("--shapes", default=",".join(SHAPES))
    p.add_argument("--noises", default=",".join(str(n) for n in NOISES))
    p.add_argument("--timeout", type=float, default=300.0)
    p.add_argument("--pictures", default=None,
                   help="folder for each mesh and cloud as .npz (vertices, faces, points)")
    args = p.parse_args(argv)
    run_bench(tuple(s for s in args.shapes.split(",") if s),
              tuple(float(n) for n in args.noises.split(",") if n), args.points, args.timeout,
              pictures=args.pictures)
    return 0


if __name__ == "__main__":
    sys.exit(main())
