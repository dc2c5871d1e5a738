"""Area and enclosed volume from the spline surface (issue 27): exact on a sphere field,
whose cubic-c1 and to-quadratic isosurfaces are spheres of a radius known from thesis
Lemma 4 (both reproduce x^2 + y^2 + z^2 up to 3 h^2 / 4), closer than a flying-edges
mesh; tabulated over the steps of a time-varying volume and written as CSV."""

from __future__ import annotations

import csv
import math

import numpy as np
import pytest

import splineviz as sv
from splineviz.core.splines import build_spline
from splineviz.core.surface_measures import MeasureError, measure_isosurface, triangle_rule
from splineviz.io.time_series import TimeSeries
from splineviz.model.quantities import quantities_over_time
from splineviz.model.scene import Scene


def _sphere_field(n=32, h=0.5, centre=(0.0, 0.0, 0.0)):
    g = (np.arange(n) - (n - 1) / 2) * h
    x, y, z = np.meshgrid(g, g, g, indexing="ij")
    f = (x - centre[0]) ** 2 + (y - centre[1]) ** 2 + (z - centre[2]) ** 2
    return sv.Volume(f, spacing=(h, h, h), origin=(g[0],) * 3)


def test_triangle_rule_is_exact_to_its_degree():
    uv, w = triangle_rule(4)
    u, v = uv.T
    # int_T u^a v^b = a! b! / (a + b + 2)!
    for a, b in ((0, 0), (3, 2), (7, 0), (2, 5)):
        exact = math.factorial(a) * math.factorial(b) / math.factorial(a + b + 2)
        assert np.sum(w * u**a * v**b) == pytest.approx(exact, rel=1e-13)


@pytest.mark.parametrize("model", ["cubic-c1", "to-quadratic"])
def test_sphere_area_and_volume_within_1e_5(model):
    h, iso = 0.5, 25.0
    vol = _sphere_field(h=h, centre=(0.13, -0.21, 0.07))
    r = math.sqrt(iso - 0.75 * h * h)  # Lemma 4 (iv): the spline is f + 3 h^2 / 4
    area, volume = 4 * math.pi * r * r, 4 / 3 * math.pi * r**3
    m = measure_isosurface(build_spline(vol, model), iso)
    assert m.closed
    assert m.area == pytest.approx(area, rel=1e-5)
    assert m.volume == pytest.approx(volume, rel=1e-5)

    # a flying-edges mesh of the same samples is further off (facets, trilinear edges)
    import pyvista as pv

    grid = pv.ImageData(dimensions=vol.shape, spacing=vol.spacing, origin=vol.origin)
    grid.point_data["f"] = np.asarray(vol.data).ravel(order="F")
    mesh = grid.contour([iso], scalars="f", method="flying_edges")
    assert abs(mesh.area / area - 1) > 100 * abs(m.area / area - 1)
    assert abs(mesh.volume / volume - 1) > 100 * abs(m.volume / volume - 1)


def test_open_surface_has_no_volume_and_no_surface_is_refused():
    vol = _sphere_field(n=16, h=0.5)
    s = build_spline(vol, "cubic-c1")
    m = measure_isosurface(s, 20.0)  # radius 4.4 > half the box: cut by its faces
    assert not m.closed and math.isnan(m.volume) and m.area > 0
    with pytest.raises(MeasureError, match="outside the data range"):
        measure_isosurface(s, 1e6)


def test_table_over_time_and_csv(tmp_path):
    h = 0.5
    base = np.asarray(_sphere_field(n=24, h=h).data)
    steps = np.stack([base / (1.0 + 0.25 * t) for t in range(3)])  # a growing sphere
    series = TimeSeries.from_array(steps, spacing=(h,) * 3, origin=(-5.75,) * 3,
                                   times=[0.0, 0.5, 1.0], unit="s")
    scene = Scene()
    scene.add_time_series(series, "grow", isovalue=16.0, model="to-quadratic")
    scene.set_step(1)
    table = quantities_over_time(scene)
    assert scene.step_index() == 1  # the scene is not moved
    assert table.column("time") == [0.0, 0.5, 1.0]
    for k, volume in enumerate(table.column("volume")):
        # the spline of f / c is (f + 3 h^2 / 4) / c: a sphere of radius^2 16 c - 3 h^2 / 4
        r = math.sqrt(16.0 * (1.0 + 0.25 * k) - 0.75 * h * h)
        assert volume == pytest.approx(4 / 3 * math.pi * r**3, rel=1e-5)
    table.to_csv(tmp_path / "q.csv")
    with open(tmp_path / "q.csv", newline="") as fh:
        rows = list(csv.reader(fh))
    assert rows[0] == ["step", "time [s]", "object", "area", "volume", "length"]
    assert [r[0] for r in rows[1:]] == ["0", "1", "2"]
    assert float(rows[3][4]) == table.rows[2][4]


def test_section_length_and_area_over_time():
    h = 0.5
    base = np.asarray(_sphere_field(n=24, h=h).data)
    steps = np.stack([base / (1.0 + 0.25 * t) for t in range(2)])
    scene = Scene()
    vol = scene.add_time_series(TimeSeries.from_array(steps, spacing=(h,) * 3,
                                                      origin=(-5.75,) * 3), "grow",
                                isovalue=16.0, model="cubic-c1")
    iso = scene.isosurfaces[0]
    plane = scene.add_clip_plane((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), volume=vol)
    scene.add_section(iso, plane, name="equator")
    table = quantities_over_time(scene)
    assert table.column("object") == ["isosurface", "equator"] * 2
    for k in range(2):
        r = math.sqrt(16.0 * (1.0 + 0.25 * k) - 0.75 * h * h)  # the equator of the sphere
        assert table.column("length", "equator")[k] == pytest.approx(2 * math.pi * r, rel=1e-5)
        assert table.column("area", "equator")[k] == pytest.approx(math.pi * r * r, rel=1e-5)
        assert math.isnan(table.column("volume", "equator")[k])
        assert math.isnan(table.column("length", "isosurface")[k])
