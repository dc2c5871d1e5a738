"""Exact cross sections (splineviz.core.sections) on fields the splines reproduce exactly.

cubic-c1 and Q_2 map x^2 + y^2 + z^2 to itself plus 3 h^2 / 4 (Lemma 4), so away from the
box boundary their isosurface of that field is an exact sphere and its sections are exact
circles; the linear field x is reproduced exactly, so its isosurfaces are exact planes.
"""

import numpy as np
import pytest

import splineviz as sv
from splineviz.core import sections
from splineviz.core.volume import Volume

#: samples on a unit grid centred at 0: x^2 + y^2 + z^2 are quarter-integers, exact in float32
SPHERE = Volume.from_function(lambda x, y, z: x * x + y * y + z * z, (32, 32, 32),
                              ((-15.5, 15.5),) * 3)
RADIUS = 10.0
ISO = RADIUS**2 + 0.75  # + 3 h^2 / 4 with h = 1
EXACT = ("cubic-c1", "to-quadratic")


@pytest.fixture(scope="module", params=EXACT)
def sphere(request):
    return sv.build_spline(SPHERE, request.param)


def _on_surface(spline, iso, points):
    lo, hi = spline.volume.finite_range
    return np.abs(spline.evaluate(points) - iso).max() / (hi - lo)


@pytest.mark.parametrize("origin, normal", [((0, 0, 2.3), (0, 0, 1)),
                                            ((1.0, -0.5, 0.7), (0.3, -0.8, 0.52))])
def test_plane_section_of_exact_sphere_is_the_circle(sphere, origin, normal):
    curves = sections.plane_section(sphere, ISO, origin, normal)
    assert len(curves) == 1
    c = curves[0]
    n = np.asarray(normal, float) / np.linalg.norm(normal)
    d = float(np.dot(origin, n))
    r = np.sqrt(RADIUS**2 - d * d)
    assert c.closed
    assert abs(c.length / (2 * np.pi * r) - 1) < 1e-6
    assert abs(c.area / (np.pi * r * r) - 1) < 1e-6
    assert _on_surface(sphere, ISO, c.points) < 1e-6
    assert np.abs((c.points - origin) @ n).max() < 1e-9


def test_two_isosurfaces_meet_in_the_circle(sphere):
    # x reproduced exactly on another grid (other spacing, origin and extent)
    lin = Volume.from_function(lambda x, y, z: x + 0 * y, (20, 24, 28),
                               ((-12, 12), (-14, 13), (-13, 14)))
    plane = sv.build_spline(lin, sphere.model)
    curves = sections.surface_intersection(sphere, ISO, plane, 3.1)
    assert len(curves) == 1
    c = curves[0]
    r = np.sqrt(RADIUS**2 - 3.1**2)
    assert c.closed
    assert abs(c.length / (2 * np.pi * r) - 1) < 1e-6
    assert abs(c.area / (np.pi * r * r) - 1) < 1e-6
    assert _on_surface(sphere, ISO, c.points) < 1e-6
    assert _on_surface(plane, 3.1, c.points) < 1e-6


def test_open_section_ends_on_the_box_faces():
    # a sphere centred outside the box: the section leaves the box through the x = 15.5 face
    vol = Volume.from_function(lambda x, y, z: (x - 20) ** 2 + y * y + z * z, (24, 24, 24),
                               ((-7.5, 15.5), (-11.5, 11.5), (-11.5, 11.5)))
    s = sv.build_spline(vol, "cubic-c1")
    curves = sections.plane_section(s, 64.75, (0, 0, 1.0), (0, 0, 1))
    assert len(curves) == 1
    c = curves[0]
    assert not c.closed and np.isnan(c.area)
    ends = c.points[[0, -1]]
    np.testing.assert_allclose(ends[:, 0], 15.5, atol=1e-9)
    assert _on_surface(s, 64.75, c.points) < 1e-6
    # away from the face (where the ghost layer's linear extrapolation ends the quadratic
    # reproduction) the vertices are on the circle of radius sqrt(64 - 1) around x = 20
    inner = c.points[c.points[:, 0] < 13.5]
    assert len(inner) > 20
    np.testing.assert_allclose(np.hypot(inner[:, 0] - 20, inner[:, 1]), np.sqrt(63.0),
                               rtol=1e-9)
    assert c.length > 2 * np.sqrt(63.0) * np.arccos(6.5 / np.sqrt(63.0))


def test_trilinear_sections_lie_on_both_surfaces():
    s = sv.build_spline(SPHERE, "trilinear")
    curves = sections.plane_section(s, ISO, (0.3, 0.2, 0.1), (1, 2, 3))
    assert len(curves) == 1 and curves[0].closed
    assert _on_surface(s, ISO, curves[0].points) < 1e-6


def test_no_section_and_bad_input():
    s = sv.build_spline(SPHERE, "trilinear")
    assert sections.plane_section(s, ISO, (0, 0, 14.0), (0, 0, 1)) == []
    with pytest.raises(sections.SectionError):
        sections.plane_section(s, ISO, (0, 0, 0), (0, 0, 0))
    far = Volume(np.zeros((4, 4, 4)), origin=(100, 100, 100))
    with pytest.raises(sections.SectionError):
        sections.surface_intersection(s, ISO, sv.build_spline(far, "trilinear"), 0.0)
