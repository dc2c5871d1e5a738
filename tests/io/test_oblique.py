"""Oblique scans (a grid rotated against the world axes) carried as a direction matrix from the
file to the picture: the samples lie where the file's affine says, the ray-cast surface lands
on the analytic world surface, composites with meshes in the same world, and its outline,
bounds, sections and exported meshes are in world too (issue 25)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from oblique_phantom import CENTRE, RADIUS, rotation

import splineviz as sv
from splineviz.core.camera import Camera
from splineviz.core.errors import SplinevizWarning
from splineviz.io import describe, read_volume
from splineviz.io.errors import InvalidDataError
from splineviz.io.geometry import affine_from, orientation

nib = pytest.importorskip("nibabel")

def sphere_file(path, rot, *, flip_x=True, shape=(28, 26, 24), spacing=(1.0, 1.1, 0.9)):
    """A NIfTI of ``|x - CENTRE|^2`` sampled on a grid turned by ``rot`` (and stored with its
    first axis reversed, as LAS files are), centred near the sphere. Returns the affine."""
    direction = rot.copy()
    if flip_x:
        direction[:, 0] *= -1
    half = 0.5 * (np.array(shape) - 1) * np.array(spacing)
    origin = CENTRE + np.array([0.7, -0.4, 0.3]) - direction @ half
    affine = affine_from(spacing, origin, direction)
    index = np.stack(np.meshgrid(*[np.arange(n) for n in shape], indexing="ij"), -1)
    world = nib.affines.apply_affine(affine, index)
    field = ((world - CENTRE) ** 2).sum(axis=-1).astype(np.float32)
    nib.save(nib.Nifti1Image(field, affine), path)
    return affine


def read(path, **options):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SplinevizWarning)
        return read_volume(path, **options)


def test_oblique_nifti_keeps_its_rotation_and_every_sample_its_world_position(tmp_path):
    rot = rotation(12.0, -7.0, 25.0)
    affine = sphere_file(tmp_path / "o.nii", rot)
    vol = read(tmp_path / "o.nii")
    assert not vol.axis_aligned
    np.testing.assert_allclose(vol.direction.T @ vol.direction, np.eye(3), atol=1e-12)
    assert np.linalg.det(vol.direction) == pytest.approx(1.0)
    data = np.asanyarray(nib.load(tmp_path / "o.nii").dataobj)
    orient = orientation(affine, data.shape, "o.nii")
    assert orient.flips[0] and orient.perm == (0, 1, 2)  # the stored flip is undone
    rng = np.random.default_rng(1)
    file_index = rng.integers(0, data.shape, size=(40, 3))
    ours = file_index.copy()
    ours[:, 0] = data.shape[0] - 1 - file_index[:, 0]
    world = vol.to_world(vol.index_to_world(ours.astype(float)))
    np.testing.assert_allclose(world, nib.affines.apply_affine(affine, file_index),
                               atol=1e-5)
    np.testing.assert_array_equal(vol.data[tuple(ours.T)], data[tuple(file_index.T)])
    # and back: world -> the volume's own frame -> index
    np.testing.assert_allclose(vol.world_to_index(vol.from_world(world)), ours, atol=1e-6)


def test_an_oblique_grid_is_refused_or_resampled_when_asked_and_info_prints_direction(
        tmp_path):
    sphere_file(tmp_path / "o.nii", rotation(0.0, 0.0, 20.0), flip_x=False)
    with pytest.raises(InvalidDataError, match=r"o.nii is an oblique scan .*20 degrees"):
        read_volume(tmp_path / "o.nii", oblique="error")
    with pytest.warns(SplinevizWarning, match="resampled"):
        flat = read_volume(tmp_path / "o.nii", oblique="resample")
    assert flat.axis_aligned
    info = describe(tmp_path / "o.nii")
    assert "rotated by 20 degrees" in info["oblique"]
    np.testing.assert_allclose(info["direction"], rotation(0.0, 0.0, 20.0), atol=1e-6)
    with pytest.raises(ValueError, match="oblique must be one of"):
        read_volume(tmp_path / "o.nii", oblique="tilt")


def test_a_sheared_grid_is_resampled_with_a_warning(tmp_path):
    affine = np.eye(4)
    affine[0, 1] = 0.5  # the j axis leans into x: no rotation places it
    g = np.linspace(-1, 1, 8)
    nib.save(nib.Nifti1Image(np.add.outer(np.add.outer(g, g), g).astype(np.float32), affine),
             tmp_path / "s.nii")
    with pytest.warns(SplinevizWarning, match="sheared grid .* resampled"):
        vol = read_volume(tmp_path / "s.nii")
    assert vol.axis_aligned
    with pytest.raises(InvalidDataError, match="oblique"):
        read_volume(tmp_path / "s.nii", oblique="error")


def test_volume_direction_must_be_a_rotation():
    with pytest.raises(sv.core.volume.VolumeError, match="rotation"):
        sv.Volume(np.zeros((2, 2, 2)), direction=np.diag([1.0, 1.0, -1.0]))
    with pytest.raises(sv.core.volume.VolumeError, match="rotation"):
        sv.Volume(np.zeros((2, 2, 2)), direction=[[1, 0.5, 0], [0, 1, 0], [0, 0, 1]])
    assert sv.Volume(np.zeros((2, 2, 2))).axis_aligned


def world_camera():
    """A camera looking at the sphere's world centre from an oblique direction."""
    return Camera(CENTRE + np.array([30.0, -38.0, 22.0]), CENTRE, view_up=(0, 0, 1),
                  view_angle=30.0)


