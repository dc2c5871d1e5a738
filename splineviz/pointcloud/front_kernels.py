"""Compiled (numba) geometry tests of the advancing front (:mod:`.advancing_front`).

A front step asks a handful of questions of small sets (the front vertices and edges near a
candidate triangle, the triangles under it, the input points around a probe).  NumPy's
per-call overhead (microseconds per operation on arrays of a few dozen rows) made those tests
most of the front's time; here each question is one compiled call.

Conventions: positions ``(V, 3)`` float64, unit normals ``(V, 3)``; a *hash grid* files items
(front vertices, triangles) under the integer cell ``floor(x / cell)`` of their position in
linked lists: ``head (S,)`` the first item of each hash slot (-1 for none), ``nxt (C,)`` /
``prv (C,)`` the neighbours of an item in its slot's list, ``cells (C, 3)`` int64 the cell of
each item (items of other cells that share the slot are skipped by comparing it).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from splineviz.pointcloud.vec3 import cross, dot, norm, row, sub


@numba.njit(cache=True, inline="always")
def _slot(i, j, k, mask):
    # three large primes (Teschner et al. 2003, optimized spatial hashing)
    return ((i * 73856093) ^ (j * 19349663) ^ (k * 83492791)) & mask


@numba.njit(cache=True)
def grid_insert(head, nxt, prv, cells, item, i, j, k):
    """File ``item`` under cell ``(i, j, k)`` (see the module docstring)."""
    s = _slot(i, j, k, len(head) - 1)
    cells[item, 0], cells[item, 1], cells[item, 2] = i, j, k
    first = head[s]
    nxt[item] = first
    prv[item] = -1
    if first >= 0:
        prv[first] = item
    head[s] = item


@numba.njit(cache=True)
def grid_remove(head, nxt, prv, cells, item):
    """Take ``item`` out of its cell's list."""
    p, q = prv[item], nxt[item]
    if p >= 0:
        nxt[p] = q
    else:
        head[_slot(cells[item, 0], cells[item, 1], cells[item, 2], len(head) - 1)] = q
    if q >= 0:
        prv[q] = p
    nxt[item] = -1
    prv[item] = -1


@numba.njit(cache=True)
def _gather(head, nxt, cells, cell, x, reach, out):
    """Items filed in the cells within ``reach`` cells of ``x``'s cell, written to ``out``;
    returns their number (``out`` grows by doubling)."""
    ci = int(math.floor(x[0] / cell))
    cj = int(math.floor(x[1] / cell))
    ck = int(math.floor(x[2] / cell))
    mask = len(head) - 1
    count = 0
    for i in range(ci - reach, ci + reach + 1):
        for j in range(cj - reach, cj + reach + 1):
            for k in range(ck - reach, ck + reach + 1):
                item = head[_slot(i, j, k, mask)]
                while item >= 0:
                    if cells[item, 0] == i and cells[item, 1] == j and cells[item, 2] == k:
                        if count == len(out):
                            bigger = np.empty(2 * len(out), dtype=np.int64)
                            bigger[:count] = out
                            out = bigger
                        out[count] = item
                        count += 1
                    item = nxt[item]
    return out[:count]


@numba.njit(cache=True)
def vertices_near(head, nxt, cells, cell, V, N, x, radius, n, use_normal):
    """Front vertices within ``radius`` of ``x`` nearest first; with ``use_normal`` only
    those whose normal faces along ``n`` (not the back of a thin sheet).

    Returns
    -------
    (K,) int64 vertex ids.
    """
    found = _gather(head, nxt, cells, cell, x, int(math.ceil(radius / cell)),
                    np.empty(64, dtype=np.int64))
    keep = np.empty(len(found), dtype=np.int64)
    dist = np.empty(len(found))
    count = 0
    for v in found:
        d = math.sqrt((V[v, 0] - x[0]) ** 2 + (V[v, 1] - x[1]) ** 2 + (V[v, 2] - x[2]) ** 2)
        if d > radius:
            continue
        if use_normal and N[v, 0] * n[0] + N[v, 1] * n[1] + N[v, 2] * n[2] <= 0:
            continue
        keep[count] = v
        dist[count] = d
        count += 1
    # nearest first, ties by vertex id: the order does not depend on the grid's lists
    by_id = np.argsort(keep[:count])
    order = by_id[np.argsort(dist[:count][by_id], kind="mergesort")]
    out = keep[:count][order]
    return out


