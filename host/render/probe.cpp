// Probe kernel dispatch (see probe.h).
#include "render/probe.h"

#include "probe_spv.h" // kProbeSpv
#include "vk/buffer.h"

namespace vkray {

Probe::Probe(const vulkan::Context& context) : context_(context) {
  vulkan::vulkanStep("creating the probe pipeline", [&] {
    layout_ = vulkan::KernelLayout(context,
                                   {{gpu::kProbeBindingQueries, vk::DescriptorType::eStorageBuffer},
                                    {gpu::kProbeBindingResults, vk::DescriptorType::eStorageBuffer},
                                    {gpu::kProbeBindingVertices, vk::DescriptorType::eStorageBuffer}},
                                   sizeof(std::uint32_t));
  });
  pipeline_ =
      std::make_unique<vulkan::ComputePipeline>(context, std::span<const std::uint32_t>(kProbeSpv),
                                                layout_.pipelineLayout(), vulkan::Specialization{}, nullptr, "probe");
}

std::vector<gpu::ProbeResult> Probe::run(const std::vector<gpu::ProbeQuery>& queries,
                                         const std::vector<glm::vec4>& polygonVertices) {
  using vulkan::Buffer;
  using vulkan::MemoryUse;
  Buffer in(context_, queries.size() * sizeof(gpu::ProbeQuery), vk::BufferUsageFlagBits::eStorageBuffer,
            MemoryUse::DeviceLocal, "probe queries");
  in.write(queries.data(), queries.size() * sizeof(gpu::ProbeQuery));
  Buffer out(context_, queries.size() * sizeof(gpu::ProbeResult), vk::BufferUsageFlagBits::eStorageBuffer,
             MemoryUse::DeviceLocal, "probe results");
  Buffer verts(context_, polygonVertices.size() * sizeof(glm::vec4), vk::BufferUsageFlagBits::eStorageBuffer,
               MemoryUse::DeviceLocal, "probe vertices");
  verts.write(polygonVertices.data(), polygonVertices.size() * sizeof(glm::vec4));

  vk::raii::DescriptorSets sets = layout_.allocate();
  std::array<vk::DescriptorBufferInfo, 3> infos{vk::DescriptorBufferInfo(in.handle(), 0, VK_WHOLE_SIZE),
                                                vk::DescriptorBufferInfo(out.handle(), 0, VK_WHOLE_SIZE),
                                                vk::DescriptorBufferInfo(verts.handle(), 0, VK_WHOLE_SIZE)};
  std::array<vk::WriteDescriptorSet, 3> writes;
  for (std::uint32_t b = 0; b < 3; ++b) {
    writes[b] = vk::WriteDescriptorSet(*sets.front(), b, 0, 1, vk::DescriptorType::eStorageBuffer, nullptr, &infos[b]);
  }
  context_.device().updateDescriptorSets(writes, {});

  auto count = static_cast<std::uint32_t>(queries.size());
  context_.submitAndWait("running the probe kernel", [&](const vk::raii::CommandBuffer& cmd) {
    cmd.bindPipeline(vk::PipelineBindPoint::eCompute, pipeline_->handle());
    cmd.bindDescriptorSets(vk::PipelineBindPoint::eCompute, layout_.pipelineLayout(), 0, {*sets.front()}, {});
    cmd.pushConstants<std::uint32_t>(layout_.pipelineLayout(), vk::ShaderStageFlagBits::eCompute, 0, count);
    cmd.dispatch((count + 63) / 64, 1, 1);
    vk::MemoryBarrier barrier(vk::AccessFlagBits::eShaderWrite,
                              vk::AccessFlagBits::eHostRead | vk::AccessFlagBits::eTransferRead);
    cmd.pipelineBarrier(vk::PipelineStageFlagBits::eComputeShader,
                        vk::PipelineStageFlagBits::eHost | vk::PipelineStageFlagBits::eTransfer, {}, barrier, {}, {});
  });
  std::vector<gpu::ProbeResult> results(queries.size());
  out.read(results.data(), results.size() * sizeof(gpu::ProbeResult));
  return results;
}

} // namespace vkray
