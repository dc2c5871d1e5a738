"""``splineviz bench remesh``: our advancing-front mesher against the meshers users pick today.

For each cloud (bunny, kitten, Lucy, the bunny with Gaussian noise of 0.2 % of the
bounding-box diagonal, and an open scan: the bunny cut by a plane, so it has a long border)
the table lists, for every method, vertex/face counts, mean and minimum radius ratio
(2 r_in / r_circ), fraction of valence-6 interior vertices, the two-sided Hausdorff distance,
the farthest input point from the mesh and the RMS distance of the points (in % of the
diagonal), border and non-manifold edges, and wall time.  Methods:

* ``ours``: ``sv.remesh`` with default parameters (the noise-aware projection chooses the
  width of the local fits, also on the noisy cloud);
* ``ours-s2.5``: on the noisy cloud only, the thesis' user-scaled Gaussian width
  ``smoothing=2.5`` (the tuned setting before the noise-aware projection);
* ``ours-mls2``: ablation, the same pipeline with an MLS-style fixed degree-2 projection;
* ``poisson8``: Open3D screened Poisson, depth 8, normals estimated and oriented by Open3D;
* ``bpa``: Open3D ball pivoting with radii 1, 2, 4 times the mean neighbour distance;
* ``poisson+remesh``: the Poisson mesh remeshed by pymeshlab's
  ``meshing_isotropic_explicit_remeshing`` to our vertex count (the strongest peer).

Peers run in a child process under a time limit (Poisson can hang).  The last columns give the
Hausdorff and wall-time ratios against ``poisson+remesh`` measured in the same run.  Distances to
the noisy points reward a mesh that follows the noise, so a second table measures the meshes of
the noisy cloud against the noise-free scan it was made from.

Before the meshes, a projection table: a unit sphere of 20,000 points with radial Gaussian
noise (sigma 0, 0.002, 0.005) projected onto itself by ``sv.Projector(cloud).project`` (time
includes building the projector), with the median, 99th percentile and maximum of ``|r - 1|``,
and the 99th percentile for 2,000 query points at radii 0.9-1.1 ("far"); the peer is CGAL's
``jet_smooth_point_set`` (k = 48, degree 2, Cazals-Pouget osculating jets) when the ``cgal``
package (a ``[bench]`` extra) is installed, timed on the call alone.

Run: ``splineviz bench remesh [--data-dir DIR] [--timeout S] [--clouds a,b]`` (or ``python -m
splineviz.bench.remesh``).
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import re
import sys
import time
from pathlib import Path

import numpy as np

from splineviz.bench.memory import peak_rss

CLOUDS = ("bunny", "kitten", "lucy", "bunny-noisy", "bunny-open")
NOISE = 0.002  # Gaussian sigma in units of the bounding-box diagonal
#: dense clouds ``<mesh>-<count>`` (``lucy-2m``, ``bunny-500k``): the shared mesh's triangles
#: sampled area-uniformly with that many points, moved by Gaussian noise of this fraction of
#: the diagonal
DENSE_NOISE = 0.001
#: the dense clouds' peers: Poisson at this depth, remeshed
DENSE_DEPTH = 10
#: the dense rows' time limit per method, at least (s)
DENSE_TIMEOUT = 3600.0
_COUNT = re.compile(r"^(\d+(?:\.\d+)?)([km]?)$")


def dense_count(name: str) -> int | None:
    """The point count of a dense cloud's name (``lucy-2m`` -> 2,000,000), else None."""
    base, _, tail = name.rpartition("-")
    match = _COUNT.match(tail.lower())
    if not base or match is None:
        return None
    return int(float(match[1]) * {"": 1, "k": 1e3, "m": 1e6}[match[2]])


