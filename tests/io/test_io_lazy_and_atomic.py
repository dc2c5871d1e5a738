"""Start-up stays cheap (no io, no plugins on ``import splineviz``) and writes are atomic."""

import subprocess
import sys

import numpy as np
import pytest

import splineviz as sv
from splineviz.io import errors
from splineviz.io import volumes as vol_mod


def test_import_splineviz_loads_no_io_and_no_plugin():
    code = ("import sys, splineviz; print(any(m.startswith(('splineviz.io', 'splineviz.plugins',"
            " 'splineviz_sources', 'vtk')) for m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=120)
    assert out.stdout.strip() == "False", out.stderr


def test_interrupted_write_keeps_the_old_file(tmp_path, monkeypatch):
    target = tmp_path / "v.npy"
    sv.write_volume(target, np.zeros((2, 3, 4)))
    before = target.read_bytes()

    def crash_midway(path, data, allow_pickle=False):
        with open(path, "wb") as fh:
            fh.write(b"\x93NUMPY partial")
        raise KeyboardInterrupt  # the user hit Ctrl-C in the middle of a write

    monkeypatch.setattr(vol_mod.np, "save", crash_midway)
    with pytest.raises(KeyboardInterrupt):
        sv.write_volume(target, np.ones((2, 3, 4)))
    assert target.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == ["v.npy"]


def test_failed_write_of_a_new_file_leaves_nothing(tmp_path):
    with pytest.raises(errors.InvalidDataError):
        sv.write_screenshot(tmp_path / "s.png", np.zeros((0, 4, 3), np.uint8))
    assert list(tmp_path.iterdir()) == []


def test_mrc_header_origin_wins_over_start_indices(tmp_path):
    import mrcfile

    with mrcfile.new(tmp_path / "o.mrc") as m:
        m.set_data(np.zeros((4, 3, 2), np.float32))
        m.voxel_size = 1.5
        m.header.origin = (10.0, 20.0, 30.0)
        m.header.nxstart = 5
    v = sv.read_volume(tmp_path / "o.mrc")
    assert v.shape == (2, 3, 4) and v.origin == (10.0, 20.0, 30.0)
