"""A screen-filling quad that shows a ray-cast frame with exact depth (thesis §6.3, Remark 6).

The ray caster produces, per pixel, a hit flag, a unit normal and the OpenGL window depth of
the first hit. This module draws that image into a VTK scene so that it *composites* with
ordinary props (meshes, outline, axes, widgets): a quad covering the viewport whose fragment
shader

* discards pixels without a hit,
* writes ``gl_FragDepth`` from the frame's depth, so the depth test against the other props
  (and their later depth tests against it) is per pixel and exact to 24 bits,
* shades the pixel (two-sided headlight Phong) from the normal texture with the surface's
  colour, opacity and material given as uniforms, so changing them needs no new ray cast.

Textures (why 8-bit): float textures reached the shader quantised to 8 bits on Mesa/llvmpipe
and ``SetIsDepthTexture`` gave wrong depths (ENVIRONMENT.md), so depth is packed into the RGB
bytes of an 8-bit texture (:func:`pack_depth`, 24 bits) and normals into RGB (8 bits per
component is plenty for shading). Both are sampled nearest-neighbour: interpolating packed
bytes would mix digits.

Image conventions: frames are ``(H, W)`` with row 0 at the top (PNG order); VTK images have
row 0 at the bottom, so rows are flipped on upload.
"""

from __future__ import annotations

import numpy as np
import vtk
from vtk.util import numpy_support

from splineviz.core.material import BACK_COLOR, DEFAULT_MATERIAL, FRONT_COLOR, MATERIALS, Material

#: largest packed depth code (24 bits)
DEPTH_CODES = (1 << 24) - 1

VERTEX_SHADER = """//VTK::System::Dec
in vec4 vertexMC;
out vec2 quadUV;
void main()
{
  // the quad's points 0..3 are the viewport corners (0,0), (1,0), (1,1), (0,1), whatever
  // their model coordinates (those only give VTK the surface's bounds)
  int i = gl_VertexID;
  quadUV = vec2((i == 1 || i == 2) ? 1.0 : 0.0, (i >= 2) ? 1.0 : 0.0);
  gl_Position = vec4(2.0 * quadUV - 1.0, 0.0, 1.0);
}
"""

FRAGMENT_SHADER = """//VTK::System::Dec
//VTK::Output::Dec
in vec2 quadUV;
uniform sampler2D normtex;
uniform sampler2D depthtex;
uniform sampler2D colortex;
uniform float useColorTex;  // 1: colour by the per-pixel colours of colortex (colour by)
uniform vec3 frontColor;
uniform vec3 backColor;
uniform float surfaceOpacity;
uniform float ambientK;
uniform float diffuseK;
uniform float specularK;
uniform float shininess;
uniform vec2 viewScale;   // (tan(angle/2) * aspect, tan(angle/2)) of the frame's camera
void main()
{
  vec4 nt = texture(normtex, quadUV);
  if (nt.a < 0.5) { discard; }
  vec3 d8 = floor(texture(depthtex, quadUV).rgb * 255.0 + 0.5);
  gl_FragDepth = (d8.r * 65536.0 + d8.g * 256.0 + d8.b) / 16777215.0;
  // normal in view coordinates (x right, y up, z towards the eye)
  vec3 n = normalize(nt.rgb * 2.0 - 1.0);
  // direction from the eye through this pixel, view coordinates
  vec3 dir = normalize(vec3((2.0 * quadUV - 1.0) * viewScale, -1.0));
  float ndl = dot(n, dir);
  float c = abs(ndl);
  // the side the gradient points away from the viewer is the front (as the reference)
  vec3 base = ndl > 0.0 ? frontColor : backColor;
  if (useColorTex > 0.5) { base = texture(colortex, quadUV).rgb; }
  vec3 rgb = base * (ambientK + diffuseK * c) + vec3(specularK * pow(c, shininess));
  gl_FragData[0] = vec4(clamp(rgb, 0.0, 1.0), surfaceOpacity);
}
"""


def pack_depth(depth: np.ndarray) -> np.ndarray:
    """Pack window depths in [0, 1] into 24-bit RGB bytes (big end first).

    Parameters
    ----------
    depth : (H, W) float

    Returns
    -------
    (H, W, 3) uint8; the shader decodes ``(r * 65536 + g * 256 + b) / (2**24 - 1)``.
    """
    code = np.rint(np.clip(np.asarray(depth, np.float64), 0.0, 1.0) * DEPTH_CODES)
    code = code.astype(np.uint32)
    out = np.empty(code.shape + (3,), dtype=np.uint8)
    out[..., 0] = code >> 16
    out[..., 1] = (code >> 8) & 0xFF
    out[..., 2] = code & 0xFF
    return out


