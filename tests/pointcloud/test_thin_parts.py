"""Issue 13, Lucy's 99th-percentile points-to-mesh distance: the rims of thin parts survive
the relaxation, surface detail the samples resolve is not read as noise, and the long narrow
loops the fronts leave at the rims of thin folds are filled (loops off the samples are not)."""

import numpy as np
from scipy.spatial import cKDTree

import splineviz as sv
from splineviz.pointcloud.quality import distance_to_mesh


def _spacing(pts):
    """Median over the points of the mean distance to their 6 nearest neighbours."""
    return float(np.median(cKDTree(pts).query(pts, k=7)[0][:, 1:].mean(axis=1)))


def _lens(n=1500, thickness=0.15):
    """``(n, 3)`` Fibonacci points on the ellipsoid with semi-axes (1, 1, thickness): a disc
    whose rim bends with radius ``thickness**2`` (a third of the spacing), the sharp edge of a
    thin part."""
    i = np.arange(n) + 0.5
    phi = np.arccos(1 - 2 * i / n)
    theta = np.pi * (1 + 5**0.5) * i
    return np.stack([np.cos(theta) * np.sin(phi), np.sin(theta) * np.sin(phi),
                     thickness * np.cos(phi)], axis=1)


def test_relaxation_keeps_the_rim_of_a_thin_part():
    # measured, in spacings: the front alone leaves the rim points a median 0.18 from the
    # mesh; relaxed in the samples' tangent planes (at the rim one side's plane) the rim
    # vertices slid inwards, 0.42 (p99 of all points 0.57); in the mesh's own planes 0.28
    # (p99 0.39)
    pts = _lens()
    mesh = sv.remesh(pts)
    v = np.asarray(mesh.points)
    f = np.asarray(mesh.faces).reshape(-1, 4)[:, 1:]
    d = distance_to_mesh(pts, v, f) / _spacing(pts)
    r = np.hypot(pts[:, 0], pts[:, 1])
    rim = r > np.percentile(r, 95)
    assert np.median(d[rim]) < 0.35
    assert np.percentile(d, 99) < 0.48
    assert sv.mesh_quality(mesh)["boundary_edges"] == 0


def _bumpy_sphere(n=4000, amplitude=0.01, frequency=20.0, seed=0):
    """``(n, 3)`` noise-free points on a sphere with bumps of about 5 spacings' wavelength
    everywhere but on a flat (spherical) cap below ``z = -0.6``, and the exact radius
    function of the direction ``(M, 3) -> (M,)``."""
    rng = np.random.default_rng(seed)
    u = rng.normal(size=(n, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)

    def radius(d):
        bumps = np.cos(frequency * d[:, 0]) * np.cos(frequency * d[:, 1]) * \
            np.cos(frequency * d[:, 2])
        return 1.0 + amplitude * (d[:, 2] > -0.6) * bumps

    return u * radius(u)[:, None], radius


def test_surface_detail_is_not_read_as_noise():
    # the residuals of the narrowest fit hold the bias of the bumps, not noise; measured with
    # the cap at twice the median level (before): 71 % of the fits 4.2 spacings wide, the
    # points projected onto themselves 0.150 spacings off at p99; capped at twice the cloud's
    # floor (the flat cap's level): 2 %, 0.082
    pts, radius = _bumpy_sphere()
    proj = sv.Projector(pts)
    assert np.mean(proj.width >= 4.0) < 0.2
    q = proj.project(pts)
    err = np.abs(np.linalg.norm(q, axis=1) - radius(q / np.linalg.norm(q, axis=1)[:, None]))
    assert np.percentile(err, 99) < 0.11 * _spacing(pts)


def _strip_front(lift):
    """An advancing front over 1,500 samples of the square [-2, 2]^2 (spacing ~0.1) holding
    one loop of 50 front edges around a 2.4 x 0.1 strip at height ``lift`` above it."""
    from splineviz.pointcloud.advancing_front import AdvancingFront
    from splineviz.pointcloud.guidance import guidance_field
    from splineviz.pointcloud.projection import Projector

    rng = np.random.default_rng(9)
    pts = np.c_[rng.uniform(-2, 2, (1500, 2)), np.zeros(1500)]
    proj = Projector(pts)
    front = AdvancingFront(proj, guidance_field(proj, edge_length=0.1))
    xs = np.linspace(-1.2, 1.2, 25)
    # counter-clockwise seen from +z: the unmeshed strip lies to the left of every edge
    corners = [(x, -0.05) for x in xs] + [(x, 0.05) for x in xs[::-1]]
    up = np.array([0.0, 0.0, 1.0])
    loop = [front._add_vertex(np.array([x, y, lift]), up) for x, y in corners]
    for a, b in zip(loop, loop[1:] + loop[:1], strict=True):
        front._front_add(a, b)
    return front


def test_long_narrow_loops_on_the_samples_are_filled():
    front = _strip_front(0.0)
    front._fill_holes()
    assert not front.front
    assert len(front.faces) == 50 - 2
    # the same loop half a unit above the samples (five spacings) would get a lid
    front = _strip_front(0.5)
    front._fill_holes()
    assert len(front.front) == 50 and not front.faces
