// Small helpers used by every shader: the ray type, a sign that is never 0, hashing for sampling.
#ifndef VKRAY_COMMON_GLSL
#define VKRAY_COMMON_GLSL

// The largest float stands in for infinity: a literal Inf is not a constant expression in GLSL.
const float kInfinity = 3.402823466e+38;
const float kPi = 3.14159265358979;

struct Ray {
  vec3 origin;
  vec3 dir; // not necessarily unit length for probe rays; trace.comp keeps it unit
};

// Lavapipe (Mesa 22.3) re-specializes a shader at dispatch time on uniform values that decide a
// branch or a loop ("inline uniforms"): it recompiles on first use, and it crashes when the value
// comes from push constants. vkray specializes explicitly (specialization constants), so every
// uniform-only condition goes through this factor the pass cannot see through: a zero read from
// the statistics buffer (RayStats.zero, which the host keeps 0) at the start of main().
uint gDynamicZero = 0u;
uint opaqueUniform(uint v) { return v + gDynamicZero; }

// sgn(x) in {-1, +1}: GLSL's sign(0) is 0, which would turn the stable quadratic's q into 0.
float signNonZero(float x) { return x < 0.0 ? -1.0 : 1.0; }

float maxComponent(vec3 v) { return max(v.x, max(v.y, v.z)); }

// True when every component is finite (no NaN, no Inf).
bool isFiniteVec(vec3 v) { return !any(isnan(v)) && !any(isinf(v)); }

// PCG-style integer hash (O'Neill 2014; the 32-bit "pcg_hash" variant of Jarzynski & Olano 2020).
uint hashPcg(uint v) {
  uint state = v * 747796405u + 2891336453u;
  uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
  return (word >> 22u) ^ word;
}

// Uniform float in [0, 1) from the top 24 bits of a hash.
float hashToUnit(uint h) { return float(h >> 8u) * (1.0 / 16777216.0); }

#endif
