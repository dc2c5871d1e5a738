//VTK::System::Dec
// Cell projection of relevant tetrahedra (thesis §6.1.2): per vertex, the world position,
// the corner (4 * generic tet + vertex slot, which gives the barycentric coordinates of the
// vertex, interpolated, and the generic tet's barycentric gradients, flat, from a table) and
// the tet's B-coefficients (flat: constant over the tet), and the eye.
in vec4 vertexMC;
in float corner;
//CELLPROJ::CoefIn
uniform mat4 MCDCMatrix;
uniform mat4 MCVCMatrix;
// per generic tet t: d lam / dx (4), d lam / dy (4), d lam / dz (4) at tetGrad[12 t ..]
uniform float tetGrad[12 * NGENERIC];
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
  gl_Position = MCDCMatrix * vertexMC;
  clipVS = gl_Position;
  posVS = vertexMC.xyz;
  int c = int(corner + 0.5);
  int t = c / 4;
  int k = c - 4 * t;
  lamVS = vec4(k == 0 ? 1.0 : 0.0, k == 1 ? 1.0 : 0.0, k == 2 ? 1.0 : 0.0, k == 3 ? 1.0 : 0.0);
  int g = 12 * t;
  gradxVS = vec4(tetGrad[g], tetGrad[g + 1], tetGrad[g + 2], tetGrad[g + 3]);
  gradyVS = vec4(tetGrad[g + 4], tetGrad[g + 5], tetGrad[g + 6], tetGrad[g + 7]);
  gradzVS = vec4(tetGrad[g + 8], tetGrad[g + 9], tetGrad[g + 10], tetGrad[g + 11]);
  // the eye is the view origin; MCVCMatrix is rigid, so its inverse is exact to rounding
  // (inverting the projection instead lost ~1e-5 in depth)
  eyeVS = -(transpose(mat3(MCVCMatrix)) * MCVCMatrix[3].xyz);
  // the view-to-clip projection terms that map view directions to NDC x and y
  mat4 vcdc = MCDCMatrix * inverse(MCVCMatrix);
  projVS = vec4(vcdc[0][0], vcdc[1][1], vcdc[2][0], vcdc[2][1]);
//CELLPROJ::CoefCopy
}
