"""The Animation dock (ParaView's Animation View, lite) and File > Export animation.

:class:`AnimationPanel` edits the scene's :class:`~splineviz.model.animation.Animation`
(``scene.animation``, saved with the session): presets (orbit, isovalue sweep, clip sweep,
and time playback while the scene holds a time-varying volume; "combine" adds a preset's
tracks to the animation there is), the tracks with their keyframes,
"add keyframe" of the camera or of the current isosurface's isovalue at the slider's frame,
a frame slider that sets the scene to that frame (the view previews while it is dragged and
refines after), and Play (previews only while playing, the exact frame when it stops).
The GUI thread never reads a time step: a frame whose steps are not read yet is shown once
a job (or, while playing, the series' read-ahead) has read them, as the time toolbar does.

:func:`export_animation` asks for size, frame rate, format and quality
(:class:`ExportAnimationDialog`) and a file, then :func:`start_export` runs
:func:`splineviz.render.movie.export_session` in a job process (:mod:`splineviz.gui.jobs`):
the window stays responsive, the status bar shows "frame i of N, s left", and a cancel
(Esc, Tools > Cancel) stops the process at once and removes its staging folder, so no
partial file is left.
"""

from __future__ import annotations

import shutil
from pathlib import Path

from PySide6.QtCore import Qt, QTimer
from PySide6.QtWidgets import (
    QCheckBox,
    QComboBox,
    QDialog,
    QDockWidget,
    QDoubleSpinBox,
    QFileDialog,
    QFormLayout,
    QHBoxLayout,
    QLabel,
    QListWidget,
    QPushButton,
    QSlider,
    QSpinBox,
    QStackedWidget,
    QVBoxLayout,
    QWidget,
)

from splineviz.gui.dialogs import ok_cancel, size_boxes
from splineviz.model.animation import (
    SWEEP_AXES,
    TIME_TARGET,
    Animation,
    clip_sweep,
    isovalue_sweep,
    orbit,
    time_playback,
)
from splineviz.model.nodes import IsosurfaceNode

#: (label, preset key) of the preset list (the last offered only while the scene holds a
#: time-varying volume)
PRESET_CHOICES = (("Orbit", "orbit"), ("Isovalue sweep", "iso"), ("Clip sweep", "clip"),
                  ("Time playback", "time"))
#: steps read ahead of the frame shown while playing
READ_AHEAD = 3


