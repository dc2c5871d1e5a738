"""The command line's volume options: ``--channel`` picks a channel of a multi-channel file
(``render`` and ``info``), ``--oblique`` shows a rotated scan in place, resampled or refused,
and ``info`` prints the affine."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from splineviz.cli import main

nib = pytest.importorskip("nibabel")


@pytest.fixture
def two_channels(tmp_path):
    """(x, y, z, t, c) NIfTI: channel 0 a ball, channel 1 a square prism, two times."""
    g = np.linspace(-1.0, 1.0, 16)
    x, y, z = np.meshgrid(g, g, g, indexing="ij")
    ball = np.sqrt(x**2 + y**2 + z**2)
    prism = np.maximum(np.abs(x), np.abs(y))
    data = np.stack([np.stack([ball, prism], -1)] * 2, 3).astype(np.float32)
    path = tmp_path / "two.nii"
    nib.save(nib.Nifti1Image(data, np.eye(4)), path)
    return path


def test_render_channel_chooses_what_is_drawn(two_channels, tmp_path, capsys):
    shots = []
    for channel in (0, 1):
        out = tmp_path / f"c{channel}.png"
        assert main(["render", str(two_channels), "--iso", "0.6", "--model", "trilinear",
                     "--size", "48x36", "--channel", str(channel), "-o", str(out)]) == 0
        shots.append(np.asarray(Image.open(out).convert("L"), dtype=float))
    assert "2 frames" in capsys.readouterr().err
    # the prism's silhouette is not the ball's
    assert np.abs(shots[0] - shots[1]).mean() > 2.0
    assert main(["render", str(two_channels), "--channel", "7", "-o",
                 str(tmp_path / "x.png")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "channel 7 is not one" in err[0]


def test_info_prints_affine_frames_and_channel(two_channels, capsys):
    assert main(["info", str(two_channels), "--channel", "1"]) == 0
    text = capsys.readouterr().out
    assert "affine: [1 0 0 0]  [0 1 0 0]  [0 0 1 0]  [0 0 0 1]" in text
    assert "frames: 2 along frame" in text and "channel: 1 of 2" in text


def test_render_oblique_scan_in_place_resampled_or_refused(tmp_path, capsys):
    t = np.radians(20.0)
    affine = np.eye(4)
    affine[:2, :2] = [[np.cos(t), -np.sin(t)], [np.sin(t), np.cos(t)]]
    g = np.linspace(-1.0, 1.0, 16)
    x, y, z = np.meshgrid(g, g, g, indexing="ij")
    nib.save(nib.Nifti1Image(np.sqrt(x**2 + y**2 + z**2).astype(np.float32), affine),
             tmp_path / "tilted.nii")
    args = ["render", str(tmp_path / "tilted.nii"), "--iso", "0.6", "--model", "trilinear",
            "--size", "32x24", "-o", str(tmp_path / "t.png")]
    assert main(args) == 0
    assert main([*args, "--oblique", "error"]) == 2
    assert "20 degrees" in capsys.readouterr().err
    assert main([*args, "--oblique", "resample"]) == 0
    assert "resampled" in capsys.readouterr().err
    assert main(["info", str(tmp_path / "tilted.nii")]) == 0
    out = capsys.readouterr().out
    assert "oblique: rotated by 20 degrees" in out and "direction: [0.939693" in out
