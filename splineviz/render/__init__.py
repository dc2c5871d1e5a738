"""Rendering with VTK/pyvista (no Qt): ray-cast spline isosurfaces composited with meshes.

* :mod:`splineviz.render.quad` -- the screen quad that shows a frame with exact depth;
* :mod:`splineviz.render.isosurface` -- :class:`IsosurfaceLayer`, one isosurface's state;
* :mod:`splineviz.render.scene` -- :class:`SplineScene` and :func:`offscreen_screenshot`.
"""
