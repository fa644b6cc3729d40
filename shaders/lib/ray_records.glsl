// The records a ray query passes along: the ray with its precomputation, the closest hit (pbrt's
// first step: t and barycentrics) and the surface built from it (the second step).
#ifndef VKRAY_RAY_RECORDS_GLSL
#define VKRAY_RAY_RECORDS_GLSL

#include "scene_access.glsl"

// intersect.glsl reads polygon vertices through this (they live in a buffer only the includer knows).
#define VKRAY_POLYGON_VERTEX(i) loadPolyVertex(i)
#include "intersect.glsl"

// ---- Hits ----------------------------------------------------------------------------------------
const uint kNoHit = 0xFFFFFFFFu;

struct Hit {
  float t;    // the query's tMax when nothing was hit
  uint kind;  // kPrimSphere / kPrimTriangle / kPrimPolygon / kPrimPlane, or kNoHit
  uint index; // into the array of that kind
  vec3 bary;  // triangles: barycentric weights of v0, v1, v2
};

// Everything shading needs about a hit, built once for the closest hit (pbrt's second step).
struct Surface {
  vec3 p;           // hit point
  vec3 ng;          // geometric normal, unit, as stored (outward for spheres)
  vec3 ns;          // shading normal, unit, on the same side as ng
  float errorBound; // distance of p from the true surface along ng, at most
  uint material;
  uint kind;        // kPrim* of the primitive hit
  uint index;       // and its index in its array
  // TEXTURES only (left unset otherwise, so the compiler drops them):
  bool hasUv;       // a triangle with texture coordinates
  vec4 uv;          // xy: set 0, zw: set 1
  vec2 uvLodBias;   // 0.5 log2(uv area / world area) of the triangle, sets 0 and 1
  float curvature;  // of the surface along ng, per unit length: 1 / radius for spheres, 0 for flat ones
  vec3 vertexColor; // VERTEX_COLORS only: interpolated COLOR_0 (1 elsewhere)
};

// A ray with its per-ray precomputation for the watertight triangle test and the BVH slabs.
struct TraceRay {
  Ray ray;
  WatertightRay w;
  vec3 invDir;
};

TraceRay makeTraceRay(vec3 origin, vec3 dir) {
  TraceRay r;
  r.ray = Ray(origin, dir);
  if (HAS_TRIANGLES || HAS_POLYGONS) r.w = watertightSetup(dir);
  // An exactly-zero component would give (0 * inf) = NaN in the slab test; a tiny one gives the same
  // classification for every box the ray does not lie in the face plane of.
  vec3 safe = mix(dir, vec3(1e-30), equal(dir, vec3(0.0)));
  r.invDir = 1.0 / safe;
  return r;
}

// This invocation's pixel in the dispatch (before the tile's origin). lavapipe runs a workgroup as
// SIMD batches of 8 consecutive invocations, rows of the 8 x 8 group; each batch takes a 4 x 2 block

#endif