def dense_samples(name: str, data_dir: Path, seed: int = 0):
    """A dense cloud (see ``DENSE_NOISE``): ``(clean (N, 3), noisy (N, 3))``, the same
    samples on the mesh's triangles without and with the noise."""
    import pyvista as pv

    base, n = name.rpartition("-")[0], dense_count(name)
    mesh = pv.read(data_dir / f"{base}.ply").triangulate()
    v = np.asarray(mesh.points, dtype=np.float64)
    f = np.asarray(mesh.faces).reshape(-1, 4)[:, 1:]
    area = np.linalg.norm(np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]), axis=1)
    rng = np.random.default_rng(seed)
    tri = rng.choice(len(f), n, p=area / area.sum())
    u, w = rng.random(n), rng.random(n)
    flip = u + w > 1  # folded back into the triangle: uniform over its area
    u[flip], w[flip] = 1 - u[flip], 1 - w[flip]
    clean = (v[f[tri, 0]] * (1 - u - w)[:, None] + v[f[tri, 1]] * u[:, None]
             + v[f[tri, 2]] * w[:, None])
    diag = float(np.linalg.norm(np.ptp(clean, axis=0)))
    return clean, clean + rng.normal(scale=DENSE_NOISE * diag, size=clean.shape)


def load_cloud(name: str, data_dir: Path) -> np.ndarray:
    """``(N, 3)`` points of a named benchmark cloud."""
    from splineviz.io.points import read_points

    if dense_count(name):
        return dense_samples(name, data_dir)[1]
    base = name.split("-")[0]
    file = {"bunny": "bunny.ply", "kitten": "kitten.xyz", "lucy": "lucy.ply"}[base]
    pts = read_points(data_dir / file).points
    if name.endswith("-noisy"):
        diag = np.linalg.norm(np.ptp(pts, axis=0))
        pts = pts + np.random.default_rng(0).normal(scale=NOISE * diag, size=pts.shape)
    if name.endswith("-open"):
        # an open scan: keep the part of the bunny in front of a plane through its middle
        centre = pts.mean(axis=0)
        pts = pts[(pts - centre) @ np.array([0.3, 0.2, 1.0]) > 0]
    return pts


def _o3d_cloud(points, scanners=None):
    """An Open3D cloud with estimated normals, oriented consistently over the tangent-plane
    graph or, given each point's scanner position ``scanners (N, 3)``, towards its scanner
    (as a range scanner knows them)."""
    import open3d as o3d

    pcd = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))
    pcd.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(knn=30))
    if scanners is None:
        pcd.orient_normals_consistent_tangent_plane(30)
    else:
        n = np.asarray(pcd.normals)
        away = np.einsum("ij,ij->i", n, np.asarray(scanners) - np.asarray(points)) < 0
        n[away] *= -1
        pcd.normals = o3d.utility.Vector3dVector(n)
    return pcd


def _poisson(points, depth=8, trim=0.0, scanners=None):
    """Open3D screened Poisson ``(V, F)``; ``trim``: the fraction of lowest-density vertices
    dropped (with their triangles), as users cut Poisson's extrapolated sheets;
    ``scanners``: see :func:`_o3d_cloud`."""
    import open3d as o3d

    pcd = _o3d_cloud(points, scanners)
    mesh, density = o3d.geometry.TriangleMesh.create_from_point_cloud_poisson(pcd, depth=depth)
    if trim > 0:
        density = np.asarray(density)
        mesh.remove_vertices_by_mask(density < np.quantile(density, trim))
    return np.asarray(mesh.vertices), np.asarray(mesh.triangles)


def _bpa(points):
    import open3d as o3d
    from scipy.spatial import cKDTree

    pcd = _o3d_cloud(points)
    d, _ = cKDTree(points).query(points, k=2)
    r = float(np.mean(d[:, 1]))
    radii = o3d.utility.DoubleVector([r, 2 * r, 4 * r])
    mesh = o3d.geometry.TriangleMesh.create_from_point_cloud_ball_pivoting(pcd, radii)
    return np.asarray(mesh.vertices), np.asarray(mesh.triangles)


def _poisson_remeshed(points, n_vertices, depth=8):
    import pymeshlab

    v, f = _poisson(points, depth)
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(v, f))
    area = 0.5 * np.linalg.norm(np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]),
                                axis=1).sum()
    # a regular triangulation has about 2 triangles of area sqrt(3)/4 L^2 per vertex
    length = float(np.sqrt(area / (n_vertices * np.sqrt(3) / 2)))
    ms.meshing_isotropic_explicit_remeshing(iterations=10, targetlen=pymeshlab.PureValue(length))
    m = ms.current_mesh()
    return m.vertex_matrix(), m.face_matrix()


