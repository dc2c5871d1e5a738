"""Hybrid cell projection / ray casting of tetrahedral spline isosurfaces (type-6:
super-quadratic, cubic-c1; truncated octahedra: to-quadratic) in VTK's OpenGL pipeline
(thesis §6.1).

The relevant tetrahedra (:mod:`splineviz.core.relevant_tets`) are drawn as one point each, from
which a geometry program emits the tet's four faces; the rasteriser finds the pixels each tet
covers and a fragment program intersects that pixel's ray with the tet's B-form patch
(``cell_projection.frag.glsl``): the ray is cut to the tet and the data box, the patch
restricted to the segment is a univariate Bernstein polynomial whose coefficients are
blossoms of the segment's ends, its first root is found, the hit is shaded (headlight Phong,
as the ray casters) and ``gl_FragDepth`` is written, so the surface composites exactly with
every other prop of the scene.

Per-tet data travel as vertex attributes, not textures: float textures reached shaders
quantised to 8 bits on Mesa/llvmpipe (ENVIRONMENT.md), vertex attributes keep float32. The
point of a tet is its cell's centre and carries its generic tet (``tet``) and B-coefficients
(``coef0..``); what is the same for every tet of an orientation is stored once, in uniform
tables of the partition's generic tets (:func:`generic_tables`: vertices, outward faces and
the barycentric gradients in world units, the columns of ``M_T`` scaled by the spacing), as
the thesis' instancing by orientation (Fig. 6.6) stores the geometry once. A cubic tet takes
24 floats, where four points of its own with their barycentric coordinates and gradients
took 156 (the memory that bounds the largest surfaces drawn). Only the outward faces facing
the eye are drawn (back-face culling): a ray enters a convex tet through exactly one front
face.

Deviation from the thesis: one draw of all relevant tets whose faces a geometry program
emits, not one instanced draw per generic orientation (Fig. 6.6); VTK's poly data mapper has
no instancing hook. The fragment work is the thesis'.

Conventions: world coordinates ``origin + index * spacing``; the depth is OpenGL window depth
of VTK's projection, as :meth:`splineviz.core.camera.Camera.window_depth` for the same
clipping range.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache
from pathlib import Path

import numpy as np
import vtk
from vtk.util import numpy_support

from splineviz.core import bform
from splineviz.core.camera import Camera, parse_size
from splineviz.core.material import BACK_COLOR, DEFAULT_MATERIAL, FRONT_COLOR, MATERIALS, Material
from splineviz.core.raycast_reference import BACKGROUND, ClipPlaneError, normalize_clip_planes
from splineviz.core.relevant_tets import PARTITIONS, RelevantTets, partition_of, relevant_tets

_HERE = Path(__file__).parent

#: clip planes the fragment program takes (uniforms clipPlane0..)
MAX_CLIP_PLANES = 6


def _vec4_count(degree: int) -> int:
    return -(-bform.n_coefficients(degree) // 4)


def _blossom_glsl(degree: int) -> str:
    """GLSL ``blossom(c, a_1, .., a_d)`` unrolled from the de Casteljau reduction tables, and
    ``blossom1(c, x, u)`` = b(x, .., x, u)."""
    args = [f"a{k}" for k in range(1, degree + 1)]
    lines = [f"float blossom(float c[NCOEF], {', '.join('vec4 ' + a for a in args)})", "{"]
    prev = [f"c[{i}]" for i in range(bform.n_coefficients(degree))]
    for step, k in enumerate(range(degree, 0, -1), start=1):
        table = bform._reduction_table(k)
        cur = []
        for i, row in enumerate(table):
            name = f"s{step}_{i}"
            lines.append(f"  float {name} = dot({args[step - 1]}, vec4("
                         f"{', '.join(prev[int(j)] for j in row)}));")
            cur.append(name)
        prev = cur
    lines += [f"  return {prev[0]};", "}", "",
              "float blossom1(float c[NCOEF], vec4 x, vec4 u)", "{",
              f"  return blossom(c, {', '.join(['x'] * (degree - 1) + ['u'])});", "}"]
    return "\n".join(lines)


@cache
def shader_sources(degree: int, partition: str = "type6") -> tuple[str, str, str]:
    """(vertex, geometry, fragment) GLSL of the cell projection for B-forms of ``degree``
    (2 or 3) on ``partition`` (a :data:`~splineviz.core.relevant_tets.PARTITIONS` key)."""
    nv = _vec4_count(degree)
    ncoef = bform.n_coefficients(degree)
    vert = (_HERE / "cell_projection.vert.glsl").read_text()
    vert = vert.replace("//CELLPROJ::CoefIn", "\n".join(f"in vec4 coef{i};" for i in range(nv)))
    vert = vert.replace("//CELLPROJ::CoefOut",
                        "\n".join(f"flat out vec4 coefGS{i};" for i in range(nv)))
    vert = vert.replace("//CELLPROJ::CoefCopy",
                        "\n".join(f"  coefGS{i} = coef{i};" for i in range(nv)))
    geom = (_HERE / "cell_projection.geom.glsl").read_text()
    geom = geom.replace("//VTK::System::Dec", "//VTK::System::Dec\n#define NGENERIC "
                        f"{len(PARTITIONS[partition][0]())}")
    geom = geom.replace("//CELLPROJ::CoefGSIn",
                        "\n".join(f"flat in vec4 coefGS{i}[];" for i in range(nv)))
    geom = geom.replace("//CELLPROJ::CoefOut",
                        "\n".join(f"flat out vec4 coefVS{i};" for i in range(nv)))
    geom = geom.replace("//CELLPROJ::CoefCopy",
                        "\n".join(f"      coefVS{i} = coefGS{i}[0];" for i in range(nv)))
    frag = (_HERE / "cell_projection.frag.glsl").read_text()
    frag = frag.replace("//VTK::System::Dec",
                        f"//VTK::System::Dec\n#extension GL_ARB_sample_shading : enable\n"
                        f"#define DEGREE {degree}\n#define NCOEF {ncoef}")
    frag = frag.replace("//CELLPROJ::CoefIn",
                        "\n".join(f"flat in vec4 coefVS{i};" for i in range(nv)))
    frag = frag.replace("//CELLPROJ::CoefUnpack", "\n".join(
        f"  c[{i}] = coefVS{i // 4}[{i % 4}];" for i in range(ncoef)))
    frag = frag.replace("//CELLPROJ::Blossom", _blossom_glsl(degree))
    seg = []
    for k in range(degree + 1):
        seg.append(f"  b[{k}] = blossom(c, {', '.join(['p0'] * (degree - k) + ['p1'] * k)});")
    frag = frag.replace("//CELLPROJ::Segment", "\n".join(seg))
    return vert, geom, frag


@cache
def _outward_faces(partition: str) -> np.ndarray:
    """(T, 4, 3) vertex indices of the four faces of each generic tet of ``partition`` (a
    :data:`~splineviz.core.relevant_tets.PARTITIONS` key), counter-clockwise seen from
    outside (OpenGL front faces)."""
    generic = PARTITIONS[partition][0]()
    out = np.empty((len(generic), 4, 3), np.int64)
    for t, v in enumerate(generic):
        for m in range(4):
            face = [i for i in range(4) if i != m]
            a, b, c = v[face]
            if np.dot(np.cross(b - a, c - a), a - v[m]) < 0:
                face = [face[0], face[2], face[1]]
            out[t, m] = face
    return out


def tets_polydata(tets: RelevantTets, origin, spacing, isovalue: float) -> vtk.vtkPolyData:
    """The relevant tets as points with the attributes of the shaders.

    Parameters
    ----------
    tets : RelevantTets with N tets
    origin, spacing : (3,) world origin and spacing of the volume
    isovalue : float, subtracted from the coefficients in float64 before they are rounded
        to float32 (the roots of ``p - iso`` then keep the coefficients' relative precision;
        subtracting in the shader cost up to 7e-5 in depth on grazing rays)

    Returns
    -------
    vtkPolyData with N points (the world centres of the tets' cells), N vertex cells (32-bit
    ids) and float32 point arrays ``tet`` (1: the generic tet, see :func:`generic_tables`)
    and ``coef0..`` (4 each: the coefficients of ``p - isovalue``, zero-padded to whole
    vec4s).
    """
    n = len(tets)
    centres = np.asarray(tets.cube, np.float64) * np.asarray(spacing, np.float64) \
        + np.asarray(origin, np.float64)
    poly = vtk.vtkPolyData()
    vpts = vtk.vtkPoints()
    vpts.SetData(numpy_support.numpy_to_vtk(centres.astype(np.float32), deep=True))
    poly.SetPoints(vpts)
    cells = vtk.vtkCellArray()
    # 32-bit ids while they fit: half the memory of VTK's 64-bit ones
    ids = np.int32 if n < 2**31 else np.int64
    cells.SetData(numpy_support.numpy_to_vtk(np.arange(n + 1, dtype=ids), deep=True),
                  numpy_support.numpy_to_vtk(np.arange(n, dtype=ids), deep=True))
    poly.SetVerts(cells)

    def add(name, values):
        arr = numpy_support.numpy_to_vtk(np.ascontiguousarray(values, dtype=np.float32),
                                         deep=True)
        arr.SetName(name)
        poly.GetPointData().AddArray(arr)

    add("tet", tets.tet)
    nv = _vec4_count(tets.degree)
    coef = np.zeros((n, 4 * nv), np.float32)
    coef[:, :tets.coeffs.shape[1]] = tets.coeffs - float(isovalue)
    for i in range(nv):
        add(f"coef{i}", coef[:, 4 * i:4 * i + 4])
    return poly


def generic_tables(partition: str, spacing) -> dict[str, np.ndarray]:
    """The geometry shader's tables of the generic tets of ``partition``, each (T * 12,):

    * ``tetGrad`` float32: per generic tet ``t`` the world gradients of its barycentric
      coordinates, d lam_m / dx (m = 0..3), then / dy, then / dz (``M[m, a] / spacing[a]``);
    * ``tetVert`` float32: its vertices 0..3 relative to the cell centre, world units;
    * ``tetFace`` int32: the vertex slots of its four faces, outward counter-clockwise.
    """
    spacing = np.asarray(spacing, np.float64)
    grads = PARTITIONS[partition][1]()[:, :, :3] / spacing
    verts = PARTITIONS[partition][0]() * spacing
    return {"tetGrad": np.ascontiguousarray(grads.transpose(0, 2, 1), np.float32).ravel(),
            "tetVert": np.ascontiguousarray(verts, np.float32).ravel(),
            "tetFace": np.ascontiguousarray(_outward_faces(partition), np.int32).ravel()}


@dataclass(frozen=True, eq=False)
class CellGeometry:
    """The relevant tets of one isovalue of a spline as the shaders draw them.

    Attributes
    ----------
    spline : Type6Spline or TOQuadraticSpline
    isovalue : float
    tets : RelevantTets
    polydata : vtkPolyData
        :func:`tets_polydata` of ``tets`` (several views' actors may draw it).
    """

    spline: object
    isovalue: float
    tets: RelevantTets
    polydata: vtk.vtkPolyData


def cell_geometry(spline, isovalue: float) -> CellGeometry:
    """Classify the tets of ``spline`` for ``isovalue`` and lay them out for the shaders
    (NumPy and a new vtkPolyData only: may run in a worker thread)."""
    isovalue = float(isovalue)
    tets = relevant_tets(spline, isovalue)
    vol = spline.volume
    return CellGeometry(spline, isovalue, tets,
                        tets_polydata(tets, vol.origin, vol.spacing, isovalue))


class CellProjectionLayer:
    """A VTK actor that draws one isosurface of a type-6 spline by cell projection.

    Parameters
    ----------
    spline : Type6Spline (``"super-quadratic"``, ``"cubic-c1"``) or TOQuadraticSpline
    isovalue : float or None
        None: nothing is drawn until :meth:`set_geometry`.
    """

    def __init__(self, spline, isovalue: float | None):
        self.spline = spline
        self.actor, self._mapper, main = self._make_actor(spline)
        #: the depth pre-pass of a translucent surface (drawn just before :attr:`actor`,
        #: shown while the opacity is below 1): the same fragments with alpha 0 write only
        #: the nearest hit's depth, so the colour pass blends that hit alone, as a ray
        #: caster's frame does, instead of every fold of the surface in the order the tets
        #: happen to be drawn
        self.depth_actor, self._depth_mapper, depth = self._make_actor(spline)
        self.depth_actor.VisibilityOff()
        self._uniforms = main
        self._both = (main, depth)
        self._visible = True
        self._opacity = 1.0
        lo, hi = np.asarray(spline.bounds, dtype=np.float64).T
        for u in self._both:
            u.SetUniform3f("boxMin", tuple(float(v) for v in lo))
            u.SetUniform3f("boxMax", tuple(float(v) for v in hi))
        for u in self._both:
            u.SetUniformi("normalOutput", 0)
        self.set_material()
        self.set_appearance(FRONT_COLOR, 1.0, BACK_COLOR)
        self.set_clip_planes(())
        self.tets: RelevantTets | None = None
        self.geometry: CellGeometry | None = None
        self.isovalue = None
        if isovalue is not None:
            self.set_isovalue(isovalue)

    @staticmethod
    def _make_actor(spline):
        """(actor, mapper, fragment uniforms) drawing the tets with the shaders."""
        actor = vtk.vtkActor()
        mapper = vtk.vtkOpenGLPolyDataMapper()
        # positions reach the shaders as world coordinates: the fragment program projects
        # the hit with MCDCMatrix, which a VBO shift and scale would not match
        mapper.SetVBOShiftScaleMethod(vtk.vtkOpenGLPolyDataMapper.DISABLE_SHIFT_SCALE)
        mapper.ScalarVisibilityOff()
        actor.SetMapper(mapper)
        actor.GetProperty().BackfaceCullingOn()
        # drawn in the opaque pass whatever the opacity (VTK would leave a translucent
        # prop to its translucent pass, unordered against the scene's other surfaces);
        # the shader's alpha blends it over what is drawn before it
        actor.ForceOpaqueOn()
        actor.SetPickable(False)
        partition = partition_of(spline)
        vert, geom, frag = shader_sources(spline.degree, partition)
        sp = actor.GetShaderProperty()
        sp.SetVertexShaderCode(vert)
        sp.SetGeometryShaderCode(geom)
        sp.SetFragmentShaderCode(frag)
        uniforms = sp.GetGeometryCustomUniforms()
        for name, table in generic_tables(partition, spline.volume.spacing).items():
            if table.dtype == np.int32:
                uniforms.SetUniform1iv(name, len(table), table.tolist())
            else:
                uniforms.SetUniform1fv(name, len(table), table.tolist())
        assoc = vtk.vtkDataObject.FIELD_ASSOCIATION_POINTS
        names = ["tet"] + [f"coef{i}" for i in range(_vec4_count(spline.degree))]
        for name in names:
            mapper.MapDataArrayToVertexAttribute(name, name, assoc, -1)
        return actor, mapper, sp.GetFragmentCustomUniforms()

    @property
    def actors(self) -> tuple:
        """(depth pre-pass actor, colour actor), in the order they must be drawn."""
        return self.depth_actor, self.actor

    def set_isovalue(self, isovalue: float) -> None:
        """Classify the tets for ``isovalue`` and upload them."""
        self.set_geometry(cell_geometry(self.spline, isovalue))

    def set_geometry(self, geometry: CellGeometry) -> None:
        """Draw the tets of ``geometry`` (made by :func:`cell_geometry` of this layer's
        spline, e.g. in a worker)."""
        self.geometry = geometry
        self.isovalue = geometry.isovalue
        self.tets = geometry.tets
        self._mapper.SetInputData(geometry.polydata)
        self._depth_mapper.SetInputData(geometry.polydata)

    def set_normal_output(self, flag: bool) -> None:
        """Draw the surface's unit normals in view coordinates, packed as
        :func:`splineviz.render.quad.view_normals` packs them, instead of its colours
        (opaque: the nearest hit wins the depth test)."""
        self._uniforms.SetUniformi("normalOutput", int(bool(flag)))

    def set_visible(self, visible: bool) -> None:
        """Show or hide the surface (both actors)."""
        self._visible = bool(visible)
        self.actor.SetVisibility(self._visible)
        self.depth_actor.SetVisibility(self._visible and self._opacity < 1.0)

    def set_clip_planes(self, planes) -> None:
        """Cut the surface exactly at up to :data:`MAX_CLIP_PLANES` planes, each an (origin,
        normal) pair keeping the side its normal points to (as the ray casters)."""
        arr = normalize_clip_planes(planes)
        if len(arr) > MAX_CLIP_PLANES:
            raise ClipPlaneError(f"cell projection takes at most {MAX_CLIP_PLANES} clip planes, "
                                 f"got {len(arr)}")
        for u in self._both:
            u.SetUniformi("clipCount", len(arr))
            for i in range(MAX_CLIP_PLANES):
                if i < len(arr):
                    o, n = arr[i]
                    plane = (*(float(v) for v in n), -float(np.dot(o, n)))
                else:
                    plane = (0.0, 0.0, 0.0, 0.0)
                u.SetUniform4f(f"clipPlane{i}", plane)

    def set_material(self, material: Material = MATERIALS[DEFAULT_MATERIAL]) -> None:
        """Phong constants of the headlight model."""
        for u in self._both:
            u.SetUniformf("ambientK", float(material.ambient))
            u.SetUniformf("diffuseK", float(material.diffuse))
            u.SetUniformf("specularK", float(material.specular))
            u.SetUniformf("shininess", float(max(material.shininess, 1.0)))

    def set_appearance(self, color, opacity: float, back_color=BACK_COLOR) -> None:
        """Front and back colours (RGB in [0, 1]) and opacity of the surface."""
        self._opacity = float(opacity)
        for u, alpha in zip(self._both, (self._opacity, 0.0), strict=True):
            u.SetUniform3f("frontColor", tuple(float(c) for c in color))
            u.SetUniform3f("backColor", tuple(float(c) for c in back_color))
            u.SetUniformf("surfaceOpacity", alpha)
        self.set_visible(self._visible)


def trilinear_mesh(volume, isovalue: float) -> vtk.vtkPolyData:
    """Flying-edges triangles of the samples' trilinear isosurface at ``isovalue`` (world
    coordinates of an axis-aligned volume, gradient normals): the stand-in of a cell-projected
    surface while the camera moves (:class:`ProxySurface`), as the trilinear kernel previews
    the ray caster's smooth models (thesis §6.3)."""
    img = vtk.vtkImageData()
    img.SetDimensions(*volume.data.shape)
    img.SetSpacing(*(float(v) for v in volume.spacing))
    img.SetOrigin(*(float(v) for v in volume.origin))
    values = np.ascontiguousarray(np.asarray(volume.data, dtype=np.float32).ravel(order="F"))
    img.GetPointData().SetScalars(numpy_support.numpy_to_vtk(values, deep=True))
    fe = vtk.vtkFlyingEdges3D()
    fe.SetInputData(img)
    fe.SetValue(0, float(isovalue))
    fe.ComputeNormalsOn()
    fe.ComputeScalarsOff()
    fe.Update()
    out = vtk.vtkPolyData()
    out.ShallowCopy(fe.GetOutput())
    return out


