"""Driving a Qt widget like a user, and the meter of the GUI thread's longest stall (for
:mod:`splineviz.bench.gui` and the GUI tests): mouse drags and wheel turns delivered while the
event loop runs, and a main window opened and closed for a script.

Events are sent from a QTimer callback (one step per tick) while a local event loop runs, so
the widget receives them as it would from the window system: between two steps Qt processes
timers, paint and render requests, and a :class:`StallMeter` sees how long each step held
the GUI thread.
"""

from __future__ import annotations

import time

import numpy as np
from PySide6.QtCore import QElapsedTimer, QEvent, QEventLoop, QPoint, QPointF, Qt, QTimer
from PySide6.QtGui import QMouseEvent, QWheelEvent
from PySide6.QtWidgets import QApplication

LEFT = Qt.MouseButton.LeftButton
NO_BUTTON = Qt.MouseButton.NoButton
NO_MODIFIER = Qt.KeyboardModifier.NoModifier


class StallMeter:
    """Longest gap between ticks of a 10 ms QTimer while the block runs (context manager).

    ``with StallMeter() as m: ...`` then ``m.max_ms`` (float, milliseconds) is the longest
    time the GUI thread did not get back to its event loop; ``m.ticks`` counts the ticks. A
    responsive window stays near the timer interval; a synchronous 200 ms render shows as
    ~200 ms. Only time spent in the event loop (``exec``, ``processEvents``, qtbot waits)
    lets the timer tick, so drive the widget with :func:`drag` / :func:`wheel` / :func:`pump`.
    """

    def __init__(self, interval_ms: int = 10):
        self.interval_ms = int(interval_ms)
        self.max_ms = 0.0
        self.ticks = 0
        self._timer = None
        self._clock = QElapsedTimer()
        self._last = None

    def _tick(self) -> None:
        now = self._clock.nsecsElapsed() / 1e6
        if self._last is not None:
            self.max_ms = max(self.max_ms, now - self._last)
        self._last = now
        self.ticks += 1

    def __enter__(self) -> StallMeter:
        self._timer = QTimer()
        self._timer.setTimerType(Qt.TimerType.PreciseTimer)
        self._timer.setInterval(self.interval_ms)
        self._timer.timeout.connect(self._tick)
        self._clock.start()
        self._last = 0.0
        self._timer.start()
        return self

    def __exit__(self, *exc) -> None:
        self._tick()  # the gap up to the end of the block counts too
        self._timer.stop()
        self._timer.deleteLater()
        self._timer = None


def pump(seconds: float, until=None, step_s: float = 0.005) -> bool:
    """Process events for at most ``seconds``; stop early once ``until()`` is true.

    Returns whether ``until`` became true (True when ``until`` is None)."""
    app = QApplication.instance()
    end = time.perf_counter() + seconds
    while True:
        app.processEvents(QEventLoop.ProcessEventsFlag.AllEvents, 10)
        if until is not None and until():
            return True
        if time.perf_counter() >= end:
            return until is None
        time.sleep(step_s)


def run_steps(steps, interval_ms: int = 16) -> None:
    """Call each of ``steps`` (callables) from a timer, ``interval_ms`` apart, in an event loop."""
    steps = list(steps)
    loop = QEventLoop()
    timer = QTimer()
    timer.setInterval(int(interval_ms))
    state = {"i": 0, "error": None}

    def tick():
        if state["i"] >= len(steps):
            timer.stop()
            loop.quit()
            return
        try:
            steps[state["i"]]()
        except BaseException as exc:  # re-raised outside the event loop
            state["error"] = exc
            state["i"] = len(steps)
        state["i"] += 1

    timer.timeout.connect(tick)
    timer.start()
    QTimer.singleShot(60_000, loop.quit)  # never hang a test
    loop.exec()
    timer.stop()
    if state["error"] is not None:
        raise state["error"]


def mouse(widget, kind, pos, button, buttons, modifiers=NO_MODIFIER) -> None:
    """Send one mouse event of ``kind`` (``QEvent.Type``) at widget pixel ``pos``."""
    local = QPointF(float(pos[0]), float(pos[1]))
    event = QMouseEvent(kind, local, widget.mapToGlobal(local), button, buttons, modifiers)
    QApplication.sendEvent(widget, event)


def drag_steps(widget, points, button=LEFT, modifiers=NO_MODIFIER) -> list:
    """Steps (for :func:`run_steps`) of a press at ``points[0]``, moves, release at the last."""
    points = [tuple(map(float, p)) for p in points]
    steps = [lambda: mouse(widget, QEvent.Type.MouseButtonPress, points[0], button, button,
                           modifiers)]
    for p in points[1:]:
        steps.append(lambda p=p: mouse(widget, QEvent.Type.MouseMove, p, NO_BUTTON, button,
                                       modifiers))
    steps.append(lambda: mouse(widget, QEvent.Type.MouseButtonRelease, points[-1], button,
                               NO_BUTTON, modifiers))
    return steps


def line(start, end, n: int) -> list:
    """``n + 1`` points from ``start`` to ``end`` (pixels)."""
    s, e = np.asarray(start, float), np.asarray(end, float)
    return [tuple(s + (e - s) * t) for t in np.linspace(0.0, 1.0, n + 1)]


def drag(widget, start, end, n: int = 12, button=LEFT, interval_ms: int = 16) -> None:
    """Press at ``start``, move in ``n`` steps to ``end``, release, as a user's drag."""
    run_steps(drag_steps(widget, line(start, end, n), button), interval_ms)


def wheel_step(widget, pos, clicks: int = 1) -> None:
    """Turn the wheel by ``clicks`` notches (positive: away from the user) at ``pos``."""
    local = QPointF(float(pos[0]), float(pos[1]))
    event = QWheelEvent(local, widget.mapToGlobal(local), QPoint(0, 0),
                        QPoint(0, 120 * int(clicks)), NO_BUTTON, NO_MODIFIER,
                        Qt.ScrollPhase.NoScrollPhase, False)
    QApplication.sendEvent(widget, event)


def wheel(widget, pos, clicks: int = 1, interval_ms: int = 30) -> None:
    """``abs(clicks)`` single notches, ``interval_ms`` apart, with the event loop running."""
    sign = 1 if clicks > 0 else -1
    run_steps([lambda: wheel_step(widget, pos, sign)] * abs(int(clicks)), interval_ms)


def open_window(settings_dir, **kwargs):
    """A shown main window whose recent files go to ``settings_dir`` (not the user's)."""
    from PySide6.QtCore import QSettings

    from splineviz.gui.main_window import MainWindow

    QSettings.setPath(QSettings.Format.NativeFormat, QSettings.Scope.UserScope,
                      str(settings_dir))
    w = MainWindow(**kwargs)
    w.show()
    pump(0.3)
    return w


def close_window(w) -> None:
    """Wait for ``w``'s jobs, close it and let Qt process the close."""
    w.wait_idle()
    w.close()
    pump(0.1)