def _ours(points):
    """``sv.remesh`` with default parameters as ``(V, F)`` (the dense rows run it in a child
    process, as the peers, for its own peak memory)."""
    from splineviz.pointcloud.remesh import remesh

    mesh = remesh(points)
    return np.asarray(mesh.points), np.asarray(mesh.faces).reshape(-1, 4)[:, 1:]


def _load_peers():
    # the peers' libraries are loaded before the clock starts, as ours are (open3d's
    # import alone takes 0.5-1 s, most of a small cloud's anchor time)
    import open3d  # noqa: F401
    import pymeshlab  # noqa: F401


def _load_ours():
    import pyvista  # noqa: F401  (remesh's mesh type)

    from splineviz.pointcloud import cocone, front_kernels, local_fits, relaxation

    for module in (cocone, local_fits, front_kernels, relaxation):
        module.compile_kernels()  # numba's cached kernels are loaded before the clock



def _child(queue, fn, args, preload=_load_peers):
    try:
        preload()
        t = time.perf_counter()
        v, f = fn(*args)
        secs = time.perf_counter() - t
        queue.put(("ok", np.asarray(v, float), np.asarray(f, np.int64), secs, peak_rss()))
    except Exception as exc:  # reported in the table, the benchmark goes on
        queue.put(("error", f"{type(exc).__name__}: {exc}", None, None, None))


def run_peer(fn, args, timeout, preload=_load_peers):
    """Run ``fn(*args) -> (V, F)`` in a child process after ``preload()``; ``(V, F, seconds,
    peak RSS bytes of the child)`` or a message.

    The child is spawned, not forked: the peers run OpenMP, which hangs in a child forked
    from a process whose own OpenMP threads (numba's) have run."""
    ctx = mp.get_context("spawn")
    queue = ctx.Queue()
    proc = ctx.Process(target=_child, args=(queue, fn, args, preload))
    proc.start()
    try:
        status, a, b, secs, peak = queue.get(timeout=timeout)
    except Exception:
        proc.kill()
        proc.join()
        return f"timed out after {timeout:.0f} s"
    proc.join()
    return (a, b, secs, peak) if status == "ok" else a


SPHERE_POINTS = 20000
SPHERE_SIGMAS = (0.0, 0.002, 0.005)
#: neighbours of CGAL's jet fitting in the projection table (its documentation's example: 24)
CGAL_NEIGHBOURS = 48


