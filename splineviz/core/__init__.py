"""Pure NumPy/SciPy mathematics: Bernstein-Bezier forms, partitions, splines, data model.

Nothing in this package imports Qt, VTK or OpenCL (checked by an import-linter contract).
"""

from splineviz.core import chunked  # noqa: F401  (defines Volume.from_dask)
