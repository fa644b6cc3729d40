// Descriptor types per binding (see descriptors.h).
#include "render/descriptors.h"

#include "../../shaders/shared/gpu_types.h"

namespace vkray {

namespace {

// Four storage texel buffers, the least maxPerStageDescriptorStorageImages a device may have: BVH
// records and triangles, the hottest scene arrays (imageLoad compiles inline on lavapipe), and the
// image window with its refine-pass copy.
bool isStorageTexelBinding(std::uint32_t b) {
  return b == gpu::kBindingBvhNodes || b == gpu::kBindingTriangles || b == gpu::kBindingImage ||
         b == gpu::kBindingPrevImage;
}

} // namespace

bool isUniformBinding(std::uint32_t b) {
  return b == gpu::kBindingFrame || b == gpu::kBindingSceneUbo;
}

bool isTexelBinding(std::uint32_t b) {
  return b == gpu::kBindingTriangles || b == gpu::kBindingNormals || b == gpu::kBindingBvhNodes ||
         b == gpu::kBindingPrimRefs || b == gpu::kBindingEntryTexels || b == gpu::kBindingImage ||
         b == gpu::kBindingPrevImage || b == gpu::kBindingTexCoords || b == gpu::kBindingTextureInfo ||
         b == gpu::kBindingTexels;
}

vk::DescriptorType descriptorType(std::uint32_t b) {
  if (isStorageTexelBinding(b)) return vk::DescriptorType::eStorageTexelBuffer;
  if (isTexelBinding(b)) return vk::DescriptorType::eUniformTexelBuffer;
  return isUniformBinding(b) ? vk::DescriptorType::eUniformBuffer : vk::DescriptorType::eStorageBuffer;
}

} // namespace vkray
