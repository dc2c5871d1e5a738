"""Cell projection (thesis §6.1) against the ray caster, and the relevant-tetrahedra
classification it draws (issue 32).

The ray caster is the OpenCL one where a device exists, else the NumPy reference: both are
the project's ray casters, and the OpenCL one is itself tested against the reference.
Depth must agree within 1e-5 at every pixel both hit (the shader gets the coefficients of
``p - iso`` rounded once from float64, which keeps grazing roots well placed).
"""

import numpy as np
import pytest
import vtk
from compute.helpers import cameras, load_volume

from splineviz.compute.raycast import RayCaster
from splineviz.core.camera import Camera
from splineviz.core.relevant_tets import RelevantTetsError, relevant_tets
from splineviz.core.splines import build_spline
from splineviz.core.volume import Volume

MODELS = ["super-quadratic", "cubic-c1", "to-quadratic"]
SIZE = (96, 72)


def _opengl_works() -> bool:
    win = vtk.vtkRenderWindow()
    win.SetOffScreenRendering(True)
    try:
        return bool(win.SupportsOpenGL())
    finally:
        win.Finalize()


needs_gl = pytest.mark.skipif(not _opengl_works(), reason="no OpenGL render window here")


def _sphere(n=14):
    x = np.indices((n, n, n)).astype(float) - (n - 1) / 2
    return Volume(np.sqrt((x ** 2).sum(axis=0)), spacing=(1.0, 0.8, 1.2), origin=(2, -1, 0))


def _tooth_crop():
    vol = load_volume("tooth.nrrd")
    return Volume(np.ascontiguousarray(vol.data[36:68, 31:63, 64:96]), spacing=vol.spacing)


@pytest.mark.parametrize("model", ["super-quadratic", "cubic-c1"])
def test_relevant_tets_are_exactly_the_spanning_ones(model):
    spline = build_spline(_sphere(10), model)
    iso = 3.3
    got = relevant_tets(spline, iso)
    cubes = spline.all_cubes()
    all_cube = np.repeat(cubes, 24, axis=0)
    all_tet = np.tile(np.arange(24), len(cubes))
    c = spline.tet_coefficients(all_cube, all_tet)
    keep = (c.min(axis=1) <= iso) & (iso <= c.max(axis=1))
    assert keep.sum() > 0 and len(got) == keep.sum()
    key = lambda cube, tet: set(zip(map(tuple, cube.tolist()), tet.tolist(), strict=True))  # noqa: E731
    assert key(got.cube, got.tet) == key(all_cube[keep], all_tet[keep])
    np.testing.assert_allclose(got.coeffs, spline.tet_coefficients(got.cube, got.tet))
    assert got.per_orientation().sum() == len(got)
    assert got.coeffs.shape[1] == {"super-quadratic": 10, "cubic-c1": 20}[model]


def test_relevant_truncated_octahedral_tets_are_exactly_the_spanning_ones():
    """to-quadratic: every tet of every TO meeting the data box, tested on its exact
    coefficients (the spline's own piece at the tet's centroid), against the culled
    classification."""
    from splineviz.core.partitions import truncated_octahedra as to

    vol = _sphere(10)
    spline = build_spline(vol, "to-quadratic")
    iso = 3.3
    got = relevant_tets(spline, iso)
    centres = to.centres_covering(np.zeros(3), np.array(vol.shape) - 1.0)
    generic = to.generic_tetrahedra()[0]
    n = len(generic)
    all_centre = np.repeat(centres, n, axis=0)
    all_tet = np.tile(np.arange(n), len(centres))
    # the spline's own B-form at each tet's centroid: its TO, tet and coefficients
    centroids = all_centre + generic.mean(axis=1)[all_tet]
    coeffs, _lam, _m = spline.local_bform(centroids)
    keep = (coeffs.min(axis=1) <= iso) & (iso <= coeffs.max(axis=1))
    assert keep.sum() > 0 and len(got) == keep.sum()
    key = lambda c, t: set(zip(map(tuple, np.round(2 * c).astype(int).tolist()),  # noqa: E731
                               t.tolist(), strict=True))
    assert key(got.cube, got.tet) == key(all_centre[keep], all_tet[keep])
    assert got.per_orientation().sum() == len(got) and got.degree == 2
    # the tets' vertices are the TOs' generic tets moved to their centres
    np.testing.assert_allclose(got.vertices().mean(axis=1), got.cube + generic.mean(axis=1)[
        got.tet])


def test_relevant_tets_need_a_type6_model():
    with pytest.raises(RelevantTetsError, match="type-6"):
        relevant_tets(build_spline(_sphere(6), "trilinear"), 2.0)


def _agreement(vol, model, iso, camera, planes=(), min_both=500):
    from splineviz.render.cell_projection import render_cell_projection

    spline = build_spline(vol, model)
    color, depth = render_cell_projection(spline, camera, SIZE, iso, clip_planes=planes)
    rc = RayCaster(vol, model=model)
    rc.set_isovalue(iso)
    ref = rc.render(camera, SIZE, clip_planes=planes)
    hit = depth < 1.0
    both = hit & ref.hit
    assert both.sum() > min_both, both.sum()  # the view must show the surface
    assert np.mean(hit == ref.hit) >= 0.995
    ddepth = np.abs(depth[both] - ref.depth[both])
    assert ddepth.max() <= 1e-5, np.percentile(ddepth, [50, 99, 100])
    dcol = np.abs(color[both].astype(int) - ref.color[both][:, :3].astype(int)).max(axis=1)
    assert np.mean(dcol <= 2) >= 0.995, dcol.max()
    # where neither hits, both show the background
    neither = ~hit & ~ref.hit
    np.testing.assert_array_equal(color[neither], ref.color[neither][:, :3])


