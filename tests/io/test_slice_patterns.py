"""Patterns of numbered 2-D slices (issue 25, part 3): ``read_volume("scan/*.tif")`` and
``read_volume("scan/img_%03d.png")`` open the matching slices as one stack in natural order,
on the command line too; no match or mixed sizes are one sentence."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

import splineviz as sv
from splineviz.cli import main
from splineviz.io._util import has_pattern

tifffile = pytest.importorskip("tifffile")


def _stack(n=12, ny=9, nx=11):
    """(nz, ny, nx) uint8: slice k holds 10 * k + column, so the order is visible."""
    cols = np.arange(nx, dtype=np.uint8)
    return np.stack([np.tile(10 * k + cols, (ny, 1)) for k in range(n)]).astype(np.uint8)


def _write_tiffs(folder, stack, name="s{}.tif"):
    folder.mkdir(exist_ok=True)
    for k, page in enumerate(stack):
        tifffile.imwrite(folder / name.format(k + 1), page)


def test_a_glob_pattern_opens_its_slices_in_natural_order(tmp_path):
    stack = _stack()
    _write_tiffs(tmp_path / "scan", stack)  # s1.tif ... s12.tif: s2 before s10
    (tmp_path / "scan" / "notes.txt").write_text("not a slice")
    vol = sv.read_volume(tmp_path / "scan" / "s*.tif")
    assert vol.shape == (11, 9, 12) and vol.dtype == np.uint8
    np.testing.assert_array_equal(vol.data, stack.transpose(2, 1, 0))


def test_a_printf_pattern_opens_the_numbers_written_that_way(tmp_path):
    stack = _stack(n=4)
    for k, page in enumerate(stack):
        Image.fromarray(page).save(tmp_path / f"img_{k + 8:03d}.png")
    Image.fromarray(stack[0]).save(tmp_path / "img_9.png")  # not three digits: not matched
    Image.fromarray(stack[0]).save(tmp_path / "other_001.png")
    assert has_pattern(tmp_path / "img_%03d.png") and not has_pattern(tmp_path)
    vol = sv.read_volume(tmp_path / "img_%03d.png")
    np.testing.assert_array_equal(vol.data, stack.transpose(2, 1, 0))
    # %d takes any number: img_9.png joins, between img_008 and img_010
    assert sv.read_volume(tmp_path / "img_%d.png").shape == (11, 9, 5)


def test_no_match_and_mixed_sizes_are_one_sentence(tmp_path):
    _write_tiffs(tmp_path, _stack(n=3))
    with pytest.raises(sv.SplinevizError, match=r"pattern q\*.tif in .* matches no TIFF") as e:
        sv.read_volume(tmp_path / "q*.tif")
    assert "\n" not in str(e.value)
    with pytest.raises(sv.SplinevizError, match="matches no TIFF"):
        sv.read_volume(tmp_path / "missing" / "img_%04d.tif")
    tifffile.imwrite(tmp_path / "s4.tif", np.zeros((5, 5), np.uint8))
    with pytest.raises(sv.SplinevizError, match="slice s4.tif is 5x5 uint8; the stack's "
                                                 "first slice is 11x9 uint8"):
        sv.read_volume(tmp_path / "s*.tif")


def test_info_and_render_take_a_pattern(tmp_path, capsys):
    _write_tiffs(tmp_path, _stack())
    pattern = str(tmp_path / "s*.tif")
    assert main(["info", pattern]) == 0
    out = capsys.readouterr().out
    assert "slices" in out and "11 9 12" in out
    png = tmp_path / "shot.png"
    assert main(["render", pattern, "--iso", "60", "--model", "trilinear", "--size", "48x36",
                 "-o", str(png)]) == 0
    assert png.stat().st_size > 100
    assert main(["info", str(tmp_path / "none_*.tif")]) == 2
    assert "matches no TIFF or PNG slices" in capsys.readouterr().err
