"""TIFF stacks (multi-page, BigTIFF, ImageJ, OME-TIFF) and folders or patterns of 2-D slices."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

import splineviz as sv
from splineviz.core.chunked import ChunkedVolume
from splineviz.io import load_volume_data
from splineviz.io.errors import InvalidDataError
from splineviz.io.tiff import LAZY_SHARE_ENV, natural_key

tifffile = pytest.importorskip("tifffile")

ROOT = Path(__file__).resolve().parents[2]


def _blob(shape=(24, 20, 16)):
    """An asymmetric uint16 phantom, (x, y, z): a ball off centre and a bar along x."""
    x, y, z = np.meshgrid(*[np.arange(n, dtype=np.float64) for n in shape], indexing="ij")
    ball = 1000.0 * np.exp(-((x - 9) ** 2 + (y - 8) ** 2 + (z - 7) ** 2) / 18.0)
    bar = 600.0 * ((np.abs(y - 14) < 2) & (np.abs(z - 4) < 2) & (x > 3))
    return (ball + bar).astype(np.uint16)


def _write_imagej(path, vol_xyz, spacing, unit="um", **kw):
    """ImageJ stack of ``vol_xyz`` (stored z, y, x) with x/y resolution and z spacing."""
    sx, sy, sz = spacing
    tifffile.imwrite(path, np.ascontiguousarray(vol_xyz.transpose(2, 1, 0)), imagej=True,
                     resolution=(1 / sx, 1 / sy),
                     metadata={"spacing": sz, "unit": unit, "axes": "ZYX"}, **kw)


def test_imagej_stack_has_its_spacing_unit_and_values(tmp_path):
    vol = _blob()
    _write_imagej(tmp_path / "s.tif", vol, (0.5, 0.25, 2.0))
    vd = load_volume_data(tmp_path / "s.tif")
    assert vd.format == "tiff" and vd.meta["flavour"] == "imagej"
    assert vd.meta["unit"] == "um"
    np.testing.assert_allclose(vd.spacing, (0.5, 0.25, 2.0))
    assert vd.data.dtype == np.uint16
    np.testing.assert_array_equal(vd.data, vol)


def test_ome_tiff_physical_sizes_and_unit_conversion(tmp_path):
    vol = _blob()
    tifffile.imwrite(tmp_path / "o.ome.tif", np.ascontiguousarray(vol.transpose(2, 1, 0)),
                     ome=True, metadata={"axes": "ZYX", "PhysicalSizeX": 0.5,
                                         "PhysicalSizeY": 0.75, "PhysicalSizeZ": 0.002,
                                         "PhysicalSizeZUnit": "mm"})
    vd = load_volume_data(tmp_path / "o.ome.tif")
    assert vd.meta["flavour"] == "ome"
    np.testing.assert_allclose(vd.spacing, (0.5, 0.75, 2.0))  # z in mm -> um as x
    np.testing.assert_array_equal(vd.data, vol)


@pytest.mark.parametrize("kw", [{"bigtiff": True}, {"compression": "zlib"},
                                {"compression": "lzw"}, {"tile": (16, 16)}])
def test_plain_bigtiff_and_compressed_stacks(tmp_path, kw):
    if kw.get("compression") == "lzw":
        pytest.importorskip("imagecodecs")
    vol = _blob((40, 36, 6)).astype(np.float32)
    tifffile.imwrite(tmp_path / "p.tif", np.ascontiguousarray(vol.transpose(2, 1, 0)), **kw)
    v = sv.read_volume(tmp_path / "p.tif")
    assert v.spacing == (1.0, 1.0, 1.0)
    np.testing.assert_array_equal(v.data, vol)
    if kw.get("bigtiff"):
        assert load_volume_data(tmp_path / "p.tif").meta["bigtiff"]


def test_a_renamed_tiff_is_found_by_its_content(tmp_path):
    vol = _blob()
    tifffile.imwrite(tmp_path / "stack.dat", np.ascontiguousarray(vol.transpose(2, 1, 0)))
    with pytest.raises(sv.SplinevizError):  # .dat is raw: it needs dims, says so
        sv.read_volume(tmp_path / "stack.dat")
    tifffile.imwrite(tmp_path / "stack.bin2", np.ascontiguousarray(vol.transpose(2, 1, 0)))
    np.testing.assert_array_equal(sv.read_volume(tmp_path / "stack.bin2").data, vol)


@pytest.mark.parametrize("make, says", [
    (lambda p: tifffile.imwrite(p, np.zeros((5, 2, 8, 9), np.uint8), imagej=True,
                                metadata={"axes": "ZCYX"}), "2 channels"),
    (lambda p: tifffile.imwrite(p, np.zeros((3, 5, 8, 9), np.uint8), imagej=True,
                                metadata={"axes": "TZYX"}), "3 time points"),
    (lambda p: tifffile.imwrite(p, np.zeros((8, 9), np.uint8)), "single 2-D picture"),
    (lambda p: tifffile.imwrite(p, np.zeros((8, 9, 3), np.uint8), photometric="rgb"),
     "colour"),
])
def test_what_is_not_one_volume_is_refused_in_one_sentence(tmp_path, make, says):
    make(tmp_path / "x.tif")
    with pytest.raises(InvalidDataError, match=says) as info:
        sv.read_volume(tmp_path / "x.tif")
    assert "\n" not in str(info.value)


def test_a_truncated_tiff_is_a_clean_error(tmp_path):
    vol = _blob()
    tifffile.imwrite(tmp_path / "t.tif", np.ascontiguousarray(vol.transpose(2, 1, 0)))
    raw = (tmp_path / "t.tif").read_bytes()
    (tmp_path / "t.tif").write_bytes(raw[: len(raw) // 2])
    with pytest.raises(sv.SplinevizError):
        sv.read_volume(tmp_path / "t.tif")


def test_natural_order():
    names = ["s10.png", "s2.png", "s1.png", "S3.png"]
    assert sorted(names, key=natural_key) == ["s1.png", "s2.png", "S3.png", "s10.png"]


def _write_png_slices(folder, vol):
    from PIL import Image

    folder.mkdir()
    for k in range(vol.shape[2]):
        Image.fromarray(np.ascontiguousarray(vol[:, :, k].T)).save(folder / f"slice{k}.png")


def test_folder_and_pattern_of_png_slices_in_natural_order(tmp_path):
    vol = _blob((20, 18, 12))
    _write_png_slices(tmp_path / "pngs", vol)  # slice10 sorts after slice9, not after slice1
    v = sv.read_volume(tmp_path / "pngs")
    np.testing.assert_array_equal(v.data, vol)
    opened = sv.open_path(tmp_path / "pngs" / "slice*.png")
    assert opened.kind == "volume"
    np.testing.assert_array_equal(opened.value.data, vol)
    assert load_volume_data(tmp_path / "pngs").format == "slices"


def test_folder_of_imagej_tiff_slices_keeps_the_first_slices_spacing(tmp_path):
    vol = _blob((20, 18, 11)).astype(np.float32)
    (tmp_path / "tifs").mkdir()
    for k in range(vol.shape[2]):
        _write_imagej(tmp_path / "tifs" / f"z{k:d}.tif", vol[:, :, k:k + 1], (0.3, 0.3, 1.5))
    (tmp_path / "tifs" / "notes.txt").write_text("scan notes")
    vd = load_volume_data(tmp_path / "tifs")
    assert vd.format == "slices"
    np.testing.assert_allclose(vd.spacing, (0.3, 0.3, 1.5))
    np.testing.assert_array_equal(vd.data, vol)


def test_slices_that_differ_are_refused(tmp_path):
    from PIL import Image

    (tmp_path / "s").mkdir()
    Image.fromarray(np.zeros((8, 9), np.uint8)).save(tmp_path / "s" / "a1.png")
    Image.fromarray(np.zeros((8, 9), np.uint8)).save(tmp_path / "s" / "a2.png")
    Image.fromarray(np.zeros((8, 10), np.uint8)).save(tmp_path / "s" / "a3.png")
    with pytest.raises(InvalidDataError, match="a3.png is 10x8"):
        sv.read_volume(tmp_path / "s")
    Image.fromarray(np.zeros((8, 9, 3), np.uint8)).save(tmp_path / "s" / "a3.png")
    with pytest.raises(InvalidDataError, match="RGB"):
        sv.read_volume(tmp_path / "s")


def test_above_the_lazy_share_a_stack_is_read_through_the_chunked_path(tmp_path, monkeypatch):
    vol = _blob((24, 20, 40))
    _write_imagej(tmp_path / "s.tif", vol, (0.5, 0.5, 1.0))
    _write_png_slices(tmp_path / "pngs", vol)
    monkeypatch.setenv(LAZY_SHARE_ENV, "0")
    for path in (tmp_path / "s.tif", tmp_path / "pngs"):
        v = sv.read_volume(path)
        assert isinstance(v, ChunkedVolume)
        np.testing.assert_array_equal(v.read(((3, 9), (0, 20), (33, 38))).data,
                                      vol[3:9, :, 33:38])
        np.testing.assert_array_equal(v.data.compute(), vol)
        assert v.finite_range == (float(vol.min()), float(vol.max()))
    monkeypatch.setenv(LAZY_SHARE_ENV, "1")
    assert isinstance(sv.read_volume(tmp_path / "s.tif"), sv.Volume)


def test_tiff_stack_renders_the_same_picture_as_the_same_data_in_nrrd(tmp_path):
    from compute.helpers import HAVE_CL

    from splineviz.core.camera import default_camera

    if not HAVE_CL:
        pytest.skip("no OpenCL device")
    vol = _blob()
    spacing = (0.5, 0.8, 1.25)
    _write_imagej(tmp_path / "s.tif", vol, spacing)
    import nrrd

    nrrd.write(str(tmp_path / "s.nrrd"), vol, {"spacings": list(spacing)})
    a, b = sv.read_volume(tmp_path / "s.tif"), sv.read_volume(tmp_path / "s.nrrd")
    assert a.spacing == pytest.approx(b.spacing) and a.origin == b.origin
    cam = default_camera(a.bounds)
    frames = []
    for v in (a, b):
        rc = sv.RayCaster(v, model="cubic-c1")
        rc.set_isovalue(300)
        frames.append(rc.render(cam, (96, 72)))
    assert frames[0].hit.sum() > 300
    np.testing.assert_array_equal(frames[0].color, frames[1].color)
    np.testing.assert_array_equal(frames[0].depth, frames[1].depth)


#: opens a TIFF as the GUI does (read, value range, histogram) and prints peak RSS in MiB
_PEAK_RSS = textwrap.dedent("""
    import json, os, sys, time
    from splineviz.bench.memory import peak_rss
    import dask.array, tifffile, zarr
    import splineviz.io, splineviz.model.opening as mo, splineviz.model.summaries
    from splineviz.core.chunked import ChunkedVolume
    base = peak_rss() / 2**20
    t = time.perf_counter()
    kind, vol, summaries = mo.read_file(sys.argv[1])
    print(json.dumps({"chunked": isinstance(vol, ChunkedVolume), "shape": list(vol.shape),
                      "range": list(vol.finite_range), "seconds": time.perf_counter() - t,
                      "base_mib": base,
                      "peak_mib": peak_rss() / 2**20}))
