"""The NumPy reference ray caster against exact ray-sphere intersections."""

import numpy as np
import pytest

from splineviz.core.camera import Camera
from splineviz.core.raycast_reference import (
    ClipPlaneError,
    Frame,
    normalize_clip_planes,
    phong_shade,
    ray_intervals,
    reference_raycast,
)
from splineviz.core.splines.base import Spline
from splineviz.core.volume import Volume

CENTER = np.array([10.0, 7.0, 9.0])
RADIUS = 5.0


class SphereField(Spline):
    """s(x) = |x - c|^2 over a box, through the index-space interface of the models."""

    def index_derivatives(self, u, order):
        x = u * self._spacing + self._origin
        r = x - CENTER
        out = [np.sum(r * r, axis=1)[:, None]]
        if order >= 1:
            out.append(2 * r * self._spacing)  # index-space gradient (chain rule)
        return np.concatenate(out, axis=1)


@pytest.fixture
def sphere():
    # anisotropic spacing and a shifted origin so the world/index maps are exercised
    return SphereField(Volume(np.zeros((11, 15, 10)), spacing=(2.0, 1.0, 2.0), origin=(0, 0, 0)))


def _exact_first_root(origin, d, t0, t1, planes):
    """Smallest root of |o + t d - c|^2 = R^2 in [t0, t1] (d unit)."""
    oc = origin - CENTER
    b = d @ oc
    disc = b * b - (oc @ oc - RADIUS**2)
    sq = np.sqrt(np.maximum(disc, 0))
    out = np.full(len(d), np.nan)
    for cand in (-b - sq, -b + sq):
        ok = (disc >= 0) & (cand >= t0) & (cand <= t1) & np.isnan(out)
        out[ok] = cand[ok]
    return out


@pytest.mark.parametrize("clip", [False, True])
def test_reference_matches_exact_sphere(sphere, clip):
    cam = Camera((28, -12, 20), CENTER, view_up=(0, 0, 1), view_angle=25)
    planes = [((CENTER + [0.5, 0, 0]), (-1.0, -0.2, 0.0))] if clip else []
    w, h = 40, 30
    frame = reference_raycast(sphere, cam, (w, h), RADIUS**2, clip_planes=planes, step=0.5)
    assert isinstance(frame, Frame)
    origin, dirs = cam.rays((w, h))
    d = dirs.reshape(-1, 3)
    t0, t1 = ray_intervals(origin, d, sphere.bounds, normalize_clip_planes(planes))
    t = _exact_first_root(origin, d, t0, t1, planes).reshape(h, w)
    exact_hit = np.isfinite(t)
    assert exact_hit.sum() > 200
    # dense sampling may miss only grazing rays whose chord is shorter than a sample step
    oc = origin - CENTER
    b = d @ oc
    chord = 2 * np.sqrt(np.maximum(b * b - (oc @ oc - RADIUS**2), 0)).reshape(h, w)
    differ = frame.hit != exact_hit
    assert not np.any(frame.hit & ~exact_hit)
    assert np.all(chord[differ] < 0.5 * 2.0) and differ.sum() <= 0.02 * exact_hit.sum()
    exact_hit = exact_hit & frame.hit
    pos = origin + t[..., None] * dirs
    np.testing.assert_allclose(frame.position[exact_hit], pos[exact_hit], atol=1e-9)
    np.testing.assert_allclose(frame.normal[exact_hit], (pos[exact_hit] - CENTER) / RADIUS,
                               atol=1e-9)
    assert np.all(np.isnan(frame.position[~exact_hit]))
    assert np.all(frame.depth[~exact_hit] == 1)
    clip_range = cam.fit_clipping_range(sphere.bounds)
    np.testing.assert_allclose(frame.depth[exact_hit],
                               cam.window_depth(pos[exact_hit], clip_range), atol=1e-6)
    if clip:
        # the cut is exact: every hit on the kept side, and some hits are on the far half
        o, n = normalize_clip_planes(planes)[0]
        assert np.all((frame.position[exact_hit] - o) @ n >= -1e-9)
        assert np.any((frame.normal[exact_hit] @ cam.basis()[2]) > 0)


def test_ray_intervals_box_and_planes():
    o = np.array([-1.0, 0.5, 0.5])
    d = np.array([[1.0, 0, 0], [0, 1.0, 0], [1.0, 0, 0]])
    t0, t1 = ray_intervals(o, d, ((0, 1), (0, 1), (0, 1)), np.zeros((0, 2, 3)))
    np.testing.assert_allclose([t0[0], t1[0]], [1, 2])
    assert t0[1] > t1[1]  # parallel and outside the slab
    planes = normalize_clip_planes([((0.25, 0, 0), (-2.0, 0, 0))])  # keeps x <= 0.25
    t0, t1 = ray_intervals(o, d[:1], ((0, 1), (0, 1), (0, 1)), planes)
    np.testing.assert_allclose([t0[0], t1[0]], [1, 1.25])


def test_phong_shade_colors():
    hit = np.array([[True, True, False]])
    d = np.tile([0.0, 0.0, -1.0], (1, 3, 1))
    n = np.array([[[0, 0, -1.0], [0, 0, 1.0], [np.nan] * 3]])
    img = phong_shade(hit, n, d)
    assert img.dtype == np.uint8 and img.shape == (1, 3, 4)
    # facing the light head-on: ambient + diffuse + specular, saturating at 255 for red
    assert img[0, 0, 0] == 255 and img[0, 1, 2] == 255
    assert img[0, 0, 2] < img[0, 1, 2]  # front and back sides differ in colour
    assert tuple(img[0, 2, :3]) == (26, 26, 36)


@pytest.mark.parametrize("bad", [[((0, 0, 0), (0, 0, 0))], [(1, 2)], [((0, 0, np.inf), (1, 0, 0))]])
def test_bad_clip_planes(bad):
    with pytest.raises(ClipPlaneError):
        normalize_clip_planes(bad)
