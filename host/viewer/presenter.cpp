// Resolve pass and blit to the swapchain (see presenter.h).
#include "viewer/presenter.h"

#include <array>

#include "../../shaders/shared/resolve_types.h"
#include "resolve_direct_spv.h" // kResolveDirectSpv: the same with VKRAY_RESOLVE_DIRECT
#include "resolve_spv.h"        // kResolveSpv: shaders/resolve.comp compiled at build time
#include "util/error.h"
#include "viewer/swapchain.h"

namespace vkray {

namespace {

constexpr vk::Format kDisplayFormat = vk::Format::eR16G16B16A16Sfloat; // see resolve.comp

} // namespace

Presenter::Presenter(const vulkan::Context& context, vulkan::PipelineCache* cache, bool encodeSrgb, bool allowDirect)
    : context_(context) {
  const auto& device = context.device();
  vulkan::vulkanStep("creating the viewer's resolve pass", [&] {
    // The layer is read by the direct variant only.
    layout_ = vulkan::KernelLayout(context,
                                   {{gpu::kResolveBindingSums, vk::DescriptorType::eStorageTexelBuffer},
                                    {gpu::kResolveBindingDisplay, vk::DescriptorType::eStorageImage},
                                    {gpu::kResolveBindingOverlay, vk::DescriptorType::eCombinedImageSampler},
                                    {gpu::kResolveBindingMap, vk::DescriptorType::eStorageBuffer}},
                                   0);
    vk::raii::DescriptorSets sets = layout_.allocate();
    set_ = std::move(sets.front());
    layerSampler_ = vk::raii::Sampler(
        device, vk::SamplerCreateInfo({}, vk::Filter::eNearest, vk::Filter::eNearest, vk::SamplerMipmapMode::eNearest,
                                      vk::SamplerAddressMode::eClampToEdge, vk::SamplerAddressMode::eClampToEdge,
                                      vk::SamplerAddressMode::eClampToEdge));
  });
  noMap_ = std::make_unique<vulkan::Buffer>(context, sizeof(std::uint32_t), vk::BufferUsageFlagBits::eStorageBuffer,
                                            vulkan::MemoryUse::DeviceLocal, "viewer map (unused)");
  map_ = noMap_->handle();
  cache_ = cache;
  encodeSrgb_ = encodeSrgb;
  allowDirect_ = allowDirect && context.storageWriteWithoutFormatEnabled();
  // The pipelines depend on the image's width: built by the first bind().
}

// One image row per workgroup where the device allows (resolve_types.h), in whole SIMD batches.
std::uint32_t Presenter::groupWidthFor(std::uint32_t width) const {
  const vulkan::DeviceInfo& info = context_.info();
  std::uint32_t limit = std::min(info.maxComputeWorkGroupSizeX, info.maxComputeWorkGroupInvocations);
  std::uint32_t rounded = (width + 7u) / 8u * 8u;
  return std::max(1u, std::min(rounded, limit));
}

void Presenter::buildPipelines(std::uint32_t groupX) {
  vulkan::Specialization spec;
  spec.set(gpu::kResolveSpecEncodeSrgb, encodeSrgb_);
  spec.set(gpu::kResolveSpecGroupX, groupX);
  spec.set(gpu::kResolveSpecDisplay, displayMode_);
  spec.set(gpu::kResolveSpecMapLow, mapLow_);
  spec.set(gpu::kResolveSpecMapHigh, mapHigh_);
  const vk::raii::PipelineCache* cache = cache_ ? &cache_->cache() : nullptr;
  pipeline_.reset();
  directPipeline_.reset();
  pipeline_ = std::make_unique<vulkan::ComputePipeline>(context_, std::span<const std::uint32_t>(kResolveSpv),
                                                        layout_.pipelineLayout(), spec, cache, "resolve");
  if (allowDirect_) {
    directPipeline_ =
        std::make_unique<vulkan::ComputePipeline>(context_, std::span<const std::uint32_t>(kResolveDirectSpv),
                                                  layout_.pipelineLayout(), spec, cache, "direct resolve");
  }
  groupX_ = groupX;
}

void Presenter::attach(const Swapchain& swapchain, vk::ImageView overlayLayer) {
  detach();
  // The blit variant reads no layer, but lavapipe binds every descriptor of a set and crashes on an
  // unwritten sampler: the blit path's set names the layer too.
  vk::DescriptorImageInfo layerInfo(*layerSampler_, overlayLayer, vk::ImageLayout::eShaderReadOnlyOptimal);
  context_.device().updateDescriptorSets(vk::WriteDescriptorSet(*set_, gpu::kResolveBindingOverlay, 0, 1,
                                                                vk::DescriptorType::eCombinedImageSampler, &layerInfo),
                                         {});
  if (!allowDirect_ || !swapchain.storable() || swapchain.imageCount() == 0) return;
  const auto& device = context_.device();
  vulkan::vulkanStep("creating the viewer's direct resolve sets", [&] {
    const auto n = static_cast<std::uint32_t>(swapchain.imageCount());
    directPool_ = layout_.makePool(n);
    directSets_ = layout_.allocate(directPool_, n);
    for (std::uint32_t i = 0; i < n; ++i) {
      vk::DescriptorImageInfo imageInfo(nullptr, swapchain.view(i), vk::ImageLayout::eGeneral);
      std::array<vk::WriteDescriptorSet, 2> writes{
          vk::WriteDescriptorSet(*directSets_[i], gpu::kResolveBindingDisplay, 0, 1, vk::DescriptorType::eStorageImage,
                                 &imageInfo),
          vk::WriteDescriptorSet(*directSets_[i], gpu::kResolveBindingOverlay, 0, 1,
                                 vk::DescriptorType::eCombinedImageSampler, &layerInfo)};
      device.updateDescriptorSets(writes, {});
    }
  });
  writeSums();
}

void Presenter::detach() {
  directSets_.clear();
  directPool_ = vk::raii::DescriptorPool(nullptr);
}

void Presenter::writeSums() {
  std::vector<vk::WriteDescriptorSet> writes;
  vk::DescriptorBufferInfo map(map_, 0, VK_WHOLE_SIZE);
  std::vector<vk::DescriptorSet> sets{*set_};
  for (const auto& set : directSets_) sets.push_back(*set);
  for (vk::DescriptorSet set : sets) {
    if (sumsView_) {
      writes.emplace_back(set, gpu::kResolveBindingSums, 0, 1, vk::DescriptorType::eStorageTexelBuffer, nullptr,
                          nullptr, &sumsView_);
    }
    writes.emplace_back(set, gpu::kResolveBindingMap, 0, 1, vk::DescriptorType::eStorageBuffer, nullptr, &map);
  }
  context_.device().updateDescriptorSets(writes, {});
}

void Presenter::setDisplay(std::uint32_t display, vk::Buffer map, float mapLow, float mapHigh) {
  const bool rebuild = display != displayMode_ || mapLow != mapLow_ || mapHigh != mapHigh_;
  displayMode_ = display;
  mapLow_ = mapLow;
  mapHigh_ = mapHigh;
  map_ = map ? map : noMap_->handle();
  writeSums();
  if (rebuild && groupX_ != 0) buildPipelines(groupX_);
}

void Presenter::bind(vk::Buffer sums, vk::BufferView sumsView, vk::Extent2D size) {
  // Always rewritten: the Renderer may have replaced its buffer by one with the same handle value.
  vulkan::vulkanStep("sizing the viewer's display images", [&] {
    sums_ = sums;
    sumsView_ = sumsView;
    const std::uint32_t groupX = groupWidthFor(size.width);
    if (groupX != groupX_) buildPipelines(groupX);
    if (size != size_) {
      display_ = DeviceImage();
      display_ = makeDeviceImage(context_, kDisplayFormat,
                                 vk::ImageUsageFlagBits::eStorage | vk::ImageUsageFlagBits::eTransferSrc, size);
    }
    vk::DescriptorImageInfo displayInfo(nullptr, *display_.view, vk::ImageLayout::eGeneral);
    vk::WriteDescriptorSet write(*set_, gpu::kResolveBindingDisplay, 0, 1, vk::DescriptorType::eStorageImage,
                                 &displayInfo);
    context_.device().updateDescriptorSets(write, {});
    writeSums();
  });
  size_ = size;
}

void Presenter::recordResolve(const vk::raii::CommandBuffer& cmd, const Target& target) const {
  using Stage = vk::PipelineStageFlagBits;
  using Access = vk::AccessFlagBits;
  using Layout = vk::ImageLayout;
  // The trace's writes to the sums -> the resolve's reads. The image written is the swapchain's
  // (direct) or the display image; its old contents are not needed: the display image was read by
  // the previous frame's blit, the swapchain image by presentation (the acquire semaphore, waited
  // for at the transfer stage, chains to this barrier's source scope).
  const bool toSwapchain = direct(target);
  vk::BufferMemoryBarrier sumsWritten(Access::eShaderWrite, Access::eShaderRead, VK_QUEUE_FAMILY_IGNORED,
                                      VK_QUEUE_FAMILY_IGNORED, sums_, 0, VK_WHOLE_SIZE);
  vk::ImageMemoryBarrier writable({}, Access::eShaderWrite, Layout::eUndefined, Layout::eGeneral,
                                  VK_QUEUE_FAMILY_IGNORED, VK_QUEUE_FAMILY_IGNORED,
                                  toSwapchain ? target.image : *display_.image, kColorRange);
  cmd.pipelineBarrier(Stage::eComputeShader | Stage::eTransfer, Stage::eComputeShader, {}, {}, sumsWritten, writable);

  cmd.bindPipeline(vk::PipelineBindPoint::eCompute, (toSwapchain ? directPipeline_ : pipeline_)->handle());
  cmd.bindDescriptorSets(vk::PipelineBindPoint::eCompute, layout_.pipelineLayout(), 0,
                         {toSwapchain ? *directSets_[target.index] : *set_}, {});
  // Round up: the shader bounds-checks the partial workgroups at the edges.
  cmd.dispatch((size_.width + groupX_ - 1) / groupX_, size_.height, 1);
}

void Presenter::recordBlit(const vk::raii::CommandBuffer& cmd, const Target& target) const {
  using Stage = vk::PipelineStageFlagBits;
  using Access = vk::AccessFlagBits;
  using Layout = vk::ImageLayout;
  if (direct(target)) {
    // The resolve wrote the picture, overlay and all: on to presentation (the submission's semaphore
    // orders the present after it). The destination stage is the one the overlay's pass ends at on
    // the other path, which a window read-back chains to.
    vk::ImageMemoryBarrier written(Access::eShaderWrite, Access::eColorAttachmentWrite, Layout::eGeneral,
                                   Layout::ePresentSrcKHR, VK_QUEUE_FAMILY_IGNORED, VK_QUEUE_FAMILY_IGNORED,
                                   target.image, kColorRange);
    cmd.pipelineBarrier(Stage::eComputeShader, Stage::eColorAttachmentOutput, {}, {}, {}, written);
    return;
  }
  const vk::Extent2D targetExtent = target.extent;

  // Display image: written -> blit source. Swapchain image: acquired (the submission waits for the
  // acquire semaphore at the transfer stage, which this barrier's source scope chains to) -> blit
  // destination; its old contents are discarded.
  std::array<vk::ImageMemoryBarrier, 2> toBlit{
      vk::ImageMemoryBarrier(Access::eShaderWrite, Access::eTransferRead, Layout::eGeneral, Layout::eTransferSrcOptimal,
                             VK_QUEUE_FAMILY_IGNORED, VK_QUEUE_FAMILY_IGNORED, *display_.image, kColorRange),
      vk::ImageMemoryBarrier({}, Access::eTransferWrite, Layout::eUndefined, Layout::eTransferDstOptimal,
                             VK_QUEUE_FAMILY_IGNORED, VK_QUEUE_FAMILY_IGNORED, target.image, kColorRange)};
  cmd.pipelineBarrier(Stage::eComputeShader | Stage::eTransfer, Stage::eTransfer, {}, {}, {}, toBlit);

  vk::ImageSubresourceLayers layers(vk::ImageAspectFlagBits::eColor, 0, 0, 1);
  vk::ImageBlit region(layers,
                       {vk::Offset3D(0, 0, 0), vk::Offset3D(static_cast<std::int32_t>(size_.width),
                                                            static_cast<std::int32_t>(size_.height), 1)},
                       layers,
                       {vk::Offset3D(0, 0, 0), vk::Offset3D(static_cast<std::int32_t>(targetExtent.width),
                                                            static_cast<std::int32_t>(targetExtent.height), 1)});
  bool scaled = size_ != targetExtent;
  cmd.blitImage(*display_.image, Layout::eTransferSrcOptimal, target.image, Layout::eTransferDstOptimal, region,
                scaled ? vk::Filter::eLinear : vk::Filter::eNearest);
}

void Presenter::recordWindowReadback(const vk::raii::CommandBuffer& cmd, vk::Image shown, vk::Extent2D extent,
                                     vk::Buffer pixels) {
  using Stage = vk::PipelineStageFlagBits;
  using Access = vk::AccessFlagBits;
  using Layout = vk::ImageLayout;
  // The overlay's pass wrote the image and left it in PRESENT_SRC: its writes -> the copy.
  vk::ImageMemoryBarrier toCopy(Access::eColorAttachmentWrite, Access::eTransferRead, Layout::ePresentSrcKHR,
                                Layout::eTransferSrcOptimal, VK_QUEUE_FAMILY_IGNORED, VK_QUEUE_FAMILY_IGNORED, shown,
                                kColorRange);
  cmd.pipelineBarrier(Stage::eColorAttachmentOutput, Stage::eTransfer, {}, {}, {}, toCopy);
  vk::BufferImageCopy region(0, 0, 0, vk::ImageSubresourceLayers(vk::ImageAspectFlagBits::eColor, 0, 0, 1), {0, 0, 0},
                             vk::Extent3D(extent.width, extent.height, 1));
  cmd.copyImageToBuffer(shown, Layout::eTransferSrcOptimal, pixels, region);
  // Back to PRESENT_SRC for the present (which the submission's semaphore orders after all of this);
  // the copy's writes -> the host, which reads them after the frame's fence.
  vk::ImageMemoryBarrier toPresent(Access::eTransferRead, {}, Layout::eTransferSrcOptimal, Layout::ePresentSrcKHR,
                                   VK_QUEUE_FAMILY_IGNORED, VK_QUEUE_FAMILY_IGNORED, shown, kColorRange);
  vk::BufferMemoryBarrier toHost(Access::eTransferWrite, Access::eHostRead, VK_QUEUE_FAMILY_IGNORED,
                                 VK_QUEUE_FAMILY_IGNORED, pixels, 0, VK_WHOLE_SIZE);
  cmd.pipelineBarrier(Stage::eTransfer, Stage::eBottomOfPipe | Stage::eHost, {}, {}, toHost, toPresent);
}

} // namespace vkray