def noisy_sphere(n: int, sigma: float, seed: int = 0) -> np.ndarray:
    """``(n, 3)`` points on the unit sphere moved radially by Gaussian noise ``sigma``."""
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(n, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    return v * (1.0 + sigma * rng.normal(size=(n, 1)))


def _cgal_jet(points, k=CGAL_NEIGHBOURS):
    """CGAL jet smoothing of ``(N, 3)`` points: ``(smoothed (N, 3), seconds of the call)``."""
    from CGAL.CGAL_Kernel import Point_3
    from CGAL.CGAL_Point_set_3 import Point_set_3
    from CGAL.CGAL_Point_set_processing_3 import jet_smooth_point_set

    ps = Point_set_3()
    for p in points:
        ps.insert(Point_3(*(float(c) for c in p)))
    t = time.perf_counter()
    jet_smooth_point_set(ps, k)
    secs = time.perf_counter() - t
    out = np.array([[ps.point(i).x(), ps.point(i).y(), ps.point(i).z()]
                    for i in range(ps.size())])
    return out, secs


def _radial(x):
    e = np.abs(np.linalg.norm(x, axis=1) - 1.0)
    return float(np.median(e)), float(np.percentile(e, 99)), float(e.max())


def projection_table(n=SPHERE_POINTS, sigmas=SPHERE_SIGMAS, out=sys.stdout):
    """Noisy-sphere projection rows (see the module docstring); printed, and returned."""
    from splineviz.pointcloud.projection import Projector

    try:
        import CGAL.CGAL_Point_set_processing_3  # noqa: F401

        have_cgal = True
    except ImportError:
        have_cgal = False
    Projector(noisy_sphere(500, 0.0, 9))  # loads the compiled kernels before timing
    rows = []
    for sigma in sigmas:
        pts = noisy_sphere(n, sigma)
        far = noisy_sphere(2000, 0.0, 5) * np.random.default_rng(6).uniform(0.9, 1.1, (2000, 1))
        rows.append({"sigma": sigma, "method": "input", "time_s": float("nan"),
                     "stats": _radial(pts), "far_p99": float("nan")})
        t = time.perf_counter()
        pr = Projector(pts)
        ours = pr.project(pts)
        secs = time.perf_counter() - t
        rows.append({"sigma": sigma, "method": "ours", "time_s": secs, "stats": _radial(ours),
                     "far_p99": _radial(pr.project(far))[1]})
        if have_cgal:
            smooth, csecs = _cgal_jet(pts)
            rows.append({"sigma": sigma, "method": f"cgal-jet k={CGAL_NEIGHBOURS}",
                         "time_s": csecs, "stats": _radial(smooth), "far_p99": float("nan")})
        print(f"  sphere sigma {sigma}: done", file=sys.stderr)
    peer = {r["sigma"]: r["time_s"] for r in rows if r["method"].startswith("cgal")}
    print("| sigma | method | time s | time / CGAL | median abs(r-1) | p99 | max | far p99 |",
          file=out)
    print("|---|---|---|---|---|---|---|---|", file=out)
    for r in rows:
        ratio = r["time_s"] / peer[r["sigma"]] if r["sigma"] in peer else float("nan")
        med, p99, mx = r["stats"]
        print(f"| {r['sigma']} | {r['method']} | {r['time_s']:.2f} | {ratio:.2f} | {med:.2e} | "
              f"{p99:.2e} | {mx:.2e} | {r['far_p99']:.2e} |", file=out)
    if not have_cgal:
        print("(CGAL not installed: pip install cgal, the [bench] extra)", file=out)
    return rows


def _row(cloud, method, points, diag, result):
    from splineviz.pointcloud.quality import mesh_quality

    if isinstance(result, str):
        return {"cloud": cloud, "method": method, "error": result}
    v, f, secs = result[:3]
    q = mesh_quality((v, f), reference=points)
    q.update(cloud=cloud, method=method, time_s=secs,
             peak_rss=result[3] if len(result) > 3 else float("nan"),
             hausdorff_pct=100 * q["hausdorff"] / diag,
             points_to_mesh_pct=100 * q["hausdorff_points_to_mesh"] / diag,
             points_to_mesh_p99_pct=100 * q["points_to_mesh_p99"] / diag,
             rms_pct=100 * q["rms_distance"] / diag)
    return q


def run_bench(data_dir=None, clouds=CLOUDS, timeout=180.0, peers=True, out=sys.stdout,
              projection=True):
    """Run the benchmark and print the tables; returns the list of mesh row dicts."""
    from splineviz.pointcloud import front_kernels, local_fits, relaxation
    from splineviz.pointcloud.remesh import RemeshReport, remesh

    for module in (local_fits, front_kernels, relaxation):
        module.compile_kernels()  # numba's cached kernels are loaded before any timing
    import pyvista  # noqa: F401  (remesh's mesh type: loaded before the clock, as the peers')
    if projection:
        projection_table(out=out)
        print(file=out)

    # default: the shared test clouds beside the repository (run from its root)
    data_dir = Path(data_dir) if data_dir else Path.cwd() / ".." / "shared" / "data" / "points"
    rows, truth_rows = [], []
    for cloud in clouds:
        dense = dense_count(cloud) is not None
        if dense:
            truth, pts = dense_samples(cloud, data_dir)
        else:
            pts = load_cloud(cloud, data_dir)
            # the noisy cloud's meshes are also measured against the noise-free scan
            truth = load_cloud(cloud.removesuffix("-noisy"), data_dir) \
                if cloud.endswith("-noisy") else None
        diag = float(np.linalg.norm(np.ptp(pts, axis=0)))

        def measured(method, result, cloud=cloud, pts=pts, diag=diag, truth=truth):
            rows.append(_row(cloud, method, pts, diag, result))
            if truth is not None:
                truth_rows.append(_row(cloud, method, truth, diag, result))

        if dense:
            # ours and the peer each in a child process, for their own peak memory
            limit = max(timeout, DENSE_TIMEOUT)
            result = run_peer(_ours, (pts,), limit, _load_ours)
            measured("ours", result)
            print(f"  {cloud} ours: done", file=sys.stderr)
            if peers and not isinstance(result, str):
                measured(f"poisson{DENSE_DEPTH}+remesh",
                         run_peer(_poisson_remeshed, (pts, len(result[0]), DENSE_DEPTH), limit))
                print(f"  {cloud} poisson{DENSE_DEPTH}+remesh: done", file=sys.stderr)
            continue
        ours = {}
        variants = [("ours", {}), ("ours-mls2", {"fixed_degree": 2})]
        if cloud.endswith("-noisy"):
            variants.append(("ours-s2.5", {"smoothing": 2.5}))
        for method, kwargs in variants:
            rep = RemeshReport()
            t = time.perf_counter()
            mesh = remesh(pts, report=rep, **kwargs)
            secs = time.perf_counter() - t
            v = np.asarray(mesh.points)
            f = np.asarray(mesh.faces).reshape(-1, 4)[:, 1:]
            ours[method] = (v, f, secs)
            measured(method, (v, f, secs))
            print(f"  {cloud} {method}: {len(v)} vertices in {secs:.1f} s", file=sys.stderr)
        if peers:
            n_ours = len(ours["ours"][0])
            for method, fn, args in (("poisson8", _poisson, (pts,)), ("bpa", _bpa, (pts,)),
                                     ("poisson+remesh", _poisson_remeshed, (pts, n_ours))):
                measured(method, run_peer(fn, args, timeout))
                print(f"  {cloud} {method}: done", file=sys.stderr)
    print_table(rows, out)
    if truth_rows:
        print("\nThe noisy clouds' meshes against the noise-free scan (dense clouds: the same "
              "samples without the noise):", file=out)
        print_table(truth_rows, out)
    return rows


def print_table(rows, out=sys.stdout):
    """Markdown table; last columns: Hausdorff and time over those of poisson+remesh on that
    cloud."""
    anchor = {r["cloud"]: r for r in rows
              if r["method"].startswith("poisson") and r["method"].endswith("+remesh")
              and "error" not in r}
    head = ("| cloud | method | V | F | r/R mean | r/R min | val 6 | Hausdorff % "
            "| points->mesh % | points->mesh p99 % | RMS % "
            "| border e | non-mf e | time s | peak RSS GiB | H / H(anchor) | t / t(anchor) |")
    print(head, file=out)
    print("|" + "---|" * (head.count("|") - 1), file=out)
    for r in rows:
        if "error" in r:
            print(f"| {r['cloud']} | {r['method']} | {r['error']} |" + " |" * 15, file=out)
            continue
        a = anchor.get(r["cloud"])
        ratio = r["hausdorff"] / a["hausdorff"] if a else float("nan")
        t_ratio = r["time_s"] / a["time_s"] if a else float("nan")
        print(f"| {r['cloud']} | {r['method']} | {r['n_vertices']} | {r['n_faces']} | "
              f"{r['radius_ratio_mean']:.3f} | {r['radius_ratio_min']:.3f} | "
              f"{100 * r['valence6_fraction']:.1f} % | {r['hausdorff_pct']:.3f} | "
              f"{r['points_to_mesh_pct']:.3f} | {r['points_to_mesh_p99_pct']:.3f} | "
              f"{r['rms_pct']:.4f} | {r['boundary_edges']} | {r['non_manifold_edges']} | "
              f"{r['time_s']:.1f} | {r['peak_rss'] / 2**30:.2f} | {ratio:.2f} | {t_ratio:.2f} |",
              file=out)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--data-dir", default=None)
    p.add_argument("--timeout", type=float, default=180.0)
    p.add_argument("--clouds", default=",".join(CLOUDS))
    p.add_argument("--no-peers", action="store_true")
    p.add_argument("--no-projection", action="store_true", help="skip the noisy-sphere table")
    args = p.parse_args(argv)
    clouds = tuple(c for c in args.clouds.split(",") if c)
    run_bench(args.data_dir, clouds, args.timeout, not args.no_peers,
              projection=not args.no_projection)
    return 0


if __name__ == "__main__":
    sys.exit(main())