class AnimationPanel(QWidget):
    """Presets, tracks, keyframes, frame slider and Play for ``window.scene`` (see module
    docstring)."""

    def __init__(self, window):
        super().__init__()
        self.window = window
        self.scene = window.scene
        self._play_timer = QTimer(self)
        self._play_timer.timeout.connect(self._step)
        self._playing = False
        layout = QVBoxLayout(self)

        form = QFormLayout()
        self.preset = QComboBox()
        for label, key in PRESET_CHOICES[:-1]:
            self.preset.addItem(label, key)
        self.preset.setToolTip("What the preset animates")
        form.addRow("Preset", self.preset)
        self.options = QStackedWidget()
        self.degrees = _spin(-3600.0, 3600.0, 360.0, " deg", "Degrees the camera turns "
                             "about its view up")
        self.iso_from = _spin(-1e15, 1e15, 0.0, "", "Isovalue on the first frame")
        self.iso_to = _spin(-1e15, 1e15, 1.0, "", "Isovalue on the last frame")
        self.axis = QComboBox()
        self.axis.addItems(list(SWEEP_AXES))
        self.axis.setToolTip("Direction the clip plane moves through the volume")
        self.step_from = QSpinBox()
        self.step_from.setToolTip("The first time step played")
        self.step_to = QSpinBox()
        self.step_to.setToolTip("The last time step played")
        self.per_step = QSpinBox()
        self.per_step.setRange(0, 1000)
        self.per_step.setValue(1)
        self.per_step.setSpecialValueText("match play rate")
        self.per_step.setToolTip("Frames each step lasts (0: as many as the frame rate over "
                                 "the time toolbar's speed); the steps set the frame count")
        for rows in ((("Turn", self.degrees),),
                     (("From", self.iso_from), ("To", self.iso_to)),
                     (("Axis", self.axis),),
                     (("From step", self.step_from), ("To step", self.step_to),
                      ("Frames a step", self.per_step))):
            page = QWidget()
            f = QFormLayout(page)
            f.setContentsMargins(0, 0, 0, 0)
            for label, w in rows:
                f.addRow(label, w)
            self.options.addWidget(page)
        self.preset.currentIndexChanged.connect(self._preset_changed)
        form.addRow(self.options)
        self.frames = QSpinBox()
        self.frames.setRange(1, 90_000)
        self.frames.setValue(120)
        self.frames.setToolTip("Frames of the animation")
        self.fps = _spin(1.0, 240.0, 30.0, " fps", "Frames per second")
        form.addRow("Frames", self.frames)
        form.addRow("Rate", self.fps)
        self.combine = QCheckBox("Combine with the current animation")
        self.combine.setToolTip("Add the preset's tracks to the animation there is")
        form.addRow(self.combine)
        layout.addLayout(form)
        make = QPushButton("Make animation")
        make.setToolTip("Build the animation of the preset")
        make.clicked.connect(self.make_preset)
        layout.addWidget(make)

        layout.addWidget(QLabel("Tracks"))
        self.tracks = QListWidget()
        self.tracks.setToolTip("What the animation animates, with the frames of its keys")
        layout.addWidget(self.tracks)
        keys = QHBoxLayout()
        self.key_camera = QPushButton("Key camera")
        self.key_camera.setToolTip("A keyframe of the current view's camera at this frame")
        self.key_camera.clicked.connect(lambda: self.add_key("camera"))
        self.key_iso = QPushButton("Key isovalue")
        self.key_iso.setToolTip("A keyframe of the current isosurface's isovalue at this frame")
        self.key_iso.clicked.connect(lambda: self.add_key("isovalue"))
        clear = QPushButton("Clear")
        clear.setToolTip("Remove the animation")
        clear.clicked.connect(self.clear)
        for b in (self.key_camera, self.key_iso, clear):
            keys.addWidget(b)
        layout.addLayout(keys)

        row = QHBoxLayout()
        self.play_button = QPushButton("Play")
        self.play_button.setToolTip("Play the animation in the view (previews while playing)")
        self.play_button.setCheckable(True)
        self.play_button.toggled.connect(self.play)
        self.slider = QSlider(Qt.Orientation.Horizontal)
        self.slider.setToolTip("The frame shown: drag to scrub through the animation")
        self.slider.valueChanged.connect(self._slider_moved)
        self.slider.sliderPressed.connect(lambda: self._view().begin_interaction())
        self.slider.sliderReleased.connect(lambda: self._view().end_interaction())
        self.frame_label = QLabel()
        row.addWidget(self.play_button)
        row.addWidget(self.slider, 1)
        row.addWidget(self.frame_label)
        layout.addLayout(row)
        layout.addStretch(1)
        self._shown = None
        self._read_job = None
        self._pending: int | None = None
        # a session loaded into the scene brings its own animation
        self.scene.changed.connect(self._scene_changed)
        self.refresh()
        self._offer_time()

    def _scene_changed(self) -> None:
        if self.scene.animation is not self._shown:
            self.refresh()
        self._offer_time()

    def _offer_time(self) -> None:
        """The time-playback preset, listed while the scene holds a time-varying volume
        (its step range follows the scene's steps)."""
        n = len(self.scene.time_steps())
        index = self.preset.findData("time")
        if n and index < 0:
            self.preset.addItem(*PRESET_CHOICES[-1])
        elif not n and index >= 0:
            self.preset.removeItem(index)
        if n and self.step_to.maximum() != n - 1:
            for box in (self.step_from, self.step_to):
                box.setRange(0, n - 1)
            self.step_to.setValue(n - 1)

    # -- state ---------------------------------------------------------------------------

    def _view(self):
        return self.window.view

    @property
    def animation(self) -> Animation | None:
        return self.scene.animation

    def set_animation(self, animation: Animation | None) -> None:
        """Make ``animation`` the scene's (an edit: the session has unsaved changes)."""
        self.scene.animation = animation
        self.scene.modified = True
        self.scene.changed.emit()
        self.refresh()

    def refresh(self) -> None:
        """Show the scene's animation: its tracks and the slider's range."""
        anim = self._shown = self.animation
        self.tracks.clear()
        if anim is not None:
            for t in anim.tracks:
                frames = ", ".join(str(k.frame) for k in t.keys[:12])
                more = " ..." if len(t.keys) > 12 else ""
                self.tracks.addItem(f"{t.target} {t.property} ({t.interpolation}): "
                                    f"keys at {frames}{more}")
        self.slider.blockSignals(True)
        self.slider.setRange(0, (anim.frames - 1) if anim is not None else 0)
        self.slider.blockSignals(False)
        self.slider.setEnabled(anim is not None)
        self.play_button.setEnabled(anim is not None)
        self._label()

    def _label(self) -> None:
        anim = self.animation
        n = anim.frames if anim is not None else 0
        self.frame_label.setText(f"{self.slider.value()} / {max(n - 1, 0)}")

    def _preset_changed(self, index: int) -> None:
        self.options.setCurrentIndex(index)
        if self.preset.currentData() == "iso":
            iso = self._isosurface()
            if iso is not None:
                lo, hi = self.scene.volume_of(iso).active.finite_range
                self.iso_from.setValue(lo + 0.25 * (hi - lo))
                self.iso_to.setValue(lo + 0.75 * (hi - lo))

    def _isosurface(self) -> IsosurfaceNode | None:
        sel = self.scene.selected
        if isinstance(sel, IsosurfaceNode):
            return sel
        return self.scene.isosurfaces[0] if self.scene.isosurfaces else None

    # -- editing -------------------------------------------------------------------------

    def make_preset(self) -> None:
        """Build the chosen preset (combined with the animation there is, if asked)."""
        self.window.guard(self._make_preset)

    def _make_preset(self) -> None:
        key, n, fps = self.preset.currentData(), self.frames.value(), self.fps.value()
        if key == "orbit":
            anim = orbit(self.scene, self.degrees.value(), frames=n, fps=fps)
        elif key == "iso":
            anim = isovalue_sweep(self.scene, self.iso_from.value(), self.iso_to.value(),
                                  frames=n, isosurface=self._isosurface(), fps=fps)
        elif key == "time":
            anim = time_playback(self.scene, self.step_from.value(), self.step_to.value(),
                                 frames_per_step=self.per_step.value() or None, fps=fps)
            self.frames.setValue(anim.frames)
        else:
            # the plane of the sweep there is moves again (Make twice adds no second plane)
            old = self.animation
            plane = next((t.target for t in (old.tracks if old is not None else ())
                          if t.property == "origin" and t.target in self.scene), None)
            anim = clip_sweep(self.scene, self.axis.currentText(), frames=n, fps=fps,
                              plane=plane)
        if self.combine.isChecked() and self.animation is not None:
            anim = self.animation + anim
        self.set_animation(anim)
        self.show_frame(0)

    def add_key(self, what: str) -> None:
        """A keyframe of the camera (``"camera"``) or of the current isosurface's isovalue
        (``"isovalue"``) at the slider's frame, from the scene as it is now."""
        anim = self.animation or Animation.make(frames=self.frames.value(),
                                                fps=self.fps.value())
        if what == "camera":
            target = "camera"
        else:
            iso = self._isosurface()
            if iso is None:
                self.window.show_error("there is no isosurface to key")
                return
            target = iso.id
        new = self.window.guard(anim.add_key, self.scene, self.slider.value(), target, what)
        if new is not None:
            self.set_animation(new)

    def export(self):
        """File > Export animation... (:func:`export_animation`)."""
        return export_animation(self.window)

    def clear(self) -> None:
        self.play(False)
        self.set_animation(None)

    # -- frames and playing ----------------------------------------------------------------

    def show_frame(self, k: int) -> None:
        """Set the scene to frame ``k`` (the slider follows)."""
        if self.slider.value() != k:
            self.slider.setValue(k)  # calls back into _slider_moved
        else:
            self._slider_moved(k)

    def _slider_moved(self, k: int) -> None:
        anim = self.animation
        self._label()
        if anim is None:
            return
        k = min(k, anim.frames - 1)
        if not self._steps_read(anim, k):
            # shown once a job has read its steps (the last frame asked for wins)
            self._pending = k
            if self._read_job is None:
                self._read_job = self.window.jobs.run(
                    "reading time step", self._read_steps, anim, k,
                    on_done=self._steps_done, on_error=self._steps_failed)
            return
        self._pending = None
        self.window.guard(anim.apply, self.scene, k)
        self.window.request_render()

    def _unread_steps(self, anim: Animation, k: int) -> list[tuple]:
        """``(series, index)`` of each step frame ``k`` shows that is not read yet."""
        track = anim.track(TIME_TARGET, "time")
        if track is None:
            return []
        t = track.value_at(k)[0]
        out = []
        for node in self.scene.time_varying:
            index = node.series.index_at_or_before(t - node.time_offset)
            if not node.series.cached(index):
                out.append((node.series, index))
        return out

    def _steps_read(self, anim: Animation, k: int) -> bool:
        return not self._unread_steps(anim, k)

    def _read_steps(self, anim: Animation, k: int) -> int:
        for series, index in self._unread_steps(anim, k):
            series.step(index)
        return k

    def _steps_done(self, _k: int) -> None:
        self._read_job = None
        if self._pending is not None:
            self._slider_moved(self._pending)

    def _steps_failed(self, exc) -> None:
        from splineviz.gui.jobs import error_message

        self._read_job = self._pending = None
        self.play(False)
        self.window.show_error(f"reading a time step failed: {error_message(exc)}")

    def play(self, on: bool) -> None:
        """Play the animation in the view (looping), or stop."""
        if self.play_button.isChecked() != on:
            self.play_button.setChecked(on)  # calls back
            return
        if on and self.animation is None:
            self.play_button.setChecked(False)
            return
        if on == self._playing:
            return
        self._playing = on
        if on:
            self._view().begin_interaction()
            self._play_timer.start(max(int(1000 / self.animation.fps), 1))
            self.play_button.setText("Stop")
        else:
            self._play_timer.stop()
            self._view().end_interaction()
            self.play_button.setText("Play")

    def _step(self) -> None:
        anim = self.animation
        if anim is None:
            self.play(False)
            return
        if self._read_job is not None:
            return  # the frame shown waits for its steps
        self.show_frame((self.slider.value() + 1) % anim.frames)
        if anim.track(TIME_TARGET, "time") is not None:
            for node in self.scene.time_varying:
                node.series.read_ahead(node.time_index, READ_AHEAD, loop=True)


