// One intersection function per primitive, in two steps as in pbrt-v4: a cheap test that returns t
// (and barycentrics where they exist), then a function that builds the surface record. Each test has
// a robust form (the default) and the textbook "naive" form kept for the accuracy report.
// Nothing here reads scene buffers: trace.comp and probe.comp both call these on plain values.
#ifndef VKRAY_INTERSECT_GLSL
#define VKRAY_INTERSECT_GLSL

#include "common.glsl"
#include "offset.glsl"

// ---- Error-free transformations ------------------------------------------------------------------

const float kUnitRoundoff = 5.9604645e-8; // u = 2^-24: one rounding's relative error in float32

// a + b and a * b as unevaluated pairs hi + lo, exactly (Knuth's TwoSum; Dekker's TwoProduct with
// Veltkamp's split into 12-bit halves, so no fused multiply-add is needed: Vulkan guarantees correct
// rounding for add, subtract and multiply, but only that of a multiply and an add for fma). `precise`
// forbids the reassociation and contraction that would turn each lo into zero. Ogita, Rump & Oishi,
// "Accurate Sum and Dot Product" (SIAM J. Sci. Comput. 26(6), 2005).
vec2 twoSum(float a, float b) {
  precise float s = a + b;
  precise float bv = s - a;
  precise float av = s - bv;
  precise float e = (a - av) + (b - bv);
  return vec2(s, e);
}

vec2 splitFloat(float a) {
  precise float c = 4097.0 * a; // 2^12 + 1
  precise float hi = c - (c - a);
  precise float lo = a - hi;
  return vec2(hi, lo);
}

vec2 twoSquare(float a) {
  vec2 h = splitFloat(a);
  precise float p = a * a;
  precise float e = ((h.x * h.x - p) + 2.0 * h.x * h.y) + h.y * h.y;
  return vec2(p, e);
}

// |hi + lo|^2 - r^2 for a vector given as hi + lo (|lo| <= ulp(hi)/2), as if computed in twice the
// working precision (Ogita-Rump-Oishi's Sum2 over the exact squares): the absolute error is at most
// u |result| + gamma(4)^2 (|hi|^2 + r^2), where the textbook dot(v, v) - r * r has error
// ~3u (|v|^2 + r^2). Used where the two nearly cancel: a point close to the surface of a sphere that is
// large against its distance from the point's origin (a ground sphere of radius 1e6 under the camera).
float sumOfSquaresMinus(vec3 hi, vec3 lo, float r) {
  vec2 x = twoSquare(hi.x), y = twoSquare(hi.y), z = twoSquare(hi.z), rr = twoSquare(r);
  vec2 s1 = twoSum(x.x, y.x);
  vec2 s2 = twoSum(s1.x, z.x);
  vec2 s3 = twoSum(s2.x, -rr.x);
  precise float err = ((s1.y + s2.y) + s3.y) + ((x.y + y.y) + (z.y - rr.y)) + 2.0 * dot(hi, lo);
  return s3.x + err;
}

// a - (b + bLow) as hi + lo per component: a - b exactly, then bLow (|bLow| <= ulp(b)/2) taken from
// the low part, which rounds at ~u^2 |a - b|, and the pair renormalised.
void exactDifference(vec3 a, vec3 b, vec3 bLow, out vec3 hi, out vec3 lo) {
  vec2 x = twoSum(a.x, -b.x), y = twoSum(a.y, -b.y), z = twoSum(a.z, -b.z);
  x = twoSum(x.x, x.y - bLow.x);
  y = twoSum(y.x, y.y - bLow.y);
  z = twoSum(z.x, z.y - bLow.z);
  hi = vec3(x.x, y.x, z.x);
  lo = vec3(x.y, y.y, z.y);
}

// ---- Spheres -------------------------------------------------------------------------------------