@numba.njit(cache=True)
def covered(heads, level_start, level_cell, level_radius, nxt, cells, geometry, probes, centre,
            length, margin, height):
    """Whether any of ``probes (K, 3)`` projects strictly inside (barycentric coordinates above
    ``margin``) an existing triangle, closer than ``height * length`` to its plane.

    Triangles are filed by centroid in a grid per size class (level ``l``'s hash slots are
    ``heads[level_start[l]:level_start[l + 1]]``, a power of two; its cells ``level_cell[l]``
    wide; ``level_radius[l]`` the largest centroid-to-corner distance filed in it, negative
    while empty): a probe over a triangle lies within that distance
    plus the height limit of its centroid, so each level is searched out to the cells that
    bound can reach.  One grid of cells as wide as the longest triangles gathered hundreds of
    small ones per question on strongly graded meshes.  ``geometry (F, 19)``: per triangle its
    first corner, two edge vectors, unit normal, the Gram entries ``e1.e1, e1.e2, e2.e2``, its
    centroid and the largest distance of a corner from the centroid."""
    limit = height * length
    spread = 0.0
    for p in range(probes.shape[0]):
        spread = max(spread, math.sqrt((probes[p, 0] - centre[0]) ** 2
                                       + (probes[p, 1] - centre[1]) ** 2
                                       + (probes[p, 2] - centre[2]) ** 2))
    for lev in range(len(level_cell)):
        if level_radius[lev] < 0:
            continue
        cell = level_cell[lev]
        reach = int(math.ceil((level_radius[lev] + limit + spread) / cell))
        ids = _gather(heads[level_start[lev]:level_start[lev + 1]], nxt, cells, cell, centre,
                      reach, np.empty(64, dtype=np.int64))
        for t in ids:
            g = geometry[t]
            d00, d01, d11 = g[12], g[13], g[14]
            denom = d00 * d11 - d01 * d01
            if denom <= 0:  # a degenerate triangle covers nothing
                continue
            # a probe over the triangle lies within its corner radius plus the height limit
            # of its centroid: most triangles of the neighbourhood are rejected by that alone
            r = (g[18] + limit) * (g[18] + limit)
            for p in range(probes.shape[0]):
                c0 = probes[p, 0] - g[15]
                c1 = probes[p, 1] - g[16]
                c2 = probes[p, 2] - g[17]
                if c0 * c0 + c1 * c1 + c2 * c2 > r:
                    continue
                r0 = probes[p, 0] - g[0]
                r1 = probes[p, 1] - g[1]
                r2 = probes[p, 2] - g[2]
                if abs(r0 * g[9] + r1 * g[10] + r2 * g[11]) >= limit:
                    continue
                d20 = r0 * g[3] + r1 * g[4] + r2 * g[5]
                d21 = r0 * g[6] + r1 * g[7] + r2 * g[8]
                s = (d11 * d20 - d01 * d21) / denom
                u = (d00 * d21 - d01 * d20) / denom
                if s > margin and u > margin and 1.0 - s - u > margin:
                    return True
    return False


