"""``splineviz bench dvr``: direct volume rendering against VTK's volume mappers, in one run.

Quality: Marschner-Lobb sampled at 41^3, one fixed transfer function, shaded (Phong
headlight) and unshaded; a reference image integrating the same transfer function (its exact
points, not the table) along the same rays over the analytic function with a step
``REF_FACTOR`` times finer; the RMSE of every image (RGB in [0, 1], composited on black)
against it, for each spline model and for ``vtkFixedPointVolumeRayCastMapper`` and
``vtkGPUVolumeRayCastMapper`` (same transfer function, camera, sample distance and opacity
unit distance; offscreen through EGL). Speed: bonsai 256^3 at the same frame size, trilinear
and cubic-c1 against the faster VTK mapper (median of ``repeats`` frames after a first one).
Each model is also rendered with pre-integrated segments (``+pre``). Images are written to
``out_dir`` for looking at.
"""

from __future__ import annotations

import os
import statistics
import time
from pathlib import Path

import numpy as np

from splineviz.compute.dvr import VolumeRenderer
from splineviz.core.camera import Camera, default_camera
from splineviz.core.dvr_reference import reference_dvr
from splineviz.core.raycast_reference import AMBIENT, DIFFUSE, SHININESS, SPECULAR
from splineviz.core.testfunctions import ML_ALPHA, ML_FM, ml
from splineviz.core.transfer_function import UNIT_STEP, TransferFunction
from splineviz.core.volume import Volume

MODELS = ("trilinear", "super-quadratic", "cubic-c1")
VTK_MAPPERS = ("fixed-point", "gpu")
#: the reference's step is this many times finer than the renderers'
REF_FACTOR = 10
#: inradius of the "inner" case: Marschner-Lobb's radial ripples reach the Nyquist limit of
#: 41^3 samples near r = 1 (wavelength 2 samples at the box's faces, less in its corners),
#: where no reconstruction can follow them; inside r <= 0.8 they are >= 2.5 samples long
ML_INNER = 0.8
#: the fixed transfer function on Marschner-Lobb's range [0, 1]: a cool-warm colour map and
#: an opacity tent around the classic isovalue 0.5
ML_TF = TransferFunction(
    [0.0, 0.23, 0.30, 0.75, 0.5, 0.87, 0.87, 0.87, 1.0, 0.71, 0.02, 0.15],
    [0.0, 0.0, 0.35, 0.0, 0.5, 0.6, 0.65, 0.0, 1.0, 0.0], "ml-tent")


def octagon_planes(radius: float = ML_INNER) -> list:
    """Eight clip planes keeping the octagonal prism about the z axis of inradius ``radius``.
    """
    return [((radius * np.cos(a), radius * np.sin(a), 0.0), (-np.cos(a), -np.sin(a), 0.0))
            for a in np.arange(8) * np.pi / 4]


def ml_value_gradient(points):
    """Marschner-Lobb's value and gradient in closed form: (N, 3) -> ((N,), (N, 3))."""
    x, y, z = np.asarray(points, np.float64).T
    r = np.sqrt(x * x + y * y)
    c = 2 * np.pi * ML_FM
    phase = c * np.cos(np.pi * r / 2)
    k = 1.0 / (2 * (1 + ML_ALPHA))
    v = (1 - np.sin(np.pi * z / 2) + ML_ALPHA * (1 + np.cos(phase))) * k
    drho = np.sin(phase) * c * (np.pi / 2) * np.sin(np.pi * r / 2)
    with np.errstate(invalid="ignore", divide="ignore"):
        over_r = np.where(r > 0, drho / r, 0.0)
    g = np.column_stack([ML_ALPHA * k * over_r * x, ML_ALPHA * k * over_r * y,
                         -k * (np.pi / 2) * np.cos(np.pi * z / 2)])
    return v, g


def _vtk_image(volume: Volume):
    from vtkmodules.util.numpy_support import numpy_to_vtk
    from vtkmodules.vtkCommonDataModel import vtkImageData

    img = vtkImageData()
    img.SetDimensions(*volume.shape)
    img.SetSpacing(*volume.spacing)
    img.SetOrigin(*volume.origin)
    data = np.ascontiguousarray(volume.data.ravel(order="F"))  # VTK: x varies fastest
    arr = numpy_to_vtk(data, deep=True)
    arr.SetName("v")
    img.GetPointData().SetScalars(arr)
    return img


