"""The benchmarks, one module per benchmark, each printing its table with ratios against
baselines measured in the same run (``splineviz bench NAME``, :mod:`splineviz.cli.bench`):

* :mod:`~splineviz.bench.raycast`: ray casting against VTK flying edges + an offscreen render
  and the trilinear ray caster;
* :mod:`~splineviz.bench.isovalue`: one isovalue change against flying edges + a render of
  its mesh;
* :mod:`~splineviz.bench.bricks`: out-of-core ray casting on 1 against 2 dask workers;
* :mod:`~splineviz.bench.remesh`: the advancing-front mesher against Open3D Poisson, ball
  pivoting and Poisson + pymeshlab remeshing (and CGAL's jet smoothing for the projection);
* :mod:`~splineviz.bench.movie`: a movie frame (rendered, encoded beside it) against one
  still picture, at 720p, 1080p and 4K;
* :mod:`~splineviz.bench.gui`: the GUI thread's longest stall per user action against the
  100 ms budget (:mod:`~splineviz.bench.driving` plays the user's input);
* :mod:`~splineviz.bench.evaluate`, :mod:`~splineviz.bench.curvature`,
  :mod:`~splineviz.bench.spline_mesh` (``python -m splineviz.bench.NAME``): spline evaluation
  against ``map_coordinates``, curvature at the ray hits against vtkCurvatures, spline meshes
  against flying edges.

Only this package imports the peers' libraries (open3d, pymeshlab, CGAL): an import-linter
contract in ``pyproject.toml`` keeps them out of the layers the benchmarks measure.
"""
