"""The type-6 splines (thesis §4.4): cubic C^1 and quadratic super spline, issue 3.

Oracle: the JSON mask tables in ../shared/spec/ (independent exact-arithmetic reconstruction).
"""

import json
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

import splineviz as sv
from splineviz.core import bform
from splineviz.core.partitions import type6
from splineviz.core.splines import type6_rules
from splineviz.core.splines.cubic_c1 import CubicC1Spline
from splineviz.core.splines.super_quadratic import SuperQuadraticSpline
from splineviz.core.testfunctions import TEST_FUNCTIONS

SPEC = Path(__file__).resolve().parents[1] / ".." / "shared" / "spec"
ORACLES = {
    "cubic-c1": "type6_cubic_c1_masks.json",
    "super-quadratic": "type6_quadratic_masks.json",
}
CLASSES = {"cubic-c1": CubicC1Spline, "super-quadratic": SuperQuadraticSpline}
MODELS = list(CLASSES)

#: relative jump that counts as continuous (issue 3: < 1e-9)
JUMP_TOL = 1e-9


def _random_spline(model, shape=(7, 7, 7), seed=3):
    # float32 samples: the precision a Volume stores
    data = np.random.default_rng(seed).uniform(0, 1, shape).astype(np.float32).astype(float)
    return CLASSES[model](data), data


# --------------------------------------------------------------------------- oracle


@pytest.mark.parametrize("model", MODELS)
def test_every_coefficient_of_every_tet_equals_the_json_oracle(model):
    path = SPEC / ORACLES[model]
    if not path.exists():
        pytest.skip(f"oracle {path} not present")
    oracle = json.loads(path.read_text())
    scheme = type6_rules.scheme(model)
    d = scheme.degree
    assert oracle["degree"] == d
    assert len(oracle["cube_domain_points"]) == len(scheme.cube_points)
    spline, data = _random_spline(model)
    centre = np.array([3, 3, 3])
    ours_by_key = {}
    for t in range(24):
        keys = tuple(sorted(map(tuple, np.rint(type6.VERTICES[t] * 2).astype(int).tolist())))
        ours_by_key[keys] = t
    n_checked = 0
    for tet in oracle["tetrahedra"]:
        verts = np.array([[float(Fraction(c)) for c in v] for v in tet["vertices_v0_v1_v2_v3"]])
        t = ours_by_key[tuple(sorted(map(tuple, np.rint(verts * 2).astype(int).tolist())))]
        ours = spline.tet_coefficients(centre[None], np.array([t]))[0]
        xi_ours = bform.domain_points(type6.VERTICES[t], d)
        for entry in tet["coefficients"].values():
            xi = np.array([float(Fraction(c)) for c in entry["xi"]])
            row = np.flatnonzero(np.all(np.abs(xi_ours - xi) < 1e-12, axis=1))
            assert len(row) == 1
            mask = np.zeros(27)
            expected = 0.0
            for a, b, c, w in entry["mask"]:
                mask[type6_rules._offset_row((a, b, c))] += float(Fraction(w))
                expected += float(Fraction(w)) * data[3 + a, 3 + b, 3 + c]
            assert np.allclose(scheme.tet_masks[t, row[0]], mask, atol=1e-15, rtol=0)
            assert ours[row[0]] == pytest.approx(expected, abs=1e-13)
            n_checked += 1
    assert n_checked == 24 * bform.n_coefficients(d)


@pytest.mark.parametrize("model", MODELS)
def test_masks_are_stochastic_and_use_the_stencil_sizes_of_the_thesis(model):
    scheme = type6_rules.scheme(model)
    assert np.allclose(scheme.tet_masks.sum(axis=2), 1.0)  # Q(1) = 1 (§4.3.1)
    assert scheme.tet_masks.min() >= 0  # operator norm 1 (§4.4)
    used = (scheme.tet_masks != 0).any(axis=1).sum(axis=1)
    # cubic: 23 values per tetrahedron (§6.1.2); quadratic reconstruction: 15
    assert set(used) == ({23} if model == "cubic-c1" else {15})


def test_rule_parser_reads_letter_notation():
    rule = type6_rules.parse_rule("1/4 I + 1/8 (F+BL) + 1/16 FRT")
    assert rule == {(0, 0, 0): Fraction(1, 4), (1, 0, 0): Fraction(1, 8),
                    (-1, -1, 0): Fraction(1, 8), (1, 1, 1): Fraction(1, 16)}
    with pytest.raises(ValueError):
        type6_rules.parse_rule("1/4 FB F")


# ------------------------------------------------------------- determining sets


