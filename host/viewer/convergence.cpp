// The viewer's convergence estimate (see convergence.h).
#include "viewer/convergence.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "../../shaders/shared/resolve_types.h"
#include "convergence_spv.h" // kConvergenceSpv: shaders/convergence.comp compiled at build time

namespace vkray {

namespace {

constexpr float kNoEstimate = std::numeric_limits<float>::max(); // as convergence.comp writes it

// A bin's value range: [2^lo, 2^hi).
double binLowLog2(std::uint32_t bin) {
  return gpu::kHistogramLowLog2 + static_cast<double>(bin) / gpu::kHistogramBinsPerOctave;
}

} // namespace

ConvergenceMeter::ConvergenceMeter(const vulkan::Context& context, vulkan::PipelineCache* cache)
    : context_(context), cache_(cache) {
  vulkan::vulkanStep("creating the viewer's convergence pass", [&] {
    using T = vk::DescriptorType;
    layout_ = vulkan::KernelLayout(context,
                                   {{gpu::kConvergenceBindingSums, T::eStorageTexelBuffer},
                                    {gpu::kConvergenceBindingHalf, T::eStorageTexelBuffer},
                                    {gpu::kConvergenceBindingErrors, T::eStorageTexelBuffer},
                                    {gpu::kConvergenceBindingHistogram, T::eStorageBuffer},
                                    {gpu::kConvergenceBindingEarliest, T::eStorageTexelBuffer}},
                                   sizeof(glm::uvec2));
    vk::raii::DescriptorSets sets = layout_.allocate();
    set_ = std::move(sets.front());
  });
  histogram_ =
      std::make_unique<vulkan::Buffer>(context, gpu::kHistogramWords * sizeof(std::uint32_t),
                                       vk::BufferUsageFlagBits::eStorageBuffer | vk::BufferUsageFlagBits::eTransferDst,
                                       vulkan::MemoryUse::Readback, "convergence histogram");
  std::array<std::uint32_t, gpu::kHistogramWords> zero{};
  histogram_->write(zero.data(), sizeof zero); // the shader's run-time zero among them
}

void ConvergenceMeter::buildPipelines() {
  const vulkan::DeviceInfo& info = context_.info();
  // One image row per workgroup where the device allows, in whole SIMD batches (as the resolve pass).
  const std::uint32_t limit = std::min(info.maxComputeWorkGroupSizeX, info.maxComputeWorkGroupInvocations);
  groupX_ = std::max(1u, std::min((size_.width + 7u) / 8u * 8u, limit));
  const vk::raii::PipelineCache* cache = cache_ ? &cache_->cache() : nullptr;
  for (std::uint32_t step : {0u, 1u}) {
    vulkan::Specialization spec;
    spec.set(gpu::kConvergenceSpecStep, step);
    spec.set(gpu::kConvergenceSpecGroupX, groupX_);
    spec.set(gpu::kConvergenceSpecThreshold, static_cast<float>(threshold_));
    auto pipeline = std::make_unique<vulkan::ComputePipeline>(context_, std::span<const std::uint32_t>(kConvergenceSpv),
                                                              layout_.pipelineLayout(), spec, cache,
                                                              step == 0 ? "estimate" : "reduce");
    (step == 0 ? estimate_ : reduce_) = std::move(pipeline);
  }
}

void ConvergenceMeter::bind(vk::Buffer sums, vk::BufferView sumsView, vk::Extent2D size, double threshold) {
  const bool resized = size != size_ || !half_;
  const std::uint32_t oldWidth = size_.width;
  sums_ = sums;
  size_ = size;
  if (resized) {
    const vk::DeviceSize pixels = static_cast<vk::DeviceSize>(size.width) * size.height;
    half_.reset();
    earliest_.reset();
    errors_.reset();
    half_ = std::make_unique<vulkan::Buffer>(context_, pixels * sizeof(glm::vec4), vk::Format::eR32G32B32A32Sfloat,
                                             vulkan::MemoryUse::DeviceLocal, "sums when the count last doubled");
    earliest_ =
        std::make_unique<vulkan::Buffer>(context_, pixels * sizeof(glm::vec4), vk::Format::eR32G32B32A32Sfloat,
                                         vulkan::MemoryUse::DeviceLocal, "sums when the count doubled before that");
    // Also a storage buffer: the resolve pass reads the error map's values as words.
    errors_ = std::make_unique<vulkan::Buffer>(context_, pixels * sizeof(float), vk::Format::eR32Sfloat,
                                               vulkan::MemoryUse::DeviceLocal, "error estimates",
                                               vk::BufferUsageFlagBits::eStorageBuffer);
  }
  if (!estimate_ || threshold != threshold_ || size.width != oldWidth) {
    threshold_ = threshold;
    buildPipelines();
  }
  vk::BufferView views[] = {sumsView, half_->texelView(), errors_->texelView(), earliest_->texelView()};
  vk::DescriptorBufferInfo histogram(histogram_->handle(), 0, VK_WHOLE_SIZE);
  std::array<vk::WriteDescriptorSet, 5> writes{
      vk::WriteDescriptorSet(*set_, gpu::kConvergenceBindingSums, 0, 1, vk::DescriptorType::eStorageTexelBuffer,
                             nullptr, nullptr, &views[0]),
      vk::WriteDescriptorSet(*set_, gpu::kConvergenceBindingHalf, 0, 1, vk::DescriptorType::eStorageTexelBuffer,
                             nullptr, nullptr, &views[1]),
      vk::WriteDescriptorSet(*set_, gpu::kConvergenceBindingErrors, 0, 1, vk::DescriptorType::eStorageTexelBuffer,
                             nullptr, nullptr, &views[2]),
      vk::WriteDescriptorSet(*set_, gpu::kConvergenceBindingHistogram, 0, 1, vk::DescriptorType::eStorageBuffer,
                             nullptr, &histogram),
      vk::WriteDescriptorSet(*set_, gpu::kConvergenceBindingEarliest, 0, 1, vk::DescriptorType::eStorageTexelBuffer,
                             nullptr, nullptr, &views[3])};
  context_.device().updateDescriptorSets(writes, {});
  copied_ = 0;
}

void ConvergenceMeter::record(const vk::raii::CommandBuffer& cmd, std::uint32_t samples, bool estimate, bool measure) {
  using Stage = vk::PipelineStageFlagBits;
  using Access = vk::AccessFlagBits;
  const bool restarted = copied_ == 0;
  const bool copy = samples > 0 && (copied_ == 0 || samples >= 2 * copied_);
  estimate = estimate || measure;
  if (!estimate && !copy && !restarted) return;
  // One barrier for every hazard of this frame's passes on the buffers they share: the trace's
  // writes to the sums, the last frame's copy, clear and estimates, and the earlier reads of the
  // buffers written here (the resolve pass's reads of the estimates, the reduction's of the copy).
  const vk::PipelineStageFlags stages = Stage::eComputeShader | Stage::eTransfer;
  vk::MemoryBarrier all(Access::eShaderWrite | Access::eTransferWrite,
                        Access::eShaderRead | Access::eShaderWrite | Access::eTransferRead | Access::eTransferWrite);
  cmd.pipelineBarrier(stages, stages, {}, all, {}, {});
  if (restarted) {
    // No copies since the restart: zero samples in them, so every pixel reads as not estimated yet.
    cmd.fillBuffer(half_->handle(), 0, VK_WHOLE_SIZE, 0u);
    cmd.fillBuffer(earliest_->handle(), 0, VK_WHOLE_SIZE, 0u);
    cmd.pipelineBarrier(stages, stages, {}, all, {}, {});
  }
  const glm::uvec2 size(size_.width, size_.height);
  const std::uint32_t groups = (size_.width + groupX_ - 1) / groupX_;
  cmd.bindDescriptorSets(vk::PipelineBindPoint::eCompute, layout_.pipelineLayout(), 0, {*set_}, {});
  cmd.pushConstants<glm::uvec2>(layout_.pipelineLayout(), vk::ShaderStageFlagBits::eCompute, 0, size);
  if (estimate) {
    cmd.bindPipeline(vk::PipelineBindPoint::eCompute, estimate_->handle());
    cmd.dispatch(groups, size_.height, 1);
  }
  if (measure) {
    // The histogram is cleared by transfer (the run-time zero word with it) and filled by the
    // reduction, which reads the estimates just written.
    cmd.fillBuffer(histogram_->handle(), 0, VK_WHOLE_SIZE, 0u);
    cmd.pipelineBarrier(stages, stages, {}, all, {}, {});
    cmd.bindPipeline(vk::PipelineBindPoint::eCompute, reduce_->handle());
    cmd.dispatch(groups, size_.height, 1);
    measuredSamples_ = samples;
  }
  if (copy) {
    // After the estimate, which still compares with the previous copies; the last copy moves down a
    // place (on the first after a restart it is the fill's zeros), then the sums are copied.
    if (estimate) cmd.pipelineBarrier(stages, stages, {}, all, {}, {});
    const vk::BufferCopy whole(0, 0, static_cast<vk::DeviceSize>(size_.width) * size_.height * sizeof(glm::vec4));
    cmd.copyBuffer(half_->handle(), earliest_->handle(), whole);
    cmd.pipelineBarrier(stages, stages, {}, all, {}, {});
    cmd.copyBuffer(sums_, half_->handle(), whole);
    copied_ = samples;
  }
  // The estimates and the copy before the resolve pass and the next frame's passes.
  cmd.pipelineBarrier(stages, stages, {}, all, {}, {});
}

ConvergenceFigures ConvergenceMeter::read() const {
  std::array<std::uint32_t, gpu::kHistogramWords> words{};
  histogram_->read(words.data(), sizeof words);
  ConvergenceFigures f;
  f.pixels = words[gpu::kHistogramPixels];
  if (f.pixels == 0) return f;
  f.measured = true;
  f.samples = measuredSamples_;
  f.unestimated = words[gpu::kHistogramUnestimated];
  f.converged = static_cast<double>(words[gpu::kHistogramConverged]) / static_cast<double>(f.pixels);
  const std::uint64_t estimated = f.pixels - f.unestimated;
  double sum = 0.0;
  std::uint64_t seen = 0;
  // The 95th percentile over all pixels, those without an estimate counted as infinite.
  const auto rank = static_cast<std::uint64_t>(std::ceil(0.95 * static_cast<double>(f.pixels)));
  f.errorP95 = std::numeric_limits<double>::infinity();
  bool found = false;
  for (std::uint32_t b = 0; b < gpu::kHistogramBins; ++b) {
    const std::uint32_t n = words[gpu::kHistogramFirstBin + b];
    const double low = binLowLog2(b);
    // The first bin holds the exact zeros (a flat region's samples agree) and all below 2^low.
    const double centre = b == 0 ? 0.0 : std::exp2(low + 0.5 / gpu::kHistogramBinsPerOctave);
    sum += centre * n;
    seen += n;
    if (!found && seen >= rank) {
      f.errorP95 = b == 0 ? std::exp2(binLowLog2(1)) : std::exp2(binLowLog2(b + 1));
      found = true;
    }
  }
  f.errorMean = estimated > 0 ? sum / static_cast<double>(estimated) : std::numeric_limits<double>::infinity();
  return f;
}

std::vector<float> ConvergenceMeter::readErrors() const {
  std::vector<float> e(static_cast<std::size_t>(size_.width) * size_.height);
  errors_->read(e.data(), e.size() * sizeof(float));
  for (float& v : e)
    if (v >= kNoEstimate) v = std::numeric_limits<float>::infinity();
  return e;
}

} // namespace vkray
