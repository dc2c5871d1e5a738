"""Synthetic files of every format, written by the libraries themselves (or by hand where the
layout is the point of the test), read back with the geometry the writer put in."""

import numpy as np
import pytest

import splineviz as sv
from splineviz.core.errors import SplinevizWarning
from splineviz.io import errors, load_point_data, load_volume_data, read_image

RNG = np.random.default_rng(7)


@pytest.fixture
def field():
    # asymmetric shape and values so that an axis swap or flip cannot pass
    return (np.arange(5 * 6 * 7, dtype=np.float32).reshape(5, 6, 7) * 1.5 - 20.0)


def test_nifti_spacing_origin_and_orientation(tmp_path, field):
    import nibabel as nib

    affine = np.diag([0.5, 0.75, 2.0, 1.0])
    affine[:3, 3] = (10.0, -4.0, 3.0)
    for name, cls in (("a.nii", nib.Nifti1Image), ("a.nii.gz", nib.Nifti1Image),
                      ("b.nii", nib.Nifti2Image), ("b.nii.gz", nib.Nifti2Image)):
        nib.save(cls(field, affine), tmp_path / name)
        renamed = tmp_path / (name + ".upload")  # unknown suffix: the content decides
        renamed.write_bytes((tmp_path / name).read_bytes())
        np.testing.assert_array_equal(sv.read_volume(renamed).data, field)
        vol = sv.read_volume(tmp_path / name)
        np.testing.assert_array_equal(vol.data, field)
        assert vol.spacing == (0.5, 0.75, 2.0)
        assert vol.origin == (10.0, -4.0, 3.0)
    # an x-flipped affine is reoriented to RAS+: data reversed along x, origin at the far end
    flipped = affine.copy()
    flipped[0, 0] = -0.5
    nib.save(nib.Nifti1Image(field, flipped), tmp_path / "f.nii")
    with pytest.warns(SplinevizWarning, match="negative spacing along x"):
        vol = sv.read_volume(tmp_path / "f.nii")
    np.testing.assert_array_equal(vol.data, field[::-1])
    assert vol.origin[0] == pytest.approx(10.0 - 0.5 * 4)


def test_mrc_written_by_mrcfile(tmp_path, field):
    import mrcfile

    zyx = np.ascontiguousarray(field.transpose(2, 1, 0))  # mrcfile: data[section, row, col]
    with mrcfile.new(tmp_path / "m.mrc") as m:
        m.set_data(zyx)
        m.voxel_size = (2.0, 3.0, 4.0)
        m.header.nxstart, m.header.nystart, m.header.nzstart = 1, 2, 3
    vol = sv.read_volume(tmp_path / "m.mrc")
    np.testing.assert_array_equal(vol.data, field)
    np.testing.assert_allclose(vol.spacing, (2, 3, 4))
    np.testing.assert_allclose(vol.origin, (2, 6, 12))


def _dicom_slice(path, pixels, z, instance, slope=2.0, intercept=-100.0, series="1.2.3"):
    from pydicom.dataset import FileDataset, FileMetaDataset
    from pydicom.uid import ExplicitVRLittleEndian, generate_uid

    meta = FileMetaDataset()
    meta.MediaStorageSOPClassUID = "1.2.840.10008.5.1.4.1.1.2"
    meta.MediaStorageSOPInstanceUID = generate_uid()
    meta.TransferSyntaxUID = ExplicitVRLittleEndian
    ds = FileDataset(str(path), {}, file_meta=meta, preamble=b"\0" * 128)
    ds.SOPClassUID = meta.MediaStorageSOPClassUID
    ds.SOPInstanceUID = meta.MediaStorageSOPInstanceUID
    ds.SeriesInstanceUID = series
    ds.Modality = "CT"
    ds.Rows, ds.Columns = pixels.shape
    ds.PixelSpacing = [0.8, 0.6]  # row step (y), column step (x)
    ds.ImageOrientationPatient = [1, 0, 0, 0, 1, 0]
    ds.ImagePositionPatient = [-5.0, 7.0, z]
    ds.InstanceNumber = instance
    ds.RescaleSlope, ds.RescaleIntercept = slope, intercept
    ds.SamplesPerPixel = 1
    ds.PhotometricInterpretation = "MONOCHROME2"
    ds.BitsAllocated, ds.BitsStored, ds.HighBit, ds.PixelRepresentation = 16, 16, 15, 0
    ds.PixelData = pixels.astype("<u2").tobytes()
    ds.save_as(str(path), enforce_file_format=True)


