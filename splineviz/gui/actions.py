"""Menus, toolbar and shortcuts of the main window.

Every action has a tooltip and, where it is common, a standard shortcut; the View menu and
the toolbar offer the standard views of ParaView/Slicer (+X ... -Z, isometric, reset), the
Edit menu undo and redo of the scene's edits (:mod:`splineviz.gui.undo`). Actions only call
the window's commands, panels and view; they hold no state.
"""

from __future__ import annotations

from PySide6.QtGui import QAction, QIcon, QKeySequence
from PySide6.QtWidgets import QToolBar

from splineviz.gui import dialogs, open_dialogs, preferences
from splineviz.gui.undo import undo_stack

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


def build_edit_menu(window, acts: dict[str, QAction]) -> None:
    """Edit > Undo / Redo over the scene's undo stack; their text names the step."""
    stack = undo_stack(window.scene).stack
    e = window.menuBar().addMenu("&Edit")
    # explicit keys: without a desktop environment Qt maps the standard ones to none
    for name, action, keys, tip in (
            ("undo", stack.createUndoAction(window, "&Undo"), ["Ctrl+Z"],
             "Undo the last edit of the scene"),
            ("redo", stack.createRedoAction(window, "&Redo"), ["Ctrl+Shift+Z", "Ctrl+Y"],
             "Redo the edit undone last")):
        action.setShortcuts([QKeySequence(k) for k in keys])
        tip += f" ({QKeySequence(keys[0]).toString()})"
        action.setToolTip(tip)
        action.setStatusTip(tip)
        e.addAction(action)
        acts[name] = action
    acts["preferences"] = preferences.add_action(window, e)


def build_actions(window) -> dict[str, QAction]:
    """Fill the window's menu bar and toolbar; returns the actions by name."""
    acts: dict[str, QAction] = {}
    m = window.menuBar().addMenu("&File")
    acts["new"] = _action(window, "&New", lambda: window.commands.new_scene(), menu=m,
                          shortcut="Ctrl+N", tip="An empty scene (asks about unsaved changes)")
    acts["open"] = _action(window, "&Open...", lambda: open_dialogs.open_file(window), menu=m,
                           shortcut=QKeySequence.StandardKey.Open, icon_name="open",
                           tip="Open a volume, point cloud or session")
    acts["open folder"] = _action(window, "Open &Folder...",
                                  lambda: open_dialogs.open_folder(window), menu=m,
                                  shortcut="Ctrl+Shift+O",
                                  tip="Open a DICOM series, a folder of slices or a Zarr store")
    window.recent = dialogs.RecentFiles(window, m.addMenu("Open &Recent"))
    _action(window, "Open &default data", lambda: window.commands.open_default(), menu=m,
            tip="The embedded Marschner-Lobb test volume")
    window.sources_menu = m.addMenu("Open s&ynthetic source")
    window.sources_menu.aboutToShow.connect(
        lambda: dialogs.fill_sources(window, window.sources_menu))
    window.examples_menu = m.addMenu("E&xample sessions")
    window.examples_menu.aboutToShow.connect(
        lambda: dialogs.fill_examples(window, window.examples_menu))
    m.addSeparator()
    _action(window, "&Load session...", lambda: dialogs.load_session(window), menu=m,
            tip="Replace the scene by a saved session (.svs)")
    acts["save"] = _action(window, "&Save session", lambda: dialogs.save_session(window), menu=m,
                           shortcut=QKeySequence.StandardKey.Save, icon_name="save",
                           tip="Save the scene as a session (.svs)")
    _action(window, "Save session &as...", lambda: dialogs.save_session_as(window), menu=m,
            shortcut="Ctrl+Shift+S", tip="Save the scene under another name")
    m.addSeparator()
    acts["screenshot"] = _action(window, "Export s&creenshot...",
                                 lambda: dialogs.export_screenshot(window), menu=m,
                                 shortcut="Ctrl+E", icon_name="screenshot",
                                 tip="Save the view as PNG at any size")
    _action(window, "Export &mesh...", lambda: dialogs.export_mesh(window), menu=m,
            tip="Save the selected mesh or isosurface as PLY/OBJ/STL/VTP (clipped, normals)")
    _action(window, "Export spline mesh (advancing &front)...",
            lambda: dialogs.export_mesh(window, method="front"), menu=m,
            tip="Mesh the selected isosurface with the advancing front on the spline: "
                "well-shaped, curvature-adapted triangles on the exact surface (slower)")
    acts["export animation"] = _action(
        window, "Export &animation...", lambda: window.animation_panel.export(), menu=m,
        tip="Render the Animation panel's animation into MP4, GIF or PNGs (in the background)")
    m.addSeparator()
    # explicit: without a desktop environment Qt maps StandardKey.Quit to no key at all
    _action(window, "&Quit", window.close, menu=m, shortcut="Ctrl+Q")

    build_edit_menu(window, acts)

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
    split = _action(window, "&Split view (linked cameras)",
                    lambda on: window.linked_views.set_split(on), menu=v, shortcut="F7",
                    tip="Two views side by side with one camera, each with its own "
                        "isosurfaces: compare spline models or isovalues")
    split.setCheckable(True)
    split.setChecked(window.scene.view.split)  # LinkedViews keeps it in step afterwards
    acts["split"] = split
    window.panels_menu = v.addMenu("&Panels")

    t = window.menuBar().addMenu("&Tools")
    acts["add iso"] = _action(window, "&Add isosurface", window.iso_panel.add_isosurface,
                              menu=t, icon_name="add-isosurface",
                              tip="Another isosurface of the current volume")
    acts["add plane"] = _action(window, "Add &clip plane", lambda: window.clip_panel.add_plane(),
                                menu=t, icon_name="clip-plane",
                                tip="A clip plane through the centre of the data")
    acts["cancel"] = _action(window, "&Cancel running jobs", window.cancel_all, menu=t,
                             shortcut="Esc", icon_name="cancel",
                             tip="Stop the running jobs and the exact frames being computed")

    h = window.menuBar().addMenu("&Help")
    _action(window, "&Keyboard and mouse", lambda: dialogs.show_help(window), menu=h, shortcut="F1")
    _action(window, "&About splineviz", lambda: dialogs.about(window), menu=h)

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