@pytest.mark.parametrize("model, size, points", [("cubic-c1", 56, 175),
                                                 ("super-quadratic", 24, 65)])
def test_determining_set_and_averaging_recover_every_coefficient(model, size, points):
    scheme = type6_rules.scheme(model)
    assert len(scheme.cube_points) == points
    assert len(scheme.determining) == size
    assert len(scheme.rules) == points - size
    spline, _ = _random_spline(model, seed=11)
    cubes = spline.all_cubes()
    full = spline.cube_coefficients(cubes)  # determining set + repeated averaging
    tet = np.repeat(np.arange(24), len(cubes))
    direct = spline.tet_coefficients(np.tile(cubes, (24, 1)), tet)
    via_rules = full[np.tile(np.arange(len(cubes)), 24)[:, None], scheme.tet_points[tet]]
    assert np.abs(via_rules - direct).max() < 1e-13


def test_cubic_determining_set_is_the_thesis_one():
    """xi_00kl (k + l = 3) and xi_0111: 8 vertices, 24 edge points, 24 face centroids."""
    scheme = type6_rules.scheme("cubic-c1")
    pts = scheme.cube_points[scheme.determining]
    on_surface = np.isclose(np.abs(pts).max(axis=1), 0.5)
    assert on_surface.all()
    n_half = np.isclose(np.abs(pts), 0.5).sum(axis=1)
    assert (n_half == 3).sum() == 8 and (n_half == 2).sum() == 24 and (n_half == 1).sum() == 24
    # repeated averaging: every rule combines at most 5 coefficients (eq. 4.2)
    assert max(len(src) for _, src, _ in scheme.rules) <= 5


def test_quadratic_needs_24_determining_values_not_20():
    """The coefficient functionals of a cube span 24 dimensions: 20 values cannot determine it."""
    scheme = type6_rules.scheme("super-quadratic")
    assert np.linalg.matrix_rank(scheme.cube_masks) == 24
    edges = [i for i in scheme.determining if np.isclose(np.abs(scheme.cube_points[i]), 0.5)
             .sum() >= 2]
    assert len(edges) == 20
    assert np.linalg.matrix_rank(scheme.cube_masks[edges]) == 20


# --------------------------------------------------------------------- smoothness


def _face_jumps(spline, t, m, n_points=50, seed=0):
    """Max value and gradient jumps across the face of tet t (cube (3,3,3)) opposite v_m."""
    nb, off, _ = type6.face_neighbours()
    s = nb[t, m]
    rng = np.random.default_rng(seed)
    w = rng.dirichlet(np.ones(3), n_points)
    face = np.delete(type6.VERTICES[t], m, axis=0)
    local = w @ face  # points on the face, relative to cube (3,3,3)
    cube = np.array([3, 3, 3])
    out = []
    for tet, c in ((t, cube), (s, cube + off[t, m])):
        coeffs = spline.tet_coefficients(np.tile(c, (n_points, 1)), np.full(n_points, tet))
        mat = type6.barycentric_matrices()[tet]
        lam = bform.barycentric(local + cube - c, mat)
        out.append(bform.value_gradient(coeffs, lam, mat))
    (v0, g0), (v1, g1) = out
    return np.abs(v0 - v1).max(), np.abs(g0 - g1).max()


def _all_face_types():
    nb, off, _ = type6.face_neighbours()
    inside = type6_rules.interior_faces("all")
    across = [(t, 0) for t in range(24)]
    assert len(inside) == 36 and len(across) == 24
    return inside, across


def test_cubic_is_c1_across_all_60_face_types():
    spline, data = _random_spline("cubic-c1")
    inside, across = _all_face_types()
    scale = np.abs(data).max()
    for t, m in inside + across:
        dv, dg = _face_jumps(spline, t, m)
        assert dv < JUMP_TOL * scale and dg < JUMP_TOL * scale, (t, m, dv, dg)


def test_quadratic_is_c0_everywhere_and_c1_where_the_spec_says():
    spline, data = _random_spline("super-quadratic")
    inside, across = _all_face_types()
    pyramid = set(type6_rules.interior_faces("pyramid"))
    between = set(type6_rules.interior_faces("between"))
    assert len(pyramid) == 24 and len(between) == 12
    jumps_between = []
    for t, m in inside + across:
        dv, dg = _face_jumps(spline, t, m)
        assert dv < JUMP_TOL, (t, m, dv)
        if (t, m) in between:
            jumps_between.append(dg)
        else:  # cube faces and the faces [v0, v1, corner]
            assert dg < JUMP_TOL, (t, m, dg)
    # not C^1 across [v0, v2, v3] for general data: the jump is of the order of the data
    assert min(jumps_between) > 1e-3


