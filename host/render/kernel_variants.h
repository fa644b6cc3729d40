// The kernel variants of a render. planKernels is a pure function from what the scene calls for,
// the settings, the options and where the scene is read from, to the pipelines the render needs
// (named by the SPIR-V they come from and their specialization); KernelLibrary builds each once
// per process (with the on-disk cache when there is one) and hands out the set.
#pragma once

#include <cstddef>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include "render/gpu_scene.h"
#include "render/render_options.h"
#include "render/scene_buffers.h"
#include "scene/features.h"
#include "vk/compute_pipeline.h"
#include "vk/context.h"

namespace vkray {

// The sizes of the scene's arrays that the kernels bake in, and whether it has a BVH.
struct SceneShape {
  std::size_t spheres = 0, triangles = 0, polygons = 0, planes = 0, occluderPlanes = 0, lights = 0, materials = 0;
  bool hasBvh = false;
  bool shadowEntries = false; // the scene has a shadow entry points table (GpuScene::shadowEntries)
  int bvhDepth = 0;           // the BVH's depth (BvhStats::depth), 0 without one
};
SceneShape shapeOf(const GpuScene& scene);

// One trace-kernel pipeline: its SPIR-V (kernel and precision) and specialization.
struct PipelineKey {
  Kernel kernel = Kernel::Shade;
  Precision precision = Precision::Float32;
  vulkan::Specialization spec;
  vulkan::SpecializationFolding folding = vulkan::SpecializationFolding::FoldSpirv;
  bool operator<(const PipelineKey& o) const {
    return std::tie(kernel, precision, spec, folding) < std::tie(o.kernel, o.precision, o.spec, o.folding);
  }
  bool operator==(const PipelineKey& o) const {
    return kernel == o.kernel && precision == o.precision && spec == o.spec && folding == o.folding;
  }
};

// The specialization of one pass of the trace kernel. centerSample: single samples through pixel
// centres (no sample sequence); refinePass: adaptive antialiasing's second pass; listPass: a
// progressive render's pass over a list of open pixels.
vulkan::Specialization specializationFor(const Features& features, const RenderSettings& settings,
                                         const RenderOptions& options, const SceneShape& shape, SceneMemoryUse memory,
                                         bool centerSample, bool refinePass, bool listPass = false);

// The pipelines one render (or one prepared viewer frame) runs.
struct KernelPlan {
  PipelineKey sample;                     // the sample pass (kPassSample; kPassList when progressive)
  std::optional<PipelineKey> quietSample; // the same without counters (frames the viewer does not count)
  std::optional<PipelineKey> refine;      // adaptive antialiasing's refine pass
  bool fill = false;                      // row culling's background fill (shaders/fill.comp)
  bool countStats = false;                // the fill counts rays like the sample pass
  bool entryPoints = false;               // each tile's BVH entry points first (shaders/entry.comp)
};

KernelPlan planKernels(const Features& features, const RenderSettings& settings, const RenderOptions& options,
                       const SceneShape& shape, SceneMemoryUse memory);

// A plan's pipelines, built; null where the plan has none.
struct KernelSet {
  const vulkan::ComputePipeline* sample = nullptr;
  const vulkan::ComputePipeline* quietSample = nullptr; // sample itself when the plan has no quiet pass
  const vulkan::ComputePipeline* refine = nullptr;
  const vulkan::ComputePipeline* fill = nullptr;      // sample's fill for culled rows
  const vulkan::ComputePipeline* quietFill = nullptr; // quietSample's
  const vulkan::ComputePipeline* entry = nullptr;
  double buildMs = 0.0; // wall time building this set's new pipelines, side by side (0: all reused)
  // Each pipeline built for this set, with its own creation time, in plan order, and the
  // pipeline itself (builtPipelines[i] is built[i]'s).
  std::vector<PipelineBuild> built;
  std::vector<const vulkan::ComputePipeline*> builtPipelines;
};

class KernelLibrary {
public:
  // cache may be null (no on-disk pipeline cache).
  KernelLibrary(const vulkan::Context& context, vk::PipelineLayout layout, vulkan::PipelineCache* cache);

  // The plan's pipelines, building the ones this process has not built yet, each on its own
  // thread: a driver that compiles on the CPU (lavapipe) compiles one pipeline on one core.
  KernelSet realize(const KernelPlan& plan);

private:
  // A pipeline to build: its slot in the library, its SPIR-V, specialization and name.
  struct Job {
    std::unique_ptr<vulkan::ComputePipeline>* slot;
    std::span<const std::uint32_t> code;
    vulkan::Specialization spec;
    std::string name;
    vulkan::SpecializationFolding folding = vulkan::SpecializationFolding::FoldSpirv;
  };
  // Each returns the pipeline's slot, queueing a job when it is neither built nor queued.
  std::unique_ptr<vulkan::ComputePipeline>& traceSlot(const PipelineKey& key, const char* role, std::vector<Job>& jobs);
  std::unique_ptr<vulkan::ComputePipeline>& fillSlot(bool countStats, std::vector<Job>& jobs);
  std::unique_ptr<vulkan::ComputePipeline>& entrySlot(std::vector<Job>& jobs);

  const vulkan::Context& context_;
  vk::PipelineLayout layout_;
  vulkan::PipelineCache* cache_;
  std::map<PipelineKey, std::unique_ptr<vulkan::ComputePipeline>> trace_;
  std::unique_ptr<vulkan::ComputePipeline> fill_[2]; // [countStats]
  std::unique_ptr<vulkan::ComputePipeline> entry_;
};

} // namespace vkray
