"""Synthetic data sources: scalar functions sampled on a grid, registered by plugins.

Plugins add sources through ``api.add_source`` (:mod:`splineviz.plugins`); the GUI's Sources
menu lists them and sessions name them (a ``Source`` object), so the registry lives here, below
``io`` and ``model``, and is filled through the registry's loader hook
(:mod:`splineviz.core.registry`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from splineviz.core.errors import SplinevizError
from splineviz.core.registry import Registry
from splineviz.core.volume import Volume


class SourceError(SplinevizError, ValueError):
    """An unknown source name, or a grid a source cannot be sampled on."""


@dataclass(frozen=True)
class Source:
    """A synthetic data source: a scalar function sampled on a grid.

    Attributes
    ----------
    name : str
        Registry key, e.g. ``"marschner-lobb"``.
    title : str
        Human-readable name for menus.
    function : callable
        Vectorised ``f(x, y, z) -> values`` over arrays of equal shape.
    bounds : ((xmin, xmax), (ymin, ymax), (zmin, zmax))
    shape : (3,) tuple of int
        Default sampling grid.
    isovalue : float or None
        A suggested isovalue.
    plugin : str
    description : str
    """

    name: str
    title: str
    function: Callable
    bounds: tuple
    shape: tuple[int, int, int] = (64, 64, 64)
    isovalue: float | None = None
    plugin: str = ""
    description: str = ""

    def volume(self, shape=None) -> Volume:
        """Sample the source on ``shape`` (default :attr:`shape`), an ``(nx, ny, nz)``
        :class:`~splineviz.Volume` spanning :attr:`bounds`."""
        shp = tuple(int(n) for n in (shape or self.shape))
        if len(shp) != 3 or min(shp) < 2:
            raise SourceError(f"source {self.name!r} needs a shape of three sizes >= 2, got {shp}")
        return Volume.from_function(self.function, shp, self.bounds)


#: name -> Source, filled by plugins
SOURCES: Registry[Source] = Registry("source", error=SourceError)


def sources() -> dict[str, Source]:
    """All synthetic data sources the installed plugins offer (for the GUI's Sources menu)."""
    return SOURCES.entries()


def source_volume(name: str, shape=None) -> Volume:
    """Sample the source ``name`` on ``shape`` (its default grid when None).

    Raises
    ------
    SourceError
        No installed plugin offers ``name`` (the message names those that exist), or
        ``shape`` is not three sizes >= 2.
    """
    return SOURCES.lookup(name).volume(shape)