def _gradients_at(spline, point, tets_cubes):
    out = []
    for tet, cube in tets_cubes:
        coeffs = spline.tet_coefficients(np.array([cube]), np.array([tet]))
        mat = type6.barycentric_matrices()[tet]
        lam = bform.barycentric((np.asarray(point) - cube)[None], mat)
        out.append(bform.value_gradient(coeffs, lam, mat)[1][0])
    return np.array(out)


def test_quadratic_super_smoothness_at_centres_not_at_corners():
    spline, _ = _random_spline("super-quadratic")
    centre = np.array([3, 3, 3])
    g = _gradients_at(spline, centre, [(t, centre) for t in range(24)])
    assert np.ptp(g, axis=0).max() < JUMP_TOL  # C^1 at the cube centre
    corner = centre + 0.5
    touching = [(t, c) for dc in np.ndindex(2, 2, 2) for c in [centre + np.array(dc)]
                for t in range(24)
                if np.any(np.all(np.abs(type6.VERTICES[t] + c - corner) < 1e-12, axis=1))]
    assert len(touching) == 8 * 6
    g = _gradients_at(spline, corner, touching)
    assert np.ptp(g, axis=0).max() > 1e-3  # not C^1 at cube vertices (spec)


# ------------------------------------------------------------------- reproduction


POLYS = {
    "1": (lambda x, y, z: np.ones_like(x), lambda x, y, z: np.zeros(x.shape + (3,))),
    "x": (lambda x, y, z: x, lambda x, y, z: np.stack([np.ones_like(x), 0 * x, 0 * x], -1)),
    "y": (lambda x, y, z: y, lambda x, y, z: np.stack([0 * x, np.ones_like(x), 0 * x], -1)),
    "z": (lambda x, y, z: z, lambda x, y, z: np.stack([0 * x, 0 * x, np.ones_like(x)], -1)),
    "xy": (lambda x, y, z: x * y, lambda x, y, z: np.stack([y, x, 0 * x], -1)),
    "xz": (lambda x, y, z: x * z, lambda x, y, z: np.stack([z, 0 * x, x], -1)),
    "yz": (lambda x, y, z: y * z, lambda x, y, z: np.stack([0 * x, z, y], -1)),
    "xyz": (lambda x, y, z: x * y * z, lambda x, y, z: np.stack([y * z, x * z, x * y], -1)),
}


def _check_reproduction(model, name, shift=0.0):
    f, grad = POLYS[name]
    i, j, k = np.indices((7, 6, 8)).astype(float) - 2.5
    spline = CLASSES[model](f(i, j, k))
    # interior points so that the linear ghost layer does not matter for non-linear terms
    p = np.random.default_rng(5).uniform(1, 4, (3000, 3))
    v, g = spline.value_gradient(p)
    x, y, z = (p - 2.5).T
    assert np.abs(v - f(x, y, z) - shift).max() < 1e-11
    assert np.abs(g - grad(x, y, z)).max() < 1e-10


@pytest.mark.parametrize("name", list(POLYS))
def test_cubic_reproduces_trilinear_terms(name):
    _check_reproduction("cubic-c1", name)


@pytest.mark.parametrize("name", ["1", "x", "y", "z", "xy", "xz", "yz"])
def test_quadratic_reproduces_linear_and_mixed_terms(name):
    _check_reproduction("super-quadratic", name)


@pytest.mark.parametrize("model", MODELS)
def test_x_squared_becomes_x_squared_plus_quarter_h_squared(model):
    for h in (1.0, 0.25):
        n = 9
        vol = sv.Volume.from_function(lambda x, y, z: x * x, (n, n, n),
                                      ((0, (n - 1) * h),) * 3)
        s = sv.build_spline(vol, model=model)
        p = np.random.default_rng(2).uniform(h, (n - 2) * h, (2000, 3))
        v, g = s.value_gradient(p)
        assert np.abs(v - (p[:, 0] ** 2 + h * h / 4)).max() < 1e-10
        assert np.abs(g - np.stack([2 * p[:, 0], 0 * p[:, 0], 0 * p[:, 0]], 1)).max() < 1e-9
        hess = s.hessian(p[:50])
        assert np.allclose(hess, np.diag([2.0, 0, 0]), atol=1e-8)


