// The scene as the tracing kernels see it: the two queries every ray makes (closest hit; occlusion
// up to a distance), over brute-force loops or the BVH. The pieces live one concern a file:
//   specialization.glsl  what the scene calls for (specialization constants)
//   bindings.glsl        descriptor bindings and array counts
//   scene_access.glsl    reading records: registers, uniform block or buffers
//   ray_records.glsl     TraceRay, Hit, Surface
//   precision.glsl       float32 (robust or naive) or float64 arithmetic, the one place they differ
//   primitives.glsl      one intersection test per primitive kind, and the surface of a hit
//   camera.glsl          pixels and eye rays
//   bvh.glsl             the BVH walk
#ifndef VKRAY_SCENE_GLSL
#define VKRAY_SCENE_GLSL

#include "bvh.glsl"
#include "camera.glsl"

// Closest hit in (0, tMax). anyHit: stop at the first hit (callers then read only `kind`); a loop
// whose count is baked in is unrolled, and stopping it early would only mask the remaining tests
// on CPU drivers (3 % of the showcase's instructions), so it runs to the end. shadowRay: skip the
// planes the host proved cannot stand between a surface and a light (host/scene/features.cpp).
// eyeRay: a ray from the eye through this invocation's pixel, which may start from the tile's entry
// points (loadEntryPoints). shadowStart: a shadow ray's entry points (shadowEntryPoints in
// bvh.glsl; a.x kBvhNoRef: from the root).
Hit traceScene(TraceRay r, float tMax, bool anyHit, bool shadowRay, bool eyeRay, ShadowStart shadowStart) {
  Hit hit = Hit(tMax, kNoHit, 0u, vec3(0.0));
  uint planes = HAS_PLANES ? (shadowRay ? occluderPlaneCount() : planeCount()) : 0u;
  if (planes > 0u) {
    uint i = 0u;
    while (true) {
      float t = planeT(r, i, hit.t);
      if (t > 0.0) {
        hit = Hit(t, kPrimPlane, i, vec3(0.0));
        // (Before a BVH walk the return pays: the walk is a loop that a finished lane leaves.)
        if (anyHit && (USE_BVH || (shadowRay ? OCCLUDER_PLANE_COUNT : PLANE_COUNT) == kRuntimeCount)) return hit;
      }
      if (++i >= planes) break;
    }
  }
  if (USE_BVH) {
    traverseBvh(r, hit, anyHit, ENTRY_POINTS && eyeRay, shadowStart);
  } else {
    uint spheres = HAS_SPHERES ? sphereCount() : 0u;
    if (spheres > 0u) {
      uint i = 0u;
      while (true) {
        testPrimitive(r, kPrimSphere, i, hit);
        if (anyHit && SPHERE_COUNT == kRuntimeCount && hit.kind != kNoHit) return hit;
        if (++i >= spheres) break;
      }
    }
    // Triangles and polygons: one box around each kind first (FrameParams), since their tests read
    // vertices and shear them; a ray that misses the box, or meets it beyond the closest hit so far,
    // cannot hit one. The boxes are exact and the slab test conservative (boxEntry), as for the BVH.
    uint triangles = HAS_TRIANGLES ? triangleCount() : 0u;
    if (triangles > 0u && !isinf(boxEntry(r, frame.triangleBoundsMin.xyz, frame.triangleBoundsMax.xyz, hit.t))) {
      uint i = 0u;
      while (true) {
        testPrimitive(r, kPrimTriangle, i, hit);
        if (anyHit && TRIANGLE_COUNT == kRuntimeCount && hit.kind != kNoHit) return hit;
        if (++i >= triangles) break;
      }
    }
    uint polygons = HAS_POLYGONS ? polygonCount() : 0u;
    if (polygons > 0u && !isinf(boxEntry(r, frame.polygonBoundsMin.xyz, frame.polygonBoundsMax.xyz, hit.t))) {
      uint i = 0u;
      while (true) {
        testPrimitive(r, kPrimPolygon, i, hit);
        if (anyHit && POLYGON_COUNT == kRuntimeCount && hit.kind != kNoHit) return hit;
        if (++i >= polygons) break;
      }
    }
  }
  return hit;
}

Hit traceScene(TraceRay r, float tMax, bool anyHit, bool shadowRay, bool eyeRay) {
  return traceScene(r, tMax, anyHit, shadowRay, eyeRay, fromTheRoot());
}

#endif
