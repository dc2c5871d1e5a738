"""Units on lengths and areas (issue 26, part 7): the readers record the spatial unit the
file states, and the figures a user reads (ruler, probe, curve lengths and areas, axes
titles, ``splineviz info``) carry it; a file that does not say gets no unit at all."""

import warnings

import numpy as np
import pytest

import splineviz as sv
from splineviz.core.ticks import axis_ticks
from splineviz.core.units import canonical_unit, common_unit, format_quantity


@pytest.mark.parametrize("value, unit, power, text", [
    (12.34, "mm", 1, "12.3 mm"),
    (0.0123, "m", 1, "12.3 mm"),
    (4.56, "mm", 2, "4.56 mm²"),
    (4.56e6, "mm", 2, "4.56 m²"),
    (1.2e9, "nm", 3, "1.2 µm³"),
    (1500.0, "mm", 1, "1.5 m"),
    (3.0, "Å", 1, "3 Å"),  # Ångström is kept, as cryo-EM users read it
    (12345.0, "Å", 1, "12345 Å"),
    (12.5, "", 1, "12.5"),  # no unit known: none shown
    (0.0, "mm", 1, "0 mm"),
])
def test_engineering_formatting(value, unit, power, text):
    assert format_quantity(value, unit, power) == text


def test_unit_names_files_use_and_their_ascii_labels():
    assert canonical_unit("micron") == canonical_unit("um") == "µm"
    assert canonical_unit(b"angstrom") == "Å"
    assert canonical_unit("unknown") == canonical_unit(None) == canonical_unit("???") == ""
    assert canonical_unit("furlong") == "furlong"
    assert format_quantity(2.5, "µm", 2, ascii=True) == "2.5 um^2"
    assert common_unit(["mm", "millimetre"]) == "mm" and common_unit(["mm", "Å"]) == ""
    assert common_unit([]) == ""


def test_axis_titles_take_the_prefix_of_the_scaled_labels():
    assert axis_ticks(0, 2500, "X", "mm").title == "X (m)"
    assert axis_ticks(0, 0.002, "X", "m").title == "X (mm)"
    assert axis_ticks(0, 200, "Z", "Å").title == "Z (A)"
    assert axis_ticks(0, 0.5, "Y", "µm").title == "Y (nm)"
    assert axis_ticks(0, 200, "X").title == "X"


@pytest.mark.parametrize("name, unit", [
    ("EMD-3197.map", "Å"),  # MRC: Ångström by definition
    ("embryo.slc", "µm"),  # SLC unit code 2
    ("neghip.slc", "mm"),  # SLC unit code 1
    ("tooth.nrrd", ""),  # no "space units": no unit, not a guessed one
    ("HeadMRVolume.mhd", ""),
])
def test_shared_files_state_their_unit(shared_data, name, unit):
    assert sv.read_volume(shared_data / "volumes" / name).unit == unit


def test_info_prints_the_unit_line(shared_data):
    from splineviz.io.describe import describe, format_info

    assert "unit: Å" in format_info(describe(shared_data / "volumes" / "EMD-3197.map"))
    assert "unit" not in describe(shared_data / "volumes" / "tooth.nrrd")


def _field():
    x = np.linspace(-1, 1, 8)
    return (x[:, None, None] ** 2 + x[None, :, None] ** 2 + x[None, None, :] ** 2)


@pytest.mark.parametrize("code, unit", [("micron", "µm"), ("mm", "mm"), ("unknown", "")])
def test_nifti_xyzt_units(tmp_path, code, unit):
    import nibabel as nib

    img = nib.Nifti1Image(_field().astype(np.float32), np.diag([0.5, 0.5, 0.5, 1.0]))
    img.header.set_xyzt_units(xyz=code)
    nib.save(img, tmp_path / "f.nii.gz")
    assert sv.read_volume(tmp_path / "f.nii.gz").unit == unit


def test_nrrd_space_units(tmp_path):
    import nrrd

    nrrd.write(str(tmp_path / "f.nrrd"), _field().astype(np.float32),
               {"space": "left-posterior-superior", "space units": ["mm", "mm", "mm"],
                "space directions": np.eye(3)})
    assert sv.read_volume(tmp_path / "f.nrrd").unit == "mm"


