// Kernel variants: the plan of a render's pipelines and the library that builds them.
#include "render/kernel_variants.h"

#include "entry_spv.h"   // kEntrySpv: shaders/entry.comp, each tile's BVH entry points
#include "fill_spv.h"    // kFillSpv: shaders/fill.comp, row culling's background fill
#include "hits_spv.h"    // kHitsSpv: shaders/hits.comp, the ray queries alone
#include "trace64_spv.h" // kTrace64Spv: the trace kernel intersecting in double (-DVKRAY_FLOAT64)
#include "trace_spv.h"   // kTraceSpv: shaders/trace.comp
#include "util/error.h"

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
  return s;
}

vulkan::Specialization specializationFor(const Features& f, const RenderSettings& s, const RenderOptions& o,
                                         const SceneShape& shape, SceneMemoryUse memory, bool centerSample,
                                         bool refinePass) {
  vulkan::Specialization spec;
  bool all = !o.specialize;
  spec.set(gpu::kSpecHasSpheres, all || f.spheres);
  spec.set(gpu::kSpecHasPlanes, all || f.planes);
  spec.set(gpu::kSpecHasTriangles, all || f.triangles);
  spec.set(gpu::kSpecHasPolygons, all || f.polygons);
  const bool useBvh = f.useBvh && shape.hasBvh;
  spec.set(gpu::kSpecUseBvh, useBvh);
  spec.set(gpu::kSpecEntryPoints, useBvh && o.entryPoints);
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
  spec.set(gpu::kSpecTextureFilter, static_cast<std::uint32_t>(s.textureFilter));
  spec.set(gpu::kSpecSceneInUbo, memory.scene);
  spec.set(gpu::kSpecShadingInUbo, memory.shading);
  spec.set(gpu::kSpecCenterSample, centerSample);
  spec.set(gpu::kSpecRefinePass, refinePass);
  // Bake small counts in so the driver unrolls the loops (see gpu_types.h); the all-features
  // pipeline keeps every count a runtime value.
  auto count = [&](std::size_t n) {
    return (all || n > gpu::kMaxUnrolledCount) ? gpu::kRuntimeCount : static_cast<std::uint32_t>(n);
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
  const bool adaptive = s.antialiasing == Antialiasing::Adaptive && s.spp > 1;
  // Single-sample passes go through pixel centres: a pipeline without the sample sequence.
  const bool center = !o.progressive && (s.spp == 1 || adaptive);
  auto key = [&](const RenderOptions& options, bool centerSample, bool refinePass) {
    return PipelineKey{o.kernel, s.precision,
                       specializationFor(f, s, options, shape, memory, centerSample, refinePass)};
  };
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
  plan.fill = o.cullRows && o.kernel == Kernel::Shade;
  plan.countStats = o.countStats;
  plan.entryPoints = f.useBvh && shape.hasBvh && o.entryPoints;
  return plan;
}

KernelLibrary::KernelLibrary(const vulkan::Context& context, vk::PipelineLayout layout, vulkan::PipelineCache* cache)
    : context_(context), layout_(layout), cache_(cache) {}

KernelSet KernelLibrary::realize(const KernelPlan& plan) {
  KernelSet set;
  set.sample = &trace(plan.sample, set.buildMs);
  set.quietSample = plan.quietSample ? &trace(*plan.quietSample, set.buildMs) : set.sample;
  if (plan.fill) {
    // One fill per counting mode, whatever the scene.
    set.fill = &fill(plan.countStats, set.buildMs);
    set.quietFill = set.quietSample != set.sample ? &fill(false, set.buildMs) : set.fill;
  }
  if (plan.entryPoints) set.entry = &entry(set.buildMs);
  if (plan.refine) set.refine = &trace(*plan.refine, set.buildMs);
  return set;
}

const vulkan::ComputePipeline& KernelLibrary::trace(const PipelineKey& key, double& buildMs) {
  auto it = trace_.find(key);
  if (it == trace_.end()) {
    bool f64 = key.precision == Precision::Float64;
    if (f64 && !context_.float64Enabled()) {
      throw InputError("render.precision", "float64 needs shaderFloat64, which " + context_.info().name + " lacks");
    }
    if (f64 && key.kernel == Kernel::Hits) throw InputError("render.precision", "the ray-query kernel is float32 only");
    std::span<const std::uint32_t> code = key.kernel == Kernel::Hits ? std::span<const std::uint32_t>(kHitsSpv)
                                          : f64                      ? std::span<const std::uint32_t>(kTrace64Spv)
                                                                     : std::span<const std::uint32_t>(kTraceSpv);
    const char* name = key.kernel == Kernel::Hits ? "hits" : f64 ? "trace (float64)" : "trace";
    it = trace_.emplace(key, build(code, key.spec, name)).first;
    buildMs += it->second->creationMs();
  }
  return *it->second;
}

const vulkan::ComputePipeline& KernelLibrary::fill(bool countStats, double& buildMs) {
  std::unique_ptr<vulkan::ComputePipeline>& p = fill_[countStats ? 1 : 0];
  if (!p) {
    vulkan::Specialization spec;
    spec.set(gpu::kSpecCountStats, countStats);
    p = build(kFillSpv, spec, "fill");
    buildMs += p->creationMs();
  }
  return *p;
}

const vulkan::ComputePipeline& KernelLibrary::entry(double& buildMs) {
  if (!entry_) {
    entry_ = build(kEntrySpv, vulkan::Specialization(), "entry points");
    buildMs += entry_->creationMs();
  }
  return *entry_;
}

std::unique_ptr<vulkan::ComputePipeline> KernelLibrary::build(std::span<const std::uint32_t> code,
                                                              const vulkan::Specialization& spec, const char* name) {
  auto pipeline = std::make_unique<vulkan::ComputePipeline>(context_, code, layout_, spec,
                                                            cache_ ? &cache_->cache() : nullptr, name);
  if (cache_) cache_->save();
  return pipeline;
}

} // namespace vkray
