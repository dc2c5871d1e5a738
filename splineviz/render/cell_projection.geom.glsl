//VTK::System::Dec
// Cell projection of relevant tetrahedra (thesis §6.1.2): the geometry of a tet is its
// generic tet's (tables of the partition, stored once, as the thesis' instancing of the
// generic orientations) moved to its cell. Emits the tet's faces that face the eye, outward
// and counter-clockwise; per vertex the world position
// and barycentric coordinates (interpolated), per tet the B-coefficients and barycentric
// gradients (flat), the eye and the projection terms.
layout(points) in;
layout(triangle_strip, max_vertices = 12) out;
in vec3 centreGS[];
flat in int tetGS[];
//CELLPROJ::CoefGSIn
uniform mat4 MCDCMatrix;
uniform mat4 MCVCMatrix;
// per generic tet t: d lam / dx (4), d lam / dy (4), d lam / dz (4) at tetGrad[12 t ..]
uniform float tetGrad[12 * NGENERIC];
// per generic tet t: its vertices relative to the cell centre, world units, tetVert[12 t ..]
uniform float tetVert[12 * NGENERIC];
// per generic tet t: its four faces' vertex slots, outward counter-clockwise, tetFace[12 t ..]
uniform int tetFace[12 * NGENERIC];
out vec3 posVS;
out vec4 clipVS;
out vec4 lamVS;
flat out vec4 gradxVS;
flat out vec4 gradyVS;
flat out vec4 gradzVS;
flat out vec3 eyeVS;
flat out vec4 projVS;
//CELLPROJ::CoefOut
void main()
{
  int t = tetGS[0];
  int g = 12 * t;
  vec4 gx = vec4(tetGrad[g], tetGrad[g + 1], tetGrad[g + 2], tetGrad[g + 3]);
  vec4 gy = vec4(tetGrad[g + 4], tetGrad[g + 5], tetGrad[g + 6], tetGrad[g + 7]);
  vec4 gz = vec4(tetGrad[g + 8], tetGrad[g + 9], tetGrad[g + 10], tetGrad[g + 11]);
  // the eye is the view origin; MCVCMatrix is rigid, so its inverse is exact to rounding
  // (inverting the projection instead lost ~1e-5 in depth)
  vec3 eye = -(transpose(mat3(MCVCMatrix)) * MCVCMatrix[3].xyz);
  // the view-to-clip projection terms that map view directions to NDC x and y
  mat4 vcdc = MCDCMatrix * inverse(MCVCMatrix);
  vec4 proj = vec4(vcdc[0][0], vcdc[1][1], vcdc[2][0], vcdc[2][1]);
  vec3 v[4];
  for (int k = 0; k < 4; ++k) {
    v[k] = centreGS[0] + vec3(tetVert[g + 3 * k], tetVert[g + 3 * k + 1],
                              tetVert[g + 3 * k + 2]);
  }
  for (int f = 0; f < 4; ++f) {
    // only the faces turned to the eye (a ray enters a convex tet through one of them):
    // emitting all four for the rasteriser to cull took twice the time on llvmpipe
    vec3 a = v[tetFace[g + 3 * f]];
    vec3 n = cross(v[tetFace[g + 3 * f + 1]] - a, v[tetFace[g + 3 * f + 2]] - a);
    if (dot(n, eye - a) <= 0.0) { continue; }
    for (int j = 0; j < 3; ++j) {
      int k = tetFace[g + 3 * f + j];
      gl_Position = MCDCMatrix * vec4(v[k], 1.0);
      clipVS = gl_Position;
      posVS = v[k];
      lamVS = vec4(k == 0 ? 1.0 : 0.0, k == 1 ? 1.0 : 0.0, k == 2 ? 1.0 : 0.0,
                   k == 3 ? 1.0 : 0.0);
      gradxVS = gx;
      gradyVS = gy;
      gradzVS = gz;
      eyeVS = eye;
      projVS = proj;
//CELLPROJ::CoefCopy
      EmitVertex();
    }
    EndPrimitive();
  }
}