def sphere_depth(camera, size, clipping, radius=RADIUS):
    """The analytic sphere's first hit along each pixel's ray: (hit mask, window depth)."""
    eye, d = camera.rays(size)
    oc = eye - CENTRE
    b = d @ oc
    disc = b * b - (oc @ oc - radius**2)
    hit = disc > 0
    t = -b - np.sqrt(np.where(hit, disc, 0.0))
    return hit, camera.window_depth(eye + t[..., None] * d, clipping)


@pytest.mark.parametrize("model", ["cubic-c1", "trilinear"])
def test_oblique_surface_lands_on_the_world_sphere_at_its_world_depth(tmp_path, model):
    """Cast through the real reader: every hit is on the analytic world sphere (radius
    error a small fraction of a voxel) and its window depth is the analytic sphere's along
    the same ray; the same volume read axis-aligned (direction dropped) misses it by
    voxels, so the test fails if the transform is wrong."""
    sphere_file(tmp_path / "o.nii", rotation(18.0, -11.0, 33.0))
    vol = read(tmp_path / "o.nii")
    cam = world_camera()
    cam.clipping_range = (20.0, 90.0)
    size = (64, 48)
    rc = sv.RayCaster(vol, model=model)
    rc.set_isovalue(RADIUS**2)
    frame = rc.render(cam, size=size)
    assert frame.hit.sum() > 300
    radius = np.linalg.norm(frame.position[frame.hit] - CENTRE, axis=1)
    # cubic C1 quasi-interpolates |x - c|^2 with a constant offset (a sphere 0.06 smaller,
    # concentric); trilinear bulges between samples
    spread = 0.002 if model == "cubic-c1" else 0.06
    assert np.abs(radius - np.median(radius)).max() < spread
    assert abs(np.median(radius) - RADIUS) < 0.08
    # the normals point away from the centre in world (the gradient of |x - c|^2)
    n = frame.normal[frame.hit]
    out = (frame.position[frame.hit] - CENTRE) / radius[:, None]
    assert np.min(np.sum(n * out, axis=1)) > 0.99
    # depth of a point a tenth of a voxel behind along the view axis, at the sphere's range
    step = np.abs(cam.window_depth(CENTRE + 0.1 * cam.basis()[2], cam.clipping_range)
                  - cam.window_depth(CENTRE, cam.clipping_range))
    # the window depth of each hit is that of the concentric analytic sphere of the hits'
    # radius along the same ray
    hit_r, depth_r = sphere_depth(cam, size, cam.clipping_range, np.median(radius))
    both = hit_r & frame.hit
    assert both.sum() > 0.97 * max(hit_r.sum(), frame.hit.sum())
    assert np.abs(frame.depth[both] - depth_r[both]).max() < step
    # the same samples without the direction: the surface lands elsewhere
    flat = sv.Volume(vol.data, vol.spacing, vol.origin)
    rc_flat = sv.RayCaster(flat, model=model)
    rc_flat.set_isovalue(RADIUS**2)
    wrong = rc_flat.render(cam, size=size)
    if wrong.hit.any():
        assert np.abs(np.linalg.norm(wrong.position[wrong.hit] - CENTRE, axis=1)
                      - RADIUS).max() > 1.0


