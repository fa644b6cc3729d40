// The Renderer: the headless command and the viewer both drive this one class. It owns the image
// window and the frame's parameters, and strings the rooms together: the scene's device buffers
// (scene_buffers.h), the kernel variants a render needs (kernel_variants.h) and the band loop
// (band_loop.h), in the order of a pass: prepare (pipelines, window, frame), trace bands, read back.
#pragma once

#include <cstdint>
#include <memory>

#include <vulkan/vulkan_raii.hpp>

#include "image/image.h"
#include "render/adaptive.h"
#include "render/band_loop.h"
#include "render/gpu_scene.h"
#include "render/kernel_variants.h"
#include "render/ray_stats.h"
#include "render/ray_tree.h"
#include "render/render_options.h"
#include "render/row_culling.h"
#include "render/scene_buffers.h"
#include "scene/features.h"
#include "scene/scene.h"
#include "vk/buffer.h"
#include "vk/compute_pipeline.h"
#include "vk/context.h"

namespace vkray {

class Renderer {
public:
  // cache may be null (no on-disk pipeline cache).
  Renderer(const vulkan::Context& context, vulkan::PipelineCache* cache);
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  // Packs the scene relative to its camera position and uploads it. The BVH is built when the
  // scene's features call for one (Features::useBvh). The second form takes the features the caller
  // already analysed (analyzeScene(scene, scene.render)) instead of analysing the scene again.
  void setScene(const Scene& scene);
  void setScene(const Scene& scene, const Features& features);
  double uploadMs() const { return sceneBuffers_.uploadMs(); }
  double bvhBuildMs() const { return gpuScene_.bvh.stats.buildMs; }
  const GpuScene& gpuScene() const { return gpuScene_; }
  // Why the scene has no shadow entry points' table (empty once it has one): `render --stats`.
  const std::string& shadowEntriesSkipped() const { return shadowEntriesSkipped_; }
  // Why the table holds no "nothing between" pairs, where it was built without looking for them.
  const std::string& shadowNothingSkipped() const { return shadowNothingSkipped_; }
  const Features& sceneFeatures() const { return features_; }
  HostPageUse sceneHostPages() const { return sceneBuffers_.hostPages(); }

  // Headless: the whole image, in bands, read back and averaged.
  RenderResult render(const Camera& camera, const RenderSettings& settings, const RenderOptions& options);

  // Forward tracing (settings.method forward; render() calls it): every light emits
  // settings.photons photons (shaders/forward.comp), in batches sized to options.bandBudgetMs, and
  // the image is what passed through the camera's lens. A time limit stops between batches. Needs
  // camera.aperture > 0: a pinhole receives no photon.
  RenderResult renderForward(const Camera& camera, const RenderSettings& settings, const RenderOptions& options);

  // The ray-tree inspector: traces pixel `pixel` alone with the recording kernel (kSpecRecordTree)
  // and returns every ray its samples traced. Samples as a uniform render of settings.spp does
  // (a noise threshold, time limit or adaptive antialiasing is not applied: their sample counts
  // are decided per pixel by the whole image), so the tree's value is the pixel of that render.
  // Up to `capacity` rays are kept (RayTree::notRecorded counts the rest).
  RayTree inspect(const Camera& camera, const RenderSettings& settings, const RenderOptions& options, glm::uvec2 pixel,
                  std::uint32_t capacity = 4096);

