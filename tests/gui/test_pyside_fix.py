"""PySide6 6.12 on Python 3.11 takes a reference from None at every void method call and
from True at every signal emission to a Python slot; the soak test's process aborted
("deallocating None", then "deallocating True or False"). Importing :mod:`splineviz.gui`
guards against it (:mod:`splineviz.gui._pyside_fix`)."""

import os
import subprocess
import sys

import pytest

pytest.importorskip("PySide6")

PROGRAM = """
import sys
from PySide6.QtCore import QObject, QPointF, Signal
from PySide6.QtGui import QPainterPath

class Probe(QObject):
    fired = Signal(bool)

# more calls than None and True have references
calls = 2 * max(sys.getrefcount(None), sys.getrefcount(True)) + 10_000
import splineviz.gui  # noqa: E402
path, point, probe = QPainterPath(), QPointF(), Probe()
probe.fired.connect(lambda value: None)
for _ in range(calls // 2):
    path.lineTo(1.0, 2.0)
    point.setX(0.0)
    probe.fired.emit(True)
path.clear()
print(calls)
"""


def test_many_calls_and_signals_do_not_run_none_or_true_out_of_references():
    env = {**os.environ, "QT_QPA_PLATFORM": "offscreen"}
    done = subprocess.run([sys.executable, "-c", PROGRAM], env=env, capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]
    assert int(done.stdout.split()[-1]) > 10_000
