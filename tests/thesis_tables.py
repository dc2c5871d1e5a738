"""The error protocol behind thesis Tables 5.1-5.12 for the truncated-octahedral Q_k.

As settled in ``../shared/spec/to-spline-notes.md``: f is sampled on the grid of spacing
h = 1/n covering [-1/2 - 3h, 1/2 + 3h]^3; the partition is every TO meeting [-1/2, 1/2]^3;
err_data is taken over the (n+1)^3 grid points in [-1/2, 1/2]^3; err_max / err_mean / err_rms over
the 220 degree-9 domain points of every tetrahedron of that partition (parts outside the cube
included). Derivatives are D_x and D_xx (r = 1, 2).

Run as a script to print the tables: ``python tests/thesis_tables.py 8 16 32``.
"""

from __future__ import annotations

import sys

import numpy as np

from splineviz.core import bform
from splineviz.core.partitions import truncated_octahedra as to
from splineviz.core.splines import to_quadratic as tq
from splineviz.core.testfunctions import TEST_FUNCTIONS

#: thesis values (err_data, err_max, err_mean, err_rms); key (function, k, r, 1/h)
THESIS = {}


def _table(func, k, r, rows):
    for n, *vals in rows:
        THESIS[(func, k, r, n)] = tuple(vals)


_table("blob", 3, 0, [(8, .072325, .080944, .011721, .018593), (16, .018859, .023713, .003983, .005837),
                      (32, .004765, .008360, .001503, .002074), (64, .001194, .003504, .000658, .000892),
                      (128, .000299, .001614, .000314, .000426)])
_table("fr", 3, 0, [(8, .200420, .200536, .010000, .0220219), (16, .056525, .065843, .003392, .0072288),
                    (32, .014583, .019627, .001189, .0023808), (64, .003685, .007333, .000481, .0009176),
                    (128, .000926, .003185, .000221, .0004145)])
_table("ml", 3, 0, [(8, .093599, .165222, .060747, .071258), (16, .091361, .102068, .037767, .045003),
                    (32, .045369, .048335, .012682, .015818), (64, .013786, .015158, .003474, .004388),
                    (128, .003309, .004879, .001003, .001267)])
_table("blob", 2, 0, [(8, .053447, .053719, .007873, .013093), (16, .013724, .013783, .002221, .003573),
                      (32, .003454, .003466, .000585, .000922), (64, .000865, .000867, .000149, .000233),
                      (128, .000216, .000216, .000037, .000058)])
_table("fr", 2, 0, [(8, .157341, .157385, .007047, .016126), (16, .042986, .043009, .002138, .004814),
                    (32, .010986, .010992, .000595, .001312), (64, .002761, .002763, .000157, .000342),
                    (128, .000691, .000691, .000040, .000087)])
_table("ml", 2, 0, [(8, .088397, .165560, .060171, .071867), (16, .081199, .099245, .033299, .040339),
                    (32, .031214, .034153, .009694, .012068), (64, .008584, .008928, .002415, .003028),
                    (128, .002004, .002132, .000595, .000748)])
_table("blob", 2, 1, [(8, .158589, .241703, .024732, .038537), (16, .041100, .071218, .007084, .010642),
                      (32, .010475, .018889, .001888, .002780), (64, .002647, .004782, .000487, .000709),
                      (128, .000759, .001271, .000124, .000180)])
_table("fr", 2, 1, [(8, .738493, .916685, .042349, .094669), (16, .210754, .300654, .013332, .029001),
                    (32, .057464, .082984, .003703, .007914), (64, .014565, .021206, .000971, .002056),
                    (128, .003674, .005374, .000248, .000523)])
_table("ml", 2, 1, [(8, 5.03099, 5.33248, 1.575060, 2.042270), (16, 4.21588, 4.58655, .887093, 1.254340),
                    (32, 1.52074, 2.78363, .254649, .382565), (64, .42781, .80967, .063386, .097711),
                    (128, .10828, .21132, .015481, .024102)])
_table("blob", 2, 2, [(8, 2.78180, 7.36277, .647459, .944675), (16, 1.51370, 4.48919, .366841, .525985),
                      (32, .78379, 2.34272, .192558, .273797), (64, .39897, 1.18080, .098316, .139153),
                      (128, .22540, .61108, .049920, .070501)])
_table("fr", 2, 2, [(8, 9.48307, 34.2698, 1.41213, 2.72682), (16, 6.56458, 24.2788, .87606, 1.68534),
                    (32, 3.35031, 13.2468, .48023, .91651), (64, 1.63083, 6.82766, .24989, .47418),
                    (128, .81025, 3.45017, .12726, .24070)])
_table("ml", 2, 2, [(8, 223.618, 258.992, 55.6158, 77.3912), (16, 147.363, 314.767, 43.9654, 66.5142),
                    (32, 63.4782, 306.433, 25.2862, 42.1393), (64, 29.2791, 209.945, 12.7598, 22.2219),
                    (128, 13.8998, 118.557, 6.2608, 11.0415)])

LAYERS = 3
#: TOs per evaluation chunk (220 points each)
TO_CHUNK = 20000


