// Puts the Renderer's image on the swapchain: its per-pixel sums are copied into an image, a compute
// "resolve" pass (shaders/resolve.comp) turns them into display colour in a storage image, which is
// blitted (scaled if the render resolution differs) to the acquired swapchain image.
#pragma once

#include <vulkan/vulkan_raii.hpp>

#include "vk/compute_pipeline.h"
#include "vk/context.h"

namespace vkray {

class Presenter {
public:
  // encodeSrgb: the swapchain is UNORM, so the resolve pass writes sRGB-encoded values.
  Presenter(const vulkan::Context& context, vulkan::PipelineCache* cache, bool encodeSrgb);

  // Points the resolve pass at the Renderer's image (width x height sums) and sizes the display
  // image. Only while no recorded frame is pending: it rewrites the descriptor set.
  void bind(vk::Buffer sums, vk::Extent2D size);

  // Records the copy of the sums and the resolve pass into the display image. The trace's writes to
  // the sums precede it in the command buffer.
  void recordResolve(const vk::raii::CommandBuffer& cmd) const;
  // Records the blit of the display image into `target`, which ends in TRANSFER_DST_OPTIMAL (its
  // previous contents are discarded).
  void recordBlit(const vk::raii::CommandBuffer& cmd, vk::Image target, vk::Extent2D targetExtent) const;

  // Records a copy of a presentable swapchain image (after the overlay's pass, in PRESENT_SRC) into a
  // host-visible buffer, and gives the image back to presentation. For window screenshots.
  static void recordWindowReadback(const vk::raii::CommandBuffer& cmd, vk::Image shown, vk::Extent2D extent,
                                   vk::Buffer pixels);

  vk::Extent2D size() const { return size_; }

private:
  const vulkan::Context& context_;
  // Layouts before what is built from them; the image's memory before the image bound to it.
  vk::raii::DescriptorSetLayout setLayout_{nullptr};
  vk::raii::PipelineLayout pipelineLayout_{nullptr};
  vk::raii::DescriptorPool pool_{nullptr};
  vk::raii::DescriptorSet set_{nullptr};
  std::unique_ptr<vulkan::ComputePipeline> pipeline_;
  // An image with its memory and view; memory declared first, so it is released last.
  struct OwnedImage {
    vk::raii::DeviceMemory memory{nullptr};
    vk::raii::Image image{nullptr};
    vk::raii::ImageView view{nullptr};
  };
  OwnedImage makeImage(vk::Format format, vk::ImageUsageFlags usage, vk::Extent2D size) const;

  vk::raii::Sampler sampler_{nullptr};
  OwnedImage sumsCopy_; // the sums, copied from the Renderer's buffer for texel fetches
  OwnedImage display_;  // resolved colour, the blit's source
  vk::Buffer sums_;
  vk::Extent2D size_{0, 0};
};

} // namespace vkray