@numba.njit(cache=True)
def _median_sorted(values):
    s = np.sort(values)
    k = len(s)
    return s[k // 2] if k % 2 else 0.5 * (s[k // 2 - 1] + s[k // 2])


@numba.njit(cache=True)
def outside_flags(xs, ns, dist, idx, points, normals, spacing, inside, outside, strict, gap):
    """The border test of :meth:`AdvancingFront._outside` for many points at once.

    Parameters
    ----------
    xs : (K, 3) surface points; ns : (K, 3) their normals, or (1, 3) one normal for all
    dist, idx : (K, B) distances to and ids of their B nearest input points, nearest first
    points, normals : (N, 3) input points and their oriented normals; spacing : (N,)
    inside, outside : spacings within which a point is inside / beyond which outside
    strict : outside already beyond ``inside`` spacings
    gap : widest angular gap (radians) of the neighbours that still counts as inside

    Returns
    -------
    (K,) bool
    """
    k_pts, b = idx.shape
    out = np.zeros(k_pts, dtype=np.bool_)
    sel = np.empty(b, dtype=np.int64)
    for p in range(k_pts):
        r = p if len(ns) > 1 else 0
        n0, n1, n2 = ns[r, 0], ns[r, 1], ns[r, 2]
        x0, x1, x2 = xs[p, 0], xs[p, 1], xs[p, 2]
        # neighbours of the same sheet (not the back of a thin part), if there are any
        count = 0
        for j in range(b):
            i = idx[p, j]
            if 0 <= i < len(points) and normals[i, 0] * n0 + normals[i, 1] * n1 + \
                    normals[i, 2] * n2 > 0:
                sel[count] = j
                count += 1
        if count == 0:
            for j in range(b):
                if 0 <= idx[p, j] < len(points):
                    sel[count] = j
                    count += 1
        if count == 0:
            out[p] = True
            continue
        local = np.empty(count)
        for c in range(count):
            local[c] = spacing[idx[p, sel[c]]]
        # the spacing of a rim point alone is inflated (its neighbours lie on one side): the
        # median over the neighbours is a steadier local estimate
        h = _median_sorted(local)
        d0 = dist[p, sel[0]]
        if d0 <= inside * h:
            continue
        if strict or d0 > outside * h:
            out[p] = True
            continue
        # directions to the neighbours in the tangent plane: a gap wider than ``gap`` means
        # they all lie to one side
        ang = np.empty(count)
        t1 = np.empty(3)
        t2 = np.empty(3)
        for c in range(count):
            i = idx[p, sel[c]]
            r0, r1, r2 = points[i, 0] - x0, points[i, 1] - x1, points[i, 2] - x2
            h_n = r0 * n0 + r1 * n1 + r2 * n2
            r0, r1, r2 = r0 - h_n * n0, r1 - h_n * n1, r2 - h_n * n2
            if c == 0:
                length = max(math.sqrt(r0 * r0 + r1 * r1 + r2 * r2), 1e-300)
                t1[0], t1[1], t1[2] = r0 / length, r1 / length, r2 / length
                t2[0] = n1 * t1[2] - n2 * t1[1]
                t2[1] = n2 * t1[0] - n0 * t1[2]
                t2[2] = n0 * t1[1] - n1 * t1[0]
            ang[c] = math.atan2(r0 * t2[0] + r1 * t2[1] + r2 * t2[2],
                                r0 * t1[0] + r1 * t1[1] + r2 * t1[2])
        ang = np.sort(ang)
        widest = ang[0] + 2 * math.pi - ang[count - 1]
        for c in range(1, count):
            widest = max(widest, ang[c] - ang[c - 1])
        out[p] = widest > gap
    return out


@numba.njit(cache=True)
def adj_remove(adj, cnt, u, w):
    """Remove ``w`` from the ``cnt[u]`` ids in row ``u`` of ``adj`` (the last takes its
    place)."""
    last = cnt[u] - 1
    for m in range(last + 1):
        if adj[u, m] == w:
            adj[u, m] = adj[u, last]
            adj[u, last] = -1
            cnt[u] = last
            return


@numba.njit(cache=True)
def _orient(ax, ay, bx, by, cx, cy):
    return (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)


@numba.njit(cache=True)
def front_clear(head, nxt, cells, cell, V, N, out_adj, out_cnt, in_adj, in_cnt, a, b, v,
                xv, n, radius):
    """Whether triangle ``(a, b, v)`` (apex at ``xv``; ``v = -1`` for a new vertex) keeps
    clear of the front near it: seen in the plane orthogonal to ``n`` through its centre, no
    other front vertex within ``radius`` lies inside it (closer than ``radius`` to that plane)
    and no front edge properly crosses its new sides ``a-v`` and ``b-v``.

    ``out_adj (C, D)`` / ``in_adj (C, D)`` with counts ``out_cnt`` / ``in_cnt`` (C,): the
    outgoing and incoming front edges of each vertex.
    """
    xa, xb = V[a], V[b]
    centre = np.empty(3)
    for c in range(3):
        centre[c] = (xa[c] + xb[c] + xv[c]) / 3.0
    near = vertices_near(head, nxt, cells, cell, V, N, centre, radius, n, True)
    if len(near) == 0:
        return True
    # tangent basis: t1 along a -> b, t2 = n x t1
    e0 = xb - xa
    la = math.sqrt(e0[0] ** 2 + e0[1] ** 2 + e0[2] ** 2)
    t1 = e0 / la
    t2 = np.array([n[1] * t1[2] - n[2] * t1[1], n[2] * t1[0] - n[0] * t1[2],
                   n[0] * t1[1] - n[1] * t1[0]])
    t2 /= math.sqrt(t2[0] ** 2 + t2[1] ** 2 + t2[2] ** 2)

    def plane(p):
        r0, r1, r2 = p[0] - centre[0], p[1] - centre[1], p[2] - centre[2]
        return (r0 * t1[0] + r1 * t1[1] + r2 * t1[2], r0 * t2[0] + r1 * t2[1] + r2 * t2[2])

    pa0, pa1 = plane(xa)
    pb0, pb1 = plane(xb)
    pv0, pv1 = plane(xv)
    # no other front vertex inside the triangle (in the tangent plane)
    for u in near:
        if u == a or u == b or u == v:
            continue
        q0, q1 = plane(V[u])
        height = abs((V[u, 0] - centre[0]) * n[0] + (V[u, 1] - centre[1]) * n[1]
                     + (V[u, 2] - centre[2]) * n[2])
        if _orient(pa0, pa1, pb0, pb1, q0, q1) > 0 and \
                _orient(pb0, pb1, pv0, pv1, q0, q1) > 0 and \
                _orient(pv0, pv1, pa0, pa1, q0, q1) > 0 and height < radius:
            return False
    # no front edge crosses the new sides
    for u in near:
        for side in range(2):
            cnt = out_cnt[u] if side == 0 else in_cnt[u]
            for m in range(cnt):
                w = out_adj[u, m] if side == 0 else in_adj[u, m]
                r0, r1 = plane(V[u])
                s0, s1 = plane(V[w])
                for corner in range(2):
                    c_id = a if corner == 0 else b
                    if u == c_id or w == c_id or (v >= 0 and (u == v or w == v)):
                        continue
                    p0, p1 = (pa0, pa1) if corner == 0 else (pb0, pb1)
                    d1 = _orient(r0, r1, s0, s1, p0, p1)
                    d2 = _orient(r0, r1, s0, s1, pv0, pv1)
                    d3 = _orient(p0, p1, pv0, pv1, r0, r1)
                    d4 = _orient(p0, p1, pv0, pv1, s0, s1)
                    if d1 * d2 < 0 and d3 * d4 < 0:
                        return False
    return True


@numba.njit(cache=True)
def angle_ccw(d1, d2, n):
    """Counter-clockwise angle (radians, in ``[0, 2 pi)``) from direction ``d1`` to ``d2``
    around the normal ``n`` (3-tuples)."""
    ang = math.atan2(dot(cross(d1, d2), n), dot(d1, d2))
    return ang if ang >= 0 else ang + 2 * math.pi


@numba.njit(cache=True)
def corner_angles(pa, pb, pc):
    """The interior angles (radians) of the triangle ``pa pb pc`` (3-tuples) at its three
    corners, as a 3-tuple."""
    d1, d2 = sub(pb, pa), sub(pc, pa)
    at_a = math.atan2(norm(cross(d1, d2)), dot(d1, d2))
    d1, d2 = sub(pc, pb), sub(pa, pb)
    at_b = math.atan2(norm(cross(d1, d2)), dot(d1, d2))
    d1, d2 = sub(pa, pc), sub(pb, pc)
    at_c = math.atan2(norm(cross(d1, d2)), dot(d1, d2))
    return (at_a, at_b, at_c)


@numba.njit(cache=True)
def in_front(out_adj, out_cnt, u, w):
    """Whether ``u -> w`` is a front edge (``out_adj (C, D)``, ``out_cnt (C,)``)."""
    for m in range(out_cnt[u]):
        if out_adj[u, m] == w:
            return True
    return False


@numba.njit(cache=True)
def inside_wedge(V, out_adj, out_cnt, in_adj, in_cnt, o, d, n):
    """Whether direction ``d`` (3-tuple) leaves front vertex ``o`` into unmeshed space.

    For each outgoing front edge ``o -> nxt`` the unmeshed wedge turns counter-clockwise
    around ``n`` from ``nxt - o`` to ``prv - o``, where ``prv -> o`` is the incoming front edge
    that closes the smallest such angle (a vertex on several front loops has several wedges).
    """
    po = row(V, o)
    for m in range(out_cnt[o]):
        nxt = out_adj[o, m]
        d1 = sub(row(V, nxt), po)
        total = -1.0
        for j in range(in_cnt[o]):
            prv = in_adj[o, j]
            ang = 2 * math.pi if prv == nxt else angle_ccw(d1, sub(row(V, prv), po), n)
            if total < 0 or ang < total:
                total = ang
        if total >= 0:
            ang = angle_ccw(d1, d, n)
            if 1e-9 < ang < total - 1e-9:
                return True
    return False


@numba.njit(cache=True)
def front_neighbour(V, adj, cnt, vertex, other, incoming, n):
    """The front neighbour across ``vertex`` of its front edge towards ``other``: among the
    ids in row ``vertex`` of ``adj (C, D)`` (``cnt (C,)`` of them; the incoming front edges'
    tails if ``incoming``, else the outgoing ones' heads), the first counter-clockwise from
    ``other`` around ``n`` (3-tuple) for incoming edges, the first clockwise for outgoing
    ones; -1 when there is none."""
    k = cnt[vertex]
    if k == 1:
        return adj[vertex, 0]
    pv = row(V, vertex)
    d0 = sub(row(V, other), pv)
    best, best_ang = -1, 0.0
    for m in range(k):
        c = adj[vertex, m]
        ang = angle_ccw(d0, sub(row(V, c), pv), n)
        if not incoming:
            ang = 2 * math.pi - ang
        if best < 0 or ang < best_ang:
            best, best_ang = c, ang
    return best


@numba.njit(cache=True)
def front_edge_add(out_adj, out_cnt, in_adj, in_cnt, vgrid, cell, V, a, b):
    """Record the front edge ``a -> b`` in the adjacency rows (the caller has widened a full
    row) and file its ends in the front vertices' grid ``vgrid`` (cells ``cell`` wide) unless
    they are front vertices already."""
    head, nxt, prv, cells = vgrid
    for v in (a, b):
        if out_cnt[v] == 0 and in_cnt[v] == 0:
            grid_insert(head, nxt, prv, cells, v, int(math.floor(V[v, 0] / cell)),
                        int(math.floor(V[v, 1] / cell)), int(math.floor(V[v, 2] / cell)))
    out_adj[a, out_cnt[a]] = b
    out_cnt[a] += 1
    in_adj[b, in_cnt[b]] = a
    in_cnt[b] += 1


@numba.njit(cache=True)
def front_edge_remove(out_adj, out_cnt, in_adj, in_cnt, vgrid, a, b):
    """Remove the front edge ``a -> b`` from the adjacency rows, and its ends from the front
    vertices' grid ``vgrid`` when no front edge is left at them."""
    adj_remove(out_adj, out_cnt, a, b)
    adj_remove(in_adj, in_cnt, b, a)
    head, nxt, prv, cells = vgrid
    for v in (a, b):
        if out_cnt[v] == 0 and in_cnt[v] == 0:
            grid_remove(head, nxt, prv, cells, v)


#: layout of :func:`triangle_ok`'s ``limits (7,)``
LIMIT_NORMAL_COS, LIMIT_FAN, LIMIT_COVER_MARGIN, LIMIT_COVER_HEIGHT, LIMIT_INSIDE, \
    LIMIT_OUTSIDE, LIMIT_GAP = range(7)


@numba.njit(cache=True)
def triangle_ok(V, N, fan, out_adj, out_cnt, in_adj, in_cnt, vgrid, vcell, fgrid, face_start,
                face_cell, face_radius, geometry, pgrid, cloud_normals, spacing, k, limits,
                a, b, v, xv, n, min_angle, existing, check_outside, probes):
    """The advancing front's validity test of the triangle ``(a, b, v)`` with its apex at
    ``xv`` (3-tuple; ``v = -1`` for a new vertex), seen along the surface normal ``n``
    (3-tuple): it faces along ``n`` (within ``acos(limits[LIMIT_NORMAL_COS])``), its smallest
    angle is at least ``min_angle``, no corner's triangles add up to more than
    ``limits[LIMIT_FAN]``, every new edge leaves its ends into their unmeshed wedges, its
    centre and the midpoints of its new edges (``probes``, filled, ``(3, 3)``) lie inside the
    cloud and on no existing triangle, and no front vertex or edge near it is in the way
    (:func:`front_clear`).

    ``vgrid``: the front vertices' hash grid ``(head, nxt, prv, cells)`` with cells ``vcell``
    wide; ``fgrid``, ``face_start``, ``face_cell``, ``face_radius``, ``geometry``: the
    triangles' grids (:func:`covered`); ``pgrid``: the input points' grid ``(points, cells,
    start, order, cell)`` (:class:`PointGrid`) with their normals and spacings ``(P, 3)``,
    ``(P,)`` for the border test (:func:`outside_near` with ``k`` neighbours).  ``fan (C,)``:
    the summed corner angles of each vertex's triangles.  Whether an existing apex's new
    edges are already mesh edges is the caller's test.

    Returns ``(status, probes used)``: status 1 valid, 0 not, -1 undecided because the grid
    search did not settle a probe's border test (the caller asks a k-d tree, then calls again
    with ``check_outside`` false).
    """
    xa, xb = row(V, a), row(V, b)
    e0, e1, e2 = sub(xb, xa), sub(xv, xb), sub(xa, xv)
    tn = cross(e0, sub(xv, xa))
    tl = norm(tn)
    if tl <= 0 or dot(tn, n) < limits[LIMIT_NORMAL_COS] * tl:
        return 0, 0
    la, lb, lc = norm(e0), norm(e1), norm(e2)
    # the smallest angle is opposite the shortest side: sin = 2 area / (other two sides)
    low, longest = (la, lb) if la <= lb else (lb, la)
    if lc >= longest:
        middle, longest = longest, lc
    else:
        middle = max(lc, low)
    if tl / (middle * longest) < math.sin(min_angle):
        return 0, 0
    ang_a, ang_b, ang_v = corner_angles(xa, xb, xv)
    limit = limits[LIMIT_FAN]
    if fan[a] + ang_a > limit or fan[b] + ang_b > limit or (existing and fan[v] + ang_v > limit):
        return 0, 0
    bv_new = not in_front(out_adj, out_cnt, b, v)
    va_new = not in_front(out_adj, out_cnt, v, a)
    # every new edge must leave both its ends into their unmeshed wedges
    if bv_new:
        if not inside_wedge(V, out_adj, out_cnt, in_adj, in_cnt, b, sub(xv, xb), n):
            return 0, 0
        if existing and not inside_wedge(V, out_adj, out_cnt, in_adj, in_cnt, v,
                                         sub(xb, xv), n):
            return 0, 0
    if va_new:
        if not inside_wedge(V, out_adj, out_cnt, in_adj, in_cnt, a, sub(xv, xa), n):
            return 0, 0
        if existing and not inside_wedge(V, out_adj, out_cnt, in_adj, in_cnt, v,
                                         sub(xa, xv), n):
            return 0, 0
    count = 1
    for c in range(3):
        probes[0, c] = (xa[c] + xb[c] + xv[c]) / 3.0
    if bv_new:
        for c in range(3):
            probes[count, c] = 0.5 * (xb[c] + xv[c])
        count += 1
    if va_new:
        for c in range(3):
            probes[count, c] = 0.5 * (xv[c] + xa[c])
        count += 1
    used = probes[:count]
    normal = np.empty((1, 3))
    for c in range(3):
        normal[0, c] = n[c]
    # a triangle whose centre or new edges leave the cloud spans a hole of the scan
    if check_outside:
        points, pcells, start, order, pcell = pgrid
        flags = outside_near(points, pcells, start, order, pcell, cloud_normals, spacing, used,
                             normal, k, limits[LIMIT_INSIDE], limits[LIMIT_OUTSIDE], False,
                             limits[LIMIT_GAP], MAX_SHELL)
        undecided = False
        for p in range(count):
            if flags[p] == 1:
                return 0, count
            undecided = undecided or flags[p] < 0
        if undecided:
            return -1, count
    centre = probes[0].copy()
    head, fnxt, _fprv, fcells = fgrid
    if covered(head, face_start, face_cell, face_radius, fnxt, fcells, geometry, used, centre,
               longest, limits[LIMIT_COVER_MARGIN], limits[LIMIT_COVER_HEIGHT]):
        return 0, count
    apex = np.empty(3)
    for c in range(3):
        apex[c] = xv[c]
    vhead, vnxt, _vprv, vcells = vgrid
    clear = front_clear(vhead, vnxt, vcells, vcell, V, N, out_adj, out_cnt, in_adj, in_cnt,
                        a, b, v, apex, normal[0], longest * 1.5)
    return (1 if clear else 0), count


@numba.njit(cache=True)
def face_added(V, fan, geometry, fgrid, face_start, face_cell, face_radius, f, a, b, c):
    """File the new triangle ``f = (a, b, c)``: its row of ``geometry (F, 19)`` (first corner,
    two edge vectors, unit normal, Gram entries, centroid, corner radius; see :func:`covered`),
    its place in the grid of the smallest size class whose cells are at least twice its corner
    radius, and its corner angles added to ``fan (C,)``.  Returns its area."""
    pa, pb, pc = row(V, a), row(V, b), row(V, c)
    centroid = ((pa[0] + pb[0] + pc[0]) / 3.0, (pa[1] + pb[1] + pc[1]) / 3.0,
                (pa[2] + pb[2] + pc[2]) / 3.0)
    e1, e2 = sub(pb, pa), sub(pc, pa)
    normal = cross(e1, e2)
    area2 = norm(normal)
    length = area2 if area2 > 0 else 1.0
    radius = math.sqrt(max(dot(sub(pa, centroid), sub(pa, centroid)),
                           dot(sub(pb, centroid), sub(pb, centroid)),
                           dot(sub(pc, centroid), sub(pc, centroid))))
    lev = 0
    while lev < len(face_cell) - 1 and radius > 0.5 * face_cell[lev]:
        lev += 1
    size = face_cell[lev]
    head, nxt, prv, cells = fgrid
    grid_insert(head[face_start[lev]:face_start[lev + 1]], nxt, prv, cells, f,
                int(math.floor(centroid[0] / size)), int(math.floor(centroid[1] / size)),
                int(math.floor(centroid[2] / size)))
    face_radius[lev] = max(face_radius[lev], radius)
    g = geometry[f]
    for i in range(3):
        g[i], g[3 + i], g[6 + i] = pa[i], e1[i], e2[i]
        g[9 + i] = normal[i] / length
        g[15 + i] = centroid[i]
    g[12], g[13], g[14] = dot(e1, e1), dot(e1, e2), dot(e2, e2)
    g[18] = radius
    ang_a, ang_b, ang_c = corner_angles(pa, pb, pc)
    fan[a] += ang_a
    fan[b] += ang_b
    fan[c] += ang_c
    return 0.5 * area2


class PointGrid:
    """Input points filed in a hash grid of cells ``cell`` wide, for nearest-neighbour queries
    from compiled code (:func:`knn`): a k-d tree query costs ~45 microseconds per call however
    few points it is asked about, and the front asks about a few points at a time.

    Parameters
    ----------
    points : (N, 3) float64
    cell : float, the cell width (about twice the sample spacing keeps the searches short)
    """

    def __init__(self, points, cell):
        self.points = np.ascontiguousarray(points, dtype=np.float64)
        self.cell = float(cell)
        self.cells = np.floor(self.points / self.cell).astype(np.int64)
        n_slots = 1 << max(10, (2 * len(self.points)).bit_length())
        c = self.cells
        slot = ((c[:, 0] * 73856093) ^ (c[:, 1] * 19349663) ^ (c[:, 2] * 83492791)) & (
            n_slots - 1)
        self.order = np.argsort(slot, kind="stable").astype(np.int64)
        self.start = np.searchsorted(slot[self.order], np.arange(n_slots + 1)).astype(np.int64)

    def query(self, xs, k, tree=None):
        """The ``k`` nearest points of ``xs (M, 3)``: ``dist (M, k)`` and ``idx (M, k)``
        nearest first; queries far from every point (beyond ``MAX_SHELL`` cells) go to
        ``tree`` (a ``cKDTree`` of the same points)."""
        xs = np.ascontiguousarray(xs, dtype=np.float64).reshape(-1, 3)
        k = min(int(k), len(self.points))
        dist = np.empty((len(xs), k))
        idx = np.empty((len(xs), k), dtype=np.int64)
        ok = knn(self.points, self.cells, self.start, self.order, self.cell, xs, k, MAX_SHELL,
                 dist, idx)
        if not ok.all():
            from scipy.spatial import cKDTree

            tree = cKDTree(self.points) if tree is None else tree
            d, i = tree.query(xs[~ok], k=k)
            dist[~ok], idx[~ok] = np.reshape(d, (-1, k)), np.reshape(i, (-1, k))
        return dist, idx


#: :func:`knn` searches at most this many cells out from a query's own cell
MAX_SHELL = 6


@numba.njit(cache=True)
def knn(points, cells, start, order, cell, xs, k, max_shell, dist, idx):
    """``k`` nearest points of each query by growing shells of grid cells (see
    :class:`PointGrid`); fills ``dist (M, k)`` and ``idx (M, k)`` nearest first (ties by id)
    and returns ``(M,)`` bool: False where ``max_shell`` shells did not settle the answer."""
    mask = len(start) - 2
    ok = np.zeros(len(xs), dtype=np.bool_)
    for q in range(len(xs)):
        x0, x1, x2 = xs[q, 0], xs[q, 1], xs[q, 2]
        ci = int(math.floor(x0 / cell))
        cj = int(math.floor(x1 / cell))
        ck = int(math.floor(x2 / cell))
        count = 0
        for r in range(max_shell + 1):
            for i in range(ci - r, ci + r + 1):
                for j in range(cj - r, cj + r + 1):
                    for kk in range(ck - r, ck + r + 1):
                        if max(abs(i - ci), abs(j - cj), abs(kk - ck)) != r:
                            continue  # inner cells were searched by earlier shells
                        s = _slot(i, j, kk, mask)
                        for m in range(start[s], start[s + 1]):
                            p = order[m]
                            if cells[p, 0] != i or cells[p, 1] != j or cells[p, 2] != kk:
                                continue
                            d = math.sqrt((points[p, 0] - x0) ** 2 + (points[p, 1] - x1) ** 2
                                          + (points[p, 2] - x2) ** 2)
                            if count == k and (d > dist[q, k - 1] or (
                                    d == dist[q, k - 1] and p > idx[q, k - 1])):
                                continue
                            # insertion into the sorted list of the best so far
                            pos = count if count < k else k - 1
                            while pos > 0 and (dist[q, pos - 1] > d or (
                                    dist[q, pos - 1] == d and idx[q, pos - 1] > p)):
                                if pos < k:
                                    dist[q, pos] = dist[q, pos - 1]
                                    idx[q, pos] = idx[q, pos - 1]
                                pos -= 1
                            dist[q, pos] = d
                            idx[q, pos] = p
                            if count < k:
                                count += 1
            # points of cells beyond shell r lie outside the searched block of cells: farther
            # than the query's distance to the block's nearest face (at least r cells)
            if count == k:
                exit_ = min(x0 - (ci - r) * cell, (ci + r + 1) * cell - x0,
                            x1 - (cj - r) * cell, (cj + r + 1) * cell - x1,
                            x2 - (ck - r) * cell, (ck + r + 1) * cell - x2)
                if dist[q, k - 1] <= exit_:
                    ok[q] = True
                    break
    return ok


@numba.njit(cache=True)
def outside_near(points, cells, start, order, cell, normals, spacing, xs, ns, k, inside,
                 outside, strict, gap, max_shell):
    """:func:`knn` and :func:`outside_flags` in one call (the front asks about two or three
    points at a time, so the calls' fixed costs mattered): ``(K,)`` int8, 1 outside, 0
    inside, -1 where the grid search did not settle the neighbours (ask a k-d tree)."""
    dist = np.empty((len(xs), k))
    idx = np.empty((len(xs), k), dtype=np.int64)
    ok = knn(points, cells, start, order, cell, xs, k, max_shell, dist, idx)
    for p in range(len(xs)):
        if not ok[p]:  # rows the search left half filled: any valid ids (answer discarded)
            idx[p, :] = 0
            dist[p, :] = np.inf
    flags = outside_flags(xs, ns, dist, idx, points, normals, spacing, inside, outside,
                          strict, gap)
    out = np.empty(len(xs), dtype=np.int8)
    for p in range(len(xs)):
        out[p] = (1 if flags[p] else 0) if ok[p] else -1
    return out


def compile_kernels() -> None:
    """Compile the kernels into numba's on-disk cache (install.sh runs this once)."""
    cap, slots = 8, 16
    head = np.full(slots, -1, dtype=np.int64)
    nxt = np.full(cap, -1, dtype=np.int64)
    prv = np.full(cap, -1, dtype=np.int64)
    cells = np.zeros((cap, 3), dtype=np.int64)
    V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]] * 2)
    N = np.tile([0.0, 0.0, 1.0], (cap, 1))
    for item in range(4):
        grid_insert(head, nxt, prv, cells, item, int(V[item, 0]), int(V[item, 1]), 0)
    grid_remove(head, nxt, prv, cells, 3)
    adj_remove(np.zeros((2, 2), dtype=np.int64), np.ones(2, dtype=np.int64), 0, 0)
    n = np.array([0.0, 0.0, 1.0])
    adj = np.full((cap, 4), -1, dtype=np.int64)
    adj[0, 0], adj[1, 0], adj[2, 0] = 1, 2, 0
    cnt = np.array([1, 1, 1, 0, 0, 0, 0, 0], dtype=np.int64)
    radj = np.full((cap, 4), -1, dtype=np.int64)
    radj[1, 0], radj[2, 0], radj[0, 0] = 0, 1, 2
    vertices_near(head, nxt, cells, 1.0, V, N, V[0].copy(), 2.0, n, True)
    front_clear(head, nxt, cells, 1.0, V, N, adj, cnt, radj, cnt, 0, 1, -1,
                np.array([0.5, -0.8, 0.0]), n, 2.0)
    geometry = np.zeros((cap, 19))
    covered(head, np.array([0, slots]), np.ones(1), np.zeros(1), nxt, cells, geometry, V[:2],
            V[0], 1.0, 0.02, 0.3)
    idx = np.tile(np.arange(4, dtype=np.int64), (2, 1))
    outside_flags(V[:2], N[:2], np.ones((2, 4)), idx, V[:4], N[:4], np.ones(4), 0.75, 1.5,
                  False, math.pi)
    grid = PointGrid(V[:4], 1.0)
    grid.query(V[:2], 3)
    outside_near(grid.points, grid.cells, grid.start, grid.order, grid.cell, N[:4], np.ones(4),
                 V[:2].copy(), N[:1].copy(), 3, 0.75, 1.5, False, math.pi, MAX_SHELL)
