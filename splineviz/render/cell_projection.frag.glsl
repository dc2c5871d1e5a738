//VTK::System::Dec
//VTK::Output::Dec
// Ray / B-form patch intersection per fragment (thesis §6.1.2): the ray from the eye through
// the fragment is cut to the tetrahedron (barycentric coordinates >= 0) and to the data box,
// the patch restricted to that segment is a univariate Bernstein polynomial whose
// coefficients are blossoms of the segment's end points; its first root is found on monotone
// pieces by bisection, the gradient at the hit from the blossom with one direction argument.
in vec3 posVS;
in vec4 clipVS;
in vec4 lamVS;
flat in vec4 gradxVS;
flat in vec4 gradyVS;
flat in vec4 gradzVS;
flat in vec3 eyeVS;
flat in vec4 projVS;
//CELLPROJ::CoefIn
uniform mat4 MCDCMatrix;
uniform mat4 MCVCMatrix;
uniform vec3 boxMin;
uniform vec3 boxMax;
// clip planes (n, -dot(origin, n)) keeping dot(n, x) + w >= 0, as the ray casters
uniform int clipCount;
uniform vec4 clipPlane0;
uniform vec4 clipPlane1;
uniform vec4 clipPlane2;
uniform vec4 clipPlane3;
uniform vec4 clipPlane4;
uniform vec4 clipPlane5;
uniform vec3 frontColor;
uniform vec3 backColor;
uniform float surfaceOpacity;
uniform float ambientK;
uniform float diffuseK;
uniform float specularK;
uniform float shininess;
// 1: write the unit normal in view coordinates packed as (n + 1) / 2 instead of a colour
// (the bytes of a FrameQuad's normal texture: a frame made off the GUI thread)
uniform int normalOutput;

//CELLPROJ::Blossom

// value of the univariate Bernstein polynomial b[0..DEGREE] at s
float bern(float b[DEGREE + 1], float s)
{
  float u = 1.0 - s;
#if DEGREE == 3
  return u * u * (u * b[0] + 3.0 * s * b[1]) + s * s * (3.0 * u * b[2] + s * b[3]);
#else
  return u * u * b[0] + 2.0 * u * s * b[1] + s * s * b[2];
#endif
}

// cut the ray o + t d, t in [t0, t1], to the kept side of a plane; false when nothing is left
bool clipBy(vec4 plane, vec3 o, vec3 d, inout float t0, inout float t1)
{
  float a0 = dot(plane.xyz, o) + plane.w;
  float b = dot(plane.xyz, d);
  if (b > 0.0) { t0 = max(t0, -a0 / b); }
  else if (b < 0.0) { t1 = min(t1, -a0 / b); }
  else if (a0 < 0.0) { return false; }
  return true;
}

// first root in [lo, hi] of a polynomial monotone there, by bisection (-1 when none)
float bisect(float b[DEGREE + 1], float lo, float hi)
{
  float glo = bern(b, lo);
  float ghi = bern(b, hi);
  if (glo == 0.0) { return lo; }
  if ((glo < 0.0) == (ghi < 0.0) && ghi != 0.0) { return -1.0; }
  for (int i = 0; i < 40; ++i) {
    float mid = 0.5 * (lo + hi);
    float gm = bern(b, mid);
    if ((gm < 0.0) == (glo < 0.0) && gm != 0.0) { lo = mid; } else { hi = mid; }
  }
  return 0.5 * (lo + hi);
}