def test_dicom_series_sorted_by_position_with_rescale(tmp_path):
    stack = RNG.integers(0, 1000, size=(4, 3, 5)).astype(np.uint16)  # (slices, rows, cols)
    zs = [12.5, 10.0, 15.0, 17.5]  # written out of order, with misleading instance numbers
    for n, (k, z) in enumerate(zip((1, 0, 2, 3), zs, strict=True)):
        _dicom_slice(tmp_path / f"im{n}.dcm", stack[k], z, instance=4 - n)
    (tmp_path / "notes.txt").write_text("not dicom")
    vol = sv.read_volume(tmp_path)
    assert vol.shape == (5, 3, 4)
    np.testing.assert_allclose(vol.spacing, (0.6, 0.8, 2.5))
    np.testing.assert_allclose(vol.origin, (-5, 7, 10))
    expect = stack.transpose(2, 1, 0).astype(np.float32) * 2 - 100  # sorted by z: 0, 1, 2, 3
    np.testing.assert_array_equal(vol.data, expect)


@pytest.mark.parametrize("byteorder", ["little", "big"])
def test_raw_with_dims_dtype_and_endianness(tmp_path, field, byteorder):
    dt = np.dtype("<i2" if byteorder == "little" else ">i2")
    ints = field.astype(np.int16)
    (tmp_path / "v.raw").write_bytes(b"HDR!" + ints.astype(dt).ravel(order="F").tobytes())
    vol = sv.read_volume(tmp_path / "v.raw", dims=(5, 6, 7), dtype="int16",
                         byteorder=byteorder, offset=4, spacing=(1, 2, 3))
    np.testing.assert_array_equal(vol.data, ints)
    assert vol.spacing == (1, 2, 3)


def test_npy_and_writers_round_trip(tmp_path, field):
    vol = sv.Volume(field, spacing=(0.5, 1.0, 2.5), origin=(-1, 2, 3))
    for name in ("v.vti", "v.nrrd", "v.npy"):
        sv.write_volume(tmp_path / name, vol)
        back = sv.read_volume(tmp_path / name)
        np.testing.assert_array_equal(back.data, field)
        if name != "v.npy":  # .npy holds no geometry
            assert back.spacing == vol.spacing and back.origin == vol.origin
    assert sorted(p.name for p in tmp_path.iterdir()) == ["v.npy", "v.nrrd", "v.vti"]


def test_legacy_vtk_and_metaimage_written_by_vtk(tmp_path, field):
    import pyvista as pv

    img = pv.ImageData(dimensions=field.shape, spacing=(0.5, 1, 2), origin=(3, 2, 1))
    img.point_data["s"] = field.ravel(order="F")
    img.save(tmp_path / "v.vtk")
    vol = sv.read_volume(tmp_path / "v.vtk")
    np.testing.assert_array_equal(vol.data, field)
    assert vol.spacing == (0.5, 1, 2) and vol.origin == (3, 2, 1)
    header = ("ObjectType = Image\nNDims = 3\nDimSize = 5 6 7\nElementSpacing = 1 2 3\n"
              "Offset = 4 5 6\nElementType = MET_FLOAT\nElementByteOrderMSB = False\n"
              "ElementDataFile = v.raw\n")
    (tmp_path / "v.mhd").write_text(header)
    (tmp_path / "v.raw").write_bytes(field.astype("<f4").ravel(order="F").tobytes())
    vol = sv.read_volume(tmp_path / "v.mhd")
    np.testing.assert_array_equal(vol.data, field)
    assert vol.spacing == (1, 2, 3) and vol.origin == (4, 5, 6)


def test_content_beats_a_lying_suffix(tmp_path, field):
    sv.write_volume(tmp_path / "v.nrrd", sv.Volume(field))
    (tmp_path / "v.nrrd").rename(tmp_path / "v.mhd")  # an NRRD with the wrong suffix
    np.testing.assert_array_equal(sv.read_volume(tmp_path / "v.mhd").data, field)