def _spin(lo, hi, value, suffix, tip) -> QDoubleSpinBox:
    s = QDoubleSpinBox()
    s.setRange(lo, hi)
    s.setDecimals(3)
    s.setValue(value)
    s.setSuffix(suffix)
    s.setToolTip(tip)
    return s


# ---------------------------------------------------------------------------- export
#: (label, suffix, file-dialog filter) of the export formats
EXPORT_FORMATS = (("MP4 video (H.264)", ".mp4", "MP4 videos (*.mp4)"),
                  ("Animated GIF", ".gif", "GIF images (*.gif)"),
                  ("PNG sequence", ".png", "PNG images (*.png)"))


class ExportAnimationDialog(QDialog):
    """Size, frame rate, format and quality of an exported animation."""

    def __init__(self, parent, size, fps: float):
        super().__init__(parent)
        from splineviz.render.movie import DEFAULT_QUALITY

        self.setWindowTitle("Export animation")
        self.width, self.height = size_boxes(
            size, "Pixels of every frame (even for MP4); 3840x2160 for 4K", even=True)
        self.fps = _spin(1.0, 240.0, fps, " fps", "Frames per second of the movie")
        self.format = QComboBox()
        for label, suffix, _ in EXPORT_FORMATS:
            self.format.addItem(label, suffix)
        self.format.setToolTip("MP4 for talks and the web, GIF for slides, PNGs to edit")
        self.quality = _spin(1.0, 10.0, DEFAULT_QUALITY, "", "1..10, 10 best (MP4)")
        self.transparent = QCheckBox("Transparent background (PNG)")
        self.transparent.setToolTip("Alpha 0 where nothing was drawn; PNG sequences only")
        self.format.currentIndexChanged.connect(self._format_changed)
        form = QFormLayout(self)
        form.addRow("Width", self.width)
        form.addRow("Height", self.height)
        form.addRow("Frame rate", self.fps)
        form.addRow("Format", self.format)
        form.addRow("Quality", self.quality)
        form.addRow(self.transparent)
        form.addRow(ok_cancel(self))
        self._format_changed()

    def _format_changed(self, *_):
        png = self.format.currentData() == ".png"
        self.transparent.setEnabled(png)
        self.quality.setEnabled(self.format.currentData() == ".mp4")

    def options(self) -> dict:
        """:func:`~splineviz.render.movie.export_movie` keywords of the choices."""
        png = self.format.currentData() == ".png"
        return {"size": (self.width.value(), self.height.value()), "fps": self.fps.value(),
                "quality": self.quality.value(),
                "transparent_background": png and self.transparent.isChecked()}


