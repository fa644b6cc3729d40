// What a caller asks of the Renderer besides the scene's settings (which kernel, which optimizations,
// the band budget, progress and cancellation) and what a render returns.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "image/image.h"
#include "render/ray_stats.h"
#include "scene/features.h"
#include "util/enum_names.h"

namespace vkray {

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
template <> struct EnumNames<SceneMemory> {
  static constexpr std::array<EnumName<SceneMemory>, 3> values{
      {{SceneMemory::Auto, "auto"}, {SceneMemory::Uniform, "uniform"}, {SceneMemory::Storage, "storage"}}};
};

// Whether shadow rays from triangles start their BVH walk at their (triangle, light)'s shadow entry
// points (host/accel/shadow_entries.h; the same occluders either way), and skip it for the pairs
// that nothing in the BVH can shadow ("nothing between", a dearer part of the table). Auto: each
// part when the render traces enough shadow rays per (triangle, light) to pay for it
// (Renderer::prepare, shadowEntriesPay; on a GPU only for the viewer); On: both, always (where the
// scene allows a table); Entries: the entry points alone; Off: never.
enum class ShadowEntries { Auto, On, Entries, Off };
template <> struct EnumNames<ShadowEntries> {
  static constexpr std::array<EnumName<ShadowEntries>, 4> values{{{ShadowEntries::Auto, "auto"},
                                                                  {ShadowEntries::On, "on"},
                                                                  {ShadowEntries::Entries, "entries"},
                                                                  {ShadowEntries::Off, "off"}}};
};

// Which kernel render() runs: the renderer's, or the ray queries alone (shaders/hits.comp: closest
// hit of each pixel-centre eye ray and, with shadows, one any-hit shadow ray; no shading), which
// `vkray bench meshes` sets against Embree, or the first-hit AOVs of the pixel-centre eye rays
// (shaders/aov.comp: depth, normal, albedo; `render --aov`).
// Kernel::Forward: photons from the lights (shaders/forward.comp, `render --method forward`).
enum class Kernel { Shade, Hits, Aov, Forward };

struct RenderOptions {
  Kernel kernel = Kernel::Shade;
  bool specialize = true; // false: every feature compiled in (--no-specialize)
  // Fold the specialization into the trace kernel's SPIR-V before the driver compiles it
  // (vk/spirv_fold.h): the same code, compiled in a fraction of the time on a CPU driver. Off
  // (--no-spirv-folding): the driver gets the whole module and the constants, for comparison.
  bool foldSpirv = true;
  // Bake the sizes of small scene arrays into the pipeline so the driver unrolls their loops
  // (gpu_types.h, kMaxUnrolledCount). Off (--no-unroll): run-time counts, for comparison.
  bool unroll = true;
  SceneMemory sceneMemory = SceneMemory::Auto;
  bool progressive = false;    // samples from the per-pixel sequence even at 1 spp (viewer frames)
  bool countStats = true;      // ray counters (a specialization; off costs nothing)
  double bandBudgetMs = 100.0; // target GPU time of one submission (watchdog-safe)
  // Forward tracing: at most this many photons per light in one batch (0: as many as the band budget
  // allows). The sums do not depend on the split; tests use it to split the same photons on any device.
  std::uint64_t maxBatchPhotons = 0;
  // The simplest schedule: every dispatch takes one sample of each pixel, one invocation per pixel,
  // as a driver that cuts loops short needs (Context::loopLimit), where the renderer would give a
  // dispatch all of a pixel's samples and let lanes share a pixel. The image is the same bit for
  // bit; tests compare the two.
  bool oneSamplePerDispatch = false;
  // Under a noise threshold, the passes before the first decision (min_spp / 4, min_spp / 4,
  // min_spp / 2) run as one list pass that reports each on its own (nextPasses): the same sums,
  // decisions and image, with one pass's fixed cost per pixel instead of three. Off: three passes,
  // for tests to compare.
  bool firstPassesTogether = true;
  // Rows of workgroups whose every eye ray provably meets nothing are filled with the background
  // instead of traced (render/row_culling.h; the image is the same). Off: --no-row-culling.
  bool cullRows = true;
  // Eye rays start their BVH walk at their 8 x 8 tile's entry points, found once per tile by
  // shaders/entry.comp (the same hits; docs/performance.md, "Entry points"). Off: --no-entry-points.
  bool entryPoints = true;
  // Shadow rays from a triangle start their BVH walk at the (triangle, light)'s shadow entry points
  // (see ShadowEntries): --shadow-entry-points auto|on|entries|off, --no-shadow-entry-points.
  ShadowEntries shadowEntryPoints = ShadowEntries::Auto;
  // Descent steps of the BVH walk between two subgroup votes (kSpecBvhStepsPerVote): 0 chooses by
  // the tree's depth (two from gpu::kBvhTwoStepDepth on), 1 or 2 forces it. The same hits either way.
  int bvhStepsPerVote = 0;
  // render() traces only rows [rowBegin, rowEnd) (rowEnd 0: to the last row); the other rows of the
  // image are black. A tile of the image, the same pixels as rendering it whole.
  std::uint32_t rowBegin = 0;
  std::uint32_t rowEnd = 0;
  // Keep per-pixel statistics (RenderResult::pixels): samples, estimated error and rays traced, as
  // the --aov layers `spp`, `error` and `rays` need. Renders progressively (host/render/adaptive.h).
  bool pixelStats = false;
  // Progressive (viewer) sample passes also add each pixel's rays to a buffer (pixelRaysBuffer()), for
  // the viewer's cost map; the rows row culling would fill are traced instead, so that every pixel
  // is counted. A specialization: off, nothing of it is compiled.
  bool pixelRays = false;
  // The sample pass records every ray it traces (Renderer::inspect, the ray-tree inspector). A
  // specialization: off, the recorder compiles out.
  bool recordTree = false;
  std::function<void(const RenderProgress&)> progress;
  const std::atomic<bool>* cancel = nullptr; // checked between bands
};

// Whether render() samples progressively (host/render/adaptive.h): a noise threshold or time limit
// in the settings, or per-pixel statistics asked for.
inline bool progressiveRender(const RenderSettings& settings, const RenderOptions& options) {
  return options.kernel == Kernel::Shade && (settings.progressive() || options.pixelStats);
}

// One pipeline built for a render: what creating it took, the SPIR-V folding and its first
// dispatch included.
struct PipelineBuild {
  std::string name;
  double ms = 0.0;
  double foldMs = 0.0;        // folding the specialization into the SPIR-V (0: not folded)
  std::size_t spirvBytes = 0; // the module the driver compiled
  // An empty dispatch right after creation (Renderer::prepare): lavapipe generates the machine
  // code at a pipeline's first dispatch, not at vkCreateComputePipelines, so that is where most of
  // its compile is (or its load from Mesa's on-disk shader cache).
  double firstDispatchMs = 0.0;
  bool foldKept = false; // the folded module was read back from an earlier run (vk/fold_cache.h)
};

struct RenderTimings {
  double pipelineMs = 0.0; // pipeline creation, wall time (0 when reused within the process)
  // Each pipeline built, with its own creation time (they build side by side).
  std::vector<PipelineBuild> pipelinesBuilt;
  double traceMs = 0.0;     // GPU time of the trace dispatches (timestamp queries)
  double traceWallMs = 0.0; // host wall time of the trace submissions
  double readbackMs = 0.0;  // reading results back, and adding a progressive pass's sums to the pixels'
  // A progressive render's host time between passes: deciding which pixels stay open, and adding the
  // sums of the rows that see nothing (the GPU waits meanwhile).
  double decideMs = 0.0;
  int bands = 0;
  std::uint32_t culledRows = 0; // rows filled with the background, not traced (row culling)
  // The eye rays of those rows' pixels, one per sample, answered without a trace (on the host or by
  // the fill kernel); RayStats::eye counts them with the traced ones.
  std::uint64_t culledEyeRays = 0;
  bool pipelineReused = false;
};

// Per-pixel statistics of a progressive render, row-major, one value per pixel; empty otherwise.
struct PixelStats {
  std::vector<float> samples; // samples traced
  std::vector<float> error;   // estimated standard error of the mean, the largest of R, G, B (linear)
  std::vector<float> rays;    // rays traced for the pixel, all kinds (eye, shadow, reflection, refraction)
  bool empty() const { return samples.empty(); }
};

// What a progressive render reached, over the pixels it rendered (host/render/adaptive.h).
struct ProgressiveSummary {
  int passes = 0;                         // 0: not a progressive render
  double errorMean = 0.0, errorP95 = 0.0; // estimated standard error per pixel
  double sppMean = 0.0, sppMax = 0.0;
  double converged = 0.0;  // share of pixels at or below the noise threshold (1 without one)
  double lastPassMs = 0.0; // GPU time of the last pass (a time limit holds within it)
};

// Kernel::Aov, one pixel: what its pixel-centre eye ray meets first (shaders/aov.comp writes the two
// texels as they lie here).
struct FirstHit {
  float depth;      // distance from the eye along the ray; +inf where nothing is hit
  glm::vec3 normal; // world-space unit shading normal, towards the eye; 0 where nothing is hit
  glm::vec3 albedo; // base colour (linear; checker, texture, vertex colour applied); 0 where nothing is hit
  float hit;        // 1 hit, 0 nothing
};
static_assert(sizeof(FirstHit) == 2 * sizeof(glm::vec4), "two texels per pixel (shaders/aov.comp)");

// What a forward render (settings.method forward) traced: photons each light emitted, the branches
// of them that passed through the lens onto the image (a photon that passes glass may scatter
// towards the camera at more than one surface), the rays traced, and the batches.
struct ForwardSummary {
  std::uint64_t photonsPerLight = 0; // 0: not a forward render
  std::uint32_t lights = 0;
  std::uint64_t emitted = 0;   // photonsPerLight * lights
  std::uint64_t struck = 0;    // photons (branches) that reached a pixel through the lens
  std::uint64_t rays = 0;      // every ray the photons traced
  std::uint64_t nonFinite = 0; // contributions dropped as NaN/Inf (expected 0)
  int batches = 0;
  double lastBatchMs = 0.0; // GPU time of the last batch (a time limit holds within it)
  double struckFraction() const { return emitted > 0 ? static_cast<double>(struck) / emitted : 0.0; }
};

struct RenderResult {
  Image image;       // Kernel::Shade
  PixelStats pixels; // RenderOptions::pixelStats, --noise-threshold, --time-limit
  ProgressiveSummary progressive;
  ForwardSummary forward; // settings.method forward
  // Kernel::Hits: per pixel, row-major, vec4(t or -1, hit kind, primitive index, shadow: -1 none
  // traced, 0 lit, 1 occluded).
  std::vector<glm::vec4> hits;
  std::vector<FirstHit> firstHits; // Kernel::Aov: per pixel, row-major
  RayStats stats;
  RenderTimings timings;
  Features features;
};

} // namespace vkray
