//VTK::System::Dec
// Cell projection of relevant tetrahedra (thesis §6.1.2): per vertex, the world position and
// barycentric coordinates (interpolated), the tet's B-coefficients and barycentric gradients
// (flat: constant over the tet), and the eye.
in vec4 vertexMC;
in vec4 lam;
in vec4 gradx;
in vec4 grady;
in vec4 gradz;
//CELLPROJ::CoefIn
uniform mat4 MCDCMatrix;
uniform mat4 MCVCMatrix;
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
  lamVS = lam;
  gradxVS = gradx;
  gradyVS = grady;
  gradzVS = gradz;
  // the eye is the view origin; MCVCMatrix is rigid, so its inverse is exact to rounding
  // (inverting the projection instead lost ~1e-5 in depth)
  eyeVS = -(transpose(mat3(MCVCMatrix)) * MCVCMatrix[3].xyz);
  // the view-to-clip projection terms that map view directions to NDC x and y
  mat4 vcdc = MCDCMatrix * inverse(MCVCMatrix);
  projVS = vec4(vcdc[0][0], vcdc[1][1], vcdc[2][0], vcdc[2][1]);
//CELLPROJ::CoefCopy
}
