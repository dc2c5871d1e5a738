"""Bricks of a volume for sort-last rendering: boxes, ghost halos, visibility order, culling.

A volume of ``n`` samples per axis is cut at sample planes into bricks of at most ``size``
cells per axis; neighbouring bricks share their boundary sample plane. A brick is rendered
from its *read box*: its samples plus a halo of ``halo`` real samples on every side that is
not the data boundary (the ghost layers its spline model reads beyond a box, thesis Remark
1; at the data boundary the ray caster extrapolates ghosts exactly as for the whole
volume). So the spline on a brick's own box is the global spline, and the first hit of a ray
is the nearest of the bricks' first hits inside their own boxes.

A brick owns whole cells of the ray caster's grid (:meth:`BrickGrid.cells`): the unit cells
between its samples, or, for models whose cells are cubes centred at the samples (type-6),
the cubes centred at its samples but the last (which its neighbour owns). It is ray cast in
the whole volume's coordinates (:class:`Placement`), so its rays compute, cell for cell, the
floats a single ray cast of the whole volume computes.

All boxes are in sample index space: ``inner`` are closed ranges ``[a, b]`` (the brick's
box, world ``origin + [a, b] * spacing``), ``read`` half-open ranges ``[r0, r1)``.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

from splineviz.core.camera import Camera


@dataclass(frozen=True)
class Brick:
    """One brick.

    Attributes
    ----------
    index : (3,) int
        Position in the brick grid.
    inner : ((a0, b0), (a1, b1), (a2, b2))
        Closed sample ranges of the brick's own box.
    read : ((r0, r1), ...)
        Half-open sample ranges read for it (inner plus halo, within the data).
    """

    index: tuple[int, int, int]
    inner: tuple
    read: tuple

    @property
    def samples(self) -> int:
        """Samples read for the brick."""
        return math.prod(r1 - r0 for r0, r1 in self.read)

    def touches_boundary(self, shape) -> bool:
        """Whether the read box meets the data boundary (the ray caster adds ghosts there)."""
        return any(r0 == 0 or r1 == n for (r0, r1), n in zip(self.read, shape, strict=True))


@dataclass(frozen=True)
class Placement:
    """Where a brick lies in the whole volume: what a ray caster of the brick's samples needs
    to cast it in the whole volume's index space (the same eye, entry points and cell
    boundaries as one cast of the whole volume; :meth:`RayCaster.render
    <splineviz.compute.raycast.RayCaster.render>`).

    Attributes
    ----------
    shape : (3,) int
        Samples of the whole volume.
    origin : (3,) float
        World origin of the whole volume.
    offset : (3,) int
        Whole-volume index of the brick's first sample (the start of its read box).
    cells : ((lo, hi), (lo, hi), (lo, hi)) int
        Half-open ranges of the whole volume's cells the brick's rays traverse.
    centred : bool
        Cells are cubes centred at the samples (cell c covers ``[c - 1/2, c + 1/2)``), not
        the unit cells between them (``[c, c + 1)``).
    """

    shape: tuple
    origin: tuple
    offset: tuple
    cells: tuple
    centred: bool = False

    def box(self) -> np.ndarray:
        """(3, 2) index-space box of the brick's cells within the data box ``[0, n - 1]``."""
        shift = 0.5 if self.centred else 0.0
        return np.array([(max(lo - shift, 0.0), min(hi - shift, n - 1.0))
                         for (lo, hi), n in zip(self.cells, self.shape, strict=True)])

    def face_planes(self, spacing) -> list:
        """Clip planes ``(origin, normal)`` (world) keeping :meth:`box`, on the faces inside
        the volume only: the restriction of a cast in the brick's own coordinates (the NumPy
        path), the same hits up to the rounding of those coordinates."""
        box = np.asarray(self.origin, float)[:, None] + self.box() * np.asarray(
            spacing, float)[:, None]
        planes = []
        for a, (lo, hi) in enumerate(self.box()):
            e = np.eye(3)[a]
            if lo > 0:
                planes.append((tuple(e * box[a, 0]), tuple(e)))
            if hi < self.shape[a] - 1:
                planes.append((tuple(e * box[a, 1]), tuple(-e)))
        return planes


