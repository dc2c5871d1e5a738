"""Quasi-interpolation rules of the type-6 splines, their determining sets and averaging rules.

Thesis §4.4 (eq. 4.2, 4.3, Fig. 4.4-4.7) and §6.1.1. The two schemes are

* ``"cubic-c1"``: the cubic C^1 spline S_3^1(Delta_6) of Sorokina and Zeilfelder [SZ07b];
* ``"super-quadratic"``: the quadratic super spline S_2^{0,1}(Delta_6) [NRSZ05, RZNS04a], in
  the reconstruction of ``spec/type6-formulas.md`` (the papers' formula sections were not
  available; see that file and the closing note of issue 3 for what is known).

A B-coefficient is a weighted sum of the 27 data values around the cube centre, eq. (4.3).
The rules are written *once*, for the reference tetrahedron of
:mod:`splineviz.core.partitions.type6`, in the letter notation of the spec (I the centre,
F/B = +-x, R/L = +-y, T/D = +-z, letters add) and transported to the other 23 tetrahedra by the
cube rotations ``FRAMES``. Conventions: the 27 data offsets (a, b, c) in {-1, 0, 1}^3 are
numbered ``9 (a + 1) + 3 (b + 1) + (c + 1)``; masks are float arrays ``(..., 27)``.

Per cube the coefficients live on the *cube domain points* (175 for cubics, 65 for
quadratics). A *determining set* M (§4.3) is a subset from which every other coefficient of
the cube follows from smoothness conditions alone; the *averaging rules* are these conditions
solved one coefficient at a time (Fig. 4.5, 4.7). They are derived here by code from the C^1
conditions (eq. 3.18 / 5.2) that the scheme satisfies inside a cube, never typed in.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from fractions import Fraction
from functools import cache

import numpy as np

from splineviz.core import bform
from splineviz.core.partitions import type6

#: the 27 data offsets (a, b, c) around a cube centre, row n = 9 (a+1) + 3 (b+1) + (c+1)
OFFSETS = np.array(
    [(a, b, c) for a in (-1, 0, 1) for b in (-1, 0, 1) for c in (-1, 0, 1)], dtype=np.int64
)
OFFSETS.flags.writeable = False

#: letters of the spec's notation as offsets in the reference frame (n_F, n_R, n_T)
LETTERS = {
    "I": (0, 0, 0), "F": (1, 0, 0), "B": (-1, 0, 0),
    "R": (0, 1, 0), "L": (0, -1, 0), "T": (0, 0, 1), "D": (0, 0, -1),
}

# The rules of spec/type6-formulas.md for the reference tetrahedron [v0, v1, v2, v3]
# (v2 = (1/2, -1/2, 1/2) on the L side, v3 = (1/2, 1/2, 1/2) on the R side).
CUBIC_C1_RULES = {
    "3000": "3/8 I + 1/12 (F+B+L+R+T+D) + 1/96 (FL+FR+FT+FD+BL+BR+BT+BD+LT+LD+RT+RD)",
    "2100": "3/8 I + 7/48 F + 1/48 B + 1/12 (L+R+T+D) + 1/64 (FL+FR+FT+FD)"
            " + 1/96 (LT+LD+RT+RD) + 1/192 (BL+BR+BT+BD)",
    "2010": "3/8 I + 7/48 (F+L+T) + 1/48 (R+D+B+LT+FL+FT) + 1/96 (RT+BT+FR+FD+LD+BL)",
    "2001": "3/8 I + 7/48 (F+R+T) + 1/48 (L+D+B+RT+FR+FT) + 1/96 (LT+BT+FL+FD+RD+BR)",
    "1200": "1/3 I + 5/24 F + 7/96 (L+R+T+D) + 1/32 (FL+FR+FT+FD) + 1/96 (RT+RD+LT+LD)",
    "1110": "1/3 I + 5/24 F + 1/8 (L+T) + 5/96 (FL+FT) + 1/48 (D+R+LT) + 1/96 (FD+LD+RT+FR)",
    "1101": "1/3 I + 5/24 F + 1/8 (R+T) + 5/96 (FR+FT) + 1/48 (D+L+RT) + 1/96 (FD+RD+LT+FL)",
    "1020": "1/4 I + 1/6 (F+L+T) + 1/12 (LT+FL+FT)",
    "1011": "1/3 I + 5/24 (F+T) + 1/12 FT + 1/24 (L+R) + 1/48 (LT+RT+FL+FR)",
    "1002": "1/4 I + 1/6 (F+R+T) + 1/12 (RT+FR+FT)",
    "0300": "13/48 (I+F) + 5/96 (L+R+T+D+FL+FR+FT+FD) + 1/192 (LT+LD+RT+RD+FLT+FLD+FRT+FRD)",
    "0210": "13/48 (I+F) + 17/192 (L+T+FL+FT) + 1/64 (R+D+FR+FD) + 1/96 (LT+FLT)"
            " + 1/192 (RT+LD+FRT+FLD)",
    "0201": "13/48 (I+F) + 17/192 (R+T+FR+FT) + 1/64 (L+D+FL+FD) + 1/96 (RT+FRT)"
            " + 1/192 (RD+LT+FLT+FRD)",
    "0120": "5/24 (I+F) + 1/8 (L+T+FL+FT) + 1/24 (LT+FLT)",
    "0111": "13/48 (I+F) + 7/48 (T+FT) + 1/32 (L+R+FL+FR) + 1/96 (LT+RT+FLT+FRT)",
    "0102": "5/24 (I+F) + 1/8 (R+T+FR+FT) + 1/24 (RT+FRT)",
    "0030": "1/8 (I+F+L+T+FL+FT+LT+FLT)",
    "0021": "5/24 (I+F+T+FT) + 1/24 (L+FL+LT+FLT)",
    "0012": "5/24 (I+F+T+FT) + 1/24 (R+FR+RT+FRT)",
    "0003": "1/8 (I+F+R+T+FR+FT+RT+FRT)",
}

SUPER_QUADRATIC_RULES = {
    "2000": "1/4 I + 1/8 (F+B+L+R+T+D)",
    "1100": "1/4 (I+F) + 1/8 (L+R+T+D)",
    "1010": "1/4 (I+F+L+T)",
    "1001": "1/4 (I+F+R+T)",
    "0200": "1/4 (I+F) + 1/16 (L+R+T+D+FL+FR+FT+FD)",
    "0110": "1/4 (I+F) + 1/8 (L+T+FL+FT)",
    "0101": "1/4 (I+F) + 1/8 (R+T+FR+FT)",
    "0020": "1/8 (I+F+L+T+FL+FT+LT+FLT)",
    "0011": "1/4 (I+F+T+FT)",
    "0002": "1/8 (I+F+R+T+FR+FT+RT+FRT)",
}

_TERM = re.compile(r"\s*(\d+/\d+|\d+)\s*(\(([A-Z+\s]+)\)|([A-Z]+))\s*")


def parse_rule(text: str) -> dict[tuple[int, int, int], Fraction]:
    """Parse one rule of the spec's letter notation into {offset: weight}.

    ``"1/4 I + 1/8 (F+B)"`` -> {(0,0,0): 1/4, (1,0,0): 1/8, (-1,0,0): 1/8}.
    """
    out: dict[tuple[int, int, int], Fraction] = {}
    for term in _split_terms(text):
        m = _TERM.fullmatch(term)
        if m is None:
            raise ValueError(f"cannot parse rule term {term!r}")
        weight = Fraction(m.group(1))
        names = (m.group(3) or m.group(4)).replace(" ", "").split("+")
        for name in names:
            off = tuple(int(sum(LETTERS[ch][ax] for ch in name)) for ax in range(3))
            if len(set(name)) != len(name) or max(map(abs, off)) > 1:
                raise ValueError(f"bad data letter combination {name!r}")
            out[off] = out.get(off, Fraction(0)) + weight
    return out


def _split_terms(text: str) -> list[str]:
    """Split at the '+' signs that are outside parentheses."""
    terms, depth, cur = [], 0, ""
    for ch in text:
        depth += ch == "("
        depth -= ch == ")"
        if ch == "+" and depth == 0:
            terms.append(cur)
            cur = ""
        else:
            cur += ch
    terms.append(cur)
    return [t for t in terms if t.strip()]


def _offset_row(off) -> int:
    a, b, c = (int(v) for v in off)
    return 9 * (a + 1) + 3 * (b + 1) + (c + 1)


@dataclass(frozen=True)
class Type6Scheme:
    """A quasi-interpolation scheme on Delta_6 with its per-cube structure.

    Attributes
    ----------
    name : model name
    degree : polynomial degree d
    tet_masks : (24, n_d, 27) weights of the data offsets for every B-coefficient of every
        generic tetrahedron (multi-index order of :func:`bform.multi_indices`)
    cube_points : (P, 3) cube domain points relative to the cube centre
    tet_points : (24, n_d) index into ``cube_points`` of each coefficient's domain point
    cube_masks : (P, 27) weights per cube domain point
    determining : (|M|,) indices into ``cube_points`` of the determining set M_Q
    rules : list of (target, sources (k,), weights (k,)) in application order: the averaging
        rules that give every coefficient outside M_Q from already known ones
    averaging : (P, |M|) the composed rules: cube coefficients = averaging @ b_M
    """

    name: str
    degree: int
    tet_masks: np.ndarray
    cube_points: np.ndarray
    tet_points: np.ndarray
    cube_masks: np.ndarray
    determining: np.ndarray
    rules: list
    averaging: np.ndarray

    @property
    def determining_masks(self) -> np.ndarray:
        """(|M|, 27) data weights of the determining-set coefficients."""
        return self.cube_masks[self.determining]


def reference_masks(rules: dict[str, str], degree: int) -> np.ndarray:
    """(n_d, 27) data weights of the reference tetrahedron's coefficients, eq. (4.3)."""
    idx = bform.index_map(degree)
    out = np.zeros((bform.n_coefficients(degree), 27))
    if set(rules) != {"".join(map(str, k)) for k in idx}:
        raise ValueError("rules must give every multi-index of the degree exactly once")
    for key, text in rules.items():
        row = idx[tuple(int(ch) for ch in key)]
        for off, w in parse_rule(text).items():
            out[row, _offset_row(off)] = float(w)
    return out


