// The Renderer: uploads a scene, builds the compute pipeline specialized to what the scene calls
// for, traces the image in bands whose GPU time is bounded, and reads it back with ray statistics.
// The headless command and the viewer both drive this one class.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <tuple>

#include <vulkan/vulkan_raii.hpp>

#include "image/image.h"
#include "render/gpu_scene.h"
#include "render/row_culling.h"
#include "scene/features.h"
#include "scene/scene.h"
#include "vk/buffer.h"
#include "vk/compute_pipeline.h"
#include "vk/context.h"

namespace vkray {

struct RayStats {
  std::uint64_t eye = 0;
  std::uint64_t shadow = 0;
  std::uint64_t reflection = 0;
  std::uint64_t refraction = 0;
  std::uint64_t bailoutSaved = 0;  // branches below the bailout weight, not traced
  std::uint64_t stackOverflow = 0; // branches dropped because the explicit stack was full
  std::uint64_t refinedPixels = 0; // adaptive antialiasing: pixels supersampled
  std::uint64_t nonFinite = 0;     // samples that were NaN/Inf before the guard (expected 0)
  std::uint64_t truncated = 0;     // samples the driver cut short (llvmpipe's loop limit); counted always
  std::uint32_t maxDepth = 0;      // deepest bounce traced

  std::uint64_t total() const { return eye + shadow + reflection + refraction; }
  RayStats& operator+=(const RayStats& o);
};

struct RenderProgress {
  double fraction = 0.0; // of all pixel work, 0..1
  double elapsedMs = 0.0;
  double raysPerSecond = 0.0; // when statistics are counted, else 0
  double remainingMs = 0.0;
};

// Where the kernel reads small scene arrays from. Auto: uniform buffers on CPU devices when the
// scene fits their capacity (a UBO read is one vector gather on lavapipe, an SSBO read a per-lane
// loop), storage buffers otherwise.
enum class SceneMemory { Auto, Uniform, Storage };

// Which kernel render() runs: the renderer's, or the ray queries alone (shaders/hits.comp: closest
// hit of each pixel-centre eye ray and, with shadows, one any-hit shadow ray; no shading), which
// `vkray bench meshes` sets against Embree.
enum class Kernel { Shade, Hits };

struct RenderOptions {
  Kernel kernel = Kernel::Shade;
  bool specialize = true; // false: every feature compiled in (--no-specialize)
  SceneMemory sceneMemory = SceneMemory::Auto;
  bool progressive = false;    // samples from the per-pixel sequence even at 1 spp (viewer frames)
  bool countStats = true;      // ray counters (a specialization; off costs nothing)
  double bandBudgetMs = 100.0; // target GPU time of one submission (watchdog-safe)
  // Rows of workgroups whose every eye ray provably meets nothing are filled with the background
  // instead of traced (render/row_culling.h; the image is the same). Off: --no-row-culling.
  bool cullRows = true;
  // Eye rays start their BVH walk at their 8 x 8 tile's entry points, found once per tile by
  // shaders/entry.comp (the same hits; docs/performance.md, "Entry points"). Off: --no-entry-points.
  bool entryPoints = true;
  // render() traces only rows [rowBegin, rowEnd) (rowEnd 0: to the last row); the other rows of the
  // image are black. A tile of the image, the same pixels as rendering it whole.
  std::uint32_t rowBegin = 0;
  std::uint32_t rowEnd = 0;
  std::function<void(const RenderProgress&)> progress;
  const std::atomic<bool>* cancel = nullptr; // checked between bands
};

struct RenderTimings {
  double pipelineMs = 0.0;  // pipeline creation (0 when reused within the process)
  double traceMs = 0.0;     // GPU time of the trace dispatches (timestamp queries)
  double traceWallMs = 0.0; // host wall time of the trace submissions
  double readbackMs = 0.0;
  int bands = 0;
  std::uint32_t culledRows = 0; // rows of the sample pass filled with the background (row culling)
  bool pipelineReused = false;
};

struct RenderResult {
  Image image; // Kernel::Shade
  // Kernel::Hits: per pixel, row-major, vec4(t or -1, hit kind, primitive index, shadow: -1 none
  // traced, 0 lit, 1 occluded).
  std::vector<glm::vec4> hits;
  RayStats stats;
  RenderTimings timings;
  Features features;
};

class Renderer {
public:
  // cache may be null (no on-disk pipeline cache).
  Renderer(const vulkan::Context& context, vulkan::PipelineCache* cache);
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  // Packs the scene relative to its camera position and uploads it. bvh decides whether a BVH is
  // built (Auto: when the scene has enough bounded primitives).
  void setScene(const Scene& scene);
  double uploadMs() const { return uploadMs_; }
  double bvhBuildMs() const { return gpuScene_.bvh.stats.buildMs; }
  const GpuScene& gpuScene() const { return gpuScene_; }
  const Features& sceneFeatures() const { return features_; }
  // The scene's buffers in vkray's own pages (host/vk/host_pages.h): how many bytes, and how many
  // of them the kernel backs with huge pages now. Both 0 where the device imports no host memory.
  struct HostPageUse {
    std::size_t bytes = 0;
    std::size_t hugeBytes = 0;
  };
  HostPageUse sceneHostPages() const;

  // Headless: the whole image, in bands, read back and averaged.
  RenderResult render(const Camera& camera, const RenderSettings& settings, const RenderOptions& options);

