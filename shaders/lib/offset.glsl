// Where secondary rays start: the hit point pushed off the surface along the geometric normal, to
// the side the new ray leaves from, by a bound on the error of the hit point. No epsilon on t.
// tests/numerics_test.cpp checks that spawned rays never re-hit their surface and never step over
// a neighbouring one.
#ifndef VKRAY_OFFSET_GLSL
#define VKRAY_OFFSET_GLSL

// Pharr, Jakob & Humphreys, pbrt-v4 (4th ed., section 6.8.6, OffsetRayOrigin): move p along the side
// normal by errorBound, then step each component one float further from the surface, so that
// rounding p + side * errorBound cannot bring the origin back. The step is the integer arithmetic on
// the float bits of Ray Tracing Gems ch. 6 (Wachter & Binder, "A Fast and Robust Method for
// Avoiding Self-Intersection"), but one ulp instead of its 256: there the ulps must also cover the
// error of the hit point, which here is errorBound, bounded per shape. 256 ulps of |p| is 3e-5 |p|:
// the parallel-mirror and thin-slab tests found mirrors 0.01 apart at 1e3 from the camera, and
// panes that thin, stepped over (docs/numerics.md).
const int kSpawnUlps = 1;

// x moved `ulps` representable floats in the direction of dir's sign; never past zero into the
// other sign by more than zero, never to Inf.
float stepUlps(float x, float dir, int ulps) {
  bool up = dir > 0.0;
  bool away = x == 0.0 || ((x > 0.0) == up); // moving away from zero grows the magnitude bits
  int bits = floatBitsToInt(abs(x));
  bits = away ? min(bits + ulps, 0x7F7FFFFF) : max(bits - ulps, 0);
  float m = intBitsToFloat(bits);
  float stepped = (x > 0.0 || (x == 0.0 && up)) ? m : -m;
  return dir == 0.0 ? x : stepped; // a select, not an early return (masking on CPU drivers)
}

// errorBound bounds the distance of p from the true surface along n, and the rounding the next
// intersection test makes in deciding which side an origin that close lies on (the per-shape
// analysis of pbrt-v4, 6.8). `side` is the geometric normal flipped to the side the new ray leaves
// from.
vec3 spawnOrigin(vec3 p, vec3 side, float errorBound) {
  vec3 q = p + side * errorBound;
  return vec3(stepUlps(q.x, side.x, kSpawnUlps), stepUlps(q.y, side.y, kSpawnUlps), stepUlps(q.z, side.z, kSpawnUlps));
}

// gamma(n) = n u / (1 - n u) with u = 2^-24 (pbrt's bound on n rounded float operations).
float gammaBound(int n) {
  const float u = 5.9604645e-8;
  return float(n) * u / (1.0 - float(n) * u);
}

#endif