def transport_masks(ref: np.ndarray) -> np.ndarray:
    """Map reference masks to the 24 generic tetrahedra by the cube rotations.

    Offset (a, b, c) of the reference frame becomes a n_F + b n_R + c n_T.

    Parameters
    ----------
    ref : (n_d, 27)

    Returns
    -------
    (24, n_d, 27)
    """
    rotated = np.einsum("tij,oj->toi", type6.FRAMES, OFFSETS)  # (24, 27, 3)
    dest = np.array([[_offset_row(o) for o in rows] for rows in np.rint(rotated).astype(int)])
    out = np.zeros((type6.N_TETS,) + ref.shape)
    for t in range(type6.N_TETS):
        out[t][:, dest[t]] = ref
    return out


def _point_keys(points: np.ndarray, degree: int) -> np.ndarray:
    """Exact integer keys 2 d x of domain points (coordinates are multiples of 1/(2d))."""
    return np.rint(np.asarray(points) * 2 * degree).astype(np.int64)


@cache
def cube_domain_points(degree: int):
    """Distinct domain points of one cube and their position in each generic tetrahedron.

    Returns
    -------
    points : (P, 3) relative to the cube centre (P = 65 for d = 2, 175 for d = 3)
    tet_points : (24, n_d) int64 index into ``points``
    """
    xi = bform.domain_points(type6.VERTICES, degree)  # (24, n_d, 3)
    keys = _point_keys(xi, degree).reshape(-1, 3)
    uniq, inverse = np.unique(keys, axis=0, return_inverse=True)
    points = uniq / (2.0 * degree)
    return points, inverse.reshape(type6.N_TETS, -1)


