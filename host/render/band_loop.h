// The pieces of the band loop: a render traces its image in bands of rows, each one submission whose
// GPU time stays near a budget (watchdog-safe on GPUs, responsive to cancellation everywhere). Here:
// how many rows the next band takes, the GPU timer, one band's submission, the refine pass's input
// rows, and reading a band back. The Renderer strings them together.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <vulkan/vulkan_raii.hpp>

#include "../../shaders/shared/gpu_types.h"
#include "image/image.h"
#include "render/render_options.h"
#include "vk/buffer.h"
#include "vk/context.h"

namespace vkray {

// Rows per band: about 64 K samples for the first, then as many rows as the measured speed fits in
// the budget; always whole workgroup rows (8), never more than the image window holds. The speed
// is that of the rows traced: rows that row culling filled cost next to nothing and say nothing of
// the rest (a sky band taken for the speed of the scene below it made one band of all the rest).
class BandSizer {
public:
  BandSizer(std::uint32_t width, std::uint32_t height, std::uint32_t windowRows, double budgetMs,
            std::uint32_t samplesPerPixel = 1);
  std::uint32_t rowsAt(std::uint32_t y, std::uint32_t end) const; // the band from row y, before row `end`
  void measured(std::uint32_t tracedRows, double gpuMs);          // 0 traced rows: nothing learnt

private:
  std::uint32_t windowRows_;
  std::uint32_t firstRows_;
  double budgetMs_;
  double rowsPerMs_ = 0.0; // 0 until the first band is timed
};

// GPU time between two timestamps written into a command buffer; where the device has no
// timestamps, the caller's wall time stands in.
class GpuTimer {
public:
  explicit GpuTimer(const vulkan::Context& context);
  bool enabled() const { return enabled_; }
  void reset(const vk::raii::CommandBuffer& cmd) const;
  void start(const vk::raii::CommandBuffer& cmd) const;
  void stop(const vk::raii::CommandBuffer& cmd) const;
  double elapsedMs(double wallMs) const; // after the submission completed

private:
  const vulkan::Context& context_;
  bool enabled_ = false;
  vk::raii::QueryPool queryPool_{nullptr};
};

struct BandTimes {
  double gpuMs = 0.0;
  double wallMs = 0.0;
};

// Submits one band (`record` records its dispatches), waits, and times it. A lost device is
// reported with the band's rows; `what` says which pass ("tracing", "refining").
BandTimes submitBand(const vulkan::Context& context, const GpuTimer& timer, const char* what, std::uint32_t y,
                     std::uint32_t rows, const std::function<void(const vk::raii::CommandBuffer&)>& record);

// The refine pass decides from the base pass's image with a row of neighbours across each band
// edge: uploads those rows of `base` into `prev` and sets the push constants that say where they are.
void uploadRefineRows(const Image& base, std::uint32_t y, std::uint32_t rows, vulkan::Buffer& prev,
                      gpu::PushConstants& push);

// Band rows of the image window: the averages of the sums into `image`, the hit records, or the
// first-hit AOVs (two texels per pixel).
void readBandImage(const vulkan::Buffer& window, std::uint32_t y, std::uint32_t rows, Image& image);
void readBandHits(const vulkan::Buffer& window, std::uint32_t width, std::uint32_t y, std::uint32_t rows,
                  std::vector<glm::vec4>& hits);
void readBandFirstHits(const vulkan::Buffer& window, std::uint32_t width, std::uint32_t y, std::uint32_t rows,
                       std::vector<FirstHit>& firstHits);

} // namespace vkray
