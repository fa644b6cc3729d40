// The viewer's convergence pass (host/viewer/convergence.h): each pixel's estimated standard error
// while samples accumulate, and its reduction to the figures the overlay shows. The estimate is
// render --noise-threshold's (host/render/adaptive.cpp, blockVariance), from three blocks where the
// headless passes have four: the pixel's samples before the copy of the sums taken the time before
// last that the count doubled, those between the two copies, and those since the last copy. With
// blocks of m_j samples and means x_j, var(mean) = sum_j m_j (x_j - x)^2 / (J - 1) / n, the
// largest of R, G and B; before the second copy the first block is empty, and two halves give
// (A - B)^2 n1 n2 / n^2.
#version 450
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_basic : require

#include "shared/resolve_types.h"

layout(local_size_x = kResolveGroupX, local_size_x_id = kConvergenceSpecGroupX, local_size_y = 1,
       local_size_z = 1) in;

layout(constant_id = kConvergenceSpecStep) const uint STEP = 0u;
layout(constant_id = kConvergenceSpecThreshold) const float THRESHOLD = 0.01;

// Texel buffers: one 16-byte load per lane on lavapipe, where a storage buffer's vec4 is a loop.
layout(binding = kConvergenceBindingSums, rgba32f) uniform readonly restrict imageBuffer sums;
layout(binding = kConvergenceBindingHalf, rgba32f) uniform readonly restrict imageBuffer earlier;
layout(binding = kConvergenceBindingEarliest, rgba32f) uniform readonly restrict imageBuffer earliest;
layout(binding = kConvergenceBindingErrors, r32f) uniform restrict imageBuffer errors;
layout(std430, binding = kConvergenceBindingHistogram) restrict buffer Histogram { uint words[]; };
layout(push_constant) uniform Push { uvec2 size; } pc;

// No estimate: the largest float rather than +inf, which fast-math compilers may assume away. The
// host reads it as +inf (ConvergenceMeter::readErrors).
const float kNoEstimate = 3.402823466e+38;

// One block's share of sum_j m_j (x_j - x)^2: `sum` of `count` samples against the overall mean.
vec3 blockSquares(vec3 sum, float count, vec3 mean) {
  if (!(count > 0.0)) return vec3(0.0);
  vec3 d = sum / count - mean;
  return count * d * d;
}

float estimate(int i) {
  vec4 s = imageLoad(sums, i);
  vec4 h = imageLoad(earlier, i);
  vec4 q = imageLoad(earliest, i);
  float n = s.w;
  // No copy yet, or no sample since it (or a copy from before a restart): no estimate.
  if (!(h.w > 0.0 && n > h.w)) return kNoEstimate;
  vec3 mean = s.rgb / n;
  vec3 squares = blockSquares(q.rgb, q.w, mean) + blockSquares(h.rgb - q.rgb, h.w - q.w, mean) +
                 blockSquares(s.rgb - h.rgb, n - h.w, mean);
  float blocks = q.w > 0.0 ? 3.0 : 2.0;
  vec3 v = squares / ((blocks - 1.0) * n);
  return sqrt(max(v.r, max(v.g, v.b)));
}

void main() {
  // The size through a zero read at run time: lavapipe's dispatch-time inlining of push constants
  // that decide a branch crashes on Mesa 22.3 (docs/performance.md).
  uvec2 size = pc.size + uvec2(words[kHistogramZero]);
  ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
  bool inside = all(lessThan(uvec2(pixel), size));
  int i = pixel.y * int(size.x) + pixel.x;
  if (STEP == 0u) {
    if (inside) imageStore(errors, i, vec4(estimate(i)));
    return;
  }
  // Step 1: the pixel's bin, and whether it has converged as adaptive.cpp's stillOpen judges it:
  // kConvergenceOwnShare of its own squared estimate, the rest of the mean square over the 3 x 3
  // pixels inside the image (neighbourhoodError), and with fewer than
  // kConvergenceContrastGuardSamples samples the range of those pixels' means, the largest channel,
  // over the samples (neighbourhoodContrast). Squares of estimates capped at 1e18, so that no
  // estimate squares to +inf: one without an estimate (kNoEstimate) still never converges. Every
  // pixel of the view has the same samples.
  bool converged = false;
  bool unestimated = false;
  if (inside) {
    float e = imageLoad(errors, i).r;
    unestimated = e >= kNoEstimate;
    float sum = 0.0;
    float count = 0.0;
    float n = imageLoad(sums, i).w;
    bool guarded = n < kConvergenceContrastGuardSamples;
    vec3 lo = vec3(kNoEstimate), hi = vec3(-kNoEstimate);
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        ivec2 q = pixel + ivec2(dx, dy);
        bool within = all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, ivec2(size)));
        ivec2 c = clamp(q, ivec2(0), ivec2(size) - 1);
        int j = c.y * int(size.x) + c.x;
        float neighbour = min(imageLoad(errors, j).r, 1e18);
        sum += within ? neighbour * neighbour : 0.0;
        count += within ? 1.0 : 0.0;
        if (guarded) {
          vec4 s = imageLoad(sums, j); // a clamped pixel repeats one inside: the range stays as it is
          vec3 mean = s.rgb / max(s.w, 1.0);
          lo = min(lo, mean);
          hi = max(hi, mean);
        }
      }
    }
    float own = min(e, 1e18);
    converged = kConvergenceOwnShare * own * own + (1.0 - kConvergenceOwnShare) * sum / count <= THRESHOLD * THRESHOLD;
    vec3 range = hi - lo;
    converged = converged && (!guarded || max(range.r, max(range.g, range.b)) / n <= kConvergenceContrastShare * THRESHOLD);
    if (!unestimated) {
      float bin = (log2(max(e, 1e-30)) - float(kHistogramLowLog2)) * float(kHistogramBinsPerOctave);
      uint b = uint(clamp(bin, 0.0, float(kHistogramBins - 1u)));
      atomicAdd(words[kHistogramFirstBin + b], 1u);
    }
  }
  // One atomic per subgroup for the counts (each atomic is a loop over the lanes on CPU drivers).
  uvec3 counts = subgroupAdd(uvec3(inside ? 1u : 0u, converged ? 1u : 0u, unestimated ? 1u : 0u));
  if (subgroupElect()) {
    atomicAdd(words[kHistogramPixels], counts.x);
    if (counts.y != 0u) atomicAdd(words[kHistogramConverged], counts.y);
    if (counts.z != 0u) atomicAdd(words[kHistogramUnestimated], counts.z);
  }
}
