"""The truncated-octahedral partition and the quasi-interpolants Q_k (thesis §5.2-5.4)."""

import numpy as np
import pytest

import splineviz as sv
from splineviz.core import bform
from splineviz.core.partitions import truncated_octahedra as to
from splineviz.core.splines import to_quadratic as tq

RNG = np.random.default_rng(20261122)


# --- partition ------------------------------------------------------------------------------

def test_generic_tetrahedra_counts_and_volume():
    verts, kind, _ = to.generic_tetrahedra()
    assert verts.shape == (144, 4, 3)
    assert (kind == "S").sum() == 48 and (kind == "H").sum() == 96
    vols = np.abs(np.linalg.det(verts[:, 1:] - verts[:, :1])) / 6
    # a TO of radius h has volume 4 h^3 = one BCC cell (two TOs per 2h cube)
    assert vols.sum() == pytest.approx(4.0, abs=1e-12)
    assert np.all(vols > 0.01)
    # v1 on a face, v2 an edge midpoint, v3 a TO vertex
    tov = {tuple(v) for v in to.to_vertices()}
    assert all(tuple(v) in tov for v in verts[:, 3])


def test_tetrahedra_tile_space():
    pts = RNG.uniform(-3, 5, size=(3000, 3))
    centres = to.nearest_centre(pts)
    cands = np.concatenate([np.zeros((1, 3)), to.NEIGHBOUR_OFFSETS])
    mats = to.barycentric_matrices()
    count = np.zeros(len(pts), dtype=int)
    for shift in cands:
        d = pts - (centres + shift)
        lam = np.einsum("tij,nj->nti", mats[..., :3], d) + mats[:, :, 3][None]
        count += np.sum(lam.min(axis=2) >= -1e-12, axis=1)
    assert np.all(count == 1)


def test_locate_returns_containing_tetrahedron():
    pts = RNG.uniform(-2, 6, size=(5000, 3))
    c, tet, lam = to.locate(pts)
    assert lam.min() >= -1e-12
    assert np.allclose(lam.sum(axis=1), 1)
    verts = to.generic_tetrahedra()[0][tet]
    assert np.allclose(np.einsum("nm,nmc->nc", lam, verts) + c, pts)
    # centres are on the BCC lattice: half-integers of equal parity
    i = np.rint(c - 0.5).astype(int)
    assert np.all((i[:, 0] - i[:, 1]) % 2 == 0) and np.all((i[:, 1] - i[:, 2]) % 2 == 0)


def test_neighbour_table_is_symmetric():
    nb, shift = to.neighbours()
    verts = to.generic_tetrahedra()[0]
    for t in range(144):
        for nu in range(4):
            t2, s = nb[t, nu], shift[t, nu]
            back = [nu2 for nu2 in range(4)
                    if nb[t2, nu2] == t and np.allclose(shift[t2, nu2], -s)]
            assert len(back) == 1
            shared = np.delete(verts[t], nu, axis=0)
            other = np.delete(verts[t2], back[0], axis=0) + s
            assert sorted(map(tuple, np.round(shared, 9))) == sorted(map(tuple, np.round(other, 9)))
    # F_0 faces lie on the TO boundary (neighbour in another TO), F_1..F_3 inside
    assert np.all(np.abs(shift[:, 0]).sum(axis=1) > 0)
    assert np.all(np.abs(shift[:, 1:]).sum(axis=2) == 0)


def test_centres_covering_box():
    c = to.centres_covering([0, 0, 0], [4, 4, 4])
    pts = RNG.uniform(0, 4, size=(2000, 3))
    keys = {tuple(k) for k in np.rint(2 * c).astype(int)}
    found = {tuple(k) for k in np.rint(2 * to.nearest_centre(pts)).astype(int)}
    assert found <= keys


# --- the operator Q_k ------------------------------------------------------------------------

def _grid_volume(func, n=9, h=0.25, origin=(-1.0, -0.5, -0.75)):
    return sv.Volume.from_function(
        func, (n, n + 1, n + 2),
        [(o, o + h * (m - 1)) for o, m in zip(origin, (n, n + 1, n + 2), strict=True)]
    )


def _points(vol, m=4000):
    (x0, x1), (y0, y1), (z0, z1) = vol.bounds
    return RNG.uniform([x0, y0, z0], [x1, y1, z1], size=(m, 3))


@pytest.mark.parametrize("k", [1, 2, 3, 5])
def test_reproduces_constants(k):
    vol = _grid_volume(lambda x, y, z: np.full_like(x, 3.25))
    s = sv.build_spline(vol, model="to-quadratic", k=k)
    p = _points(vol)
    assert np.allclose(s.evaluate(p), 3.25, atol=1e-12)
    assert np.allclose(s.gradient(p), 0, atol=1e-10)


