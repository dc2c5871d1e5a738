"""The scene's interactive view in a web browser (``splineviz serve``, ``scene.show()``).

* :mod:`splineviz.web.view` -- :class:`RemoteView`: previews and exact frames of a scene
  model from an off-screen plotter, orbit, zoom and the page's controls;
* :mod:`splineviz.web.server` -- :class:`ViewServer`: the page and its websocket (aiohttp)
  on 127.0.0.1.
"""
