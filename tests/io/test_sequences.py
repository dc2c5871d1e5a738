"""4-D NRRD and NumPy files as volume sequences: NRRD says which axes are space and what
the others are (kinds, axis mins, spacings, units); a .npy keeps x, y, z first."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import splineviz as sv
from splineviz.core.errors import SplinevizWarning
from splineviz.io import describe, read_volume_sequence
from splineviz.io.errors import InvalidDataError


def test_nrrd_time_axis_from_kinds_with_its_times(tmp_path):
    import nrrd

    data = np.random.default_rng(0).random((5, 6, 7, 4)).astype(np.float32)
    nrrd.write(str(tmp_path / "t.nrrd"), data,
               {"kinds": ["domain", "domain", "domain", "time"], "spacings": [1, 2, 1, 0.5],
                "axis mins": [np.nan, np.nan, np.nan, 10.0], "units": ["mm", "mm", "mm", "s"]},
               index_order="F")
    seq = read_volume_sequence(tmp_path / "t.nrrd")
    assert (len(seq), seq.axis.name, seq.axis.unit) == (4, "time", "s")
    assert seq.times == pytest.approx((10.0, 10.5, 11.0, 11.5))
    np.testing.assert_array_equal(seq[3].data, data[..., 3])
    assert seq[3].spacing == (1.0, 2.0, 1.0)
    assert describe(tmp_path / "t.nrrd")["frames"] == "4 along time (s)"


def test_nrrd_color_axis_first_is_a_channel_axis(tmp_path):
    """The RGB axis of an NRRD comes first (fastest); its space directions say ``none``."""
    import nrrd

    data = np.random.default_rng(1).random((3, 5, 6, 7)).astype(np.float32)
    dirs = np.array([[np.nan] * 3, [1.0, 0, 0], [0, -2.0, 0], [0, 0, 1.0]])
    nrrd.write(str(tmp_path / "rgb.nrrd"), data,
               {"kinds": ["RGB-color", "domain", "domain", "domain"],
                "space": "left-posterior-superior", "space directions": dirs,
                "space origin": np.zeros(3)}, index_order="F")
    with pytest.warns(SplinevizWarning, match="negative spacing along y"):
        vol = sv.read_volume(tmp_path / "rgb.nrrd", channel=2)
    np.testing.assert_array_equal(vol.data, data[2][:, ::-1, :])
    assert vol.origin == (0.0, -10.0, 0.0)
    seq = read_volume_sequence(tmp_path / "rgb.nrrd", channel=1)
    assert (len(seq), seq.channel, seq.channels) == (1, 1, 3)


def test_nrrd_4d_without_kinds_or_directions_is_refused(tmp_path):
    import nrrd

    nrrd.write(str(tmp_path / "bare.nrrd"), np.zeros((2, 3, 4, 5), np.float32),
               index_order="F")
    with pytest.raises(InvalidDataError, match="do not say which three axes are space"):
        sv.read_volume(tmp_path / "bare.nrrd")


def test_npy_4d_is_read_frame_by_frame(tmp_path):
    data = np.random.default_rng(2).random((4, 5, 6, 3)).astype(np.float32)
    np.save(tmp_path / "s.npy", data)
    seq = read_volume_sequence(tmp_path / "s.npy")
    assert (len(seq), seq.axis.name) == (3, "frame")
    np.testing.assert_array_equal(seq[-1].data, data[..., 2])
    with warnings.catch_warnings(record=True) as notes:
        warnings.simplefilter("always")
        first = sv.read_volume(tmp_path / "s.npy")
    np.testing.assert_array_equal(first.data, data[..., 0])
    assert [str(n.message) for n in notes] == [
        "s.npy holds 3 frames along its frame axis (the first is shown; read_volume_sequence "
        "reads them all)"]
    with pytest.raises(IndexError):
        seq[3]
