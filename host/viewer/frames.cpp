// Frames in flight (see frames.h).
#include "viewer/frames.h"

namespace vkray {

FrameRing::FrameRing(const vulkan::Context& context) : context_(context) {
  const auto& device = context.device();
  vulkan::vulkanStep("creating the viewer's frame resources", [&] {
    vk::raii::CommandBuffers buffers(
        device,
        vk::CommandBufferAllocateInfo(*context.commandPool(), vk::CommandBufferLevel::ePrimary, kFramesInFlight));
    for (std::uint32_t i = 0; i < kFramesInFlight; ++i) {
      slots_[i].cmd = std::move(buffers[i]);
      slots_[i].imageAcquired = vk::raii::Semaphore(device, vk::SemaphoreCreateInfo());
      // Signalled at creation, so the first wait on each slot passes.
      slots_[i].done = vk::raii::Fence(device, vk::FenceCreateInfo(vk::FenceCreateFlagBits::eSignaled));
    }
    timestamps_ = context.info().timestamps && context.timestampValidBits() > 0;
    if (timestamps_) {
      queries_ = vk::raii::QueryPool(
          device, vk::QueryPoolCreateInfo({}, vk::QueryType::eTimestamp, kStampCount * kFramesInFlight));
    }
  });
}

void FrameRing::collect(std::uint32_t index) {
  Slot& slot = slots_[index];
  if (!slot.submitted) return;
  vulkan::vulkanStep("waiting for a frame", [&] {
    while (context_.device().waitForFences(*slot.done, VK_TRUE, 1'000'000'000ull) == vk::Result::eTimeout) {
    }
  });
  slot.submitted = false;
  ++completed_.frames;
  if (!timestamps_) return;
  // Not a structured binding: clang 14 (the sanitizer build's compiler) cannot capture one in a lambda.
  auto results =
      queries_.getResults<std::uint64_t>(index * kStampCount, kStampCount, kStampCount * sizeof(std::uint64_t),
                                         sizeof(std::uint64_t), vk::QueryResultFlagBits::e64);
  if (results.first != vk::Result::eSuccess) return;
  const std::vector<std::uint64_t>& ticks = results.second;
  double msPerTick = context_.timestampPeriodNs() * 1e-6;
  auto span = [&](Stamp a, Stamp b) { return ticks[b] >= ticks[a] ? double(ticks[b] - ticks[a]) * msPerTick : 0.0; };
  completed_.sum.trace += span(kStart, kTraced);
  completed_.sum.resolve += span(kLayered, kResolved);
  completed_.sum.blit += span(kResolved, kBlitted);
  completed_.sum.overlay += span(kTraced, kLayered) + span(kBlitted, kDone);
}

FrameRing::Slot& FrameRing::begin() {
  current_ = (current_ + 1) % kFramesInFlight;
  collect(current_);
  return slots_[current_];
}

void FrameRing::waitAll() {
  for (std::uint32_t i = 0; i < kFramesInFlight; ++i) collect(i);
}

void FrameRing::resetStamps(const vk::raii::CommandBuffer& cmd) const {
  if (timestamps_) cmd.resetQueryPool(*queries_, current_ * kStampCount, kStampCount);
}

void FrameRing::stamp(const vk::raii::CommandBuffer& cmd, Stamp which, vk::PipelineStageFlagBits stage) const {
  if (timestamps_) cmd.writeTimestamp(stage, *queries_, current_ * kStampCount + which);
}

void FrameRing::submit(vk::Semaphore rendered) {
  Slot& slot = slots_[current_];
  vulkan::vulkanStep("submitting a frame", [&] {
    context_.device().resetFences(*slot.done);
    vk::Semaphore wait = *slot.imageAcquired;
    vk::PipelineStageFlags waitStage = vk::PipelineStageFlagBits::eTransfer;
    vk::CommandBuffer cmd = *slot.cmd;
    context_.queue().submit(vk::SubmitInfo(wait, waitStage, cmd, rendered), *slot.done);
  });
  slot.submitted = true;
}

FrameRing::Completed FrameRing::takeCompleted() {
  Completed c = completed_;
  completed_ = Completed();
  return c;
}

} // namespace vkray
