"""Slices of a spline (splineviz.core.slice_sampling): the sampled image is the spline on the
slice, and the contour on a slice of a shared CT lies on the isosurface and is the cross
section the 3-D view draws for a clip plane at the slice."""

import numpy as np
import pytest

import splineviz as sv
from splineviz.core import slice_sampling as ss
from splineviz.core import testfunctions as tf
from splineviz.model import ClipPlaneNode, Scene
from splineviz.model.analysis import section_curves


@pytest.fixture(scope="module")
def ml_spline():
    vol = sv.Volume.from_function(tf.ml, (12, 13, 14), tf.ml.domain)
    return vol, sv.build_spline(vol, model="cubic-c1")


@pytest.fixture(scope="module")
def tooth(shared_data):
    vol = sv.read_volume(shared_data / "volumes" / "tooth.nrrd")
    return vol, sv.build_spline(vol, model="cubic-c1")


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_image_is_the_spline_on_the_slice(ml_spline, axis):
    vol, spline = ml_spline
    b = np.asarray(spline.bounds)
    pos = 0.3 * b[axis, 0] + 0.7 * b[axis, 1]
    grid = ss.slice_grid(spline.bounds, vol.spacing, axis, pos, oversample=2)
    ua, va = ss.in_plane_axes(axis)
    assert (grid.us[0], grid.us[-1]) == tuple(b[ua]) and (grid.vs[0], grid.vs[-1]) == tuple(b[va])
    # two samples per grid step along each in-plane axis
    assert len(grid.us) == 2 * (vol.shape[ua] - 1) + 1
    values = ss.sample_slice(spline, grid)
    assert values.shape == (len(grid.vs), len(grid.us))
    j, i = 5, 7
    p = np.zeros(3)
    p[axis], p[ua], p[va] = pos, grid.us[i], grid.vs[j]
    assert values[j, i] == pytest.approx(spline.evaluate(p[None])[0], rel=1e-12, abs=1e-12)
    # a position outside the box is clamped onto its face
    assert ss.slice_grid(spline.bounds, vol.spacing, axis, b[axis, 1] + 5).position == b[axis, 1]


def test_bad_axis_is_one_sentence(ml_spline):
    with pytest.raises(ss.SliceError, match="0, 1 or 2"):
        ss.in_plane_axes(3)


def test_probe_reads_value_and_exact_gradient(ml_spline):
    _, spline = ml_spline
    p = np.array([0.1, -0.2, 0.05])
    pr = ss.probe(spline, p)
    assert pr.value == pytest.approx(spline.evaluate(p[None])[0])
    np.testing.assert_allclose(pr.gradient, spline.gradient(p[None])[0])
    assert "value" in pr.describe() and "gradient" in pr.describe()


def _distance_to_polyline(points, curve):
    """Distance of each (N, 3) point to the polyline of a SectionCurve."""
    v = curve.points
    a = v if curve.closed else v[:-1]
    b = np.roll(v, -1, axis=0) if curve.closed else v[1:]
    ab = b - a
    t = np.clip(np.einsum("snc,sc->sn", points[None] - a[:, None], ab)
                / np.maximum(np.einsum("sc,sc->s", ab, ab), 1e-300)[:, None], 0, 1)
    near = a[:, None] + t[..., None] * ab[:, None]
    return np.linalg.norm(points[None] - near, axis=-1).min(axis=0)


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_contour_on_a_ct_lies_on_the_isosurface_and_is_the_clip_plane_section(tooth, axis):
    vol, spline = tooth
    lo, hi = vol.finite_range
    iso = 0.35 * (lo + hi)
    b = np.asarray(spline.bounds)
    index = vol.shape[axis] // 2 + 3
    pos = vol.origin[axis] + index * vol.spacing[axis]
    curves = ss.slice_contours(spline, iso, axis, pos)
    assert curves, "the slice through the tooth must cut its surface"
    pts = np.concatenate([c.points for c in curves])
    # every vertex on the isosurface (within 1e-6 of the data range) and on the slice
    assert np.max(np.abs(spline.evaluate(pts) - iso)) <= 1e-6 * (hi - lo)
    np.testing.assert_allclose(pts[:, axis], pos, atol=1e-9 * np.ptp(b))

    # the 3-D view's cross section of a clip plane at the slice (its origin elsewhere in
    # the plane): the same curves
    scene = Scene()
    vnode = scene.add_volume(vol, name="tooth", isosurface=False)
    inode = scene.add_isosurface(vnode, isovalue=iso, model="cubic-c1")
    origin = b.mean(axis=1) + 0.1 * np.ptp(b, axis=1)
    origin[axis] = pos
    normal = np.zeros(3)
    normal[axis] = 1.0
    plane = scene.add(ClipPlaneNode(volume_id=vnode.id, origin=tuple(origin),
                                    normal=tuple(normal)))
    section = scene.add_section(inode, plane)
    other = section_curves(scene, section)
    assert len(other) == len(curves)
    assert sum(c.length for c in other) == pytest.approx(sum(c.length for c in curves),
                                                         rel=1e-5)
    other_pts = np.concatenate([c.points for c in other])
    # each vertex of one on the other's curves (within the sagitta tolerance of sections)
    sag = 2e-3 * min(vol.spacing)
    gap = np.min([_distance_to_polyline(pts, c) for c in other], axis=0)
    assert gap.max() <= 2 * sag
    gap = np.min([_distance_to_polyline(other_pts, c) for c in curves], axis=0)
    assert gap.max() <= 2 * sag
