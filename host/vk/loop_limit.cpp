// Context::loopLimit: whether the driver ends long loops early, measured with shaders/loop_limit.comp.
#include <array>

#include "loop_limit_spv.h" // kLoopLimitSpv
#include "vk/buffer.h"
#include "vk/compute_pipeline.h"
#include "vk/context.h"
#include "vk/kernel_layout.h"

namespace vkray::vulkan {

namespace {

// Twice Mesa 22's cut, and a few milliseconds of one CPU lane.
constexpr std::uint32_t kTurns = 1u << 17;

std::uint32_t measureLoopLimit(const Context& context) {
  KernelLayout layout;
  vulkanStep("creating the loop-limit probe's layout", [&] {
    layout = KernelLayout(context, {{0, vk::DescriptorType::eStorageBuffer}}, sizeof(std::uint32_t));
  });
  ComputePipeline pipeline(context, std::span<const std::uint32_t>(kLoopLimitSpv), layout.pipelineLayout(),
                           Specialization{}, nullptr, "loop-limit probe");
  Buffer result(context, 2 * sizeof(std::uint32_t), vk::BufferUsageFlagBits::eStorageBuffer, MemoryUse::DeviceLocal,
                "loop-limit probe result");
  vk::raii::DescriptorSets sets = layout.allocate();
  vk::DescriptorBufferInfo info(result.handle(), 0, VK_WHOLE_SIZE);
  vk::WriteDescriptorSet write(*sets.front(), 0, 0, 1, vk::DescriptorType::eStorageBuffer, nullptr, &info);
  context.device().updateDescriptorSets(write, {});
  context.submitAndWait("running the loop-limit probe", [&](const vk::raii::CommandBuffer& cmd) {
    cmd.bindPipeline(vk::PipelineBindPoint::eCompute, pipeline.handle());
    cmd.bindDescriptorSets(vk::PipelineBindPoint::eCompute, layout.pipelineLayout(), 0, {*sets.front()}, {});
    cmd.pushConstants<std::uint32_t>(layout.pipelineLayout(), vk::ShaderStageFlagBits::eCompute, 0, kTurns);
    cmd.dispatch(1, 1, 1);
    vk::MemoryBarrier barrier(vk::AccessFlagBits::eShaderWrite,
                              vk::AccessFlagBits::eHostRead | vk::AccessFlagBits::eTransferRead);
    cmd.pipelineBarrier(vk::PipelineStageFlagBits::eComputeShader,
                        vk::PipelineStageFlagBits::eHost | vk::PipelineStageFlagBits::eTransfer, {}, barrier, {}, {});
  });
  std::array<std::uint32_t, 2> turnsAndState{};
  result.read(turnsAndState.data(), sizeof turnsAndState);
  return turnsAndState[0] >= kTurns ? 0u : turnsAndState[0];
}

} // namespace

std::uint32_t Context::loopLimit() const {
  std::lock_guard lock(loopLimitMutex_);
  if (!loopLimit_) loopLimit_ = measureLoopLimit(*this);
  return *loopLimit_;
}

} // namespace vkray::vulkan