# ---------------------------------------------------------------------------- points
def _cloud(n=50):
    pts = RNG.normal(size=(n, 3))
    nrm = pts / np.linalg.norm(pts, axis=1, keepdims=True)
    col = RNG.integers(0, 255, size=(n, 3)).astype(np.uint8)
    return pts, nrm, col


@pytest.mark.parametrize("text, byte_order", [(True, "="), (False, "<"), (False, ">")])
def test_ply_encodings_with_normals_and_colours(tmp_path, text, byte_order):
    from plyfile import PlyData, PlyElement

    pts, nrm, col = _cloud()
    v = np.empty(len(pts), dtype=[("x", "f8"), ("y", "f8"), ("z", "f8"), ("nx", "f4"),
                                  ("ny", "f4"), ("nz", "f4"), ("red", "u1"), ("green", "u1"),
                                  ("blue", "u1")])
    for i, c in enumerate("xyz"):
        v[c] = pts[:, i]
        v["n" + c] = nrm[:, i]
    v["red"], v["green"], v["blue"] = col.T
    PlyData([PlyElement.describe(v, "vertex")], text=text,
            byte_order=byte_order).write(str(tmp_path / "c.ply"))
    pd = load_point_data(tmp_path / "c.ply")
    np.testing.assert_allclose(pd.points, pts, rtol=1e-12)
    np.testing.assert_allclose(pd.normals, nrm, rtol=1e-6)
    np.testing.assert_array_equal(pd.colors, col)


def test_xyz_with_and_without_normals(tmp_path):
    pts, nrm, _ = _cloud()
    np.savetxt(tmp_path / "a.xyz", pts)
    np.savetxt(tmp_path / "b.xyz", np.hstack([pts, nrm]), header="x y z nx ny nz")
    a, b = sv.read_points(tmp_path / "a.xyz"), sv.read_points(tmp_path / "b.xyz")
    np.testing.assert_allclose(a.points, pts)
    assert a.normals is None
    np.testing.assert_allclose(b.normals, nrm)


def test_pcd_ascii_and_binary(tmp_path):
    import open3d as o3d

    pts, nrm, _ = _cloud()
    pc = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(pts))
    pc.normals = o3d.utility.Vector3dVector(nrm)
    for ascii_ in (True, False):
        o3d.io.write_point_cloud(str(tmp_path / "c.pcd"), pc, write_ascii=ascii_)
        got = sv.read_points(tmp_path / "c.pcd")
        np.testing.assert_allclose(got.points, pts, rtol=1e-6, atol=1e-6)
        np.testing.assert_allclose(got.normals, nrm, rtol=1e-5, atol=1e-6)


@pytest.mark.parametrize("ext", ["obj", "stl", "off", "ply", "vtp"])
def test_mesh_vertices_and_mesh_writers(tmp_path, ext):
    import meshio
    import pyvista as pv

    mesh = pv.Icosphere(nsub=1, radius=2.0, center=(1, 2, 3))
    if ext == "off":
        faces = mesh.faces.reshape(-1, 4)[:, 1:]
        meshio.write(tmp_path / "m.off", meshio.Mesh(mesh.points, [("triangle", faces)]))
    else:
        sv.write_mesh(tmp_path / f"m.{ext}", mesh)
        back = sv.read_mesh(tmp_path / f"m.{ext}")
        assert back.n_cells == mesh.n_cells
    if ext != "vtp":
        pc = sv.read_points(tmp_path / f"m.{ext}")
        assert len(pc) == mesh.n_points
        np.testing.assert_allclose(np.linalg.norm(pc.points - (1, 2, 3), axis=1), 2.0,
                                   rtol=1e-5)
    assert [p.name for p in tmp_path.iterdir()] == [f"m.{ext}"]  # no temporary left


def test_write_mesh_from_arrays_and_screenshot(tmp_path):
    verts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    faces = np.array([[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]])
    sv.write_mesh(tmp_path / "t.ply", (verts, faces))
    assert sv.read_mesh(tmp_path / "t.ply").n_cells == 4
    img = RNG.integers(0, 255, size=(7, 9, 3)).astype(np.uint8)
    sv.write_screenshot(tmp_path / "s.png", img)
    np.testing.assert_array_equal(read_image(tmp_path / "s.png")[..., :3], img)


