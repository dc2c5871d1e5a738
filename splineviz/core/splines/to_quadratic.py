"""Quadratic C1 quasi-interpolants Q_k on the truncated-octahedral partition (thesis §5.3).

Every B-coefficient b_xi of the spline is a weighted average of the 8 data values of each TO
containing the domain point xi (eq. 5.9): one TO for points inside a TO, two on a face, three on
an edge, four at a vertex. Within each TO the data points are ordered by increasing distance to
xi and weighted by their position in that order; the weights depend on the coefficient type
(its multi-index and, for four types, whether xi lies in a T^S tetrahedron) and on k.

Three points the text leaves open are settled as ``../shared/spec/to-spline-notes.md`` records
(they are verified by the tests: linear reproduction of all 1440 stencils and C1 continuity):

* "S" coefficients are those whose domain point lies in any T^S tetrahedron;
* b_0101^H: the tie of positions 4 and 5 goes to the data point closer to v3 first;
* b_0110^H, TO "B": the tie goes to the data point closer to v2 first.

All TOs are lattice translates of the reference TO, so the 144 x 10 stencils are computed once
per k, as integer offsets from the TO's base data point ``centre - (1/2, 1/2, 1/2)``.
"""

from __future__ import annotations

import math
import numbers
from functools import cache

import numpy as np

from splineviz.core import bform
from splineviz.core.partitions import truncated_octahedra as to
from splineviz.core.splines.base import TetSpline
from splineviz.core.splines.boundary import pad_linear
from splineviz.core.splines.registry import SplineOptionError

#: ghost layers the stencils reach beyond the data box (see module docstring of boundary.py)
GHOST_LAYERS = 3

# Position patterns of eq. (5.9): weight of position i is mult * (k + c_i) / (k 2^m).
_P_EVEN = (3, 3, 1, 1, -1, -1, -3, -3)      # (k+3) A_{1,2} + (k+1) A_{3,4} + ...
_P_STEP = (3, 2, 2, 1, -1, -2, -2, -3)      # (k+3) A_1 + (k+2) A_{2,3} + (k+1) A_4 + ...
_P_FLAT = (3, 3, 0, 0, 0, 0, -3, -3)        # (k+3) A_{1,2} + k A_{3..6} + (k-3) A_{7,8}
_P_SQUARE = (2, 2, 2, 2, -2, -2, -2, -2)    # (k+2) A_{1..4} + (k-2) A_{5..8}
_P_HEX = (3, 1, 1, 1, -1, -1, -1, -3)       # (k+3) A_1 + (k+1) A_{2,3,4} + ... + (k-3) A_8
_P_MEAN = (0,) * 8                          # 2^-3 A_{1..8}  (k / k)

# (multi-index, S?) -> (m, {role: (mult, pattern)}); roles "A", "B", "C", "D"; None = any S/H
_RULES = {
    ("2000", None): (3, {"A": (1, _P_MEAN)}),
    ("1100", True): (3, {"A": (1, _P_SQUARE)}),
    ("1100", False): (3, {"A": (1, _P_HEX)}),
    ("1010", True): (3, {"A": (1, _P_STEP)}),
    ("1010", False): (3, {"A": (1, _P_FLAT)}),
    ("1001", None): (3, {"A": (1, _P_EVEN)}),
    ("0200", True): (4, {"A": (1, _P_SQUARE), "B": (1, _P_SQUARE)}),
    ("0200", False): (4, {"A": (1, _P_HEX), "B": (1, _P_HEX)}),
    ("0110", True): (4, {"A": (1, _P_STEP), "B": (1, _P_STEP)}),
    ("0110", False): (4, {"A": (1, _P_FLAT), "B": (1, _P_STEP)}),
    ("0101", None): (4, {"A": (1, _P_EVEN), "B": (1, _P_EVEN)}),
    ("0020", None): (6, {"A": (2, _P_FLAT), "B": (3, _P_STEP), "C": (3, _P_STEP)}),
    ("0011", None): (6, {"A": (2, _P_EVEN), "B": (3, _P_EVEN), "C": (3, _P_EVEN)}),
    ("0002", None): (5, {r: (1, _P_EVEN) for r in "ABCD"}),
}