class VTKVolume:
    """One VTK volume mapper rendering offscreen with a transfer function and a camera.

    Parameters
    ----------
    volume : Volume
    tf : TransferFunction
    mapper : "fixed-point" or "gpu"
    size : (width, height)
    step : sample distance in voxels of the smallest spacing
    shaded : bool
    clip_planes : sequence of (origin, normal), each keeping the side its normal points to
    """

    def __init__(self, volume, tf, mapper, size, step, shaded, clip_planes=()):
        if not os.environ.get("DISPLAY"):
            os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
        import vtkmodules.vtkRenderingOpenGL2  # noqa: F401  (the OpenGL backend)
        import vtkmodules.vtkRenderingVolumeOpenGL2  # noqa: F401
        from vtkmodules.vtkCommonDataModel import vtkPiecewiseFunction
        from vtkmodules.vtkRenderingCore import (
            vtkColorTransferFunction,
            vtkRenderer,
            vtkRenderWindow,
            vtkVolume,
            vtkVolumeProperty,
        )
        from vtkmodules.vtkRenderingVolume import vtkFixedPointVolumeRayCastMapper
        from vtkmodules.vtkRenderingVolumeOpenGL2 import vtkOpenGLGPUVolumeRayCastMapper

        unit = float(np.min(volume.spacing))
        ctf = vtkColorTransferFunction()
        for v, r, g, b in tf.rgb_points:
            ctf.AddRGBPoint(float(v), float(r), float(g), float(b))
        otf = vtkPiecewiseFunction()
        for v, a in tf.opacity_points:
            otf.AddPoint(float(v), float(a))
        prop = vtkVolumeProperty()
        prop.SetColor(ctf)
        prop.SetScalarOpacity(otf)
        prop.SetInterpolationTypeToLinear()
        prop.SetScalarOpacityUnitDistance(unit * UNIT_STEP)
        prop.SetShade(int(shaded))
        prop.SetAmbient(AMBIENT)
        prop.SetDiffuse(DIFFUSE)
        prop.SetSpecular(SPECULAR)
        prop.SetSpecularPower(SHININESS)
        if mapper == "fixed-point":
            m = vtkFixedPointVolumeRayCastMapper()
            m.SetImageSampleDistance(1.0)
            m.SetMinimumImageSampleDistance(1.0)
            m.SetMaximumImageSampleDistance(1.0)
        else:
            m = vtkOpenGLGPUVolumeRayCastMapper()
            m.SetUseJittering(0)
        m.SetAutoAdjustSampleDistances(0)
        m.SetSampleDistance(step * unit)
        m.SetInputData(_vtk_image(volume))
        from vtkmodules.vtkCommonDataModel import vtkPlane

        for origin, normal in clip_planes:
            plane = vtkPlane()
            plane.SetOrigin(*origin)
            plane.SetNormal(*normal)
            m.AddClippingPlane(plane)
        vol = vtkVolume()
        vol.SetMapper(m)
        vol.SetProperty(prop)
        self.renderer = vtkRenderer()
        self.renderer.AddVolume(vol)
        self.renderer.SetBackground(0, 0, 0)
        self.window = vtkRenderWindow()
        self.window.SetOffScreenRendering(1)
        self.window.AddRenderer(self.renderer)
        self.window.SetSize(*size)
        self.mapper = m

    def render(self, camera: Camera) -> np.ndarray:
        """(H, W, 3) float64 RGB in [0, 1] of one frame."""
        from vtkmodules.util.numpy_support import vtk_to_numpy
        from vtkmodules.vtkRenderingCore import vtkWindowToImageFilter

        cam = self.renderer.GetActiveCamera()
        cam.SetPosition(*camera.position)
        cam.SetFocalPoint(*camera.focal_point)
        cam.SetViewUp(*camera.view_up)
        cam.SetViewAngle(camera.view_angle)
        self.renderer.ResetCameraClippingRange()
        self.window.Render()
        grab = vtkWindowToImageFilter()
        grab.SetInput(self.window)
        grab.SetInputBufferTypeToRGB()
        grab.ReadFrontBufferOff()
        grab.Update()
        out = grab.GetOutput()
        w, h, _ = out.GetDimensions()
        rgb = vtk_to_numpy(out.GetPointData().GetScalars()).reshape(h, w, 3)[::-1]
        return rgb.astype(np.float64) / 255.0