class ProxySurface:
    """A plain VTK mesh actor that stands in for a cell-projected surface while the camera
    moves and a cell-projected frame takes longer than the view's budget (software OpenGL:
    0.3-1 s for the 41^3 default data): a :func:`trilinear_mesh`, in the surface's colour,
    material and opacity, cut by its clip planes (VTK's clipping keeps the side a plane's
    normal points to, as the ray casters)."""

    def __init__(self):
        self.actor = vtk.vtkActor()
        self._mapper = vtk.vtkPolyDataMapper()
        self._mapper.ScalarVisibilityOff()
        self.actor.SetMapper(self._mapper)
        self.actor.SetPickable(False)
        self.actor.SetUseBounds(False)
        self.actor.VisibilityOff()
        self.mesh = None

    def set_mesh(self, mesh: vtk.vtkPolyData) -> None:
        self.mesh = mesh
        self._mapper.SetInputData(mesh)

    def set_appearance(self, color, opacity: float, material: Material) -> None:
        prop = self.actor.GetProperty()
        prop.SetColor(*(float(c) for c in color))
        prop.SetOpacity(float(opacity))
        prop.SetAmbient(float(material.ambient))
        prop.SetDiffuse(float(material.diffuse))
        prop.SetSpecular(float(material.specular))
        prop.SetSpecularPower(float(max(material.shininess, 1.0)))
        prop.SetBackfaceCulling(False)
        self.actor.SetBackfaceProperty(_back_property(material))

    def set_clip_planes(self, planes) -> None:
        self._mapper.RemoveAllClippingPlanes()
        for o, n in normalize_clip_planes(planes):
            plane = vtk.vtkPlane()
            plane.SetOrigin(*(float(v) for v in o))
            plane.SetNormal(*(float(v) for v in n))
            self._mapper.AddClippingPlane(plane)