def test_clip_planes_in_world_cut_the_oblique_surface_in_world(tmp_path):
    sphere_file(tmp_path / "o.nii", rotation(0.0, 25.0, 40.0))
    vol = read(tmp_path / "o.nii")
    rc = sv.RayCaster(vol, model="trilinear")
    rc.set_isovalue(RADIUS**2)
    plane = (CENTRE, (1.0, 0.0, 0.0))  # keep x >= the centre's x
    frame = rc.render(world_camera(), size=(48, 36), clip_planes=[plane])
    assert frame.hit.sum() > 50
    assert frame.position[frame.hit][:, 0].min() >= CENTRE[0] - 1e-3


def test_oblique_layer_composites_with_a_mesh_in_the_same_world(tmp_path):
    """The spline sphere and pyvista spheres at the same world centre in one picture: a mesh
    sphere 2 % smaller is hidden everywhere behind the spline surface, one 2 % larger hides
    it everywhere (a misplaced surface would let the other through on one side). Each
    picture is compared with the picture of the object that must win drawn alone."""
    import pyvista as pv

    from splineviz.model import Scene
    from splineviz.render.scene_view import render_scene

    sphere_file(tmp_path / "o.nii", rotation(18.0, -11.0, 33.0))
    vol = read(tmp_path / "o.nii")
    size = (96, 72)
    cam = world_camera()
    eye, d = cam.rays(size)
    # pixels well inside the silhouette (away from anti-aliased edges)
    inner = np.linalg.norm(np.cross(d, CENTRE - eye), axis=-1) < 0.85 * RADIUS
    assert inner.sum() > 200
    # the spline's own sphere (cubic C1 shrinks |x - c|^2's level set by 1 %)
    rc = sv.RayCaster(vol, model="cubic-c1")
    rc.set_isovalue(RADIUS**2)
    f = rc.render(cam, size=(32, 24))
    radius = float(np.median(np.linalg.norm(f.position[f.hit] - CENTRE, axis=1)))
    for scale, spline_wins in ((0.98, True), (1.02, False)):
        scene = Scene()
        node = scene.add_volume(vol, name="oblique", isovalue=RADIUS**2, model="cubic-c1")
        node.show_outline = False
        iso = scene.isosurfaces[0]
        iso.color = (1.0, 0.2, 0.2)
        sphere = pv.Sphere(radius=radius * scale, center=CENTRE, theta_resolution=96,
                           phi_resolution=96).triangulate()
        faces = np.asarray(sphere.faces).reshape(-1, 4)[:, 1:]
        mesh = scene.add_mesh(np.asarray(sphere.points), faces, name="mesh",
                              color=(0.1, 0.9, 0.1))
        scene.camera.position = tuple(cam.position)
        scene.camera.focal_point = tuple(cam.focal_point)
        scene.camera.view_up = tuple(cam.view_up)
        scene.camera.view_angle = cam.view_angle
        both = render_scene(scene, size).astype(int)
        (mesh if spline_wins else iso).visible = False
        alone = render_scene(scene, size).astype(int)
        (mesh if spline_wins else iso).visible = True
        (iso if spline_wins else mesh).visible = False
        other = render_scene(scene, size).astype(int)
        assert np.abs(alone - other).max(axis=-1)[inner].min() > 30  # they look different
        same = np.abs(both - alone).max(axis=-1)[inner] <= 8
        assert same.mean() > 0.995, (scale, same.mean())


