"""Cell tables of the truncated-octahedral partition for the OpenCL ray caster (thesis §5.2).

The ray caster walks the unit cells ``[i, i+1] x [j, j+1] x [k, k+1]`` of the data grid (the
same traversal and skip volume as the other models). The TO lattice has period 2 on every
axis, so the pieces of the spline meeting a cell depend only on the cell's parity class
``(i % 2, j % 2, k % 2)``. For each of the 8 classes this module lists the (TO, generic
tetrahedron) pairs whose tetrahedron meets the cell with positive volume, generated from the
definitions in :mod:`splineviz.core.partitions.truncated_octahedra` by a separating-axis test
(convex polytopes overlap iff no face normal or edge-cross-product axis separates them).
"""

from __future__ import annotations

from functools import cache

import numpy as np

from splineviz.core.partitions import truncated_octahedra as to

#: overlap margin of the separating-axis test (index units)
SAT_EPS = 1e-9

_BOX_EDGES = np.eye(3)


def _overlaps(tet: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Whether tetrahedra overlap the box [lo, hi] with positive volume.

    Parameters
    ----------
    tet : (N, 4, 3) vertices
    lo, hi : (3,)

    Returns
    -------
    (N,) bool
    """
    box = np.stack(np.meshgrid(*zip(lo, hi, strict=True), indexing="ij"), -1).reshape(-1, 3)
    e = tet[:, [1, 2, 3, 2, 3, 3]] - tet[:, [0, 0, 0, 1, 1, 2]]  # (N, 6, 3) edges
    faces = np.stack([np.cross(tet[:, b] - tet[:, a], tet[:, c] - tet[:, a])
                      for a, b, c in ((1, 2, 3), (0, 2, 3), (0, 1, 3), (0, 1, 2))], axis=1)
    cross = np.cross(e[:, :, None, :], _BOX_EDGES[None, None, :, :]).reshape(len(tet), 18, 3)
    axes = np.concatenate([np.broadcast_to(_BOX_EDGES, (len(tet), 3, 3)), faces, cross], axis=1)
    norm = np.linalg.norm(axes, axis=2, keepdims=True)
    axes = np.where(norm > 1e-12, axes / np.where(norm > 0, norm, 1), 0.0)
    pt = np.einsum("nvc,nac->nav", tet, axes)  # (N, A, 4)
    pb = np.einsum("vc,nac->nav", box, axes)   # (N, A, 8)
    valid = norm[..., 0] > 1e-12
    separated = valid & ((pt.max(-1) <= pb.min(-1) + SAT_EPS)
                         | (pb.max(-1) <= pt.min(-1) + SAT_EPS))
    return ~separated.any(axis=1)


#: the modules whose code the truncated-octahedral tables are made from (cache keys)
_TABLE_SOURCES = ("splineviz.core.partitions.truncated_octahedra",
                  "splineviz.core.splines.to_quadratic", "splineviz.core.bform",
                  "splineviz.compute.raycast.to_tables")


@cache
def stencils(k: float = 2) -> list[tuple[np.ndarray, np.ndarray]]:
    """:func:`splineviz.core.splines.to_quadratic.stencils` of Q_k, kept on disk between runs
    (:mod:`splineviz.compute.table_cache`): 144 pairs ``(offsets (K_t, 3) int, weights
    (10, K_t) float)``."""
    from splineviz.compute.table_cache import cached_arrays
    from splineviz.core.splines import to_quadratic

    def make():
        pairs = to_quadratic.stencils(k)
        return {"counts": np.array([len(o) for o, _ in pairs], dtype=np.int64),
                "offsets": np.concatenate([o for o, _ in pairs]).astype(np.int64),
                "weights": np.concatenate([w for _, w in pairs], axis=1)}

    a = cached_arrays(f"to-stencils-k{k:g}", _TABLE_SOURCES, make)
    ends = np.cumsum(a["counts"])
    return [(a["offsets"][e - n:e], a["weights"][:, e - n:e])
            for n, e in zip(a["counts"], ends, strict=True)]


@cache
def cell_classes():
    """:func:`make_cell_classes`, kept on disk between runs."""
    from splineviz.compute.table_cache import cached_arrays

    a = cached_arrays("to-cell-classes", _TABLE_SOURCES,
                      lambda: dict(zip(("start", "centre", "tet"), make_cell_classes(),
                                       strict=True)))
    return a["start"], a["centre"], a["tet"]


def make_cell_classes():
    """The (TO, tetrahedron) pairs meeting a cell, per parity class.

    Returns
    -------
    start : (9,) int32, entries of class c are ``start[c]:start[c+1]``; class
        c = 4 (i % 2) + 2 (j % 2) + (k % 2)
    centre : (E, 3) float32 TO centre relative to the cell corner (i, j, k)
    tet : (E,) int32 generic tetrahedron
    """
    verts = to.generic_tetrahedra()[0]  # (144, 4, 3) relative to the TO centre
    starts, centres, tets = [0], [], []
    for c in range(8):
        corner = np.array([(c >> 2) & 1, (c >> 1) & 1, c & 1], dtype=np.float64)
        lo, hi = corner, corner + 1
        for ctr in to.centres_covering(lo, hi):
            ok = _overlaps(verts + ctr, lo, hi)
            for t in np.flatnonzero(ok):
                centres.append(ctr - corner)
                tets.append(t)
        starts.append(len(tets))
    return (np.array(starts, np.int32), np.array(centres, np.float32).reshape(-1, 3),
            np.array(tets, np.int32))


def walsh_sums(v: np.ndarray) -> np.ndarray:
    """The 8 Walsh sums of values at a TO's data points (in the order of ``DATA_OFFSETS``):
    ``out[m] = sum_i (-1)^popcount(i & m) v[i]``, m's bits 4, 2, 1 the x, y, z signs (m = 0:
    the sum; 4, 2, 1: the differences along x, y, z; ...). Applied twice it gives 8 v.

    Parameters
    ----------
    v : (..., 8)

    Returns
    -------
    (..., 8)
    """
    out = np.array(v, dtype=np.float64)
    for bit in (1, 2, 4):
        lo = [i for i in range(8) if not i & bit]
        a, b = out[..., lo], out[..., [i | bit for i in lo]]
        out[..., lo], out[..., [i | bit for i in lo]] = a + b, a - b
    return out


@cache
def class_points(k: float = 2, words: int = 5) -> dict[str, np.ndarray]:
    """The distinct B-net points of each cell class's pieces as stencils into the data the
    class reads, kept on disk between runs.

    Pieces of one TO share B-net points, so each point is listed once per class, with the bit
    set of the class's pieces (bit ``e - start[c]``) whose B-net holds it: a piece straddles
    the isovalue iff one of its points is <= iso and one is >= iso.

    Parameters
    ----------
    k : the parameter of Q_k
    words : 32-bit words of a class's piece bit set

    Returns
    -------
    dict of arrays:
        ``union`` (U, 3) int data offsets from the cell corner read by the classes, class c's
        being ``union[union_start[c]:union_start[c+1]]`` (``union_start`` (9,));
        ``pt_start`` (9,), class c's points are ``pt_start[c]:pt_start[c+1]``;
        ``rows`` (P+1,), ``cols`` (nnz,) indices into the class's union, ``weights`` (nnz,):
        point p = sum of weights[rows[p]:rows[p+1]] * union values[cols[...]];
        ``pieces`` (P, words) uint32 bit sets;
        the same points from the Walsh sums of the TOs they average (eq. 5.9 weights each TO's
        8 data values, so a point is a short sum of those TOs' :func:`walsh_sums`):
        ``to_start`` (9,), class c's TOs are ``to_start[c]:to_start[c+1]``; ``to_union``
        (T, 8) the union indices (class-local) of each TO's data points in the order of
        ``DATA_OFFSETS``; ``wrows`` (P+1,), ``wcols`` (wnnz,) = 8 * (class-local TO) + Walsh
        index, ``wweights`` (wnnz,): point p = sum of wweights[wrows[p]:wrows[p+1]] * the
        Walsh sums at wcols.
    """
    from splineviz.compute.table_cache import cached_arrays

    def make():
        from splineviz.core import bform
        from splineviz.core.splines import to_quadratic

        start, centre, tet = cell_classes()
        # base data point of each piece's TO relative to the cell corner: centre - 1/2
        base = np.rint(centre.astype(np.float64) - 0.5).astype(np.int64)
        tables = stencils(k)
        alphas = bform.multi_indices(2)
        parts = {}  # (tet, coefficient) -> eq. (5.9) parts, reference TO
        union, union_start, pt_start = [], [0], [0]
        rows, cols, weights, pieces = [0], [], [], []
        tos, to_start, wrows, wcols, wweights = [], [0], [0], [], []
        for c in range(8):
            pts = sorted({p for e in range(start[c], start[c + 1])
                          for p in map(tuple, tables[tet[e]][0] + base[e])})
            where = {p: n for n, p in enumerate(pts)}
            union.extend(pts)
            union_start.append(len(union))
            points = {}  # stencil (union index, weight) pairs -> point of the class
            class_tos = {}  # TO centre (cell-local, doubled to integers) -> class-local index
            for e in range(start[c], start[c + 1]):
                offsets, w = tables[tet[e]]
                idx = [where[tuple(o)] for o in offsets + base[e]]
                for i in range(w.shape[0]):
                    nz = np.flatnonzero(w[i])
                    key = tuple((idx[n], float(w[i, n])) for n in nz)
                    if key not in points:
                        points[key] = len(points)
                        cols.extend(idx[n] for n in nz)
                        weights.extend(w[i, nz])
                        rows.append(len(cols))
                        pieces.append(np.zeros(words, np.uint32))
                        if (tet[e], i) not in parts:
                            parts[tet[e], i] = to_quadratic.coefficient_parts(
                                int(tet[e]), alphas[i], k)
                        for pc, pw in parts[tet[e], i]:
                            ctr = centre[e].astype(np.float64) + pc
                            t = class_tos.setdefault(tuple(np.rint(2 * ctr).astype(int)),
                                                     len(class_tos))
                            if t == len(tos) - to_start[-1]:
                                corners = np.rint(ctr + to.DATA_OFFSETS).astype(np.int64)
                                tos.append([where[tuple(z)] for z in corners])
                            hat = walsh_sums(pw) / 8.0
                            for m in np.flatnonzero(hat):
                                wcols.append(8 * t + m)
                                wweights.append(hat[m])
                        wrows.append(len(wcols))
                    bit = e - start[c]
                    pieces[pt_start[-1] + points[key]][bit >> 5] |= np.uint32(1 << (bit & 31))
            pt_start.append(pt_start[-1] + len(points))
            to_start.append(len(tos))
        return {"union": np.array(union, np.int64), "union_start": np.array(union_start),
                "pt_start": np.array(pt_start), "rows": np.array(rows),
                "cols": np.array(cols), "weights": np.array(weights, np.float64),
                "pieces": np.array(pieces, np.uint32), "to_start": np.array(to_start),
                "to_union": np.array(tos, np.int64), "wrows": np.array(wrows),
                "wcols": np.array(wcols, np.int64),
                "wweights": np.array(wweights, np.float64)}

    return cached_arrays(f"to-class-points-k{k:g}-w{words}", _TABLE_SOURCES, make)


def node_union(k: float = 2, words: int = 5) -> np.ndarray:
    """The data a level-1 octree node (2 x 2 x 2 cells, one of each parity class: class
    ``i << 2 | j << 1 | k`` is the node's cell ``(i, j, k)``) reads, each point once: 125
    distinct points of the 416 that the 8 :func:`class_points` unions list.

    Returns
    -------
    (N, 3) int data offsets from the corner of the node's first cell.
    """
    pts = class_points(k, words)
    start = pts["union_start"]
    return np.unique(np.concatenate([pts["union"][start[c]:start[c + 1]]
                                     + [c >> 2, c >> 1 & 1, c & 1] for c in range(8)]),
                     axis=0)


#: subcells per axis of a cell for :func:`subcell_masks` (odd: the TO centre of the classes
#: 0 and 7 lies inside one subcell, where all 144 pieces meet, instead of on the corners of 8)
SUBCELLS = 5
#: widening of each subcell box (cell units) in :func:`subcell_masks`: it covers the rounding
#: of the ray's cell-local points and of the subcell walk, so the masks stay conservative
SUBCELL_MARGIN = 1e-3


@cache
def subcell_masks(words: int = 5, subcells: int = SUBCELLS) -> np.ndarray:
    """Per cell class and subcell, the bit set of the class's pieces meeting the subcell.

    A cell is split into ``subcells``^3 boxes; a ray segment in the cell can only meet the
    pieces of the subcells it crosses, so the ray caster tests a piece's four planes only when
    its bit is set in the union of those subcells' masks (about a third of a class's pieces
    for a chord of the cell). Each box is widened by :data:`SUBCELL_MARGIN`, so a piece that
    touches the segment within rounding of a crossed subcell is kept. Kept on disk between
    runs.

    Parameters
    ----------
    words : 32-bit words of a class's piece bit set
    subcells : subcells per axis

    Returns
    -------
    (8, subcells, subcells, subcells, words) uint32
        ``[c, a, b, e]``: bit ``p - start[c]`` set when piece p of class c meets the box
        ``[a, a+1] x [b, b+1] x [e, e+1] / subcells`` (cell-local, widened).
    """
    from splineviz.compute.table_cache import cached_arrays

    def make():
        start, centre, tet = cell_classes()
        verts = to.generic_tetrahedra()[0]
        n = subcells
        out = np.zeros((8, n, n, n, words), np.uint32)
        for c in range(8):
            tv = verts[tet[start[c]:start[c + 1]]] + centre[start[c]:start[c + 1], None, :]
            for sub in np.ndindex(n, n, n):
                lo = np.array(sub, np.float64) / n - SUBCELL_MARGIN
                hi = (np.array(sub, np.float64) + 1) / n + SUBCELL_MARGIN
                for bit in np.flatnonzero(_overlaps(tv, lo, hi)):
                    out[(c, *sub, bit >> 5)] |= np.uint32(1 << (bit & 31))
        return {"masks": out}

    return cached_arrays(f"to-subcell-masks-s{subcells}-w{words}", _TABLE_SOURCES,
                         make)["masks"]
