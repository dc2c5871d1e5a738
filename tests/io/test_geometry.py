"""Direction matrices: a volume whose file says its axes run against (or across) the world
axes lands with its parts where the file says, in the world coordinates that the format's
own library (VTK for MetaImage, pynrrd for NRRD, nibabel for NIfTI) gives; an oblique one
keeps its rotation as the volume's direction, or is refused in one sentence when asked."""

from __future__ import annotations

import itertools
import warnings

import numpy as np
import pytest

import splineviz as sv
from splineviz.core.errors import SplinevizWarning
from splineviz.io import describe
from splineviz.io.errors import InvalidDataError
from splineviz.io.geometry import affine_from, axis_aligned, orientation

SHAPE = (20, 16, 12)
#: an asymmetric phantom: three markers of different values at (i, j, k) of the file
MARKERS = {(3, 4, 5): 200, (15, 2, 9): 120, (8, 13, 1): 60}


def phantom() -> np.ndarray:
    """(nx, ny, nz) uint8 with 10 everywhere and the markers (no two mirror images)."""
    d = np.full(SHAPE, 10, np.uint8)
    for idx, val in MARKERS.items():
        d[idx] = val
    return d


def assert_lands(vol, world_of):
    """Each marker's value is found in ``vol`` at the world point ``world_of(index)``."""
    for idx, val in MARKERS.items():
        w = np.asarray(world_of(idx), float)
        ijk = (w - np.asarray(vol.origin)) / np.asarray(vol.spacing)
        assert np.allclose(ijk, np.round(ijk), atol=1e-6), (idx, w, ijk)
        assert vol.data[tuple(np.round(ijk).astype(int))] == val, (idx, w)
    corners = np.array([world_of(c) for c in itertools.product(
        *[(0, n - 1) for n in SHAPE])])
    lo, hi = corners.min(axis=0), corners.max(axis=0)
    np.testing.assert_allclose(np.array(vol.bounds), np.stack([lo, hi], axis=1), atol=1e-9)


def write_mha(path, data, matrix, offset, spacing):
    raw = np.ascontiguousarray(data.transpose(2, 1, 0)).tobytes()  # x fastest
    header = (
        "ObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = False\n"
        "CompressedData = False\n"
        f"TransformMatrix = {' '.join(f'{v:g}' for v in np.ravel(matrix))}\n"
        f"Offset = {' '.join(f'{v:g}' for v in offset)}\nCenterOfRotation = 0 0 0\n"
        "AnatomicalOrientation = RPS\n"
        f"ElementSpacing = {' '.join(f'{v:g}' for v in spacing)}\n"
        f"DimSize = {' '.join(str(n) for n in data.shape)}\nElementType = MET_UCHAR\n"
        "ElementDataFile = LOCAL\n")
    path.write_bytes(header.encode() + raw)


def test_metaimage_flipping_direction_lands_where_vtk_puts_it(tmp_path):
    """The issue's CT: TransformMatrix diag(1, -1, -1) rendered upside down with y bounds
    [360, 718.6]; VTK's own reader (with its direction matrix) is the reference."""
    from vtkmodules.vtkIOImage import vtkMetaImageReader

    path = tmp_path / "ct.mha"
    write_mha(path, phantom(), np.diag([1, -1, -1]), (-5.0, 360.0, 100.0), (0.7, 0.7, 1.25))
    reader = vtkMetaImageReader()
    reader.SetFileName(str(path))
    reader.Update()
    image = reader.GetOutput()

    def vtk_world(idx):
        out = [0.0, 0.0, 0.0]
        image.TransformIndexToPhysicalPoint(*idx, out)
        return out

    with pytest.warns(SplinevizWarning, match="negative spacing along y, z"):
        vol = sv.read_volume(path)
    assert_lands(vol, vtk_world)
    assert vol.bounds[1] == pytest.approx((360.0 - 15 * 0.7, 360.0))
    assert min(vol.spacing) > 0


def test_metaimage_permuted_direction_follows_itk(tmp_path):
    """A non-symmetric TransformMatrix: ITK's MetaImageIO takes the k-th triple as the
    direction of array axis k (``SetDirection(k, triple)``), as Slicer shows it."""
    path = tmp_path / "perm.mha"
    triples = np.array([[0, 1, 0], [-1, 0, 0], [0, 0, 1]], float)  # axis k -> triples[k]
    offset, spacing = np.array([1.0, 2.0, 3.0]), np.array([0.5, 2.0, 1.5])
    write_mha(path, phantom(), triples, offset, spacing)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SplinevizWarning)
        vol = sv.read_volume(path)
    assert_lands(vol, lambda idx: offset + (np.asarray(idx) * spacing) @ triples)
    assert vol.shape == (16, 20, 12)  # world x runs along the file's second axis