def test_bounds_outline_section_and_exported_mesh_are_in_world(tmp_path):
    from splineviz.core.sections import plane_section
    from splineviz.model import Scene
    from splineviz.render.extract import spline_isosurface

    rot = rotation(18.0, -11.0, 33.0)
    sphere_file(tmp_path / "o.nii", rot)
    vol = read(tmp_path / "o.nii")
    # the world box holds all eight rotated corners and is larger than the grid's own box
    from splineviz.core.frame import corners

    world = vol.to_world(corners(vol.bounds))
    wb = np.asarray(vol.world_bounds)
    np.testing.assert_allclose(wb[:, 0], world.min(axis=0))
    np.testing.assert_allclose(wb[:, 1], world.max(axis=0))
    scene = Scene()
    node = scene.add_volume(vol, name="oblique", isovalue=RADIUS**2)
    np.testing.assert_allclose(scene.bounds(), wb)
    np.testing.assert_allclose(node.bounds, wb)
    spline = sv.build_spline(vol, "cubic-c1")
    # a section by a world plane through the centre: a circle of the sphere's radius there
    normal = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
    curves = plane_section(spline, RADIUS**2, CENTRE, normal)
    assert len(curves) == 1 and curves[0].closed
    pts = curves[0].points
    np.testing.assert_allclose((pts - CENTRE) @ normal, 0.0, atol=1e-6)
    r = np.linalg.norm(pts - CENTRE, axis=1)
    # concentric with the world sphere (cubic C1's constant offset: a radius 0.06 smaller)
    assert np.abs(r - np.median(r)).max() < 1e-3 and abs(np.median(r) - RADIUS) < 0.08
    assert curves[0].length == pytest.approx(2 * np.pi * np.median(r), rel=1e-4)
    # the exported mesh: vertices on the world sphere, normals outwards in world
    mesh = spline_isosurface(spline, RADIUS**2)
    r = np.linalg.norm(np.asarray(mesh.points) - CENTRE, axis=1)
    assert mesh.n_points > 100 and np.abs(r - np.median(r)).max() < 2e-3
    assert abs(np.median(r) - RADIUS) < 0.08
    out = (np.asarray(mesh.points) - CENTRE) / r[:, None]
    assert np.min(np.abs(np.sum(np.asarray(mesh.point_data["Normals"]) * out, axis=1))) > 0.99


def test_outline_of_an_oblique_volume_is_its_rotated_box():
    import pyvista as pv

    from splineviz.model import Scene
    from splineviz.render.scene_view import SceneView

    rot = rotation(10.0, 20.0, 30.0)
    vol = sv.Volume(np.zeros((5, 6, 7), np.float32), (1.0, 2.0, 0.5), (3.0, -2.0, 1.0), rot)
    scene = Scene()
    scene.add_volume(vol, name="box", isovalue=0.5, isosurface=False)
    pl = pv.Plotter(off_screen=True, window_size=(64, 64))
    view = SceneView(scene, pl, progressive=False, device="numpy")
    try:
        outlines = [r.dataset for r in view.spline_scene.props.values() if r.kind == "outline"]
        assert len(outlines) == 1
        pts = np.asarray(outlines[0].points)
        from splineviz.core.frame import corners

        want = vol.to_world(corners(vol.bounds))
        # every outline point is a rotated corner of the grid's box
        d = np.linalg.norm(pts[:, None] - want[None], axis=-1).min(axis=1)
        assert d.max() < 1e-9
    finally:
        view.close()
        pl.close()


def test_colour_by_volume_reads_the_oblique_spline_at_the_world_hits(tmp_path):
    """Colour by the volume itself: at every hit the value is the isovalue, which holds only
    when the world hit is taken back into the volume's own frame before evaluating."""
    from splineviz.render.isosurface import IsosurfaceLayer, ViewState

    sphere_file(tmp_path / "o.nii", rotation(18.0, -11.0, 33.0))
    vol = read(tmp_path / "o.nii")
    layer = IsosurfaceLayer(vol, model="trilinear", isovalue=RADIUS**2)
    layer.set_color_by("volume", volume=vol)
    rf = layer.compute(ViewState(world_camera(), (40, 30)))
    hit = rf.frame.hit
    assert hit.sum() > 100
    np.testing.assert_allclose(rf.scalars[hit], RADIUS**2, rtol=1e-4)


@pytest.mark.parametrize("suffix", [".nrrd", ".vti"])
def test_an_oblique_volume_written_and_read_again_keeps_its_direction(tmp_path, suffix):
    rot = rotation(10.0, -20.0, 35.0)
    data = np.arange(4 * 5 * 6, dtype=np.float32).reshape(4, 5, 6)
    vol = sv.Volume(data, (1.0, 1.5, 2.0), (3.0, -1.0, 7.0), rot)
    back = read(sv.write_volume(tmp_path / f"o{suffix}", vol))
    np.testing.assert_allclose(back.direction, rot, atol=1e-6)
    np.testing.assert_allclose(back.spacing, vol.spacing, rtol=1e-6)
    np.testing.assert_allclose(back.origin, vol.origin, atol=1e-6)
    np.testing.assert_array_equal(back.data, data)


