"""Widgets tested alone with qtbot (no main window)."""

import numpy as np
import pytest
from PySide6.QtCore import QPointF, Qt

from splineviz.gui.widgets import HistogramSlider
from splineviz.model.summaries import HISTOGRAM_BINS, log_histogram


def test_log_histogram_counts():
    data = np.array([0.0, 0.0, 0.0, 1.0, np.nan, np.inf])
    counts, edges = log_histogram(data, bins=4)
    assert edges[0] == 0.0 and edges[-1] == 1.0
    assert np.allclose(counts, np.log1p([3, 0, 0, 1]))  # non-finite samples are ignored
    c, e = log_histogram(np.full(5, 2.0))
    assert len(c) == HISTOGRAM_BINS and e[0] == 2.0 and c.sum() == pytest.approx(np.log1p(5))


def test_histogram_slider_mouse_and_keys(qtbot):
    w = HistogramSlider()
    qtbot.addWidget(w)
    w.resize(212, 60)
    w.show()
    w.set_data(np.linspace(10.0, 20.0, 1000))
    assert w.range() == (10.0, 20.0)
    with qtbot.waitSignal(w.valueChanged) as sig:
        w.setValue(99.0)          # clamped to the data range
    assert sig.args == [20.0] and w.value() == 20.0
    # the plot spans x = 6 .. 206: a click at the middle picks the middle value
    qtbot.mouseClick(w, Qt.MouseButton.LeftButton, pos=QPointF(106, 30).toPoint())
    assert w.value() == pytest.approx(15.0, abs=0.06)
    with qtbot.waitSignal(w.released):
        qtbot.keyClick(w, Qt.Key.Key_Right)
    assert w.value() == pytest.approx(15.0 + 10.0 / HISTOGRAM_BINS, abs=0.06)
    qtbot.keyClick(w, Qt.Key.Key_PageDown)
    assert w.value() == pytest.approx(15.0 - 9 * 10.0 / HISTOGRAM_BINS, abs=0.06)
