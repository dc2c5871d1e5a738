"""Every file in ../shared/data reads with the right geometry (dims, spacing, origin, range).

Expected values come from the data sets' headers and README (../shared/data/README.md), not
from our own readers.
"""

import functools
from pathlib import Path

import numpy as np
import pytest

import splineviz as sv
from splineviz.io import load_point_data, load_volume_data
from splineviz.io.points import validate_point_data
from splineviz.io.volumes import to_volume

DATA = Path(__file__).resolve().parents[2] / ".." / "shared" / "data"
VOL = DATA / "volumes"
PTS = DATA / "points"

pytestmark = pytest.mark.skipif(not DATA.is_dir(), reason="shared data sets not present")

@functools.cache
def _volume_data(name):
    """Each volume file is read once per test session (in its stored dtype)."""
    return load_volume_data(VOL / name)


# file, shape (nx, ny, nz), stored dtype, spacing, origin, (min, max)
VOLUMES = [
    ("bonsai.vti", (256, 256, 256), "uint8", (1, 1, 1), (0, 0, 0), (0, 255)),
    ("engine.vti", (256, 256, 128), "uint8", (1, 1, 1), (0, 0, 0), (0, 255)),
    ("tooth.nrrd", (103, 94, 161), "uint8", (1, 1, 1), (0, 0, 0), (0, 255)),
    ("neghip.slc", (66, 66, 66), "uint8", (1, 1, 1), (0, 0, 0), (0, 255)),
    ("ironProt.vtk", (68, 68, 68), "uint8", (1, 1, 1), (0, 0, 0), (0, 255)),
    ("HeadMRVolume.mhd", (48, 62, 42), "uint8", (4, 4, 4), (0, 0, 0), (0, 255)),
    ("headsq/quarter.nhdr", (64, 64, 93), "int16", (3.2, 3.2, 1.5), (0, 0, 0), (0, 3926)),
    ("hydrogen.vti", (64, 64, 64), "float32", (1, 1, 1), (0, 0, 0), (0, 1)),
    ("carotid.vtk", (76, 49, 45), "float32", (1, 1, 1), (100, 80, 1), (0, 580)),
    ("embryo.slc", (256, 256, 256), "uint8", (1, 1, 1), (0, 0, 0), (0, 197)),
    ("frogtissue.mhd", (500, 470, 136), "uint8", (1, 1, 1.5), (0, 0, 0), (0, 29)),
]


@pytest.mark.parametrize("name, shape, dtype, spacing, origin, rng", VOLUMES,
                         ids=[v[0] for v in VOLUMES])
def test_volume_geometry(name, shape, dtype, spacing, origin, rng):
    vd = _volume_data(name)  # one read: stored dtype, then the float32 volume
    assert vd.data.shape == shape
    assert vd.data.dtype == np.dtype(dtype)
    vol = to_volume(vd, name)
    assert vol.shape == shape
    np.testing.assert_allclose(vol.spacing, spacing, rtol=1e-6)
    np.testing.assert_allclose(vol.origin, origin, rtol=1e-6)
    assert vol.finite_range == pytest.approx(rng)


def test_frog_labels_are_the_26_tissue_labels():
    # the README: a label map of 26 labels (0 is one of them; 18, 19, 22 and 28 are unused)
    labels = np.unique(_volume_data("frogtissue.mhd").data)
    assert len(labels) == 26 and labels[0] == 0 and labels[-1] == 29


def test_frog_samples_are_its_whole_compressed_stream():
    """frogtissue.mhd's CompressedDataSize (260020) understates its .zraw (262087 bytes):
    VTK's MetaIO inflates only that much and left the last 996,715 samples uninitialised
    (labels 30..255 of freed memory in a busy test run). Every sample is the stream's."""
    import zlib

    stream = zlib.decompress((VOL / "frogtissue.zraw").read_bytes())
    want = np.frombuffer(stream, np.uint8).reshape(136, 470, 500).transpose(2, 1, 0)
    np.testing.assert_array_equal(_volume_data("frogtissue.mhd").data, want)


def test_legacy_vtk_sample_order_is_x_fastest():
    """Read carotid.vtk's binary payload directly (big-endian float32 after the header) and
    compare a few samples at asymmetric indices with data[i, j, k]."""
    raw = (VOL / "carotid.vtk").read_bytes()
    start = raw.index(b"LOOKUP_TABLE default") + len(b"LOOKUP_TABLE default\n")
    nx, ny, nz = 76, 49, 45
    flat = np.frombuffer(raw, dtype=">f4", count=nx * ny * nz, offset=start)
    vol = sv.read_volume(VOL / "carotid.vtk")
    for i, j, k in [(3, 17, 40), (70, 5, 2), (40, 30, 20)]:
        assert vol.data[i, j, k] == flat[i + nx * (j + ny * k)]


