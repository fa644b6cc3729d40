// Swapchain choice, creation, acquire and present (see swapchain.h).
#include "viewer/swapchain.h"

#include <algorithm>

#include "util/error.h"

namespace vkray {

namespace {

bool isSrgb(vk::Format f) {
  return f == vk::Format::eB8G8R8A8Srgb || f == vk::Format::eR8G8B8A8Srgb || f == vk::Format::eA8B8G8R8SrgbPack32;
}

} // namespace

Swapchain::Swapchain(const vulkan::Context& context, vk::raii::SurfaceKHR surface, bool vsync)
    : context_(context), surface_(std::move(surface)) {
  const auto& pd = context.physicalDevice();
  vulkan::vulkanStep("checking the window surface", [&] {
    if (!pd.getSurfaceSupportKHR(context.queueFamily(), *surface_)) {
      throw DeviceError("device '" + context.info().name +
                        "' cannot present to this window from its compute queue; choose another with --device");
    }
    // An 8-bit UNORM format shows the resolve pass's sRGB values as they are (and is what the overlay's
    // colours assume); otherwise the first format, with the blit doing the encoding.
    auto formats = pd.getSurfaceFormatsKHR(*surface_);
    if (formats.empty()) throw DeviceError("the window surface offers no format");
    format_ = formats.front();
    for (const auto& f : formats) {
      if ((f.format == vk::Format::eB8G8R8A8Unorm || f.format == vk::Format::eR8G8B8A8Unorm) &&
          f.colorSpace == vk::ColorSpaceKHR::eSrgbNonlinear) {
        format_ = f;
        break;
      }
    }
    isSrgbFormat_ = isSrgb(format_.format);
    auto features = pd.getFormatProperties(format_.format).optimalTilingFeatures;
    if (!(features & vk::FormatFeatureFlagBits::eBlitDst) ||
        !(features & vk::FormatFeatureFlagBits::eColorAttachment)) {
      throw DeviceError("the window's format " + vk::to_string(format_.format) +
                        " cannot be blitted to or drawn into on " + context.info().name);
    }
    // FIFO is always available and is vsync. Without vsync, MAILBOX (no tearing) or IMMEDIATE.
    presentMode_ = vk::PresentModeKHR::eFifo;
    if (!vsync) {
      auto modes = pd.getSurfacePresentModesKHR(*surface_);
      for (auto want : {vk::PresentModeKHR::eMailbox, vk::PresentModeKHR::eImmediate}) {
        if (std::find(modes.begin(), modes.end(), want) != modes.end()) {
          presentMode_ = want;
          break;
        }
      }
    }
  });
}

bool Swapchain::recreate(vk::Extent2D framebuffer) {
  const auto& pd = context_.physicalDevice();
  const auto& device = context_.device();
  return vulkan::vulkanStep("creating the swapchain", [&] {
    auto caps = pd.getSurfaceCapabilitiesKHR(*surface_);
    // Most platforms dictate the extent; 0xFFFFFFFF means the window follows the swapchain.
    vk::Extent2D extent = caps.currentExtent;
    if (extent.width == 0xFFFFFFFFu) {
      extent.width = std::clamp(framebuffer.width, caps.minImageExtent.width, caps.maxImageExtent.width);
      extent.height = std::clamp(framebuffer.height, caps.minImageExtent.height, caps.maxImageExtent.height);
    }
    views_.clear();
    images_.clear();
    if (extent.width == 0 || extent.height == 0) {
      swapchain_ = vk::raii::SwapchainKHR(nullptr);
      extent_ = extent;
      return false;
    }
    if (!(caps.supportedUsageFlags & vk::ImageUsageFlagBits::eTransferDst)) {
      throw DeviceError("the window's swapchain images cannot be transfer destinations on " + context_.info().name);
    }
    // One more than the minimum so acquiring never waits on the presentation engine's own image.
    std::uint32_t count = caps.minImageCount + 1;
    if (caps.maxImageCount > 0) count = std::min(count, caps.maxImageCount);
    // Transfer source where offered: --screenshot-window reads the shown image back (overlay included).
    readable_ = static_cast<bool>(caps.supportedUsageFlags & vk::ImageUsageFlagBits::eTransferSrc);
    vk::ImageUsageFlags usage = vk::ImageUsageFlagBits::eColorAttachment | vk::ImageUsageFlagBits::eTransferDst;
    if (readable_) usage |= vk::ImageUsageFlagBits::eTransferSrc;
    // Storage where the surface, the format and the device allow it: the resolve pass then writes
    // the image itself. Not for an sRGB format: a shader's store does not encode (the blit does).
    auto formatFeatures = pd.getFormatProperties(format_.format).optimalTilingFeatures;
    storable_ = !isSrgbFormat_ && static_cast<bool>(caps.supportedUsageFlags & vk::ImageUsageFlagBits::eStorage) &&
                static_cast<bool>(formatFeatures & vk::FormatFeatureFlagBits::eStorageImage) &&
                context_.storageWriteWithoutFormatEnabled();
    if (storable_) usage |= vk::ImageUsageFlagBits::eStorage;
    vk::SwapchainCreateInfoKHR info({}, *surface_, count, format_.format, format_.colorSpace, extent, 1, usage,
                                    vk::SharingMode::eExclusive, {}, caps.currentTransform,
                                    vk::CompositeAlphaFlagBitsKHR::eOpaque, presentMode_, VK_TRUE, *swapchain_);
    if (!(caps.supportedCompositeAlpha & vk::CompositeAlphaFlagBitsKHR::eOpaque)) {
      info.compositeAlpha = vk::CompositeAlphaFlagBitsKHR::eInherit;
    }
    vk::raii::SwapchainKHR next(device, info);
    swapchain_ = std::move(next); // the old one is destroyed once the new one exists
    extent_ = extent;
    images_ = swapchain_.getImages();
    for (vk::Image image : images_) {
      vk::ImageViewCreateInfo viewInfo({}, image, vk::ImageViewType::e2D, format_.format, {},
                                       vk::ImageSubresourceRange(vk::ImageAspectFlagBits::eColor, 0, 1, 0, 1));
      views_.emplace_back(device, viewInfo);
    }
    while (renderFinished_.size() < images_.size()) renderFinished_.emplace_back(device, vk::SemaphoreCreateInfo());
    return true;
  });
}

std::optional<std::uint32_t> Swapchain::acquire(vk::Semaphore signal) {
  try {
    auto [result, index] = swapchain_.acquireNextImage(UINT64_MAX, signal, nullptr);
    // A suboptimal image still has its semaphore signalled: use it, re-create after presenting.
    return index;
  } catch (const vk::OutOfDateKHRError&) {
    return std::nullopt;
  } catch (const vk::SystemError& e) {
    vulkan::rethrowVulkanError("acquiring a swapchain image", e);
  }
}

bool Swapchain::present(std::uint32_t image, vk::Semaphore wait) {
  vk::SwapchainKHR chain = *swapchain_;
  vk::PresentInfoKHR info(wait, chain, image);
  try {
    return context_.queue().presentKHR(info) == vk::Result::eSuccess;
  } catch (const vk::OutOfDateKHRError&) {
    return false;
  } catch (const vk::SystemError& e) {
    vulkan::rethrowVulkanError("presenting a swapchain image", e);
  }
}

} // namespace vkray
