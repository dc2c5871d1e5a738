"""Sort-last compositing of ray-cast bricks into one frame (as IceT does for ParaView).

Each brick's ray caster returns a :class:`Fragment`: its first hits in the brick's own cells,
cropped to the rectangle of pixels that have one. Because the ray caster gives exact
window depth per pixel and the bricks do not overlap, the first hit of the whole volume is
the brick hit of least depth (:meth:`Composite.add_nearest`, any arrival order), or, painting
fragments in back-to-front brick order, the last one painted (:meth:`Composite.paint`, the
order translucent layers are blended in; the same first hits).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from splineviz.core.raycast_reference import BACKGROUND, Frame


@dataclass
class Fragment:
    """The hits of one brick inside the pixel rectangle ``rect``.

    Attributes
    ----------
    index : (3,) int, the brick
    rect : (r0, r1, c0, c1) half-open rows and columns (empty: r0 == r1)
    hit : (h, w) bool
    depth : (h, w) float32 window depth (1 where no hit)
    position, normal : (h, w, 3) float64 (NaN where no hit)
    color : (h, w, 4) uint8
    stats : dict, timings and value bounds reported by the worker
    """

    index: tuple
    rect: tuple
    hit: np.ndarray
    depth: np.ndarray
    position: np.ndarray
    normal: np.ndarray
    color: np.ndarray
    stats: dict = field(default_factory=dict)

    @classmethod
    def from_frame(cls, index, frame: Frame, stats=None, offset=(0, 0)) -> Fragment:
        """Crop a brick's frame to the bounding rectangle of its hits.

        Parameters
        ----------
        index : (3,) int
        frame : Frame
            The whole frame, or a window of it whose first pixel is at ``offset``.
        stats : dict, optional
        offset : (row, column) of the frame's first pixel in the whole frame
        """
        rows = np.flatnonzero(frame.hit.any(axis=1))
        cols = np.flatnonzero(frame.hit.any(axis=0))
        if rows.size == 0:
            r0 = r1 = c0 = c1 = 0
            rect = (0, 0, 0, 0)
        else:
            r0, r1, c0, c1 = int(rows[0]), int(rows[-1]) + 1, int(cols[0]), int(cols[-1]) + 1
            dr, dc = (int(v) for v in offset)
            rect = (r0 + dr, r1 + dr, c0 + dc, c1 + dc)
        crop = (slice(r0, r1), slice(c0, c1))
        return cls(tuple(index), rect, frame.hit[crop].copy(), frame.depth[crop].copy(),
                   frame.position[crop].copy(), frame.normal[crop].copy(),
                   frame.color[crop].copy(), dict(stats or {}))


class Composite:
    """Colour and depth of a frame being assembled from fragments.

    Parameters
    ----------
    size : (width, height)
    """

    def __init__(self, size):
        w, h = size
        self.size = (int(w), int(h))
        self.hit = np.zeros((h, w), bool)
        self.depth = np.ones((h, w), np.float32)
        self.position = np.full((h, w, 3), np.nan)
        self.normal = np.full((h, w, 3), np.nan)
        self.color = np.empty((h, w, 4), np.uint8)
        self.color[:] = [*(int(round(255 * c)) for c in BACKGROUND), 255]

    def _put(self, frag: Fragment, take: np.ndarray) -> None:
        r0, r1, c0, c1 = frag.rect
        win = (slice(r0, r1), slice(c0, c1))
        self.hit[win][take] = True
        self.depth[win][take] = frag.depth[take]
        self.position[win][take] = frag.position[take]
        self.normal[win][take] = frag.normal[take]
        self.color[win][take] = frag.color[take]

    def add_nearest(self, frag: Fragment) -> None:
        """Keep, per pixel, the hit of least depth (opaque surfaces; any order). On equal
        depth (a hit on the face two bricks share) the earlier one stays."""
        r0, r1, c0, c1 = frag.rect
        if r0 == r1:
            return
        take = frag.hit & (frag.depth < self.depth[r0:r1, c0:c1])
        self._put(frag, take)

    def paint(self, frag: Fragment) -> None:
        """Paint a fragment over the others (call in back-to-front brick order)."""
        if frag.rect[0] == frag.rect[1]:
            return
        self._put(frag, frag.hit)

    def frame(self) -> Frame:
        """The composite as a :class:`~splineviz.core.raycast_reference.Frame` (copies)."""
        return Frame(self.hit.copy(), self.position.copy(), self.normal.copy(),
                     self.depth.copy(), self.color.copy())


def blend(frame: Frame, opacity: float, background=BACKGROUND) -> np.ndarray:
    """(H, W, 3) uint8 picture of a translucent surface: its shaded first hit over the
    background with ``opacity`` (the picture a translucent layer shows over empty space)."""
    bg = np.asarray(background, float) * 255.0
    rgb = frame.color[..., :3].astype(np.float64)
    out = np.where(frame.hit[..., None], opacity * rgb + (1.0 - opacity) * bg, bg)
    return np.rint(out).astype(np.uint8)