def test_detached_multifile_nrrd_slices_in_order():
    """quarter.%d: slice k of the volume is the file quarter.(k+1), little-endian int16."""
    vol = sv.read_volume(VOL / "headsq" / "quarter.nhdr")
    for k in (0, 41, 92):
        sl = np.fromfile(VOL / "headsq" / f"quarter.{k + 1}", dtype="<i2").reshape(64, 64)
        np.testing.assert_array_equal(vol.data[:, :, k], sl.T.astype(np.float32))


def test_mrc_voxel_size_origin_and_axis_order():
    """EMD-3001 stores columns along z, rows along x, sections along y (MAPC/R/S = 3, 1, 2),
    cell 17.93 x 4.71 x 33.03 A over 40 x 12 x 72 intervals, start indices (0, -21, -12)."""
    import mrcfile

    vd = load_volume_data(VOL / "EMD-3001.map")
    assert vd.data.shape == (43, 25, 73)
    assert vd.meta["axis_order"] == "zxy"
    vs = (17.93 / 40, 4.71 / 12, 33.03 / 72)
    np.testing.assert_allclose(vd.spacing, vs, rtol=1e-5)
    np.testing.assert_allclose(vd.origin, (-21 * vs[0], -12 * vs[1], 0.0), rtol=1e-5)
    with mrcfile.open(VOL / "EMD-3001.map") as m:
        d = np.array(m.data)  # [section (y), row (x), column (z)]
    assert vd.data[5, 7, 60] == d[7, 5, 60]
    vd2 = load_volume_data(VOL / "EMD-3197.map")
    assert vd2.data.shape == (20, 20, 20)
    np.testing.assert_allclose(vd2.spacing, (11.4,) * 3, rtol=1e-6)
    vol = sv.read_volume(VOL / "EMD-3197.map")
    assert vol.finite_range == pytest.approx((-4.1337457, 5.576737), rel=1e-6)


@functools.cache
def _points(name):
    """Each point file is parsed once per test session (bunny.ply's ascii takes ~1.5 s)."""
    return load_point_data(PTS / name)


# file, vertices, normals, colours, encoding
POINTS = [
    ("bunny.ply", 35947, False, False, "ascii"),
    ("bunny_res2.ply", 8171, False, False, "ascii"),
    ("kitten.xyz", 5210, True, False, None),
    ("lucy.ply", 49987, False, False, "binary_little_endian"),
    ("horse.ply", 48485, False, True, "binary_big_endian"),
    ("pepper.ply", 14980, False, False, None),
    ("turbineblade.ply", 99519, False, False, None),
]


@pytest.mark.parametrize("name, n, normals, colours, enc", POINTS, ids=[p[0] for p in POINTS])
def test_point_files(name, n, normals, colours, enc):
    pd = _points(name)
    assert len(pd.points) == n
    assert (pd.colors is not None) == colours
    if enc is not None:
        assert pd.meta["encoding"] == enc
    pc = validate_point_data(pd, name)  # what read_points does after reading
    assert (pc.normals is not None) == normals
    assert len(pc.points) <= n and len(pc.points) >= 0.99 * n
    assert np.all(np.isfinite(pc.points))


def test_kitten_normals_are_unit():
    pc = sv.read_points(PTS / "kitten.xyz")
    np.testing.assert_allclose(np.linalg.norm(pc.normals, axis=1), 1.0, atol=1e-4)


def test_bunny_bounds_match_the_stanford_model():
    # bun_zipper.ply's documented extent (metres); first vertex -0.0378297 0.12794 0.00447467
    pc = validate_point_data(_points("bunny.ply"), "bunny.ply")
    np.testing.assert_allclose(pc.points[0], (-0.0378297, 0.12794, 0.00447467), rtol=1e-5)
    assert pc.points[:, 1].max() == pytest.approx(0.187, abs=1e-3)


def test_cli_info_reports_dims_dtype_range_spacing(capsys):
    import json

    from splineviz import cli

    assert cli.main(["info", str(VOL / "headsq" / "quarter.nhdr"), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["kind"] == "volume" and info["format"] == "nrrd"
    assert info["dims"] == [64, 64, 93] and info["dtype"] == "int16"
    assert info["range"] == [0.0, 3926.0] and info["spacing"] == [3.2, 3.2, 1.5]
    assert cli.main(["info", str(PTS / "kitten.xyz")]) == 0
    text = capsys.readouterr().out
    assert "points: 5210" in text and "normals: True" in text


def test_relative_paths_work_for_detached_payloads(monkeypatch):
    """Regression: slice files of a header given by a relative path were looked up twice
    relative to its folder."""
    import os

    monkeypatch.chdir(VOL)
    rel = os.path.join("headsq", "quarter.nhdr")
    assert sv.read_volume(rel).shape == (64, 64, 93)
    for name in ("HeadMRVolume.mhd", "tooth.nrrd", "neghip.slc"):
        assert sv.read_volume(name).shape == sv.read_volume(VOL / name).shape