def export_animation(window):
    """File > Export animation...: the dialog, a file name, then :func:`start_export`;
    returns the job (None when the user stopped)."""
    anim = window.scene.animation
    if anim is None:
        window.show_error("there is no animation to export: make one in the Animation panel")
        return None
    dlg = ExportAnimationDialog(window, window.spline_scene.window_size(), anim.fps)
    if dlg.exec() != QDialog.DialogCode.Accepted:
        return None
    label, suffix, filt = EXPORT_FORMATS[dlg.format.currentIndex()]
    default = "animation" + ("_%04d" if suffix == ".png" else "") + suffix
    path, _ = QFileDialog.getSaveFileName(window, "Export animation", default, filt)
    if not path:
        return None
    if not path.lower().endswith(suffix):
        path += suffix
    return window.guard(start_export, window, path, **dlg.options())


def _export_in_process(session, data, path, options, job):
    """The job thread: the export in a child process (:func:`splineviz.gui.jobs` stops it
    on cancel); whatever way it ends early, its staging folder goes."""
    from splineviz.gui.jobs import _in_process
    from splineviz.render.movie import export_session, staging_folder

    try:
        return _in_process(export_session, (session, data, path), options, job)
    except BaseException:
        shutil.rmtree(staging_folder(path), ignore_errors=True)
        raise