def test_duplicates_are_merged_not_refused(tmp_path):
    pts, _, _ = _cloud(20)
    np.savetxt(tmp_path / "d.xyz", np.vstack([pts, pts[:5]]))
    assert len(sv.read_points(tmp_path / "d.xyz")) == 20
    assert len(sv.read_points(tmp_path / "d.xyz", dedupe=False)) == 25


def test_nonfinite_samples_fill_option(tmp_path, field):
    f = field.copy()
    f[1, 2, 3] = np.nan
    np.save(tmp_path / "n.npy", f)
    with pytest.raises(errors.InvalidDataError, match="1 NaN or infinite"):
        sv.read_volume(tmp_path / "n.npy")
    with pytest.warns(sv.SplinevizWarning, match="1 NaN or infinite samples were replaced"):
        vol = sv.read_volume(tmp_path / "n.npy", nonfinite="fill")
    assert vol.data[1, 2, 3] == np.nanmin(f)


def test_stored_dtype_is_kept_in_volume_data(tmp_path):
    a = RNG.integers(-3000, 3000, size=(3, 4, 5)).astype(np.int16)
    np.save(tmp_path / "i.npy", a)
    vd = load_volume_data(tmp_path / "i.npy")
    assert vd.data.dtype == np.int16 and vd.format == "npy"


@pytest.mark.parametrize("compressed", [False, True])
def test_metaimage_mha_written_by_vtk(tmp_path, field, compressed):
    from vtkmodules.util.numpy_support import numpy_to_vtk
    from vtkmodules.vtkCommonDataModel import vtkImageData
    from vtkmodules.vtkIOImage import vtkMetaImageWriter

    img = vtkImageData()
    img.SetDimensions(*field.shape)
    img.SetSpacing(0.5, 1.5, 2.5)
    img.SetOrigin(-1, -2, -3)
    img.GetPointData().SetScalars(numpy_to_vtk(field.ravel(order="F"), deep=True))
    w = vtkMetaImageWriter()
    w.SetFileName(str(tmp_path / "v.mha"))
    w.SetCompression(compressed)
    w.SetInputData(img)
    w.Write()
    vol = sv.read_volume(tmp_path / "v.mha")
    np.testing.assert_array_equal(vol.data, field)
    assert vol.spacing == (0.5, 1.5, 2.5) and vol.origin == (-1, -2, -3)


@pytest.mark.parametrize("etype, dtype, msb", [("MET_SHORT", ">i2", True),
                                                ("MET_FLOAT", "<f4", False)])
def test_metaimage_zraw_is_read_whole_whatever_its_compressed_size_says(tmp_path, etype,
                                                                         dtype, msb):
    """A header whose CompressedDataSize is short of its stream (MetaIO would inflate only
    that much and leave the rest of the grid uninitialised) or absent: every sample is the
    stream's, in the header's byte order, with VTK's spacing and origin."""
    import zlib

    data = (np.arange(7 * 6 * 5) % 97 - 40).astype(dtype).reshape(5, 6, 7)  # (z, y, x)
    stream = zlib.compress(data.tobytes(), 9)
    (tmp_path / "v.zraw").write_bytes(stream)
    for size in (f"CompressedDataSize = {len(stream) // 2}\n", ""):
        (tmp_path / "v.mhd").write_text(
            "ObjectType = Image\nNDims = 3\nBinaryData = True\n"
            f"BinaryDataByteOrderMSB = {msb}\nCompressedData = True\n{size}"
            "Offset = 1 -2 3\nElementSpacing = 0.5 1 2\nDimSize = 7 6 5\n"
            f"ElementType = {etype}\nElementDataFile = v.zraw\n")
        vol = sv.read_volume(tmp_path / "v.mhd")
        np.testing.assert_array_equal(vol.data, data.transpose(2, 1, 0).astype(np.float32))
        assert vol.spacing == (0.5, 1, 2) and vol.origin == (1, -2, 3)
        # the same with the stream in the header's own file
        head = (tmp_path / "v.mhd").read_text().replace("v.zraw", "LOCAL")
        (tmp_path / "v.mha").write_bytes(head.encode() + stream)
        np.testing.assert_array_equal(sv.read_volume(tmp_path / "v.mha").data, vol.data)


