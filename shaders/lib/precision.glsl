// The arithmetic of intersection, the one place the two builds of the kernel differ: float32, robust
// or textbook by NUMERICS, or, in the kernel built with -DVKRAY_FLOAT64, double precision (the
// accuracy report's reference; it ignores NUMERICS, and shading stays in float). Each function is
// whole in each build: no braces split across the #ifdef, no return left dead.
#ifndef VKRAY_PRECISION_GLSL
#define VKRAY_PRECISION_GLSL

#include "ray_records.glsl"

#ifdef VKRAY_FLOAT64
#extension GL_ARB_gpu_shader_fp64 : enable
#include "intersect64.glsl"

float sphereDistance(TraceRay r, vec3 center, vec3 centerLow, float radius, float tMax) {
  return intersectSphere64(r.ray, center, centerLow, radius, tMax);
}

float triangleDistance(TraceRay r, vec3 v0, vec3 v1, vec3 v2, float tMax, out vec3 bary) {
  return intersectTriangle64(r.ray, v0, v1, v2, tMax, bary);
}

// The inside test as in float (edge functions are exact for the sign that matters), t in double.
float polygonDistance(TraceRay r, vec3 normal, uint first, uint count, float boundRadius, float tMax) {
  float tf = intersectPolygonRobust(r.ray, r.w, normal, first, count, boundRadius, tMax);
  if (tf < 0.0) return -1.0;
  dvec3 n = dvec3(normal);
  double td = dot(n, dvec3(loadPolyVertex(first)) - dvec3(r.ray.origin)) / dot(n, dvec3(r.ray.dir));
  return (td > 0.0 && td < double(tMax)) ? max(float(td), 1.4e-45) : -1.0;
}

float planeDistance(TraceRay r, vec3 normal, float offset, float tMax) {
  return intersectPlane64(r.ray, normal, offset, tMax);
}

void sphereHitPoint(Ray ray, float t, vec3 center, vec3 centerLow, float radius, out vec3 p, out vec3 n,
                    out float errorBound) {
  sphereSurface64(ray, t, center, centerLow, radius, p, n, errorBound);
}

void triangleHitPoint(Ray ray, float t, vec3 bary, vec3 v0, vec3 v1, vec3 v2, out vec3 p, out vec3 ng,
                      out float errorBound) {
  triangleSurface64(bary, v0, v1, v2, p, ng, errorBound);
}

#else

// Naive numerics take the centre as the float it rounds to (the textbook sphere); robust ones add
// its low part.
float sphereDistance(TraceRay r, vec3 center, vec3 centerLow, float radius, float tMax) {
  return ROBUST ? intersectSphereRobust(r.ray, 1.0, center, centerLow, radius, tMax)
                : intersectSphereNaive(r.ray, center, radius, tMax);
}

float triangleDistance(TraceRay r, vec3 v0, vec3 v1, vec3 v2, float tMax, out vec3 bary) {
  return ROBUST ? intersectTriangleRobust(r.ray, r.w, v0, v1, v2, tMax, bary)
                : intersectTriangleNaive(r.ray, v0, v1, v2, tMax, bary);
}

float polygonDistance(TraceRay r, vec3 normal, uint first, uint count, float boundRadius, float tMax) {
  return ROBUST ? intersectPolygonRobust(r.ray, r.w, normal, first, count, boundRadius, tMax)
                : intersectPolygonNaive(r.ray, normal, first, count, tMax);
}

float planeDistance(TraceRay r, vec3 normal, float offset, float tMax) {
  return ROBUST ? intersectPlaneRobust(r.ray, normal, offset, tMax) : intersectPlaneNaive(r.ray, normal, offset, tMax);
}

// Robust: o + t d moved onto the sphere by its compensated distance; naive: the re-projection c + r n.
void sphereHitPoint(Ray ray, float t, vec3 center, vec3 centerLow, float radius, out vec3 p, out vec3 n,
                    out float errorBound) {
  if (ROBUST) {
    sphereSurface(ray, t, center, centerLow, radius, p, n, errorBound);
  } else {
    sphereSurfaceReprojected(ray, t, center, radius, p, n, errorBound);
  }
}

// Robust: the point from the barycentrics (pbrt-v4); naive: the textbook origin + t * dir.
void triangleHitPoint(Ray ray, float t, vec3 bary, vec3 v0, vec3 v1, vec3 v2, out vec3 p, out vec3 ng,
                      out float errorBound) {
  if (ROBUST) {
    triangleSurface(bary, v0, v1, v2, p, ng, errorBound);
  } else {
    vec3 unused;
    triangleSurface(bary, v0, v1, v2, unused, ng, errorBound);
    p = ray.origin + t * ray.dir;
  }
}

#endif

#endif
