"""Writers of cross-section curves (:mod:`splineviz.core.sections`) as VTP or CSV.

VTP: one polyline cell per curve (a closed curve repeats its first vertex), with the cell
arrays ``length``, ``area`` (NaN for open curves) and ``closed``. CSV: one row per vertex,
``curve, closed, length, area, x, y, z``, so a spreadsheet can sum lengths per curve without
the geometry. Both are written atomically like every other output.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from splineviz.io import _vtk
from splineviz.io._util import atomic_output
from splineviz.io.errors import InvalidDataError, UnknownFormatError, WriteError

#: file suffixes :func:`write_curves` knows
CURVE_SUFFIXES = (".vtp", ".csv")


def curves_polydata(curves):
    """``pyvista.PolyData`` of the curves: polyline cells with length, area, closed.

    Parameters
    ----------
    curves : sequence of SectionCurve

    Returns
    -------
    pyvista.PolyData with ``sum(M_i)`` points and one line cell per curve
    """
    import pyvista as pv

    points, cells, offset = [], [], 0
    for c in curves:
        m = len(c.points)
        ids = np.arange(offset, offset + m)
        if c.closed:
            ids = np.r_[ids, offset]
        cells.append(np.r_[len(ids), ids])
        points.append(np.asarray(c.points, dtype=np.float64))
        offset += m
    if not points:
        raise InvalidDataError("there is no cross-section curve to write")
    poly = pv.PolyData(np.concatenate(points), lines=np.concatenate(cells).astype(np.int64))
    poly.cell_data["length"] = np.array([c.length for c in curves])
    poly.cell_data["area"] = np.array([c.area for c in curves])
    poly.cell_data["closed"] = np.array([c.closed for c in curves], dtype=np.uint8)
    return poly


def _write_vtp(path: Path, curves) -> None:
    from vtkmodules.vtkIOXML import vtkXMLPolyDataWriter

    poly = curves_polydata(curves)
    with atomic_output(path) as tmp:
        w = vtkXMLPolyDataWriter()
        w.SetFileName(str(tmp))
        w.SetInputData(poly)
        with _vtk.captured_vtk_output() as out:
            ok = w.Write()
        err = _vtk.first_vtk_error(out[0])
        if not ok or err:
            raise WriteError(f"cannot write {path.name}: {err or 'the writer failed'}")


def _write_csv(path: Path, curves) -> None:
    if not curves:
        raise InvalidDataError("there is no cross-section curve to write")
    rows = []
    for i, c in enumerate(curves):
        m = len(c.points)
        per_curve = np.tile([i, float(c.closed), c.length, c.area], (m, 1))
        rows.append(np.hstack([per_curve, np.asarray(c.points, dtype=np.float64)]))
    table = np.concatenate(rows)
    with atomic_output(path) as tmp:
        # 17 significant digits: the vertices are exact to rounding and should stay so
        np.savetxt(tmp, table, delimiter=",", header="curve,closed,length,area,x,y,z",
                   comments="", fmt=["%d", "%d", "%.17g", "%.17g", "%.17g", "%.17g", "%.17g"])


def write_curves(path, curves) -> Path:
    """Write cross-section curves as VTP or CSV (by suffix), atomically.

    Parameters
    ----------
    path : path-like ending in ``.vtp`` or ``.csv``
    curves : sequence of SectionCurve

    Returns
    -------
    Path
    """
    p = Path(os.fspath(path)).expanduser()
    suffix = p.suffix.lower()
    if suffix == ".vtp":
        _write_vtp(p, list(curves))
    elif suffix == ".csv":
        _write_csv(p, list(curves))
    else:
        raise UnknownFormatError(f"curves are written as {' or '.join(CURVE_SUFFIXES)}, "
                                 f"not {p.suffix or 'a file without suffix'}")
    return p
