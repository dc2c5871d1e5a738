"""Edit > Preferences...: the app's defaults, kept in QSettings beside the window's geometry
(:mod:`splineviz.gui.window_state`).

What a user sets, and when it acts:

* **default spline model** of a volume's first isosurface: on the next volume opened
  (:attr:`splineviz.model.Scene.preferred_model`);
* **background colour** of the 3-D view: at once (the scene's view node), and in new scenes;
* **preview quality**: the finest resolution a fast preview may reach while dragging
  (:attr:`splineviz.render.scene.SplineScene.max_preview_scale`), at once;
* **lazy reading threshold**: the share of the memory budget above which volumes are
  memory-mapped or read chunk by chunk (``$SPLINEVIZ_LAZY_SHARE``,
  :func:`splineviz.io.mapped.lazy_threshold`), from the next file read;
* **default layout** (View > Layout), at once and when the app starts.

"Restore defaults" in the dialog puts the built-in values back into its fields. The app
(:func:`splineviz.gui.app.run_gui`) applies the stored preferences at start; windows made by
scripts and tests apply them only when asked (:func:`apply`).
"""

from __future__ import annotations

import os
from dataclasses import asdict, dataclass, fields, replace

from PySide6.QtCore import QSettings
from PySide6.QtGui import QAction, QColor
from PySide6.QtWidgets import (
    QColorDialog,
    QComboBox,
    QDialog,
    QDialogButtonBox,
    QDoubleSpinBox,
    QFormLayout,
    QPushButton,
    QVBoxLayout,
)

#: QSettings group of the preferences
SETTINGS_GROUP = "preferences"
#: (menu text, finest preview resolution factor) of the preview qualities
PREVIEW_QUALITIES = (("Full resolution", 1.0), ("Half resolution", 0.5),
                     ("Quarter resolution", 0.25))


#: whether :func:`apply` has set ``$SPLINEVIZ_LAZY_SHARE`` in this process
_lazy_written = False


def _layouts():
    from splineviz.gui.layout import LAYOUT_CHOICES

    return [(f"{layout}:{single}" if single else layout, text.replace("&", ""))
            for layout, single, text, _tip in LAYOUT_CHOICES]


@dataclass(frozen=True)
class Preferences:
    """The stored preferences (see the module docstring).

    Attributes
    ----------
    model : str
        Key of a registered spline model.
    background : (3,) tuple of float in [0, 1]
    max_preview_scale : float
        One of :data:`PREVIEW_QUALITIES`' factors.
    lazy_share : float in [0, 1]
        Share of the memory budget above which volumes are read lazily.
    layout : str
        ``"3d"``, ``"four-up"`` or ``"one-slice:<slice>"``.
    """

    model: str
    background: tuple[float, float, float]
    max_preview_scale: float
    lazy_share: float
    layout: str

    @classmethod
    def defaults(cls) -> Preferences:
        """The built-in values."""
        from splineviz.core.raycast_reference import BACKGROUND
        from splineviz.io.mapped import LAZY_SHARE
        from splineviz.model.scene import default_model

        return cls(default_model(), tuple(float(c) for c in BACKGROUND), 1.0, LAZY_SHARE, "3d")


def _settings() -> QSettings:
    return QSettings("splineviz", "splineviz")


def load() -> Preferences:
    """The stored preferences, each missing or unusable value replaced by its default (a
    model is checked against the registry with the plugins' models in it)."""
    from splineviz.core.splines import MODELS
    from splineviz.plugins import load_plugins

    load_plugins()

    prefs = Preferences.defaults()
    s = _settings()
    s.beginGroup(SETTINGS_GROUP)
    try:
        stored = {f.name: s.value(f.name) for f in fields(Preferences) if s.contains(f.name)}
    finally:
        s.endGroup()
    values = {}
    try:
        if stored.get("model") in MODELS:
            values["model"] = str(stored["model"])
        if "background" in stored:
            rgb = tuple(float(c) for c in str(stored["background"]).split(","))
            if len(rgb) == 3 and all(0.0 <= c <= 1.0 for c in rgb):
                values["background"] = rgb
        if "max_preview_scale" in stored:
            scale = float(stored["max_preview_scale"])
            if scale in [f for _, f in PREVIEW_QUALITIES]:
                values["max_preview_scale"] = scale
        if "lazy_share" in stored:
            values["lazy_share"] = min(max(float(stored["lazy_share"]), 0.0), 1.0)
        if stored.get("layout") in [key for key, _ in _layouts()]:
            values["layout"] = str(stored["layout"])
    except (TypeError, ValueError):
        pass  # a hand-edited settings file: the values read so far, defaults for the rest
    return replace(prefs, **values)


def save(prefs: Preferences) -> None:
    """Store ``prefs`` (the background as "r,g,b" in [0, 1], exactly; the rest as they
    are)."""
    s = _settings()
    s.beginGroup(SETTINGS_GROUP)
    try:
        for name, value in asdict(prefs).items():
            if name == "background":
                value = ",".join(repr(float(c)) for c in value)
            s.setValue(name, value)
    finally:
        s.endGroup()
    s.sync()


