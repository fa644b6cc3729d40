// Host side of shaders/probe.comp: runs arrays of ProbeQuery through the shader library's own
// intersection, offset and optics functions on the device, for numerical tests.
#pragma once

#include <vector>

#include <vulkan/vulkan_raii.hpp>

#include "../../shaders/shared/gpu_types.h"
#include "vk/compute_pipeline.h"
#include "vk/context.h"
#include "vk/kernel_layout.h"

namespace vkray {

class Probe {
public:
  explicit Probe(const vulkan::Context& context);
  // polygonVertices backs kProbePolygon queries (op.z/op.w index it).
  std::vector<gpu::ProbeResult> run(const std::vector<gpu::ProbeQuery>& queries,
                                    const std::vector<glm::vec4>& polygonVertices = {});

private:
  const vulkan::Context& context_;
  vulkan::KernelLayout layout_;
  std::unique_ptr<vulkan::ComputePipeline> pipeline_;
};

} // namespace vkray
