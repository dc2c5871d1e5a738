"""Menus, toolbar and shortcuts of the main window.

Every action has a tooltip and, where it is common, a standard shortcut; the View menu and
the toolbar offer the standard views of ParaView/Slicer (+X ... -Z, isometric, reset).
Actions only call the window's commands, panels and view; they hold no state.
"""

from __future__ import annotations

from PySide6.QtGui import QAction, QIcon, QKeySequence
from PySide6.QtWidgets import QToolBar

#: (view name, menu text, shortcut, icon name) of the standard views
STANDARD_VIEW_ACTIONS = (
    ("+X", "Look down +X", "Ctrl+1", "view-px"),
    ("-X", "Look down -X", "Ctrl+Shift+1", "view-mx"),
    ("+Y", "Look down +Y", "Ctrl+2", "view-py"),
    ("-Y", "Look down -Y", "Ctrl+Shift+2", "view-my"),
    ("+Z", "Look down +Z", "Ctrl+3", "view-pz"),
    ("-Z", "Look down -Z", "Ctrl+Shift+3", "view-mz"),
    ("isometric", "Isometric", "Ctrl+0", "view-iso"),
)

#: shown by Help > Keyboard and mouse
HELP_TEXT = """<b>Mouse in the 3-D view</b><br>
left drag: rotate &nbsp; right drag or wheel: zoom &nbsp; middle drag or Shift+left: pan<br>
hover over a surface: position and data value in the status bar<br><br>
<b>Keys in the 3-D view</b><br>
r: reset the camera to all data &nbsp; v: isometric view<br><br>
<b>Shortcuts</b><br>
Ctrl+O open, Ctrl+S save session, Ctrl+Shift+S save session as, Ctrl+E export screenshot,
Ctrl+1/2/3 look down +X/+Y/+Z (with Shift: -X/-Y/-Z), Ctrl+0 isometric, Esc cancel jobs"""


def icon(name: str) -> QIcon:
    """The toolbar icon ``name`` from ``resources/icons`` (an empty icon when missing)."""
    try:
        from splineviz.resources import icon_path

        return QIcon(str(icon_path(name)))
    except Exception:  # noqa: BLE001  (resources are optional: text-only actions then)
        return QIcon()


def _action(window, text, slot, *, shortcut=None, tip="", icon_name=None, menu=None):
    a = QAction(text, window)
    if shortcut is not None:
        a.setShortcut(QKeySequence(shortcut))
    tip = tip or text.replace("&", "").rstrip(".")
    if shortcut is not None:
        tip += f" ({QKeySequence(shortcut).toString()})"
    a.setToolTip(tip)
    a.setStatusTip(tip)
    if icon_name:
        a.setIcon(icon(icon_name))
    a.triggered.connect(slot)
    if menu is not None:
        menu.addAction(a)
    return a


def build_actions(window) -> dict[str, QAction]:
    """Fill the window's menu bar and toolbar; returns the actions by name."""
    acts: dict[str, QAction] = {}
    m = window.menuBar().addMenu("&File")
    acts["open"] = _action(window, "&Open...", window.open_dialog, menu=m,
                           shortcut=QKeySequence.StandardKey.Open, icon_name="open",
                           tip="Open a volume, point cloud or session")
    window.recent_menu = m.addMenu("Open &Recent")
    _action(window, "Open &default data", lambda: window.commands.open_default(), menu=m,
            tip="The embedded Marschner-Lobb test volume")
    window.sources_menu = m.addMenu("Open s&ynthetic source")
    window.sources_menu.aboutToShow.connect(window.fill_sources)
    window.examples_menu = m.addMenu("E&xample sessions")
    window.examples_menu.aboutToShow.connect(window.fill_examples)
    m.addSeparator()
    _action(window, "&Load session...", window.load_session_dialog, menu=m,
            tip="Replace the scene by a saved session (.svs)")
    acts["save"] = _action(window, "&Save session", window.save_session_action, menu=m,
                           shortcut=QKeySequence.StandardKey.Save, icon_name="save",
                           tip="Save the scene as a session (.svs)")
    _action(window, "Save session &as...", window.save_session_dialog, menu=m,
            shortcut="Ctrl+Shift+S", tip="Save the scene under another name")
    m.addSeparator()
    acts["screenshot"] = _action(window, "Export s&creenshot...", window.screenshot_dialog,
                                 menu=m, shortcut="Ctrl+E", icon_name="screenshot",
                                 tip="Save the view as PNG at any size")
    _action(window, "Export &mesh...", window.export_mesh_dialog, menu=m,
            tip="Save the selected mesh or isosurface as PLY/OBJ/STL/VTP (clipped, normals)")
    m.addSeparator()
    _action(window, "&Quit", window.close, menu=m, shortcut=QKeySequence.StandardKey.Quit)

    v = window.menuBar().addMenu("&View")
    acts["reset"] = _action(window, "&Reset camera", lambda: window.view.standard_view(None),
                            menu=v, shortcut="Ctrl+R", icon_name="reset-camera",
                            tip="Show all data, keeping the viewing direction")
    v.addSeparator()
    for name, text, shortcut, icon_name in STANDARD_VIEW_ACTIONS:
        acts[f"view {name}"] = _action(window, text,
                                       lambda _=False, n=name: window.view.standard_view(n),
                                       menu=v, shortcut=shortcut, icon_name=icon_name)
    v.addSeparator()
    grid = _action(window, "Axes &grid", lambda on: window.scene.view.update(show_scale=on),
                   menu=v, tip="Axes with world-unit ticks around the data")
    grid.setCheckable(True)
    grid.setChecked(window.scene.view.show_scale)
    acts["grid"] = grid
    window.panels_menu = v.addMenu("&Panels")

    t = window.menuBar().addMenu("&Tools")
    acts["add iso"] = _action(window, "&Add isosurface", window.iso_panel.add_isosurface,
                              menu=t, icon_name="add-isosurface",
                              tip="Another isosurface of the current volume")
    acts["add plane"] = _action(window, "Add &clip plane", lambda: window.clip_panel.add_plane(),
                                menu=t, icon_name="clip-plane",
                                tip="A clip plane through the centre of the data")
    acts["cancel"] = _action(window, "&Cancel running jobs", window.jobs.cancel_all, menu=t,
                             shortcut="Esc", icon_name="cancel")

    h = window.menuBar().addMenu("&Help")
    _action(window, "&Keyboard and mouse", window.show_help, menu=h, shortcut="F1")
    _action(window, "&About splineviz", window.about, menu=h)

    bar = QToolBar("Main toolbar", window)
    bar.setObjectName("main toolbar")
    for key in ("open", "save", "screenshot", None, "reset", "view +X", "view -X", "view +Y",
                "view -Y", "view +Z", "view -Z", "view isometric", None, "add iso",
                "add plane"):
        if key is None:
            bar.addSeparator()
        else:
            bar.addAction(acts[key])
    window.addToolBar(bar)
    window.toolbar = bar
    return acts
