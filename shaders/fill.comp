// Row culling's fill pass (host/render/row_culling.h): every eye ray of the dispatch is known to
// meet nothing, so each sample is the background. The same sums and counters as trace.comp gives
// for those pixels, bit for bit: a traced miss of weight 1 is 0 + 1 * background, summed over the
// dispatch's samples from zero, added to the sums when accumulating; one eye ray per sample. A
// kernel of its own, not a specialization of trace.comp: lavapipe took longer to compile that
// specialization than the whole tracing kernel.
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_basic : require

#include "shared/gpu_types.h"

layout(local_size_x = kWorkgroupSizeX, local_size_y = kWorkgroupSizeY, local_size_z = 1) in;

#include "lib/common.glsl"

layout(std140, binding = kBindingFrame) uniform FrameBlock { FrameParams frame; };
// Read as texels, written as a storage buffer: as trace.comp (gpu_types.h, kBindingImageOut).
layout(binding = kBindingImage, rgba32f) uniform readonly imageBuffer imageTexels;
layout(std430, binding = kBindingImageOut) writeonly buffer ImageOut { vec4 imageOut[]; };
layout(std430, binding = kBindingStats) buffer StatsBuffer { RayStats stats; };
layout(push_constant) uniform Push { PushConstants pc; };
layout(constant_id = kSpecCountStats) const bool COUNT_STATS = true;

void main() {
  gDynamicZero = stats.zero; // push-constant values pass through opaqueUniform (common.glsl)
  vec3 background = frame.background.rgb;
  uint samples = opaqueUniform(pc.sampleCount);
  bool accumulate = (opaqueUniform(pc.flags) & kFlagAccumulate) != 0u;
  uvec2 local = gl_GlobalInvocationID.xy;
  uvec2 pixel = pc.tileOrigin + local;
  bool inside = all(lessThan(local, pc.tileSize)) && all(lessThan(pixel, frame.imageSize));
  uint eyeRays = 0u;
  if (inside) {
    vec3 radiance = vec3(0.0) + vec3(1.0) * background;
    if (!isFiniteVec(radiance)) radiance = vec3(0.0); // as trace.comp's traceSample
    vec3 sum = vec3(0.0);
    for (uint k = 0u; k < samples; ++k) sum += radiance;
    eyeRays = samples;
    int slot = int((pixel.y - pc.imageRow0) * frame.imageSize.x + pixel.x);
    vec4 result = vec4(sum, float(pc.sampleCount));
    if (accumulate) result += imageLoad(imageTexels, slot);
    imageOut[slot] = result;
  }
  if (COUNT_STATS) {
    uint total = subgroupAdd(eyeRays);
    if (subgroupElect() && total != 0u) atomicAdd(stats.eyeRays, total);
  }
}