// Ray Tracing Gems ch. 7 (Haines, Gunther & Akenine-Moller, "Precision Improvements for Ray/Sphere
// Intersection"): the discriminant from the distance of the centre to the ray line,
// r^2 - |f - (f.d/a) d|^2, which keeps its precision for small spheres far away; and the root pair
// c/q, q/a from q = b' + sgn(b') sqrt(a disc), which avoids cancellation in the smaller root.
// c = |f|^2 - r^2 says on which side of the surface the origin lies, and the near root c/q carries
// its relative error. It cancels when the origin is close to the surface against the radius (a ray
// leaving a sphere; every eye ray above a ground sphere, where 6 units above a radius of 10^6 leave
// c five good bits and t an error of 3 %). When more than 8 bits cancel (the origin within ~r/256
// of the surface), c is recomputed with f = o - centre exact and the squares compensated
// (sumOfSquaresMinus): the side is right even 10^-12 radii above the surface and t is good to a few
// ulps; otherwise the fast c costs t at most 2u * 2^8 = 3e-5 of itself. Chosen by the numbers: rays
// far from every sphere's surface run the test they ran before. Returns the nearest root in
// (0, tMax), or -1. `a` is
// dot(dir, dir); the kernel passes the constant 1 for its unit directions. The centre is
// center + centerLow (gpu_types.h, sphereCenterLow).
float intersectSphereRobust(Ray ray, float a, vec3 center, vec3 centerLow, float radius, float tMax) {
  vec3 f = (ray.origin - center) - centerLow;
  float bPrime = -dot(f, ray.dir);  // b' = -f.d (half of -b)
  vec3 l = f + (bPrime / a) * ray.dir; // f minus its projection on d: centre-to-line vector
  float r2 = radius * radius;
  float discA = r2 - dot(l, l);        // = disc / a
  float ff = dot(f, f);
  float c = ff - r2;
  if (abs(c) < 0.00390625 * (ff + r2)) { // 2^-8
    vec3 fh, fl;
    exactDifference(ray.origin, center, centerLow, fh, fl);
    c = sumOfSquaresMinus(fh, fl, radius);
  }
  float q = bPrime + signNonZero(bPrime) * sqrt(a * max(discA, 0.0));
  float t0 = c / q;
  float t1 = q / a;
  float tNear = min(t0, t1);
  float tFar = max(t0, t1);
  float t = (tNear > 0.0 && tNear < tMax) ? tNear : ((tFar > 0.0 && tFar < tMax) ? tFar : -1.0);
  // A miss (discA < 0), or a degenerate direction (a == 0) or ray through the centre of a point
  // (q == 0). Selects, not early returns: on CPU drivers a return inside a lane's branch costs
  // the masking of everything after it.
  return (discA < 0.0 || q == 0.0) ? -1.0 : t;
}

// The textbook quadratic formula with a fixed epsilon on t (as in most first ray tracers).
float intersectSphereNaive(Ray ray, vec3 center, float radius, float tMax) {
  vec3 f = ray.origin - center;
  float a = dot(ray.dir, ray.dir);
  float b = 2.0 * dot(f, ray.dir);
  float c = dot(f, f) - radius * radius;
  float disc = b * b - 4.0 * a * c;
  if (disc < 0.0) return -1.0;
  float s = sqrt(disc);
  float t0 = (-b - s) / (2.0 * a);
  float t1 = (-b + s) / (2.0 * a);
  if (t0 > kNaiveEpsilon && t0 < tMax) return t0;
  if (t1 > kNaiveEpsilon && t1 < tMax) return t1;
  return -1.0;
}

// Robust hit point (docs/numerics.md, "Spheres of any radius"): p0 = o + t d, then moved onto the
// sphere along the normal by its distance g = |p0 - c| - r, computed with p0 - c exact and the
// squares compensated: g = (|e|^2 - r^2) / (|e| + r). The point's error is then a few roundings of
// |p0| and |g| (plus the compensated sum's gamma(4)^2 residual at the sphere's scale), not of
// |c| + r as for the re-projection c + r n: 10^-5 instead of 0.4 for the ground of radius 10^6 under
// the camera, the same for a bead far away. The bound also covers the side decision that the next
// intersection test makes from c = |f|^2 - r^2 (same compensated sum).
void sphereSurface(Ray ray, float t, vec3 center, vec3 centerLow, float radius, out vec3 p, out vec3 n,
                   out float errorBound) {
  vec3 p0 = ray.origin + t * ray.dir;
  vec3 eh, el;
  exactDifference(p0, center, centerLow, eh, el);
  float len = length(eh);
  n = len > 0.0 ? eh / len : vec3(0.0, 0.0, 1.0);
  float g = sumOfSquaresMinus(eh, el, radius) / (len + radius);
  p = p0 - g * n;
  float gamma4 = gammaBound(4);
  errorBound = gammaBound(8) * (maxComponent(abs(p0)) + abs(g)) + 8.0 * gamma4 * gamma4 * (len + radius);
}