def test_nrrd_detached_header_written_by_pynrrd(tmp_path, field):
    import nrrd

    header = {"space dimension": 3, "space directions": np.diag([0.25, 0.5, 4.0]),
              "space origin": np.array([1.0, 2.0, 3.0]), "encoding": "gzip"}
    nrrd.write(str(tmp_path / "v.nhdr"), field, header, detached_header=True, index_order="F")
    assert (tmp_path / "v.raw.gz").exists()
    vol = sv.read_volume(tmp_path / "v.nhdr")
    np.testing.assert_array_equal(vol.data, field)
    assert vol.spacing == (0.25, 0.5, 4.0) and vol.origin == (1, 2, 3)


def test_info_on_a_dicom_folder(tmp_path):
    from splineviz.io.describe import describe

    for n, z in enumerate((0.0, 1.5, 3.0)):
        _dicom_slice(tmp_path / f"s{n}.dcm", np.full((3, 4), n, np.uint16), z, instance=n)
    info = describe(tmp_path)
    assert info["format"] == "dicom" and info["dims"] == [4, 3, 3]
    assert info["spacing"] == [0.6, 0.8, 1.5] and info["range"] == [-100.0, -96.0]


def test_info_on_a_raw_file_with_dims(tmp_path, capsys):
    from splineviz import cli

    (tmp_path / "v.raw").write_bytes(np.arange(24, dtype=">u2").tobytes())
    assert cli.main(["info", str(tmp_path / "v.raw"), "--dims", "2", "3", "4", "--dtype",
                     "uint16", "--byteorder", "big", "--json"]) == 0
    import json

    info = json.loads(capsys.readouterr().out)
    assert info["dims"] == [2, 3, 4] and info["range"] == [0.0, 23.0]
    assert cli.main(["info", str(tmp_path / "v.raw")]) == 2
    assert "give its dims and dtype" in capsys.readouterr().err


@pytest.mark.parametrize("kind", ["vti", "nrrd", "npy", "vtk", "mha", "nii", "mrc",
                                  "ply-ascii", "ply-binary", "pcd", "off"])
def test_every_signed_format_is_recognised_by_content(tmp_path, kind):
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).parent))
    try:
        from test_io_fuzz import _make
    finally:
        sys.path.pop(0)
    path, reader = _make(kind, tmp_path)
    upload = tmp_path / "upload.bin2"  # an unknown suffix
    upload.write_bytes(path.read_bytes())
    a, b = reader(path), reader(upload)
    if isinstance(a, sv.Volume):
        np.testing.assert_array_equal(a.data, b.data)
        assert a.spacing == b.spacing and a.origin == b.origin
    else:
        np.testing.assert_array_equal(a.points, b.points)


def test_slc_run_length_code_is_decoded_exactly_and_completely(tmp_path):
    """Literal runs (n | 0x80), repeats (n) and the end code 0; samples the code does not
    reach are 0 (VTK's reader left them uninitialised: the same file read differently)."""
    from splineviz.io.errors import CorruptFileError
    from splineviz.io.volumes import _slc_decode

    code = bytes([0x83, 7, 8, 9, 2, 5, 0])
    assert _slc_decode(code, 8, "t.slc", 0).tolist() == [7, 8, 9, 5, 5, 0, 0, 0]
    with pytest.raises(CorruptFileError, match="more than 4 samples"):
        _slc_decode(bytes([0x05, 1, 0]), 4, "t.slc", 0)
    # a whole file: 3 x 2 x 2, two run-length slices
    slices = [bytes([0x86, 1, 2, 3, 4, 5, 6, 0]), bytes([6, 9, 0])]
    body = b"".join(b"%d X" % len(s) + s for s in slices)
    (tmp_path / "v.slc").write_bytes(b"11111\n3 2 2 8\n0.5 1 2\n2 6 4 1\n0 0 X" + body)
    vol = sv.read_volume(tmp_path / "v.slc")
    assert vol.spacing == (0.5, 1.0, 2.0)
    assert vol.data[:, :, 0].T.ravel().tolist() == [1, 2, 3, 4, 5, 6]
    assert np.all(vol.data[:, :, 1] == 9)