@pytest.mark.parametrize("dirs", [
    [[-0.5, 0, 0], [0, 0.75, 0], [0, 0, -2.0]],
    [[0, 0.75, 0], [0, 0, -2.0], [0.5, 0, 0]],
], ids=["flips", "permutation"])
def test_nrrd_space_directions_land_where_pynrrd_says(tmp_path, dirs):
    import nrrd

    dirs = np.asarray(dirs, float)
    origin = np.array([12.0, -30.0, 7.5])
    path = tmp_path / "phantom.nrrd"
    nrrd.write(str(path), phantom(), {"space": "left-posterior-superior",
                                      "space directions": dirs, "space origin": origin},
               index_order="F")
    header = nrrd.read_header(str(path))
    rows = np.asarray(header["space directions"], float)  # row a: world step of axis a
    start = np.asarray(header["space origin"], float)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SplinevizWarning)
        vol = sv.read_volume(path)
    assert_lands(vol, lambda idx: start + np.asarray(idx, float) @ rows)
    assert describe(path)["space"] == "LPS"


def test_nifti_stored_las_lands_where_nibabel_says(tmp_path):
    import nibabel as nib

    affine = np.array([[-2.0, 0, 0, 90], [0, 0, 2.5, -126], [0, 3.0, 0, -72], [0, 0, 0, 1]])
    path = tmp_path / "las.nii.gz"
    nib.save(nib.Nifti1Image(phantom(), affine), path)
    img = nib.load(path)
    with pytest.warns(SplinevizWarning, match="negative spacing along x"):
        vol = sv.read_volume(path)
    assert_lands(vol, lambda idx: nib.affines.apply_affine(img.affine, idx))
    np.testing.assert_allclose(describe(path)["affine"], img.affine)


@pytest.mark.parametrize("degrees", [30.0, 2.5])
def test_oblique_volume_keeps_its_direction_or_is_refused_naming_file_and_angle(tmp_path,
                                                                                degrees):
    import nibabel as nib

    t = np.radians(degrees)
    rot = np.array([[np.cos(t), -np.sin(t), 0], [np.sin(t), np.cos(t), 0], [0, 0, 1]])
    nib.save(nib.Nifti1Image(phantom(), affine_from((1, 1, 2), (0, 0, 0), rot)),
             tmp_path / "tilted.nii")
    write_mha(tmp_path / "tilted.mha", phantom(), rot.T, (0, 0, 0), (1, 1, 1))
    for name in ("tilted.nii", "tilted.mha"):
        vol = sv.read_volume(tmp_path / name)
        np.testing.assert_allclose(vol.direction, rot, atol=1e-6)
        with pytest.raises(InvalidDataError) as err:
            sv.read_volume(tmp_path / name, oblique="error")
        msg = str(err.value)
        assert name in msg and f"{degrees:g} degrees" in msg and "\n" not in msg


def test_float_noise_in_a_direction_is_not_oblique(tmp_path):
    """Scanner headers hold directions in float32: 1e-6 off the axes is axis-aligned."""
    import nibabel as nib

    affine = np.diag([1.0, 1.0, 1.0, 1.0])
    affine[0, 1] = 1e-6
    nib.save(nib.Nifti1Image(phantom(), affine), tmp_path / "noise.nii")
    vol = sv.read_volume(tmp_path / "noise.nii")
    assert vol.shape == SHAPE


def test_every_signed_permutation_keeps_each_sample_at_its_world_position():
    rng = np.random.default_rng(7)
    data = rng.random((3, 4, 5))
    index = np.stack(np.meshgrid(*[np.arange(n) for n in data.shape], indexing="ij"), -1)
    for perm in itertools.permutations(range(3)):
        for signs in itertools.product((1, -1), repeat=3):
            d = np.zeros((3, 3))
            for a, (w, s) in enumerate(zip(perm, signs, strict=True)):
                d[w, a] = s
            affine = affine_from(rng.uniform(0.5, 2, 3), rng.uniform(-9, 9, 3), d)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", SplinevizWarning)
                out, orient = axis_aligned(data, affine, "p")
            world = index @ affine[:3, :3].T + affine[:3, 3]
            j = np.round((world - orient.origin) / orient.spacing).astype(int)
            assert np.array_equal(out[j[..., 0], j[..., 1], j[..., 2]], data)
            assert all(s > 0 for s in orient.spacing)
            assert orientation(affine, data.shape, "p").angle == 0.0


