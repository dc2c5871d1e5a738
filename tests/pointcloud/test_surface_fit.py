"""Least-squares vertex heights (surface_fit): the mesh approximates the surface instead of
interpolating it, and keeps its border."""

import numpy as np
import pc_surfaces as S

import splineviz as sv
from splineviz.pointcloud.projection import Projector
from splineviz.pointcloud.quality import edge_face_counts, surface_samples
from splineviz.pointcloud.surface_fit import BORDER_RINGS, fit_heights


def _arrays(mesh):
    return np.asarray(mesh.points), np.asarray(mesh.faces).reshape(-1, 4)[:, 1:]


def _signed_sphere(x):
    return np.linalg.norm(x, axis=1) - 1.0


def test_sphere_mesh_has_no_mean_sag():
    pts = S.sphere(5000, seed=1)
    pr = Projector(pts)
    # the front alone: every vertex on the sphere, every triangle inside it
    v, f = _arrays(sv.remesh(pts, edge_length=0.15, projector=pr, optimize_mesh=False))
    assert np.abs(_signed_sphere(v)).max() < 1e-6
    before = _signed_sphere(surface_samples(v, f))
    fitted = fit_heights(v, f, pr)
    after = _signed_sphere(surface_samples(fitted, f))
    # the chords sag by L^2 / 8 = 2.8e-3 at the edge midpoints, 3.8e-3 at the centroids
    assert before.mean() < -1.5e-3
    assert abs(after.mean()) < 0.1 * abs(before.mean())
    assert np.abs(after).max() < 0.8 * np.abs(before).max()
    # the vertices move out, by about the sag of their edges (the longest, 0.2: 5e-3)
    assert np.all(_signed_sphere(fitted) > 0.5e-3)
    assert np.all(_signed_sphere(fitted) < 7.5e-3)


def test_remesh_fits_the_vertices():
    pts = S.sphere(5000, seed=2)
    v, f = _arrays(sv.remesh(pts, edge_length=0.15))
    dev = _signed_sphere(surface_samples(v, f))
    assert abs(dev.mean()) < 3e-4
    assert np.all(_signed_sphere(v) > 0)


def test_border_and_its_ring_stay():
    pts = S.paraboloid(4000, seed=3)
    pr = Projector(pts)
    v, f = _arrays(sv.remesh(pts, edge_length=0.1, projector=pr, optimize_mesh=False))
    fitted = fit_heights(v, f, pr)
    edges, counts = edge_face_counts(f)
    keep = np.zeros(len(v), dtype=bool)
    keep[edges[counts == 1].ravel()] = True
    for _ in range(BORDER_RINGS):
        keep[edges[keep[edges].any(axis=1)].ravel()] = True
    assert keep.sum() > 50 and (~keep).sum() > 50
    assert np.array_equal(fitted[keep], v[keep])
    moved = np.linalg.norm(fitted - v, axis=1)
    # the paraboloid bends everywhere (curvature 0.4-1): every inner vertex moves
    assert np.all(moved[~keep] > 0)
    before = np.abs(S.paraboloid_distance(surface_samples(v, f)))
    after = np.abs(S.paraboloid_distance(surface_samples(fitted, f)))
    assert after.mean() < 0.7 * before.mean()


def test_mass_solve_by_conjugate_gradients_is_the_direct_solve():
    """The mass system solved by preconditioned CG (a sparse LU took 500 MB on the mesh of a
    2-million-point cloud) gives the direct solution, also with a zero-area triangle."""
    import pyvista as pv
    from scipy import sparse
    from scipy.sparse.linalg import spsolve

    from splineviz.pointcloud.surface_fit import solve_mass

    sphere = pv.Sphere(theta_resolution=40, phi_resolution=40)
    v, f = np.asarray(sphere.points, dtype=float), sphere.faces.reshape(-1, 4)[:, 1:]
    f = np.vstack([f, [[f[0, 0], f[0, 0], f[0, 1]]]])  # a degenerate face
    area = 0.5 * np.linalg.norm(np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]),
                                axis=1)
    pair = (np.ones((3, 3)) + np.eye(3)) / 12.0
    n = len(v)
    mass = sparse.csr_matrix(((area[:, None, None] * pair).ravel(),
                              (np.repeat(f, 3, axis=1).ravel(), np.tile(f, (1, 3)).ravel())),
                             shape=(n, n))
    mass = mass + sparse.identity(n, format="csr") * 1e-12 * mass.diagonal().max()
    rhs = np.random.default_rng(0).normal(size=n) * area.mean()
    want = spsolve(mass.tocsc(), rhs)
    assert np.abs(solve_mass(mass, rhs) - want).max() < 1e-9 * np.abs(want).max()
