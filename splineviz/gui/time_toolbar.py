"""The time toolbar: play the steps of time-varying volumes (ParaView's VCR controls).

First / previous / play-pause / next / last, loop, speed (steps per second), a slider over
the scene's time steps and the step and time in the data's unit. Space plays and pauses,
the arrow keys step. The toolbar shows while the scene holds a time-varying volume; a volume
opened from a 4-D file becomes one (its steps are found by a job, not the GUI thread).

The GUI thread never reads a step: a step not yet read is read by a job (or by the series'
read-ahead thread while playing, which also makes the step's range and histogram there) and
shown when it arrives. A new step is ray cast in the view's worker like any change of data:
first a reduced-resolution preview with the cheap caster, then the exact frame. While
playing, the player moves to the next step once it is read and the view shows a frame of
the current one (the preview), which gives up the exact frame under way; so every step is
seen, steps only ever go forward (until a loop starts over), and on pause the exact frame of
the step shown follows. The rate is what reading and previews allow, at most the chosen
speed.
"""

from __future__ import annotations

from PySide6.QtCore import Qt, QTimer, Signal
from PySide6.QtGui import QKeySequence, QShortcut
from PySide6.QtWidgets import QCheckBox, QDoubleSpinBox, QLabel, QSlider, QStyle, QToolBar

from splineviz.io.time_series import format_time
from splineviz.model.nodes import VolumeNode

#: suffixes of the volume files that may hold a time axis (others are read as 3-D only)
TIME_SUFFIXES = (".nii", ".nii.gz", ".mgz", ".mgh", ".mnc", ".nrrd", ".nhdr", ".npy",
                 ".hdr", ".img", ".par", ".head", ".brik")
#: steps read ahead of the one shown while playing
READ_AHEAD = 3


def _may_vary(path: str) -> bool:
    low = path.lower()
    return any(low.endswith(s) for s in TIME_SUFFIXES)


def _probe_series(path: str, read_options: dict, step: int):
    """Job: the time series of a volume file when it has more than one step along an axis
    that is not a channel axis, with ``step`` read; else None."""
    from splineviz.io.time_series import open_time_series

    series = open_time_series(path, **read_options)
    if len(series) < 2 or series.axis == "channel":
        return None
    series.step(min(step, len(series) - 1))
    return series


