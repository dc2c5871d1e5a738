"""File > Open for every volume a user brings: files or folders (a DICOM series, a folder of
slices, a Zarr store), the file filter built from the format registry, the dialog that asks
for a raw file's layout (remembered per file) and the chooser between the series of a DICOM
folder. Reading runs in the window's jobs; the GUI thread only looks at a file's first
kilobyte to tell a raw file."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PySide6.QtCore import QSettings
from PySide6.QtWidgets import (
    QComboBox,
    QDialog,
    QDialogButtonBox,
    QDoubleSpinBox,
    QFileDialog,
    QFormLayout,
    QHBoxLayout,
    QLabel,
    QListWidget,
    QSpinBox,
    QVBoxLayout,
    QWidget,
)

#: sample types offered for raw files (NumPy names)
RAW_TYPES = ("uint8", "int8", "uint16", "int16", "uint32", "int32", "float32", "float64")
#: QSettings group of the raw layouts, one entry per absolute file path
RAW_SETTINGS = "raw-files"


def file_filter() -> str:
    """The Open dialog's filter: everything readable first, then each volume and point
    format of the registry with its endings, sessions, and all files."""
    from splineviz.io.registry import formats
    from splineviz.plugins import ensure_loaded

    ensure_loaded()
    lines, every = [], []
    for kind in ("volume", "points"):
        for fmt in formats(kind):
            if not fmt.extensions:
                continue
            globs = " ".join(f"*{e}" for e in fmt.extensions)
            every.extend(f"*{e}" for e in fmt.extensions)
            lines.append(f"{fmt.description or fmt.name} ({globs})")
    every.append("*.svs")
    head = f"All readable files ({' '.join(dict.fromkeys(every))})"
    return ";;".join([head, *lines, "splineviz sessions (*.svs)", "All files (*)"])


def open_file(window) -> None:
    """File > Open: a file (a DICOM file opens its series, a Zarr store's metadata file its
    folder, a raw file asks for its layout)."""
    path, _ = QFileDialog.getOpenFileName(window, "Open volume, point cloud or session", "",
                                          file_filter())
    if path:
        open_chosen(window, path)


def open_folder(window) -> None:
    """File > Open Folder: a DICOM series, a folder of numbered slices or a Zarr store."""
    path = QFileDialog.getExistingDirectory(window, "Open a DICOM series, a folder of slices "
                                            "or a Zarr store")
    if path:
        open_chosen(window, path)


def open_chosen(window, path, mode: str = "ask"):
    """Open what the user chose: a folder is first looked into (in a job) for several DICOM
    series to choose from; a raw file asks for its layout; the rest opens at once. Returns
    the job started, or None when nothing is read (yet)."""
    from splineviz.io.registry import find_format

    p = Path(path)
    if p.is_dir():
        # a process: pydicom parses headers in Python, holding the GIL for long stretches
        return window.jobs.run(f"Looking into {p.name}", _several_series, str(p),
                               on_done=lambda found: _folder_looked_into(window, p, found,
                                                                         mode), process=True)
    try:
        fmt = find_format(p, "volume").name
    except Exception:  # noqa: BLE001 - unknown or damaged: the reader's own message follows
        fmt = None
    if fmt == "raw":
        raw = ask_raw_layout(window, p)
        if raw is None:
            return None
        return window.guard(window.commands.open_path, str(p), mode=mode, raw=raw)
    return window.open_path(str(p), mode=mode)


def _several_series(folder: str):
    """(labels, first files) of the DICOM series of ``folder`` when it holds several, else
    None (a job: reading every file's header takes a while)."""
    from splineviz.io.dicom import list_series

    found = list_series(folder)
    if len(found) < 2:
        return None
    return [s.label() for s in found], [str(s.files[0]) for s in found]


def _folder_looked_into(window, folder: Path, found, mode):
    if found is None:
        return window.open_path(str(folder), mode=mode)
    labels, files = found
    dialog = SeriesDialog(window, folder.name, labels)
    if dialog.exec() != QDialog.DialogCode.Accepted:
        return None
    # a file of the chosen series opens that series
    return window.open_path(files[dialog.chosen()], mode=mode)


class SeriesDialog(QDialog):
    """Which DICOM series of a folder to open (one line per series)."""

    def __init__(self, parent, folder: str, labels):
        super().__init__(parent)
        self.setWindowTitle("Choose a DICOM series")
        layout = QVBoxLayout(self)
        layout.addWidget(QLabel(f"{folder} holds {len(labels)} DICOM series. Open which?"))
        self.list = QListWidget()
        self.list.addItems(list(labels))
        self.list.setCurrentRow(0)
        self.list.itemDoubleClicked.connect(lambda _: self.accept())
        self.list.setMinimumWidth(min(900, 40 + 7 * max(len(t) for t in labels)))
        layout.addWidget(self.list)
        buttons = QDialogButtonBox(QDialogButtonBox.StandardButton.Open
                                   | QDialogButtonBox.StandardButton.Cancel)
        buttons.accepted.connect(self.accept)
        buttons.rejected.connect(self.reject)
        layout.addWidget(buttons)

    def chosen(self) -> int:
        """Index of the chosen series."""
        return max(0, self.list.currentRow())


class RawDialog(QDialog):
    """A raw file's layout: samples per axis, sample type, byte order, spacing and header
    bytes; the dialog says whether the numbers match the file's size."""

    def __init__(self, parent, path: Path, layout: dict | None = None):
        super().__init__(parent)
        self.path = Path(path)
        self.size = self.path.stat().st_size
        self.setWindowTitle(f"Raw file {self.path.name}")
        layout = {**_guess_layout(self.size), **(layout or {})}
        form = QFormLayout(self)
        form.addRow(QLabel(f"{self.path.name} has no header ({self.size:,} bytes): give its "
                           "layout, x varying fastest."))
        self.dims = [self._spin(1, 1 << 20, n) for n in layout["dims"]]
        form.addRow("Samples x, y, z", _row(self.dims))
        self.dtype = QComboBox()
        self.dtype.addItems(RAW_TYPES)
        self.dtype.setCurrentText(layout["dtype"])
        form.addRow("Sample type", self.dtype)
        self.byteorder = QComboBox()
        self.byteorder.addItems(["little", "big"])
        self.byteorder.setCurrentText(layout["byteorder"])
        form.addRow("Byte order", self.byteorder)
        self.spacing = []
        for s in layout["spacing"]:
            box = QDoubleSpinBox()
            box.setDecimals(6)
            box.setRange(1e-6, 1e6)
            box.setValue(float(s))
            self.spacing.append(box)
        form.addRow("Spacing x, y, z", _row(self.spacing))
        self.offset = self._spin(0, 2**31 - 1, layout["offset"])
        self.offset.setToolTip("Bytes of header to skip before the samples")
        form.addRow("Header bytes", self.offset)
        self.check = QLabel()
        form.addRow(self.check)
        self.buttons = QDialogButtonBox(QDialogButtonBox.StandardButton.Open
                                        | QDialogButtonBox.StandardButton.Cancel)
        self.buttons.accepted.connect(self.accept)
        self.buttons.rejected.connect(self.reject)
        form.addRow(self.buttons)
        for w in (*self.dims, self.offset):
            w.valueChanged.connect(self._update)
        self.dtype.currentTextChanged.connect(self._update)
        self._update()

    @staticmethod
    def _spin(lo, hi, value) -> QSpinBox:
        s = QSpinBox()
        s.setRange(lo, hi)
        s.setValue(int(value))
        return s

    def layout_values(self) -> dict:
        """The layout entered: ``dims, dtype, byteorder, offset, spacing``."""
        return {"dims": [s.value() for s in self.dims], "dtype": self.dtype.currentText(),
                "byteorder": self.byteorder.currentText(), "offset": self.offset.value(),
                "spacing": [s.value() for s in self.spacing]}

    def _update(self) -> None:
        v = self.layout_values()
        need = int(np.prod(v["dims"], dtype=object)) * np.dtype(v["dtype"]).itemsize
        have = self.size - v["offset"]
        ok = need == have
        self.check.setText(f"{need:,} bytes of samples: matches the file" if ok else
                           f"{need:,} bytes of samples, but the file holds {have:,} after "
                           "the header")
        self.buttons.button(QDialogButtonBox.StandardButton.Open).setEnabled(ok)


def _row(widgets) -> QWidget:
    w = QWidget()
    h = QHBoxLayout(w)
    h.setContentsMargins(0, 0, 0, 0)
    for x in widgets:
        h.addWidget(x)
    return w


def _guess_layout(size: int) -> dict:
    """A first guess for a file never opened: a cube of bytes, else of 16-bit samples."""
    layout = {"dims": [1, 1, 1], "dtype": "uint8", "byteorder": "little", "offset": 0,
              "spacing": [1.0, 1.0, 1.0]}
    for dtype in ("uint8", "uint16", "float32"):
        n = size // np.dtype(dtype).itemsize
        side = round(n ** (1 / 3))
        if side**3 * np.dtype(dtype).itemsize == size:
            return {**layout, "dims": [side] * 3, "dtype": dtype}
    return layout


def remembered_layout(path) -> dict | None:
    """The layout last entered for ``path`` (QSettings), or None."""
    value = QSettings("splineviz", "splineviz").value(f"{RAW_SETTINGS}/{_key(path)}")
    if not isinstance(value, dict):
        return None
    try:
        return {"dims": [int(n) for n in value["dims"]], "dtype": str(value["dtype"]),
                "byteorder": str(value["byteorder"]), "offset": int(value["offset"]),
                "spacing": [float(s) for s in value["spacing"]]}
    except (KeyError, TypeError, ValueError):
        return None


def _key(path) -> str:
    # QSettings keys treat "/" as groups: the absolute path as one key
    return str(Path(path).absolute()).replace("/", "|")


def ask_raw_layout(window, path) -> dict | None:
    """Ask for a raw file's layout (prefilled with the one remembered for it) and remember
    the answer: the read options (``dims, dtype, byteorder, offset, spacing`` of
    :func:`~splineviz.io.volumes.read_volume`) for :meth:`Commands.open_path`'s ``raw``, or
    None if cancelled."""
    dialog = RawDialog(window, Path(path), remembered_layout(path))
    if dialog.exec() != QDialog.DialogCode.Accepted:
        return None
    values = dialog.layout_values()
    QSettings("splineviz", "splineviz").setValue(f"{RAW_SETTINGS}/{_key(path)}", values)
    return {k: (tuple(v) if isinstance(v, list) else v) for k, v in values.items()}