def rmse(a: np.ndarray, b: np.ndarray) -> float:
    """Root mean square difference of two RGB images in [0, 1]."""
    return float(np.sqrt(np.mean((np.asarray(a, float) - np.asarray(b, float)) ** 2)))


def _save(path: Path, rgb: np.ndarray) -> None:
    from PIL import Image

    Image.fromarray(np.rint(np.clip(rgb, 0, 1) * 255).astype(np.uint8)).save(path)


def _timed(render, repeats: int):
    t = time.perf_counter()
    image = render()
    first = time.perf_counter() - t
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        render()
        times.append(time.perf_counter() - t)
    return image, first, statistics.median(times) if times else first


def quality(size=(512, 512), step: float = 0.5, device=None, out_dir=None, models=MODELS,
            log=print) -> list[dict]:
    """RMSE of each renderer against the analytic reference, shaded and unshaded."""
    vol = Volume.from_function(ml, (41, 41, 41), ml.domain)
    cam = default_camera(vol.bounds)
    rows = []
    for region, planes in (("cube", []), ("inner", octagon_planes())):
        for shaded in (False, True):
            rows += _quality_case(vol, cam, size, step, device, out_dir, models, log, shaded,
                                  region, planes)
    return rows


def _quality_case(vol, cam, size, step, device, out_dir, models, log, shaded, region,
                  planes) -> list[dict]:
    label = ("shaded" if shaded else "unshaded") + ("" if region == "cube" else f"-{region}")
    rows = []
    t = time.perf_counter()
    refimg = reference_dvr(ml_value_gradient, vol.bounds, vol.spacing, cam, size, ML_TF,
                           step / REF_FACTOR, shaded, clip_planes=planes, exact_tf=True)
    log(f"reference ({label}, step {step / REF_FACTOR:g} voxels): "
        f"{time.perf_counter() - t:.1f} s")
    want = refimg.color[..., :3] / 255.0
    if out_dir:
        _save(Path(out_dir) / f"ml_{label}_reference.png", want)
    for model in models:
        for pre in (False, True):
            vr = VolumeRenderer(vol, model, ML_TF, device=device, step=step, shaded=shaded,
                                preintegrated=pre)
            got = vr.render(cam, size, clip_planes=planes).color[..., :3] / 255.0
            name = model + ("+pre" if pre else "")
            rows.append({"case": label, "renderer": name, "rmse": rmse(got, want)})
            if out_dir:
                _save(Path(out_dir) / f"ml_{label}_{name}.png", got)
    for mapper in VTK_MAPPERS:
        try:
            got = VTKVolume(vol, ML_TF, mapper, size, step, shaded, planes).render(cam)
        except Exception as exc:  # noqa: BLE001  (a peer that cannot run is reported)
            rows.append({"case": label, "renderer": f"vtk-{mapper}", "rmse": None,
                         "note": f"{type(exc).__name__}: {exc}"})
            continue
        note = "blank image" if got.max() == 0 else ""
        rows.append({"case": label, "renderer": f"vtk-{mapper}", "rmse": rmse(got, want),
                     "note": note})
        if out_dir:
            _save(Path(out_dir) / f"ml_{label}_vtk-{mapper}.png", got)
    return rows