def _c1_conditions(degree: int, points: np.ndarray, faces, vertex_only: bool):
    """Rows of the C^1 conditions (eq. 5.2) across the given in-cube faces.

    For tetrahedra T, T' sharing face F (opposite vertices v_m in T, w in T'), with
    phi = barycentric coordinates of w w.r.t. T: for every degree-(d-1) multi-index gamma on F,
    b'(gamma + w) = sum_k phi_k b(gamma + v_k). With ``vertex_only`` only gamma = (d-1) v0
    (C^1 at the cube centre, the super-smoothness of S_2^{0,1}).

    Returns
    -------
    (K, P) float array; each row r satisfies r @ b = 0 for the coefficients b of a cube.
    """
    keymap = {tuple(k): n for n, k in enumerate(_point_keys(points, degree))}
    nb_tet, nb_off, nb_opp = type6.face_neighbours()
    mats = type6.barycentric_matrices()
    rows = []
    for t, m in faces:
        s = nb_tet[t, m]
        w = type6.VERTICES[s, nb_opp[t, m]]
        phi = mats[t] @ np.append(w, 1.0)
        for gamma in bform.multi_indices(degree - 1):
            if gamma[m] != 0:
                continue
            if vertex_only and gamma[0] != degree - 1:
                continue
            base = gamma @ type6.VERTICES[t]
            row = np.zeros(len(points))
            row[keymap[tuple(_point_keys((base + w) / degree, degree))]] -= 1.0
            for k in range(4):
                p = (base + type6.VERTICES[t, k]) / degree
                row[keymap[tuple(_point_keys(p, degree))]] += phi[k]
            rows.append(row)
    return np.array(rows)


