// The BVH records as the kernels read them: each gpu::BvhWideNode packed into kBvhRecordTexels
// RGBA32UI texels, its two child references carried in the low bytes of eight box coordinates.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "../../shaders/shared/gpu_types.h"

namespace vkray {

// A box's lower (upper) coordinate with `byte` in its low 8 bits, rounded outwards first so that the
// result lies at or below (above) `v` whatever the byte: the packed box holds the exact one.
std::uint32_t lowerBoundWithByte(float v, std::uint32_t byte);
std::uint32_t upperBoundWithByte(float v, std::uint32_t byte);

// The records in the kernels' layout (gpu_types.h, kBvhRecordTexels): the texels of record i start at
// kBvhRecordTexels * i. Throws Error for a box coordinate beyond ±1e38 (scenes stop at 1e18).
std::vector<glm::uvec4> packBvhRecords(const std::vector<gpu::BvhWideNode>& nodes);

// The record as the kernels decode it (loadBvhNode in shaders/lib/scene_access.glsl): the same
// references, the boxes as packed (each holding the exact one).
gpu::BvhWideNode unpackBvhRecord(const std::vector<glm::uvec4>& texels, std::uint32_t record);

} // namespace vkray
