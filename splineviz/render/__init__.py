"""Rendering with VTK/pyvista (no Qt): ray-cast spline isosurfaces composited with meshes.

* :mod:`splineviz.render.quad` -- the screen quad that shows a frame with exact depth;
* :mod:`splineviz.render.isosurface` -- :class:`IsosurfaceLayer`, the frames of one
  isosurface node (it reads the node);
* :mod:`splineviz.render.scene` -- :class:`SplineScene` and :func:`offscreen_screenshot`;
* :mod:`splineviz.render.scene_view` -- :class:`SceneView`, a scene model in a plotter
  (one view class per node type) and :func:`render_scene`.
"""
