"""Quantities of isosurfaces over time: area and enclosed volume of each isosurface at each
step of a scene's time-varying volumes, as a table that exports to CSV.

The figures come from the spline surface itself
(:func:`splineviz.core.surface_measures.measure_isosurface`), not from a flying-edges mesh,
whose smoothing and facets misestimate them.
"""

from __future__ import annotations

import csv
import os
from dataclasses import dataclass, field

from splineviz.core.surface_measures import SurfaceMeasures, measure_isosurface
from splineviz.model.nodes import IsosurfaceNode
from splineviz.model.scene import Scene

#: the columns of :class:`QuantityTable` (and of its CSV file)
COLUMNS = ("step", "time", "isosurface", "area", "volume")


def measure(scene: Scene, iso: IsosurfaceNode, volume=None, **options) -> SurfaceMeasures:
    """Area and enclosed volume of ``iso`` in ``volume`` (default: the samples its volume
    node shows now, smoothed where it is; ``options``: ``order``, ``refine`` of
    :func:`~splineviz.core.surface_measures.measure_isosurface`)."""
    from splineviz.core.splines import build_spline

    volume = scene.volume_of(iso).active if volume is None else volume
    spline = build_spline(volume, iso.model, **iso.model_options())
    return measure_isosurface(spline, iso.isovalue, **options)


@dataclass
class QuantityTable:
    """Rows of ``(step, time, isosurface name, area, volume)`` (:data:`COLUMNS`), with the
    units of time and length."""

    rows: list = field(default_factory=list)
    time_unit: str = ""
    length_unit: str = ""

    def column(self, name: str, isosurface: str | None = None) -> list:
        """One column (of one isosurface's rows when ``isosurface`` is given)."""
        k = COLUMNS.index(name)
        return [r[k] for r in self.rows if isosurface is None or r[2] == isosurface]

    def to_csv(self, path) -> None:
        """Write the table with a header naming the units (``time [s]``, ``area [mm^2]``)."""
        def head(name, unit):
            return f"{name} [{unit}]" if unit else name

        lu = self.length_unit
        header = ["step", head("time", self.time_unit), "isosurface",
                  head("area", f"{lu}^2" if lu else ""), head("volume", f"{lu}^3" if lu else "")]
        with open(os.fspath(path), "w", newline="", encoding="utf-8") as fh:
            out = csv.writer(fh)
            out.writerow(header)
            for step, time, name, area, volume in self.rows:
                out.writerow([step, repr(float(time)), name, repr(area), repr(volume)])


def quantities_over_time(scene: Scene, isosurfaces=None, steps=None, cancelled=None,
                         **options) -> QuantityTable:
    """Area and enclosed volume of ``isosurfaces`` (default: all) at each of ``steps``
    (indices of :meth:`Scene.time_steps`; default all, or the one step of a scene that does
    not vary).

    The steps are read from the volumes' series (their samples as read: a smoothing the
    view applies is left out, except at a volume that does not vary); the scene is not
    moved, so this may run on a job thread. ``cancelled()``, when given, is asked between
    steps: True stops the table where it is.

    Returns
    -------
    QuantityTable
    """
    isos = list(scene.isosurfaces if isosurfaces is None else isosurfaces)
    times = scene.time_steps()
    varying = scene.time_varying
    table = QuantityTable(time_unit=varying[0].time_unit if varying else "",
                          length_unit=scene.length_unit())
    if not times:
        for iso in isos:
            m = measure(scene, iso, **options)
            table.rows.append((0, scene.time, iso.name, m.area, m.volume))
        return table
    for k in (range(len(times)) if steps is None else steps):
        for iso in isos:
            if cancelled is not None and cancelled():
                return table
            node = scene.volume_of(iso)
            volume = None
            if node.series is not None:
                volume = node.series.step(node.series.index_at_or_before(
                    times[k] - node.time_offset))
            m = measure(scene, iso, volume, **options)
            table.rows.append((k, times[k], iso.name, m.area, m.volume))
    return table
