// Frames in flight: per-frame command buffer, "image acquired" semaphore, fence and timestamp
// queries, reused round-robin. The GPU times of a frame's parts are read once its fence has passed.
#pragma once

#include <array>
#include <cstdint>

#include <vulkan/vulkan_raii.hpp>

#include "vk/context.h"

namespace vkray {

// GPU milliseconds of one frame's parts (timestamp queries; zero where the device has none).
struct FrameGpuTimes {
  double trace = 0.0;   // the Renderer's dispatch
  double resolve = 0.0; // resolve pass (sums to display colour)
  double blit = 0.0;    // blit to the swapchain image
  double overlay = 0.0; // the overlay's render pass (on the layer or the swapchain image)
};

class FrameRing {
public:
  static constexpr std::uint32_t kFramesInFlight = 2;
  // Timestamps per frame: before the trace, after it, after the overlay's layer (direct path; none
  // drawn in most frames), after the resolve, after the blit, after the overlay's pass (blit path).
  enum Stamp : std::uint32_t { kStart, kTraced, kLayered, kResolved, kBlitted, kDone, kStampCount };

  explicit FrameRing(const vulkan::Context& context);

  struct Slot {
    vk::raii::CommandBuffer cmd{nullptr};
    vk::raii::Semaphore imageAcquired{nullptr};
    vk::raii::Fence done{nullptr};
    bool submitted = false; // fence pending or signalled by a submission whose times are unread
  };

  // The next slot, once the GPU is done with its previous use (its times are then in `finished`).
  Slot& begin();
  // Waits for every submitted frame; their times go to `finished`.
  void waitAll();
  // Records a timestamp for the current slot (no-op without timestamp support).
  void stamp(const vk::raii::CommandBuffer& cmd, Stamp which, vk::PipelineStageFlagBits stage) const;
  void resetStamps(const vk::raii::CommandBuffer& cmd) const;
  // Submits the current slot's command buffer: waits for `acquired` at the transfer stage (the first
  // write to the swapchain image is the blit), signals `rendered`, and the slot's fence.
  void submit(vk::Semaphore rendered);

  // Times of frames completed since the last call (sum and count).
  struct Completed {
    FrameGpuTimes sum;
    std::uint32_t frames = 0;
  };
  Completed takeCompleted();
  bool hasTimestamps() const { return timestamps_; }

private:
  void collect(std::uint32_t index);

  const vulkan::Context& context_;
  bool timestamps_ = false;
  vk::raii::QueryPool queries_{nullptr}; // kStampCount per slot
  std::array<Slot, kFramesInFlight> slots_;
  std::uint32_t current_ = kFramesInFlight - 1;
  Completed completed_;
};

} // namespace vkray