def unpack_depth(rgb: np.ndarray) -> np.ndarray:
    """Inverse of :func:`pack_depth` (what the fragment shader computes). (H, W, 3) -> (H, W)."""
    c = np.asarray(rgb).astype(np.uint32)
    return ((c[..., 0] << 16) | (c[..., 1] << 8) | c[..., 2]) / DEPTH_CODES


def view_normals(normal: np.ndarray, hit: np.ndarray, basis) -> np.ndarray:
    """World normals to view coordinates packed as RGBA bytes (alpha = hit).

    Parameters
    ----------
    normal : (H, W, 3) unit world normals (NaN where no hit)
    hit : (H, W) bool
    basis : (right, up, dop) of the camera, each (3,)

    Returns
    -------
    (H, W, 4) uint8: ``rgb = (n_view + 1) / 2`` with ``n_view = (n.right, n.up, -n.dop)``.
    """
    right, up, dop = (np.asarray(v, dtype=np.float64) for v in basis)
    m = np.stack([right, up, -dop], axis=1)  # world -> view
    n = np.nan_to_num(np.asarray(normal, dtype=np.float64)) @ m
    out = np.empty(hit.shape + (4,), dtype=np.uint8)
    out[..., :3] = np.rint(np.clip((n + 1.0) * 127.5, 0.0, 255.0)).astype(np.uint8)
    out[..., 3] = np.where(hit, 255, 0).astype(np.uint8)
    return out


def frame_textures(hit: np.ndarray, normal: np.ndarray, depth: np.ndarray, basis):
    """The two textures of a frame, ready to upload: ``(normals (H*W, 4), depth (H*W, 3))``
    uint8, rows flipped to VTK's bottom-up order (:func:`view_normals`, :func:`pack_depth`).
    Pure NumPy, so a worker thread can make them while the GUI thread draws."""
    return packed_textures(view_normals(normal, hit, basis), depth)


def packed_textures(normals: np.ndarray, depth: np.ndarray):
    """:func:`frame_textures` of normals already packed: ``normals`` (H, W, 4) uint8 as
    :func:`view_normals` makes them, ``depth`` (H, W) window depth."""
    h, w = depth.shape
    return tuple(np.ascontiguousarray(a[::-1]).reshape(h * w, -1)
                 for a in (normals, pack_depth(depth)))


def frame_colors(rgb: np.ndarray) -> np.ndarray:
    """Per-pixel colours ``(H, W, 3)`` uint8 (row 0 at the top) as the colour texture's
    ``(H*W, 3)`` rows in VTK's bottom-up order."""
    h, w = rgb.shape[:2]
    return np.ascontiguousarray(rgb[::-1]).reshape(h * w, 3)


def _image_texture(ncomp: int) -> tuple[vtk.vtkTexture, vtk.vtkImageData]:
    image = vtk.vtkImageData()
    image.SetDimensions(1, 1, 1)
    image.AllocateScalars(vtk.VTK_UNSIGNED_CHAR, ncomp)
    image.GetPointData().GetScalars().Fill(0)
    tex = vtk.vtkTexture()
    tex.SetInputData(image)
    tex.InterpolateOff()
    tex.MipmapOff()
    tex.RepeatOff()
    tex.EdgeClampOn()
    tex.SetColorModeToDirectScalars()
    return tex, image