def _sample_operators():
    """Per generic tet: (220, 10) maps from B-coefficients to value, D_u, D_uu (u = x index)."""
    lam = bform.multi_indices(9).astype(np.float64) / 9.0  # (220, 4)
    eye = np.eye(10)
    mats = to.barycentric_matrices()
    val = bform.bernstein_basis(lam, 2)  # (220, 10)
    dx, dxx = [], []
    for t in range(144):
        a = np.broadcast_to(mats[t, :, 0], (220, 4))
        dx.append(np.stack([bform.directional_derivative(np.broadcast_to(e, (220, 10)), lam, a)
                            for e in eye], axis=1))
        dxx.append(np.stack([bform.directional_derivative(np.broadcast_to(e, (220, 10)), lam, a, a)
                             for e in eye], axis=1))
    return lam, val, np.array(dx), np.array(dxx)


def _covered_grid_points(centres, n):
    """Grid points (index space) lying in a TO of the partition, with that TO's centre.

    Every grid point is the centre of a hexagon shared by exactly two TOs, p +- s/2.
    """
    inner = np.arange(LAYERS - 1, LAYERS + n + 2, dtype=np.float64)
    gp = np.stack(np.meshgrid(inner, inner, inner, indexing="ij"), axis=-1).reshape(-1, 3)
    keys = {tuple(k) for k in np.rint(2 * centres).astype(np.int64)}
    owner = np.full(gp.shape, np.nan)
    for s in to.HEX_NEIGHBOURS:
        cand = gp + s / 2.0
        hit = np.array([tuple(k) in keys for k in np.rint(2 * cand).astype(np.int64)])
        owner[hit] = cand[hit]
    ok = ~np.isnan(owner[:, 0])
    return gp[ok], owner[ok]


def error_tables(func_name: str, n: int, ks=(2, 3)):
    """Errors of Q_k(f) for r = 0, 1, 2 on the grid 1/h = n.

    Returns
    -------
    dict (k, r) -> (err_data, err_max, err_mean, err_rms)
    """
    f = TEST_FUNCTIONS[func_name]
    h = 1.0 / n
    m = n + 2 * LAYERS + 1
    axis = -0.5 - LAYERS * h + h * np.arange(m)
    gx, gy, gz = np.meshgrid(axis, axis, axis, indexing="ij")
    data = f(gx, gy, gz)
    centres = to.centres_covering([LAYERS] * 3, [LAYERS + n] * 3)
    base = np.rint(centres - 0.5).astype(np.int64)
    lam, val, dx, dxx = _sample_operators()
    verts = to.generic_tetrahedra()[0]
    scale = (1.0, 1.0 / h, 1.0 / h**2)
    acc = {(k, r): [0.0, 0.0, 0.0] for k in ks for r in range(3)}  # max, sum, sum of squares
    count = 0
    for t in range(144):
        for start in range(0, len(centres), TO_CHUNK):  # bounds memory at 1/h = 128
            chunk = slice(start, start + TO_CHUNK)
            pts_idx = centres[chunk, None, :] + (lam @ verts[t])[None]  # (M, 220, 3)
            world = (pts_idx - LAYERS) * h - 0.5
            ref = f.derivatives(world[..., 0], world[..., 1], world[..., 2], [[1.0, 0.0, 0.0]])
            exact = (ref.v, ref.g[..., 0], ref.h[..., 0, 0])
            count += world.shape[0] * world.shape[1]
            for k in ks:
                coeffs = tq.coefficients(data, base[chunk], np.full(len(base[chunk]), t), k)
                approx = (coeffs @ val.T, coeffs @ dx[t].T, coeffs @ dxx[t].T)
                for r in range(3):
                    err = np.abs(exact[r] - approx[r] * scale[r])
                    a = acc[(k, r)]
                    a[0] = max(a[0], float(err.max()))
                    a[1] += float(err.sum())
                    a[2] += float(np.sum(err**2))
    # err_data over the data points V inside the region the partition covers
    gp, gcentre = _covered_grid_points(centres, n)
    c, tet, glam = to.locate(gp + 1e-9 * (gcentre - gp))  # the piece of a partition TO
    lam_exact = bform.barycentric(gp - c, to.barycentric_matrices()[tet])
    gbase = np.rint(c - 0.5).astype(np.int64)
    world = (gp - LAYERS) * h - 0.5
    ref = f.derivatives(world[:, 0], world[:, 1], world[:, 2], [[1.0, 0.0, 0.0]])
    exact = (ref.v, ref.g[:, 0], ref.h[:, 0, 0])
    a_dir = to.barycentric_matrices()[tet][:, :, 0]
    glam = lam_exact
    out = {}
    for k in ks:
        coeffs = tq.coefficients(data, gbase, tet, k)
        approx = (
            bform.evaluate(coeffs, glam),
            bform.directional_derivative(coeffs, glam, a_dir) / h,
            bform.directional_derivative(coeffs, glam, a_dir, a_dir) / h**2,
        )
        for r in range(3):
            mx, s, s2 = acc[(k, r)]
            err_data = float(np.abs(exact[r] - approx[r]).max())
            out[(k, r)] = (err_data, mx, s / count, np.sqrt(s2 / count))
    return out


def main(argv):
    ns = [int(a) for a in argv] or [8, 16, 32]
    for name in ("blob", "fr", "ml"):
        for n in ns:
            res = error_tables(name, n)
            for (k, r), vals in sorted(res.items()):
                ref = THESIS.get((name, k, r, n))
                if ref is None:
                    continue
                cells = "  ".join(f"{v:.6g} ({t:.6g})" for v, t in zip(vals, ref, strict=False))
                print(f"{name:5s} k={k} D^{r} 1/h={n:4d}  {cells}", flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