  // Progressive use (the viewer). prepare() sizes the image buffer to hold the whole image, builds
  // or reuses the pipelines and updates the frame parameters; recordSamples() records one dispatch
  // adding `count` samples per pixel (sample indices base, base + 1, ...) to the image sums.
  // countRays = false uses the same pipeline without the ray counters (with options.countStats and
  // progressive, prepare() builds both): the viewer counts a sample of its frames, since counting
  // costs 10-20 %.
  void prepare(const Camera& camera, const RenderSettings& settings, const RenderOptions& options);
  // Whether the last prepare() let one dispatch take all of a pixel's samples (see samplesTogether_),
  // and the driver's loop cut that otherwise splits them (Context::loopLimit; 0: none).
  bool samplesTogether() const { return samplesTogether_; }
  std::uint32_t driverLoopLimit() const { return context_.loopLimit(); }
  void recordSamples(const vk::raii::CommandBuffer& cmd, std::uint32_t sampleBase, std::uint32_t count, bool accumulate,
                     bool countRays = true);
  vk::Buffer imageBuffer() const;        // vec4(sum rgb, samples) per pixel, row-major
  vk::BufferView imageTexelView() const; // the same as RGBA32F texels (a storage texel buffer)
  // options.pixelRays: rays traced per pixel, a uint per pixel summed over its samples like the
  // image; a placeholder otherwise.
  vk::Buffer pixelRaysBuffer() const { return pixelRays_->handle(); }
  std::vector<std::uint32_t> readPixelRays() const; // after the recorded work completed
  Image readImage() const;                          // averages of the sums (after the recorded work completed)
  RayStats takeStats();                             // reads and zeroes the counters
  const Features& currentFeatures() const { return current_; }
  bool usesUniformScene() const { return memory_.scene; }
  bool usesUniformShading() const { return memory_.shading; }
  double lastPipelineMs() const { return kernels_.buildMs; }

private:
  // Builds and uploads the shadow entry points' table when the render's options ask for it and
  // its shadow rays pay for it (shadowEntriesPay in renderer.cpp); returns whether it did now.
  bool prepareShadowEntries(const RenderSettings& settings, const RenderOptions& options);
  // One pass over the whole image in bands: the sample pass, or (refine) adaptive AA's refine pass
  // deciding from `base`. The sizer carries the measured speed from one pass to the next.
  // Rows [begin, end) of the image.
  void traceBands(bool refine, std::uint32_t begin, std::uint32_t end, const RenderSettings& settings,
                  const RenderOptions& options, const Image* base, BandSizer& sizer, RenderResult& result,
                  const std::function<void(std::uint32_t)>& advanced);
  // Progressive passes over lists of open pixels (adaptive.h): the noise threshold, the time
  // limit, per-pixel statistics.
  void renderProgressive(const RenderSettings& settings, const RenderOptions& options, RenderResult& result);
  // shaders/entry.comp over the whole image (the list pass's lanes read any tile's), before a
  // progressive render's first pass; grows the entry-point buffer to hold every tile. Returns its
  // GPU time (part of the trace's).
  double findEntryPointsOfTheWholeImage(const RenderSettings& settings);
  // pixelTexels: RGBA32F texels per pixel of the window (2 for Kernel::Aov, else 1).
  // pixelRays: a ray count per pixel of the window too (options.pixelRays).
  void ensureImageWindow(std::uint32_t width, std::uint32_t rows, std::uint32_t pixelTexels, bool needPrev,
                         bool pixelRays = false);
  void writeFrameParams(const Camera& camera, const RenderSettings& settings, const Features& f);
  // Dispatches each pipeline prepare() just built once over an empty tile (every invocation
  // returns at once) and adds the time to its build: a CPU driver compiles at the first dispatch.
  void firstDispatchNewPipelines();
  void updateDescriptors();
  // fill: the background pipeline for rows that see nothing (row culling), or null to trace all.
  // timer: timestamps around the dispatches, or null. Returns how many rows went to `fill`.
  std::uint32_t recordDispatch(const vk::raii::CommandBuffer& cmd, const vulkan::ComputePipeline& pipeline,
                               const gpu::PushConstants& push, const GpuTimer* timer,
                               const vulkan::ComputePipeline* fill = nullptr);
  RayStats readStatsAndReset();

  const vulkan::Context& context_;
  // A dispatch takes all of a pixel's samples in a band (or pass) instead of one sample each: the
  // driver lets loops run to their end (Context::loopLimit). Set by prepare().
  bool samplesTogether_ = false;

  // Layouts first: the pipelines and descriptor set built from them are declared (and destroyed) after.
  vk::raii::DescriptorSetLayout setLayout_{nullptr};
  vk::raii::PipelineLayout pipelineLayout_{nullptr};
  vk::raii::DescriptorPool descriptorPool_{nullptr};
  vk::raii::DescriptorSet descriptorSet_{nullptr};
  GpuTimer timer_;
  KernelLibrary library_;

  // The scene.
  GpuScene gpuScene_;
  SceneBuffers sceneBuffers_;
  Features features_; // scene facts; settings applied per render into current_

  // This render (or prepared viewer frame).
  Features current_;
  std::string shadowEntriesSkipped_;
  std::string shadowNothingSkipped_;
  SceneMemoryUse memory_;
  KernelSet kernels_;
  CullScene cull_; // the frame's camera and scene, for row culling
  std::uint32_t frameWidth_ = 0;
  std::uint32_t frameHeight_ = 0;

  // The renderer's own buffers.
  std::unique_ptr<vulkan::Buffer> frameBuffer_;
  std::unique_ptr<vulkan::Buffer> stats_;
  std::unique_ptr<vulkan::Buffer> image_;       // window of imageRows_ rows
  std::unique_ptr<vulkan::Buffer> prevImage_;   // refine pass input (or a 16-byte placeholder)
  std::unique_ptr<vulkan::Buffer> entryPoints_; // two uvec4 per 8 x 8 tile of the window
  std::unique_ptr<vulkan::Buffer> pixelRays_;   // a uint per pixel of the window (or a placeholder)
  std::unique_ptr<vulkan::Buffer> rayTree_;     // the inspector's records (or a placeholder)
  std::unique_ptr<vulkan::Buffer> photonImage_; // forward tracing's fixed-point sums (or a placeholder)
  std::uint32_t imageWidth_ = 0;
  std::uint32_t imageRows_ = 0;
  std::uint32_t imagePixelTexels_ = 1;
};

} // namespace vkray
