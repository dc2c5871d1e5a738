"""A workaround for a reference-counting bug of PySide6 6.12 on Python 3.11.

Found by the GUI soak test: shiboken 6.12 returns ``None`` from void methods
(``QPainterPath.lineTo``, ``QWidget.update``, ``QTimer.start`` ...) without a new reference,
so every such call takes one reference away from ``None``. Python 3.12 and later do not
count ``None``'s references (PEP 683, immortal objects); Python 3.11 does, and aborts the
process with "Fatal Python error: none_dealloc: deallocating None" once they run out: about
60,000 references after start-up, a few hundred isovalue changes of the window (the
histogram's repaint alone makes ~140 void calls).

:func:`guard_none_refcount` detects the leak (a few void calls, and the count of ``None``'s
references before and after) and, where it is present, gives ``None`` the practically
infinite reference count that Python 3.12 gives it. Nothing changes where the bug is
absent (a fixed PySide6, Python >= 3.12).
"""

from __future__ import annotations

import ctypes
import sys

#: references added to None where the leak is found: 2^60 void calls before it could matter
RESERVE = 2**60
#: void calls made to detect the leak
PROBES = 16


def leaks_none() -> bool:
    """Whether a PySide6 void method call takes a reference from ``None``."""
    from PySide6.QtCore import QPointF

    p = QPointF()
    before = sys.getrefcount(None)
    for _ in range(PROBES):
        p.setX(0.0)
    return before - sys.getrefcount(None) >= PROBES


def guard_none_refcount() -> bool:
    """Make ``None`` immortal where PySide6 leaks its references (see the module
    docstring); returns whether it did."""
    if sys.version_info >= (3, 12) or not leaks_none():
        return False
    # ob_refcnt is the first field of an object in CPython builds without Py_TRACE_REFS;
    # checked against sys.getrefcount (which counts its own argument) before writing
    refcnt = ctypes.c_ssize_t.from_address(id(None))
    if abs(refcnt.value - (sys.getrefcount(None) - 1)) > PROBES:
        return False
    refcnt.value += RESERVE
    return True