class BrickGrid:
    """The bricks of a ``shape`` volume (see module docstring).

    Parameters
    ----------
    shape : (3,) int
        Samples per axis (>= 2 each).
    size : int or (3,) int
        Cells per brick along each axis (the last brick of an axis may be smaller).
    halo : int
        Ghost layers of the spline model (:attr:`ModelSpec.ghost_layers`).
    align : int
        The model's lattice period (:attr:`ModelSpec.lattice_period`): brick sizes and the
        starts of read boxes are multiples of it, so every brick's partition is the global
        one (a truncated-octahedral spline of a box starting at an odd offset differs).
    centred : bool
        The ray caster's cells are cubes centred at the samples
        (:attr:`ModelSpec.centred_cells`): a brick owns the cubes of its samples but the
        last, which the next brick owns (at the volume's end: it too).

    Examples
    --------
    >>> g = BrickGrid((9, 9, 5), size=4, halo=1)
    >>> g.counts, len(g)
    ((2, 2, 1), 4)
    >>> g[(1, 0, 0)].inner, g[(1, 0, 0)].read
    (((4, 8), (0, 4), (0, 4)), ((3, 9), (0, 6), (0, 5)))
    """

    def __init__(self, shape, size, halo: int, align: int = 1, centred: bool = False):
        self.shape = tuple(int(n) for n in shape)
        self.centred = bool(centred)
        align = max(1, int(align))
        self.size = tuple(-(-int(s) // align) * align for s in np.broadcast_to(size, 3))
        if min(self.shape) < 2 or min(self.size) < 1 or halo < 0:
            raise ValueError(f"bricks need >= 2 samples and >= 1 cell per axis, got shape "
                             f"{self.shape}, size {self.size}, halo {halo}")
        self.halo = int(halo)
        # cut planes per axis: 0, s, 2s, ..., n-1
        self.cuts = [list(range(0, n - 1, s)) + [n - 1]
                     for n, s in zip(self.shape, self.size, strict=True)]
        self.counts = tuple(len(c) - 1 for c in self.cuts)
        self._bricks = {}
        for idx in itertools.product(*(range(c) for c in self.counts)):
            inner = tuple((self.cuts[a][m], self.cuts[a][m + 1]) for a, m in enumerate(idx))
            reach = -(-self.halo // align) * align
            read = tuple((max(0, lo - reach), min(n, hi + 1 + self.halo))
                         for (lo, hi), n in zip(inner, self.shape, strict=True))
            self._bricks[idx] = Brick(idx, inner, read)

    @classmethod
    def split(cls, shape, counts, halo: int, align: int = 1, centred: bool = False
              ) -> BrickGrid:
        """A grid of ``counts`` bricks per axis (as equal as the cells allow)."""
        counts = np.broadcast_to(np.asarray(counts, int), 3)
        size = [-(-(n - 1) // c) for n, c in zip(shape, counts, strict=True)]
        return cls(shape, size, halo, align, centred)

    def __len__(self) -> int:
        return len(self._bricks)

    def __iter__(self):
        return iter(self._bricks.values())

    def __getitem__(self, index) -> Brick:
        return self._bricks[tuple(index)]

    def cells(self, brick: Brick) -> tuple:
        """Half-open ranges of the ray caster's cells the brick owns, per axis (together the
        bricks own every cell once)."""
        return tuple((lo, n if self.centred and hi == n - 1 else hi)
                     for (lo, hi), n in zip(brick.inner, self.shape, strict=True))

    def placement(self, brick: Brick, origin) -> Placement:
        """The brick's :class:`Placement` in the volume of origin ``origin``."""
        return Placement(self.shape, tuple(float(o) for o in origin),
                         tuple(r0 for r0, _ in brick.read), self.cells(brick), self.centred)

    def world_box(self, brick: Brick, spacing, origin) -> np.ndarray:
        """(3, 2) world bounds of the part of the volume the brick's cells cover (its own box;
        with centred cells shifted by half a cell, within the data box): its rays' hits lie
        in it."""
        box = self.placement(brick, origin).box()
        return np.asarray(origin, float)[:, None] + box * np.asarray(spacing, float)[:, None]

    def visibility_order(self, eye, spacing, origin) -> list[Brick]:
        """Bricks front to back as seen from ``eye`` (world point).

        For a brick B hidden behind A, every axis on which they differ has a cut plane with
        the eye on A's side, so B lies more brick steps away from the eye's slab on each of
        those axes and the sum of the steps orders them (exact for axis-aligned bricks under
        any perspective; bricks not hiding one another may come in either order).
        """
        key = self.slab_steps(eye, spacing, origin)
        return sorted(self, key=lambda b: (key[b.index], b.index))

    def slab_steps(self, eye, spacing, origin) -> dict:
        """Brick index -> sum over the axes of the brick steps from the eye's slab (the key of
        :meth:`visibility_order`: a brick hides only bricks of larger keys)."""
        u = (np.asarray(eye, float) - np.asarray(origin, float)) / np.asarray(spacing, float)
        # the planes between bricks' cells: at the cuts, half a cell before them when centred
        shift = 0.5 if self.centred else 0.0
        slab = [int(np.searchsorted(np.asarray(self.cuts[a][1:-1]) - shift, u[a],
                                    side="right"))
                if 0 <= u[a] <= self.shape[a] - 1
                else (-1 if u[a] < 0 else self.counts[a]) for a in range(3)]
        return {b.index: sum(abs(m - s) for m, s in zip(b.index, slab, strict=True))
                for b in self}


def value_margin(lo: float, hi: float, ghost: int, negative_mass: float,
                 at_boundary: bool) -> tuple[float, float]:
    """Conservative bounds of a spline over a box from the range of the samples it reads.

    Ghosts extrapolated at the data boundary widen the range (as
    :func:`splineviz.compute.raycast.sample_type_for` bounds them); each B-coefficient is an
    affine combination of samples whose negative weights sum to at most ``negative_mass``, and
    the piecewise polynomial lies within its coefficients.

    Returns
    -------
    (lo, hi) float
    """
    if at_boundary and ghost:
        grow = (hi - lo) * ghost * sum((1 + 2 * ghost) ** a for a in range(3))
        lo, hi = lo - grow, hi + grow
    w = negative_mass * (hi - lo)
    return lo - w, hi + w


def screen_footprint(camera: Camera, box, size, clipping_range):
    """Pixels a world box can cover, and the nearest window depth of any of its points.

    Parameters
    ----------
    camera : Camera
    box : (3, 2) world bounds
    size : (width, height)
    clipping_range : (near, far)

    Returns
    -------
    rect : (r0, r1, c0, c1)
        Half-open pixel rows/columns holding the projection (the whole image when the box
        reaches behind the eye).
    nearest : float
        The smallest window depth of the box (0 when it reaches behind the eye).
    hull : (k, 2) float or None
        Convex polygon (column, row) of the projected box in pixel units, counter-clockwise;
        the ray through a pixel centre meets the box only inside it. None: the whole image.
    """
    w, h = size
    corners = np.stack(np.meshgrid(*np.asarray(box, float), indexing="ij"),
                       axis=-1).reshape(-1, 3)
    right, up, dop = camera.basis()
    rel = corners - np.asarray(camera.position)
    ze = rel @ dop
    near, _ = clipping_range
    if ze.min() <= 0.5 * near:
        return (0, h, 0, w), 0.0, None
    tan_half = np.tan(np.radians(camera.view_angle) / 2.0)
    x = (rel @ right) / (ze * tan_half * w / h)
    y = (rel @ up) / (ze * tan_half)
    cols = (x + 1.0) * 0.5 * w - 0.5
    rows = (1.0 - y) * 0.5 * h - 0.5
    # pixel centres at integer (col, row): a pixel of slack on each side
    c0, c1 = int(np.floor(cols.min())) - 1, int(np.ceil(cols.max())) + 2
    r0, r1 = int(np.floor(rows.min())) - 1, int(np.ceil(rows.max())) + 2
    depth = float(camera.window_depth(corners[np.argmin(ze)], clipping_range))
    return ((max(r0, 0), min(r1, h), max(c0, 0), min(c1, w)), depth,
            _convex_hull(np.c_[cols, rows]))


def _cross2(o, a, b) -> float:
    """z of the cross product (a - o) x (b - o) of 2-D points."""
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])


def _convex_hull(points: np.ndarray) -> np.ndarray | None:
    """(k, 2) counter-clockwise hull of (n, 2) points (Andrew's monotone chain); None when
    the points are collinear (no area: no pixel test, the bounding rectangle serves)."""
    pts = sorted(map(tuple, points))

    def half(seq):
        out = []
        for p in seq:
            while len(out) >= 2 and _cross2(out[-2], out[-1], p) <= 0:
                out.pop()
            out.append(p)
        return out

    hull = half(pts)[:-1] + half(pts[::-1])[:-1]
    return np.asarray(hull, float) if len(hull) >= 3 else None


#: pixels of slack of the hull test (rounding of projected corners)
HULL_SLACK = 1e-3


def occluded(depth: np.ndarray, hit: np.ndarray, rect, nearest: float, hull=None) -> bool:
    """Whether every pixel whose ray can meet a box already shows a hit nearer than the box's
    nearest point (so nothing inside the box can be seen): the exact early termination of
    front-to-back sort-last rendering of opaque surfaces.

    Parameters
    ----------
    depth : (H, W) float32 window depth of the composite so far
    hit : (H, W) bool
    rect : (r0, r1, c0, c1)
    nearest : float, the box's nearest window depth
    hull : (k, 2) counter-clockwise (column, row) polygon of the box, or None (all of rect)
    """
    r0, r1, c0, c1 = rect
    if r0 >= r1 or c0 >= c1:
        return True  # the box projects outside the image
    covered = hit[r0:r1, c0:c1] & (depth[r0:r1, c0:c1] < nearest)
    if hull is None:
        return bool(np.all(covered))
    cc, rr = np.meshgrid(np.arange(c0, c1, dtype=float), np.arange(r0, r1, dtype=float))
    inside = np.ones(cc.shape, bool)
    for (xa, ya), (xb, yb) in zip(hull, np.roll(hull, -1, axis=0), strict=True):
        # left of every edge of a counter-clockwise polygon (rows grow downwards: the sign
        # of the cross product is the same for every edge, whichever it is)
        cross = (xb - xa) * (rr - ya) - (yb - ya) * (cc - xa)
        inside &= cross >= -HULL_SLACK * np.hypot(xb - xa, yb - ya)
    return bool(np.all(covered | ~inside))
