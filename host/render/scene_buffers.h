// The scene's device buffers: every packed array uploaded once per scene, the uniform copy of the
// small arrays, the choice of which of the two the kernels read, and how much lives in vkray's own
// huge pages.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "render/gpu_scene.h"
#include "render/render_options.h"
#include "vk/buffer.h"
#include "vk/context.h"

namespace vkray {

// Where one render's kernels read the small arrays from.
struct SceneMemoryUse {
  bool scene = false;   // every small array from the uniform block (kSpecSceneInUbo)
  bool shading = false; // materials, lights and planes from it, the primitives not (kSpecShadingInUbo)
};

// The scene's buffers in vkray's own pages (host/vk/host_pages.h): how many bytes, and how many of
// them the kernel backs with huge pages now. Both 0 where the device imports no host memory.
struct HostPageUse {
  std::size_t bytes = 0;
  std::size_t hugeBytes = 0;
};

class SceneBuffers {
public:
  explicit SceneBuffers(const vulkan::Context& context);

  void upload(const GpuScene& scene);
  // The BVH records and, after them, the shadow entry points' table (GpuScene::shadowEntries):
  // upload() calls it, and Renderer::prepare again once it has built the table. The descriptors
  // that name the old buffer must be rewritten.
  void uploadBvhNodes(const GpuScene& scene);
  bool uploaded() const { return buffers_[gpu::kBindingMaterials] != nullptr; }
  double uploadMs() const { return uploadMs_; }

  // Uniform: the whole scene must fit the block (else an error naming --scene-memory); Storage:
  // never; Auto: whatever fits, on CPU devices, where a uniform read is one gather.
  SceneMemoryUse memoryFor(SceneMemory requested) const;

  // The buffer behind one of the scene's bindings (gpu::kBinding*).
  const vulkan::Buffer& at(std::uint32_t binding) const { return *buffers_[binding]; }
  HostPageUse hostPages() const;

private:
  const vulkan::Context& context_;
  std::vector<std::unique_ptr<vulkan::Buffer>> buffers_; // indexed by binding (SSBO, texel and UBO copies)
  bool sceneFitsUbo_ = false;
  bool shadingFitsUbo_ = false; // materials, lights and planes (a mesh scene's primitives do not fit)
  double uploadMs_ = 0.0;
};

} // namespace vkray
