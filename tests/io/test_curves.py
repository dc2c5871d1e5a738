"""Cross-section curves written as VTP and CSV keep vertices, lengths and areas."""

import numpy as np
import pytest
import pyvista as pv

from splineviz.core.sections import SectionCurve
from splineviz.io.curves import write_curves
from splineviz.io.errors import InvalidDataError, UnknownFormatError

T = np.linspace(0, 2 * np.pi, 40, endpoint=False)
LOOP = SectionCurve(np.c_[np.cos(T), np.sin(T), np.zeros_like(T)], True, 6.28, 3.14)
ARC = SectionCurve(np.c_[T, T ** 2, np.ones_like(T)][:7], False, 2.5, float("nan"))


def test_vtp_round_trip(tmp_path):
    path = write_curves(tmp_path / "c.vtp", [LOOP, ARC])
    poly = pv.read(path)
    assert poly.n_cells == 2 and poly.n_points == 47
    np.testing.assert_array_equal(poly.cell_data["length"], [6.28, 2.5])
    assert poly.cell_data["area"][0] == 3.14 and np.isnan(poly.cell_data["area"][1])
    loop = poly.get_cell(0).point_ids
    assert len(loop) == 41 and loop[0] == loop[-1]  # a closed polyline repeats its start
    np.testing.assert_array_equal(poly.points[:40], LOOP.points.astype(poly.points.dtype))


def test_csv_round_trip(tmp_path):
    path = write_curves(tmp_path / "c.csv", [LOOP, ARC])
    table = np.genfromtxt(path, delimiter=",", names=True)
    assert table.dtype.names == ("curve", "closed", "length", "area", "x", "y", "z")
    assert len(table) == 47
    np.testing.assert_array_equal(table["x"][:40], LOOP.points[:, 0])  # 17 digits: exact
    assert set(table["length"][table["curve"] == 1]) == {2.5}
    assert np.isnan(table["area"][-1]) and table["closed"][0] == 1


def test_refusals(tmp_path):
    with pytest.raises(UnknownFormatError):
        write_curves(tmp_path / "c.txt", [LOOP])
    with pytest.raises(InvalidDataError):
        write_curves(tmp_path / "c.vtp", [])
    assert not list(tmp_path.iterdir())