def _back_property(material: Material) -> vtk.vtkProperty:
    """The inside of a proxy seen through a cut, in the back colour as the ray casters."""
    back = vtk.vtkProperty()
    back.SetColor(*BACK_COLOR)
    back.SetAmbient(float(material.ambient))
    back.SetDiffuse(float(material.diffuse))
    back.SetSpecular(float(material.specular))
    back.SetSpecularPower(float(max(material.shininess, 1.0)))
    return back


class OffscreenCellProjection:
    """An off-screen window drawing one cell-projection layer, for many frames.

    Parameters
    ----------
    layer : CellProjectionLayer
    size : (width, height) or "WxH"
    """

    def __init__(self, layer: CellProjectionLayer, size):
        self.layer = layer
        self.size = parse_size(size)
        self._ren = vtk.vtkRenderer()
        self._ren.SetBackground(*BACKGROUND)
        for actor in layer.actors:
            self._ren.AddActor(actor)
        #: the vtkRenderer, to add other props (they composite by depth with the surface)
        self.renderer = self._ren
        self._win = vtk.vtkRenderWindow()
        self._win.SetOffScreenRendering(True)
        self._win.SetSize(*self.size)
        self._win.SetMultiSamples(0)
        self._win.AddRenderer(self._ren)

    def render(self, camera: Camera):
        """One frame from ``camera`` (its clipping range, or the one fitted to the data box,
        as the ray casters use).

        Returns
        -------
        color : (H, W, 3) uint8, row 0 at the top
        depth : (H, W) float32 OpenGL window depth, 1 where nothing was drawn
        """
        w, h = self.size
        cam = self._ren.GetActiveCamera()
        cam.SetPosition(*camera.position)
        cam.SetFocalPoint(*camera.focal_point)
        cam.SetViewUp(*camera.view_up)
        cam.SetViewAngle(camera.view_angle)
        cam.SetClippingRange(*camera.fit_clipping_range(self.layer.spline.bounds))
        self._win.Render()
        rgba = vtk.vtkUnsignedCharArray()
        self._win.GetRGBACharPixelData(0, 0, w - 1, h - 1, 0, rgba, 0)
        color = numpy_support.vtk_to_numpy(rgba).reshape(h, w, 4)[::-1, :, :3].copy()
        zbuf = vtk.vtkFloatArray()
        self._win.GetZbufferData(0, 0, w - 1, h - 1, zbuf)
        depth = numpy_support.vtk_to_numpy(zbuf).reshape(h, w)[::-1].astype(np.float32)
        return color, depth

    def close(self) -> None:
        """Release the window's OpenGL resources."""
        self._win.Finalize()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def render_cell_projection(spline, camera: Camera, size, isovalue: float, clip_planes=()):
    """Render one isosurface off screen by cell projection (:class:`OffscreenCellProjection`
    for one frame).

    Parameters
    ----------
    spline : Type6Spline or TOQuadraticSpline
    camera : Camera
    size : (width, height) or "WxH"
    isovalue : float
    clip_planes : sequence of (origin, normal), see :meth:`CellProjectionLayer.set_clip_planes`

    Returns
    -------
    color : (H, W, 3) uint8, row 0 at the top
    depth : (H, W) float32 OpenGL window depth, 1 where nothing was drawn
    """
    layer = CellProjectionLayer(spline, isovalue)
    layer.set_clip_planes(clip_planes)
    with OffscreenCellProjection(layer, size) as view:
        return view.render(camera)
