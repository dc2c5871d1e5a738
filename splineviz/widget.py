"""The scene as an ipywidgets view in a notebook: its exact picture and the main controls.

:class:`SceneWidget` (``scene.widget()``) is an ipywidgets box of an ``Image`` and the
controls of the web page (:mod:`splineviz.web`): isovalue slider, model, clip plane on/off,
colour-by, and buttons that orbit and zoom. Every control goes through the web page's
:class:`~splineviz.web.view.RemoteView` (the scene model is the state, as in the desktop
app), and every picture is its exact frame, :func:`~splineviz.render.scene_view.render_scene`
of the scene: the image a script or ``splineviz render`` makes for the same camera.

Widget events run in the kernel's main thread, one at a time, so the view's VTK objects are
used from one thread as they must be. Dragging on the image needs mouse events on it
(ipyevents), which splineviz does not depend on: the buttons orbit instead.
"""

from __future__ import annotations

import ipywidgets as widgets

from splineviz.model import Scene
from splineviz.web.png import png_bytes
from splineviz.web.view import DEGREES_PER_VIEW_HEIGHT, RemoteView

#: degrees one press of an orbit button turns the camera
ORBIT_STEP_DEG = 15.0
#: distance factor of one press of a zoom button
ZOOM_STEP = 1.25
#: isovalue slider positions across the volume's range
SLIDER_STEPS = 200


class SceneWidget(widgets.VBox):
    """An ipywidgets view of ``scene`` (see module docstring).

    Parameters
    ----------
    scene : splineviz.model.Scene
    size : (width, height)
    device : str or None
        OpenCL device preference of the ray casters.

    Attributes
    ----------
    view : splineviz.web.view.RemoteView
    image : ipywidgets.Image
        PNG of the view's exact frame.
    isovalue, model, clip, color_by : ipywidgets controls (None where the scene has no
        isosurface, except ``clip``)
    """

    def __init__(self, scene: Scene, size=(640, 480), device=None):
        self.view = RemoteView(scene, size=size, device=device)
        controls, state = self.view.controls(), self.view.state()
        self.image = widgets.Image(format="png", width=self.view.size[0],
                                   height=self.view.size[1])
        self.isovalue = self.model = self.color_by = None
        row = []
        if "isovalue" in state:
            lo, hi = controls["isovalue_range"]
            self.isovalue = widgets.FloatSlider(
                value=state["isovalue"], min=lo, max=hi, step=(hi - lo) / SLIDER_STEPS or 1.0,
                readout_format=".4g", description="isovalue", continuous_update=False)
            models = controls["models"]
            if state["model"] not in models:
                models = [*models, state["model"]]
            self.model = widgets.Dropdown(options=models, value=state["model"],
                                          description="model")
            self.color_by = widgets.Dropdown(options=controls["color_by"],
                                             value=state["color_by"], description="colour by")
            row += [self.isovalue, self.model, self.color_by]
        self.clip = widgets.Checkbox(value=state["clip"], description="clip plane")
        row.append(self.clip)
        for name in ("isovalue", "model", "color_by", "clip"):
            control = getattr(self, name)
            if control is not None:
                control.observe(self._setter(name), names="value")
        pixels = ORBIT_STEP_DEG * self.view.size[1] / DEGREES_PER_VIEW_HEIGHT
        buttons = []
        for label, action in (("◀", lambda: self.view.orbit(-pixels, 0)),
                              ("▶", lambda: self.view.orbit(pixels, 0)),
                              ("▲", lambda: self.view.orbit(0, -pixels)),
                              ("▼", lambda: self.view.orbit(0, pixels)),
                              ("+", lambda: self.view.zoom(ZOOM_STEP)),
                              ("−", lambda: self.view.zoom(1.0 / ZOOM_STEP))):
            button = widgets.Button(description=label,
                                    layout=widgets.Layout(width="3em"))
            button.on_click(self._action(action))
            buttons.append(button)
        super().__init__([self.image, widgets.HBox(row[:2]), widgets.HBox(row[2:]),
                          widgets.HBox(buttons)])
        self.refresh()

    def _setter(self, name):
        def changed(change):
            self.view.set(name, change["new"])
            self.refresh()

        return changed

    def _action(self, action):
        def clicked(_button):
            action()
            self.refresh()

        return clicked

    def refresh(self) -> None:
        """Show the view's exact frame now."""
        self.image.value = png_bytes(self.view.exact().image)

    def close(self) -> None:
        """Close the widgets and the view's off-screen window."""
        self.view.close()
        super().close()
