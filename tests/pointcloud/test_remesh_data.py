"""Issue 7 acceptance on the real scans: manifold, radius ratio >= 0.90, >= 70 % valence 6,
no non-manifold edges, every input point within 1 % of the diagonal from the mesh, the
two-sided Hausdorff distance, time.  The kitten runs by default; bunny and lucy (35k / 50k
points, one to two minutes each here) are ``slow``.

The two-sided Hausdorff distance also measures how far the mesh gets from the points, which
no mesh of the surface can bring below the largest gap between samples: the kitten's samples
are 1.5 % of its diagonal apart, and the mesh Lucy's points come from is itself 2.15 % of the
diagonal away from them in places (its sparsely sampled base).
"""

import json
import time

import numpy as np
import pytest

import splineviz as sv
from splineviz.cli import main as cli_main


def _check(cloud, seconds_limit, hausdorff_limit, **kwargs):
    pts = cloud.points
    diag = float(np.linalg.norm(np.ptp(pts, axis=0)))
    t = time.perf_counter()
    mesh = sv.remesh(cloud, **kwargs)
    elapsed = time.perf_counter() - t
    q = sv.mesh_quality(mesh, reference=cloud)
    assert q["non_manifold_edges"] == 0
    assert q["radius_ratio_mean"] >= 0.90
    assert q["valence6_fraction"] >= 0.70
    assert q["hausdorff_points_to_mesh"] <= 0.01 * diag
    assert q["hausdorff"] <= hausdorff_limit * diag
    assert elapsed < seconds_limit
    return q


def test_kitten(shared_data):
    # measured: points to mesh 0.68 %, two-sided 0.960 % (issue 13: no worse than the 1.005 %
    # of the Cocone-connected projector).  The largest gap between samples on the surface is
    # 0.986 %; before the least-squares vertex heights a triangle of 2.7 spacings in a bend
    # the guidance's shortest edge cannot follow sat 0.29 % off the surface over a gap of
    # 0.88 %: 1.077 %
    cloud = sv.read_points(shared_data / "points" / "kitten.xyz")
    q = _check(cloud, 60, hausdorff_limit=0.01005)
    assert q["boundary_edges"] == 0  # the kitten is closed


@pytest.mark.slow
def test_bunny(shared_data):
    # measured: points to mesh 0.56 %, two-sided 1.10 % (triangles at the ragged rims of the
    # scan's bottom holes reach past the last samples)
    _check(sv.read_points(shared_data / "points" / "bunny.ply"), 120, hausdorff_limit=0.012)


@pytest.mark.slow
def test_lucy(shared_data):
    # measured: points to mesh 0.89 %, two-sided 2.02 %, 60-90 s on this 2-core machine.
    # Lucy's samples are the vertices of a decimated mesh, free of noise, so they are meshed
    # with the interpolating projection (smoothing=1.0); the noise-aware default read her
    # under-resolved folds as noise and reached 1.26 % points to mesh, 1.01 % since the noise
    # is capped at twice the cloud's noise floor (issue 13)
    path = shared_data / "points" / "lucy.ply"
    source = sv.read_mesh(path)  # the decimated mesh whose vertices are the cloud
    own = sv.mesh_quality(source, reference=np.asarray(source.points))["hausdorff"]
    diag = float(np.linalg.norm(np.ptp(np.asarray(source.points), axis=0)))
    _check(sv.read_points(path), 120, hausdorff_limit=own / diag, smoothing=1.0)