void main()
{
  // one ray per sample of a multisampled window (gl_FragCoord is then the sample's
  // position): a fragment shaded once per pixel would leave the samples of a pixel that a
  // neighbouring tet's front face covers, whose ray misses that tet, unwritten, and every
  // tet edge would show as a line
#ifdef GL_ARB_sample_shading
  if (gl_SampleID < 0) { discard; }
#endif
  float c[NCOEF];
//CELLPROJ::CoefUnpack
  // The ray through the pixel centre from the camera, as the ray casters cast it (the
  // interpolated position is only near that ray, to float rounding of the rasteriser). The
  // viewport is recovered from the interpolated NDC and rounded to whole pixels.
  vec2 ndcI = clipVS.xy / clipVS.w;
  vec2 size = round(2.0 / vec2(dFdx(ndcI.x), dFdy(ndcI.y)));
  vec2 corner = round(gl_FragCoord.xy - (ndcI + 1.0) * 0.5 * size);
  vec2 ndc = 2.0 * (gl_FragCoord.xy - corner) / size - 1.0;
  vec3 dirVC = vec3((ndc.x + projVS.z) / projVS.x, (ndc.y + projVS.w) / projVS.y, -1.0);
  vec3 d = normalize(transpose(mat3(MCVCMatrix)) * dirVC);
  // parameter origin: the point of the ray nearest to the fragment (t = distance from it),
  // its barycentric coordinates from the fragment's by the affine map
  float tf = dot(posVS - eyeVS, d);
  vec3 o = eyeVS + tf * d;
  vec3 off = o - posVS;
  vec4 lo = lamVS + gradxVS * off.x + gradyVS * off.y + gradzVS * off.z;
  vec4 dl = gradxVS * d.x + gradyVS * d.y + gradzVS * d.z;
  float t0 = -tf;  // the ray starts at the eye
  float t1 = 1e30;
  for (int m = 0; m < 4; ++m) {
    if (dl[m] > 0.0) { t0 = max(t0, -lo[m] / dl[m]); }
    else if (dl[m] < 0.0) { t1 = min(t1, -lo[m] / dl[m]); }
  }
  for (int a = 0; a < 3; ++a) {
    if (d[a] != 0.0) {
      float ta = (boxMin[a] - o[a]) / d[a];
      float tb = (boxMax[a] - o[a]) / d[a];
      t0 = max(t0, min(ta, tb));
      t1 = min(t1, max(ta, tb));
    } else if (o[a] < boxMin[a] || o[a] > boxMax[a]) { discard; }
  }
  bool kept = true;
  if (clipCount > 0) { kept = kept && clipBy(clipPlane0, o, d, t0, t1); }
  if (clipCount > 1) { kept = kept && clipBy(clipPlane1, o, d, t0, t1); }
  if (clipCount > 2) { kept = kept && clipBy(clipPlane2, o, d, t0, t1); }
  if (clipCount > 3) { kept = kept && clipBy(clipPlane3, o, d, t0, t1); }
  if (clipCount > 4) { kept = kept && clipBy(clipPlane4, o, d, t0, t1); }
  if (clipCount > 5) { kept = kept && clipBy(clipPlane5, o, d, t0, t1); }
  if (!kept || !(t0 <= t1)) { discard; }
  vec4 p0 = lo + t0 * dl;
  vec4 p1 = lo + t1 * dl;
  float b[DEGREE + 1];
//CELLPROJ::Segment
  // monotone pieces: split [0, 1] at the roots of the derivative
  float cut[4];
  int ncut = 0;
  cut[ncut++] = 0.0;
#if DEGREE == 3
  {
    // derivative / 3 in Bernstein form of degree 2: e0, e1, e2; power form A s^2 + B s + C
    float e0 = b[1] - b[0], e1 = b[2] - b[1], e2 = b[3] - b[2];
    float A = e0 - 2.0 * e1 + e2, B = 2.0 * (e1 - e0), C = e0;
    float r0 = -1.0, r1 = -1.0;
    if (abs(A) > 1e-12 * (abs(B) + abs(C))) {
      float disc = B * B - 4.0 * A * C;
      if (disc >= 0.0) {
        float q = -0.5 * (B + (B >= 0.0 ? sqrt(disc) : -sqrt(disc)));
        r0 = q / A;
        r1 = q != 0.0 ? C / q : -1.0;
      }
    } else if (B != 0.0) { r0 = -C / B; }
    float lo = min(r0, r1), hi = max(r0, r1);
    if (lo > 0.0 && lo < 1.0) { cut[ncut++] = lo; }
    if (hi > 0.0 && hi < 1.0 && hi != lo) { cut[ncut++] = hi; }
  }
#else
  {
    float den = b[0] - 2.0 * b[1] + b[2];
    if (den != 0.0) {
      float r = (b[0] - b[1]) / den;
      if (r > 0.0 && r < 1.0) { cut[ncut++] = r; }
    }
  }
#endif
  cut[ncut++] = 1.0;
  float s = -1.0;
  for (int i = 0; i + 1 < ncut; ++i) {
    s = bisect(b, cut[i], cut[i + 1]);
    if (s >= 0.0) { break; }
  }
  if (s < 0.0) { discard; }
  float t = t0 + s * (t1 - t0);
  vec3 pos = o + t * d;
  vec4 lh = lo + t * dl;
  // gradient: DEGREE * sum_m b(lh, .., lh, e_m) grad(lam_m)
  vec4 dm = vec4(
    blossom1(c, lh, vec4(1.0, 0.0, 0.0, 0.0)), blossom1(c, lh, vec4(0.0, 1.0, 0.0, 0.0)),
    blossom1(c, lh, vec4(0.0, 0.0, 1.0, 0.0)), blossom1(c, lh, vec4(0.0, 0.0, 0.0, 1.0)));
  vec3 grad = vec3(dot(dm, gradxVS), dot(dm, gradyVS), dot(dm, gradzVS));
  vec4 clip = MCDCMatrix * vec4(pos, 1.0);
  gl_FragDepth = 0.5 * (clip.z / clip.w) + 0.5;
  vec3 n = length(grad) > 0.0 ? normalize(grad) : vec3(0.0);
  if (normalOutput == 1) {
    gl_FragData[0] = vec4(0.5 * mat3(MCVCMatrix) * n + 0.5, 1.0);
    return;
  }
  float ndl = dot(n, d);
  float cs = abs(ndl);
  vec3 base = ndl > 0.0 ? frontColor : backColor;
  vec3 rgb = base * (ambientK + diffuseK * cs) + vec3(specularK * pow(cs, shininess));
  gl_FragData[0] = vec4(clamp(rgb, 0.0, 1.0), surfaceOpacity);
}
