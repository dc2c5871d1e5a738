"""``splineviz bench dvr``: direct volume rendering against VTK's volume mappers, in one run.

Quality: Marschner-Lobb sampled at 41^3, one fixed transfer function, shaded (Phong
headlight) and unshaded; a reference image integrating the same transfer function (its exact
points, not the table) along the same rays over the analytic function with a step
``REF_FACTOR`` times finer; the RMSE of every image (RGB in [0, 1], composited on black)
against it, for each spline model and for ``vtkFixedPointVolumeRayCastMapper`` and
``vtkGPUVolumeRayCastMapper`` (same transfer function, camera, sample distance and opacity
unit distance; offscreen through EGL), and the RMSE of the reconstructions themselves against
the function (what bounds the images' errors). Speed: bonsai 256^3 and its 512^3 resample at
the frame size and twice its side, trilinear and cubic-c1 against the faster VTK mapper
(median of ``repeats`` frames after a first one), a preview while moving.
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


def speed(data, spacing, size=(512, 512), step: float = 0.5, repeats: int = 3, device=None,
          out_dir=None, label: str = "bonsai", log=print) -> list[dict]:
    """Frame times of one volume (bonsai or its resample), shaded, CT-bone preset on its range.

    Parameters
    ----------
    data : (nx, ny, nz) array
    spacing : (3,) float
    size : (width, height) of the frames

    Returns
    -------
    list of dict: ``renderer``, ``first_s``, ``frame_s`` (median of ``repeats`` after the
    first), ``note`` ("preview" for the preview row)
    """
    from splineviz.core.transfer_function import preset

    vol = Volume(data, spacing=spacing)
    tf = preset("ct-bone", (float(np.min(data)), float(np.max(data))))
    cam = default_camera(vol.bounds)
    w, h = size
    tag = f"{label}_{w}x{h}"
    rows = []
    for model, pre in (("trilinear", False), ("cubic-c1", False), ("cubic-c1", True)):
        vr = VolumeRenderer(vol, model, tf, device=device, step=step, shaded=True,
                            preintegrated=pre)
        frame, first, median = _timed(lambda vr=vr: vr.render(cam, size), repeats)
        name = model + ("+pre" if pre else "")
        rows.append({"renderer": name, "first_s": first, "frame_s": median})
        if out_dir:
            _save(Path(out_dir) / f"{tag}_{name}.png", frame.color[..., :3] / 255.0)
        if model == "trilinear":
            # a preview while moving as the live view casts one: its model is trilinear
            # (render/volume_layer.py PREVIEW_MODEL), a quarter of the side
            preview = (max(w // 4, 1), max(h // 4, 1))
            _, first, median = _timed(lambda vr=vr, p=preview: vr.render(cam, p), repeats)
            rows.append({"renderer": f"trilinear preview {preview[0]}x{preview[1]}",
                         "first_s": first, "frame_s": median, "note": "preview"})
        del vr
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
            _save(Path(out_dir) / f"{tag}_vtk-{mapper}.png", image)
        del vv
    return rows


def field_errors(ns=(41, 81), models=MODELS + ("to-quadratic",), points: int = 100_000,
                 seed: int = 0) -> list[dict]:
    """RMSE of each model's value and gradient against Marschner-Lobb at random points of
    the inner region (r <= :data:`ML_INNER`), for the sample counts ``ns`` per axis: what the
    reconstruction itself gives the images (trilinear is VTK's mappers' reconstruction).
    Rows ``bspline-3`` and ``bspline-5`` (values only): scipy's prefiltered cubic and quintic
    B-spline interpolation of the same samples, what a near-ideal reconstruction reaches."""
    from scipy.ndimage import map_coordinates

    from splineviz.core.splines import build_spline

    rng = np.random.default_rng(seed)
    rows = []
    for n in ns:
        vol = Volume.from_function(ml, (n, n, n), ml.domain)
        lo, hi = np.array(vol.bounds).T
        p = lo + (hi - lo) * rng.random((points, 3))
        p = p[np.hypot(p[:, 0], p[:, 1]) <= ML_INNER]
        v, g = ml_value_gradient(p)
        for model in models:
            sv, sg = build_spline(vol, model).value_gradient(p)
            rows.append({"n": n, "model": model, "value_rmse": rmse(sv, v),
                         "gradient_rmse": float(np.sqrt(np.mean(np.sum((sg - g) ** 2,
                                                                        axis=1))))})
        index = ((p - lo) / np.asarray(vol.spacing)).T
        for order in (3, 5):
            sv = map_coordinates(np.asarray(vol.data, np.float64), index, order=order,
                                 mode="nearest")
            rows.append({"n": n, "model": f"bspline-{order}", "value_rmse": rmse(sv, v),
                         "gradient_rmse": None})
    return rows


def run_dvr_bench(data_dir, size=(512, 512), step: float = 0.5, repeats: int = 3,
                  device=None, out_dir=None, volume_sizes=(256, 512)) -> dict:
    """Both parts, printed as tables; returns their rows.

    Quality at ``size``; speed on bonsai at each of ``volume_sizes`` (256: the file, larger:
    its linear resample) at ``size`` and twice its side."""
    import resource

    from splineviz.bench.isovalue import bonsai_volume

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
    fe = field_errors()
    print("\nthe reconstruction alone: RMSE against Marschner-Lobb, r <= "
          f"{ML_INNER} (trilinear = VTK's)")
    print(f"{'n':>4} {'model':<16} {'value':>9} {'gradient':>9}")
    for r in fe:
        grad = "-" if r["gradient_rmse"] is None else f"{r['gradient_rmse']:.2e}"
        print(f"{r['n']:>4} {r['model']:<16} {r['value_rmse']:>9.2e} {grad:>9}")
    s = []
    bonsai = Path(data_dir) / "bonsai.vti"
    if not bonsai.exists():
        print(f"\n{bonsai} not found: speed part skipped")
    for n in volume_sizes if bonsai.exists() else ():
        data, spacing = bonsai_volume(data_dir, n)
        for fw, fh in ((w, h), (2 * w, 2 * h)):
            print(f"\nbonsai {n}^3{'' if n == 256 else ' (resampled)'}, {fw}x{fh}, shaded, "
                  f"ct-bone preset (median of {repeats})")
            rows = speed(data, spacing, (fw, fh), step, repeats, device, out_dir,
                         label=f"bonsai{n}")
            print(f"{'renderer':<26} {'first s':>8} {'frame s':>8}  note")
            for r in rows:
                f = "-" if r["frame_s"] is None else f"{r['frame_s']:.3f}"
                f0 = "-" if r["first_s"] is None else f"{r['first_s']:.3f}"
                print(f"{r['renderer']:<26} {f0:>8} {f:>8}  {r.get('note', '')}")
            vtk = [r["frame_s"] for r in rows if r["renderer"].startswith("vtk")
                   and r["frame_s"] is not None and not r.get("note")]
            if vtk:
                for r in rows:
                    if not r["renderer"].startswith("vtk") and not r.get("note"):
                        target = {"trilinear": " (target <= 1.0)",
                                  "cubic-c1": " (target <= 2.0)"}.get(r["renderer"], "")
                        print(f"{r['renderer']} / fastest VTK = "
                              f"{r['frame_s'] / min(vtk):.2f}x{target}")
            for r in rows:
                if r.get("note") == "preview":
                    print(f"preview while moving: {r['frame_s'] * 1000:.0f} ms (target <= 100)")
            s += [{**r, "n": n, "size": (fw, fh)} for r in rows]
        del data
    print(f"\npeak RSS {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024:.0f} MiB")
    return {"quality": q, "field": fe, "speed": s}