@needs_gl
@pytest.mark.parametrize("model", MODELS)
def test_sphere_agrees_with_the_ray_caster(model):
    vol = _sphere()
    _agreement(vol, model, 4.3, cameras(vol)[0])


@needs_gl
@pytest.mark.parametrize("model", MODELS)
def test_tooth_crop_agrees_with_the_ray_caster(model):
    vol = _tooth_crop()
    _agreement(vol, model, 100.5, cameras(vol)[1])


@needs_gl
def test_camera_inside_the_data_box():
    # rays start at the eye: the box and tet cuts must not reach behind it
    vol = _sphere()
    b = np.asarray(vol.bounds)
    c = b.mean(axis=1)
    cam = Camera(c + (0.5, -0.3, 0.2), c + (3.0, 4.0, 1.0), view_up=(0, 0, 1), view_angle=60)
    _agreement(vol, "cubic-c1", 4.3, cam)


@needs_gl
@pytest.mark.parametrize("model", MODELS)
def test_clip_planes_cut_as_in_the_ray_caster(model):
    # two planes through the sphere: the cut shows the inside (back faces) as the caster does
    vol = _sphere()
    c = np.asarray(vol.bounds).mean(axis=1)
    planes = [(c + (1, 0, 0), (-1.0, 1.0, -0.3)), (c + (0, 0, -3.0), (0.0, 0.2, 1.0))]
    _agreement(vol, model, 4.3, cameras(vol)[0], planes, min_both=300)


@needs_gl
def test_bench_renderers_reports_both_renderers(capsys):
    from splineviz.bench.renderers import run_renderers_bench

    rows = run_renderers_bench(sizes=(8,), size=(32, 32), repeats=1)
    assert rows[0]["tets"] > 0 and rows[0]["cell_projection_s"] > 0 < rows[0]["raycast_s"]
    assert "note:" in capsys.readouterr().out


def test_too_many_clip_planes_is_one_error():
    from splineviz.core.raycast_reference import ClipPlaneError
    from splineviz.render.cell_projection import MAX_CLIP_PLANES, CellProjectionLayer

    layer = CellProjectionLayer(build_spline(_sphere(6), "super-quadratic"), 2.0)
    with pytest.raises(ClipPlaneError, match="at most"):
        layer.set_clip_planes([((0, 0, 0), (1, 0, 0))] * (MAX_CLIP_PLANES + 1))


@needs_gl
def test_a_mesh_through_the_surface_composites_by_depth():
    # an unlit green square through the sphere's centre: each pixel shows whichever of the
    # square and the ray caster's hit is nearer
    from splineviz.render.cell_projection import CellProjectionLayer, OffscreenCellProjection

    vol = _sphere()
    cam = cameras(vol)[0]
    c = np.asarray(vol.bounds).mean(axis=1)
    normal = np.array([0.3, 1.0, 0.2]) / np.linalg.norm([0.3, 1.0, 0.2])
    u = np.cross(normal, (0, 0, 1.0))
    u /= np.linalg.norm(u)
    v = np.cross(normal, u)
    half = 8.0
    plane = vtk.vtkPlaneSource()
    plane.SetOrigin(*(c - half * u - half * v))
    plane.SetPoint1(*(c + half * u - half * v))
    plane.SetPoint2(*(c - half * u + half * v))
    mapper = vtk.vtkPolyDataMapper()
    mapper.SetInputConnection(plane.GetOutputPort())
    actor = vtk.vtkActor()
    actor.SetMapper(mapper)
    prop = actor.GetProperty()
    prop.SetColor(0.0, 1.0, 0.0)
    prop.SetAmbient(1.0)
    prop.SetDiffuse(0.0)
    prop.SetSpecular(0.0)
    layer = CellProjectionLayer(build_spline(vol, "cubic-c1"), 4.3)
    with OffscreenCellProjection(layer, SIZE) as view:
        view.renderer.AddActor(actor)
        color, _ = view.render(cam)
    rc = RayCaster(vol, model="cubic-c1")
    rc.set_isovalue(4.3)
    ref = rc.render(cam, SIZE)
    # where each pixel's ray meets the square, and that point's window depth
    eye, dirs = cam.rays(SIZE)
    t = ((c - eye) @ normal) / (dirs @ normal)
    pts = eye + t[..., None] * dirs
    on_square = (np.abs((pts - c) @ u) < half) & (np.abs((pts - c) @ v) < half) & (t > 0)
    square_depth = cam.window_depth(pts, cam.fit_clipping_range(vol.bounds))
    surface_first = ref.hit & (~on_square | (ref.depth < square_depth))
    green = np.all(color == (0, 255, 0), axis=-1)
    expect_green = on_square & ~surface_first
    assert expect_green.sum() > 300 and surface_first.sum() > 300
    assert np.mean(green == expect_green) >= 0.995
    shown = surface_first & ~green
    dcol = np.abs(color[shown].astype(int) - ref.color[shown][:, :3].astype(int)).max(axis=1)
    assert np.mean(dcol <= 2) >= 0.995
