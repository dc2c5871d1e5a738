"""The peer of the round-trip benchmark: pyvista's trame backend (``trame-pyvista``, server-side
rendering: images streamed to the page) showing VTK's flying-edges isosurface of the embedded
default data. Run as a script: prints ``serving http://127.0.0.1:PORT/`` once it listens."""

import sys

import numpy as np


def flying_edges_mesh():
    import pyvista as pv

    from splineviz.model.opening import default_volume

    vol, iso = default_volume()
    grid = pv.ImageData(dimensions=vol.data.shape, spacing=vol.spacing, origin=vol.origin)
    grid.point_data["v"] = np.asarray(vol.data, dtype=np.float32).ravel(order="F")
    return grid.contour([iso], scalars="v", method="flying_edges")


def main(port: int, width: int, height: int) -> None:
    import pyvista as pv
    from trame.app import get_server
    from trame.ui.vuetify3 import SinglePageLayout
    from trame.widgets import vuetify3
    from trame_pyvista.ui import plotter_ui

    # the default server: trame_pyvista registers its view components there
    server = get_server(client_type="vue3")
    plotter = pv.Plotter(off_screen=True, window_size=(width, height))
    plotter.add_mesh(flying_edges_mesh(), color=(0.9, 0.8, 0.6), smooth_shading=True)
    plotter.view_isometric()
    with SinglePageLayout(server) as layout:
        layout.title.set_text("pyvista trame: flying edges")
        with layout.content:
            # a container of the view's size: in a container of no height the view is blank
            with vuetify3.VContainer(fluid=True, classes="pa-0",
                                     style=f"width: {width}px; height: {height}px"):
                plotter_ui(plotter, mode="server")

    @server.controller.add("on_server_ready")
    def ready(**_):
        print(f"serving http://127.0.0.1:{server.port}/", flush=True)

    server.start(port=port, host="127.0.0.1", open_browser=False, show_connection_info=False,
                 disable_logging=True)


if __name__ == "__main__":
    main(int(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3]))
