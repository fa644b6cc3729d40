// A 2-D colour image in device memory with its view: the viewer's own images (the blit path's
// display image, the overlay's layer).
#pragma once

#include <vulkan/vulkan_raii.hpp>

#include "vk/context.h"

namespace vkray {

struct DeviceImage {
  // Memory declared first, so it is released last.
  vk::raii::DeviceMemory memory{nullptr};
  vk::raii::Image image{nullptr};
  vk::raii::ImageView view{nullptr};
};

// One mip level, one layer, optimal tiling, in device-local memory where the device has it.
DeviceImage makeDeviceImage(const vulkan::Context& context, vk::Format format, vk::ImageUsageFlags usage,
                            vk::Extent2D size);

extern const vk::ImageSubresourceRange kColorRange; // the colour aspect of such an image

} // namespace vkray