class FrameQuad:
    """The VTK actor that shows one ray-cast frame (see module docstring).

    Parameters
    ----------
    bounds : ((xmin, xmax), (ymin, ymax), (zmin, zmax))
        World box of the surface. The quad's points span it, so VTK's automatic clipping
        range and ``reset_camera`` include the surface although the vertex shader puts the
        quad on the screen.
    """

    def __init__(self, bounds):
        self.actor = vtk.vtkActor()
        self._poly = vtk.vtkPolyData()
        self._mapper = vtk.vtkPolyDataMapper()
        self._mapper.SetInputData(self._poly)
        self._mapper.SetScalarVisibility(False)
        self.actor.SetMapper(self._mapper)
        self.actor.SetPickable(False)
        self.set_bounds(bounds)
        self._norm_tex, self._norm_img = _image_texture(4)
        self._depth_tex, self._depth_img = _image_texture(3)
        self._color_tex, self._color_img = _image_texture(3)
        prop = self.actor.GetProperty()
        prop.SetTexture("normtex", self._norm_tex)
        prop.SetTexture("depthtex", self._depth_tex)
        prop.SetTexture("colortex", self._color_tex)
        prop.BackfaceCullingOff()
        sp = self.actor.GetShaderProperty()
        sp.SetVertexShaderCode(VERTEX_SHADER)
        sp.SetFragmentShaderCode(FRAGMENT_SHADER)
        self._uniforms = sp.GetFragmentCustomUniforms()
        self.set_material()
        self.set_appearance(FRONT_COLOR, 1.0)
        self.set_view_scale(1.0, 1.0)
        self._uniforms.SetUniformf("useColorTex", 0.0)
        self.has_image = False
        self.actor.VisibilityOff()

    def set_bounds(self, bounds) -> None:
        """Quad corners spanning ``bounds`` (see class docstring)."""
        (x0, x1), (y0, y1), (z0, z1) = bounds
        pts = vtk.vtkPoints()
        for p in ((x0, y0, z0), (x1, y0, z0), (x1, y1, z1), (x0, y1, z1)):
            pts.InsertNextPoint(*p)
        cells = vtk.vtkCellArray()
        cells.InsertNextCell(4, [0, 1, 2, 3])
        tc = numpy_support.numpy_to_vtk(np.array([[0, 0], [1, 0], [1, 1], [0, 1]], np.float32),
                                        deep=True)
        tc.SetName("tcoords")
        self._poly.SetPoints(pts)
        self._poly.SetPolys(cells)
        self._poly.GetPointData().SetTCoords(tc)
        self._poly.Modified()

    def set_material(self, material: Material = MATERIALS[DEFAULT_MATERIAL]) -> None:
        """Phong constants of a :class:`~splineviz.core.material.Material` (default: the
        ray casters' own)."""
        u = self._uniforms
        u.SetUniformf("ambientK", float(material.ambient))
        u.SetUniformf("diffuseK", float(material.diffuse))
        u.SetUniformf("specularK", float(material.specular))
        u.SetUniformf("shininess", float(max(material.shininess, 1.0)))
        self.actor.Modified()

    def set_appearance(self, color, opacity, back_color=None) -> None:
        """Front colour (RGB in [0, 1]), opacity in [0, 1], optional back-face colour."""
        color = tuple(float(c) for c in color)
        if back_color is None:
            # the inside seen through a cut, as the ray casters colour it
            back_color = BACK_COLOR
        self._uniforms.SetUniform3f("frontColor", color)
        self._uniforms.SetUniform3f("backColor", tuple(float(c) for c in back_color))
        self._uniforms.SetUniformf("surfaceOpacity", float(opacity))
        # translucent quads must not be culled as opaque geometry; ForceOpaque keeps them in
        # the opaque pass (drawn last by the scene, blended over what is already there)
        self.actor.ForceOpaqueOn()
        self.actor.Modified()

    def set_view_scale(self, sx: float, sy: float) -> None:
        self._uniforms.SetUniform2f("viewScale", (float(sx), float(sy)))

    def set_colors(self, size, colors: np.ndarray | None) -> None:
        """Per-pixel surface colours ``(W*H, 3)`` uint8 in VTK row order (see
        :func:`frame_colors`), or None for the flat front colour."""
        if colors is None:
            self._uniforms.SetUniformf("useColorTex", 0.0)
        else:
            w, h = size
            vtk_arr = numpy_support.numpy_to_vtk(colors, deep=True,
                                                 array_type=vtk.VTK_UNSIGNED_CHAR)
            self._color_img.SetDimensions(w, h, 1)
            self._color_img.GetPointData().SetScalars(vtk_arr)
            self._color_img.Modified()
            self._color_tex.Modified()
            self._uniforms.SetUniformf("useColorTex", 1.0)
        self.actor.Modified()

    def set_textures(self, size, normals: np.ndarray, depth: np.ndarray) -> None:
        """Upload textures made by :func:`frame_textures` for a frame of ``size`` (W, H)."""
        w, h = size
        for image, flat in ((self._norm_img, normals), (self._depth_img, depth)):
            vtk_arr = numpy_support.numpy_to_vtk(flat, deep=True,
                                                 array_type=vtk.VTK_UNSIGNED_CHAR)
            image.SetDimensions(w, h, 1)
            image.GetPointData().SetScalars(vtk_arr)
            image.Modified()
        self._norm_tex.Modified()
        self._depth_tex.Modified()
        self.has_image = True
