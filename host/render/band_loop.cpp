// The band loop's pieces (see band_loop.h).
#include "render/band_loop.h"

#include <algorithm>
#include <chrono>

#include "util/error.h"
#include "util/parallel.h"

namespace vkray {

BandSizer::BandSizer(std::uint32_t width, std::uint32_t height, std::uint32_t windowRows, double budgetMs,
                     std::uint32_t samplesPerPixel)
    : windowRows_(windowRows), budgetMs_(budgetMs) {
  const std::uint64_t perRow = static_cast<std::uint64_t>(std::max(1u, width)) * std::max(1u, samplesPerPixel);
  firstRows_ = std::min<std::uint32_t>(height, std::max<std::uint32_t>(8, (65536 / perRow + 7) / 8 * 8));
}

std::uint32_t BandSizer::rowsAt(std::uint32_t y, std::uint32_t end) const {
  std::uint32_t rows = firstRows_;
  if (rowsPerMs_ > 0.0) {
    double want = rowsPerMs_ * budgetMs_;
    rows = static_cast<std::uint32_t>(std::clamp(want, 8.0, static_cast<double>(windowRows_)));
    rows = std::max<std::uint32_t>(8, rows / 8 * 8);
  }
  return std::min({rows, windowRows_, end - y});
}

void BandSizer::measured(std::uint32_t tracedRows, double gpuMs) {
  if (tracedRows == 0) return;
  rowsPerMs_ = static_cast<double>(tracedRows) / std::max(gpuMs, 1e-3);
}

GpuTimer::GpuTimer(const vulkan::Context& context) : context_(context) {
  enabled_ = context.info().timestamps && context.timestampValidBits() > 0;
  if (enabled_) {
    vulkan::vulkanStep("creating the timestamp queries", [&] {
      queryPool_ = vk::raii::QueryPool(context.device(), vk::QueryPoolCreateInfo({}, vk::QueryType::eTimestamp, 2));
    });
  }
}

void GpuTimer::reset(const vk::raii::CommandBuffer& cmd) const {
  if (enabled_) cmd.resetQueryPool(*queryPool_, 0, 2);
}

void GpuTimer::start(const vk::raii::CommandBuffer& cmd) const {
  if (enabled_) cmd.writeTimestamp(vk::PipelineStageFlagBits::eTopOfPipe, *queryPool_, 0);
}

void GpuTimer::stop(const vk::raii::CommandBuffer& cmd) const {
  if (enabled_) cmd.writeTimestamp(vk::PipelineStageFlagBits::eBottomOfPipe, *queryPool_, 1);
}

double GpuTimer::elapsedMs(double wallMs) const {
  if (!enabled_) return wallMs;
  auto [res, ticks] =
      queryPool_.getResults<std::uint64_t>(0, 2, 2 * sizeof(std::uint64_t), sizeof(std::uint64_t),
                                           vk::QueryResultFlagBits::e64 | vk::QueryResultFlagBits::eWait);
  if (res != vk::Result::eSuccess || ticks[1] < ticks[0]) return wallMs;
  return static_cast<double>(ticks[1] - ticks[0]) * context_.timestampPeriodNs() * 1e-6;
}

BandTimes submitBand(const vulkan::Context& context, const GpuTimer& timer, const char* what, std::uint32_t y,
                     std::uint32_t rows, const std::function<void(const vk::raii::CommandBuffer&)>& record) {
  using Clock = std::chrono::steady_clock;
  const std::string band = std::to_string(y) + ".." + std::to_string(y + rows - 1);
  auto start = Clock::now();
  try {
    context.submitAndWait(std::string(what) + " rows " + band, [&](const vk::raii::CommandBuffer& cmd) {
      timer.reset(cmd);
      record(cmd);
      // Shader writes must be visible to the host's mapped reads (or the readback copy).
      vk::MemoryBarrier barrier(vk::AccessFlagBits::eShaderWrite,
                                vk::AccessFlagBits::eHostRead | vk::AccessFlagBits::eTransferRead);
      cmd.pipelineBarrier(vk::PipelineStageFlagBits::eComputeShader,
                          vk::PipelineStageFlagBits::eHost | vk::PipelineStageFlagBits::eTransfer, {}, barrier, {}, {});
    });
  } catch (const DeviceLostError& e) {
    throw DeviceLostError(std::string(e.what()) + " in the band of rows " + band);
  }
  BandTimes t;
  t.wallMs = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
  t.gpuMs = timer.elapsedMs(t.wallMs);
  return t;
}

void uploadRefineRows(const Image& base, std::uint32_t y, std::uint32_t rows, vulkan::Buffer& prev,
                      gpu::PushConstants& push) {
  const std::uint32_t width = base.width;
  std::uint32_t p0 = y > 0 ? y - 1 : 0;
  std::uint32_t p1 = std::min(base.height, y + rows + 1);
  std::vector<glm::vec4> rowsData(static_cast<std::size_t>(width) * (p1 - p0));
  for (std::uint32_t r = p0; r < p1; ++r) {
    for (std::uint32_t x = 0; x < width; ++x) {
      rowsData[static_cast<std::size_t>(r - p0) * width + x] = glm::vec4(base.at(x, r), 1.0f);
    }
  }
  prev.write(rowsData.data(), rowsData.size() * sizeof(glm::vec4));
  push.prevRow0 = p0;
  push.prevRows = p1 - p0;
}

void readBandImage(const vulkan::Buffer& window, std::uint32_t y, std::uint32_t rows, Image& image) {
  const std::uint32_t width = image.width;
  // Each pixel's sum divided by its samples, rows side by side on every thread, read in place where
  // the host sees the window's memory (lavapipe), else copied out through a staging buffer first
  // (one queue submission). The 4K showcase's 8.3 M sums took 98 ms copied whole and divided on one
  // thread.
  std::vector<glm::vec4> copy;
  const glm::vec4* sums = window.view(copy, static_cast<std::size_t>(width) * rows);
  parallelFor(rows, 32, [&](std::size_t r0, std::size_t r1) {
    for (std::size_t r = r0; r < r1; ++r) {
      glm::vec3* out = &image.at(0, y + static_cast<std::uint32_t>(r));
      const glm::vec4* in = sums + r * width;
      for (std::uint32_t x = 0; x < width; ++x) out[x] = in[x].w > 0.0f ? glm::vec3(in[x]) / in[x].w : glm::vec3(0.0f);
    }
  });
}

void readBandHits(const vulkan::Buffer& window, std::uint32_t width, std::uint32_t y, std::uint32_t rows,
                  std::vector<glm::vec4>& hits) {
  // The hit records are the result as they stand.
  window.read(hits.data() + static_cast<std::size_t>(y) * width,
              static_cast<std::size_t>(width) * rows * sizeof(glm::vec4));
}

void readBandFirstHits(const vulkan::Buffer& window, std::uint32_t width, std::uint32_t y, std::uint32_t rows,
                       std::vector<FirstHit>& firstHits) {
  // Two texels per pixel, laid out as FirstHit.
  window.read(firstHits.data() + static_cast<std::size_t>(y) * width,
              static_cast<std::size_t>(width) * rows * sizeof(FirstHit));
}

} // namespace vkray
