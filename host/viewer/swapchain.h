// The window's swapchain: surface format and present mode choice (FIFO for vsync, else MAILBOX or
// IMMEDIATE), creation and re-creation on resize, acquire and present, and one "rendering finished"
// semaphore per image (a present has no fence, so that semaphore is only known free once its image is
// acquired again).
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include <vulkan/vulkan_raii.hpp>

#include "vk/context.h"

namespace vkray {

class Swapchain {
public:
  Swapchain(const vulkan::Context& context, vk::raii::SurfaceKHR surface, bool vsync);

  // (Re)creates the swapchain for a framebuffer of this size; the caller has waited for the device to
  // be idle. Returns false (and holds no swapchain) when the size is zero, i.e. the window is minimized.
  bool recreate(vk::Extent2D framebuffer);
  bool valid() const { return static_cast<bool>(*swapchain_); }

  // The next image, or nothing when the swapchain is out of date and must be re-created.
  std::optional<std::uint32_t> acquire(vk::Semaphore signal);
  // Presents after `wait`; false when the swapchain should be re-created (out of date or suboptimal).
  bool present(std::uint32_t image, vk::Semaphore wait);

  vk::Format format() const { return format_.format; }
  // UNORM target: the resolve pass writes sRGB-encoded values; an sRGB target encodes in the blit.
  bool encodeInShader() const { return !isSrgbFormat_; }
  vk::Extent2D extent() const { return extent_; }
  vk::PresentModeKHR presentMode() const { return presentMode_; }
  std::size_t imageCount() const { return images_.size(); }
  vk::Image image(std::uint32_t i) const { return images_[i]; }
  vk::ImageView view(std::uint32_t i) const { return *views_[i]; }
  vk::Semaphore renderFinished(std::uint32_t i) const { return *renderFinished_[i]; }
  // The images can be copied from (window screenshots).
  bool readable() const { return readable_; }
  // The images are storage images a shader can write without naming their format: the resolve pass
  // writes them directly, with no intermediate image and blit (presenter.h).
  bool storable() const { return storable_; }

private:
  const vulkan::Context& context_;
  // The surface outlives the swapchain built on it: declared first, destroyed last.
  vk::raii::SurfaceKHR surface_;
  vk::SurfaceFormatKHR format_;
  bool isSrgbFormat_ = false;
  bool readable_ = false;
  bool storable_ = false;
  vk::PresentModeKHR presentMode_ = vk::PresentModeKHR::eFifo;
  vk::Extent2D extent_;
  vk::raii::SwapchainKHR swapchain_{nullptr};
  std::vector<vk::Image> images_; // owned by the swapchain
  std::vector<vk::raii::ImageView> views_;
  std::vector<vk::raii::Semaphore> renderFinished_;
};

} // namespace vkray
