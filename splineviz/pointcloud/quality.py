"""Triangle-mesh quality measures (thesis §7.3, Fig. 7.1).

Conventions: ``vertices (V, 3)`` float64, ``faces (F, 3)`` int; reference points ``(N, 3)``.
The radius ratio of a triangle is ``2 r_in / r_circ`` (1 for an equilateral triangle, 0 for a
degenerate one).  The thesis reports the *diameter* ratio of incircle to circumcircle, whose
maximum is 0.5: it is half of ours, so its 0.46-0.47 are 0.92-0.94 here.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from splineviz.core.errors import SplinevizError
from splineviz.core.points import PointCloud


class MeshQualityError(SplinevizError, ValueError):
    """A mesh whose quality cannot be measured (wrong shapes, no faces)."""


def radius_ratios(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """``2 r_in / r_circ`` per triangle, shape ``(F,)``.

    With side lengths ``a, b, c`` and semi-perimeter ``s``: ``r_in = A / s`` and
    ``r_circ = abc / (4 A)``, so ``2 r_in / r_circ = 8 A^2 / (s a b c)``
    ``= (b + c - a)(c + a - b)(a + b - c) / (abc)`` (Heron), which avoids the area's sign.
    """
    p = vertices[faces]
    a = np.linalg.norm(p[:, 1] - p[:, 2], axis=1)
    b = np.linalg.norm(p[:, 2] - p[:, 0], axis=1)
    c = np.linalg.norm(p[:, 0] - p[:, 1], axis=1)
    num = np.maximum(b + c - a, 0) * np.maximum(c + a - b, 0) * np.maximum(a + b - c, 0)
    den = a * b * c
    return np.divide(num, den, out=np.zeros_like(num), where=den > 0)


def edge_face_counts(faces: np.ndarray):
    """Unique undirected edges ``(E, 2)`` and the number of faces on each ``(E,)``."""
    e = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]),
                axis=1).astype(np.int64)
    # one int64 key per edge, ordered as the rows (np.unique over rows sorts structured
    # records, several times slower on a dense cloud's mesh)
    n = int(e.max()) + 1 if len(e) else 1
    keys, counts = np.unique(e[:, 0] * n + e[:, 1], return_counts=True)
    return np.stack([keys // n, keys % n], axis=1), counts


def valences(n_vertices: int, edges: np.ndarray) -> np.ndarray:
    """Number of edges at each vertex, ``(V,)``."""
    return np.bincount(edges.ravel(), minlength=n_vertices)


def point_to_triangle_distance(points: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """Exact distance of points to triangles, pairwise.

    Parameters
    ----------
    points : (M, 3)
    tri : (M, 3, 3) one triangle per point

    Returns
    -------
    (M,) distances (Ericson, Real-Time Collision Detection, §5.1.5, vectorised).
    """
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    ab, ac, ap = b - a, c - a, points - a

    def dot(u, v):
        return np.einsum("ij,ij->i", u, v)

    d1, d2 = dot(ab, ap), dot(ac, ap)
    bp = points - b
    d3, d4 = dot(ab, bp), dot(ac, bp)
    cp = points - c
    d5, d6 = dot(ab, cp), dot(ac, cp)
    va = d3 * d6 - d5 * d4
    vb = d5 * d2 - d1 * d6
    vc = d1 * d4 - d3 * d2
    denom = va + vb + vc
    with np.errstate(divide="ignore", invalid="ignore"):
        v = vb / denom
        w = vc / denom
    closest = a + ab * v[:, None] + ac * w[:, None]  # interior case
    # edge regions
    with np.errstate(divide="ignore", invalid="ignore"):
        t_ab = d1 / (d1 - d3)
        t_ac = d2 / (d2 - d6)
        t_bc = (d4 - d3) / ((d4 - d3) + (d5 - d6))
    m_bc = (va <= 0) & (d4 - d3 >= 0) & (d5 - d6 >= 0)
    closest[m_bc] = (b + (c - b) * t_bc[:, None])[m_bc]
    m_ac = (vb <= 0) & (d2 >= 0) & (d6 <= 0)
    closest[m_ac] = (a + ac * t_ac[:, None])[m_ac]
    m_ab = (vc <= 0) & (d1 >= 0) & (d3 <= 0)
    closest[m_ab] = (a + ab * t_ab[:, None])[m_ab]
    # vertex regions
    m_c = (d6 >= 0) & (d5 <= d6)
    closest[m_c] = c[m_c]
    m_b = (d3 >= 0) & (d4 <= d3)
    closest[m_b] = b[m_b]
    m_a = (d1 <= 0) & (d2 <= 0)
    closest[m_a] = a[m_a]
    bad = ~np.isfinite(closest).all(axis=1)  # degenerate triangles: nearest corner
    if bad.any():
        corner = np.argmin(np.linalg.norm(tri[bad] - points[bad, None], axis=2), axis=1)
        closest[bad] = tri[bad][np.arange(bad.sum()), corner]
    return np.linalg.norm(points - closest, axis=1)


#: points per block of :func:`distance_to_mesh`
DISTANCE_BLOCK = 131072


def distance_to_mesh(points: np.ndarray, vertices: np.ndarray, faces: np.ndarray,
                     candidates: int = 16, return_faces: bool = False):
    """Distance of each point to the triangle mesh, ``(M,)``.

    The exact point-triangle distance is taken over the ``candidates`` triangles whose
    centroids are nearest; a triangle farther than that is farther than the nearest centroid
    distance minus its circumradius, which the candidate count keeps below the result on the
    meshes measured here (near-uniform triangles).  With ``return_faces``, also the index
    ``(M,)`` of the nearest triangle: ``(distances, face ids)``.
    """
    cent = vertices[faces].mean(axis=1)
    k = min(candidates, len(faces))
    tree = cKDTree(cent)
    best = np.full(len(points), np.inf)
    nearest = np.zeros(len(points), dtype=np.int64)
    # in blocks: the candidates' (M, k) ids and (M, 3, 3) triangles of a dense scan's
    # millions of points took gigabytes at once
    for lo in range(0, len(points), DISTANCE_BLOCK):
        block = points[lo:lo + DISTANCE_BLOCK]
        _, idx = tree.query(block, k=k)
        idx = idx.reshape(len(block), k)
        out = best[lo:lo + DISTANCE_BLOCK]
        near = nearest[lo:lo + DISTANCE_BLOCK]
        for j in range(k):
            d = point_to_triangle_distance(block, vertices[faces[idx[:, j]]])
            closer = d < out
            out[closer] = d[closer]
            near[closer] = idx[closer, j]
    return (best, nearest) if return_faces else best


def face_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Unit normals ``(F, 3)`` of the triangles (zero for degenerate ones)."""
    p = vertices[faces]
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    length = np.linalg.norm(n, axis=1, keepdims=True)
    return np.divide(n, length, out=np.zeros_like(n), where=length > 0)