  // Progressive use (the viewer). prepare() sizes the image buffer to hold the whole image, builds
  // or reuses the pipeline and updates the frame parameters; recordSamples() records one dispatch
  // adding `count` samples per pixel (sample indices base, base + 1, ...) to the image sums.
  // countRays = false uses the same pipeline without the ray counters (with options.countStats and
  // progressive, prepare() builds both): the viewer counts a sample of its frames, since counting
  // costs 10-20 %.
  void prepare(const Camera& camera, const RenderSettings& settings, const RenderOptions& options);
  void recordSamples(const vk::raii::CommandBuffer& cmd, std::uint32_t sampleBase, std::uint32_t count, bool accumulate,
                     bool countRays = true);
  vk::Buffer imageBuffer() const;        // vec4(sum rgb, samples) per pixel, row-major
  vk::BufferView imageTexelView() const; // the same as RGBA32F texels (a storage texel buffer)
  Image readImage() const;               // averages of the sums (after the recorded work completed)
  RayStats takeStats();                  // reads and zeroes the counters
  const Features& currentFeatures() const { return current_; }
  bool usesUniformScene() const { return usesUniformScene_; }
  bool usesUniformShading() const { return usesUniformShading_; }
  double lastPipelineMs() const { return lastPipelineMs_; }

private:
  struct PipelineKey;
  vulkan::Specialization specializationFor(const Features& f, const RenderSettings& s, const RenderOptions& o,
                                           bool centerSample, bool refinePass) const;
  bool useUniformScene(const RenderOptions& o) const;
  // Materials, lights and planes from the uniform block: with the whole scene, or on their own in a
  // scene too large for it (on CPU devices, where a uniform read is a gather).
  bool useUniformShading(const RenderOptions& o) const;
  const vulkan::ComputePipeline& pipelineFor(Kernel kernel, Precision precision, const vulkan::Specialization& spec,
                                             bool& reused);
  void ensureImageWindow(std::uint32_t width, std::uint32_t rows, bool needPrev);
  void writeFrameParams(const Camera& camera, const RenderSettings& settings, const Features& f);
  void updateDescriptors();
  // A pipeline from SPIR-V and a specialization, with the on-disk cache when there is one.
  std::unique_ptr<vulkan::ComputePipeline> buildPipeline(std::span<const std::uint32_t> code,
                                                         const vulkan::Specialization& spec, const char* name);
  // fill: the background pipeline for rows that see nothing (row culling), or null to trace all.
  // Returns how many rows went to `fill`.
  std::uint32_t recordDispatch(const vk::raii::CommandBuffer& cmd, const vulkan::ComputePipeline& pipeline,
                               const gpu::PushConstants& push, bool timestamps,
                               const vulkan::ComputePipeline* fill = nullptr);
  RayStats readStatsAndReset();

  const vulkan::Context& context_;
  vulkan::PipelineCache* cache_;

  // Layouts first: pipelines and descriptor sets built from them are declared (and destroyed) after.
  vk::raii::DescriptorSetLayout setLayout_{nullptr};
  vk::raii::PipelineLayout pipelineLayout_{nullptr};
  vk::raii::DescriptorPool descriptorPool_{nullptr};
  vk::raii::DescriptorSet descriptorSet_{nullptr};
  vk::raii::QueryPool queryPool_{nullptr};
  std::map<std::tuple<Kernel, Precision, vulkan::Specialization>, std::unique_ptr<vulkan::ComputePipeline>> pipelines_;
  const vulkan::ComputePipeline* samplePipeline_ = nullptr;               // pass kPassSample
  const vulkan::ComputePipeline* quietSamplePipeline_ = nullptr;          // the same without counters
  const vulkan::ComputePipeline* refinePipeline_ = nullptr;               // adaptive AA's refine pass
  std::array<std::unique_ptr<vulkan::ComputePipeline>, 2> fillPipelines_; // shaders/fill.comp, [counting]
  const vulkan::ComputePipeline* fillPipeline_ = nullptr;                 // samplePipeline_'s fill for culled rows
  const vulkan::ComputePipeline* quietFillPipeline_ = nullptr;            // quietSamplePipeline_'s
  std::unique_ptr<vulkan::ComputePipeline> entryPipeline_;                // shaders/entry.comp
  bool useEntryPoints_ = false;                                           // this render's pipelines read them
  CullScene cull_;                                                        // the frame's camera and scene, for culling

  GpuScene gpuScene_;
  Features features_; // scene facts; settings applied per render into current_
  Features current_;
  std::unique_ptr<vulkan::Buffer> frameBuffer_;
  std::vector<std::unique_ptr<vulkan::Buffer>> sceneBuffers_; // indexed by binding (SSBO and UBO copies)
  bool sceneFitsUbo_ = false;
  bool shadingFitsUbo_ = false;               // materials, lights and planes (a mesh scene's primitives do not fit)
  std::unique_ptr<vulkan::Buffer> image_;     // window of imageRows_ rows
  std::unique_ptr<vulkan::Buffer> prevImage_; // refine pass input (or a 16-byte placeholder)
  std::unique_ptr<vulkan::Buffer> stats_;
  std::unique_ptr<vulkan::Buffer> entryPoints_; // two uvec4 per 8 x 8 tile of the window
  std::uint32_t imageWidth_ = 0;
  std::uint32_t imageRows_ = 0;
  std::uint32_t frameWidth_ = 0;
  std::uint32_t frameHeight_ = 0;
  double uploadMs_ = 0.0;
  double lastPipelineMs_ = 0.0;
  bool timestamps_ = false;
  bool usesUniformScene_ = false;
  bool usesUniformShading_ = false;
};

} // namespace vkray