def test_linear_reproduction_up_to_the_box_boundary_with_spacing_and_origin():
    spacing, origin = (0.5, 1.0, 2.0), (-1.0, 3.0, 0.5)
    vol = sv.Volume.from_function(lambda x, y, z: 2 * x - y + 0.5 * z + 1, (5, 6, 4),
                                  [(o, o + (n - 1) * s) for o, n, s in
                                   zip(origin, (5, 6, 4), spacing, strict=True)])
    for model in MODELS:
        s = sv.build_spline(vol, model=model)
        (x0, x1), (y0, y1), (z0, z1) = s.bounds
        corners = np.array([[x, y, z] for x in (x0, x1) for y in (y0, y1) for z in (z0, z1)])
        p = np.concatenate([corners, np.random.default_rng(0).uniform(
            [x0, y0, z0], [x1, y1, z1], (500, 3))])
        v, g = s.value_gradient(p)
        # float32 storage of the samples limits the accuracy
        assert np.abs(v - (2 * p[:, 0] - p[:, 1] + 0.5 * p[:, 2] + 1)).max() < 1e-5
        assert np.abs(g - [2, -1, 0.5]).max() < 1e-5
        assert s.hessian(p[:10]).shape == (10, 3, 3)


def test_models_are_registered():
    data = np.random.default_rng(0).uniform(size=(4, 4, 4))
    assert isinstance(sv.build_spline(data, model="cubic-c1"), CubicC1Spline)
    assert isinstance(sv.build_spline(data, model="super-quadratic"), SuperQuadraticSpline)


def test_hessian_matches_finite_differences_of_the_gradient():
    spline, _ = _random_spline("cubic-c1", seed=9)
    # points well inside tetrahedra so the finite-difference stencil stays in one piece
    cube, tet = np.array([[3, 3, 3]] * 24), np.arange(24)
    centroid = type6.VERTICES.mean(axis=1) + cube
    hess = spline.hessian(centroid)
    eps = 1e-5
    for a in range(3):
        e = np.zeros(3)
        e[a] = eps
        fd = (spline.gradient(centroid + e) - spline.gradient(centroid - e)) / (2 * eps)
        assert np.abs(hess[:, :, a] - fd).max() < 1e-6
    del tet


# ------------------------------------------------------------------- convergence


def error_table(model, func, inv_h, n_random=100_000, seed=0, **kwargs):
    """Errors of values and D_x on [-1/2, 1/2]^3 (thesis §5.5 columns).

    Samples on the grid of spacing h = 1/inv_h covering [-1/2 - 3h, 1/2 + 3h]^3 (as for Q_2,
    spec/to-spline-notes.md); err_data over the grid points in [-1/2, 1/2]^3; err_max, mean,
    rms over ``n_random`` uniform random points of [-1/2, 1/2]^3 (the same points for every
    model; not the 220-points-per-tetrahedron set of the thesis, which differs per partition).

    Returns
    -------
    dict: {"value": (data, max, mean, rms), "dx": (data, max, mean, rms)}
    """
    h = 1.0 / inv_h
    n = inv_h + 7
    lo, hi = -0.5 - 3 * h, 0.5 + 3 * h
    vol = sv.Volume(
        func(*np.meshgrid(*[np.linspace(lo, hi, n)] * 3, indexing="ij")).astype(np.float64),
        spacing=(h, h, h), origin=(lo, lo, lo),
    )
    s = sv.build_spline(vol, model=model, **kwargs)
    g1 = np.linspace(-0.5, 0.5, inv_h + 1)
    grid = np.stack(np.meshgrid(g1, g1, g1, indexing="ij"), -1).reshape(-1, 3)
    rand = np.random.default_rng(seed).uniform(-0.5, 0.5, (n_random, 3))
    out = {}
    for key, pts in (("grid", grid), ("rand", rand)):
        v, g = s.value_gradient(pts)
        x, y, z = pts.T
        out[key] = (np.abs(v - func(x, y, z)), np.abs(g[:, 0] - func.gradient(x, y, z)[:, 0]))
    res = {}
    for c, name in enumerate(("value", "dx")):
        e = out["rand"][c]
        res[name] = (out["grid"][c].max(), e.max(), e.mean(), np.sqrt((e * e).mean()))
    return res


@pytest.mark.parametrize("model", MODELS)
def test_values_and_gradients_converge_with_order_two_on_blob(model):
    blob = TEST_FUNCTIONS["blob"]
    errs = [error_table(model, blob, n, n_random=20_000) for n in (8, 16, 32)]
    for kind in ("value", "dx"):
        for col in (0, 1, 3):  # err_data, err_max, err_rms
            ratio = errs[1][kind][col] / errs[2][kind][col]
            assert 3.0 < ratio < 5.0, (kind, col, ratio)