def start_export(window, path, **options):
    """Export the scene's animation to ``path`` in the background (see module docstring);
    returns the job."""
    from splineviz.model.session import needs_data_file, to_session
    from splineviz.render.movie import movie_format

    movie_format(path)  # a bad name is refused now, not in the child
    scene = window.scene
    # data without a file travels with the job: the child gets it in memory
    written = {n.id: (f"<memory {n.id}>", {}) for n in scene if needs_data_file(n)}
    session = to_session(scene, written=written)
    data = {}
    for node in scene:
        if getattr(node, "vertices", None) is not None:
            data[node.id] = (node.vertices, node.faces, node.normals)
        elif getattr(node, "data", None) is not None:
            data[node.id] = node.data
    path = str(Path(path).expanduser().absolute())

    def done(stats):
        window.statusBar().showMessage(f"exported {stats.frames} frames to {stats.path}", 8000)
        window.log.add(f"exported animation {stats.path} ({stats.frames} frames, "
                       f"{stats.seconds_per_frame:.2f} s a frame)")

    return window.jobs.run(f"export {Path(path).name}", _export_in_process, session, data,
                           path, {**options, "device": window.device}, on_done=done)


def install(window) -> QDockWidget:
    """Add the Animation dock to ``window``: under the view, as ParaView's Animation View,
    hidden until View > Panels shows it."""
    window.animation_panel = AnimationPanel(window)
    dock = window._dock("Animation", window.animation_panel,
                        Qt.DockWidgetArea.BottomDockWidgetArea)
    dock.hide()
    window.docks["Animation"] = dock
    return dock
