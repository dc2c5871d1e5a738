"""The main window's size, position and dock layout: the first opening's, and the last
session's remembered in QSettings (as ParaView and Slicer do).

A first opening takes :data:`SCREEN_SHARE` of the screen's available area, centred (never more
than the screen: on a 1600x1000 screen 1360x850, not the 1280x800 a fixed 80 % gave). The app
(:func:`splineviz.gui.app.run_gui`) restores the last geometry and dock layout with
:func:`restore_geometry` and :func:`restore_layout` and saves them with :func:`remember`
when the window closes; windows made by
scripts and tests neither read nor write them.
"""

from __future__ import annotations

from PySide6.QtCore import QByteArray, QEvent, QObject, QRect, QSettings, Qt, QTimer
from PySide6.QtGui import QGuiApplication
from PySide6.QtWidgets import QTabBar

#: share of the screen's available width and height a first opening takes
SCREEN_SHARE = 0.85
#: QSettings group of the remembered geometry and dock layout
SETTINGS_GROUP = "window"
#: version of the dock layout (restoreState refuses a layout saved under another)
LAYOUT_VERSION = 1
#: share of the window's width a dock column may take to show its tabs' whole titles
MAX_COLUMN_SHARE = 0.3
#: the dock tabs' look (see :func:`readable_tabs`)
TAB_STYLE = "QTabBar::tab { padding: 3px 7px; }"


def _settings() -> QSettings:
    return QSettings("splineviz", "splineviz")


def _available(window) -> QRect | None:
    screen = window.screen() or QGuiApplication.primaryScreen()
    return None if screen is None else screen.availableGeometry()


def first_geometry(avail: QRect, wanted_width: int, wanted_height: int) -> QRect:
    """The window's rectangle on a screen whose available area is ``avail``: the wanted
    size grown to :data:`SCREEN_SHARE` of the screen, at most the screen, centred."""
    w = min(max(wanted_width, int(SCREEN_SHARE * avail.width())), avail.width())
    h = min(max(wanted_height, int(SCREEN_SHARE * avail.height())), avail.height())
    return QRect(avail.x() + (avail.width() - w) // 2, avail.y() + (avail.height() - h) // 2,
                 w, h)


def fit_to_screen(window) -> None:
    """Size and centre ``window`` as :func:`first_geometry` says."""
    avail = _available(window)
    if avail is None:
        return
    want = window.sizeHint().expandedTo(window.minimumSizeHint())
    rect = first_geometry(avail, want.width(), want.height())
    window.resize(rect.width(), rect.height())
    window.move(rect.x(), rect.y())


class _ReadableTabs(QObject):
    """Gives every tab bar the window makes from now on (a dock dragged onto another, a
    restored layout) the settings of :func:`readable_tabs`."""

    def eventFilter(self, obj, event):  # noqa: N802 (Qt naming)
        if event.type() == QEvent.Type.ChildPolished and isinstance(event.child(), QTabBar):
            _readable(event.child())
        return False


def _readable(bar: QTabBar) -> None:
    bar.setElideMode(Qt.TextElideMode.ElideNone)
    bar.setUsesScrollButtons(True)
    # narrower padding than the style's: four titles fit a column of 30 % at 1280x800
    bar.setStyleSheet(TAB_STYLE)


def readable_tabs(window) -> int:
    """Let the tabs of tabbed docks show their whole titles ("Clipping", not "Clipp..."):
    Qt elides them to fit the column; here they keep their text and scroll when the column
    is narrower still, now and in the tab bars the window makes later. Returns the width the
    widest tab bar needs (0: no tabs yet, Qt makes the bars once the window is laid out)."""
    if window.findChild(_ReadableTabs) is None:
        window.installEventFilter(_ReadableTabs(window))
    need = 0
    for bar in window.findChildren(QTabBar):
        _readable(bar)
        if bar.isVisible():
            need = max(need, bar.sizeHint().width())
    return need


def column_width(window, share_width: int) -> int:
    """The width of a column of tabbed docks: ``share_width``, widened to show the whole
    tab titles (:func:`readable_tabs`) up to :data:`MAX_COLUMN_SHARE` of the window."""
    need = readable_tabs(window)
    return max(share_width, min(need, int(MAX_COLUMN_SHARE * window.width())))


def keep_on_screen(window) -> None:
    """Shrink and move ``window`` into its screen's available area (a geometry remembered
    on a bigger or another screen)."""
    avail = _available(window)
    if avail is None:
        return
    frame = window.frameGeometry()
    w = min(window.width(), avail.width() - (frame.width() - window.width()))
    h = min(window.height(), avail.height() - (frame.height() - window.height()))
    if (w, h) != (window.width(), window.height()):
        window.resize(max(w, 1), max(h, 1))
        frame = window.frameGeometry()
    x = min(max(frame.x(), avail.x()), avail.right() + 1 - frame.width())
    y = min(max(frame.y(), avail.y()), avail.bottom() + 1 - frame.height())
    if (x, y) != (frame.x(), frame.y()):
        window.move(x, y)


def remember(window) -> None:
    """Save ``window``'s geometry and dock layout (``QMainWindow.saveGeometry`` and
    ``saveState``) for the next opening."""
    s = _settings()
    s.setValue(f"{SETTINGS_GROUP}/geometry", window.saveGeometry())
    s.setValue(f"{SETTINGS_GROUP}/state", window.saveState(LAYOUT_VERSION))
    s.sync()


def restore_geometry(window) -> bool:
    """Give ``window`` the size and position :func:`remember` saved, kept on the screen
    (before it is shown: no jump); False (nothing changed) when none was saved."""
    geometry = _settings().value(f"{SETTINGS_GROUP}/geometry")
    if not isinstance(geometry, QByteArray) or not window.restoreGeometry(geometry):
        return False
    keep_on_screen(window)
    return True


def restore_layout(window) -> None:
    """Give the shown ``window`` the dock layout :func:`remember` saved, once the window's
    own first layout (docks sized to the window, one turn of the event loop after it is
    shown) is done."""
    state = _settings().value(f"{SETTINGS_GROUP}/state")
    if isinstance(state, QByteArray):
        QTimer.singleShot(0, lambda: window.restoreState(state, LAYOUT_VERSION))
