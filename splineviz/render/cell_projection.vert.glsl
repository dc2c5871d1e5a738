//VTK::System::Dec
// Cell projection of relevant tetrahedra (thesis §6.1.2), one point per tet: its cell's
// centre in world coordinates, its generic tet (orientation) and its B-coefficients, handed
// to the geometry shader, which emits the tet's faces.
in vec4 vertexMC;
in float tet;
//CELLPROJ::CoefIn
out vec3 centreGS;
flat out int tetGS;
//CELLPROJ::CoefOut
void main()
{
  centreGS = vertexMC.xyz;
  tetGS = int(tet + 0.5);
  gl_Position = vertexMC;
//CELLPROJ::CoefCopy
}