// The textbook surface (naive numerics): the hit point re-projected onto the sphere (RTG ch. 7),
// c + r n, with an error bound of a few roundings of values of size |centre| + r (pbrt-v4).
void sphereSurfaceReprojected(Ray ray, float t, vec3 center, float radius, out vec3 p, out vec3 n,
                              out float errorBound) {
  vec3 hit = ray.origin + t * ray.dir;
  vec3 rel = hit - center;
  float len = length(rel);
  n = len > 0.0 ? rel / len : vec3(0.0, 0.0, 1.0);
  p = center + radius * n;
  errorBound = gammaBound(6) * (radius + maxComponent(abs(center)));
}

// ---- Planes: n.x + D = 0 -------------------------------------------------------------------------

// Rays parallel to the plane (n.d == 0) miss; so does an origin exactly on the plane (t == 0).
float intersectPlaneRobust(Ray ray, vec3 n, float offsetD, float tMax) {
  float denom = dot(n, ray.dir);
  if (denom == 0.0) return -1.0;
  float t = -(dot(n, ray.origin) + offsetD) / denom;
  return (t > 0.0 && t < tMax) ? t : -1.0;
}

float intersectPlaneNaive(Ray ray, vec3 n, float offsetD, float tMax) {
  float denom = dot(n, ray.dir);
  if (abs(denom) < 1e-6) return -1.0;
  float t = -(dot(n, ray.origin) + offsetD) / denom;
  return (t > kNaiveEpsilon && t < tMax) ? t : -1.0;
}

// The distance of p = o + t d from the plane is the rounding of n.o + D (values of size |o|, |D|)
// and of t d: bound it by a few ulps of their sum.
void planeSurface(Ray ray, float t, vec3 n, float offsetD, out vec3 p, out float errorBound) {
  p = ray.origin + t * ray.dir;
  float scale = maxComponent(abs(ray.origin)) + abs(offsetD) + t * maxComponent(abs(ray.dir)) +
                maxComponent(abs(p));
  errorBound = gammaBound(6) * scale;
}

// ---- Triangles -----------------------------------------------------------------------------------

// Per-ray set-up of the watertight test (Woop, Benthin & Wald, "Watertight Ray/Triangle
// Intersection", JCGT 2(1), 2013): permute axes so z is the largest direction component, then
// shear so the ray becomes the +z axis.
struct WatertightRay {
  ivec3 k;   // kx, ky, kz
  vec3 shear; // Sx, Sy, Sz
};

WatertightRay watertightSetup(vec3 dir) {
  vec3 a = abs(dir);
  int kz = (a.x > a.y) ? ((a.x > a.z) ? 0 : 2) : ((a.y > a.z) ? 1 : 2);
  int kx = (kz + 1) % 3;
  int ky = (kx + 1) % 3;
  if (dir[kz] < 0.0) { int tmp = kx; kx = ky; ky = tmp; } // keep the winding
  WatertightRay w;
  w.k = ivec3(kx, ky, kz);
  w.shear = vec3(dir[kx] / dir[kz], dir[ky] / dir[kz], 1.0 / dir[kz]);
  return w;
}

// Edge function of the 2-D edge p -> q in the sheared ray space. `precise` forbids fusing the two
// products into an FMA: then edge(q, p) == -edge(p, q) bit for bit, so a shared edge is classified
// identically from both sides and no ray slips through (Woop et al. section 3). Polygons use the same
// function, so a polygon and a triangle sharing an edge leave no crack either.
float edgeFunction(vec2 p, vec2 q) {
  precise float a = q.x * p.y;
  precise float b = q.y * p.x;
  precise float e = a - b;
  return e;
}

// Vertex relative to the ray origin, permuted and sheared (x, y in the ray's 2-D frame, z scaled).
vec3 shearVertex(vec3 v, Ray ray, WatertightRay w) {
  vec3 r = v - ray.origin;
  float rz = r[w.k.z];
  return vec3(r[w.k.x] - w.shear.x * rz, r[w.k.y] - w.shear.y * rz, w.shear.z * rz);
}

