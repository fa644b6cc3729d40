// Kernel variants: the plan of a render's pipelines and the library that builds them.
#include "render/kernel_variants.h"

#include "aov_spv.h"     // kAovSpv: shaders/aov.comp, the first-hit AOVs
#include "entry_spv.h"   // kEntrySpv: shaders/entry.comp, each tile's BVH entry points
#include "fill_spv.h"    // kFillSpv: shaders/fill.comp, row culling's background fill
#include "forward_spv.h" // kForwardSpv: shaders/forward.comp, photons from the lights
#include "hits_spv.h"    // kHitsSpv: shaders/hits.comp, the ray queries alone
#include "trace64_spv.h" // kTrace64Spv: the trace kernel intersecting in double (-DVKRAY_FLOAT64)
#include "trace_spv.h"   // kTraceSpv: shaders/trace.comp
#include "util/error.h"

#include <algorithm>
#include <chrono>
#include <exception>
#include <future>

namespace vkray {

SceneShape shapeOf(const GpuScene& g) {
  SceneShape s;
  s.spheres = g.spheres.size();
  s.triangles = g.triangles.size();
  s.polygons = g.polygons.size();
  s.planes = g.planes.size();
  s.occluderPlanes = g.occluderPlanes;
  s.lights = g.lights.size();
  s.materials = g.materials.size();
  s.hasBvh = !g.bvh.nodes.empty();
  s.shadowEntries = !g.shadowEntries.empty();
  s.bvhDepth = s.hasBvh ? g.bvh.stats.depth : 0;
  return s;
}

vulkan::Specialization specializationFor(const Features& f, const RenderSettings& s, const RenderOptions& o,
                                         const SceneShape& shape, SceneMemoryUse memory, bool centerSample,
                                         bool refinePass, bool listPass) {
  vulkan::Specialization spec;
  bool all = !o.specialize;
  spec.set(gpu::kSpecHasSpheres, all || f.spheres);
  spec.set(gpu::kSpecHasPlanes, all || f.planes);
  spec.set(gpu::kSpecHasTriangles, all || f.triangles);
  spec.set(gpu::kSpecHasPolygons, all || f.polygons);
  const bool useBvh = f.useBvh && shape.hasBvh;
  spec.set(gpu::kSpecUseBvh, useBvh);
  // Entry points are found for rays from the eye point; a lens's eye rays start off it.
  spec.set(gpu::kSpecEntryPoints, useBvh && o.entryPoints && !f.thinLens);
  spec.set(gpu::kSpecShadowEntries,
           useBvh && o.shadowEntryPoints != ShadowEntries::Off && shape.shadowEntries && (all || f.shadows));
  const int steps = o.bvhStepsPerVote > 0 ? o.bvhStepsPerVote : (shape.bvhDepth >= gpu::kBvhTwoStepDepth ? 2 : 1);
  spec.set(gpu::kSpecBvhStepsPerVote, useBvh ? static_cast<std::uint32_t>(std::clamp(steps, 1, 2)) : 1u);
  spec.set(gpu::kSpecShadows, all || f.shadows);
  spec.set(gpu::kSpecReflection, all || f.reflection);
  spec.set(gpu::kSpecRefraction, all || f.refraction);
  spec.set(gpu::kSpecStackSize, all ? static_cast<int>(gpu::kMaxStackSize) : f.stackSize);
  spec.set(gpu::kSpecCountStats, o.countStats);
  spec.set(gpu::kSpecNumerics, s.numerics == Numerics::Naive ? gpu::kNumericsNaive : gpu::kNumericsRobust);
  spec.set(gpu::kSpecFresnel, s.fresnel == FresnelMode::Schlick ? gpu::kFresnelSchlick : gpu::kFresnelExact);
  // Attenuated shadows only matter when something transmits; otherwise the any-hit test is exact.
  bool attenuate = s.transmissiveShadows == TransmissiveShadows::Attenuated && (all || f.anyTransmissiveMaterial);
  spec.set(gpu::kSpecShadowMode, attenuate ? gpu::kShadowsAttenuated : gpu::kShadowsOpaque);
  spec.set(gpu::kSpecChecker, all || f.checker);
  spec.set(gpu::kSpecSmoothNormals, all || f.smoothNormals);
  spec.set(gpu::kSpecTextures, all || f.textures);
  spec.set(gpu::kSpecAlphaMask, all || f.alphaMask);
  spec.set(gpu::kSpecVertexColors, all || f.vertexColors);
  spec.set(gpu::kSpecSpecularOnly, all || f.specularOnlyMaterial);
  spec.set(gpu::kSpecTextureFilter, static_cast<std::uint32_t>(s.textureFilter));
  spec.set(gpu::kSpecSceneInUbo, memory.scene);
  spec.set(gpu::kSpecShadingInUbo, memory.shading);
  spec.set(gpu::kSpecCenterSample, centerSample);
  spec.set(gpu::kSpecRefinePass, refinePass);
  spec.set(gpu::kSpecListPass, listPass);
  spec.set(gpu::kSpecPixelRays, o.pixelRays && !refinePass && !listPass);
  // The camera's, not an effect's: on exactly when the scene has an aperture, even in the
  // all-features pipeline, whose images must equal the specialized ones.
  spec.set(gpu::kSpecThinLens, f.thinLens);
  spec.set(gpu::kSpecRecordTree, o.recordTree && !refinePass && !listPass);
  // Bake small counts in so the driver unrolls the loops (see gpu_types.h); the all-features
  // pipeline keeps every count a runtime value.
  auto count = [&](std::size_t n) {
    return (all || !o.unroll || n > gpu::kMaxUnrolledCount) ? gpu::kRuntimeCount : static_cast<std::uint32_t>(n);
  };
  spec.set(gpu::kSpecSphereCount, f.useBvh ? gpu::kRuntimeCount : count(shape.spheres));
  spec.set(gpu::kSpecTriangleCount, f.useBvh ? gpu::kRuntimeCount : count(shape.triangles));
  spec.set(gpu::kSpecPolygonCount, f.useBvh ? gpu::kRuntimeCount : count(shape.polygons));
  spec.set(gpu::kSpecPlaneCount, count(shape.planes));
  spec.set(gpu::kSpecOccluderPlaneCount, count(shape.occluderPlanes));
  spec.set(gpu::kSpecLightCount, count(shape.lights));
  spec.set(gpu::kSpecMaterialCount, count(shape.materials));
  return spec;
}

KernelPlan planKernels(const Features& f, const RenderSettings& s, const RenderOptions& o, const SceneShape& shape,
                       SceneMemoryUse memory) {
  KernelPlan plan;
  // Only the shading kernel has a refine pass; the ray-query and AOV kernels trace pixel centres.
  const bool adaptive = o.kernel == Kernel::Shade && s.antialiasing == Antialiasing::Adaptive && s.spp > 1;
  // Single-sample passes go through pixel centres: a pipeline without the sample sequence.
  const bool center = !o.progressive && (s.spp == 1 || adaptive);
  auto key = [&](const RenderOptions& options, bool centerSample, bool refinePass, bool listPass = false) {
    // The first-hit AOVs are float32 whatever the render's precision: one eye ray, no tree to
    // keep from cracks, and a depth or normal needs no more.
    Precision precision = o.kernel == Kernel::Aov ? Precision::Float32 : s.precision;
    return PipelineKey{
        o.kernel, precision, specializationFor(f, s, options, shape, memory, centerSample, refinePass, listPass),
        o.foldSpirv ? vulkan::SpecializationFolding::FoldSpirv : vulkan::SpecializationFolding::DriverOnly};
  };
  if (o.kernel == Kernel::Forward) {
    plan.sample = key(o, false, false);
    return plan;
  }
  if (progressiveRender(s, o) && o.kernel == Kernel::Shade) {
    // Progressive passes over lists of open pixels (host/render/adaptive.h): one pipeline, with
    // entry points found once for the whole image, and no fill kernel (the host adds the sums of
    // rows that see nothing itself, Renderer::renderProgressive).
    plan.sample = key(o, false, false, true);
    plan.countStats = o.countStats;
    plan.entryPoints = f.useBvh && shape.hasBvh && o.entryPoints && !f.thinLens;
    return plan;
  }
  plan.sample = key(o, center, false);
  if (o.countStats && o.progressive) {
    // The same pass without counters, for the frames the viewer does not count. Planned with the
    // other rather than built on first use: a pipeline build is a pause of up to a second on CPU
    // devices, better before the first frame than after it.
    RenderOptions quiet = o;
    quiet.countStats = false;
    plan.quietSample = key(quiet, center, false);
  }
  if (adaptive) plan.refine = key(o, false, true);
  // Counting each pixel's rays needs every pixel traced: the fill writes no counts.
  // Row culling proves rows empty for rays from the eye point alone: off with a thin lens.
  plan.fill = o.cullRows && !o.pixelRays && o.kernel == Kernel::Shade && !f.thinLens;
  plan.countStats = o.countStats;
  plan.entryPoints = f.useBvh && shape.hasBvh && o.entryPoints && !f.thinLens;
  return plan;
}

namespace {

template <class Job, class Slot> bool queued(const std::vector<Job>& jobs, const Slot& slot) {
  return std::any_of(jobs.begin(), jobs.end(), [&](const Job& j) { return j.slot == &slot; });
}

} // namespace

KernelLibrary::KernelLibrary(const vulkan::Context& context, vk::PipelineLayout layout, vulkan::PipelineCache* cache)
    : context_(context), layout_(layout), cache_(cache) {}

KernelSet KernelLibrary::realize(const KernelPlan& plan) {
  std::vector<Job> jobs;
  auto& sample = traceSlot(plan.sample, "", jobs);
  auto& quietSample = plan.quietSample ? traceSlot(*plan.quietSample, " (quiet)", jobs) : sample;
  std::unique_ptr<vulkan::ComputePipeline>* fill = nullptr;
  std::unique_ptr<vulkan::ComputePipeline>* quietFill = nullptr;
  if (plan.fill) {
    // One fill per counting mode, whatever the scene.
    fill = &fillSlot(plan.countStats, jobs);
    quietFill = &quietSample != &sample ? &fillSlot(false, jobs) : fill;
  }
  auto* entry = plan.entryPoints ? &entrySlot(jobs) : nullptr;
  auto* refine = plan.refine ? &traceSlot(*plan.refine, " (refine)", jobs) : nullptr;

  KernelSet set;
  auto start = std::chrono::steady_clock::now();
  auto build = [&](const Job& job) {
    return std::make_unique<vulkan::ComputePipeline>(context_, job.code, layout_, job.spec,
                                                     cache_ ? &cache_->cache() : nullptr, job.name, job.folding,
                                                     cache_ ? &cache_->foldCache() : nullptr);
  };
  // vkCreateComputePipelines may run on several threads at once, with one pipeline cache
  // (VkPipelineCache is internally synchronized); the first job runs on this thread.
  std::vector<std::future<std::unique_ptr<vulkan::ComputePipeline>>> others;
  for (std::size_t i = 1; i < jobs.size(); ++i) others.push_back(std::async(std::launch::async, build, jobs[i]));
  std::exception_ptr failure;
  if (!jobs.empty()) {
    try {
      *jobs[0].slot = build(jobs[0]);
    } catch (...) {
      failure = std::current_exception();
    }
  }
  for (std::size_t i = 1; i < jobs.size(); ++i) {
    try {
      *jobs[i].slot = others[i - 1].get();
    } catch (...) {
      if (!failure) failure = std::current_exception();
    }
  }
  if (failure) std::rethrow_exception(failure);
  if (!jobs.empty()) {
    set.buildMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    for (const Job& job : jobs) {
      const vulkan::ComputePipeline& p = **job.slot;
      set.built.push_back(PipelineBuild{job.name, p.creationMs(), p.foldMs(), p.spirvBytes(), 0.0, p.foldKept()});
      set.builtPipelines.push_back(&p);
    }
    if (cache_) cache_->save();
  }
  set.sample = sample.get();
  set.quietSample = quietSample.get();
  set.fill = fill ? fill->get() : nullptr;
  set.quietFill = quietFill ? quietFill->get() : nullptr;
  set.entry = entry ? entry->get() : nullptr;
  set.refine = refine ? refine->get() : nullptr;
  return set;
}

std::unique_ptr<vulkan::ComputePipeline>& KernelLibrary::traceSlot(const PipelineKey& key, const char* role,
                                                                   std::vector<Job>& jobs) {
  std::unique_ptr<vulkan::ComputePipeline>& slot = trace_[key];
  if (slot || queued(jobs, slot)) return slot;
  bool f64 = key.precision == Precision::Float64;
  if (f64 && !context_.float64Enabled()) {
    throw InputError("render.precision", "float64 needs shaderFloat64, which " + context_.info().name + " lacks");
  }
  if (f64 && key.kernel == Kernel::Hits) throw InputError("render.precision", "the ray-query kernel is float32 only");
  std::span<const std::uint32_t> code = key.kernel == Kernel::Hits      ? std::span<const std::uint32_t>(kHitsSpv)
                                        : key.kernel == Kernel::Aov     ? std::span<const std::uint32_t>(kAovSpv)
                                        : key.kernel == Kernel::Forward ? std::span<const std::uint32_t>(kForwardSpv)
                                        : f64                           ? std::span<const std::uint32_t>(kTrace64Spv)
                                                                        : std::span<const std::uint32_t>(kTraceSpv);
  const char* kernel = key.kernel == Kernel::Hits      ? "hits"
                       : key.kernel == Kernel::Aov     ? "aov"
                       : key.kernel == Kernel::Forward ? "forward"
                                                       : "trace";
  std::string name = std::string(kernel) + role + (f64 ? " (float64)" : "");
  jobs.push_back(Job{&slot, code, key.spec, name, key.folding});
  return slot;
}

std::unique_ptr<vulkan::ComputePipeline>& KernelLibrary::fillSlot(bool countStats, std::vector<Job>& jobs) {
  std::unique_ptr<vulkan::ComputePipeline>& slot = fill_[countStats ? 1 : 0];
  if (!slot && !queued(jobs, slot)) {
    vulkan::Specialization spec;
    spec.set(gpu::kSpecCountStats, countStats);
    jobs.push_back(Job{&slot, kFillSpv, spec, countStats ? "fill" : "fill (quiet)"});
  }
  return slot;
}

std::unique_ptr<vulkan::ComputePipeline>& KernelLibrary::entrySlot(std::vector<Job>& jobs) {
  if (!entry_ && !queued(jobs, entry_))
    jobs.push_back(Job{&entry_, kEntrySpv, vulkan::Specialization(), "entry points"});
  return entry_;
}

} // namespace vkray
