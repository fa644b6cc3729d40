// Double-precision intersection, compiled only into the float64 variant of the kernel (the
// accuracy report's reference, on devices with shaderFloat64). Same algorithms as intersect.glsl,
// evaluated in double from the same float inputs; results are rounded to float once, at the end.
#ifndef VKRAY_INTERSECT64_GLSL
#define VKRAY_INTERSECT64_GLSL

#include "common.glsl"

// RTG ch. 7 sphere test in double; returns the nearest root in (0, tMax) or -1.
float intersectSphere64(Ray ray, vec3 center, vec3 centerLow, float radius, float tMax) {
  dvec3 o = dvec3(ray.origin);
  dvec3 d = dvec3(ray.dir);
  dvec3 f = o - (dvec3(center) + dvec3(centerLow));
  double r = double(radius);
  double a = dot(d, d);
  double bPrime = -dot(f, d);
  dvec3 l = f + (bPrime / a) * d;
  double discA = r * r - dot(l, l);
  if (discA < 0.0) return -1.0;
  double q = bPrime + (bPrime < 0.0 ? -1.0 : 1.0) * sqrt(a * discA);
  if (q == 0.0) return -1.0;
  double t0 = (dot(f, f) - r * r) / q;
  double t1 = q / a;
  double tNear = min(t0, t1);
  double tFar = max(t0, t1);
  double tm = double(tMax);
  double t = (tNear > 0.0 && tNear < tm) ? tNear : ((tFar > 0.0 && tFar < tm) ? tFar : -1.0);
  // A root this close to zero would round to 0 in float: report the smallest positive float.
  return t > 0.0 ? max(float(t), 1.4e-45) : -1.0;
}

void sphereSurface64(Ray ray, float t, vec3 center, vec3 centerLow, float radius, out vec3 p, out vec3 n,
                     out float errorBound) {
  dvec3 hit = dvec3(ray.origin) + double(t) * dvec3(ray.dir);
  dvec3 rel = hit - (dvec3(center) + dvec3(centerLow));
  double len = length(rel);
  dvec3 nd = len > 0.0 ? rel / len : dvec3(0.0, 0.0, 1.0);
  // The hit moved onto the sphere along the normal (as the float build does): rounding to float then
  // costs half an ulp of |p|, not of |centre| + r, and double's own error is ~2^-50 of the sphere's
  // scale (the cancellation in |rel| - r).
  p = vec3(hit - (len - double(radius)) * nd);
  n = vec3(nd);
  errorBound = gammaBound(2) * maxComponent(abs(p)) + 8.9e-16 * (radius + maxComponent(abs(center)));
}

float intersectPlane64(Ray ray, vec3 n, float offsetD, float tMax) {
  dvec3 nd = dvec3(n);
  double denom = dot(nd, dvec3(ray.dir));
  if (denom == 0.0) return -1.0;
  double t = -(dot(nd, dvec3(ray.origin)) + double(offsetD)) / denom;
  return (t > 0.0 && t < double(tMax)) ? max(float(t), 1.4e-45) : -1.0;
}

// Watertight triangle test (Woop et al. 2013) in double: the permutation and shear of the float
// version, with double edge functions.
float intersectTriangle64(Ray ray, vec3 v0, vec3 v1, vec3 v2, float tMax, out vec3 bary) {
  bary = vec3(0.0);
  dvec3 dir = dvec3(ray.dir);
  dvec3 ad = abs(dir);
  int kz = (ad.x > ad.y) ? ((ad.x > ad.z) ? 0 : 2) : ((ad.y > ad.z) ? 1 : 2);
  int kx = (kz + 1) % 3;
  int ky = (kx + 1) % 3;
  if (dir[kz] < 0.0) {
    int tmp = kx;
    kx = ky;
    ky = tmp;
  }
  double sx = dir[kx] / dir[kz];
  double sy = dir[ky] / dir[kz];
  double sz = 1.0 / dir[kz];
  dvec3 o = dvec3(ray.origin);
  dvec3 a = dvec3(v0) - o;
  dvec3 b = dvec3(v1) - o;
  dvec3 c = dvec3(v2) - o;
  double ax = a[kx] - sx * a[kz], ay = a[ky] - sy * a[kz];
  double bx = b[kx] - sx * b[kz], by = b[ky] - sy * b[kz];
  double cx = c[kx] - sx * c[kz], cy = c[ky] - sy * c[kz];
  double U = cx * by - cy * bx;
  double V = ax * cy - ay * cx;
  double W = bx * ay - by * ax;
  if ((U < 0.0 || V < 0.0 || W < 0.0) && (U > 0.0 || V > 0.0 || W > 0.0)) return -1.0;
  double det = U + V + W;
  if (det == 0.0) return -1.0;
  double T = (U * a[kz] + V * b[kz] + W * c[kz]) * sz;
  double t = T / det;
  if (!(t > 0.0 && t < double(tMax))) return -1.0;
  bary = vec3(dvec3(U, V, W) / det);
  return max(float(t), 1.4e-45);
}

void triangleSurface64(vec3 bary, vec3 v0, vec3 v1, vec3 v2, out vec3 p, out vec3 ng, out float errorBound) {
  dvec3 pd = double(bary.x) * dvec3(v0) + double(bary.y) * dvec3(v1) + double(bary.z) * dvec3(v2);
  p = vec3(pd);
  dvec3 cr = cross(dvec3(v1) - dvec3(v0), dvec3(v2) - dvec3(v0));
  double len = length(cr);
  ng = len > 0.0 ? vec3(cr / len) : vec3(0.0, 0.0, 1.0);
  vec3 extent = max(v0, max(v1, v2)) - min(v0, min(v1, v2));
  errorBound = gammaBound(2) * (maxComponent(abs(p)) + maxComponent(extent));
}

#endif