// A triangle of zero area never hits (pbrt-v4's IntersectTriangle tests this first). The sheared 2-D
// projection cannot tell: it rounds collinear vertices off their line into a sliver with det != 0
// (found by the degenerate-triangle test). The 3-D cross product of the float edges is exactly zero
// for coincident vertices and for collinear ones whose differences are exact; `precise` keeps a
// fused multiply-add from turning a zero into a rounding residue. Called only on the rare path
// where the edge test has passed.
bool degenerateTriangle(vec3 v0, vec3 v1, vec3 v2) {
  precise vec3 e1 = v1 - v0;
  precise vec3 e2 = v2 - v0;
  precise vec3 c = e1.yzx * e2.zxy - e1.zxy * e2.yzx;
  return all(equal(c, vec3(0.0)));
}

// Returns t in (0, tMax) or -1; bary = (b0, b1, b2) weights of v0, v1, v2. Degenerate triangles
// never hit and never divide.
float intersectTriangleRobust(Ray ray, WatertightRay w, vec3 v0, vec3 v1, vec3 v2, float tMax,
                              out vec3 bary) {
  bary = vec3(0.0);
  vec3 A = shearVertex(v0, ray, w);
  vec3 B = shearVertex(v1, ray, w);
  vec3 C = shearVertex(v2, ray, w);
  float U = edgeFunction(B.xy, C.xy);
  float V = edgeFunction(C.xy, A.xy);
  float W = edgeFunction(A.xy, B.xy);
  if ((U < 0.0 || V < 0.0 || W < 0.0) && (U > 0.0 || V > 0.0 || W > 0.0)) return -1.0;
  float det = U + V + W;
  if (det == 0.0 || degenerateTriangle(v0, v1, v2)) return -1.0;
  float T = U * A.z + V * B.z + W * C.z;
  // t = T / det must lie in (0, tMax). Decided on the t that is returned, not by the paper's
  // division-free T against tMax * det (fig. 2): the two can round an ulp apart, and then which of
  // two nearly equal hits is kept would depend on the order the triangles are tested in (through
  // the BVH or brute force). Checked against brute force, bit for bit, in tests/bvh_test.cpp.
  float inv = 1.0 / det;
  float t = T * inv;
  if (!(t > 0.0 && t < tMax)) return -1.0;
  bary = vec3(U, V, W) * inv;
  return t;
}

// The seed's area test: t from the plane, then the hit point is inside when the three sub-triangle
// areas (unnormalised cross products) agree in sign with the face normal; fixed epsilon on t.
float intersectTriangleNaive(Ray ray, vec3 v0, vec3 v1, vec3 v2, float tMax, out vec3 bary) {
  bary = vec3(0.0);
  vec3 n = cross(v1 - v0, v2 - v0);
  float denom = dot(n, ray.dir);
  if (abs(denom) < 1e-12) return -1.0;
  float t = dot(n, v0 - ray.origin) / denom;
  if (!(t > kNaiveEpsilon && t < tMax)) return -1.0;
  vec3 p = ray.origin + t * ray.dir;
  float a0 = dot(n, cross(v2 - v1, p - v1));
  float a1 = dot(n, cross(v0 - v2, p - v2));
  float a2 = dot(n, cross(v1 - v0, p - v0));
  if (a0 < 0.0 || a1 < 0.0 || a2 < 0.0) return -1.0;
  float nn = dot(n, n);
  bary = vec3(a0, a1, a2) / nn;
  return t;
}

// Hit point from the barycentrics (more accurate than o + t d; RTG ch. 6), and its error bound:
// pbrt-v4 bounds the rounding of b0 v0 + b1 v1 + b2 v2 by gamma(7) sum |b_i v_i|. A spawned ray's
// own test then decides the side of its origin from differences v_i - o and edge products of the
// size of the triangle, which for a triangle larger than its distance from the origin exceed that
// bound (the re-intersection sweep found a re-hit): gamma(16) of the triangle's extent covers them
// (first order of pbrt-v4's deltaT analysis).
void triangleSurface(vec3 bary, vec3 v0, vec3 v1, vec3 v2, out vec3 p, out vec3 ng,
                     out float errorBound) {
  p = bary.x * v0 + bary.y * v1 + bary.z * v2;
  vec3 sumAbs = abs(bary.x * v0) + abs(bary.y * v1) + abs(bary.z * v2);
  vec3 extent = max(v0, max(v1, v2)) - min(v0, min(v1, v2));
  errorBound = gammaBound(7) * maxComponent(sumAbs) + gammaBound(16) * maxComponent(extent);
  vec3 c = cross(v1 - v0, v2 - v0);
  float len = length(c);
  ng = len > 0.0 ? c / len : vec3(0.0, 0.0, 1.0);
}