def area_samples(vertices: np.ndarray, faces: np.ndarray, n: int, seed: int = 0):
    """``n`` points uniformly distributed over the mesh's area.

    Returns
    -------
    points : (n, 3)
    face_ids : (n,) the triangle each point lies on
    """
    p = vertices[faces]
    area = np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
    rng = np.random.default_rng(seed)
    tri = rng.choice(len(faces), n, p=area / area.sum())
    u, w = rng.random(n), rng.random(n)
    flip = u + w > 1  # folded back into the triangle: uniform over its area
    u[flip], w[flip] = 1 - u[flip], 1 - w[flip]
    pts = p[tri, 0] * (1 - u - w)[:, None] + p[tri, 1] * u[:, None] + p[tri, 2] * w[:, None]
    return pts, tri


def surface_agreement(vertices: np.ndarray, faces: np.ndarray, true_vertices: np.ndarray,
                      true_faces: np.ndarray, threshold: float, true_samples=None,
                      n_samples: int = 100000, seed: int = 0) -> dict:
    """How well a mesh reproduces a known surface (the reconstruction measures of Knapitsch
    et al.'s Tanks and Temples and Mescheder et al.'s Occupancy Networks).

    Samples of the mesh are measured against the true mesh (accuracy) and samples of the true
    surface against the mesh (completeness), both with exact point-triangle distances.

    Parameters
    ----------
    vertices (V, 3), faces (F, 3) : the mesh
    true_vertices (T, 3), true_faces (G, 3) : the true surface; its triangles should be small
        (:func:`distance_to_mesh` looks at the nearest centroids)
    threshold : float
        Distance under which a sample counts as matched, for the F-score.
    true_samples : tuple (points (M, 3), face ids (M,)), optional
        The part of the true surface the mesh should cover (e.g. the part a scanner saw);
        default ``n_samples`` area-uniform samples of the whole true surface.
    n_samples : int
        Area-uniform samples of the mesh (and of the truth when not given).

    Returns
    -------
    dict with ``chamfer`` (mean of the two directions' mean distances), ``precision`` and
    ``recall`` (fractions of mesh / true samples within ``threshold`` of the other surface),
    ``fscore`` (their harmonic mean), ``normal_consistency`` (mean of the two directions'
    mean ``|n . n'|`` between a sample's triangle and the nearest one on the other surface),
    ``hausdorff`` (the larger of ``accuracy_max`` and ``completeness_max``, the farthest
    mesh sample from the truth and true sample from the mesh).
    """
    vertices, faces = _as_arrays((vertices, faces))
    true_vertices, true_faces = _as_arrays((true_vertices, true_faces))
    if true_samples is None:
        true_samples = area_samples(true_vertices, true_faces, n_samples, seed + 1)
    t_pts, t_tri = true_samples
    m_pts, m_tri = area_samples(vertices, faces, n_samples, seed)
    n_mesh, n_true = face_normals(vertices, faces), face_normals(true_vertices, true_faces)
    d_acc, near_true = distance_to_mesh(m_pts, true_vertices, true_faces, return_faces=True)
    d_comp, near_mesh = distance_to_mesh(t_pts, vertices, faces, return_faces=True)
    precision = float(np.mean(d_acc <= threshold))
    recall = float(np.mean(d_comp <= threshold))
    nc_acc = np.abs(np.einsum("ij,ij->i", n_mesh[m_tri], n_true[near_true])).mean()
    nc_comp = np.abs(np.einsum("ij,ij->i", n_true[t_tri], n_mesh[near_mesh])).mean()
    return {
        "chamfer": float(0.5 * (d_acc.mean() + d_comp.mean())),
        "precision": precision,
        "recall": recall,
        "fscore": 2 * precision * recall / (precision + recall) if precision + recall else 0.0,
        "normal_consistency": float(0.5 * (nc_acc + nc_comp)),
        "accuracy_max": float(d_acc.max()),
        "completeness_max": float(d_comp.max()),
        "hausdorff": float(max(d_acc.max(), d_comp.max())),
    }


