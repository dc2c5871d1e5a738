"""Driving a Qt widget like a user, in tests: mouse drags and wheel turns delivered while the
event loop runs, a meter of the longest GUI-thread stall, and image measures that tell an
exact ray-cast frame from a reduced-resolution preview.

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


def _mouse(widget, kind, pos, button, buttons, modifiers=NO_MODIFIER) -> None:
    local = QPointF(float(pos[0]), float(pos[1]))
    event = QMouseEvent(kind, local, widget.mapToGlobal(local), button, buttons, modifiers)
    QApplication.sendEvent(widget, event)


def drag_steps(widget, points, button=LEFT, modifiers=NO_MODIFIER) -> list:
    """Steps (for :func:`run_steps`) of a press at ``points[0]``, moves, release at the last."""
    points = [tuple(map(float, p)) for p in points]
    steps = [lambda: _mouse(widget, QEvent.Type.MouseButtonPress, points[0], button, button,
                            modifiers)]
    for p in points[1:]:
        steps.append(lambda p=p: _mouse(widget, QEvent.Type.MouseMove, p, NO_BUTTON, button,
                                        modifiers))
    steps.append(lambda: _mouse(widget, QEvent.Type.MouseButtonRelease, points[-1], button,
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


# -- images ------------------------------------------------------------------------------

def surface_mask(img: np.ndarray, background) -> np.ndarray:
    """Pixels of ``img`` (H, W, 3 uint8) that differ from the background colour."""
    bg = np.round(np.asarray(background, float)[:3] * 255.0)
    return np.abs(img[..., :3].astype(int) - bg).max(axis=2) > 2


def blockiness(img: np.ndarray, mask: np.ndarray) -> float:
    """Share of masked pixels equal to their left neighbour (ENVIRONMENT.md): ~0.8 for a
    20 px preview, about 1 - 1/b for b-pixel blocks, < 0.15 for an exact frame."""
    a = img[..., :3].astype(int)
    same = (a[:, 1:] == a[:, :-1]).all(axis=2)
    m = mask[:, 1:] & mask[:, :-1]
    return float(same[m].mean()) if m.any() else 0.0


def agreement(a: np.ndarray, b: np.ndarray, tol: int = 2, shift: int = 0) -> float:
    """Share of pixels of ``a`` whose channels all differ by at most ``tol`` (of 255) from
    ``b``'s pixel at the same place or, with ``shift`` > 0, from one of ``b``'s pixels up
    to ``shift`` pixels away (absorbs one-pixel differences in how lines are rasterised)."""
    if a.shape[:2] != b.shape[:2]:
        raise ValueError(f"image sizes differ: {a.shape} vs {b.shape}")
    a = a[..., :3].astype(int)
    b = b[..., :3].astype(int)
    h, w = a.shape[:2]
    s = int(shift)
    padded = np.pad(b, ((s, s), (s, s), (0, 0)), mode="edge")
    best = None
    for dy in range(2 * s + 1):
        for dx in range(2 * s + 1):
            d = np.abs(a - padded[dy:dy + h, dx:dx + w]).max(axis=2)
            best = d if best is None else np.minimum(best, d)
    return float((best <= tol).mean())


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
    w.wait_idle()
    w.close()
    pump(0.1)


#: set in the fresh process :func:`in_fresh_process` starts
FRESH = "SPLINEVIZ_TEST_FRESH_PROCESS"


def in_fresh_process(nodeid: str, timeout_s: float = 600.0) -> None:
    """Run the test ``nodeid`` in a new pytest process and assert that it passed.

    GUI-stall and latency checks measure this app's GUI thread; in the process of the whole
    suite they also measured what earlier tests left behind (their threads, caches and
    libraries' state: 100-130 ms against 50-90 ms alone), so they run on their own.
    """
    import os
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    done = subprocess.run([sys.executable, "-m", "pytest", "-q", "-s", "-p", "no:randomly",
                           nodeid], cwd=root, env={**os.environ, FRESH: "1"},
                          capture_output=True, text=True, timeout=timeout_s)
    print(done.stdout[-3000:])
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-2000:]
