// One intersection test per primitive kind over the scene's records (the cheap step: t, and
// barycentrics for triangles), and the surface record of the closest hit (the second step, once per
// ray; pbrt-v4's split).
#ifndef VKRAY_PRIMITIVES_GLSL
#define VKRAY_PRIMITIVES_GLSL

#include "precision.glsl"
#include "texture.glsl"

float sphereT(TraceRay r, uint i, float tMax) {
  Sphere s = loadSphere(i);
  return sphereDistance(r, sphereCenter(s), sphereCenterLow(s), sphereRadius(s), tMax);
}

float triangleT(TraceRay r, uint i, float tMax, out vec3 bary) {
  Triangle tri = loadTriangle(i);
  return triangleDistance(r, tri.v0.xyz, tri.v1.xyz, tri.v2.xyz, tMax, bary);
}

float polygonT(TraceRay r, uint i, float tMax) {
  Polygon poly = loadPolygon(i);
  return polygonDistance(r, polygonNormal(poly), polygonFirstVertex(poly), polygonVertexCount(poly),
                         polygonBoundRadius(poly), tMax);
}

float planeT(TraceRay r, uint i, float tMax) {
  Plane pl = loadPlane(i);
  return planeDistance(r, planeNormal(pl), planeOffset(pl), tMax);
}

// Tests one BVH leaf reference (or brute-force primitive) and keeps the closest hit.
void testPrimitive(TraceRay r, uint kind, uint index, inout Hit hit) {
  if (HAS_SPHERES && kind == kPrimSphere) {
    float t = sphereT(r, index, hit.t);
    if (t > 0.0) hit = Hit(t, kPrimSphere, index, vec3(0.0));
  } else if (HAS_TRIANGLES && kind == kPrimTriangle) {
    vec3 bary;
    float t = triangleT(r, index, hit.t, bary);
    if (t > 0.0 && !(ALPHA_MASK && alphaCutOut(index, bary))) hit = Hit(t, kPrimTriangle, index, bary);
  } else if (HAS_POLYGONS && kind == kPrimPolygon) {
    float t = polygonT(r, index, hit.t);
    if (t > 0.0) hit = Hit(t, kPrimPolygon, index, vec3(0.0));
  }
}

// The curvature a smooth-shaded triangle's vertex normals describe, for the ray cones (TEXTURES):
// along each edge, the normal's change projected on the edge over the edge's squared length, which
// is exactly 1 / radius for vertices on a sphere with radial normals ((p_j - p_i) / R dotted with
// p_j - p_i); the mean of the three edges, signed along ng (positive: bulging out of ng's side).
// Flat-shaded triangles, whose normals agree, give 0.
float meshCurvature(vec3 p0, vec3 p1, vec3 p2, vec3 n0, vec3 n1, vec3 n2, vec3 ng, vec3 ns) {
  vec3 e01 = p1 - p0, e12 = p2 - p1, e20 = p0 - p2;
  float k = dot(n1 - n0, e01) / max(dot(e01, e01), 1e-30) + dot(n2 - n1, e12) / max(dot(e12, e12), 1e-30) +
            dot(n0 - n2, e20) / max(dot(e20, e20), 1e-30);
  return (dot(ns, ng) < 0.0 ? -k : k) / 3.0;
}

// Builds the surface record of the closest hit (called once per ray, not per candidate).
Surface surfaceAt(TraceRay r, Hit hit) {
  Surface s;
  s.kind = hit.kind;
  s.index = hit.index;
  if (TEXTURES) {
    s.hasUv = false;
    s.curvature = 0.0;
  }
  if (VERTEX_COLORS) s.vertexColor = vec3(1.0);
  if (hit.kind == kPrimSphere) {
    Sphere sph = loadSphere(hit.index);
    sphereHitPoint(r.ray, hit.t, sphereCenter(sph), sphereCenterLow(sph), sphereRadius(sph), s.p, s.ng, s.errorBound);
    s.ns = s.ng;
    s.material = sphereMaterial(sph);
    if (TEXTURES) s.curvature = 1.0 / sphereRadius(sph);
  } else if (hit.kind == kPrimTriangle) {
    Triangle tri = loadTriangle(hit.index);
    triangleHitPoint(r.ray, hit.t, hit.bary, tri.v0.xyz, tri.v1.xyz, tri.v2.xyz, s.p, s.ng, s.errorBound);
    s.ns = s.ng;
    uint normalBase = triangleNormalBase(tri);
    if (SMOOTH_NORMALS && normalBase != kNoNormals) {
      vec3 n0 = loadShadingNormal(normalBase);
      vec3 n1 = loadShadingNormal(normalBase + 1u);
      vec3 n2 = loadShadingNormal(normalBase + 2u);
      vec3 n = hit.bary.x * n0 + hit.bary.y * n1 + hit.bary.z * n2;
      float len = length(n);
      if (len > 0.0) s.ns = n / len; // zero-length interpolated normal: keep the geometric one
      if (TEXTURES) s.curvature = meshCurvature(tri.v0.xyz, tri.v1.xyz, tri.v2.xyz, n0, n1, n2, s.ng, s.ns);
    }
    s.material = triangleMaterial(tri);
    uint uvBase = triangleUvBasePlusOne(tri);
    if ((TEXTURES || VERTEX_COLORS) && uvBase != 0u) {
      int b = int(uvBase - 1u);
      UvInfo info = loadUvInfo(b);
      if (TEXTURES) {
        s.uv = hit.bary.x * loadUvCorner(b, 0) + hit.bary.y * loadUvCorner(b, 1) + hit.bary.z * loadUvCorner(b, 2);
        s.uvLodBias = triangleLodBias(info);
        s.hasUv = hasTexCoords(info);
      }
      if (VERTEX_COLORS && hasVertexColors(info)) {
        s.vertexColor = hit.bary.x * loadCornerColor(b, 0) + hit.bary.y * loadCornerColor(b, 1) +
                        hit.bary.z * loadCornerColor(b, 2);
      }
    }
  } else if (hit.kind == kPrimPolygon) {
    Polygon poly = loadPolygon(hit.index);
    polygonSurface(r.ray, hit.t, loadPolyVertex(polygonFirstVertex(poly)), s.p, s.errorBound);
    s.ng = polygonNormal(poly);
    s.ns = s.ng;
    s.material = polygonMaterial(poly);
  } else {
    Plane pl = loadPlane(hit.index);
    planeSurface(r.ray, hit.t, planeNormal(pl), planeOffset(pl), s.p, s.errorBound);
    s.ng = planeNormal(pl);
    s.ns = s.ng;
    s.material = planeMaterial(pl);
  }
  return s;
}

#endif
