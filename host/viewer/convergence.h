// The viewer's estimate of how far its accumulating image is from converged, on the GPU
// (shaders/convergence.comp). The frames add samples uniformly; when the count per pixel has doubled
// since the last copy, the sums are copied (a buffer copy) and the copy before moves down a place,
// so that the two copies and the sums split each pixel's samples in three blocks (at a count n
// between copies at c and 2c: c/2, c/2 and n - c samples): render --noise-threshold's block
// estimate of the standard error (host/render/adaptive.cpp, four blocks there) follows per pixel.
// A second step reduces the estimates to a histogram of their logarithm and the count of pixels
// converged at the threshold (0.8 of the pixel's own squared estimate and 0.2 of its 3 x 3
// neighbourhood's mean square at most the threshold squared, as the headless progressive passes
// decide), read back by the host twice a second; the figures' cost is that pass's, and the copies'
// when the count doubles (docs/viewer.md has the measurements).
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include <vulkan/vulkan_raii.hpp>

#include "vk/buffer.h"
#include "vk/compute_pipeline.h"
#include "vk/context.h"
#include "vk/kernel_layout.h"

namespace vkray {

// What a measurement found, over the pixels of the image.
struct ConvergenceFigures {
  bool measured = false;     // false until a measurement has been read
  std::uint32_t samples = 0; // samples per pixel when measured
  std::uint64_t pixels = 0;
  std::uint64_t unestimated = 0; // pixels without an estimate yet (fewer than 2 samples)
  double errorMean = 0.0;        // mean estimate over the pixels with one (from the histogram: each
                                 // bin at its geometric centre, within 9 %; below 2^-24 counts as 0)
  double errorP95 = 0.0;         // 95th percentile over all pixels (+inf while 5 % have none), a bin's top
  double converged = 0.0;        // share of pixels converged at the threshold, 0..1
  bool estimated() const { return pixels > unestimated; }
};

class ConvergenceMeter {
public:
  ConvergenceMeter(const vulkan::Context& context, vulkan::PipelineCache* cache);

  // Points the passes at the Renderer's sums (a width x height window) and builds them for the noise
  // threshold; re-creates the copy and the estimates at a new size. Only while no frame is pending.
  void bind(vk::Buffer sums, vk::BufferView sumsView, vk::Extent2D size, double threshold);
  // Accumulation started again: the next record() clears the copy before it estimates.
  void restart() { copied_ = 0; }
  // Records, after a frame's trace, with `samples` per pixel in the image after it: the estimates
  // (estimate or measure), their reduction (measure), and the copy of the sums when the count has
  // doubled since the last one.
  void record(const vk::raii::CommandBuffer& cmd, std::uint32_t samples, bool estimate, bool measure);
  // The last measurement, once the frame that recorded it has completed.
  ConvergenceFigures read() const;
  // The estimates (R32F per pixel, row-major; the largest float where there is none), for the error
  // map, and read back (+inf where there is none) once the recording frame has completed.
  vk::Buffer errors() const { return errors_ ? errors_->handle() : vk::Buffer(); }
  std::vector<float> readErrors() const;
  double threshold() const { return threshold_; }

private:
  void buildPipelines();

  const vulkan::Context& context_;
  vulkan::PipelineCache* cache_;
  // Layouts before the pipelines and the set built from them.
  vulkan::KernelLayout layout_;
  vk::raii::DescriptorSet set_{nullptr};
  std::unique_ptr<vulkan::ComputePipeline> estimate_;
  std::unique_ptr<vulkan::ComputePipeline> reduce_;
  std::unique_ptr<vulkan::Buffer> half_;      // the sums when the count last doubled (RGBA32F texels)
  std::unique_ptr<vulkan::Buffer> earliest_;  // the copy before that (zero samples until there is one)
  std::unique_ptr<vulkan::Buffer> errors_;    // the estimates (R32F texels)
  std::unique_ptr<vulkan::Buffer> histogram_; // kHistogramWords, read by the host
  vk::Buffer sums_;
  vk::Extent2D size_{0, 0};
  double threshold_ = 0.0;
  std::uint32_t groupX_ = 0;
  std::uint32_t copied_ = 0;          // samples per pixel in the copy (0: none since the restart)
  std::uint32_t measuredSamples_ = 0; // of the last recorded measurement
};

} // namespace vkray