#: number of TOs sharing each domain point type (interior, face, edge, vertex)
_SHARING = {"2000": 1, "1100": 1, "1010": 1, "1001": 1, "0200": 2, "0110": 2, "0101": 2,
            "0020": 3, "0011": 3, "0002": 4}


def _rule(name: str, is_s: bool):
    return _RULES.get((name, None)) or _RULES[(name, is_s)]


def _sq(a, b) -> int:
    """Squared distance in units of 1/64 (all coordinates are multiples of 1/8): exact ties."""
    return int(round(float(np.sum((np.asarray(a) - np.asarray(b)) ** 2)) * 64))


@cache
def _s_domain_points() -> frozenset:
    verts, kind, _ = to.generic_tetrahedra()
    pts = bform.domain_points(verts[kind == "S"], 2).reshape(-1, 3)
    return frozenset(tuple(np.round(p * 8).astype(int)) for p in pts)


def _is_s(xi, centres) -> bool:
    """Whether xi lies in a T^S tetrahedron of any of the TOs ``centres``."""
    s_pts = _s_domain_points()
    return any(tuple(np.round((xi - c) * 8).astype(int)) in s_pts for c in centres)


def _ordered_data(centre, xi, tiebreak_point=None) -> list[int]:
    """The 8 data points of a TO ordered by distance to xi (§5.3), ties as documented: their
    indices into ``centre + DATA_OFFSETS``."""
    z = centre + to.DATA_OFFSETS
    keys = [
        (_sq(p, xi), _sq(p, tiebreak_point) if tiebreak_point is not None else 0, tuple(p))
        for p in z
    ]
    return sorted(range(8), key=lambda i: keys[i])


def _roles(centres, xi):
    """Assign roles A, B, C, D to the TOs sharing xi (§5.3)."""
    if len(centres) == 1:
        return {"A": centres[0]}
    second = [_sq(c + to.DATA_OFFSETS[_ordered_data(c, xi)[1]], xi) for c in centres]
    order = sorted(range(len(centres)), key=lambda i: (second[i], tuple(centres[i])))
    return {role: centres[i] for role, i in zip("ABCD", order, strict=False)}


def coefficient_parts(tet: int, alpha, k: float) -> list[tuple[np.ndarray, np.ndarray]]:
    """The terms of eq. (5.9) of one B-coefficient of the reference TO, one per TO sharing
    its domain point.

    Parameters
    ----------
    tet : generic tetrahedron index in [0, 144)
    alpha : (4,) multi-index with |alpha| = 2
    k : the operator's parameter (k >= 1)

    Returns
    -------
    list of ``(centre, weights)`` in role order (A, B, C, D): ``centre`` (3,) of the TO
    relative to the reference TO, ``weights`` (8,) of its data points ``centre +
    DATA_OFFSETS`` (in the order of :data:`~splineviz.core.partitions.truncated_octahedra.
    DATA_OFFSETS`); the coefficient is the sum of the parts.
    """
    verts, _, _ = to.generic_tetrahedra()
    v = verts[tet]
    name = "".join(str(int(a)) for a in alpha)
    xi = np.asarray(alpha, dtype=np.float64) @ v / 2.0
    cands = np.concatenate([np.zeros((1, 3)), to.NEIGHBOUR_OFFSETS])
    centres = [c for c in cands if to.contains(c, xi[None])[0]]
    if len(centres) != _SHARING[name]:
        raise RuntimeError(f"domain point {name} of tet {tet} lies in {len(centres)} TOs")
    is_s = _is_s(xi, centres)
    m, role_rules = _rule(name, is_s)
    parts = []
    for role, centre in _roles(centres, xi).items():
        mult, pattern = role_rules[role]
        tiebreak = None
        if name == "0101" and not is_s:
            tiebreak = v[3]
        elif name == "0110" and not is_s and role == "B":
            tiebreak = v[2]
        weights = np.zeros(8)
        for pos, i in enumerate(_ordered_data(centre, xi, tiebreak)):
            weights[i] = mult * (k + pattern[pos]) / (k * 2.0**m)
        parts.append((centre, weights))
    return parts


