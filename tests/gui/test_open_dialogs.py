"""File > Open through the real widgets: the filter lists the new formats, folders open (a
folder of slices, a DICOM folder of two series through the chooser), a raw file asks for its
layout and the answer is remembered per file."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("pytestqt")

from PySide6.QtWidgets import QDialog, QDialogButtonBox, QFileDialog  # noqa: E402

import splineviz.gui.open_dialogs as od  # noqa: E402

sys.path.insert(0, str(Path(__file__).parent))
sys.path.insert(0, str(Path(__file__).parents[1] / "io"))

from interaction import close_window, open_window  # noqa: E402


@pytest.fixture
def window(qtbot, tmp_path):
    w = open_window(tmp_path / "settings", size=(160, 120))
    yield w
    close_window(w)


def test_the_open_filter_shows_the_new_formats():
    text = od.file_filter()
    first = text.split(";;")[0]
    for glob in ("*.tif", "*.tiff", "*.ome.tif", "*.dcm", "*.nrrd", "*.raw", "*.svs"):
        assert glob in first, glob
    assert "TIFF stack" in text and "DICOM file" in text and text.endswith("All files (*)")


def test_file_open_and_open_folder_use_the_dialogs(window, tmp_path, monkeypatch):
    from PIL import Image

    folder = tmp_path / "slices"
    folder.mkdir()
    vol = np.zeros((12, 10, 11), np.uint8)
    vol[3:8, 2:7, 4:9] = 200
    for k in range(vol.shape[2]):
        Image.fromarray(np.ascontiguousarray(vol[:, :, k].T)).save(folder / f"z{k}.png")
    asked = {}

    def folder_dialog(parent, title, *a, **k):
        asked["folder"] = title
        return str(folder)

    monkeypatch.setattr(QFileDialog, "getExistingDirectory", staticmethod(folder_dialog))
    window.actions_by_name["open folder"].trigger()
    window.wait_idle(60)
    window.wait_idle(60)
    assert "DICOM series" in asked["folder"]
    assert [v.name for v in window.scene.volumes][-1] == "slices"
    np.testing.assert_array_equal(window.scene.volumes[-1].data.data, vol)

    def file_dialog(parent, title, directory, filters, *a, **k):
        asked["filter"] = filters
        return str(folder / "z3.png"), ""

    monkeypatch.setattr(QFileDialog, "getOpenFileName", staticmethod(file_dialog))
    window.actions_by_name["open"].trigger()
    window.wait_idle(60)
    assert "*.tif" in asked["filter"]


def test_a_raw_file_asks_for_its_layout_and_remembers_it(window, tmp_path, monkeypatch):
    data = np.arange(6 * 5 * 4, dtype=">u2").reshape(4, 5, 6)  # z, y, x: x fastest
    path = tmp_path / "scan.raw"
    path.write_bytes(b"HDR!" + data.tobytes())
    shown = []

    def fill_and_accept(dialog):
        shown.append(dialog.layout_values())
        for box, n in zip(dialog.dims, (6, 5, 4), strict=True):
            box.setValue(n)
        dialog.dtype.setCurrentText("uint16")
        dialog.byteorder.setCurrentText("big")
        dialog.offset.setValue(3)
        assert not dialog.buttons.button(QDialogButtonBox.StandardButton.Open).isEnabled()
        assert "holds" in dialog.check.text()
        dialog.offset.setValue(4)
        assert dialog.buttons.button(QDialogButtonBox.StandardButton.Open).isEnabled()
        for box, s in zip(dialog.spacing, (0.5, 0.5, 2.0), strict=True):
            box.setValue(s)
        return QDialog.DialogCode.Accepted

    monkeypatch.setattr(od.RawDialog, "exec", fill_and_accept)
    od.open_chosen(window, path, mode="replace")
    window.wait_idle(60)
    node = window.scene.volumes[-1]
    assert node.name == "scan.raw" and node.data.spacing == (0.5, 0.5, 2.0)
    np.testing.assert_array_equal(node.data.data, data.transpose(2, 1, 0))
    assert node.read_options["dtype"] == "uint16" and node.read_options["offset"] == 4
    # the second time the dialog starts from what was entered for this file
    od.open_chosen(window, path, mode="replace")
    window.wait_idle(60)
    assert shown[1] == {"dims": [6, 5, 4], "dtype": "uint16", "byteorder": "big",
                        "offset": 4, "spacing": [0.5, 0.5, 2.0]}
    assert od.remembered_layout(tmp_path / "other.raw") is None

    monkeypatch.setattr(od.RawDialog, "exec", lambda d: QDialog.DialogCode.Rejected)
    n = len(window.scene.volumes)
    assert od.open_chosen(window, path, mode="add") is None
    assert len(window.scene.volumes) == n


def test_a_dicom_folder_of_two_series_asks_which(window, tmp_path, monkeypatch):
    from test_dicom import _write_ct_series

    _write_ct_series(tmp_path / "two", n=5, number=2, description="soft")
    _write_ct_series(tmp_path / "two", n=4, number=7, description="bone")
    offered = []

    def choose_second(dialog):
        offered.extend(dialog.list.item(i).text() for i in range(dialog.list.count()))
        dialog.list.setCurrentRow(1)
        return QDialog.DialogCode.Accepted

    monkeypatch.setattr(od.SeriesDialog, "exec", choose_second)
    od.open_chosen(window, tmp_path / "two", mode="replace")
    window.wait_idle(60)
    window.wait_idle(60)
    assert len(offered) == 2 and "'bone'" in offered[1]
    assert window.scene.volumes[-1].data.shape == (128, 128, 4)
