"""Colour maps by name (matplotlib's tables; the offered names are
:data:`splineviz.core.colour_by.COLORMAPS`) and the colouring of frames by a scalar.

The maps offered are the perceptually uniform sequential ones and a few diverging ones for
signed values (curvatures); the tables are matplotlib's, not copies.

Conventions: scalars ``(H, W)`` float with NaN where there is no value; colours ``uint8``.
"""

from __future__ import annotations

from functools import cache

import numpy as np

from splineviz.core.colour_by import COLORMAPS
from splineviz.core.errors import SplinevizError

#: entries of a lookup table
LUT_SIZE = 256
#: colour of a hit without a value (outside the second volume, vanishing gradient)
NAN_COLOR = (128, 128, 128)


class ColormapError(SplinevizError, ValueError):
    """A colour map name matplotlib does not know."""


@cache
def lut(name: str) -> np.ndarray:
    """``(LUT_SIZE, 3)`` uint8 table of the matplotlib colour map ``name``."""
    import matplotlib

    try:
        cmap = matplotlib.colormaps[name]
    except KeyError:
        raise ColormapError(f"unknown colour map {name!r}; choose one of "
                            f"{', '.join(COLORMAPS)}") from None
    rgba = cmap(np.linspace(0.0, 1.0, LUT_SIZE))
    table = np.rint(rgba[:, :3] * 255.0).astype(np.uint8)
    table.flags.writeable = False
    return table


def colorize(values: np.ndarray, name: str, lo: float, hi: float) -> np.ndarray:
    """Colours of scalars through the map ``name`` spanning ``[lo, hi]`` (clamped outside).

    Parameters
    ----------
    values : (...,) float, NaN allowed
    name : str
    lo, hi : float, lo < hi

    Returns
    -------
    (..., 3) uint8
    """
    v = np.asarray(values, dtype=np.float64)
    finite = np.isfinite(v)
    t = np.clip((np.where(finite, v, lo) - lo) / (hi - lo), 0.0, 1.0)
    idx = np.minimum((t * LUT_SIZE).astype(np.int64), LUT_SIZE - 1)
    out = lut(name)[idx]
    out[~finite] = NAN_COLOR
    return out
