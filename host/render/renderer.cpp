// Renderer: scene upload, specialized pipelines, banded dispatch, readback and statistics.
#include "render/renderer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>

#include "entry_spv.h"   // kEntrySpv: shaders/entry.comp, each tile's BVH entry points
#include "fill_spv.h"    // kFillSpv: shaders/fill.comp, row culling's background fill
#include "hits_spv.h"    // kHitsSpv: shaders/hits.comp, the ray queries alone
#include "trace64_spv.h" // kTrace64Spv: the same, intersecting in double (-DVKRAY_FLOAT64)
#include "trace_spv.h"   // kTraceSpv: shaders/trace.comp compiled at build time
#include "util/error.h"

namespace vkray {

namespace {

using Clock = std::chrono::steady_clock;

double msSince(Clock::time_point t) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

// Bytes of image window the renderer allows itself: bands of rows are traced into it and read back.
constexpr vk::DeviceSize kImageWindowBudget = 64ull << 20;
// The image window and the refine pass's copy are texel buffers of (sum rgb, samples).
constexpr vk::Format kImageTexelFormat = vk::Format::eR32G32B32A32Sfloat;

bool isUniformBinding(std::uint32_t b) {
  return b == gpu::kBindingFrame || b == gpu::kBindingSceneUbo;
}

// The mesh-sized arrays are texel buffers (see shaders/lib/scene.glsl); BVH records and triangles,
// the hottest, are storage texel buffers (imageLoad compiles inline on lavapipe), the others
// uniform texel buffers. (The image and its refine-pass copy are storage texel buffers too, but
// the renderer's own, not the scene's.)
bool isTexelBinding(std::uint32_t b) {
  return b == gpu::kBindingTriangles || b == gpu::kBindingNormals || b == gpu::kBindingBvhNodes ||
         b == gpu::kBindingPrimRefs || b == gpu::kBindingEntryTexels;
}

// Four storage texel buffers, the least maxPerStageDescriptorStorageImages a device may have.
bool isStorageTexelBinding(std::uint32_t b) {
  return b == gpu::kBindingBvhNodes || b == gpu::kBindingTriangles || b == gpu::kBindingImage ||
         b == gpu::kBindingPrevImage;
}

vk::DescriptorType descriptorType(std::uint32_t b) {
  if (isStorageTexelBinding(b)) return vk::DescriptorType::eStorageTexelBuffer;
  if (isTexelBinding(b)) return vk::DescriptorType::eUniformTexelBuffer;
  return isUniformBinding(b) ? vk::DescriptorType::eUniformBuffer : vk::DescriptorType::eStorageBuffer;
}

template <typename T>
void uploadArray(std::unique_ptr<vulkan::Buffer>& buffer, const vulkan::Context& ctx, const std::vector<T>& data,
                 const std::string& name) {
  buffer = std::make_unique<vulkan::Buffer>(ctx, data.size() * sizeof(T), vk::BufferUsageFlagBits::eStorageBuffer,
                                            vulkan::MemoryUse::DeviceLocal, name);
  buffer->write(data.data(), data.size() * sizeof(T));
}

template <typename T>
void uploadTexels(std::unique_ptr<vulkan::Buffer>& buffer, const vulkan::Context& ctx, const std::vector<T>& data,
                  vk::Format format, const std::string& name) {
  buffer.reset(); // the old array's memory goes back first
  buffer = std::make_unique<vulkan::Buffer>(ctx, data.size() * sizeof(T), format, vulkan::MemoryUse::DeviceLocal, name);
  buffer->write(data.data(), data.size() * sizeof(T));
}

// Entry-point tiles (shaders/entry.comp) covering `rows` rows of a `width`-pixel image.
std::uint32_t entryTileCount(std::uint32_t width, std::uint32_t rows) {
  return ((width + gpu::kEntryTileSize - 1) / gpu::kEntryTileSize) *
         ((rows + gpu::kEntryTileSize - 1) / gpu::kEntryTileSize);
}

// Copies an array into its slot of the packed SceneUbo.
template <typename T, std::size_t N> void packUniform(T (&slot)[N], const std::vector<T>& data) {
  std::copy(data.begin(), data.end(), slot);
}

} // namespace

RayStats& RayStats::operator+=(const RayStats& o) {
  eye += o.eye;
  shadow += o.shadow;
  reflection += o.reflection;
  refraction += o.refraction;
  bailoutSaved += o.bailoutSaved;
  stackOverflow += o.stackOverflow;
  refinedPixels += o.refinedPixels;
  nonFinite += o.nonFinite;
  truncated += o.truncated;
  maxDepth = std::max(maxDepth, o.maxDepth);
  return *this;
}

Renderer::Renderer(const vulkan::Context& context, vulkan::PipelineCache* cache) : context_(context), cache_(cache) {
  const auto& device = context.device();
  vulkan::vulkanStep("creating the renderer's layouts", [&] {
    std::vector<vk::DescriptorSetLayoutBinding> bindings;
    for (std::uint32_t b = 0; b < gpu::kBindingCount; ++b) {
      bindings.emplace_back(b, descriptorType(b), 1, vk::ShaderStageFlagBits::eCompute);
    }
    setLayout_ = vk::raii::DescriptorSetLayout(device, vk::DescriptorSetLayoutCreateInfo({}, bindings));
    vk::PushConstantRange push(vk::ShaderStageFlagBits::eCompute, 0, sizeof(gpu::PushConstants));
    vk::DescriptorSetLayout layouts[] = {*setLayout_};
    pipelineLayout_ = vk::raii::PipelineLayout(device, vk::PipelineLayoutCreateInfo({}, layouts, push));
    std::array<vk::DescriptorPoolSize, 4> sizes{
        vk::DescriptorPoolSize(vk::DescriptorType::eStorageTexelBuffer, 4),
        vk::DescriptorPoolSize(vk::DescriptorType::eUniformBuffer, 2),
        vk::DescriptorPoolSize(vk::DescriptorType::eStorageBuffer, gpu::kBindingCount),
        vk::DescriptorPoolSize(vk::DescriptorType::eUniformTexelBuffer, 5)};
    descriptorPool_ = vk::raii::DescriptorPool(
        device, vk::DescriptorPoolCreateInfo(vk::DescriptorPoolCreateFlagBits::eFreeDescriptorSet, 1, sizes));
    vk::raii::DescriptorSets sets(device, vk::DescriptorSetAllocateInfo(*descriptorPool_, layouts));
    descriptorSet_ = std::move(sets.front());
    timestamps_ = context.info().timestamps && context.timestampValidBits() > 0;
    if (timestamps_) {
      queryPool_ = vk::raii::QueryPool(device, vk::QueryPoolCreateInfo({}, vk::QueryType::eTimestamp, 2));
    }
  });
  frameBuffer_ =
      std::make_unique<vulkan::Buffer>(context, sizeof(gpu::FrameParams), vk::BufferUsageFlagBits::eUniformBuffer,
                                       vulkan::MemoryUse::Upload, "frame parameters");
  stats_ = std::make_unique<vulkan::Buffer>(
      context, sizeof(gpu::RayStats), vk::BufferUsageFlagBits::eStorageBuffer | vk::BufferUsageFlagBits::eTransferDst,
      vulkan::MemoryUse::Readback, "ray statistics");
  gpu::RayStats zero{};
  stats_->write(&zero, sizeof zero);
  prevImage_ = std::make_unique<vulkan::Buffer>(context, sizeof(glm::vec4), kImageTexelFormat,
                                                vulkan::MemoryUse::DeviceLocal, "previous image (unused)");
  entryPoints_ = std::make_unique<vulkan::Buffer>(context, 2 * sizeof(glm::uvec4), vk::Format::eR32G32B32A32Uint,
                                                  vulkan::MemoryUse::DeviceLocal, "entry points (unused)",
                                                  vk::BufferUsageFlagBits::eStorageBuffer);
  sceneBuffers_.resize(gpu::kBindingCount);
}

Renderer::~Renderer() = default;

void Renderer::setScene(const Scene& scene) {
  auto start = Clock::now();
  features_ = analyzeScene(scene, scene.render);
  // The BVH is built when the scene's own settings would use it, or the user asked for it.
  gpuScene_ = packScene(scene, scene.camera.position, features_.useBvh);
  const auto& g = gpuScene_;
  uploadArray(sceneBuffers_[gpu::kBindingMaterials], context_, g.materials, "materials");
  uploadArray(sceneBuffers_[gpu::kBindingLights], context_, g.lights, "lights");
  uploadArray(sceneBuffers_[gpu::kBindingSpheres], context_, g.spheres, "spheres");
  uploadArray(sceneBuffers_[gpu::kBindingPlanes], context_, g.planes, "planes");
  uploadTexels(sceneBuffers_[gpu::kBindingTriangles], context_, g.triangles, vk::Format::eR32G32B32A32Uint,
               "triangles");
  uploadArray(sceneBuffers_[gpu::kBindingPolygons], context_, g.polygons, "polygons");
  uploadArray(sceneBuffers_[gpu::kBindingPolyVertices], context_, g.polyVertices, "polygon vertices");
  uploadTexels(sceneBuffers_[gpu::kBindingNormals], context_, g.normals, vk::Format::eR32G32B32A32Sfloat,
               "shading normals");
  uploadTexels(sceneBuffers_[gpu::kBindingBvhNodes], context_, g.bvhNodes, vk::Format::eR32G32B32A32Uint, "BVH nodes");
  uploadTexels(sceneBuffers_[gpu::kBindingPrimRefs], context_, g.bvh.primRefs, vk::Format::eR32Uint,
               "BVH primitive references");
  shadingFitsUbo_ = g.materials.size() <= gpu::kUboMaterials && g.lights.size() <= gpu::kUboLights &&
                    g.planes.size() <= gpu::kUboPlanes;
  sceneFitsUbo_ = shadingFitsUbo_ && g.spheres.size() <= gpu::kUboSpheres && g.triangles.size() <= gpu::kUboTriangles &&
                  g.polygons.size() <= gpu::kUboPolygons && g.polyVertices.size() <= gpu::kUboPolyVertices;
  // The uniform copy always exists at full size (the shader declares fixed arrays); the materials,
  // lights and planes are filled in when they fit, the primitives when the whole scene does.
  auto packed = std::make_unique<gpu::SceneUbo>();
  if (shadingFitsUbo_) {
    packUniform(packed->materials, g.materials);
    packUniform(packed->lights, g.lights);
    packUniform(packed->planes, g.planes);
  }
  if (sceneFitsUbo_) {
    packUniform(packed->spheres, g.spheres);
    packUniform(packed->triangles, g.triangles);
    packUniform(packed->polygons, g.polygons);
    packUniform(packed->polyVertices, g.polyVertices);
  }
  sceneBuffers_[gpu::kBindingSceneUbo] =
      std::make_unique<vulkan::Buffer>(context_, sizeof(gpu::SceneUbo), vk::BufferUsageFlagBits::eUniformBuffer,
                                       vulkan::MemoryUse::DeviceLocal, "small scene (uniform)");
  sceneBuffers_[gpu::kBindingSceneUbo]->write(packed.get(), sizeof(gpu::SceneUbo));
  uploadMs_ = msSince(start);
  image_.reset(); // descriptors are rewritten once the image window exists
}

Renderer::HostPageUse Renderer::sceneHostPages() const {
  HostPageUse use;
  for (const auto& buffer : sceneBuffers_) {
    if (const vulkan::HostPages* pages = buffer ? buffer->hostPages() : nullptr) {
      use.bytes += pages->size();
      use.hugeBytes += pages->hugeBytes();
    }
  }
  return use;
}

bool Renderer::useUniformScene(const RenderOptions& o) const {
  switch (o.sceneMemory) {
  case SceneMemory::Uniform:
    if (!sceneFitsUbo_) throw InputError("--scene-memory", "the scene's arrays exceed the uniform-buffer capacities");
    return true;
  case SceneMemory::Storage:
    return false;
  case SceneMemory::Auto:
    break;
  }
  return sceneFitsUbo_ && context_.info().type == "CPU";
}

bool Renderer::useUniformShading(const RenderOptions& o) const {
  if (useUniformScene(o)) return true;
  return o.sceneMemory == SceneMemory::Auto && shadingFitsUbo_ && context_.info().type == "CPU";
}

vulkan::Specialization Renderer::specializationFor(const Features& f, const RenderSettings& s, const RenderOptions& o,
                                                   bool centerSample, bool refinePass) const {
  vulkan::Specialization spec;
  bool all = !o.specialize;
  spec.set(gpu::kSpecHasSpheres, all || f.spheres);
  spec.set(gpu::kSpecHasPlanes, all || f.planes);
  spec.set(gpu::kSpecHasTriangles, all || f.triangles);
  spec.set(gpu::kSpecHasPolygons, all || f.polygons);
  const bool useBvh = f.useBvh && !gpuScene_.bvh.nodes.empty();
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
  spec.set(gpu::kSpecSceneInUbo, usesUniformScene_);
  spec.set(gpu::kSpecShadingInUbo, usesUniformShading_);
  spec.set(gpu::kSpecCenterSample, centerSample);
  spec.set(gpu::kSpecRefinePass, refinePass);
  // Bake small counts in so the driver unrolls the loops (see gpu_types.h); the all-features
  // pipeline keeps every count a runtime value.
  auto count = [&](std::size_t n) {
    return (all || n > gpu::kMaxUnrolledCount) ? gpu::kRuntimeCount : static_cast<std::uint32_t>(n);
  };
  spec.set(gpu::kSpecSphereCount, f.useBvh ? gpu::kRuntimeCount : count(gpuScene_.spheres.size()));
  spec.set(gpu::kSpecTriangleCount, f.useBvh ? gpu::kRuntimeCount : count(gpuScene_.triangles.size()));
  spec.set(gpu::kSpecPolygonCount, f.useBvh ? gpu::kRuntimeCount : count(gpuScene_.polygons.size()));
  spec.set(gpu::kSpecPlaneCount, count(gpuScene_.planes.size()));
  spec.set(gpu::kSpecOccluderPlaneCount, count(gpuScene_.occluderPlanes));
  spec.set(gpu::kSpecLightCount, count(gpuScene_.lights.size()));
  spec.set(gpu::kSpecMaterialCount, count(gpuScene_.materials.size()));
  return spec;
}

const vulkan::ComputePipeline& Renderer::pipelineFor(Kernel kernel, Precision precision,
                                                     const vulkan::Specialization& spec, bool& reused) {
  auto key = std::make_tuple(kernel, precision, spec);
  auto it = pipelines_.find(key);
  reused = it != pipelines_.end();
  if (!reused) {
    bool f64 = precision == Precision::Float64;
    if (f64 && !context_.float64Enabled()) {
      throw InputError("render.precision", "float64 needs shaderFloat64, which " + context_.info().name + " lacks");
    }
    if (f64 && kernel == Kernel::Hits) throw InputError("render.precision", "the ray-query kernel is float32 only");
    std::span<const std::uint32_t> code = kernel == Kernel::Hits ? std::span<const std::uint32_t>(kHitsSpv)
                                          : f64                  ? std::span<const std::uint32_t>(kTrace64Spv)
                                                                 : std::span<const std::uint32_t>(kTraceSpv);
    const char* name = kernel == Kernel::Hits ? "hits" : f64 ? "trace (float64)" : "trace";
    it = pipelines_.emplace(key, buildPipeline(code, spec, name)).first;
  }
  return *it->second;
}

std::unique_ptr<vulkan::ComputePipeline> Renderer::buildPipeline(std::span<const std::uint32_t> code,
                                                                 const vulkan::Specialization& spec, const char* name) {
  auto pipeline = std::make_unique<vulkan::ComputePipeline>(context_, code, *pipelineLayout_, spec,
                                                            cache_ ? &cache_->cache() : nullptr, name);
  if (cache_) cache_->save();
  return pipeline;
}

void Renderer::ensureImageWindow(std::uint32_t width, std::uint32_t rows, bool needPrev) {
  bool rebuild = !image_ || imageWidth_ != width || imageRows_ != rows;
  if (rebuild) {
    vk::DeviceSize bytes = static_cast<vk::DeviceSize>(width) * rows * sizeof(glm::vec4);
    image_.reset(); // the old window's memory goes back first
    image_ =
        std::make_unique<vulkan::Buffer>(context_, bytes, kImageTexelFormat, vulkan::MemoryUse::DeviceLocal, "image");
    imageWidth_ = width;
    imageRows_ = rows;
  }
  // The refine pass reads the band plus one row above and below.
  vk::DeviceSize prevBytes =
      needPrev ? static_cast<vk::DeviceSize>(width) * (rows + 2) * sizeof(glm::vec4) : sizeof(glm::vec4);
  if (prevImage_->size() < prevBytes) {
    prevImage_.reset();
    prevImage_ = std::make_unique<vulkan::Buffer>(context_, prevBytes, kImageTexelFormat,
                                                  vulkan::MemoryUse::DeviceLocal, "previous image");
    rebuild = true;
  }
  // Two uvec4 per tile of the window (shaders/entry.comp).
  vk::DeviceSize tiles = entryTileCount(width, rows);
  if (entryPoints_->size() < tiles * 2 * sizeof(glm::uvec4)) {
    entryPoints_.reset();
    entryPoints_ = std::make_unique<vulkan::Buffer>(context_, tiles * 2 * sizeof(glm::uvec4),
                                                    vk::Format::eR32G32B32A32Uint, vulkan::MemoryUse::DeviceLocal,
                                                    "entry points", vk::BufferUsageFlagBits::eStorageBuffer);
    rebuild = true;
  }
  if (rebuild) updateDescriptors();
}

void Renderer::updateDescriptors() {
  std::vector<vk::DescriptorBufferInfo> infos(gpu::kBindingCount);
  std::vector<vk::BufferView> views(gpu::kBindingCount);
  std::vector<vk::WriteDescriptorSet> writes;
  for (std::uint32_t b = 0; b < gpu::kBindingCount; ++b) {
    if (b == gpu::kBindingImage || b == gpu::kBindingPrevImage) {
      views[b] = (b == gpu::kBindingImage ? image_ : prevImage_)->texelView();
      writes.emplace_back(*descriptorSet_, b, 0, 1, descriptorType(b), nullptr, nullptr, &views[b]);
      continue;
    }
    if (isTexelBinding(b)) {
      views[b] = (b == gpu::kBindingEntryTexels ? entryPoints_ : sceneBuffers_[b])->texelView();
      writes.emplace_back(*descriptorSet_, b, 0, 1, descriptorType(b), nullptr, nullptr, &views[b]);
      continue;
    }
    vk::Buffer handle;
    if (b == gpu::kBindingFrame)
      handle = frameBuffer_->handle();
    else if (b == gpu::kBindingStats)
      handle = stats_->handle();
    else if (b == gpu::kBindingEntryPoints)
      handle = entryPoints_->handle();
    else
      handle = sceneBuffers_[b]->handle();
    infos[b] = vk::DescriptorBufferInfo(handle, 0, VK_WHOLE_SIZE);
    writes.emplace_back(*descriptorSet_, b, 0, 1, descriptorType(b), nullptr, &infos[b]);
  }
  context_.device().updateDescriptorSets(writes, {});
}

void Renderer::writeFrameParams(const Camera& camera, const RenderSettings& s, const Features& f) {
  CameraFrame cam = makeCameraFrame(camera, s.width, s.height);
  cull_ = makeCullScene(gpuScene_, cam);
  gpu::FrameParams p{};
  p.cameraForward = glm::vec4(glm::vec3(cam.forward), 0.0f);
  p.cameraRight = glm::vec4(glm::vec3(cam.right * (cam.tanHalfFovY * cam.aspect)), 0.0f);
  p.cameraUp = glm::vec4(glm::vec3(cam.up * cam.tanHalfFovY), 0.0f);
  p.cameraOrigin = glm::vec4(glm::vec3(camera.position - gpuScene_.origin), 0.0f);
  p.worldOffset = glm::vec4(glm::vec3(gpuScene_.origin), 0.0f);
  p.background = glm::vec4(glm::vec3(gpuScene_.background), 0.0f);
  p.ambientLight = glm::vec4(glm::vec3(gpuScene_.ambientLight), 0.0f);
  p.knobs = glm::vec4(static_cast<float>(s.bailout), static_cast<float>(s.adaptiveThreshold), 0.0f, 0.0f);
  // Depth beyond what the weights can reach changes nothing; the specialized kernel stops there.
  p.imageSize = glm::uvec4(s.width, s.height, 0u, static_cast<std::uint32_t>(f.reflection ? f.usableDepth : 0));
  p.counts = glm::uvec4(gpuScene_.spheres.size(), gpuScene_.planes.size(), gpuScene_.triangles.size(),
                        gpuScene_.polygons.size());
  p.counts2 = glm::uvec4(gpuScene_.lights.size(), 0u, gpuScene_.occluderPlanes, gpuScene_.bvhRoot);
  frameBuffer_->write(&p, sizeof p);
  frameWidth_ = s.width;
  frameHeight_ = s.height;
}

std::uint32_t Renderer::recordDispatch(const vk::raii::CommandBuffer& cmd, const vulkan::ComputePipeline& pipeline,
                                       const gpu::PushConstants& push, bool timestamps,
                                       const vulkan::ComputePipeline* fill) {
  // Row culling: the dispatch's rows in runs of whole workgroup rows, each traced or filled.
  std::vector<RowRun> runs;
  if (fill != nullptr) {
    runs = splitRows(cull_, frameWidth_, frameHeight_, push.tileOrigin.y, push.tileSize.y, gpu::kWorkgroupSizeY);
  } else {
    runs.push_back({push.tileOrigin.y, push.tileSize.y, false});
  }
  std::uint32_t culled = 0;
  for (const RowRun& run : runs) culled += run.empty ? run.rows : 0;
  cmd.bindDescriptorSets(vk::PipelineBindPoint::eCompute, *pipelineLayout_, 0, {*descriptorSet_}, {});
  if (timestamps) cmd.writeTimestamp(vk::PipelineStageFlagBits::eTopOfPipe, *queryPool_, 0);
  if (useEntryPoints_) {
    // The band's entry points, one invocation per tile, before the passes that read them.
    gpu::PushConstants band = push;
    band.tileOrigin = glm::uvec2(0, push.imageRow0);
    band.tileSize = glm::uvec2(frameWidth_, push.tileOrigin.y + push.tileSize.y - push.imageRow0);
    std::uint32_t tiles = entryTileCount(frameWidth_, band.tileSize.y);
    cmd.bindPipeline(vk::PipelineBindPoint::eCompute, entryPipeline_->handle());
    cmd.pushConstants<gpu::PushConstants>(*pipelineLayout_, vk::ShaderStageFlagBits::eCompute, 0, band);
    cmd.dispatch((tiles + 63) / 64, 1, 1);
    vk::MemoryBarrier written(vk::AccessFlagBits::eShaderWrite, vk::AccessFlagBits::eShaderRead);
    cmd.pipelineBarrier(vk::PipelineStageFlagBits::eComputeShader, vk::PipelineStageFlagBits::eComputeShader, {},
                        written, {}, {});
  }
  // One dispatch per sample, each adding to the sums of the one before. llvmpipe (lavapipe) stops
  // every loop of an invocation once the loops of its SIMD group have run 65535 iterations in all
  // (LP_MAX_TGSI_LOOP_ITERATIONS, shared by all loops of a shader): 64 samples of a deep glass tree
  // in one invocation reach that and lose their last samples without a trace. A dispatch per
  // sample gives each sample the whole budget; the sums are added in the same order as the
  // shader's own sample loop, so the image is bit for bit the same.
  std::uint32_t dispatches = std::max(1u, push.sampleCount);
  for (std::uint32_t k = 0; k < dispatches; ++k) {
    gpu::PushConstants one = push;
    if (push.sampleCount > 1) {
      one.sampleBase = push.sampleBase + k;
      one.sampleCount = 1;
      if (k > 0) {
        one.flags |= gpu::kFlagAccumulate;
        vk::MemoryBarrier sums(vk::AccessFlagBits::eShaderWrite,
                               vk::AccessFlagBits::eShaderRead | vk::AccessFlagBits::eShaderWrite);
        cmd.pipelineBarrier(vk::PipelineStageFlagBits::eComputeShader, vk::PipelineStageFlagBits::eComputeShader, {},
                            sums, {}, {});
      }
    }
    for (const RowRun& run : runs) {
      one.tileOrigin = glm::uvec2(push.tileOrigin.x, run.row0);
      one.tileSize = glm::uvec2(push.tileSize.x, run.rows);
      cmd.bindPipeline(vk::PipelineBindPoint::eCompute, (run.empty ? *fill : pipeline).handle());
      cmd.pushConstants<gpu::PushConstants>(*pipelineLayout_, vk::ShaderStageFlagBits::eCompute, 0, one);
      // Round up: the last partial workgroup covers the remaining pixels, the shader bounds-checks.
      cmd.dispatch((one.tileSize.x + gpu::kWorkgroupSizeX - 1) / gpu::kWorkgroupSizeX,
                   (one.tileSize.y + gpu::kWorkgroupSizeY - 1) / gpu::kWorkgroupSizeY, 1);
    }
  }
  if (timestamps) cmd.writeTimestamp(vk::PipelineStageFlagBits::eBottomOfPipe, *queryPool_, 1);
  return culled;
}

RayStats Renderer::readStatsAndReset() {
  gpu::RayStats raw{};
  stats_->read(&raw, sizeof raw);
  gpu::RayStats zero{};
  stats_->write(&zero, sizeof zero);
  RayStats s;
  s.eye = raw.eyeRays;
  s.shadow = raw.shadowRays;
  s.reflection = raw.reflectionRays;
  s.refraction = raw.refractionRays;
  s.bailoutSaved = raw.bailoutSaved;
  s.stackOverflow = raw.stackOverflow;
  s.refinedPixels = raw.refinedPixels;
  s.nonFinite = raw.nonFinite;
  s.truncated = raw.truncated;
  s.maxDepth = raw.maxDepth;
  return s;
}

RenderResult Renderer::render(const Camera& camera, const RenderSettings& settings, const RenderOptions& options) {
  RenderResult result;
  prepare(camera, settings, options);
  result.features = current_;
  result.timings.pipelineMs = lastPipelineMs_;
  result.timings.pipelineReused = lastPipelineMs_ == 0.0;

  const std::uint32_t width = settings.width;
  const std::uint32_t height = settings.height;
  const bool hitsKernel = options.kernel == Kernel::Hits;
  if (hitsKernel)
    result.hits.resize(static_cast<std::size_t>(width) * height);
  else
    result.image = Image(width, height);
  const bool adaptive = !hitsKernel && settings.antialiasing == Antialiasing::Adaptive && settings.spp > 1;
  // Bands never exceed the image window; rows come in whole workgroups.
  const std::uint32_t windowRows = imageRows_;

  // Work units: base pass plus, for adaptive AA, the refine pass (weighted like a base pass).
  // A row window (a tile): adaptive AA's base pass also traces the row on each side that the refine
  // pass reads as neighbours, so the window's pixels are those of the whole image.
  const std::uint32_t rowEnd = options.rowEnd == 0 ? height : std::min(options.rowEnd, height);
  const std::uint32_t rowBegin = std::min(options.rowBegin, rowEnd);
  const double totalWork = static_cast<double>(rowEnd - rowBegin) * (adaptive ? 2.0 : 1.0);
  double doneWork = 0.0;
  auto traceStart = Clock::now();
  double rowsPerMs = 0.0; // measured speed, drives the band height

  // The refine pass decides from the base pass's image, with a row of neighbours across each band
  // edge: it reads a copy, so rows refined by the band above do not change the decisions of the next
  // band, and the image does not depend on where the bands split.
  Image baseImage;
  auto runPass = [&](bool refine) {
    const std::uint32_t end = adaptive && !refine ? std::min(height, rowEnd + 1) : rowEnd;
    std::uint32_t y = adaptive && !refine && rowBegin > 0 ? rowBegin - 1 : rowBegin;
    std::uint32_t rows =
        std::min<std::uint32_t>(height, std::max<std::uint32_t>(8, (65536 / std::max(1u, width) + 7) / 8 * 8));
    while (y < end) {
      if (options.cancel && options.cancel->load()) throw CancelledError("interrupted");
      if (rowsPerMs > 0.0) {
        double want = rowsPerMs * options.bandBudgetMs;
        rows = static_cast<std::uint32_t>(std::clamp(want, 8.0, static_cast<double>(windowRows)));
        rows = std::max<std::uint32_t>(8, rows / 8 * 8);
      }
      rows = std::min({rows, windowRows, end - y});

      gpu::PushConstants push{};
      push.tileOrigin = glm::uvec2(0, y);
      push.tileSize = glm::uvec2(width, rows);
      push.imageRow0 = y;
      if (refine) {
        // Upload the base image for this band plus a row of neighbours above and below.
        std::uint32_t p0 = y > 0 ? y - 1 : 0;
        std::uint32_t p1 = std::min(height, y + rows + 1);
        std::vector<glm::vec4> rowsData(static_cast<std::size_t>(width) * (p1 - p0));
        for (std::uint32_t r = p0; r < p1; ++r) {
          for (std::uint32_t x = 0; x < width; ++x) {
            rowsData[static_cast<std::size_t>(r - p0) * width + x] = glm::vec4(baseImage.at(x, r), 1.0f);
          }
        }
        prevImage_->write(rowsData.data(), rowsData.size() * sizeof(glm::vec4));
        push.pass = gpu::kPassRefine;
        push.sampleBase = 0;
        push.sampleCount = static_cast<std::uint32_t>(settings.spp);
        push.prevRow0 = p0;
        push.prevRows = p1 - p0;
      } else {
        push.pass = gpu::kPassSample;
        push.sampleBase = 0;
        push.sampleCount = adaptive ? 1u : static_cast<std::uint32_t>(settings.spp);
        push.flags = push.sampleCount == 1 ? gpu::kFlagCenterSample : 0u;
      }

      auto bandStart = Clock::now();
      std::string step = std::string(refine ? "refining" : "tracing") + " rows " + std::to_string(y) + ".." +
                         std::to_string(y + rows - 1);
      std::uint32_t culled = 0;
      try {
        context_.submitAndWait(step, [&](const vk::raii::CommandBuffer& cmd) {
          if (timestamps_) cmd.resetQueryPool(*queryPool_, 0, 2);
          culled = recordDispatch(cmd, refine ? *refinePipeline_ : *samplePipeline_, push, timestamps_,
                                  refine ? nullptr : fillPipeline_);
          // Shader writes must be visible to the host's mapped reads (or the readback copy).
          vk::MemoryBarrier barrier(vk::AccessFlagBits::eShaderWrite,
                                    vk::AccessFlagBits::eHostRead | vk::AccessFlagBits::eTransferRead);
          cmd.pipelineBarrier(vk::PipelineStageFlagBits::eComputeShader,
                              vk::PipelineStageFlagBits::eHost | vk::PipelineStageFlagBits::eTransfer, {}, barrier, {},
                              {});
        });
      } catch (const DeviceLostError& e) {
        throw DeviceLostError(std::string(e.what()) + " in the band of rows " + std::to_string(y) + ".." +
                              std::to_string(y + rows - 1));
      }
      result.timings.culledRows += culled; // the refine pass culls nothing
      double bandWallMs = msSince(bandStart);
      double bandGpuMs = bandWallMs;
      if (timestamps_) {
        auto [res, ticks] =
            queryPool_.getResults<std::uint64_t>(0, 2, 2 * sizeof(std::uint64_t), sizeof(std::uint64_t),
                                                 vk::QueryResultFlagBits::e64 | vk::QueryResultFlagBits::eWait);
        if (res == vk::Result::eSuccess && ticks[1] >= ticks[0]) {
          bandGpuMs = static_cast<double>(ticks[1] - ticks[0]) * context_.timestampPeriodNs() * 1e-6;
        }
      }
      result.timings.traceMs += bandGpuMs;
      result.timings.traceWallMs += bandWallMs;
      ++result.timings.bands;
      // Without countStats only `truncated` is counted; the other counters stay 0.
      result.stats += readStatsAndReset();
      rowsPerMs = static_cast<double>(rows) / std::max(bandGpuMs, 1e-3);

      auto readStart = Clock::now();
      const std::size_t bandTexels = static_cast<std::size_t>(width) * rows;
      if (hitsKernel) {
        // The hit records are the result as they stand.
        image_->read(result.hits.data() + static_cast<std::size_t>(y) * width, bandTexels * sizeof(glm::vec4));
      } else {
        std::vector<glm::vec4> sums(bandTexels);
        image_->read(sums.data(), sums.size() * sizeof(glm::vec4));
        for (std::uint32_t r = 0; r < rows; ++r) {
          for (std::uint32_t x = 0; x < width; ++x) {
            const glm::vec4& v = sums[static_cast<std::size_t>(r) * width + x];
            result.image.at(x, y + r) = v.w > 0.0f ? glm::vec3(v) / v.w : glm::vec3(0.0f);
          }
        }
      }
      result.timings.readbackMs += msSince(readStart);

      y += rows;
      doneWork += rows;
      if (options.progress) {
        RenderProgress p;
        p.fraction = std::min(1.0, doneWork / totalWork);
        p.elapsedMs = msSince(traceStart);
        p.raysPerSecond = p.elapsedMs > 0 ? static_cast<double>(result.stats.total()) / (p.elapsedMs * 1e-3) : 0.0;
        p.remainingMs = p.fraction > 0 ? p.elapsedMs * (1.0 - p.fraction) / p.fraction : 0.0;
        options.progress(p);
      }
    }
  };
  runPass(false);
  if (adaptive) {
    baseImage = result.image;
    runPass(true);
  }
  return result;
}

void Renderer::prepare(const Camera& camera, const RenderSettings& settings, const RenderOptions& options) {
  if (sceneBuffers_[gpu::kBindingMaterials] == nullptr) throw Error("Renderer::prepare: no scene set");
  current_ = features_;
  current_.applySettings(settings);
  // The BVH exists only if setScene built it; without it the kernel loops over all primitives.
  current_.useBvh = current_.useBvh && !gpuScene_.bvh.nodes.empty();
  usesUniformScene_ = useUniformScene(options);
  usesUniformShading_ = useUniformShading(options);
  const bool adaptive = settings.antialiasing == Antialiasing::Adaptive && settings.spp > 1;
  // Single-sample passes go through pixel centres: a pipeline without the sample sequence.
  bool reused = false;
  bool center = !options.progressive && (settings.spp == 1 || adaptive);
  samplePipeline_ = &pipelineFor(options.kernel, settings.precision,
                                 specializationFor(current_, settings, options, center, false), reused);
  lastPipelineMs_ = reused ? 0.0 : samplePipeline_->creationMs();
  quietSamplePipeline_ = samplePipeline_;
  if (options.countStats && options.progressive) {
    // The same pass without counters, for the frames the viewer does not count. Built here, with
    // the other, rather than on first use: a pipeline build is a pause of up to a second on CPU
    // devices, better before the first frame than after it.
    RenderOptions quiet = options;
    quiet.countStats = false;
    quietSamplePipeline_ = &pipelineFor(options.kernel, settings.precision,
                                        specializationFor(current_, settings, quiet, center, false), reused);
    if (!reused) lastPipelineMs_ += quietSamplePipeline_->creationMs();
  }
  fillPipeline_ = nullptr;
  quietFillPipeline_ = nullptr;
  if (options.cullRows && options.kernel == Kernel::Shade) {
    // The background fill for culled rows (shaders/fill.comp): one per counting mode, whatever the
    // scene, built on first use.
    auto fillFor = [&](bool count) -> const vulkan::ComputePipeline* {
      std::unique_ptr<vulkan::ComputePipeline>& p = fillPipelines_[count ? 1 : 0];
      if (!p) {
        vulkan::Specialization spec;
        spec.set(gpu::kSpecCountStats, count);
        p = buildPipeline(kFillSpv, spec, "fill");
        lastPipelineMs_ += p->creationMs();
      }
      return p.get();
    };
    fillPipeline_ = fillFor(options.countStats);
    quietFillPipeline_ = quietSamplePipeline_ != samplePipeline_ ? fillFor(false) : fillPipeline_;
  }
  useEntryPoints_ = current_.useBvh && options.entryPoints;
  if (useEntryPoints_ && !entryPipeline_) {
    entryPipeline_ = buildPipeline(kEntrySpv, vulkan::Specialization(), "entry points");
    lastPipelineMs_ += entryPipeline_->creationMs();
  }
  refinePipeline_ = nullptr;
  if (adaptive) {
    refinePipeline_ = &pipelineFor(options.kernel, settings.precision,
                                   specializationFor(current_, settings, options, false, true), reused);
    if (!reused) lastPipelineMs_ += refinePipeline_->creationMs();
  }

  std::uint64_t rowBytes = static_cast<std::uint64_t>(settings.width) * sizeof(glm::vec4);
  std::uint64_t limit =
      std::min<std::uint64_t>(context_.info().maxTexelBufferElements * sizeof(glm::vec4), kImageWindowBudget);
  std::uint64_t rowsFit = limit / rowBytes;
  // The refine pass's window holds two extra rows.
  if (adaptive && rowsFit > 2) rowsFit -= 2;
  if (rowsFit < 8 && rowsFit < settings.height) {
    throw InputError("image.width", "an image " + std::to_string(settings.width) + " pixels wide needs " +
                                        std::to_string(rowBytes * 8 >> 20) + " MiB per band of 8 rows, more than " +
                                        context_.info().name + " reads from one texel buffer (maxTexelBufferElements)");
  }
  auto rows = static_cast<std::uint32_t>(std::min<std::uint64_t>(rowsFit, settings.height));
  ensureImageWindow(settings.width, rows, adaptive);
  writeFrameParams(camera, settings, current_);
}

void Renderer::recordSamples(const vk::raii::CommandBuffer& cmd, std::uint32_t sampleBase, std::uint32_t count,
                             bool accumulate, bool countRays) {
  if (imageRows_ < frameHeight_) throw Error("the image does not fit one window; use render() instead");
  gpu::PushConstants push{};
  push.tileOrigin = glm::uvec2(0, 0);
  push.tileSize = glm::uvec2(frameWidth_, frameHeight_);
  push.pass = gpu::kPassSample;
  push.sampleBase = sampleBase;
  push.sampleCount = count;
  push.flags = accumulate ? gpu::kFlagAccumulate : 0u;
  recordDispatch(cmd, countRays ? *samplePipeline_ : *quietSamplePipeline_, push, false,
                 countRays ? fillPipeline_ : quietFillPipeline_);
}

vk::Buffer Renderer::imageBuffer() const {
  return image_ ? image_->handle() : vk::Buffer();
}

vk::BufferView Renderer::imageTexelView() const {
  return image_ ? image_->texelView() : vk::BufferView();
}

Image Renderer::readImage() const {
  Image img(frameWidth_, frameHeight_);
  std::vector<glm::vec4> sums(static_cast<std::size_t>(frameWidth_) * frameHeight_);
  image_->read(sums.data(), sums.size() * sizeof(glm::vec4));
  for (std::size_t i = 0; i < sums.size(); ++i) {
    img.pixels[i] = sums[i].w > 0.0f ? glm::vec3(sums[i]) / sums[i].w : glm::vec3(0.0f);
  }
  return img;
}

RayStats Renderer::takeStats() {
  return readStatsAndReset();
}

} // namespace vkray