def apply(window, prefs: Preferences, previous: Preferences | None = None) -> None:
    """Make ``prefs`` act in ``window`` (see the module docstring for when each does).

    With ``previous`` (the preferences before the dialog's OK) the background and the
    layout change only where the preference changed: a session's own background and the
    layout the user chose stay. An unmodified scene stays unmodified (a colour or layout
    preference is no edit to save)."""
    from splineviz.io.mapped import LAZY_SHARE_ENV

    scene = window.scene
    scene.preferred_model = prefs.model
    was_modified = scene.modified
    if previous is None or previous.background != prefs.background:
        if tuple(scene.view.background) != tuple(prefs.background):
            scene.view.background = tuple(prefs.background)
    if previous is None or previous.layout != prefs.layout:
        layout, _, single = prefs.layout.partition(":")
        window.view_layout.set_layout(layout, single or None)
    if not was_modified:
        scene.mark_saved()
    for view in window.linked_views.views:
        view.spline_scene.max_preview_scale = prefs.max_preview_scale
    # the readers read it per file: the next file opened follows the preference. A value
    # the user put in the environment at launch stays while the preference is the default
    if prefs.lazy_share != Preferences.defaults().lazy_share or _lazy_written:
        os.environ[LAZY_SHARE_ENV] = repr(float(prefs.lazy_share))
        globals()["_lazy_written"] = True


class PreferencesDialog(QDialog):
    """The preferences as a form; OK stores and applies them (:func:`save`, :func:`apply`),
    "Restore defaults" refills the fields with the built-in values.

    Parameters
    ----------
    window : splineviz.gui.main_window.MainWindow
    """

    def __init__(self, window):
        super().__init__(window)
        from splineviz.core.splines import MODELS

        self.window = window
        self.setWindowTitle("Preferences")
        self.setObjectName("preferences")
        form = QFormLayout()
        self.model = QComboBox()
        for name, spec in MODELS.items():
            self.model.addItem(spec.display_label, name)
        self.model.setToolTip("The spline model of a volume's first isosurface "
                              "(from the next volume opened)")
        form.addRow("Default spline model", self.model)
        self.background = QPushButton()
        self.background.setToolTip("Background colour of the 3-D view")
        self.background.clicked.connect(self._choose_background)
        form.addRow("Background", self.background)
        self.preview = QComboBox()
        for text, scale in PREVIEW_QUALITIES:
            self.preview.addItem(text, scale)
        self.preview.setToolTip("The finest resolution of the quick previews shown while "
                                "dragging (coarser: smoother dragging on slow machines)")
        form.addRow("Preview quality", self.preview)
        self.lazy = QDoubleSpinBox()
        self.lazy.setRange(0.0, 100.0)
        self.lazy.setDecimals(1)
        self.lazy.setSuffix(" % of memory")
        self.lazy.setToolTip("Volumes bigger than this share of the memory budget are read "
                             "lazily, piece by piece (from the next file opened)")
        form.addRow("Read lazily above", self.lazy)
        self.layout_box = QComboBox()
        for key, text in _layouts():
            self.layout_box.addItem(text, key)
        self.layout_box.setToolTip("The views the window shows (View > Layout)")
        form.addRow("Default layout", self.layout_box)
        buttons = QDialogButtonBox(QDialogButtonBox.StandardButton.Ok
                                   | QDialogButtonBox.StandardButton.Cancel
                                   | QDialogButtonBox.StandardButton.RestoreDefaults)
        buttons.accepted.connect(self.accept)
        buttons.rejected.connect(self.reject)
        self.restore_button = buttons.button(QDialogButtonBox.StandardButton.RestoreDefaults)
        self.restore_button.clicked.connect(lambda: self.show_values(Preferences.defaults()))
        self.buttons = buttons
        box = QVBoxLayout(self)
        box.addLayout(form)
        box.addWidget(buttons)
        self._background = (0.0, 0.0, 0.0)
        self.show_values(load())

    def show_values(self, prefs: Preferences) -> None:
        """Fill the fields with ``prefs``."""
        self.model.setCurrentIndex(max(0, self.model.findData(prefs.model)))
        self._set_background(prefs.background)
        self.preview.setCurrentIndex(max(0, self.preview.findData(prefs.max_preview_scale)))
        self.lazy.setValue(100.0 * prefs.lazy_share)
        self.layout_box.setCurrentIndex(max(0, self.layout_box.findData(prefs.layout)))

    def values(self) -> Preferences:
        """The preferences the fields hold."""
        return Preferences(self.model.currentData(), self._background,
                           float(self.preview.currentData()), self.lazy.value() / 100.0,
                           self.layout_box.currentData())

    def _set_background(self, rgb) -> None:
        self._background = tuple(float(c) for c in rgb)
        name = QColor.fromRgbF(*self._background).name()
        self.background.setText(name)
        self.background.setStyleSheet(f"background-color: {name};")

    def _choose_background(self) -> None:
        colour = QColorDialog.getColor(QColor.fromRgbF(*self._background), self,
                                       "Background colour")
        if colour.isValid():
            self._set_background((colour.redF(), colour.greenF(), colour.blueF()))

    def accept(self) -> None:
        prefs, previous = self.values(), load()
        save(prefs)
        apply(self.window, prefs, previous)
        super().accept()


def show_dialog(window) -> PreferencesDialog:
    """Open the dialog, not blocking (the window keeps drawing); returns it."""
    dialog = PreferencesDialog(window)
    dialog.setModal(True)
    dialog.show()
    window._preferences_dialog = dialog  # kept alive while it shows
    return dialog


def add_action(window, menu) -> QAction:
    """Edit > Preferences... (Ctrl+,; the application menu's Preferences on macOS)."""
    action = QAction("&Preferences...", window)
    action.setMenuRole(QAction.MenuRole.PreferencesRole)
    action.setShortcut("Ctrl+,")
    tip = "The default model, background, preview quality, lazy reading and layout (Ctrl+,)"
    action.setToolTip(tip)
    action.setStatusTip(tip)
    action.triggered.connect(lambda: show_dialog(window))
    menu.addSeparator()
    menu.addAction(action)
    return action