def test_imagej_tiff_unit(tmp_path):
    import tifffile

    data = (100 * _field()).astype(np.uint8).transpose(2, 1, 0)  # (z, y, x) on disk
    tifffile.imwrite(tmp_path / "f.tif", data, imagej=True, resolution=(2.0, 2.0),
                     metadata={"spacing": 0.5, "unit": "micron", "axes": "ZYX"})
    assert sv.read_volume(tmp_path / "f.tif").unit == "µm"


def test_ome_zarr_axis_unit_reaches_the_chunked_volume_and_its_bricks(tmp_path):
    import zarr
    from ome_zarr.io import parse_url

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        from ome_zarr.writer import write_image
    path = tmp_path / "f.ome.zarr"
    root = zarr.group(store=parse_url(str(path), mode="w").store)
    write_image((100 * np.tile(_field(), (2, 2, 2))).astype(np.uint8), root, axes="zyx",
                storage_options={"chunks": (8, 8, 8)}, scale_factors=[])
    # the writer drops axis units: put them where OME-NGFF 0.5 has them
    ome = dict(root.attrs["ome"])
    ome["multiscales"][0]["axes"] = [{"name": a, "type": "space", "unit": "micrometer"}
                                     for a in "zyx"]
    root.attrs["ome"] = ome
    volume = sv.read_volume(path)
    assert volume.unit == "µm"
    assert volume.read(((0, 4), (0, 4), (0, 4))).unit == "µm"


def test_dicom_is_millimetres(tmp_path):
    pydicom = pytest.importorskip("pydicom")
    from pydicom.data import get_testdata_file
    from pydicom.uid import generate_uid

    template = pydicom.dcmread(get_testdata_file("CT_small.dcm"))
    uid = generate_uid()
    for k in range(3):
        ds = template.copy()
        ds.SeriesInstanceUID, ds.SOPInstanceUID = uid, generate_uid()
        ds.ImagePositionPatient = [0.0, 0.0, 2.0 * k]
        ds.save_as(tmp_path / f"s{k}.dcm")
    assert sv.read_volume(tmp_path).unit == "mm"


def test_scene_probe_and_curve_figures_carry_the_unit():
    from splineviz.core.slice_sampling import Probe
    from splineviz.gui.panels.analysis import curve_summary
    from splineviz.model import Scene

    scene = Scene()
    scene.add_volume(sv.Volume(_field(), unit="mm"), "a", isosurface=False)
    assert scene.length_unit() == "mm"
    scene.add_volume(sv.Volume(_field()), "b", isosurface=False)
    assert scene.length_unit() == ""  # one volume of no stated unit: no unit for the scene
    line = Probe(np.array([1.0, 2.0, 3.0]), 0.5, np.array([1.0, 0.0, 0.0])).describe("mm")
    assert "(1, 2, 3) mm" in line and "/mm" in line

    class Curve:
        closed, length, area = True, 31.4159, 78.54

    assert curve_summary([Curve()], "µm") == \
        "curve 1: closed, length 31.4159 µm, area 78.54 µm²"
    assert curve_summary([Curve()]) == "curve 1: closed, length 31.4159, area 78.54"
    assert curve_summary([Curve()], "mm").endswith("area 78.54 mm²")


def test_ruler_labels_in_slice_and_3d_views():
    import vtk

    from splineviz.render.slice_view import SlicePlanesMarker, SliceScene

    renderer = vtk.vtkRenderer()
    scene = SliceScene(renderer, "axial")
    scene.set_extent(((0.0, 100.0), (0.0, 100.0), (0.0, 100.0)))
    scene.set_ruler(np.array([0.0, 0.0, 5.0]), np.array([30.0, 40.0, 5.0]), "µm")
    assert scene._ruler_label.GetInput() == "50 um"  # VTK's fonts draw ASCII
    marker = SlicePlanesMarker(renderer)
    marker.set_ruler(np.zeros(3), np.array([0.0, 0.0, 2500.0]), "mm")
    label = marker._props[renderer][2]  # the label the marker draws in this renderer
    assert label.GetInput() == "2.5 m"
    marker.set_ruler(np.zeros(3), np.array([0.0, 0.0, 12.5]))
    assert label.GetInput() == "12.5"
