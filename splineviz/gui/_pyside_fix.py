"""A workaround for reference-counting bugs of PySide6 6.12 on Python 3.11.

Found by the GUI soak test. shiboken 6.12 returns ``None`` from void methods
(``QPainterPath.lineTo``, ``QWidget.update``, ``QTimer.start`` ...) without a new reference,
and every emission of a signal to a Python slot takes a reference from ``True``. Python 3.12
and later do not count the references of these singletons (PEP 683, immortal objects);
Python 3.11 does, and aborts the process ("Fatal Python error: none_dealloc: deallocating
None", "bool_dealloc: deallocating True or False") once they run out: ``None`` has about
60,000 references after start-up, a few hundred isovalue changes of the window (the
histogram's repaint alone makes ~140 void calls); ``True`` ran out at the end of the
1,000-change soak.

:func:`guard_singleton_refcounts` detects each leak (a few calls, and the singleton's
reference count before and after) and gives a leaking singleton the practically infinite
reference count that Python 3.12 gives it. Nothing changes where the bugs are absent (a
fixed PySide6, Python >= 3.12).
"""

from __future__ import annotations

import ctypes
import sys

#: references added to a leaking singleton: 2^60 calls before it could matter
RESERVE = 2**60
#: calls made to detect a leak
PROBES = 16


def _void_call():
    from PySide6.QtCore import QPointF

    point = QPointF()
    return lambda: point.setX(0.0)


def _signal_emission():
    from PySide6.QtCore import QObject, Signal

    class _Probe(QObject):
        fired = Signal(int)

    probe = _Probe()
    probe.fired.connect(lambda _value: None)
    return lambda: probe.fired.emit(1)


def leaking() -> list:
    """The singletons (None, True) that PySide6 calls take references from."""
    found = []
    for obj, make in ((None, _void_call), (True, _signal_emission)):
        call = make()
        before = sys.getrefcount(obj)
        for _ in range(PROBES):
            call()
        if before - sys.getrefcount(obj) >= PROBES:
            found.append(obj)
    return found


def _immortalize(obj) -> bool:
    # ob_refcnt is the first field of an object in CPython builds without Py_TRACE_REFS;
    # checked against sys.getrefcount (which counts its own argument) before writing
    refcnt = ctypes.c_ssize_t.from_address(id(obj))
    if abs(refcnt.value - (sys.getrefcount(obj) - 1)) > PROBES:
        return False
    refcnt.value += RESERVE
    return True


def guard_singleton_refcounts() -> list:
    """Make the singletons PySide6 leaks references of immortal (see the module
    docstring); returns those it changed (``False`` goes with ``True``)."""
    if sys.version_info >= (3, 12):
        return []
    found = leaking()
    if True in found:
        found.append(False)  # the same conversions hand out either
    return [obj for obj in found if _immortalize(obj)]
