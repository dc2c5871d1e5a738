"""The min-max octree of the ray caster (classify.cl): its stored levels and sizes."""

from __future__ import annotations

import numpy as np


def octree_levels(cells: tuple[int, int, int]) -> list[tuple[int, int, int, int]]:
    """(offset, nx, ny, nz) of the stored min-max octree levels 1, 2, ... (nodes of 2^L
    cells; level 0, the cells, is not stored: see classify.cl)."""
    levels = []
    off = 0
    dims = tuple(cells)
    while True:
        dims = tuple((n + 1) // 2 for n in dims)
        levels.append((off, *dims))
        off += int(np.prod(dims))
        if max(dims) == 1:
            return levels


def octree_nodes(levels) -> int:
    """Nodes of all stored octree levels."""
    return levels[-1][0] + int(np.prod(levels[-1][1:]))