def test_cli_remesh_writes_mesh_and_report(tmp_path, capsys):
    rng = np.random.default_rng(0)
    v = rng.normal(size=(3000, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    src = tmp_path / "sphere.xyz"
    np.savetxt(src, v)
    out, report = tmp_path / "mesh.ply", tmp_path / "report.json"
    code = cli_main(["remesh", str(src), "-o", str(out), "--edge-length", "0.15",
                     "--report", str(report)])
    assert code == 0
    mesh = sv.read_mesh(out)
    data = json.loads(report.read_text())
    assert data["quality"]["n_faces"] == mesh.n_cells > 500
    assert data["quality"]["boundary_edges"] == 0
    assert data["parameters"]["edge_length"] == 0.15
    assert set(data["timings"]) >= {"projector_s", "front_s", "total_s"}
    assert "vertices" in capsys.readouterr().out


def test_cli_remesh_user_errors(tmp_path, capsys):
    assert cli_main(["remesh", str(tmp_path / "missing.ply"), "-o", str(tmp_path / "m.ply")]) == 2
    err = capsys.readouterr().err
    assert "error" in err and "Traceback" not in err
    # a malformed argument is one line and exit code 2 too (no usage text, no SystemExit)
    assert cli_main(["remesh", "x.ply", "-o", "m.ply", "--rho", "0"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--rho" in err


@pytest.mark.slow
def test_noisy_bunny_points_to_mesh_p99_against_the_anchor(shared_data):
    # issue 13: the bunny with Gaussian noise of 0.2 % of the diagonal, default parameters;
    # the 99th-percentile distance of the points to our mesh at most that to Poisson depth 8
    # + isotropic remeshing at our vertex count (measured 0.514 % against 0.532 %; 0.550 %
    # with the mesh's corners on the surface)
    pytest.importorskip("open3d")
    pytest.importorskip("pymeshlab")
    from splineviz.bench.remesh import _poisson_remeshed, load_cloud

    pts = load_cloud("bunny-noisy", shared_data / "points")
    ours = sv.mesh_quality(sv.remesh(pts), reference=pts)
    anchor = sv.mesh_quality(_poisson_remeshed(pts, ours["n_vertices"]), reference=pts)
    assert ours["points_to_mesh_p99"] <= anchor["points_to_mesh_p99"]
    assert ours["non_manifold_edges"] == 0


def test_bench_dense_clouds_are_noisy_samples_of_the_shared_mesh(shared_data):
    """``splineviz bench remesh --clouds lucy-2m,bunny-500k``: the names give the counts, the
    clean samples lie on the mesh's triangles and the noise is DENSE_NOISE of the diagonal;
    the table shows each method's peak RSS and takes poisson10+remesh as the anchor."""
    import io

    from splineviz.bench.remesh import DENSE_NOISE, dense_count, dense_samples, print_table
    from splineviz.pointcloud.quality import distance_to_mesh

    assert dense_count("lucy-2m") == 2_000_000 and dense_count("bunny-500k") == 500_000
    assert dense_count("bunny-1.5m") == 1_500_000 and dense_count("lucy-3000") == 3000
    assert dense_count("bunny-noisy") is None and dense_count("lucy") is None
    clean, noisy = dense_samples("bunny-20k", shared_data / "points")
    assert clean.shape == noisy.shape == (20000, 3)
    import pyvista as pv

    mesh = pv.read(shared_data / "points" / "bunny.ply").triangulate()
    diag = float(np.linalg.norm(np.ptp(clean, axis=0)))
    on = distance_to_mesh(clean, np.asarray(mesh.points, dtype=float),
                          mesh.faces.reshape(-1, 4)[:, 1:])
    assert on.max() < 1e-6 * diag
    assert abs(np.std(noisy - clean) / (DENSE_NOISE * diag) - 1) < 0.05
    row = {"n_vertices": 10, "n_faces": 16, "radius_ratio_mean": 0.9, "radius_ratio_min": 0.5,
           "valence6_fraction": 0.7, "hausdorff_pct": 1.0, "points_to_mesh_pct": 1.0,
           "points_to_mesh_p99_pct": 0.5, "rms_pct": 0.1, "boundary_edges": 0,
           "non_manifold_edges": 0, "cloud": "bunny-20k"}
    rows = [{**row, "method": "ours", "hausdorff": 1.0, "time_s": 50.0, "peak_rss": 2**31},
            {**row, "method": "poisson10+remesh", "hausdorff": 2.0, "time_s": 100.0,
             "peak_rss": 2**30}]
    out = io.StringIO()
    print_table(rows, out)
    lines = out.getvalue().splitlines()
    assert "peak RSS GiB" in lines[0]
    assert lines[2].endswith("| 50.0 | 2.00 | 0.50 | 0.50 |")
