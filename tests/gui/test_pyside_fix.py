"""PySide6 6.12 on Python 3.11 takes a reference from None at every void method call; the
process aborted ("deallocating None") after a few hundred isovalue changes in the soak test.
Importing :mod:`splineviz.gui` guards against it (:mod:`splineviz.gui._pyside_fix`)."""

import os
import subprocess
import sys

import pytest

pytest.importorskip("PySide6")

PROGRAM = """
import sys
from PySide6.QtCore import QPointF
from PySide6.QtGui import QPainterPath
calls = 2 * sys.getrefcount(None) + 10_000  # more than None has references
import splineviz.gui  # noqa: E402
path, point = QPainterPath(), QPointF()
for _ in range(calls // 2):
    path.lineTo(1.0, 2.0)
    point.setX(0.0)
path.clear()
print(calls)
"""


def test_many_void_calls_do_not_run_none_out_of_references():
    env = {**os.environ, "QT_QPA_PLATFORM": "offscreen"}
    done = subprocess.run([sys.executable, "-c", PROGRAM], env=env, capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]
    assert int(done.stdout.split()[-1]) > 10_000
