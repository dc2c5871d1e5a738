"""Advancing-front triangulation of a point-set surface (thesis §7.1, Fig. 7.3 left; §7.3).

Conventions: the mesh is ``vertices (V, 3)`` float64 and ``faces (F, 3)`` int, triangles
counter-clockwise seen from the side the normals point to.  The *front* is a set of directed
boundary edges ``(a, b)``: the unmeshed region lies to the left of ``a -> b`` (seen from the
normal side), so the next triangle built on it is ``(a, b, v)``.

One step takes a front edge, predicts a new point at the height of an equilateral triangle of
the guidance length, projects it onto the surface (:class:`~.projection.Projector`) and either
adds it or, when a front vertex is close, connects to that vertex instead.  Connecting to the
front neighbour closes an *ear*; connecting to another vertex of the same front loop *splits*
it, to a vertex of another loop *merges* the two (Hartmann's operations [Har98]).  Every
candidate triangle must keep the mesh an oriented manifold: it must face along the surface
normal, stay inside the unmeshed wedges at its corners, cross no front edge, contain no front
vertex, and use no edge that already has two triangles.  Two tests do not rely on the tangent
plane, which misleads where neighbouring normals differ by ~90 degrees (thin parts and sharp
folds of coarse scans): no triangle may lie over one already built, and the triangles at a
vertex may not add up to more than a full turn.  Where the predicted point leaves the point
cloud, the edge becomes part of a border and stays open.

Edges that fail repeatedly are given up; regions no front reached get a new seed; given-up
edges are retried with shorter target lengths; what is still open and not a border of the
scan is filled, hole by hole, with the best-shaped triangulation of its loop.
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass, field

import numpy as np

from splineviz.core.errors import SplinevizError
from splineviz.pointcloud import front_kernels as fk

#: a front angle below this (radians) is an ear: close it before growing
EAR_ANGLE = np.deg2rad(75.0)
#: front vertices within this many target lengths of the predicted point are tried first
CONNECT_RADIUS = 0.6
#: a new vertex closer than this many target lengths to a front vertex is rejected
MIN_VERTEX_DISTANCE = 0.45
#: smallest accepted triangle angle when a new vertex is created / an existing one is used
MIN_ANGLE_NEW = np.deg2rad(30.0)
MIN_ANGLE_CONNECT = np.deg2rad(12.0)
#: a candidate triangle's normal must be within this angle of the surface normal
MAX_NORMAL_DEVIATION = np.deg2rad(60.0)
#: border test (see AdvancingFront._outside): inside within INSIDE_SPACINGS of the nearest
#: input point, outside beyond OUTSIDE_SPACINGS, in between outside when the nearest
#: BORDER_NEIGHBOURS points leave an angular gap wider than BORDER_GAP in the tangent plane
INSIDE_SPACINGS = 0.75
OUTSIDE_SPACINGS = 1.5
#: ... or OUTSIDE_VOID_FACTOR times the cloud's void ratio, if larger
OUTSIDE_VOID_FACTOR = 1.5
BORDER_NEIGHBOURS = 24
BORDER_GAP = np.deg2rad(180.0)
#: where the predicted point leaves the cloud, an edge at least RIM_MIN_EDGE target lengths
#: long tries a triangle of RIM_HEIGHT times the height before it becomes a border
RIM_MIN_EDGE = 0.7
RIM_HEIGHT = 0.5
#: number of times an edge is postponed before the relaxed rules apply, and before giving up
RETRIES = 2
GIVE_UP = 4
#: relaxed connection radius (target lengths) after RETRIES failures
RELAXED_RADIUS = 1.3
#: ear angle limit after RETRIES failures
RELAXED_EAR_ANGLE = np.deg2rad(110.0)
#: new seeds are placed at input points farther than this many target lengths from the mesh
#: vertices (inside a triangle of the front a point is at most ~0.6 of its longest side from
#: a corner): thin parts that the fronts around them could not enter get fronts of their own
SEED_DISTANCE = 1.0
#: ... when at least this many input points are that far (a region the fronts did not reach)
SEED_MIN_POINTS = 10
#: at most this many seeds (connected components)
MAX_SEEDS = 64
#: the front stops (stats.truncated) beyond this many vertices per input point
VERTEX_BUDGET = 2
#: given-up edges are retried this many times, each time with REFINE_FACTOR shorter edges
#: (on Lucy a second pass of 0.36 times the length gave up again around the same thin parts
#: and left 4.7 times the border edges in holes too long to fill, for 23 % more steps)
REFINE_PASSES = 1
REFINE_FACTOR = 0.6
#: front loops left with at most this many edges are filled at the end (unless they are
#: borders of the scan); the optimal triangulation costs O(edges^3)
MAX_HOLE_EDGES = 40
#: ... and loops of up to this many edges when the triangulation stays on the samples (no
#: centroid beyond the border test's hard limit from the nearest input point): the rims of
#: folds thinner than the spacing (Lucy's dress), where the fronts of the two sides meet
#: facing apart and give up, leave long narrow loops; a loop around the mouth of a cavity
#: (between Lucy's wing and back) would get a lid.  Lucy at 0.6 % noise (the 2-million-point
#: bench's noise over its spacing) left loops of 69-84 edges along its wings' rims, all on
#: the samples (0.1 s of triangulation each); 64 left them open
LONG_HOLE_EDGES = 128
#: the corner angles of the triangles at one vertex may add up to at most 2 pi plus this:
#: saddles of coarse meshes exceed 2 pi by up to ~0.55 rad (measured on the kitten), while a
#: front that wraps around a vertex where the tangent plane misleads the wedge test (normals
#: of neighbours ~90 degrees apart on coarsely sampled creases) keeps adding full triangles
FAN_SLACK = 0.7
#: a candidate triangle is laid over the mesh when its centroid or a new edge's midpoint
#: projects strictly inside an existing triangle (all barycentric coordinates above
#: COVER_MARGIN) less than COVER_HEIGHT of the candidate's longest side away from it
COVER_MARGIN = 0.02
COVER_HEIGHT = 0.3
#: initial number of front edges per vertex and direction the adjacency arrays hold (they
#: widen when a vertex lies on more front loops)
FRONT_DEGREE = 8
#: the apexes of up to this many front edges next in the queue are predicted and projected in
#: one call (the projection's fixed cost per call dwarfs its cost per point)
PREDICT_BATCH = 64


class FrontError(SplinevizError, RuntimeError):
    """The advancing front cannot start (no seed triangle can be placed)."""


class Cancelled(SplinevizError):
    """The triangulation was cancelled through the progress callback."""


@dataclass
class FrontStats:
    """Counts of the front events of one run."""

    new_vertices: int = 0
    ears: int = 0
    connections: int = 0
    borders: int = 0
    given_up: int = 0
    holes_filled: int = 0
    seeds: int = 0
    steps: int = 0
    truncated: bool = False
    events: dict = field(default_factory=dict)


def _sub(u, v):
    return (u[0] - v[0], u[1] - v[1], u[2] - v[2])


def _dot(u, v):
    return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]


def _cross(u, v):
    return (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])


def _norm(u):
    return math.sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2])


def _unit(u):
    length = _norm(u)
    return (u[0] / length, u[1] / length, u[2] / length)


def _angle_ccw(d1, d2, n):
    """Counter-clockwise angle from ``d1`` to ``d2`` around normal ``n``, in ``[0, 2 pi)``.

    Small 3-vectors are plain tuples: NumPy's per-call overhead dominates at this size.
    """
    ang = math.atan2(_dot(_cross(d1, d2), n), _dot(d1, d2))
    return ang if ang >= 0 else ang + 2 * math.pi


def heap_smallest(heap: list, k: int) -> list:
    """The ``k`` smallest items of the binary heap ``heap`` in ascending order, as
    ``heapq.nsmallest(k, heap)`` gives them, in O(k log k): an item's children are no smaller
    than it, so the next smallest is always a child of one already taken (``nsmallest`` looks
    at every item, and the front's heap holds thousands on a large surface)."""
    if not heap or k <= 0:
        return []
    out, cand = [], [(heap[0], 0)]
    while cand and len(out) < k:
        item, i = heapq.heappop(cand)
        out.append(item)
        for c in (2 * i + 1, 2 * i + 2):
            if c < len(heap):
                heapq.heappush(cand, (heap[c], c))
    return out


def edge_loops(edges, preferred) -> list[list[int]]:
    """Closed loops of directed edges, every edge on at most one.

    Each edge continues with its ``preferred`` next edge (one out of its end vertex) unless
    an earlier edge took it; an edge left without one takes an edge out of the same vertex
    that no edge continues with.  Where two loops meet at a vertex (a pinched loop of a thin
    part's rim) both edges into it may prefer the same edge out; following preferences alone
    left the other edge out of the vertex on no loop (Lucy at 0.6 % noise: 384 of the 390
    front edges left after the front were on no loop, and none was filled).

    Parameters
    ----------
    edges : list of (a, b)
    preferred : dict (a, b) -> (b, c) or None

    Returns
    -------
    list of loops, each the list of the start vertices ``a`` of its edges in order
    """
    present = set(edges)
    nxt, taken, waiting, leaving = {}, set(), {}, {}
    for edge in edges:
        leaving.setdefault(edge[0], []).append(edge)
    for edge in edges:
        want = preferred.get(edge)
        if want in present and want not in taken:
            nxt[edge] = want
            taken.add(want)
        else:
            waiting.setdefault(edge[1], []).append(edge)
    for vertex, stuck in waiting.items():
        free = [e for e in leaving.get(vertex, ()) if e not in taken]
        for edge, out in zip(stuck, free, strict=False):
            nxt[edge] = out
            taken.add(out)
    seen, loops = set(), []
    for start in edges:
        if start in seen:
            continue
        loop, edge = [], start
        while edge in nxt and edge not in seen:
            seen.add(edge)
            loop.append(edge[0])
            edge = nxt[edge]
        if edge == start and loop:
            loops.append(loop)
    return loops


def simple_loops(loop):
    """Split a closed vertex loop at its repeated vertices into loops without repeats.

    A front loop pinched at a vertex (two of its wedges meet there) would otherwise give the
    two halves' triangulations a shared edge twice.
    """
    first: dict[int, int] = {}
    out, stack = [], []
    for v in loop:
        if v in first:
            i = first[v]
            out.append(stack[i:])
            for w in stack[i + 1:]:
                del first[w]
            del stack[i + 1:]
        else:
            first[v] = len(stack)
            stack.append(v)
    out.append(stack)
    return [part for part in out if len(part) >= 3]


class AdvancingFront:
    """Advancing-front mesher driven by a projector and a guidance field.

    Parameters
    ----------
    projector : Projector
        Projection onto the surface (``project_with_normals``), the input points and spacing.
    guidance : GuidanceField
        Target edge length at any position.
    progress : callable, optional
        Called as ``progress(fraction, message)``; if it returns ``False`` the run stops with
        :class:`Cancelled`.
    """

    #: at most this many seeds, MAX_SEEDS when None (subclasses for surfaces of many pieces
    #: raise it)
    max_seeds: int | None = None
    #: vertices per input point before the run stops, VERTEX_BUDGET when None (subclasses
    #: whose edges may be shorter than the points' spacing raise it)
    vertex_budget: float | None = None

    def __init__(self, projector, guidance, progress=None):
        self.proj = projector
        self.guide = guidance
        self.progress = progress
        self.stats = FrontStats()
        cap = 1024
        self.V = np.empty((cap, 3))
        self.N = np.empty((cap, 3))
        self.L = np.empty(cap)
        self.nv = 0
        # the front edges of each vertex as arrays for the compiled tests (the sets below
        # serve the Python logic): ids (cap, FRONT_DEGREE), -1 padded, and counts (cap,)
        self.out_adj = np.full((cap, FRONT_DEGREE), -1, dtype=np.int64)
        self.in_adj = np.full((cap, FRONT_DEGREE), -1, dtype=np.int64)
        self.out_cnt = np.zeros(cap, dtype=np.int64)
        self.in_cnt = np.zeros(cap, dtype=np.int64)
        # hash grids (front_kernels): front vertices by position, triangles by centroid;
        # about two slots per input point keep the lists short
        slots = 1 << max(10, (2 * len(projector.points)).bit_length())
        self.vgrid = (np.full(slots, -1, dtype=np.int64), np.full(cap, -1, dtype=np.int64),
                      np.full(cap, -1, dtype=np.int64), np.zeros((cap, 3), dtype=np.int64))
        # triangles by size class (front_kernels.covered): cells of twice the median target
        # length, doubling up to the longest
        longest = float(np.max(guidance.lengths))
        fine = min(longest, 2.0 * float(np.median(guidance.lengths)))
        levels = 1 + max(0, math.ceil(math.log2(longest / fine)))
        self.face_cell = fine * 2.0 ** np.arange(levels)
        self.face_radius = np.full(levels, -1.0)
        # a class of twice the size covers a quarter of the cells: a quarter of the slots
        sizes = [max(1024, slots >> (2 * lev)) for lev in range(levels)]
        self.face_start = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
        self.fgrid = (np.full(int(self.face_start[-1]), -1, dtype=np.int64),
                      np.full(cap, -1, dtype=np.int64), np.full(cap, -1, dtype=np.int64),
                      np.zeros((cap, 3), dtype=np.int64))
        # positions and normals as tuples for scalar math (vertices never move)
        self.P: list[tuple[float, float, float]] = []
        self.Pn: list[tuple[float, float, float]] = []
        self.faces: list[tuple[int, int, int]] = []
        self.front: dict[tuple[int, int], int] = {}  # edge -> number of failed attempts
        self.edge_faces: dict[tuple[int, int], int] = {}
        self.length_factor = 1.0  # lowered by the refinement passes (see _retry_given_up)
        self.fan = np.zeros(cap)  # sum of the corner angles of each vertex's triangles
        # per triangle, for _covered: first corner, two edge vectors, unit normal, the Gram
        # matrix entries of the edges, the centroid and the corners' largest distance from
        # it, (F, 19)
        self.face_geometry = np.empty((cap, 19))
        self.border: set[tuple[int, int]] = set()  # front edges no longer advanced
        self.scan_border: set[tuple[int, int]] = set()  # ... because the cloud ends there
        self.heap: list = []
        # front edge -> (projected apex (3,), its normal (3,), whether it lies outside the
        # cloud, the guidance length there), computed ahead in batches (see _predict)
        self.predictions: dict[tuple[int, int], tuple] = {}
        self.counter = 0
        # front vertices are found within radii of about a target length: cells of twice
        # the median length (one cell of the longest gathered hundreds on graded meshes)
        self.cell = fine
        # the cloud's points in a grid for the border test's neighbour queries (cells of
        # three spacings: the BORDER_NEIGHBOURS nearest lie within one or two cells)
        self.pgrid = fk.PointGrid(projector.points, 3.0 * float(np.median(projector.scale)))
        g = self.pgrid
        self._pgrid_arrays = (g.points, g.cells, g.start, g.order, g.cell)
        # the cloud's arrays in the layout the compiled border test reads
        self._cloud = (np.ascontiguousarray(projector.points, dtype=np.float64),
                       np.ascontiguousarray(projector.normals, dtype=np.float64),
                       np.ascontiguousarray(projector.scale, dtype=np.float64))
        self.area_done = 0.0
        self.spacing = projector.scale
        # irregular (e.g. random) samplings have wider empty gaps between samples: the hard
        # border limit follows the cloud's own largest ordinary gaps
        self.outside_spacings = max(OUTSIDE_SPACINGS,
                                    OUTSIDE_VOID_FACTOR * projector.conn.void_ratio())
        # the total area estimate drives the progress fraction
        self.area_total = float(np.sum(np.pi * (0.5 * projector.scale) ** 2)) * 1.1
        # the compiled triangle test's limits (front_kernels.LIMIT_*), read when the front
        # is built so that the module's constants can be changed for an experiment
        self._limits = np.array([math.cos(MAX_NORMAL_DEVIATION), 2 * math.pi + FAN_SLACK,
                                 COVER_MARGIN, COVER_HEIGHT, INSIDE_SPACINGS,
                                 self.outside_spacings, BORDER_GAP])
        self._neighbours = min(BORDER_NEIGHBOURS, len(self.pgrid.points))
        self._probes = np.empty((3, 3))  # the triangle test's probes, (3, 3)

    # -- bookkeeping -----------------------------------------------------------------------
    def _add_vertex(self, x, n, length=None):
        """Append vertex ``x (3,)`` with normal ``n (3,)`` and the guidance length at ``x``
        (``length`` if known); returns its id."""
        if self.nv == len(self.V):
            def grow(a, fill):
                return np.concatenate([a, np.full_like(a, fill)])

            self.V, self.N, self.L = grow(self.V, 0.0), grow(self.N, 0.0), grow(self.L, 0.0)
            self.fan = grow(self.fan, 0.0)
            self.out_adj, self.in_adj = grow(self.out_adj, -1), grow(self.in_adj, -1)
            self.out_cnt, self.in_cnt = grow(self.out_cnt, 0), grow(self.in_cnt, 0)
            head, nxt, prv, cells = self.vgrid
            self.vgrid = (head, grow(nxt, -1), grow(prv, -1), grow(cells, 0))
        i = self.nv
        self.V[i], self.N[i] = x, n
        self.P.append((float(x[0]), float(x[1]), float(x[2])))
        self.Pn.append((float(n[0]), float(n[1]), float(n[2])))
        if length is None:
            length = float(self.guide(x[None])[0])
        self.L[i] = self.length_factor * length
        self.nv += 1
        return i

    def _front_add(self, a, b):
        # a vertex on more front loops than its adjacency rows hold: widen them
        if self.out_cnt[a] == self.out_adj.shape[1]:
            self.out_adj = np.concatenate([self.out_adj, np.full_like(self.out_adj, -1)], axis=1)
        if self.in_cnt[b] == self.in_adj.shape[1]:
            self.in_adj = np.concatenate([self.in_adj, np.full_like(self.in_adj, -1)], axis=1)
        fk.front_edge_add(self.out_adj, self.out_cnt, self.in_adj, self.in_cnt, self.vgrid,
                          self.cell, self.V, a, b)
        self.front[(a, b)] = 0
        self._push(a, b)

    def _front_remove(self, a, b):
        del self.front[(a, b)]
        self.predictions.pop((a, b), None)
        self.border.discard((a, b))
        self.scan_border.discard((a, b))
        fk.front_edge_remove(self.out_adj, self.out_cnt, self.in_adj, self.in_cnt, self.vgrid,
                             a, b)

    def _push(self, a, b, delay=0):
        self.counter += 1
        heapq.heappush(self.heap, (delay, self.counter, a, b))

    def _add_triangle(self, a, b, c):
        self.faces.append((a, b, c))
        for u, w in ((a, b), (b, c), (c, a)):
            key = (u, w) if u < w else (w, u)
            self.edge_faces[key] = self.edge_faces.get(key, 0) + 1
            if (u, w) in self.front:
                self._front_remove(u, w)
            else:
                self._front_add(w, u)
        nf = len(self.faces) - 1
        if nf == len(self.face_geometry):
            self.face_geometry = np.concatenate([self.face_geometry,
                                                 np.empty_like(self.face_geometry)])
            head, nxt, prv, cells = self.fgrid
            self.fgrid = (head, np.concatenate([nxt, np.full_like(nxt, -1)]),
                          np.concatenate([prv, np.full_like(prv, -1)]),
                          np.concatenate([cells, np.zeros_like(cells)]))
        self.area_done += fk.face_added(self.V, self.fan, self.face_geometry, self.fgrid,
                                        self.face_start, self.face_cell, self.face_radius, nf,
                                        a, b, c)

    def _front_vertices_near(self, x, radius, n=None):
        """Front vertices within ``radius`` of ``x (3,)``, nearest first; with a normal ``n``
        only those facing along it (vertices facing the other way belong to the back of a
        thin sheet)."""
        head, nxt, _prv, cells = self.vgrid
        return fk.vertices_near(head, nxt, cells, self.cell, self.V, self.N,
                                np.asarray(x, dtype=np.float64), float(radius),
                                np.asarray(n if n is not None else (0.0, 0.0, 0.0),
                                           dtype=np.float64), n is not None)

    # -- geometry tests --------------------------------------------------------------------
    def _triangle_ok(self, a, b, v, xv, n, min_angle, existing):
        """Validity of triangle ``(a, b, v)`` with apex at ``xv`` (a 3-tuple; ``v = -1`` for
        a new vertex) seen along the normal ``n`` (3-tuple): no edge of the mesh used a second
        time, then :func:`.front_kernels.triangle_ok` (orientation, shape, fans, unmeshed
        wedges, no front vertex inside, no front edge crossed, no existing triangle covered,
        and not spanning a hole of the cloud)."""
        if existing:
            front = self.front
            for u, w in ((b, v), (v, a)):
                key = (u, w) if u < w else (w, u)
                if (u, w) not in front and key in self.edge_faces:
                    return False
        args = (self.V, self.N, self.fan, self.out_adj, self.out_cnt, self.in_adj, self.in_cnt,
                self.vgrid, self.cell, self.fgrid, self.face_start, self.face_cell,
                self.face_radius, self.face_geometry, self._pgrid_arrays, self._cloud[1],
                self._cloud[2], self._neighbours, self._limits, a, b, v, xv, n, min_angle,
                existing)
        status, count = fk.triangle_ok(*args, True, self._probes)
        if status >= 0:
            return bool(status)
        # the grid search left a probe's border test open: the k-d tree settles it
        if self._outside_any(self._probes[:count], n):
            return False
        return bool(fk.triangle_ok(*args, False, self._probes)[0])

    def _covered(self, probes, centre, length):
        """Whether any of ``probes (K, 3)`` lies on an existing triangle (see COVER_HEIGHT).

        The front's own tests only see front vertices and edges; where the wedge or the
        tangent plane mislead it (strongly curved, coarsely sampled regions), a front can
        advance over the already meshed surface, which no front element marks.
        """
        head, nxt, _prv, cells = self.fgrid
        return fk.covered(head, self.face_start, self.face_cell, self.face_radius, nxt, cells,
                          self.face_geometry, np.asarray(probes, dtype=np.float64),
                          np.asarray(centre, dtype=np.float64), float(length), COVER_MARGIN,
                          COVER_HEIGHT)

    def _outside(self, x, n, strict=False):
        """Whether surface point ``x`` (normal ``n``) lies beyond a border of the cloud;
        ``strict``: whether it lies farther than ``INSIDE_SPACINGS`` spacings from the samples.

        Inside the cloud the nearest input points surround ``x``; past a border (or in a hole
        of the scan) they all lie to one side.  So ``x`` is outside when its nearest input point
        is farther than ``INSIDE_SPACINGS`` spacings and the directions to its
        ``BORDER_NEIGHBOURS`` nearest points, seen in the tangent plane, leave a gap wider than
        ``BORDER_GAP``; or unconditionally beyond ``OUTSIDE_SPACINGS`` spacings (more for
        irregular samplings, see :meth:`Connectivity.void_ratio`).  Random
        sampling gaps are surrounded by points and do not count.  Only input points whose
        normals face along ``n`` count (not the back of a thin sheet), and the spacing is the
        median over them (the spacing of a rim point alone is inflated).
        """
        x = np.asarray(x, dtype=np.float64).reshape(1, 3)
        return bool(self._outside_flags(x, np.asarray(n, dtype=np.float64).reshape(1, 3),
                                        strict)[0])

    def _outside_any(self, xs, n):
        """Whether any of the points ``xs (K, 3)`` lies beyond a border (:meth:`_outside`)."""
        return bool(self._outside_flags(xs, np.asarray(n, dtype=np.float64).reshape(1, 3),
                                        False).any())

    def _outside_flags(self, xs, ns, strict):
        """:meth:`_outside` of points ``xs (K, 3)`` with normals ``ns (K, 3)`` or one normal
        ``(1, 3)``: ``(K,)`` bool."""
        g = self.pgrid
        _points, normals, spacing = self._cloud
        k = self._neighbours
        xs = np.ascontiguousarray(xs, dtype=np.float64)
        ns = np.ascontiguousarray(ns, dtype=np.float64)
        flags = fk.outside_near(g.points, g.cells, g.start, g.order, g.cell, normals, spacing,
                                xs, ns, k, INSIDE_SPACINGS, self.outside_spacings, bool(strict),
                                BORDER_GAP, fk.MAX_SHELL)
        undecided = flags < 0
        if undecided.any():  # far from every input point: the k-d tree finds the neighbours
            dist, idx = g.query(xs[undecided], k, self.proj.conn.tree)
            flags[undecided] = fk.outside_flags(
                xs[undecided], ns if len(ns) == 1 else ns[undecided], dist, idx, g.points,
                normals, spacing, INSIDE_SPACINGS, self.outside_spacings, bool(strict),
                BORDER_GAP)
        return flags.astype(bool)

    # -- the front step --------------------------------------------------------------------
    def _neighbour(self, vertex, other, incoming, n):
        """The front neighbour across ``vertex`` of the edge towards ``other``, -1 if none
        (:func:`.front_kernels.front_neighbour`)."""
        if incoming:
            return fk.front_neighbour(self.V, self.in_adj, self.in_cnt, vertex, other, True, n)
        return fk.front_neighbour(self.V, self.out_adj, self.out_cnt, vertex, other, False, n)

    def _step(self, a, b):
        st = self.stats
        st.steps += 1
        attempts = self.front[(a, b)]
        P = self.P
        xa, xb = P[a], P[b]
        na, nb = self.Pn[a], self.Pn[b]
        n = _unit((na[0] + nb[0], na[1] + nb[1], na[2] + nb[2]))
        ab = _sub(xb, xa)
        lab = _norm(ab)
        target = 0.5 * (self.L[a] + self.L[b])
        relaxed = attempts >= RETRIES
        min_connect = MIN_ANGLE_CONNECT * (0.5 if relaxed else 1.0)
        # 1. ears: a sharp front angle at a or b is closed with the front neighbour
        x = self._neighbour(a, b, True, n)
        y = self._neighbour(b, a, False, n)
        ears = []
        if x >= 0 and x != b:
            ears.append((_angle_ccw(ab, _sub(P[x], xa), n), x))
        if y >= 0 and y != a:
            ears.append((_angle_ccw(_sub(P[y], xb), (-ab[0], -ab[1], -ab[2]), n), y))
        ears.sort()
        limit = EAR_ANGLE if not relaxed else RELAXED_EAR_ANGLE
        for ang, v in ears:
            if ang < limit and self._triangle_ok(a, b, v, P[v], n, min_connect, True):
                self._add_triangle(a, b, v)
                st.ears += 1
                return
        # 2. predict the apex of an equilateral-ish triangle and project it
        d = _unit(_cross(n, ab))
        length = min(max(target, 0.55 * lab), 1.8 * lab)
        height = math.sqrt(max(length**2 - 0.25 * lab**2, 0.1 * lab**2))
        if (a, b) not in self.predictions:
            self._predict(a, b)
        xp, npn, outside, guided = self.predictions.pop((a, b))
        if outside:
            # 3. the point left the cloud: this edge is a border of an open scan.  A flatter
            # triangle may still fit before the rim and bring the border up to the last samples
            if lab >= RIM_MIN_EDGE * target:
                guess = np.array([0.5 * (xa[i] + xb[i]) + RIM_HEIGHT * height * d[i]
                                  for i in range(3)])
                pts, nrm = self.proj.project_with_normals(guess[None], np.asarray(n)[None])
                # close to the samples, not just surrounded by them: in a small hole of the
                # scan the samples all around would let the triangle reach into the hole
                if not self._outside(pts[0], nrm[0], strict=True) and \
                        self._new_vertex(a, b, pts[0], nrm[0], n, d, target):
                    return
            self.border.add((a, b))
            self.scan_border.add((a, b))
            st.borders += 1
            return
        # 4. connect to a nearby front vertex (ear, split or merge)
        radius = (RELAXED_RADIUS if relaxed else CONNECT_RADIUS) * target
        near = self._front_vertices_near(xp, radius, n)
        for v in near:
            if v == a or v == b:
                continue
            if self._triangle_ok(a, b, v, P[v], n, min_connect, True):
                self._add_triangle(a, b, v)
                st.connections += 1
                return
        # 5. a new vertex, if nothing is too close to it
        if self._new_vertex(a, b, xp, npn, n, d, target, guided):
            return
        # 6. postpone; after GIVE_UP attempts leave the edge as an unresolved border
        if attempts + 1 >= GIVE_UP:
            self.border.add((a, b))
            st.given_up += 1
            return
        self.front[(a, b)] = attempts + 1
        self._push(a, b, delay=attempts + 1)

    def _predict(self, a, b):
        """Predict, project and test (:meth:`_outside`) the apex of front edge ``(a, b)``
        and of the edges queued next, in one batch, into ``self.predictions``.

        The apex lies at the height of a triangle of the target side length (between 0.55
        and 1.8 times the edge's own), along the edge's outward direction in the plane
        orthogonal to the mean normal of its ends.  Each prediction depends only on its
        edge's vertices, so the batch gives what one edge at a time would.
        """
        edges = {(a, b): None}
        for _delay, _c, u, w in heap_smallest(self.heap, PREDICT_BATCH):
            if (u, w) in self.front and (u, w) not in self.border and \
                    (u, w) not in self.predictions:
                edges[(u, w)] = None
        e = np.array(list(edges), dtype=np.int64)
        xa, xb = self.V[e[:, 0]], self.V[e[:, 1]]
        n = self.N[e[:, 0]] + self.N[e[:, 1]]
        n /= np.sqrt(n[:, 0] * n[:, 0] + n[:, 1] * n[:, 1] + n[:, 2] * n[:, 2])[:, None]
        ab = xb - xa
        lab = np.sqrt(ab[:, 0] * ab[:, 0] + ab[:, 1] * ab[:, 1] + ab[:, 2] * ab[:, 2])
        target = 0.5 * (self.L[e[:, 0]] + self.L[e[:, 1]])
        d = np.cross(n, ab)
        d /= np.sqrt(d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1] + d[:, 2] * d[:, 2])[:, None]
        length = np.minimum(np.maximum(target, 0.55 * lab), 1.8 * lab)
        height = np.sqrt(np.maximum(length * length - 0.25 * lab * lab, 0.1 * lab * lab))
        guess = 0.5 * (xa + xb) + height[:, None] * d
        pts, nrm = self.proj.project_with_normals(guess, n)
        outside = self._outside_flags(pts, nrm, False)
        lengths = self.guide(pts)
        for k, edge in enumerate(edges):
            self.predictions[edge] = (pts[k], nrm[k], bool(outside[k]), float(lengths[k]))

    def _new_vertex(self, a, b, xp, npn, n, d, target, length=None):
        """Add the triangle ``(a, b, new vertex at xp)`` (normal ``npn``, guidance
        ``length`` if known) if no front vertex is too close to ``xp``, it lies ahead of the
        edge (direction ``d``) and the triangle is valid; returns whether it was added."""
        close = self._front_vertices_near(xp, MIN_VERTEX_DISTANCE * target, n)
        close = close[(close != a) & (close != b)]
        if len(close):
            return False
        xa, xb = self.P[a], self.P[b]
        xpt = (float(xp[0]), float(xp[1]), float(xp[2]))
        mid = (0.5 * (xa[0] + xb[0]), 0.5 * (xa[1] + xb[1]), 0.5 * (xa[2] + xb[2]))
        if _dot(_sub(xpt, mid), d) <= 0.2 * _norm(_sub(xb, xa)) or \
                not self._triangle_ok(a, b, -1, xpt, n, MIN_ANGLE_NEW, False):
            return False
        v = self._add_vertex(xp, npn, length)
        self._add_triangle(a, b, v)
        self.stats.new_vertices += 1
        return True

    # -- seeding and the main loop ---------------------------------------------------------
    def _seed(self, i):
        """Place an equilateral triangle at input point ``i``; False if it does not fit."""
        proj = self.proj
        p, nrm = proj.project_with_normals(proj.points[i][None])
        p, nrm = p[0], nrm[0]
        length = float(self.guide(p[None])[0])
        frame = np.cross(nrm, [1.0, 0.0, 0.0])
        if np.linalg.norm(frame) < 0.5:
            frame = np.cross(nrm, [0.0, 1.0, 0.0])
        t1 = frame / np.linalg.norm(frame)
        t2 = np.cross(nrm, t1)
        guess = np.stack([p + length * t1, p + length * (0.5 * t1 + np.sqrt(0.75) * t2)])
        q, qn = proj.project_with_normals(guess)
        tri = np.stack([p, q[0], q[1]])
        tn = np.cross(tri[1] - tri[0], tri[2] - tri[0])
        if np.dot(tn, nrm) <= 0.5 * np.linalg.norm(tn):
            return False
        # a seed beside the mesh (a thin part the fronts could not enter) must not lie on it
        probes = np.vstack([tri.mean(axis=0), 0.5 * (tri + np.roll(tri, -1, axis=0))])
        if self.nv and self._covered(probes, probes[0], length):
            return False
        ids = [self._add_vertex(p, nrm), self._add_vertex(q[0], qn[0]),
               self._add_vertex(q[1], qn[1])]
        self._add_triangle(*ids)
        self.stats.seeds += 1
        return True

    def _report(self, message):
        if self.progress is None:
            return
        frac = min(0.999, self.area_done / max(self.area_total, 1e-300))
        if self.progress(frac, message) is False:
            raise Cancelled("the triangulation was cancelled")

    def run(self):
        """Triangulate; returns ``(vertices (V, 3), faces (F, 3))``."""
        proj = self.proj
        kappa_order = np.argsort(self.guide.lengths)[::-1]  # flattest (longest edges) first
        tried = 0
        checked = 0  # the vertices the points in kappa_order are known to be far from
        reach = SEED_DISTANCE * float(np.max(self.guide.lengths))
        for _ in range(MAX_SEEDS if self.max_seeds is None else self.max_seeds):
            if self.stats.truncated:
                break
            if self.nv > checked:
                # vertices are never removed nor moved: a point near the mesh stays near it,
                # so each round asks only about the points that were far in the previous one,
                # only about the vertices added since, and of those points only the ones in
                # reach of their bounding box (a surface of many pieces, such as the bonsai's
                # leaves, takes thousands of rounds, each meshing a small piece)
                new = self.V[checked: self.nv]
                checked = self.nv
                pts = proj.points[kappa_order]
                cand = np.flatnonzero(np.all((pts >= new.min(axis=0) - reach) &
                                             (pts <= new.max(axis=0) + reach), axis=1))
                if len(cand):
                    from scipy.spatial import cKDTree

                    dist, _ = cKDTree(new).query(pts[cand])
                    near = dist <= SEED_DISTANCE * self.guide.lengths[kappa_order[cand]]
                    kappa_order = np.delete(kappa_order, cand[near])
            if self.nv and len(kappa_order) < SEED_MIN_POINTS:
                break
            start = kappa_order[0]
            tried += 1
            if not self._seed(start):
                if self.nv == 0 and tried > 10:
                    raise FrontError("no seed triangle could be placed on the point cloud")
                kappa_order = kappa_order[kappa_order != start]
                continue
            self._advance()
        if self.nv == 0:
            raise FrontError("no seed triangle could be placed on the point cloud")
        for _ in range(REFINE_PASSES):
            if self.stats.truncated or not self._retry_given_up():
                break
            self._advance()
        self._fill_holes()
        return self.V[: self.nv].copy(), np.array(self.faces, dtype=np.int64).reshape(-1, 3)

    def front_loops(self):
        """The front as closed vertex loops, each listing ``a`` for its edges ``a -> b``
        (:func:`edge_loops`): each front edge ``a -> b`` continues with the front edge out of
        ``b`` into the unmeshed wedge it arrived in (the same choice as a front step)."""
        preferred = {}
        for a, b in self.front:
            c = self._neighbour(b, a, False, self.Pn[b])
            preferred[(a, b)] = (b, c) if c >= 0 else None
        return edge_loops(list(self.front), preferred)

    def _retry_given_up(self):
        """Reopen the given-up front edges with REFINE_FACTOR times shorter target lengths.

        A front gives up where its triangles are too large for the surface (thin parts and
        sharp folds of coarsely sampled scans, where neighbouring normals differ by ~90
        degrees); smaller triangles resolve them.  Returns whether any edge was reopened.
        """
        stuck = [e for e in self.border if e not in self.scan_border]
        if not stuck:
            return False
        self.length_factor *= REFINE_FACTOR
        self.predictions.clear()  # they depend on the target lengths
        for a, b in stuck:
            for v in (a, b):
                self.L[v] = min(self.L[v], self.length_factor * float(self.guide(self.V[v])[0]))
            self.border.discard((a, b))
            self.front[(a, b)] = 0
            self._push(a, b)
        return True

    def _fill_holes(self):
        """Fill front loops left by given-up edges (not borders of the scan) of at most
        ``MAX_HOLE_EDGES`` edges, or ``LONG_HOLE_EDGES`` where the triangles stay on the
        samples (:meth:`_on_the_samples`), with the best-shaped triangulation of the loop
        (dynamic programming over its diagonals, as in Liepa's hole filling, 2003); the
        relaxation after the front evens out the new triangles."""
        # filling one loop can change how loops through its vertices are traced: repeat
        failed: set[tuple[int, int]] = set()
        while True:
            filled = False
            for loop in (part for whole in self.front_loops() for part in simple_loops(whole)):
                k = len(loop)
                edges = [(loop[i], loop[(i + 1) % k]) for i in range(k)]
                if k < 3 or k > LONG_HOLE_EDGES or edges[0] in failed or \
                        2 * sum(e in self.scan_border for e in edges) > k:
                    continue
                tris = self._best_triangulation(loop)
                if not tris or (k > MAX_HOLE_EDGES and not self._on_the_samples(tris)):
                    failed.update(edges)
                    continue
                for tri in tris:
                    self._add_triangle(*tri)
                self.stats.holes_filled += 1
                filled = True
            if not filled:
                return

    def _on_the_samples(self, tris):
        """Whether every triangle of ``tris`` (vertex id triples) has its centroid within the
        border test's hard limit (``outside_spacings`` local spacings) of an input point."""
        tv = self.V[np.array(tris, dtype=np.int64)]
        dist, idx = self.proj.conn.tree.query(tv.mean(axis=1))
        return bool(np.all(dist <= self.outside_spacings * self.spacing[idx]))

    def _best_triangulation(self, loop):
        """Triangles ``(loop[i], loop[m], loop[j])`` of the polygon ``loop`` minimising the
        summed shape cost ``(sum of squared sides) / (4 sqrt 3 area)`` (1 for equilateral
        triangles), with every triangle facing along the loop's (Newell) normal or its own
        corners' normals and no diagonal that is already a mesh edge.  Returns ``[]`` when no
        such triangulation exists."""
        k = len(loop)
        pts = self.V[loop]
        normal = tuple(np.cross(pts, np.roll(pts, -1, axis=0)).sum(axis=0).tolist())
        P = [self.P[u] for u in loop]
        nrm = [tuple(x) for x in self.N[loop].tolist()]

        def edge_free(i, j):
            u, w = loop[i], loop[j]
            if u == w:
                return False
            if j == i + 1 or (i == 0 and j == k - 1):
                return True
            return ((u, w) if u < w else (w, u)) not in self.edge_faces

        def cost(i, m, j):
            # scalar tuple math: NumPy's per-call overhead dominated on single triangles
            p, q, r = P[i], P[m], P[j]
            tn = _cross(_sub(q, p), _sub(r, p))
            area2 = _norm(tn)
            # a loop twisted by a sharp fold has no single facing direction: a triangle may
            # face along the loop's normal or along its own corners' normals
            if area2 <= 0 or (_dot(tn, normal) <= 0 and
                              _dot(tn, (nrm[i][0] + nrm[m][0] + nrm[j][0],
                                        nrm[i][1] + nrm[m][1] + nrm[j][1],
                                        nrm[i][2] + nrm[m][2] + nrm[j][2])) <= 0):
                return math.inf
            qp, rq, pr = _sub(q, p), _sub(r, q), _sub(p, r)
            sides = _dot(qp, qp) + _dot(rq, rq) + _dot(pr, pr)
            return sides / (2 * math.sqrt(3) * area2)

        best = [[math.inf] * k for _ in range(k)]  # lists: O(k^3) scalar lookups
        split = [[-1] * k for _ in range(k)]
        for i in range(k - 1):
            best[i][i + 1] = 0.0
        for span in range(2, k):
            for i in range(k - span):
                j = i + span
                if not edge_free(i, j):
                    continue
                row = best[i]
                for m in range(i + 1, j):
                    c = row[m] + best[m][j]
                    if c < row[j]:
                        c += cost(i, m, j)
                        if c < row[j]:
                            row[j], split[i][j] = c, m
        if not math.isfinite(best[0][k - 1]):
            return []
        tris, stack = [], [(0, k - 1)]
        while stack:
            i, j = stack.pop()
            m = split[i][j]
            if m < 0:
                continue
            tris.append((loop[i], loop[m], loop[j]))
            stack += [(i, m), (m, j)]
        return tris

    def _advance(self):
        steps = 0
        # runaway guard: with edges never shorter than ~the sample spacing, a valid mesh has
        # fewer vertices than the cloud has points; far more means the front overlaps itself
        factor = VERTEX_BUDGET if self.vertex_budget is None else self.vertex_budget
        budget = factor * len(self.proj.points) + 1000
        while self.heap:
            if self.nv > budget:
                self.stats.truncated = True
                return
            _delay, _c, a, b = heapq.heappop(self.heap)
            if (a, b) not in self.front or (a, b) in self.border:
                continue
            self._step(a, b)
            steps += 1
            if steps % 500 == 0:
                self._report(f"{len(self.faces)} triangles")