def surface_samples(vertices: np.ndarray, faces: np.ndarray, per_face: int = 4) -> np.ndarray:
    """Vertices, edge midpoints and interior points of every face: samples of the surface."""
    p = vertices[faces]
    bary = [(1 / 3, 1 / 3, 1 / 3), (0.5, 0.5, 0), (0, 0.5, 0.5), (0.5, 0, 0.5),
            (2 / 3, 1 / 6, 1 / 6), (1 / 6, 2 / 3, 1 / 6), (1 / 6, 1 / 6, 2 / 3)][: 3 + per_face]
    samples = [vertices] + [np.einsum("k,fkc->fc", np.array(w), p) for w in bary]
    return np.concatenate(samples)


def mesh_quality(mesh, reference=None) -> dict:
    """Quality of a triangle mesh, optionally against the points it was built from (§7.3).

    Parameters
    ----------
    mesh : pyvista.PolyData or tuple (vertices (V, 3), faces (F, 3))
    reference : PointCloud or (N, 3) array_like, optional
        Input points for ``hausdorff`` (two-sided: the larger of ``hausdorff_points_to_mesh``,
        the farthest input point from the mesh, and ``hausdorff_mesh_to_points``, the farthest
        mesh sample from the points, which no mesh of the surface can bring below the
        largest gap of the sampling) and ``rms_distance`` (root mean square distance of the
        points to the mesh).

    Returns
    -------
    dict with ``radius_ratio_mean``, ``radius_ratio_min`` (2 r_in / r_circ),
    ``valence6_fraction`` (over interior vertices), ``valence_histogram`` (dict valence ->
    count, interior vertices), ``hausdorff``, ``hausdorff_points_to_mesh``,
    ``hausdorff_mesh_to_points``, ``rms_distance`` (NaN without reference),
    ``boundary_edges``, ``non_manifold_edges``, ``n_vertices``, ``n_faces``.
    """
    vertices, faces = _as_arrays(mesh)
    edges, counts = edge_face_counts(faces)
    val = valences(len(vertices), edges)
    on_border = np.zeros(len(vertices), dtype=bool)
    on_border[edges[counts == 1].ravel()] = True
    used = np.zeros(len(vertices), dtype=bool)
    used[faces.ravel()] = True
    interior = used & ~on_border
    hist_v, hist_c = np.unique(val[interior], return_counts=True)
    rr = radius_ratios(vertices, faces)
    out = {
        "radius_ratio_mean": float(rr.mean()),
        "radius_ratio_min": float(rr.min()),
        "valence6_fraction": float(np.mean(val[interior] == 6)) if interior.any() else 0.0,
        "valence_histogram": {int(v): int(c) for v, c in zip(hist_v, hist_c, strict=True)},
        "hausdorff": float("nan"),
        "hausdorff_points_to_mesh": float("nan"),
        "hausdorff_mesh_to_points": float("nan"),
        "rms_distance": float("nan"),
        "points_to_mesh_p99": float("nan"),
        "boundary_edges": int(np.sum(counts == 1)),
        "non_manifold_edges": int(np.sum(counts > 2)),
        "n_vertices": int(used.sum()),
        "n_faces": int(len(faces)),
    }
    if reference is not None:
        pts = reference.points if isinstance(reference, PointCloud) else \
            PointCloud(reference).points
        d_pm = distance_to_mesh(pts, vertices, faces)
        d_mp, _ = cKDTree(pts).query(surface_samples(vertices, faces))
        out["hausdorff_points_to_mesh"] = float(d_pm.max())
        # a few stray scan points set the maximum; the 99th percentile shows where the mesh
        # leaves out covered parts (thin features, borders)
        out["points_to_mesh_p99"] = float(np.percentile(d_pm, 99))
        out["hausdorff_mesh_to_points"] = float(d_mp.max())
        out["hausdorff"] = max(out["hausdorff_points_to_mesh"], out["hausdorff_mesh_to_points"])
        out["rms_distance"] = float(np.sqrt(np.mean(d_pm**2)))
    return out


def _as_arrays(mesh):
    if isinstance(mesh, tuple) and len(mesh) == 2:
        vertices, faces = (np.asarray(m) for m in mesh)
    elif hasattr(mesh, "faces") and hasattr(mesh, "points"):
        if hasattr(mesh, "is_all_triangles") and not mesh.is_all_triangles:
            mesh = mesh.triangulate()
        vertices = np.asarray(mesh.points, dtype=np.float64)
        faces = np.asarray(mesh.faces).reshape(-1, 4)[:, 1:]
    else:
        raise MeshQualityError("mesh must be a pyvista.PolyData or a (vertices, faces) pair")
    vertices = np.asarray(vertices, dtype=np.float64)
    faces = np.asarray(faces, dtype=np.int64)
    if vertices.ndim != 2 or vertices.shape[1] != 3 or faces.ndim != 2 or faces.shape[1] != 3:
        raise MeshQualityError(
            f"expected vertices (V, 3) and faces (F, 3), got {vertices.shape} and {faces.shape}")
    if len(faces) == 0:
        raise MeshQualityError("the mesh has no faces")
    if faces.min() < 0 or faces.max() >= len(vertices):
        raise MeshQualityError("faces refer to vertices that do not exist")
    return vertices, faces