""")


def _write_big(path, shape_zyx, bigtiff):
    """A stack written page by page (never whole in memory): page k holds value k % 251
    with a bright square, so the range is known."""
    nz, ny, nx = shape_zyx

    def pages():
        for k in range(nz):
            page = np.full((ny, nx), k % 200, np.uint8)
            page[ny // 4: ny // 2, nx // 4: nx // 2] = 250
            yield page

    tifffile.imwrite(path, pages(), shape=shape_zyx, dtype=np.uint8, bigtiff=bigtiff,
                     metadata=None)


def _peak(path, env=None):
    import os

    out = subprocess.run([sys.executable, "-c", _PEAK_RSS, str(path)], capture_output=True,
                         text=True, timeout=900, cwd=ROOT,
                         env={**os.environ, **(env or {})}, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_opening_a_stack_above_the_lazy_share_keeps_memory_down(tmp_path):
    """A 256 MiB BigTIFF opened lazily (read, range, histogram) grows the process by far less
    than its size; read eagerly it would hold it and its float32 copy (1.25 GiB)."""
    _write_big(tmp_path / "big.tif", (256, 1024, 1024), bigtiff=True)
    got = _peak(tmp_path / "big.tif", {LAZY_SHARE_ENV: "0.0001"})
    assert got["chunked"] and got["shape"] == [1024, 1024, 256]
    assert 0 <= got["range"][0] < got["range"][1] <= 250  # from the coarse preview level
    print("256 MiB BigTIFF:", got)
    assert got["peak_mib"] - got["base_mib"] < 200, got


@pytest.mark.slow
def test_a_2_gb_bigtiff_opens_under_1_gb_peak_rss(tmp_path):
    """The issue's figure: 2 GiB of uint8 samples, default lazy share, peak RSS < 1 GB."""
    _write_big(tmp_path / "big2g.tif", (2048, 1024, 1024), bigtiff=True)
    got = _peak(tmp_path / "big2g.tif")
    print("2 GiB BigTIFF:", got)
    assert got["chunked"] and got["shape"] == [1024, 1024, 2048]
    assert 0 <= got["range"][0] < got["range"][1] <= 250
    assert got["peak_mib"] < 1000, got