def test_oblique_volume_resampled_on_request_keeps_every_value_in_place(tmp_path):
    """A linear field sampled on a rotated grid: trilinear resampling reproduces a linear
    field exactly, so every new sample inside the rotated box must equal the field at its
    own world point (nibabel's affine gives the file's sample positions)."""
    import nibabel as nib

    t = np.radians(30.0)
    rot = np.array([[np.cos(t), -np.sin(t), 0], [np.sin(t), np.cos(t), 0], [0, 0, 1]])
    affine = affine_from((1.5, 1.0, 2.0), (5.0, -3.0, 1.0), rot)
    index = np.stack(np.meshgrid(*[np.arange(n) for n in SHAPE], indexing="ij"), -1)
    world = nib.affines.apply_affine(affine, index)

    def field(w):
        return w[..., 0] + 2.0 * w[..., 1] - 0.5 * w[..., 2]

    nib.save(nib.Nifti1Image(field(world).astype(np.float32), affine), tmp_path / "o.nii")
    with pytest.warns(SplinevizWarning, match="oblique scan .*30 degrees.* resampled"):
        vol = sv.read_volume(tmp_path / "o.nii", oblique="resample")
    out_index = np.stack(np.meshgrid(*[np.arange(n) for n in vol.shape], indexing="ij"), -1)
    out_world = np.asarray(vol.origin) + out_index * np.asarray(vol.spacing)
    back = nib.affines.apply_affine(np.linalg.inv(affine), out_world)
    inside = np.all((back >= 1e-6) & (back <= np.array(SHAPE) - 1 - 1e-6), axis=-1)
    assert inside.sum() > 0.3 * np.prod(SHAPE)
    np.testing.assert_allclose(vol.data[inside], field(out_world)[inside], atol=1e-3)
    assert np.all(vol.data[~inside] >= field(world).min() - 1e-3)
    lo, hi = world.reshape(-1, 3).min(axis=0), world.reshape(-1, 3).max(axis=0)
    np.testing.assert_allclose([b[0] for b in vol.bounds], lo, atol=1e-9)
    assert all(b[1] <= h + 1e-9 for b, h in zip(vol.bounds, hi, strict=True))


def test_flipped_metaimage_renders_as_the_same_anatomy_stored_upright(tmp_path):
    """Through to the picture: the issue's diag(1, -1, -1) CT and the same world anatomy
    stored with an identity matrix (data reversed, offset at the other end) render the same
    image; before, the first came out upside down."""
    from PIL import Image

    from splineviz.cli import main

    g = np.linspace(-1.0, 1.0, 14)
    x, y, z = np.meshgrid(g, g, g, indexing="ij")
    # an asymmetric blob: a ball with a bump towards +y+z of the file's own axes
    field = np.sqrt(x**2 + y**2 + z**2) - 0.5 * np.exp(-8 * ((y - 0.5)**2 + (z - 0.5)**2))
    data = (100 * (1.5 - field)).clip(0, 255).astype(np.uint8)
    write_mha(tmp_path / "flipped.mha", data, np.diag([1, -1, -1]), (0.0, 26.0, 26.0),
              (2.0, 2.0, 2.0))
    write_mha(tmp_path / "upright.mha", data[:, ::-1, ::-1], np.eye(3), (0.0, 0.0, 0.0),
              (2.0, 2.0, 2.0))
    shots = []
    for name in ("flipped", "upright"):
        out = tmp_path / f"{name}.png"
        assert main(["render", str(tmp_path / f"{name}.mha"), "--iso", "90", "--model",
                     "trilinear", "--size", "48x36", "-o", str(out)]) == 0
        shots.append(np.asarray(Image.open(out).convert("RGB")))
    assert np.count_nonzero(shots[1] != shots[1][0, 0]) > 100  # something was drawn
    np.testing.assert_array_equal(shots[0], shots[1])


def test_vti_direction_matrix_is_honoured(tmp_path):
    """VTK 9's ImageData carries a Direction: it is read like VTK itself places samples."""
    from vtkmodules.util.numpy_support import numpy_to_vtk
    from vtkmodules.vtkCommonDataModel import vtkImageData
    from vtkmodules.vtkIOXML import vtkXMLImageDataReader, vtkXMLImageDataWriter

    image = vtkImageData()
    image.SetDimensions(*SHAPE)
    image.SetSpacing(1.0, 0.5, 2.0)
    image.SetOrigin(3.0, 4.0, 5.0)
    image.SetDirectionMatrix(-1, 0, 0, 0, 1, 0, 0, 0, -1)
    arr = numpy_to_vtk(np.ascontiguousarray(phantom().ravel(order="F")), deep=True)
    arr.SetName("scalars")
    image.GetPointData().SetScalars(arr)
    writer = vtkXMLImageDataWriter()
    writer.SetFileName(str(tmp_path / "d.vti"))
    writer.SetInputData(image)
    writer.Write()
    reader = vtkXMLImageDataReader()
    reader.SetFileName(str(tmp_path / "d.vti"))
    reader.Update()
    back = reader.GetOutput()

    def vtk_world(idx):
        out = [0.0, 0.0, 0.0]
        back.TransformIndexToPhysicalPoint(*idx, out)
        return out

    with pytest.warns(SplinevizWarning, match="negative spacing along x, z"):
        vol = sv.read_volume(tmp_path / "d.vti")
    assert_lands(vol, vtk_world)
