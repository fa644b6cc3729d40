// The descriptor type of every binding of the kernels' one set (numbers in shaders/shared/gpu_types.h).
#pragma once

#include <cstdint>

#include <vulkan/vulkan_raii.hpp>

namespace vkray {

// Uniform buffers: the frame's parameters and the small-scene block.
bool isUniformBinding(std::uint32_t binding);
// Texel buffers: the mesh-sized arrays (see shaders/lib/bindings.glsl), the image window, its
// refine-pass copy and the entry points as the trace kernels read them.
bool isTexelBinding(std::uint32_t binding);
vk::DescriptorType descriptorType(std::uint32_t binding);

} // namespace vkray