// ---- Convex polygons -----------------------------------------------------------------------------
// The inside test runs in the triangle's sheared frame with the same edge function, so a polygon and
// a triangle sharing an edge classify rays on it identically: no crack. t comes from the plane through
// the first vertex, in coordinates relative to the ray origin (accurate far from the world origin).
// Vertices live in a buffer only the includer knows: it defines VKRAY_POLYGON_VERTEX(i) first.

// t in (tMin, tMax) of the plane through v0 with normal n, or -1. Robust callers pass tMin = 0 and
// minDenom = 0 (only an exactly parallel ray misses); naive ones the textbook epsilons.
float polygonPlaneT(Ray ray, vec3 n, vec3 v0, float tMax, float tMin, float minDenom) {
  float denom = dot(n, ray.dir);
  if (abs(denom) <= minDenom) return -1.0;
  float t = dot(n, v0 - ray.origin) / denom;
  return (t > tMin && t < tMax) ? t : -1.0;
}

#ifdef VKRAY_POLYGON_VERTEX
// boundRadius: every vertex lies within it of v0. A plane hit farther from v0 than that, with a
// margin of 1e-4 of the coordinates' size (thousands of times the rounding of o + t d), misses
// without the edge loop: most rays that meet a polygon's plane miss the polygon, and the loop
// shears every vertex into the ray's frame (a sixth of a small scene's work per polygon).
float intersectPolygonRobust(Ray ray, WatertightRay w, vec3 n, uint first, uint count, float boundRadius,
                             float tMax) {
  vec3 v0 = VKRAY_POLYGON_VERTEX(first);
  float t = polygonPlaneT(ray, n, v0, tMax, 0.0, 0.0);
  if (t < 0.0) return -1.0;
  vec3 p = ray.origin + t * ray.dir;
  float size = maxComponent(abs(ray.origin)) + t * maxComponent(abs(ray.dir)) + maxComponent(abs(v0));
  float reach = boundRadius * (1.0 + 1e-4) + size * 1e-4;
  vec3 fromV0 = p - v0;
  if (dot(fromV0, fromV0) > reach * reach) return -1.0;
  vec2 start = shearVertex(v0, ray, w).xy;
  vec2 prev = start;
  bool anyNeg = false;
  bool anyPos = false;
  // Vertex loops are tested at the bottom (bvh.glsl, traverseBvh: a loop tested at the top runs
  // one more whole turn, masked off, on CPU drivers).
  uint i = 1u;
  while (count > 1u) {
    vec2 cur = shearVertex(VKRAY_POLYGON_VERTEX(first + i), ray, w).xy;
    float e = edgeFunction(prev, cur);
    anyNeg = anyNeg || e < 0.0;
    anyPos = anyPos || e > 0.0;
    prev = cur;
    if (++i >= count) break;
  }
  float e = edgeFunction(prev, start);
  anyNeg = anyNeg || e < 0.0;
  anyPos = anyPos || e > 0.0;
  // Mixed signs: outside. All zero: the ray lies in the polygon's plane (degenerate), a miss.
  return (anyNeg == anyPos) ? -1.0 : t;
}

// The seed's test: t from the plane with a fixed epsilon, then the hit point must lie on the inner
// side of every edge (3-D cross products against the face normal).
float intersectPolygonNaive(Ray ray, vec3 n, uint first, uint count, float tMax) {
  vec3 v0 = VKRAY_POLYGON_VERTEX(first);
  float t = polygonPlaneT(ray, n, v0, tMax, kNaiveEpsilon, 1e-6);
  if (t < 0.0) return -1.0;
  vec3 p = ray.origin + t * ray.dir;
  vec3 prev = v0;
  uint i = 1u;
  while (count > 0u) {
    vec3 cur = VKRAY_POLYGON_VERTEX(first + (i % count));
    if (dot(n, cross(cur - prev, p - prev)) < 0.0) return -1.0;
    prev = cur;
    if (++i > count) break;
  }
  return t;
}
#endif

// Error bound as for planes: p = o + t d against the plane through v0.
void polygonSurface(Ray ray, float t, vec3 v0, out vec3 p, out float errorBound) {
  p = ray.origin + t * ray.dir;
  float scale = maxComponent(abs(ray.origin)) + maxComponent(abs(v0)) +
                t * maxComponent(abs(ray.dir)) + maxComponent(abs(p));
  errorBound = gammaBound(6) * scale;
}

#endif