POLYS = {
    "1": (lambda x, y, z: 1 + 0 * x, 0.0),
    "x": (lambda x, y, z: x, 0.0),
    "y": (lambda x, y, z: y, 0.0),
    "z": (lambda x, y, z: z, 0.0),
    "xy": (lambda x, y, z: x * y, 0.0),
    "xz": (lambda x, y, z: x * z, 0.0),
    "yz": (lambda x, y, z: y * z, 0.0),
    "x2": (lambda x, y, z: x * x, 1.0),
    "y2": (lambda x, y, z: y * y, 1.0),
    "z2": (lambda x, y, z: z * z, 1.0),
}


@pytest.mark.parametrize("name", sorted(POLYS))
def test_q2_reproduces_quadratics_up_to_h2_over_4(name):
    """Lemma 4 (i)-(iv): exact for P1 and xy, xz, yz; x^2 -> x^2 + h^2/4. Ghost layers are
    linear extrapolations, so only the interior (away from the box by 3h) is exact for the
    quadratic monomials; linear ones are exact everywhere."""
    func, shift = POLYS[name]
    h = 0.25
    vol = _grid_volume(func, n=14, h=h)
    s = sv.build_spline(vol, model="to-quadratic")
    p = _points(vol)
    if name not in ("1", "x", "y", "z"):
        lo = np.array([b[0] for b in vol.bounds]) + 3 * h
        hi = np.array([b[1] for b in vol.bounds]) - 3 * h
        p = RNG.uniform(lo, hi, size=(3000, 3))
    assert np.allclose(s.evaluate(p), func(*p.T) + shift * h * h / 4, atol=1e-11)


def test_q2_reproduces_first_and_second_derivatives_of_quadratics():
    """Corollary 5 / Remark 3: D^alpha Q_2(p) = D^alpha p for |alpha| = 1, 2."""
    # powers of two and eighths keep the samples exact in the volume's float32 storage
    h = (0.25, 0.5, 0.125)
    a = RNG.integers(-16, 17, size=10) / 8

    def q(x, y, z):
        return (a[0] + a[1] * x + a[2] * y + a[3] * z + a[4] * x * x + a[5] * y * y
                + a[6] * z * z + a[7] * x * y + a[8] * x * z + a[9] * y * z)

    shape = (14, 13, 15)
    vol = sv.Volume.from_function(q, shape, [(0, h[i] * (shape[i] - 1)) for i in range(3)])
    s = sv.build_spline(vol, model="to-quadratic")
    lo = 3 * np.array(h)
    hi = np.array([b[1] for b in vol.bounds]) - 3 * np.array(h)
    p = RNG.uniform(lo, hi, size=(2000, 3))
    x, y, z = p.T
    grad = np.stack([a[1] + 2 * a[4] * x + a[7] * y + a[8] * z,
                     a[2] + 2 * a[5] * y + a[7] * x + a[9] * z,
                     a[3] + 2 * a[6] * z + a[8] * x + a[9] * y], axis=1)
    hess = np.array([[2 * a[4], a[7], a[8]], [a[7], 2 * a[5], a[9]], [a[8], a[9], 2 * a[6]]])
    assert np.allclose(s.gradient(p), grad, atol=1e-9)
    assert np.allclose(s.hessian(p), hess, atol=1e-8)
    # the value is off by the constant C h^2 of Lemma 4 (v): here (a4 hx^2 + a5 hy^2 + a6 hz^2)/4
    c = (a[4] * h[0] ** 2 + a[5] * h[1] ** 2 + a[6] * h[2] ** 2) / 4
    assert np.allclose(s.evaluate(p), q(x, y, z) + c, atol=1e-10)


@pytest.mark.parametrize("k", [1, 3, 5])
def test_lemma6_linear_values_at_grid_points(k):
    func = POLYS["x"][0]
    vol = _grid_volume(lambda x, y, z: 2 * x - y + 0.5 * z + 1, n=10)
    s = sv.build_spline(vol, model="to-quadratic", k=k)
    g = np.stack(np.meshgrid(*[np.arange(n) for n in vol.shape], indexing="ij"), -1).reshape(-1, 3)
    p = vol.index_to_world(g)
    x, y, z = p.T
    assert np.allclose(s.evaluate(p), 2 * x - y + 0.5 * z + 1, atol=1e-12)
    # but off the grid points linear functions are not reproduced for k != 2
    q = _points(vol, 500)
    assert np.abs(sv.build_spline(_grid_volume(lambda x, y, z: func(x, y, z), n=10),
                                  model="to-quadratic", k=k).evaluate(q) - q[:, 0]).max() > 1e-4


