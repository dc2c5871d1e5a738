"""OpenCL compute layer (pyopencl): device choice, cached programs and the spline ray caster.

Nothing here imports Qt or the renderer. OpenCL is imported lazily, so importing this package
works on machines without any OpenCL platform.
"""
