"""Tick labels of the axes grid (issue 26, part 6): round values in engineering notation,
no "-0", no float noise, one exponent per axis shown in its title."""

import pytest

from splineviz.core.ticks import LABEL_CHAR_PX, MAX_LABELS, axis_ticks, label_stride, vtk_step


def test_float_noise_at_an_origin_is_zero():
    t = axis_ticks(6e-29, 10.0, "X")
    assert t.labels == ("0", "2", "4", "6", "8", "10") and t.title == "X"
    assert t.lo == 0.0 and t.hi == 10.0


def test_a_bunny_in_metres_is_labelled_in_millimetres_without_minus_zero():
    t = axis_ticks(-0.094, 0.061, "Y", unit="m")
    assert t.title == "Y (mm)" and t.exponent == -3
    assert t.labels[0] == "-100" and t.labels[-1] == "80" and "0" in t.labels
    assert not any(label in ("-0", "-0.0") or "e" in label for label in t.labels)
    assert t.lo <= -0.094 and t.hi >= 0.061


def test_without_a_unit_the_exponent_is_a_factor_in_the_title():
    t = axis_ticks(1e-5, 3.3e-5, "Z")
    assert t.title == "Z (x 1e-6)" and t.labels == ("10", "15", "20", "25", "30", "35")
    assert axis_ticks(0.0, 255.0, "X").title == "X"


@pytest.mark.parametrize(("lo", "hi"), [(-0.3, 0.3), (-9.44, 9.44), (1.0, 1.0 + 1e-12),
                                        (0.0, 1e6), (-1234.5, -17.25), (5.0, 5.0)])
def test_labels_are_whole_steps_that_cover_the_range(lo, hi):
    t = axis_ticks(lo, hi, "X")
    assert t.lo <= lo and t.hi >= hi
    n = round((t.hi - t.lo) / t.step)
    assert len(t.labels) == n + 1
    # the step is the one VTK's cube axes draw ticks at, on the padded range
    assert vtk_step(t.hi - t.lo) == pytest.approx(t.step)
    shown = [float(x) for x in t.labels]
    scale = 10.0 ** -t.exponent
    assert shown == pytest.approx([(t.lo + k * t.step) * scale for k in range(n + 1)],
                                  abs=1e-9 * scale * t.step)
    assert all(float(x) != 0 or x == "0" for x in t.labels)  # no "-0", no "0.0"


def test_a_narrow_axis_shows_fewer_labels_that_fit_and_keep_zero():
    labels = axis_ticks(0.0, 100.0, "X").labels  # 0, 20, ..., 100 (or finer)
    wide = label_stride(labels, 2000.0)
    assert len(labels[::wide]) <= MAX_LABELS
    for axis_px in (60.0, 90.0, 140.0, 200.0):
        stride = label_stride(labels, axis_px)
        shown = [t for k, t in enumerate(labels) if k % stride == 0]
        assert shown[0] == "0" and len(shown) >= 1
        width = (max(map(len, labels)) + 2) * LABEL_CHAR_PX
        assert len(shown) <= max(2, axis_px // width), (axis_px, shown)
    assert label_stride(labels, 60.0) > label_stride(labels, 400.0)