def test_a_lazy_stack_pickles_and_renders_in_bricks_as_in_memory(tmp_path, monkeypatch):
    """Bricks read on dask workers: the region reader pickles (opening the file again in
    the worker), and the bricked picture is the in-memory one."""
    import pickle

    from compute.bricked_helpers import assert_same_picture, compare_frames, local_client
    from compute.helpers import HAVE_CL

    from splineviz.compute.bricked import BrickedRayCaster
    from splineviz.core.camera import default_camera

    vol = _blob((40, 36, 44))
    _write_imagej(tmp_path / "s.tif", vol, (0.5, 0.5, 1.0), compression="zlib")
    monkeypatch.setenv(LAZY_SHARE_ENV, "0")
    lazy = sv.read_volume(tmp_path / "s.tif")
    assert isinstance(lazy, ChunkedVolume)
    copy = pickle.loads(pickle.dumps(lazy.source))
    np.testing.assert_array_equal(copy[5:9, 0:36, 30:44], vol[5:9, :, 30:44])
    if not HAVE_CL:
        pytest.skip("no OpenCL device")
    mem = sv.Volume(vol, lazy.spacing, lazy.origin)
    cam = default_camera(lazy.bounds)
    rc = sv.RayCaster(mem, model="cubic-c1")
    rc.set_isovalue(200)
    with local_client(2) as client:
        brc = BrickedRayCaster(lazy, model="cubic-c1", client=client, brick_size=24)
        brc.set_isovalue(200)
        assert brc.stats["bricks"] > 1
        assert_same_picture(compare_frames(rc.render(cam, (128, 96)),
                                           brc.render(cam, (128, 96))))
