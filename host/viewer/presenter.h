// Puts the Renderer's image on the swapchain: a compute "resolve" pass (shaders/resolve.comp) reads
// its per-pixel sums, a storage texel buffer, and turns them into display colour. Two paths:
// - direct: where the swapchain images are storage images (Swapchain::storable) and the render size
//   is the window's, the pass writes the acquired swapchain image itself;
//   It composites the overlay's layer (Overlay::recordLayer) on the way, so the image is ready to
//   present;
// - blit: otherwise (a scaled render, or a device that cannot), it writes a half-float storage image,
//   which is blitted, scaled if need be, to the swapchain image, and the overlay draws on that.
// On lavapipe the direct path saves about 2 ms a frame at 640 x 480 (docs/viewer.md).
#pragma once

#include <vector>

#include <vulkan/vulkan_raii.hpp>

#include "viewer/device_image.h"
#include "vk/buffer.h"
#include "vk/compute_pipeline.h"
#include "vk/context.h"
#include "vk/kernel_layout.h"

namespace vkray {

class Swapchain;

class Presenter {
public:
  // encodeSrgb: the swapchain is UNORM, so the resolve pass writes sRGB-encoded values.
  // allowDirect: use the direct path where the swapchain allows it (off: always blit, to compare).
  Presenter(const vulkan::Context& context, vulkan::PipelineCache* cache, bool encodeSrgb, bool allowDirect = true);

  // Points the resolve pass at the Renderer's image (width x height sums: the buffer, and its
  // RGBA32F texel view), sizes the display image and, for a new width, builds the pipelines (their
  // workgroups are a row wide). Only while no recorded frame is pending: it rewrites the descriptor
  // sets.
  void bind(vk::Buffer sums, vk::BufferView sumsView, vk::Extent2D size);
  // Builds the direct path's descriptor sets for the swapchain's images (none when it is not
  // storable), with the overlay's layer (a sampled image of the swapchain's size and format, in
  // SHADER_READ_ONLY_OPTIMAL when read), and drops them before the swapchain is re-created. Only
  // while no frame is pending.
  void attach(const Swapchain& swapchain, vk::ImageView overlayLayer);
  // What the pass shows (kDisplay* in resolve_types.h) and, for a map, its values (a uint per
  // pixel, row-major as the sums) and its log scale's ends. Only while no frame is pending.
  void setDisplay(std::uint32_t display, vk::Buffer map = {}, float mapLow = 0.001f, float mapHigh = 0.1f);
  void detach();

  // The swapchain image a frame is shown on: its index, handle and size.
  struct Target {
    std::uint32_t index = 0;
    vk::Image image;
    vk::Extent2D extent;
  };
  // Whether a frame on `target` takes the direct path.
  bool direct(const Target& target) const { return !directSets_.empty() && target.extent == size_; }
  // Records the resolve pass, into the swapchain image (direct) or the display image. The trace's writes to the sums
  // precede it in the command buffer; the submission waits for the image's acquisition at the transfer stage, which
  // this chains to.
  void recordResolve(const vk::raii::CommandBuffer& cmd, const Target& target) const;
  // Records the blit of the display image into the target, which ends in TRANSFER_DST_OPTIMAL for
  // the overlay's pass; on the direct path only the transition to PRESENT_SRC_KHR (the overlay is
  // in the picture already).
  void recordBlit(const vk::raii::CommandBuffer& cmd, const Target& target) const;

  // Records a copy of a presentable swapchain image (in PRESENT_SRC, after the overlay's pass or the
  // direct path's transition, both of which end at the colour-attachment-output stage) into a
  // host-visible buffer, and gives the image back to presentation. For window screenshots.
  static void recordWindowReadback(const vk::raii::CommandBuffer& cmd, vk::Image shown, vk::Extent2D extent,
                                   vk::Buffer pixels);

  vk::Extent2D size() const { return size_; }

private:
  const vulkan::Context& context_;
  // Layouts before what is built from them; the image's memory before the image bound to it.
  vulkan::KernelLayout layout_;
  vk::raii::DescriptorSet set_{nullptr};
  std::unique_ptr<vulkan::ComputePipeline> pipeline_;
  std::unique_ptr<vulkan::ComputePipeline> directPipeline_; // null where the device cannot
  vk::raii::DescriptorPool directPool_{nullptr};            // one set per swapchain image
  std::vector<vk::raii::DescriptorSet> directSets_;
  void writeSums(); // the sums' view into every set
  std::uint32_t groupWidthFor(std::uint32_t width) const;
  void buildPipelines(std::uint32_t groupX); // both variants, `groupX` invocations wide
  vulkan::PipelineCache* cache_ = nullptr;
  bool encodeSrgb_ = true;
  bool allowDirect_ = false;
  std::uint32_t groupX_ = 0;      // the pipelines' workgroup width (0: none built yet)
  std::uint32_t displayMode_ = 0; // kDisplay*
  float mapLow_ = 0.001f, mapHigh_ = 0.1f;
  std::unique_ptr<vulkan::Buffer> noMap_; // bound while the image is shown (every binding must be valid)
  vk::Buffer map_;

  vk::raii::Sampler layerSampler_{nullptr}; // nearest: the layer is read texel for texel
  DeviceImage display_;                     // resolved colour, the blit's source (blit path)
  vk::Buffer sums_;
  vk::BufferView sumsView_;
  vk::Extent2D size_{0, 0};
};

} // namespace vkray
