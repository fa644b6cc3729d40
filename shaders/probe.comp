// Numerical test kernel: runs the renderer's own intersection, offset and optics functions
// (shaders/lib) on arrays of rays supplied by the tests, one invocation per query.
#version 460
#extension GL_GOOGLE_include_directive : require

#include "shared/gpu_types.h"

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

layout(std430, binding = kProbeBindingQueries) readonly buffer Queries { ProbeQuery queries[]; };
layout(std430, binding = kProbeBindingResults) writeonly buffer Results { ProbeResult results[]; };
layout(std430, binding = kProbeBindingVertices) readonly buffer Vertices { vec4 vertices[]; };
layout(push_constant) uniform Push { uint queryCount; } pc;

#define VKRAY_POLYGON_VERTEX(i) vertices[i].xyz
#include "lib/intersect.glsl"
#include "lib/optics.glsl"

void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= pc.queryCount) return;
  ProbeQuery q = queries[i];
  Ray ray = Ray(q.origin.xyz, q.dir.xyz);
  float tMax = q.origin.w > 0.0 ? q.origin.w : kInfinity;
  bool robust = q.op.y == kNumericsRobust;
  ProbeResult r;
  r.hit = vec4(-1.0, 0.0, 0.0, 0.0);
  r.point = vec4(0.0);
  r.normal = vec4(0.0);
  r.spawnOut = vec4(0.0);
  r.spawnIn = vec4(0.0);

  vec3 p = vec3(0.0);
  vec3 n = vec3(0.0);
  float err = 0.0;
  float t = -1.0;
  uint op = q.op.x;
  if (op == kProbeSphere) {
    // op.z == 1: the kernel's call for its unit directions, with the constant a = 1.
    float a = q.op.z == 1u ? 1.0 : dot(ray.dir, ray.dir);
    // b.xyz: the centre's low part (zero unless a test sets it).
    t = robust ? intersectSphereRobust(ray, a, q.a.xyz, q.b.xyz, q.a.w, tMax)
               : intersectSphereNaive(ray, q.a.xyz, q.a.w, tMax);
    if (t > 0.0 && robust) sphereSurface(ray, t, q.a.xyz, q.b.xyz, q.a.w, p, n, err);
    if (t > 0.0 && !robust) sphereSurfaceReprojected(ray, t, q.a.xyz, q.a.w, p, n, err);
  } else if (op == kProbePlane) {
    t = robust ? intersectPlaneRobust(ray, q.a.xyz, q.a.w, tMax) : intersectPlaneNaive(ray, q.a.xyz, q.a.w, tMax);
    if (t > 0.0) {
      planeSurface(ray, t, q.a.xyz, q.a.w, p, err);
      n = q.a.xyz;
    }
  } else if (op == kProbeTriangle) {
    vec3 bary;
    if (robust) {
      t = intersectTriangleRobust(ray, watertightSetup(ray.dir), q.a.xyz, q.b.xyz, q.c.xyz, tMax, bary);
    } else {
      t = intersectTriangleNaive(ray, q.a.xyz, q.b.xyz, q.c.xyz, tMax, bary);
    }
    if (t > 0.0) {
      triangleSurface(bary, q.a.xyz, q.b.xyz, q.c.xyz, p, n, err);
      if (!robust) p = ray.origin + t * ray.dir;
      r.hit.yzw = bary;
    }
  } else if (op == kProbePolygon) {
    // No bound radius here: the probe tests the inside test itself (an infinite reach never rejects).
    t = robust ? intersectPolygonRobust(ray, watertightSetup(ray.dir), q.a.xyz, q.op.z, q.op.w, kInfinity, tMax)
               : intersectPolygonNaive(ray, q.a.xyz, q.op.z, q.op.w, tMax);
    if (t > 0.0) {
      polygonSurface(ray, t, vertices[q.op.z].xyz, p, err);
      n = q.a.xyz;
    }
  } else if (op == kProbeSpawn) {
    r.spawnOut.xyz = spawnOrigin(q.origin.xyz, q.dir.xyz, q.a.x);
    r.spawnIn.xyz = spawnOrigin(q.origin.xyz, -q.dir.xyz, q.a.x);
    results[i] = r;
    return;
  } else if (op == kProbeDielectric) {
    DielectricSplit s = dielectricSplit(q.dir.xyz, q.a.xyz, q.b.xyz, q.c.x, q.c.y, q.op.z == 1u);
    r.hit.x = s.fresnel;
    r.point.xyz = s.refracted;
    r.normal.xyz = mirrorDirection(q.dir.xyz, q.a.xyz, q.b.xyz);
    results[i] = r;
    return;
  }
  if (t > 0.0) {
    r.hit.x = t;
    r.point = vec4(p, err);
    r.normal.xyz = n;
    // The side the ray came from, as trace.comp decides it.
    vec3 ngf = dot(n, ray.dir) < 0.0 ? n : -n;
    r.spawnOut.xyz = robust ? spawnOrigin(p, ngf, err) : p;
    r.spawnIn.xyz = robust ? spawnOrigin(p, -ngf, err) : p;
  }
  results[i] = r;
}