class TimeToolbar(QToolBar):
    """The time toolbar of a main window (see module notes).

    Attributes
    ----------
    shown_steps : list of int
        Every step the scene moved to, in order (the tests check that playing goes
        forward only).

    Signals
    -------
    playing(bool)
        Playback started or stopped.
    """

    playing = Signal(bool)

    def __init__(self, window):
        super().__init__("Time", window)
        self.setObjectName("Time")
        self.window = window
        self.scene = window.scene
        self.shown_steps: list[int] = []
        self._target: int | None = None
        self._job = None
        self._timer = QTimer(self)
        self._timer.timeout.connect(self._tick)
        icon = self.style().standardIcon
        px = QStyle.StandardPixmap
        self._icons = {True: icon(px.SP_MediaPause), False: icon(px.SP_MediaPlay)}
        self.a_first = self.addAction(icon(px.SP_MediaSkipBackward), "First",
                                      lambda: self.show_step(0))
        self.a_prev = self.addAction(icon(px.SP_MediaSeekBackward), "Previous",
                                     lambda: self.step_by(-1))
        self.a_play = self.addAction(self._icons[False], "Play", self.toggle)
        self.a_play.setCheckable(True)
        self.a_next = self.addAction(icon(px.SP_MediaSeekForward), "Next",
                                     lambda: self.step_by(1))
        self.a_last = self.addAction(icon(px.SP_MediaSkipForward), "Last",
                                     lambda: self.show_step(-1))
        for action, tip in ((self.a_first, "First step"), (self.a_prev, "Previous step (Left)"),
                            (self.a_play, "Play / pause (Space)"),
                            (self.a_next, "Next step (Right)"), (self.a_last, "Last step")):
            action.setToolTip(tip)
        self.loop = QCheckBox("Loop")
        self.loop.setToolTip("Start over after the last step")
        self.addWidget(self.loop)
        self.speed = QDoubleSpinBox()
        self.speed.setRange(0.1, 120.0)
        self.speed.setDecimals(1)
        self.speed.setSuffix(" steps/s")
        self.speed.setToolTip("Most steps per second while playing")
        self.speed.valueChanged.connect(self._speed_changed)
        self.addWidget(self.speed)
        self.slider = QSlider(Qt.Orientation.Horizontal)
        self.slider.setMinimumWidth(160)
        self.slider.setMaximumWidth(320)
        self.slider.setToolTip("Time step")
        self.slider.valueChanged.connect(self._slider_moved)
        self.addWidget(self.slider)
        self.label = QLabel()
        self.addWidget(self.label)
        self._shortcuts = []
        for key, slot in ((Qt.Key.Key_Space, self.toggle), (Qt.Key.Key_Left,
                                                            lambda: self.step_by(-1)),
                          (Qt.Key.Key_Right, lambda: self.step_by(1))):
            sc = QShortcut(QKeySequence(key), window)
            sc.setContext(Qt.ShortcutContext.WindowShortcut)
            sc.activated.connect(slot)
            self._shortcuts.append(sc)
        self.scene.inserted.connect(self._inserted)
        self.scene.removed.connect(lambda _node: self._refresh())
        self.scene.time_changed.connect(lambda _t: self._refresh())
        self._refresh()

    # -- state -----------------------------------------------------------------------------

    @property
    def is_playing(self) -> bool:
        return self._timer.isActive()

    def _refresh(self) -> None:
        """Show the toolbar while something varies; the slider and label follow the scene."""
        steps = self.scene.time_steps()
        varying = bool(steps) and len(steps) > 1
        self.setVisible(varying)
        for sc in self._shortcuts:
            sc.setEnabled(varying)
        if not varying:
            self.pause()
            return
        k = self.scene.step_index()
        self.slider.blockSignals(True)
        self.slider.setRange(0, len(steps) - 1)
        self.slider.setValue(k)
        self.slider.blockSignals(False)
        self.speed.blockSignals(True)
        self.speed.setValue(self.scene.play_rate)
        self.speed.blockSignals(False)
        unit = self.scene.time_varying[0].time_unit
        self.label.setText(f" step {k + 1}/{len(steps)}  t = {format_time(steps[k], unit)} ")

    def _inserted(self, node) -> None:
        if isinstance(node, VolumeNode) and node.series is None and node.path \
                and _may_vary(node.path):
            self.window.jobs.run("reading time steps", _probe_series, node.path,
                                 dict(node.read_options), node.time_index,
                                 on_done=lambda s: self._attach(node, s))
        self._refresh()

    def _attach(self, node: VolumeNode, series) -> None:
        if series is None or node.id not in self.scene or node.series is not None:
            return
        node.update(series=series, time_series=True)
        self._refresh()

    # -- stepping --------------------------------------------------------------------------

    def _ready(self, index: int) -> bool:
        """Whether every volume's step at time step ``index`` is read (starting the reads
        of those that are not)."""
        t = self.scene.time_steps()[index]
        ready = True
        for node in self.scene.time_varying:
            k = node.series.index_at_or_before(t - node.time_offset)
            if not node.series.cached(k):
                node.series.read_ahead(max(k - 1, 0), count=1)
                ready = False
        return ready

    def show_step(self, index: int) -> None:
        """Move the scene to time step ``index`` (negative from the end): at once when its
        data are read, else once a job has read them (the last asked for wins)."""
        steps = self.scene.time_steps()
        if not steps:
            return
        index = index % len(steps)
        if self._ready(index):
            self._target = None
            self._go(index)
            return
        self._target = index
        if self._job is None:
            self._job = self.window.jobs.run("reading time step", self._read, index,
                                             on_done=self._read_done,
                                             on_error=self._read_failed)

    def _read(self, index: int) -> int:
        t = self.scene.time_steps()[index]
        for node in self.scene.time_varying:
            node.series.step(node.series.index_at_or_before(t - node.time_offset))
        return index

    def _read_done(self, index: int) -> None:
        self._job = None
        target, self._target = self._target, None
        if target is not None:
            self.show_step(target)

    def _read_failed(self, exc) -> None:
        from splineviz.gui.jobs import error_message

        self._job = None
        self._target = None
        self.pause()
        self.window.show_error(f"reading a time step failed: {error_message(exc)}")

    def _go(self, index: int) -> None:
        self.window.guard(self.scene.set_step, index)
        self.shown_steps.append(index)
        if self.is_playing:
            for node in self.scene.time_varying:
                node.series.read_ahead(node.time_index, READ_AHEAD, loop=self.loop.isChecked())

    def step_by(self, delta: int) -> None:
        """The next (``delta`` 1) or previous (-1) step; pauses playback."""
        self.pause()
        steps = self.scene.time_steps()
        if steps:
            self.show_step(min(max(self.scene.step_index() + delta, 0), len(steps) - 1))

    def _slider_moved(self, value: int) -> None:
        self.pause()
        self.show_step(value)

    def _speed_changed(self, value: float) -> None:
        self.scene.play_rate = value
        if self.is_playing:
            self._timer.setInterval(max(1, int(1000.0 / value)))

    # -- playing ---------------------------------------------------------------------------

    def toggle(self) -> None:
        """Space: play or pause."""
        if self.is_playing:
            self.pause()
        else:
            self.play()

    def play(self) -> None:
        """Play from the current step (from the first when at the last)."""
        steps = self.scene.time_steps()
        if len(steps) < 2 or self.is_playing:
            return
        if self.scene.step_index() == len(steps) - 1:
            self.show_step(0)
        for node in self.scene.time_varying:
            node.series.read_ahead(node.time_index, READ_AHEAD, loop=self.loop.isChecked())
        self._timer.start(max(1, int(1000.0 / self.scene.play_rate)))
        self.a_play.setChecked(True)
        self.a_play.setIcon(self._icons[True])
        self.playing.emit(True)

    def pause(self) -> None:
        """Stop playing; the step shown stays (its exact frame follows, as after an
        orbit)."""
        if not self._timer.isActive():
            return
        self._timer.stop()
        self.a_play.setChecked(False)
        self.a_play.setIcon(self._icons[False])
        self.playing.emit(False)

    def _frame_shown(self) -> bool:
        """Whether every view shows a frame of the current step of each visible layer."""
        for view in self.window.linked_views.views:
            ss = view.spline_scene
            if ss is None:
                continue
            for layer in ss.layers:
                rf = ss.shown_frame(layer)
                if layer.visible and not ss.drawn_by_cells(layer) and (
                        rf is None or rf.state != layer.state):
                    return False
        return True

    def _tick(self) -> None:
        steps = self.scene.time_steps()
        if len(steps) < 2:
            self.pause()
            return
        nxt = self.scene.step_index() + 1
        if nxt == len(steps):
            if not self.loop.isChecked():
                self.pause()
                return
            nxt = 0
        if self._target is None and self._ready(nxt) and self._frame_shown():
            self._go(nxt)

    def close(self) -> bool:
        self.pause()
        return super().close()
