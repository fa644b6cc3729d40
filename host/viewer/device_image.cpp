// See device_image.h.
#include "viewer/device_image.h"

#include "util/error.h"

namespace vkray {

const vk::ImageSubresourceRange kColorRange(vk::ImageAspectFlagBits::eColor, 0, 1, 0, 1);

namespace {

std::uint32_t deviceLocalType(const vulkan::Context& context, std::uint32_t typeBits) {
  auto props = context.physicalDevice().getMemoryProperties();
  for (auto want : {vk::MemoryPropertyFlags(vk::MemoryPropertyFlagBits::eDeviceLocal), vk::MemoryPropertyFlags()}) {
    for (std::uint32_t i = 0; i < props.memoryTypeCount; ++i) {
      if ((typeBits & (1u << i)) && (props.memoryTypes[i].propertyFlags & want) == want) return i;
    }
  }
  throw DeviceError("creating the viewer's images: no memory type fits");
}

} // namespace

DeviceImage makeDeviceImage(const vulkan::Context& context, vk::Format format, vk::ImageUsageFlags usage,
                            vk::Extent2D size) {
  const auto& device = context.device();
  DeviceImage out;
  vk::ImageCreateInfo info({}, vk::ImageType::e2D, format, vk::Extent3D(size.width, size.height, 1), 1, 1,
                           vk::SampleCountFlagBits::e1, vk::ImageTiling::eOptimal, usage);
  out.image = vk::raii::Image(device, info);
  auto req = out.image.getMemoryRequirements();
  out.memory =
      vk::raii::DeviceMemory(device, vk::MemoryAllocateInfo(req.size, deviceLocalType(context, req.memoryTypeBits)));
  out.image.bindMemory(*out.memory, 0);
  out.view = vk::raii::ImageView(
      device, vk::ImageViewCreateInfo({}, *out.image, vk::ImageViewType::e2D, format, {}, kColorRange));
  return out;
}

} // namespace vkray
