"""Quantities over time: area and enclosed volume of each isosurface, and length and enclosed
area of each cross section, at each step of a scene's time-varying volumes, as a table that
exports to CSV.

The figures come from the spline surface itself
(:func:`splineviz.core.surface_measures.measure_isosurface`; sections:
:func:`splineviz.core.sections.plane_section` and
:func:`~splineviz.core.sections.surface_intersection`), not from a flying-edges mesh, whose
smoothing and facets misestimate them.
"""

from __future__ import annotations

import csv
import math
import os
from dataclasses import dataclass, field

from splineviz.core.surface_measures import SurfaceMeasures, measure_isosurface
from splineviz.model.nodes import IsosurfaceNode, SectionNode
from splineviz.model.scene import Scene

#: the columns of :class:`QuantityTable` (and of its CSV file): an isosurface's row has its
#: area and enclosed volume (NaN when the surface leaves the data box) and no length; a
#: section's row the summed length of its curves and the area they enclose (closed ones)
COLUMNS = ("step", "time", "object", "area", "volume", "length")


def measure(scene: Scene, iso: IsosurfaceNode, volume=None, **options) -> SurfaceMeasures:
    """Area and enclosed volume of ``iso`` in ``volume`` (default: the samples its volume
    node shows now, smoothed where it is; ``options``: ``order``, ``refine`` of
    :func:`~splineviz.core.surface_measures.measure_isosurface`)."""
    return measure_isosurface(_spline(scene, iso, volume), iso.isovalue, **options)


def _spline(scene: Scene, iso: IsosurfaceNode, volume=None):
    from splineviz.core.splines import build_spline

    volume = scene.volume_of(iso).active if volume is None else volume
    return build_spline(volume, iso.model, **iso.model_options())


def measure_section(scene: Scene, node: SectionNode, volumes=None) -> tuple[float, float]:
    """``(enclosed area, length)`` of a section's curves (areas of the closed ones), in
    ``volumes`` (volume id -> Volume; default: what the volume nodes show now)."""
    from splineviz.core import sections

    volumes = volumes or {}
    iso = scene.get(node.isosurface_id)
    spline = _spline(scene, iso, volumes.get(iso.volume_id))
    if node.plane_id is not None:
        plane = scene.get(node.plane_id)
        curves = sections.plane_section(spline, iso.isovalue, plane.origin, plane.normal)
    else:
        other = scene.get(node.other_id)
        curves = sections.surface_intersection(
            spline, iso.isovalue, _spline(scene, other, volumes.get(other.volume_id)),
            other.isovalue)
    area = sum(c.area for c in curves if c.closed)
    return float(area), float(sum(c.length for c in curves))


@dataclass
class QuantityTable:
    """Rows of ``(step, time, object name, area, volume, length)`` (:data:`COLUMNS`), with
    the units of time and length."""

    rows: list = field(default_factory=list)
    time_unit: str = ""
    length_unit: str = ""

    def column(self, name: str, obj: str | None = None) -> list:
        """One column (of one object's rows when ``obj`` names it)."""
        k = COLUMNS.index(name)
        return [r[k] for r in self.rows if obj is None or r[2] == obj]

    def to_csv(self, path) -> None:
        """Write the table with a header naming the units (``time [s]``, ``area [mm^2]``)."""
        def head(name, power=1):
            lu = self.length_unit
            unit = self.time_unit if name == "time" else \
                f"{lu}^{power}" if lu and power > 1 else lu
            return f"{name} [{unit}]" if unit else name

        header = ["step", head("time"), "object", head("area", 2), head("volume", 3),
                  head("length")]
        with open(os.fspath(path), "w", newline="", encoding="utf-8") as fh:
            out = csv.writer(fh)
            out.writerow(header)
            for step, time, name, area, volume, length in self.rows:
                out.writerow([step, repr(float(time)), name, repr(area), repr(volume),
                              repr(length)])


def _step_volumes(scene: Scene, time: float) -> dict:
    """Volume id -> the samples of each time-varying volume's step at ``time`` (read from
    its series; not the node's data, so that the scene is not moved)."""
    out = {}
    for node in scene.time_varying:
        k = node.series.index_at_or_before(time - node.time_offset)
        out[node.id] = node.series.step(k)
    return out


def quantities_over_time(scene: Scene, isosurfaces=None, steps=None, cancelled=None,
                         **options) -> QuantityTable:
    """Area and enclosed volume of ``isosurfaces`` (default: all), and length and enclosed
    area of every section of them, at each of ``steps`` (indices of
    :meth:`Scene.time_steps`; default all, or the one step of a scene that does not vary).

    The steps are read from the volumes' series (their samples as read: a smoothing the
    view applies is left out, except at a volume that does not vary); the scene is not
    moved, so this may run on a job thread. ``cancelled()``, when given, is asked between
    objects: True stops the table where it is. ``options``: ``order``, ``refine`` of
    :func:`~splineviz.core.surface_measures.measure_isosurface`.

    Returns
    -------
    QuantityTable
    """
    isos = list(scene.isosurfaces if isosurfaces is None else isosurfaces)
    ids = {i.id for i in isos}
    secs = [s for s in scene.sections if s.isosurface_id in ids]
    times = scene.time_steps()
    varying = scene.time_varying
    table = QuantityTable(time_unit=varying[0].time_unit if varying else "",
                          length_unit=scene.length_unit())
    nan = math.nan
    for k in ((None,) if not times else range(len(times)) if steps is None else steps):
        t = scene.time if k is None else times[k]
        volumes = {} if k is None else _step_volumes(scene, t)
        for iso in isos:
            if cancelled is not None and cancelled():
                return table
            m = measure(scene, iso, volumes.get(iso.volume_id), **options)
            table.rows.append((k or 0, t, iso.name, m.area, m.volume, nan))
        for sec in secs:
            if cancelled is not None and cancelled():
                return table
            area, length = measure_section(scene, sec, volumes)
            table.rows.append((k or 0, t, sec.name, area, nan, length))
    return table
