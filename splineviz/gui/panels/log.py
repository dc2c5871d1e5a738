"""The log panel: warnings and errors of this session, newest last (ParaView's output
window). Python ``logging`` records of ``splineviz`` and ``py.warnings`` at WARNING and above
appear here, and so does every message the window shows the user."""

from __future__ import annotations

import logging
import time

from PySide6.QtCore import QObject, Signal
from PySide6.QtWidgets import QPlainTextEdit, QPushButton, QVBoxLayout, QWidget

#: lines kept in the panel
MAX_LINES = 2000


class _Relay(QObject):
    """Logging handlers may run in any thread; the signal carries the line to the GUI."""

    line = Signal(str)


class _Handler(logging.Handler):
    def __init__(self, relay: _Relay):
        super().__init__(logging.WARNING)
        self.relay = relay

    def emit(self, record):
        try:
            self.relay.line.emit(f"{record.levelname.lower()}: {record.getMessage()}")
        except RuntimeError:  # the panel is gone
            pass


class LogPanel(QWidget):
    """Read-only list of messages with a Clear button."""

    def __init__(self, parent=None):
        super().__init__(parent)
        self.text = QPlainTextEdit()
        self.text.setReadOnly(True)
        self.text.setMaximumBlockCount(MAX_LINES)
        self.text.setToolTip("Warnings and errors of this session")
        clear = QPushButton("Clear")
        clear.setToolTip("Empty the log")
        clear.clicked.connect(self.text.clear)
        lay = QVBoxLayout(self)
        lay.addWidget(self.text)
        lay.addWidget(clear)
        self._relay = _Relay()
        self._relay.line.connect(self.add)
        self._handler = _Handler(self._relay)
        logging.captureWarnings(True)
        for name in ("splineviz", "py.warnings"):
            logging.getLogger(name).addHandler(self._handler)

    def add(self, message: str) -> None:
        self.text.appendPlainText(f"{time.strftime('%H:%M:%S')}  {message}")

    def lines(self) -> list[str]:
        return self.text.toPlainText().splitlines()

    def close_log(self) -> None:
        for name in ("splineviz", "py.warnings"):
            logging.getLogger(name).removeHandler(self._handler)
        logging.captureWarnings(False)