def fig_5_6_errors(model, n=64, n_random=300_000):
    """Marschner-Lobb sampled on n^3 points of its domain [-1, 1]^3 (thesis Fig. 5.6).

    Three extra sample layers outside the domain (the function is known there) keep the
    boundary treatment out of the comparison. Returns (err_max, err_mean, err_rms) of the
    values over uniform random points of [-1, 1]^3.
    """
    ml = TEST_FUNCTIONS["ml"]
    h, g = 2.0 / (n - 1), 3
    ax = -1 - g * h + h * np.arange(n + 2 * g)
    vol = sv.Volume(ml(*np.meshgrid(ax, ax, ax, indexing="ij")), spacing=(h,) * 3,
                    origin=(ax[0],) * 3)
    p = np.random.default_rng(0).uniform(-1, 1, (n_random, 3))
    e = np.abs(sv.build_spline(vol, model=model).evaluate(p) - ml(*p.T))
    return e.max(), e.mean(), np.sqrt((e * e).mean())


@pytest.mark.slow
def test_convergence_tables_and_fig_5_6(capsys):
    """Prints the §5.5-style tables for both type-6 splines next to Q_2 (1/h = 8..64).

    Fig. 5.6 claims Q_2 reconstructs Marschner-Lobb on a 64^3 grid with a lower error than
    both type-6 splines. Measured here it does not: the three errors agree within a few per
    cent and Q_2's maximal error is the largest, so the test pins the measured agreement.
    """
    models = MODELS + ["to-quadratic"]
    lines = []
    for fname in ("blob", "fr", "ml"):
        func = TEST_FUNCTIONS[fname]
        for model in models:
            prev = None
            for inv_h in (8, 16, 32, 64):
                r = error_table(model, func, inv_h)
                ratio = "" if prev is None else (
                    f"  ratio max {prev['value'][1] / r['value'][1]:.2f}"
                    f" dx {prev['dx'][1] / r['dx'][1]:.2f}")
                lines.append(
                    f"{fname:4s} {model:15s} 1/h={inv_h:3d} value "
                    + " ".join(f"{e:.6f}" for e in r["value"]) + "  D_x "
                    + " ".join(f"{e:.6f}" for e in r["dx"]) + ratio)
                if fname == "blob" and inv_h == 64:  # smooth data: order two at 1/h = 64
                    assert 3.5 < prev["value"][1] / r["value"][1] < 4.5
                    assert 3.3 < prev["dx"][1] / r["dx"][1] < 4.7
                prev = r
    fig = {model: fig_5_6_errors(model) for model in models}
    with capsys.disabled():
        print("\n" + "\n".join(lines))
        for model, (emax, emean, erms) in fig.items():
            print(f"Fig. 5.6 ml 64^3 on [-1,1]^3 {model:15s} err_max {emax:.5f} "
                  f"err_mean {emean:.5f} err_rms {erms:.5f}")
    rms = np.array([fig[m][2] for m in models])
    assert np.ptp(rms) / rms.min() < 0.15


@pytest.mark.bench
@pytest.mark.parametrize("model", MODELS)
def test_large_volume_memory_and_speed_against_map_coordinates(model):
    """10^6 points of a 256^3 volume: < 2 GB and within 5x map_coordinates(order=3)."""
    from splineviz.bench.evaluate import run_one

    r = run_one(model, 256, 1_000_000)
    print(f"\n{model}: {r['time_s']:.2f} s, map_coordinates {r['baseline_s']:.2f} s, "
          f"ratio {r['ratio']:.2f}, peak RSS {r['peak_rss_mib']:.0f} MiB")
    assert r["ratio"] < 5.0
    assert r["peak_rss_mib"] < 2048


@pytest.mark.parametrize("model", MODELS)
@pytest.mark.parametrize("shape", [(1, 4, 5), (2, 2, 2), (1, 1, 1)])
def test_thin_volumes_are_covered_and_linear_data_reproduced(model, shape):
    i, j, k = np.indices(shape).astype(float)
    data = 1.0 + 0.5 * i - 0.25 * j + 2.0 * k
    s = sv.build_spline(data, model=model)
    (x0, x1), (y0, y1), (z0, z1) = s.bounds
    p = np.random.default_rng(1).uniform([x0, y0, z0], [x1, y1, z1], (200, 3))
    p = np.concatenate([p, [[x0, y0, z0], [x1, y1, z1]]])
    expected = 1.0 + 0.5 * p[:, 0] - 0.25 * p[:, 1] + 2.0 * p[:, 2]
    assert np.abs(s.evaluate(p) - expected).max() < 1e-12
