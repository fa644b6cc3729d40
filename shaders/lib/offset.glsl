// Where secondary rays start: the hit point pushed off the surface along the geometric normal, to
// the side the new ray leaves from, by a bound on the error of the hit point. No epsilon on t.
#ifndef VKRAY_OFFSET_GLSL
#define VKRAY_OFFSET_GLSL

// Ray Tracing Gems ch. 6 (Wachter & Binder, "A Fast and Robust Method for Avoiding
// Self-Intersection"): move p by a fixed number of ulps along n, as integers, so the offset scales
// with |p|; near the origin, where ulps become tiny, fall back to a small absolute offset.
vec3 offsetRayOriginUlps(vec3 p, vec3 n) {
  const float kOrigin = 1.0 / 32.0;
  const float kFloatScale = 1.0 / 65536.0;
  const float kIntScale = 256.0;
  ivec3 ofi = ivec3(kIntScale * n);
  vec3 pi = vec3(intBitsToFloat(floatBitsToInt(p.x) + (p.x < 0.0 ? -ofi.x : ofi.x)),
                 intBitsToFloat(floatBitsToInt(p.y) + (p.y < 0.0 ? -ofi.y : ofi.y)),
                 intBitsToFloat(floatBitsToInt(p.z) + (p.z < 0.0 ? -ofi.z : ofi.z)));
  return vec3(abs(p.x) < kOrigin ? p.x + kFloatScale * n.x : pi.x,
              abs(p.y) < kOrigin ? p.y + kFloatScale * n.y : pi.y,
              abs(p.z) < kOrigin ? p.z + kFloatScale * n.z : pi.z);
}

// The ulp offset covers the rounding of p itself. A hit point computed from much larger quantities
// (a radius-1e4 ground sphere hit near the origin) can be off by far more than ulps of p, so each
// intersector also reports errorBound, an absolute bound on the distance of p from the true surface
// along n (the per-shape error analysis of pbrt-v4, "Pharr, Jakob & Humphreys, 4th ed., 6.8").
// `side` is the geometric normal flipped to the side the new ray leaves from.
vec3 spawnOrigin(vec3 p, vec3 side, float errorBound) {
  return offsetRayOriginUlps(p + side * errorBound, side);
}

// gamma(n) = n u / (1 - n u) with u = 2^-24 (pbrt's bound on n rounded float operations).
float gammaBound(int n) {
  const float u = 5.9604645e-8;
  return float(n) * u / (1.0 - float(n) * u);
}

#endif