def speed(path, size=(512, 512), step: float = 0.5, repeats: int = 3, device=None,
          out_dir=None, log=print) -> list[dict]:
    """Frame times on a real volume (bonsai), shaded, CT-bone-like preset on its range."""
    import pyvista as pv

    from splineviz.core.transfer_function import preset

    img = pv.read(str(path))
    data = np.asarray(img.point_data.active_scalars).reshape(img.dimensions, order="F")
    vol = Volume(data, spacing=img.spacing, origin=img.origin)
    tf = preset("ct-bone", (float(data.min()), float(data.max())))
    cam = default_camera(vol.bounds)
    rows = []
    for model, pre in (("trilinear", False), ("cubic-c1", False), ("cubic-c1", True)):
        vr = VolumeRenderer(vol, model, tf, device=device, step=step, shaded=True,
                            preintegrated=pre)
        frame, first, median = _timed(lambda vr=vr: vr.render(cam, size), repeats)
        name = model + ("+pre" if pre else "")
        rows.append({"renderer": name, "first_s": first, "frame_s": median})
        if out_dir:
            _save(Path(out_dir) / f"bonsai_{name}.png", frame.color[..., :3] / 255.0)
    # a preview while moving: a quarter of the frame's side, the trilinear model
    w, h = size
    preview = (max(w // 4, 1), max(h // 4, 1))
    vr = VolumeRenderer(vol, "trilinear", tf, device=device, step=step, shaded=True)
    _, first, median = _timed(lambda: vr.render(cam, preview), repeats)
    rows.append({"renderer": f"trilinear preview {preview[0]}x{preview[1]}", "first_s": first,
                 "frame_s": median, "note": "preview"})
    for mapper in VTK_MAPPERS:
        try:
            vv = VTKVolume(vol, tf, mapper, size, step, True)
            image, first, median = _timed(lambda vv=vv: vv.render(cam), repeats)
        except Exception as exc:  # noqa: BLE001  (a peer that cannot run is reported)
            rows.append({"renderer": f"vtk-{mapper}", "first_s": None, "frame_s": None,
                         "note": f"{type(exc).__name__}: {exc}"})
            continue
        rows.append({"renderer": f"vtk-{mapper}", "first_s": first, "frame_s": median,
                     "note": "blank image" if image.max() == 0 else ""})
        if out_dir:
            _save(Path(out_dir) / f"bonsai_vtk-{mapper}.png", image)
    return rows


def run_dvr_bench(data_dir, size=(512, 512), step: float = 0.5, repeats: int = 3,
                  device=None, out_dir=None) -> dict:
    """Both parts, printed as tables; returns their rows."""
    import resource

    if out_dir:
        Path(out_dir).mkdir(parents=True, exist_ok=True)
    w, h = size
    print(f"Marschner-Lobb 41^3, {w}x{h}, step {step} voxels, RMSE vs analytic reference")
    q = quality(size, step, device, out_dir)
    print(f"{'case':<10} {'renderer':<18} {'RMSE':>8}  note")
    for r in q:
        val = "-" if r["rmse"] is None else f"{r['rmse']:.4f}"
        print(f"{r['case']:<10} {r['renderer']:<18} {val:>8}  {r.get('note', '')}")
    for case in dict.fromkeys(r["case"] for r in q):
        vtk = [r["rmse"] for r in q if r["case"] == case and r["renderer"].startswith("vtk")
               and r["rmse"] is not None and not r.get("note")]
        c1 = [r["rmse"] for r in q if r["case"] == case and r["renderer"] == "cubic-c1"]
        if vtk and c1:
            print(f"{case}: cubic-c1 / best VTK = {c1[0] / min(vtk):.3f} (target <= 0.333)")
    s = []
    bonsai = Path(data_dir) / "bonsai.vti"
    if bonsai.exists():
        print(f"\nbonsai 256^3, {w}x{h}, shaded, ct-bone preset (median of {repeats})")
        s = speed(bonsai, size, step, repeats, device, out_dir)
        print(f"{'renderer':<18} {'first s':>8} {'frame s':>8}  note")
        for r in s:
            f = "-" if r["frame_s"] is None else f"{r['frame_s']:.3f}"
            f0 = "-" if r["first_s"] is None else f"{r['first_s']:.3f}"
            print(f"{r['renderer']:<18} {f0:>8} {f:>8}  {r.get('note', '')}")
        vtk = [r["frame_s"] for r in s if r["renderer"].startswith("vtk")
               and r["frame_s"] is not None and not r.get("note")]
        if vtk:
            for r in s:
                if not r["renderer"].startswith("vtk") and not r.get("note"):
                    print(f"{r['renderer']} / fastest VTK = {r['frame_s'] / min(vtk):.2f}x")
    else:
        print(f"\n{bonsai} not found: speed part skipped")
    print(f"peak RSS {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024:.0f} MiB")
    return {"quality": q, "speed": s}