def interior_faces(kind: str = "all"):
    """In-cube faces as (t, m) pairs, each once.

    ``kind``: ``"all"`` (36 faces), ``"pyramid"`` (the 24 faces [v0, v1, corner] inside a
    pyramid) or ``"between"`` (the 12 faces [v0, v2, v3] between pyramids).
    """
    nb_tet, nb_off, _ = type6.face_neighbours()
    out = []
    for t in range(type6.N_TETS):
        for m in range(4):
            s = nb_tet[t, m]
            if nb_off[t, m].any() or s < t:
                continue
            if kind == "pyramid" and m == 1 or kind == "between" and m != 1:
                continue
            out.append((t, m))
    return out


def derive_rules(conditions: np.ndarray, known: np.ndarray, n_points: int):
    """Solve smoothness conditions one unknown at a time (repeated averaging).

    Parameters
    ----------
    conditions : (K, P) rows r with r @ b = 0
    known : (|M|,) indices of the determining set

    Returns
    -------
    rules : list of (target, sources, weights)
    averaging : (P, |M|) b = averaging @ b_M

    Raises
    ------
    ValueError
        If the conditions do not determine every coefficient from ``known``.
    """
    is_known = np.zeros(n_points, dtype=bool)
    is_known[known] = True
    # expression of every known coefficient in terms of the determining set
    expr = np.zeros((n_points, len(known)))
    expr[known, np.arange(len(known))] = 1.0
    rules = []
    support = conditions != 0
    progress = True
    while progress and not is_known.all():
        progress = False
        unknown_count = (support & ~is_known).sum(axis=1)
        for r in np.flatnonzero(unknown_count == 1):
            row = conditions[r]
            pending = np.flatnonzero(support[r] & ~is_known)
            if len(pending) != 1:
                continue  # solved by an earlier row of this sweep
            target = int(pending[0])
            others = np.flatnonzero(support[r] & (np.arange(n_points) != target))
            weights = -row[others] / row[target]
            rules.append((target, others, weights))
            expr[target] = weights @ expr[others]
            is_known[target] = True
            progress = True
        if not progress and not is_known.all():
            # no single condition isolates a coefficient: combine conditions. Every pending
            # coefficient whose unit vector lies in the row space of the conditions restricted
            # to the pending ones gets a rule from that combination.
            pend = np.flatnonzero(~is_known)
            c_u = conditions[:, pend]
            combo = np.linalg.pinv(c_u)  # (|U|, K): combo @ c_u = I where determined
            hit = np.abs(combo @ c_u - np.eye(len(pend))).max(axis=1) < 1e-9
            c_k = conditions[:, is_known]
            known_idx = np.flatnonzero(is_known)
            for u in np.flatnonzero(hit):
                weights = -(combo[u] @ c_k)
                weights[np.abs(weights) < 1e-12] = 0.0
                nz = np.flatnonzero(weights)
                rules.append((int(pend[u]), known_idx[nz], weights[nz]))
                expr[pend[u]] = weights[nz] @ expr[known_idx[nz]]
            is_known[pend[hit]] = True
            progress = bool(hit.any())
    if not is_known.all():
        raise ValueError(f"{(~is_known).sum()} coefficients are not determined by the rules")
    return rules, expr