def test_slice_planes_of_an_oblique_volume_are_drawn_turned_into_world():
    """The slice views work in the volume's own frame; their outline in the 3-D view (and a
    ruler there) is turned into world by the direction."""
    from vtkmodules.vtkRenderingCore import vtkRenderer

    from splineviz.render.slice_view import SlicePlanesMarker

    rot = rotation(10.0, 20.0, 30.0)
    vol = sv.Volume(np.zeros((5, 6, 7), np.float32), (1.0, 2.0, 0.5), (3.0, -2.0, 1.0), rot)
    centre = np.mean(np.asarray(vol.bounds), axis=1)
    marker = SlicePlanesMarker(vtkRenderer())
    marker.update(vol.bounds, centre, ("axial",))
    flat = marker.outlines["axial"].copy()
    marker.frame = vol
    marker.update(vol.bounds, centre, ("axial",))
    np.testing.assert_allclose(marker.outlines["axial"], vol.to_world(flat), atol=1e-12)
    assert np.abs(marker.outlines["axial"] - flat).max() > 0.5
    marker.close()


def test_a_chunked_volume_keeps_its_direction():
    """Bricked rendering carries a direction (tests/compute/test_bricked_oblique.py): a lazily
    read oblique grid keeps its rotation, never made axis-aligned silently."""
    import dask.array as da

    from splineviz.io.chunked import to_chunked_volume
    from splineviz.io.volume_data import VolumeData

    vd = VolumeData(da.zeros((8, 8, 8), chunks=4), (1.0, 1.0, 1.0), (0.0, 0.0, 0.0), "zarr",
                    {}, rotation(0.0, 0.0, 20.0))
    vol = to_chunked_volume(vd, "big.zarr")
    assert not vol.axis_aligned
    np.testing.assert_allclose(vol.direction, rotation(0.0, 0.0, 20.0), atol=1e-12)
    vd.direction = None
    assert to_chunked_volume(vd, "big.zarr").axis_aligned


def test_kernel_hessians_and_picked_values_of_an_oblique_volume_are_in_world(tmp_path):
    """An anisotropic quadratic field (x - c)^T A (x - c) sampled on a turned grid: the
    Hessian at every hit is 2 A in world (2 R^T A R in the volume's own frame), and the
    3-D view's readout interpolates the sample at a world point."""
    from splineviz.gui.view import _trilinear

    a = np.diag([1.0, 2.0, 3.0])
    rot = rotation(25.0, 10.0, -30.0)
    shape, spacing = (24, 24, 24), np.array([0.8, 0.8, 0.8])
    origin = CENTRE - rot @ (0.5 * (np.array(shape) - 1) * spacing)
    affine = affine_from(spacing, origin, rot)
    index = np.stack(np.meshgrid(*[np.arange(n) for n in shape], indexing="ij"), -1)
    p = nib.affines.apply_affine(affine, index) - CENTRE
    field = np.einsum("...i,ij,...j->...", p, a, p).astype(np.float32)
    nib.save(nib.Nifti1Image(field, affine), tmp_path / "q.nii")
    vol = read(tmp_path / "q.nii")
    rc = sv.RayCaster(vol, model="cubic-c1")
    rc.set_isovalue(20.0)
    frame = rc.render(world_camera(), size=(64, 48), hessian=True)
    if frame.hessian is None:
        pytest.skip("no OpenCL device: the NumPy path returns no Hessians")
    assert frame.hit.sum() > 50
    np.testing.assert_allclose(frame.hessian[frame.hit], np.broadcast_to(2 * a, (
        int(frame.hit.sum()), 3, 3)), atol=0.05)
    ijk = np.array([[5, 7, 9], [12, 3, 20]])
    world = vol.to_world(vol.index_to_world(ijk.astype(float)))
    for w, (i, j, k) in zip(world, ijk, strict=True):
        assert _trilinear(vol, w) == pytest.approx(float(vol.data[i, j, k]), rel=1e-5)