def coefficient_stencil(tet: int, alpha, k: float) -> dict:
    """Data weights of one B-coefficient of the reference TO (eq. 5.9): the sum of its
    :func:`coefficient_parts`.

    Returns
    -------
    dict mapping integer data offsets (3-tuples, relative to the reference TO's base data point
    (-1/2, -1/2, -1/2)) to weights.
    """
    stencil: dict = {}
    for centre, weights in coefficient_parts(tet, alpha, k):
        for z, w in zip(centre + to.DATA_OFFSETS, weights, strict=True):
            key = tuple(int(round(c)) for c in z + 0.5)
            stencil[key] = stencil.get(key, 0.0) + w
    return stencil


@cache
def stencils(k: float = 2):
    """Dense per-tetrahedron stencils of Q_k.

    Returns
    -------
    list of 144 pairs ``(offsets, weights)``: ``offsets`` (K_t, 3) int data offsets from the
    TO's base data point, ``weights`` (10, K_t) so that coefficients = weights @ data[offsets].
    """
    out = []
    for t in range(144):
        per_coeff = [coefficient_stencil(t, a, k) for a in bform.multi_indices(2)]
        keys = sorted(set().union(*per_coeff))
        index = {key: i for i, key in enumerate(keys)}
        w = np.zeros((10, len(keys)))
        for n, st in enumerate(per_coeff):
            for key, weight in st.items():
                w[n, index[key]] = weight
        offsets = np.array(keys, dtype=np.int64)
        offsets.flags.writeable = False
        w.flags.writeable = False
        out.append((offsets, w))
    return tuple(out)


def coefficients(padded: np.ndarray, base: np.ndarray, tet: np.ndarray, k: float = 2):
    """B-coefficients of the pieces (TO ``base``, generic ``tet``) from padded data.

    Parameters
    ----------
    padded : (X, Y, Z) data array (already extended by ghost layers)
    base : (N, 3) int index of each TO's base data point in ``padded``
    tet : (N,) generic tetrahedron index
    k : operator parameter

    Returns
    -------
    (N, 10) B-coefficients in :func:`splineviz.core.bform.multi_indices` order
    """
    out = np.empty((len(tet), 10))
    table = stencils(k)
    strides = np.array(padded.strides) // padded.itemsize
    flat = np.ravel(padded)
    base_flat = base @ strides
    order = np.argsort(tet, kind="stable")
    bounds = np.searchsorted(tet[order], np.arange(145))
    for t in range(144):
        rows = order[bounds[t]:bounds[t + 1]]
        if len(rows) == 0:
            continue
        offsets, w = table[t]
        out[rows] = flat[base_flat[rows, None] + offsets @ strides] @ w.T
    return out


class TOQuadraticSpline(TetSpline):
    """The spline Q_k(f) of eq. (5.9) over a volume (``model="to-quadratic"``).

    Parameters
    ----------
    volume : Volume
    k : float, default 2
        Operator parameter; Q_2 reproduces quadratics up to a constant and approximates values
        and derivatives with optimal order (Lemma 4, Theorem 9); Q_k is positive for k >= 3.

    Notes
    -----
    The partition lives in index space (h = one grid step): TO centres on the BCC lattice of
    :mod:`splineviz.core.partitions.truncated_octahedra`, data points at the integer points. The
    data are extended by ``GHOST_LAYERS`` linearly extrapolated layers so that the whole data
    box is covered (thesis Remark 1).
    """

    model = "to-quadratic"
    #: polynomial degree of the pieces
    degree = 2

    def __init__(self, volume, k: float = 2):
        super().__init__(volume)
        if not (isinstance(k, numbers.Real) and math.isfinite(k) and k >= 1):
            raise SplineOptionError(f"the to-quadratic model needs a finite k >= 1 (thesis "
                                    f"Q_k), got {k!r}")
        self.k = float(k)
        self._padded = pad_linear(self.volume.data, GHOST_LAYERS)
        stencils(self.k)  # build the tables once, up front

    def local_bform(self, upoints):
        centre, tet, lam = to.locate(upoints)
        base = np.rint(centre - 0.5).astype(np.int64) + GHOST_LAYERS
        coeffs = coefficients(self._padded, base, tet, self.k)
        return coeffs, lam, to.barycentric_matrices()[tet]