def apply_rules(known_values: np.ndarray, scheme: Type6Scheme) -> np.ndarray:
    """All cube coefficients from the determining set by the averaging rules, in order.

    This is the step the ray caster runs per cube (§6.1.1): read b_M, average.

    Parameters
    ----------
    known_values : (N, |M|) determining-set coefficients of N cubes

    Returns
    -------
    (N, P) coefficients on the cube domain points
    """
    b_m = np.asarray(known_values, dtype=np.float64)
    out = np.empty((b_m.shape[0], len(scheme.cube_points)))
    out[:, scheme.determining] = b_m
    for target, sources, weights in scheme.rules:
        out[:, target] = out[:, sources] @ weights
    return out


def _determining_set(name: str, degree: int, tet_points: np.ndarray) -> np.ndarray:
    """Indices of M_Q in the cube domain points.

    cubic-c1 (§4.4): xi_00kl (k + l = 3) and xi_0111 of every tetrahedron: the 8 cube
    vertices, 2 points on each of the 12 cube edges and the 24 face-triangle centroids (56).
    super-quadratic: the 8 cube vertices and 12 edge midpoints (xi_0020, xi_0002, xi_0011),
    plus the cube centre xi_2000 and xi_1100 of the three tetrahedra with n_F = +x, +y, +z
    (value and gradient at the centre): 24; see :func:`scheme` for why not 20.
    """
    idx = bform.index_map(degree)
    if name == "cubic-c1":
        keys = [(0, 0, 3, 0), (0, 0, 2, 1), (0, 0, 1, 2), (0, 0, 0, 3), (0, 1, 1, 1)]
        picks = {int(tet_points[t, idx[k]]) for t in range(type6.N_TETS) for k in keys}
        return np.array(sorted(picks))
    picks = {int(tet_points[t, idx[k]]) for t in range(type6.N_TETS)
             for k in [(0, 0, 2, 0), (0, 0, 1, 1), (0, 0, 0, 2)]}
    centre = int(tet_points[0, idx[(2, 0, 0, 0)]])
    axes = []
    for axis in range(3):
        t = int(next(t for t in range(type6.N_TETS) if type6.FRAMES[t][axis, 0] == 1))
        axes.append(int(tet_points[t, idx[(1, 1, 0, 0)]]))
    return np.array(sorted(picks) + [centre] + axes)


@cache
def scheme(name: str) -> Type6Scheme:
    """Build the tables of ``"cubic-c1"`` or ``"super-quadratic"`` (computed once).

    The averaging rules use the C^1 conditions that the scheme satisfies inside a cube:
    across all 36 interior faces for cubic-c1; for super-quadratic across the 24 faces
    [v0, v1, corner] and, at the cube centre only, across all faces (super-smoothness). The
    reconstructed quadratic rules are not C^1 at the cube vertices, so the 20 coefficients on
    the cube edges do not determine the interior: its determining set needs 24 values.
    """
    if name == "cubic-c1":
        degree, rules_text = 3, CUBIC_C1_RULES
    elif name == "super-quadratic":
        degree, rules_text = 2, SUPER_QUADRATIC_RULES
    else:
        raise ValueError(f"unknown type-6 scheme {name!r}")
    masks = transport_masks(reference_masks(rules_text, degree))
    points, tet_points = cube_domain_points(degree)
    cube_masks = np.zeros((len(points), 27))
    cube_masks[tet_points.ravel()] = masks.reshape(-1, 27)
    determining = _determining_set(name, degree, tet_points)
    if name == "cubic-c1":
        cond = _c1_conditions(degree, points, interior_faces("all"), vertex_only=False)
    else:
        cond = np.concatenate([
            _c1_conditions(degree, points, interior_faces("pyramid"), vertex_only=False),
            _c1_conditions(degree, points, interior_faces("all"), vertex_only=True),
        ])
    rules, averaging = derive_rules(cond, determining, len(points))
    for arr in (masks, points, tet_points, cube_masks, determining, averaging):
        arr.flags.writeable = False
    return Type6Scheme(name, degree, masks, points, tet_points, cube_masks, determining,
                       rules, averaging)