def test_stencils_reproduce_linear_functions_all_1440():
    """Every stencil reproduces x, y, z exactly for k = 2 (the tie-break rules matter)."""
    verts = to.generic_tetrahedra()[0]
    for t, (off, w) in enumerate(tq.stencils(2)):
        z = off - 0.5  # data point positions relative to the reference TO centre
        for axis in range(3):
            want = bform.bform_of_polynomial(lambda p, a=axis: p[:, a], verts[t], 2)
            assert np.allclose(w @ z[:, axis], want, atol=1e-13), (t, axis)


def test_coefficient_parts_sum_to_the_stencils():
    """Eq. (5.9) per TO: each part's weights sum to its share, the parts to the stencil."""
    for t in (0, 17, 101, 143):
        for alpha in bform.multi_indices(2):
            parts = tq.coefficient_parts(t, alpha, 2)
            assert 1 <= len(parts) <= 4
            total = {}
            for centre, w in parts:
                for z, wz in zip(centre + to.DATA_OFFSETS, w, strict=True):
                    key = tuple(int(round(c)) for c in z + 0.5)
                    total[key] = total.get(key, 0.0) + wz
            assert total == tq.coefficient_stencil(t, alpha, 2)
            assert np.isclose(sum(w.sum() for _, w in parts), 1.0)


@pytest.mark.parametrize("k", [3, 4, 7])
def test_positive_for_k_at_least_3(k):
    """Corollary 3: all weights are >= 0 for k >= 3, so positive data give a positive spline."""
    assert min(w.min() for _, w in tq.stencils(k)) >= 0
    vol = _grid_volume(lambda x, y, z: 1e-3 + 0 * x, n=9)
    data = RNG.uniform(0.001, 1.0, size=vol.shape)
    s = sv.build_spline(sv.Volume(data), model="to-quadratic", k=k)
    p = RNG.uniform(0, np.array(vol.shape) - 1, size=(5000, 3))
    assert s.evaluate(p).min() > 0
    # k = 2 has negative weights (it is not positive)
    assert min(w.min() for _, w in tq.stencils(2)) < 0


def _face_type(t, nu):
    kind = to.generic_tetrahedra()[1][t]
    return f"F{nu}^{kind}"


@pytest.mark.parametrize("k", [1, 2, 3])
def test_c1_across_every_face_type(k):
    """Value and gradient jumps across all interior faces (F0..F3 of T^S and T^H) for random
    data: < 1e-9 relative (Theorem 2)."""
    data = RNG.normal(size=(12, 12, 12))
    mats = to.barycentric_matrices()
    verts = to.generic_tetrahedra()[0]
    nb, shift = to.neighbours()
    c0 = np.array([5.5, 5.5, 5.5])
    scale = np.abs(data).max()
    seen = set()
    for t in range(144):
        for nu in range(4):
            t2, c2 = nb[t, nu], c0 + shift[t, nu]
            w = RNG.dirichlet(np.ones(3), 4)
            p = w @ (np.delete(verts[t], nu, axis=0) + c0)
            vals = []
            for tt, cc in ((t, c0), (t2, c2)):
                base = np.repeat(np.rint(cc - 0.5).astype(int)[None], len(p), 0)
                co = tq.coefficients(data, base, np.full(len(p), tt), k)
                vals.append(bform.value_gradient(co, bform.barycentric(p - cc, mats[tt]), mats[tt]))
            assert np.abs(vals[0][0] - vals[1][0]).max() < 1e-9 * scale
            assert np.abs(vals[0][1] - vals[1][1]).max() < 1e-9 * scale
            seen.add(_face_type(t, nu))
    assert seen == {f"F{nu}^{c}" for nu in range(4) for c in "SH"}


def test_spline_covers_whole_box_and_uses_world_units():
    vol = sv.Volume(RNG.normal(size=(5, 6, 7)), spacing=(0.5, 2.0, 1.0), origin=(1, -2, 3))
    s = sv.build_spline(vol, model="to-quadratic")
    corners = np.array(np.meshgrid(*vol.bounds, indexing="ij")).reshape(3, -1).T
    assert np.all(np.isfinite(s.evaluate(corners)))
    assert s.bounds == vol.bounds
    # world gradient = index gradient / spacing: compare with central differences
    p = _points(vol, 50)
    p = np.clip(p, [b[0] + 0.01 for b in vol.bounds], [b[1] - 0.01 for b in vol.bounds])
    eps = 1e-6
    fd = np.stack([(s.evaluate(p + eps * e) - s.evaluate(p - eps * e)) / (2 * eps)
                   for e in np.eye(3)], 1)
    assert np.allclose(s.gradient(p), fd, atol=1e-5)
    fd2 = np.stack([(s.gradient(p + eps * e) - s.gradient(p - eps * e)) / (2 * eps)
                    for e in np.eye(3)], 2)
    assert np.allclose(s.hessian(p), fd2, atol=1e-3)
