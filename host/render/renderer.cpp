// Renderer: the image window, the frame's parameters and the order of a render (see renderer.h).
#include "render/renderer.h"

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <numeric>

#include "render/descriptors.h"
#include "util/clock.h"
#include "util/error.h"
#include "util/host_memory.h"
#include "util/parallel.h"

namespace vkray {

namespace {

// Bytes of image window the renderer allows itself: bands of rows are traced into it and read back.
constexpr vk::DeviceSize kImageWindowBudget = 64ull << 20;
// The most the shadow entry points' table may take (32 bytes per triangle and light).
constexpr std::uint64_t kShadowEntryBudget = 512ull << 20;
// The image window and the refine pass's copy are texel buffers of (sum rgb, samples).
constexpr vk::Format kImageTexelFormat = vk::Format::eR32G32B32A32Sfloat;

// The rows [begin, end) a render traces: options.rowBegin up to options.rowEnd (0: the image's
// last row), within the image.
struct RowWindow {
  std::uint32_t begin, end;
};
RowWindow rowWindow(const RenderSettings& settings, const RenderOptions& options) {
  const std::uint32_t end = options.rowEnd == 0 ? settings.height : std::min(options.rowEnd, settings.height);
  return {std::min(options.rowBegin, end), end};
}

// Entry-point tiles (shaders/entry.comp) covering `rows` rows of a `width`-pixel image.
std::uint32_t entryTileCount(std::uint32_t width, std::uint32_t rows) {
  return ((width + gpu::kEntryTileSize - 1) / gpu::kEntryTileSize) *
         ((rows + gpu::kEntryTileSize - 1) / gpu::kEntryTileSize);
}

vk::raii::DescriptorSetLayout makeSetLayout(const vulkan::Context& context) {
  return vulkan::vulkanStep("creating the renderer's descriptor set layout", [&] {
    std::vector<vk::DescriptorSetLayoutBinding> bindings;
    for (std::uint32_t b = 0; b < gpu::kBindingCount; ++b) {
      bindings.emplace_back(b, descriptorType(b), 1, vk::ShaderStageFlagBits::eCompute);
    }
    return vk::raii::DescriptorSetLayout(context.device(), vk::DescriptorSetLayoutCreateInfo({}, bindings));
  });
}

vk::raii::PipelineLayout makePipelineLayout(const vulkan::Context& context, const vk::raii::DescriptorSetLayout& set) {
  return vulkan::vulkanStep("creating the renderer's pipeline layout", [&] {
    vk::PushConstantRange push(vk::ShaderStageFlagBits::eCompute, 0, sizeof(gpu::PushConstants));
    vk::DescriptorSetLayout layouts[] = {*set};
    return vk::raii::PipelineLayout(context.device(), vk::PipelineLayoutCreateInfo({}, layouts, push));
  });
}

// The order in which a progressive pass lists a chunk's n entries: whole workgroups of `group`
// entries, the groups in van der Corput order (0, 4, 2, 6, 1, 5, ... for 8), each group's entries
// in their own order. llvmpipe hands each of its threads one contiguous block of a dispatch's
// workgroups; in list order those blocks would be different parts of the image (sky in one, the
// scene in another) and one thread would idle while the other finishes. In this order every
// contiguous block of 1/2, 1/4, ... of the groups samples the whole chunk alike. Which lane traces
// a pixel does not change its value, so the image is the same.
void spreadGroups(std::size_t n, std::size_t group, std::vector<std::uint32_t>& order) {
  // A partial last group goes last, so that every whole group stays aligned to a workgroup (and its
  // 4 x 2 blocks to the SIMD batches).
  const std::size_t whole = n / group;
  unsigned bits = 0;
  while ((std::size_t{1} << bits) < whole) ++bits;
  order.clear();
  order.reserve(n);
  for (std::size_t k = 0; k < (std::size_t{1} << bits); ++k) {
    std::size_t g = 0; // k's lowest `bits` bits reversed
    for (unsigned b = 0; b < bits; ++b) g |= ((k >> b) & 1u) << (bits - 1 - b);
    if (g >= whole) continue;
    for (std::size_t j = g * group; j < (g + 1) * group; ++j) order.push_back(static_cast<std::uint32_t>(j));
  }
  for (std::size_t j = whole * group; j < n; ++j) order.push_back(static_cast<std::uint32_t>(j));
}

// Orders the shader writes of the dispatches recorded so far before the shader reads and writes of
// the next ones in the same command buffer: passes that add to the sums the one before wrote, and
// row runs that write the image through one descriptor and read it through another.
void orderShaderWrites(const vk::raii::CommandBuffer& cmd) {
  vk::MemoryBarrier written(vk::AccessFlagBits::eShaderWrite,
                            vk::AccessFlagBits::eShaderRead | vk::AccessFlagBits::eShaderWrite);
  cmd.pipelineBarrier(vk::PipelineStageFlagBits::eComputeShader, vk::PipelineStageFlagBits::eComputeShader, {}, written,
                      {}, {});
}

// The sample pass's tile-row stride for a dispatch `rows` workgroups high (trace.comp, main): coprime
// to `rows`, so that row r -> r * stride mod rows is a permutation, and near rows / golden ratio, so
// that any contiguous block of workgroup rows (one llvmpipe thread's share) maps to rows spread over
// the whole dispatch (the three-distance theorem). 1 (rows in order) for one or two rows.
std::uint32_t spreadStride(std::uint32_t rows) {
  if (rows <= 2) return 1;
  auto stride = static_cast<std::uint32_t>(std::lround(rows * 0.6180339887498949));
  stride = std::clamp<std::uint32_t>(stride, 1, rows - 1);
  while (std::gcd(stride, rows) != 1) stride = stride + 1 < rows ? stride + 1 : 1;
  return stride;
}

// Reports progress over all of a render's pixel work (the refine pass weighs like a base pass).
class ProgressMeter {
public:
  ProgressMeter(const RenderOptions& options, double totalRows) : options_(options), totalRows_(totalRows) {}
  void advance(std::uint32_t rows, std::uint64_t raysSoFar) {
    doneRows_ += rows;
    if (!options_.progress) return;
    RenderProgress p;
    p.fraction = totalRows_ > 0 ? std::min(1.0, doneRows_ / totalRows_) : 1.0;
    p.elapsedMs = msSince(start_);
    p.raysPerSecond = p.elapsedMs > 0 ? static_cast<double>(raysSoFar) / (p.elapsedMs * 1e-3) : 0.0;
    p.remainingMs = p.fraction > 0 ? p.elapsedMs * (1.0 - p.fraction) / p.fraction : 0.0;
    options_.progress(p);
  }

private:
  const RenderOptions& options_;
  double totalRows_;
  double doneRows_ = 0.0;
  Clock::time_point start_ = Clock::now();
};

} // namespace

Renderer::Renderer(const vulkan::Context& context, vulkan::PipelineCache* cache)
    : context_(context), setLayout_(makeSetLayout(context)), pipelineLayout_(makePipelineLayout(context, setLayout_)),
      timer_(context), library_(context, *pipelineLayout_, cache), sceneBuffers_(context) {
  const auto& device = context.device();
  vulkan::vulkanStep("creating the renderer's descriptor set", [&] {
    std::array<vk::DescriptorPoolSize, 4> sizes{
        vk::DescriptorPoolSize(vk::DescriptorType::eStorageTexelBuffer, 4),
        vk::DescriptorPoolSize(vk::DescriptorType::eUniformBuffer, 2),
        vk::DescriptorPoolSize(vk::DescriptorType::eStorageBuffer, gpu::kBindingCount),
        vk::DescriptorPoolSize(vk::DescriptorType::eUniformTexelBuffer, 8)};
    descriptorPool_ = vk::raii::DescriptorPool(
        device, vk::DescriptorPoolCreateInfo(vk::DescriptorPoolCreateFlagBits::eFreeDescriptorSet, 1, sizes));
    vk::DescriptorSetLayout layouts[] = {*setLayout_};
    vk::raii::DescriptorSets sets(device, vk::DescriptorSetAllocateInfo(*descriptorPool_, layouts));
    descriptorSet_ = std::move(sets.front());
  });
  frameBuffer_ =
      std::make_unique<vulkan::Buffer>(context, sizeof(gpu::FrameParams), vk::BufferUsageFlagBits::eUniformBuffer,
                                       vulkan::MemoryUse::Upload, "frame parameters");
  stats_ = std::make_unique<vulkan::Buffer>(
      context, sizeof(gpu::RayStats), vk::BufferUsageFlagBits::eStorageBuffer | vk::BufferUsageFlagBits::eTransferDst,
      vulkan::MemoryUse::Readback, "ray statistics");
  gpu::RayStats zero{}; // also RayStats.zero, the kernels' run-time zero
  stats_->write(&zero, sizeof zero);
  prevImage_ = std::make_unique<vulkan::Buffer>(context, sizeof(glm::vec4), kImageTexelFormat,
                                                vulkan::MemoryUse::DeviceLocal, "previous image (unused)");
  entryPoints_ = std::make_unique<vulkan::Buffer>(context, 2 * sizeof(glm::uvec4), vk::Format::eR32G32B32A32Uint,
                                                  vulkan::MemoryUse::DeviceLocal, "entry points (unused)",
                                                  vk::BufferUsageFlagBits::eStorageBuffer);
  pixelRays_ = std::make_unique<vulkan::Buffer>(context, sizeof(std::uint32_t), vk::BufferUsageFlagBits::eStorageBuffer,
                                                vulkan::MemoryUse::DeviceLocal, "rays per pixel (unused)");
  rayTree_ = std::make_unique<vulkan::Buffer>(context, sizeof(gpu::TreeRayHeader) + sizeof(gpu::TreeRay),
                                              vk::BufferUsageFlagBits::eStorageBuffer, vulkan::MemoryUse::DeviceLocal,
                                              "ray tree (unused)");
  photonImage_ = std::make_unique<vulkan::Buffer>(context, gpu::kPhotonHeaderWords * sizeof(std::uint32_t),
                                                  vk::BufferUsageFlagBits::eStorageBuffer,
                                                  vulkan::MemoryUse::DeviceLocal, "photon image (unused)");
}

Renderer::~Renderer() = default;

void Renderer::setScene(const Scene& scene) {
  setScene(scene, analyzeScene(scene, scene.render));
}

void Renderer::setScene(const Scene& scene, const Features& features) {
  features_ = features;
  // The BVH is built when the scene's own settings would use it, or the user asked for it.
  gpuScene_ = packScene(scene, scene.camera.position, features_.useBvh);
  sceneBuffers_.upload(gpuScene_);
  image_.reset(); // descriptors are rewritten once the image window exists
}

RenderResult Renderer::render(const Camera& camera, const RenderSettings& settings, const RenderOptions& options) {
  if (settings.method == Method::Forward && options.kernel == Kernel::Shade) {
    return renderForward(camera, settings, options);
  }
  RenderResult result;
  prepare(camera, settings, options);
  result.features = current_;
  result.timings.pipelineMs = kernels_.buildMs;
  result.timings.pipelineReused = kernels_.buildMs == 0.0;
  result.timings.pipelinesBuilt = kernels_.built;

  if (progressiveRender(settings, options)) {
    renderProgressive(settings, options, result);
    return result;
  }
  const std::size_t pixels = static_cast<std::size_t>(settings.width) * settings.height;
  if (options.kernel == Kernel::Hits)
    result.hits.resize(pixels);
  else if (options.kernel == Kernel::Aov)
    result.firstHits.resize(pixels);
  else
    result.image = Image(settings.width, settings.height);
  const bool adaptive =
      options.kernel == Kernel::Shade && settings.antialiasing == Antialiasing::Adaptive && settings.spp > 1;

  // A row window (a tile): adaptive AA's base pass also traces the row on each side that the refine
  // pass reads as neighbours, so the window's pixels are those of the whole image.
  const RowWindow rows = rowWindow(settings, options);
  const std::uint32_t rowBegin = rows.begin, rowEnd = rows.end;
  const std::uint32_t baseBegin = adaptive && rowBegin > 0 ? rowBegin - 1 : rowBegin;
  const std::uint32_t baseEnd = adaptive ? std::min(settings.height, rowEnd + 1) : rowEnd;

  ProgressMeter meter(options, static_cast<double>(rowEnd - rowBegin) * (adaptive ? 2.0 : 1.0));
  auto advanced = [&](std::uint32_t rows) { meter.advance(rows, result.stats.total()); };
  BandSizer sizer(settings.width, settings.height, imageRows_, options.bandBudgetMs,
                  static_cast<std::uint32_t>(std::max(1, settings.spp)));
  traceBands(false, baseBegin, baseEnd, settings, options, nullptr, sizer, result, advanced);
  if (adaptive) {
    // The refine pass reads a copy of the base image: rows refined by the band above do not change
    // the decisions of the next band, and the image does not depend on where the bands split.
    Image base = result.image;
    traceBands(true, rowBegin, rowEnd, settings, options, &base, sizer, result, advanced);
  }
  return result;
}

void Renderer::renderProgressive(const RenderSettings& settings, const RenderOptions& options, RenderResult& result) {
  checkProgressiveSettings(settings);
  const std::uint32_t width = settings.width;
  // Plain variables, not a structured binding: clang 15 does not let lambdas capture one.
  const RowWindow rows = rowWindow(settings, options);
  const std::uint32_t rowBegin = rows.begin, rowEnd = rows.end;
  // A tile under a noise threshold also traces a margin of rows on each side: a pixel's decision
  // reads its neighbours', whose decisions read theirs, so a difference at the margin's outer edge
  // (a neighbour not traced) moves one row inward per decision. With a margin as wide as there are
  // decisions, the tile's own rows decide as in the whole image, and tiles merge into exactly the
  // whole render.
  const bool tile = rowBegin > 0 || rowEnd < settings.height;
  const std::uint32_t margin = settings.noiseThreshold > 0.0 && tile ? decisionCount(settings) : 0;
  const std::uint32_t traceBegin = rowBegin > margin ? rowBegin - margin : 0;
  const std::uint32_t traceEnd = std::min(settings.height, rowEnd + margin);
  if (auto available = hostMemoryAvailable())
    checkProgressiveMemory(width, settings.height, traceEnd - traceBegin, *available);
  ProgressiveImage acc(width, settings.height, traceBegin, traceEnd);
  // The list in the order the sample pass's lanes take pixels: 8 x 8 tiles, row by row, each in
  // 4 x 2 blocks (camera.glsl, invocationPixel), so eight neighbouring list entries are a compact
  // block of the image while they are all open, and their rays walk the same BVH nodes.
  std::vector<std::uint32_t> open;
  open.reserve(static_cast<std::size_t>(width) * (traceEnd - traceBegin));
  for (std::uint32_t ty = traceBegin / 8 * 8; ty < traceEnd; ty += 8)
    for (std::uint32_t tx = 0; tx < width; tx += 8)
      for (std::uint32_t by = 0; by < 8; by += 2)
        for (std::uint32_t bx = 0; bx < 8; bx += 4)
          for (std::uint32_t j = 0; j < 8; ++j) {
            const std::uint32_t x = tx + bx + (j & 3u), y = ty + by + (j >> 2);
            if (x < width && y >= traceBegin && y < traceEnd) open.push_back(y * width + x);
          }
  const double totalPixels = static_cast<double>(open.size());
  if (kernels_.entry) result.timings.traceMs += findEntryPointsOfTheWholeImage(settings);

  // Rows whose every eye ray provably meets nothing (row culling, render/row_culling.h): each sample
  // of their pixels is a miss of weight 1, the background, so the host adds their sums as the
  // kernel would (in float, a sample at a time, each pass from zero; one eye ray per sample) and the
  // passes list only the other pixels: the same sums, decisions and image, bit for bit.
  std::vector<char> emptyRow(settings.height, 0);
  if (options.cullRows && options.kernel == Kernel::Shade && !current_.thinLens)
    for (const RowRun& run :
         splitRows(cull_, width, settings.height, traceBegin, traceEnd - traceBegin, gpu::kWorkgroupSizeY))
      if (run.empty) std::fill_n(emptyRow.begin() + run.row0, run.rows, char{1});
  result.timings.culledRows =
      static_cast<std::uint32_t>(std::count(emptyRow.begin() + rowBegin, emptyRow.begin() + rowEnd, char{1}));
  const glm::vec3 background = glm::vec3(gpuScene_.background);
  std::vector<std::uint32_t> traced, missed; // the open pixels the pass lists, and those of empty rows

  auto start = Clock::now();
  double msPerSample = 0.0;  // GPU time per pixel-sample, measured
  std::uint32_t samples = 0; // of each open pixel
  int passes = 0;
  double lastPassMs = 0.0;
  std::vector<glm::vec4> list, sums;
  std::vector<std::uint32_t> order; // list position -> entry of the chunk (spreadGroups)
  while (true) {
    auto decideStart = Clock::now();
    traced.clear();
    missed.clear();
    for (std::uint32_t i : open) (emptyRow[i / width] ? missed : traced).push_back(i);
    // The passes before the first decision run as one list pass, which reports each on its own. A
    // time limit budgets for the pixels the pass traces (at least one while any is open: the rows
    // that see nothing cost no GPU time).
    const std::size_t budgeted = open.empty() ? 0 : std::max<std::size_t>(traced.size(), 1);
    const std::vector<std::uint32_t> ks =
        nextPasses(settings, samples, budgeted, msPerSample, result.timings.traceMs, options.firstPassesTogether);
    if (ks.empty()) break;
    const std::uint32_t k = std::accumulate(ks.begin(), ks.end(), 0u);
    const auto together = static_cast<std::uint32_t>(ks.size());
    // Two texels of output per entry and pass; the list itself goes to the pass input (prevImage_).
    const std::size_t capacity = std::min<std::size_t>(
        static_cast<std::size_t>(imageWidth_) * imageRows_ / (2 * together), prevImage_->size() / 16);
    // The open pixels of empty rows: their passes' sums (rgb, samples) and (first half, rays).
    std::vector<glm::vec4> missSums;
    for (std::uint32_t pass : ks) {
      glm::vec3 sum(0.0f), half(0.0f);
      for (std::uint32_t j = 0; j < pass; ++j) {
        sum += background;
        if (j < firstHalf(pass)) half += background;
      }
      missSums.push_back(glm::vec4(sum, static_cast<float>(pass)));
      missSums.push_back(glm::vec4(half, options.countStats && pass == ks.back() ? static_cast<float>(k) : 0.0f));
    }
    parallelFor(missed.size(), ProgressiveImage::kPixelsPerThread, [&](std::size_t begin, std::size_t end) {
      for (std::size_t j = begin; j < end; ++j)
        for (std::size_t p = 0; p < missSums.size(); p += 2) acc.addPixel(missed[j], missSums[p], missSums[p + 1]);
    });
    const std::uint64_t missedEyeRays = static_cast<std::uint64_t>(missed.size()) * k; // one per sample
    result.timings.culledEyeRays += missedEyeRays;
    if (options.countStats) result.stats.eye += missedEyeRays;
    result.timings.decideMs += msSince(decideStart);
    double passMs = 0.0;
    for (std::size_t first = 0; first < traced.size();) {
      if (options.cancel && options.cancel->load()) throw CancelledError("interrupted");
      // A chunk of the list near the band budget at the measured speed (64 K entries per sample first).
      double want = msPerSample > 0.0 ? options.bandBudgetMs / (msPerSample * k) : 65536.0 / k;
      std::size_t n = std::clamp<std::size_t>(static_cast<std::size_t>(want), 4096, capacity);
      n = std::min(n, traced.size() - first);
      list.resize(n);
      // Lanes of a subgroup share each listed pixel and trace its samples side by side
      // (trace.comp, listPass): late passes list scattered pixels, and a SIMD batch of one pixel's
      // samples walks nearly equal rays where eight pixels' rays diverge. Each lane still traces at
      // least eight samples, so that its fixed cost is spread. Lanes pay in glass trees and over
      // textures; on cheap scenes their shuffles cost more than they save (docs/progressive.md,
      // "Lanes share a pixel"). Where the driver lets loops run to their end, one dispatch takes
      // the whole pass. Elsewhere a lane takes `perLane` samples per dispatch, as recordDispatch
      // takes one (Mesa 22's loop limit applies per dispatch), more for short lists: a dispatch of
      // a few workgroups is mostly launch overhead, so the last passes, over a few hundred pixels
      // with hundreds of samples each, take several samples per lane (a tree that still meets
      // Mesa 22's limit is counted as truncated). The image does not depend on the split.
      constexpr std::uint32_t group = gpu::kWorkgroupSizeX * gpu::kWorkgroupSizeY;
      const std::uint32_t subgroup = std::min(std::bit_floor(std::max(1u, context_.info().subgroupSize)), group);
      const bool divergent = current_.refraction || current_.textures;
      const std::uint32_t lanes =
          options.oneSamplePerDispatch || !divergent ? 1u : std::min(subgroup, std::bit_floor(std::max(1u, k / 8)));
      const std::uint32_t perLane =
          std::bit_floor(static_cast<std::uint32_t>(std::clamp<std::size_t>(16384 / n, 1, 16)));
      const std::uint32_t perDispatch = options.oneSamplePerDispatch ? 1u : samplesTogether_ ? k : perLane * lanes;
      spreadGroups(n, group / lanes, order);
      for (std::size_t j = 0; j < n; ++j) {
        std::uint32_t i = traced[first + order[j]];
        list[j] = glm::vec4(static_cast<float>(i % width), static_cast<float>(i / width), 0.0f, 0.0f);
      }
      prevImage_->write(list.data(), n * sizeof(glm::vec4));

      gpu::PushConstants push{};
      push.pass = gpu::kPassList;
      push.tileSize = glm::uvec2(static_cast<std::uint32_t>(n), 1);
      push.param = lanes;
      // Each pass's two halves, for the error estimate; the second and third pass where there are.
      push.splitBase = samples + firstHalf(ks[0]);
      if (together > 1) {
        push.segmentEnd0 = samples + ks[0];
        push.splitBase1 = push.segmentEnd0 + firstHalf(ks[1]);
      }
      if (together > 2) {
        push.segmentEnd1 = push.segmentEnd0 + ks[1];
        push.splitBase2 = push.segmentEnd1 + firstHalf(ks[2]);
      }
      // Where one dispatch takes the whole list pass, the kernel neither writes nor reads the texel of
      // an empty first half (a pass of one sample; never the last pass, whose half carries the rays).
      std::uint32_t noHalf = 0;
      if (perDispatch >= k)
        for (std::uint32_t p = 0; p + 1 < together; ++p)
          if (firstHalf(ks[p]) == 0) noHalf |= gpu::kFlagNoHalf0 << p;
      push.flags = noHalf;
      BandTimes t =
          submitBand(context_, timer_, "sampling", 0, settings.height, [&](const vk::raii::CommandBuffer& cmd) {
            cmd.bindDescriptorSets(vk::PipelineBindPoint::eCompute, *pipelineLayout_, 0, {*descriptorSet_}, {});
            cmd.bindPipeline(vk::PipelineBindPoint::eCompute, kernels_.sample->handle());
            timer_.start(cmd);
            for (std::uint32_t s = 0; s < k; s += perDispatch) {
              gpu::PushConstants one = push;
              one.sampleBase = samples + s;
              one.sampleCount = std::min(perDispatch, k - s);
              if (s > 0) {
                one.flags |= gpu::kFlagAccumulate;
                orderShaderWrites(cmd);
              }
              cmd.pushConstants<gpu::PushConstants>(*pipelineLayout_, vk::ShaderStageFlagBits::eCompute, 0, one);
              cmd.dispatch(static_cast<std::uint32_t>((n * lanes + group - 1) / group), 1, 1);
            }
            timer_.stop(cmd);
          });
      result.timings.traceMs += t.gpuMs;
      result.timings.traceWallMs += t.wallMs;
      ++result.timings.bands;
      passMs += t.gpuMs;
      result.stats += readStatsAndReset();
      msPerSample = t.gpuMs / (static_cast<double>(n) * k);

      auto readStart = Clock::now();
      // The sums in place where the host sees the buffer's memory (lavapipe), else copied out.
      const glm::vec4* passSums = image_->view(sums, 2 * together * n);
      // Each entry is a pixel of its own: added on every hardware thread.
      parallelFor(n, ProgressiveImage::kPixelsPerThread, [&](std::size_t begin, std::size_t end) {
        constexpr std::size_t ahead = ProgressiveImage::kPrefetchAhead;
        for (std::size_t j = begin; j < end; ++j) {
          if (j + ahead < end) acc.prefetchPixel(traced[first + order[j + ahead]]);
          const std::uint32_t i = traced[first + order[j]];
          for (std::uint32_t p = 0; p < together; ++p) {
            const std::size_t t = 2 * (together * j + p);
            acc.addPixel(i, passSums[t], noHalf & (gpu::kFlagNoHalf0 << p) ? glm::vec4(0.0f) : passSums[t + 1]);
          }
        }
      });
      result.timings.readbackMs += msSince(readStart);
      first += n;

      if (options.progress) {
        RenderProgress p;
        const double closed = totalPixels - static_cast<double>(traced.size() - first);
        p.fraction = settings.timeLimit > 0.0 ? std::min(1.0, result.timings.traceMs / (settings.timeLimit * 1e3))
                                              : closed / std::max(1.0, totalPixels);
        p.elapsedMs = msSince(start);
        p.raysPerSecond = p.elapsedMs > 0 ? static_cast<double>(result.stats.total()) / (p.elapsedMs * 1e-3) : 0.0;
        p.remainingMs = p.fraction > 0 ? p.elapsedMs * (1.0 - p.fraction) / p.fraction : 0.0;
        options.progress(p);
      }
    }
    samples += k;
    passes += static_cast<int>(together); // the schedule's passes
    lastPassMs = passMs;
    // Decisions start once every pixel has min_spp samples (passes of a quarter, a quarter and a half).
    const auto minSpp = static_cast<std::uint32_t>(settings.minSpp);
    if (settings.noiseThreshold > 0.0 && samples >= minSpp) {
      decideStart = Clock::now();
      open = acc.stillOpen(open, settings.noiseThreshold, samples - k < minSpp);
      result.timings.decideMs += msSince(decideStart);
    }
  }
  result.image = acc.image();
  result.pixels = acc.stats();
  // The margin's rows are not the tile's: black, and no statistics, as outside any tile.
  auto outside = [&](std::size_t i) { return i / width < rowBegin || i / width >= rowEnd; };
  for (std::size_t i = 0; i < result.image.pixels.size(); ++i) {
    if (!outside(i)) continue;
    result.image.pixels[i] = glm::vec3(0.0f);
    result.pixels.samples[i] = result.pixels.error[i] = result.pixels.rays[i] = 0.0f;
  }
  result.progressive = summarize(result.pixels, passes);
  result.progressive.lastPassMs = lastPassMs;
  // Converged: closed by the threshold before the cap (without one, every pixel counts).
  if (settings.noiseThreshold > 0.0) {
    auto stillOpen = std::count_if(open.begin(), open.end(), [&](std::uint32_t i) { return !outside(i); });
    result.progressive.converged =
        1.0 - static_cast<double>(stillOpen) / (static_cast<double>(width) * (rowEnd - rowBegin));
  }
}

double Renderer::findEntryPointsOfTheWholeImage(const RenderSettings& settings) {
  const vk::DeviceSize bytes = entryTileCount(settings.width, settings.height) * 2 * sizeof(glm::uvec4);
  if (entryPoints_->size() < bytes) {
    entryPoints_.reset();
    entryPoints_ =
        std::make_unique<vulkan::Buffer>(context_, bytes, vk::Format::eR32G32B32A32Uint, vulkan::MemoryUse::DeviceLocal,
                                         "entry points", vk::BufferUsageFlagBits::eStorageBuffer);
    updateDescriptors();
  }
  gpu::PushConstants push{};
  push.tileSize = glm::uvec2(settings.width, settings.height);
  const std::uint32_t tiles = entryTileCount(settings.width, settings.height);
  BandTimes t =
      submitBand(context_, timer_, "finding entry points", 0, settings.height, [&](const vk::raii::CommandBuffer& cmd) {
        cmd.bindDescriptorSets(vk::PipelineBindPoint::eCompute, *pipelineLayout_, 0, {*descriptorSet_}, {});
        cmd.bindPipeline(vk::PipelineBindPoint::eCompute, kernels_.entry->handle());
        timer_.start(cmd);
        cmd.pushConstants<gpu::PushConstants>(*pipelineLayout_, vk::ShaderStageFlagBits::eCompute, 0, push);
        cmd.dispatch((tiles + 63) / 64, 1, 1);
        timer_.stop(cmd);
        // The passes' reads, in later submissions, come after these writes.
        vk::MemoryBarrier written(vk::AccessFlagBits::eShaderWrite, vk::AccessFlagBits::eShaderRead);
        cmd.pipelineBarrier(vk::PipelineStageFlagBits::eComputeShader, vk::PipelineStageFlagBits::eComputeShader, {},
                            written, {}, {});
      });
  return t.gpuMs;
}

void Renderer::traceBands(bool refine, std::uint32_t begin, std::uint32_t end, const RenderSettings& settings,
                          const RenderOptions& options, const Image* base, BandSizer& sizer, RenderResult& result,
                          const std::function<void(std::uint32_t)>& advanced) {
  const std::uint32_t width = settings.width;
  const bool adaptive =
      options.kernel == Kernel::Shade && settings.antialiasing == Antialiasing::Adaptive && settings.spp > 1;
  for (std::uint32_t y = begin; y < end;) {
    if (options.cancel && options.cancel->load()) throw CancelledError("interrupted");
    const std::uint32_t rows = sizer.rowsAt(y, end);

    gpu::PushConstants push{};
    push.tileOrigin = glm::uvec2(0, y);
    push.tileSize = glm::uvec2(width, rows);
    push.imageRow0 = y;
    push.sampleBase = 0;
    if (refine) {
      uploadRefineRows(*base, y, rows, *prevImage_, push);
      push.pass = gpu::kPassRefine;
      push.sampleCount = static_cast<std::uint32_t>(settings.spp);
    } else {
      push.pass = gpu::kPassSample;
      push.sampleCount = adaptive ? 1u : static_cast<std::uint32_t>(settings.spp);
      push.flags = push.sampleCount == 1 ? gpu::kFlagCenterSample : 0u;
    }

    std::uint32_t culled = 0;
    BandTimes t = submitBand(context_, timer_, refine ? "refining" : "tracing", y, rows, [&](const auto& cmd) {
      culled = recordDispatch(cmd, refine ? *kernels_.refine : *kernels_.sample, push, &timer_,
                              refine ? nullptr : kernels_.fill);
    });
    result.timings.culledRows += culled; // the refine pass culls nothing
    result.timings.culledEyeRays += std::uint64_t{culled} * width * push.sampleCount;
    result.timings.traceMs += t.gpuMs;
    result.timings.traceWallMs += t.wallMs;
    ++result.timings.bands;
    // Without countStats only `truncated` is counted; the other counters stay 0.
    result.stats += readStatsAndReset();
    sizer.measured(rows - culled, t.gpuMs);

    auto readStart = Clock::now();
    if (options.kernel == Kernel::Hits)
      readBandHits(*image_, width, y, rows, result.hits);
    else if (options.kernel == Kernel::Aov)
      readBandFirstHits(*image_, width, y, rows, result.firstHits);
    else
      readBandImage(*image_, y, rows, result.image);
    result.timings.readbackMs += msSince(readStart);

    y += rows;
    advanced(rows);
  }
}

RayTree Renderer::inspect(const Camera& camera, const RenderSettings& settings, const RenderOptions& options,
                          glm::uvec2 pixel, std::uint32_t capacity) {
  if (pixel.x >= settings.width || pixel.y >= settings.height)
    throw Error("Renderer::inspect: pixel outside the image");
  RenderSettings s = settings;
  s.noiseThreshold = 0.0;
  s.timeLimit = 0.0;
  s.antialiasing = Antialiasing::Stratified;
  RenderOptions o = options;
  o.kernel = Kernel::Shade;
  o.recordTree = true;
  o.progressive = false;
  o.pixelStats = false;
  o.pixelRays = false;
  // Entry points and row culling serve whole tiles and rows; one pixel starts at the root. The
  // hits are the same (they are exact), so the tree is the one the render traces.
  o.entryPoints = false;
  o.cullRows = false;
  prepare(camera, s, o);

  const vk::DeviceSize bytes = sizeof(gpu::TreeRayHeader) + vk::DeviceSize(capacity) * sizeof(gpu::TreeRay);
  if (rayTree_->size() < bytes) {
    rayTree_.reset();
    rayTree_ = std::make_unique<vulkan::Buffer>(context_, bytes, vk::BufferUsageFlagBits::eStorageBuffer,
                                                vulkan::MemoryUse::Readback, "ray tree");
    updateDescriptors();
  }
  gpu::TreeRayHeader header{glm::uvec4(0u, capacity, 0u, 0u)};
  rayTree_->write(&header, sizeof header);

  gpu::PushConstants push{};
  push.tileOrigin = pixel;
  push.tileSize = glm::uvec2(1, 1);
  push.imageRow0 = pixel.y;
  push.pass = gpu::kPassSample;
  push.sampleCount = static_cast<std::uint32_t>(s.spp);
  push.flags = s.spp == 1 ? gpu::kFlagCenterSample : 0u;
  submitBand(context_, timer_, "inspecting", pixel.y, 1,
             [&](const auto& cmd) { recordDispatch(cmd, *kernels_.sample, push, nullptr); });
  readStatsAndReset();

  glm::vec4 sums;
  image_->read(&sums, sizeof sums, vk::DeviceSize(pixel.x) * sizeof(glm::vec4));
  rayTree_->read(&header, sizeof header);
  std::vector<gpu::TreeRay> records(std::min(header.counts.x, capacity));
  if (!records.empty()) rayTree_->read(records.data(), records.size() * sizeof(gpu::TreeRay), sizeof header);
  return rayTreeFromRecords(header, records, gpuScene_, pixel, sums, static_cast<std::uint32_t>(settings.maxDepth));
}

void Renderer::prepare(const Camera& camera, const RenderSettings& settings, const RenderOptions& options) {
  if (!sceneBuffers_.uploaded()) throw Error("Renderer::prepare: no scene set");
  current_ = features_;
  current_.applySettings(settings);
  // The BVH exists only if setScene built it; without it the kernel loops over all primitives.
  current_.useBvh = current_.useBvh && !gpuScene_.bvh.nodes.empty();
  memory_ = sceneBuffers_.memoryFor(options.sceneMemory);
  const bool newTable = prepareShadowEntries(settings, options);
  kernels_ = library_.realize(planKernels(current_, settings, options, shapeOf(gpuScene_), memory_));

  const bool adaptive =
      options.kernel == Kernel::Shade && settings.antialiasing == Antialiasing::Adaptive && settings.spp > 1;
  // The AOV kernel writes two texels per pixel (shaders/aov.comp), the others one.
  const std::uint32_t pixelTexels = options.kernel == Kernel::Aov ? 2u : 1u;
  std::uint64_t rowBytes = static_cast<std::uint64_t>(settings.width) * pixelTexels * sizeof(glm::vec4);
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
  // The driver is asked once per device (a one-invocation kernel), and only by a render that takes
  // more than one sample of a pixel.
  const bool manySamples = settings.spp > 1 || progressiveRender(settings, options) || options.progressive;
  samplesTogether_ = manySamples && !options.oneSamplePerDispatch && context_.loopLimit() == 0;
  auto rows = static_cast<std::uint32_t>(std::min<std::uint64_t>(rowsFit, settings.height));
  // A progressive render lists its open pixels in the pass input (the refine pass's buffer).
  ensureImageWindow(settings.width, rows, pixelTexels, adaptive || progressiveRender(settings, options),
                    options.pixelRays);
  if (newTable) updateDescriptors(); // the BVH records' buffer was replaced
  writeFrameParams(camera, settings, current_);
  firstDispatchNewPipelines();
}

namespace {

// What the shadow entry points' table costs and saves, on the 2-core KVM machine with an 8 MB L3
// (lavapipe Mesa 25.0.7, 2026-12-05; docs/performance.md, "Shadow entry points per triangle and
// light"): about 0.18 µs per (triangle, light) to build on both threads, 90-130 ns saved per
// shadow ray that leaves a triangle of a 100 k- to 1 M-triangle mesh, so it pays after about two
// shadow rays per (triangle, light). A pixel sample sends at most one shadow ray to each light
// from its eye ray's hit, fewer where eye rays miss or face away from the light: the rule asks
// for twice that many pixel samples per triangle.
constexpr double kPixelSamplesPerTriangle = 4.0;

// The "nothing between" pairs: about 0.95 µs more per (triangle, light) on both threads, and
// they save about 100 ns per shadow ray at 100 k and 1 M triangles (2-core KVM Xeon, lavapipe Mesa
// 25.0.7, 2026-12-07; docs/performance.md, "Nothing between"), so they pay after about ten shadow
// rays per (triangle, light). The bench's mesh sends 0.42 shadow rays per pixel sample and breaks
// even near 23 pixel samples per triangle, a torus covering less of the picture (0.21) near 44.
constexpr double kPixelSamplesPerTriangleNothing = 32.0;

// The viewer accumulates without end, so the marks pay for themselves there sooner or later, but
// they are built before its first frame: it looks for them while that costs at most about a
// quarter of a second (about 1 µs per pair), so that a large mesh's first image does not wait
// for them (1 M triangles under one light: about 1 s).
constexpr std::size_t kViewerNothingPairs = 250000;

bool shadowEntriesPay(std::size_t triangles, double samplesPerPixel, std::uint64_t pixels, double perTriangle) {
  return samplesPerPixel * static_cast<double>(pixels) >= perTriangle * static_cast<double>(triangles);
}

} // namespace

bool Renderer::prepareShadowEntries(const RenderSettings& settings, const RenderOptions& options) {
  GpuScene& g = gpuScene_;
  const ShadowEntries mode = options.shadowEntryPoints;
  auto skip = [&](std::string why) {
    shadowEntriesSkipped_ = std::move(why);
    return false;
  };
  if (mode == ShadowEntries::Off) return skip("off (--shadow-entry-points off)");
  if (!current_.useBvh || g.triangles.empty()) return skip("none (no triangles in a BVH)");
  if (!current_.shadows || (options.kernel != Kernel::Shade && options.kernel != Kernel::Hits))
    return skip("none (no shadow rays)");
  if (g.lights.size() > gpu::kShadowEntryLightsMax)
    return skip("none (more than " + std::to_string(gpu::kShadowEntryLightsMax) + " lights)");
  const std::uint64_t texels = gpu::kBvhRecordTexels * g.bvhNodes.size() + 2ull * g.triangles.size() * g.lights.size();
  if (texels > context_.info().maxTexelBufferElements || texels * sizeof(glm::uvec4) > kShadowEntryBudget)
    return skip("none (the table would not fit one texel buffer)");
  // Which parts of the table the render asks for: the entry points, and the "nothing between"
  // pairs on top of them.
  bool entries = true, nothing = mode == ShadowEntries::On;
  if (mode == ShadowEntries::Auto) {
    if (options.progressive) {
      // The viewer accumulates without end and builds the entry points at its first frame, and
      // the marks too unless they would hold up that frame.
      nothing = g.triangles.size() * g.lights.size() <= kViewerNothingPairs;
      if (!nothing)
        shadowNothingSkipped_ = "not looked for (over " + std::to_string(kViewerNothingPairs) +
                                " pairs: they would hold up the first frame; --shadow-entry-points on looks for them)";
    } else if (context_.info().type != "CPU") {
      // The rules below were measured on lavapipe; a GPU traces a shadow ray in a small fraction
      // of the table's build time per triangle, so there only a render without end recovers it.
      entries = false;
      shadowEntriesSkipped_ =
          "not built (on a GPU one render's shadow rays do not pay for it; --shadow-entry-points on builds it)";
    } else {
      // A progressive render takes at least minSpp samples.
      const RowWindow rows = rowWindow(settings, options);
      const std::uint64_t pixels = static_cast<std::uint64_t>(settings.width) * (rows.end - rows.begin);
      const double samples =
          progressiveRender(settings, options) ? std::max(1, settings.minSpp) : std::max(1, settings.spp);
      entries = shadowEntriesPay(g.triangles.size(), samples, pixels, kPixelSamplesPerTriangle);
      nothing = shadowEntriesPay(g.triangles.size(), samples, pixels, kPixelSamplesPerTriangleNothing);
      if (!entries)
        shadowEntriesSkipped_ =
            "not built (too few pixel samples per triangle to pay for it; --shadow-entry-points on builds it)";
      else if (!nothing)
        shadowNothingSkipped_ = "not looked for (too few pixel samples per triangle to pay for it; "
                                "--shadow-entry-points on looks for them)";
    }
  } else if (mode == ShadowEntries::Entries) {
    shadowNothingSkipped_ = "not looked for (--shadow-entry-points entries)";
  }
  if (mode == ShadowEntries::Auto && nothing && settings.numerics == Numerics::Naive) {
    nothing = false; // the kernel walks anyway there (bvh.glsl, traverseBvh)
    shadowNothingSkipped_ = "not looked for (naive numerics do not use them)";
  }
  // A table already built serves while it holds what is asked for; Auto takes a richer one as it is.
  if (!g.shadowEntries.empty()) {
    if (g.shadowNothingBetween == nothing || (mode == ShadowEntries::Auto && g.shadowNothingBetween)) return false;
  } else if (!entries) {
    return false;
  }
  ShadowEntryOptions build;
  build.nothingBetween = nothing;
  g.shadowEntries.clear();
  buildShadowEntries(g, build);
  if (g.shadowEntries.empty()) return skip("none");
  shadowEntriesSkipped_.clear();
  if (nothing) shadowNothingSkipped_.clear();
  sceneBuffers_.uploadBvhNodes(g);
  return true;
}

void Renderer::firstDispatchNewPipelines() {
  // lavapipe turns a pipeline into machine code only when it is first dispatched (llvmpipe keys
  // that code on the resources bound, so the descriptor set is the render's own), and Mesa keeps it
  // in its on-disk shader cache for the next process: without this step the compile, seconds on a
  // cold cache, landed in the first band's trace time. All push constants zero: an empty tile, no
  // samples, no photons; each kernel returns before it touches a pixel or a counter.
  for (std::size_t i = 0; i < kernels_.builtPipelines.size(); ++i) {
    PipelineBuild& build = kernels_.built[i];
    auto start = Clock::now();
    context_.submitAndWait("first dispatch of pipeline '" + build.name + "'", [&](const vk::raii::CommandBuffer& cmd) {
      cmd.bindDescriptorSets(vk::PipelineBindPoint::eCompute, *pipelineLayout_, 0, {*descriptorSet_}, {});
      cmd.bindPipeline(vk::PipelineBindPoint::eCompute, kernels_.builtPipelines[i]->handle());
      cmd.pushConstants<gpu::PushConstants>(*pipelineLayout_, vk::ShaderStageFlagBits::eCompute, 0,
                                            gpu::PushConstants{});
      cmd.dispatch(1, 1, 1);
      // Its counter atomics add zero, but they are writes: visible before the host's next access.
      vk::MemoryBarrier barrier(vk::AccessFlagBits::eShaderWrite,
                                vk::AccessFlagBits::eHostRead | vk::AccessFlagBits::eHostWrite);
      cmd.pipelineBarrier(vk::PipelineStageFlagBits::eComputeShader, vk::PipelineStageFlagBits::eHost, {}, barrier, {},
                          {});
    });
    build.firstDispatchMs = msSince(start);
    build.ms += build.firstDispatchMs;
    kernels_.buildMs += build.firstDispatchMs;
  }
  kernels_.builtPipelines.clear(); // once per build: a reused set is not dispatched again
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
  recordDispatch(cmd, countRays ? *kernels_.sample : *kernels_.quietSample, push, nullptr,
                 countRays ? kernels_.fill : kernels_.quietFill);
}

void Renderer::ensureImageWindow(std::uint32_t width, std::uint32_t rows, std::uint32_t pixelTexels, bool needPrev,
                                 bool pixelRays) {
  bool rebuild = !image_ || imageWidth_ != width || imageRows_ != rows || imagePixelTexels_ != pixelTexels;
  if (rebuild) {
    vk::DeviceSize bytes = static_cast<vk::DeviceSize>(width) * rows * pixelTexels * sizeof(glm::vec4);
    image_.reset(); // the old window's memory goes back first
    image_ = std::make_unique<vulkan::Buffer>(context_, bytes, kImageTexelFormat, vulkan::MemoryUse::DeviceLocal,
                                              "image", vk::BufferUsageFlagBits::eStorageBuffer); // kBindingImageOut
    imageWidth_ = width;
    imageRows_ = rows;
    imagePixelTexels_ = pixelTexels;
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
  const vk::DeviceSize rayBytes = static_cast<vk::DeviceSize>(width) * rows * sizeof(std::uint32_t);
  if (pixelRays && pixelRays_->size() < rayBytes) {
    pixelRays_.reset();
    pixelRays_ = std::make_unique<vulkan::Buffer>(context_, rayBytes, vk::BufferUsageFlagBits::eStorageBuffer,
                                                  vulkan::MemoryUse::DeviceLocal, "rays per pixel");
    rebuild = true;
  }
  if (rebuild) updateDescriptors();
}

void Renderer::updateDescriptors() {
  std::vector<vk::DescriptorBufferInfo> infos(gpu::kBindingCount);
  std::vector<vk::BufferView> views(gpu::kBindingCount);
  std::vector<vk::WriteDescriptorSet> writes;
  for (std::uint32_t b = 0; b < gpu::kBindingCount; ++b) {
    if (isTexelBinding(b)) {
      views[b] = b == gpu::kBindingImage         ? image_->texelView()
                 : b == gpu::kBindingPrevImage   ? prevImage_->texelView()
                 : b == gpu::kBindingEntryTexels ? entryPoints_->texelView()
                                                 : sceneBuffers_.at(b).texelView();
      writes.emplace_back(*descriptorSet_, b, 0, 1, descriptorType(b), nullptr, nullptr, &views[b]);
      continue;
    }
    vk::Buffer handle = b == gpu::kBindingFrame         ? frameBuffer_->handle()
                        : b == gpu::kBindingStats       ? stats_->handle()
                        : b == gpu::kBindingEntryPoints ? entryPoints_->handle()
                        : b == gpu::kBindingPixelRays   ? pixelRays_->handle()
                        : b == gpu::kBindingRayTree     ? rayTree_->handle()
                        : b == gpu::kBindingPhotonImage ? photonImage_->handle()
                        : b == gpu::kBindingImageOut    ? image_->handle()
                                                        : sceneBuffers_.at(b).handle();
    infos[b] = vk::DescriptorBufferInfo(handle, 0, VK_WHOLE_SIZE);
    writes.emplace_back(*descriptorSet_, b, 0, 1, descriptorType(b), nullptr, &infos[b]);
  }
  context_.device().updateDescriptorSets(writes, {});
}

void Renderer::writeFrameParams(const Camera& camera, const RenderSettings& s, const Features& f) {
  CameraFrame cam = makeCameraFrame(camera, s.width, s.height);
  cull_ = makeCullScene(gpuScene_, cam);
  const GpuScene& g = gpuScene_;
  gpu::FrameParams p{};
  p.cameraForward = glm::vec4(glm::vec3(cam.forward), 0.0f);
  p.cameraRight = glm::vec4(glm::vec3(cam.right * (cam.tanHalfFovY * cam.aspect)), 0.0f);
  p.cameraUp = glm::vec4(glm::vec3(cam.up * cam.tanHalfFovY), 0.0f);
  p.cameraOrigin = glm::vec4(glm::vec3(camera.position - g.origin), static_cast<float>(camera.aperture));
  p.worldOffset = glm::vec4(glm::vec3(g.origin), 0.0f);
  p.background = glm::vec4(glm::vec3(g.background), 0.0f);
  p.ambientLight = glm::vec4(glm::vec3(g.ambientLight), 0.0f);
  p.bailout = static_cast<float>(s.bailout);
  p.adaptiveThreshold = static_cast<float>(s.adaptiveThreshold);
  // A pixel's angle (RTG ch. 20, eq. 20.30: atan(2 tan(fov / 2) / height)), the eye rays' cone.
  p.coneSpread = static_cast<float>(std::atan(2.0 * cam.tanHalfFovY / s.height));
  p.focusDistance = static_cast<float>(camera.focusDistanceOrDefault());
  p.imageSize = glm::uvec2(s.width, s.height);
  // Depth beyond what the weights can reach changes nothing; the specialized kernel stops there.
  p.maxDepth = static_cast<std::uint32_t>(f.reflection ? f.usableDepth : 0);
  p.sphereCount = static_cast<std::uint32_t>(g.spheres.size());
  p.planeCount = static_cast<std::uint32_t>(g.planes.size());
  p.triangleCount = static_cast<std::uint32_t>(g.triangles.size());
  p.polygonCount = static_cast<std::uint32_t>(g.polygons.size());
  p.lightCount = static_cast<std::uint32_t>(g.lights.size());
  p.occluderPlaneCount = g.occluderPlanes;
  p.bvhRoot = g.bvhRoot;
  if (!g.shadowEntries.empty()) {
    p.shadowEntryBase =
        static_cast<std::uint32_t>(gpu::kBvhRecordTexels * g.bvhNodes.size()); // never 0: the root has a record
    p.shadowEntryLights = static_cast<std::uint32_t>(g.lights.size());         // two texels each
  }
  p.triangleBoundsMin = glm::vec4(g.triangleBounds.min, 0.0f);
  p.triangleBoundsMax = glm::vec4(g.triangleBounds.max, 0.0f);
  p.polygonBoundsMin = glm::vec4(g.polygonBounds.min, 0.0f);
  p.polygonBoundsMax = glm::vec4(g.polygonBounds.max, 0.0f);
  p.sampleSeed = s.seed;
  frameBuffer_->write(&p, sizeof p);
  frameWidth_ = s.width;
  frameHeight_ = s.height;
}

std::uint32_t Renderer::recordDispatch(const vk::raii::CommandBuffer& cmd, const vulkan::ComputePipeline& pipeline,
                                       const gpu::PushConstants& push, const GpuTimer* timer,
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
  if (timer) timer->start(cmd);
  if (kernels_.entry) {
    // The band's entry points, one invocation per tile, before the passes that read them.
    gpu::PushConstants band = push;
    band.tileOrigin = glm::uvec2(0, push.imageRow0);
    band.tileSize = glm::uvec2(frameWidth_, push.tileOrigin.y + push.tileSize.y - push.imageRow0);
    std::uint32_t tiles = entryTileCount(frameWidth_, band.tileSize.y);
    cmd.bindPipeline(vk::PipelineBindPoint::eCompute, kernels_.entry->handle());
    cmd.pushConstants<gpu::PushConstants>(*pipelineLayout_, vk::ShaderStageFlagBits::eCompute, 0, band);
    cmd.dispatch((tiles + 63) / 64, 1, 1);
    vk::MemoryBarrier written(vk::AccessFlagBits::eShaderWrite, vk::AccessFlagBits::eShaderRead);
    cmd.pipelineBarrier(vk::PipelineStageFlagBits::eComputeShader, vk::PipelineStageFlagBits::eComputeShader, {},
                        written, {}, {});
  }
  // Where the driver cuts loops short, one dispatch per sample, each adding to the sums of the one
  // before. Mesa 22's llvmpipe stops every loop of an invocation once the loops of its SIMD group
  // have run 65535 iterations in all (LP_MAX_TGSI_LOOP_ITERATIONS, shared by all loops of a
  // shader): 64 samples of a deep glass tree in one invocation reach that and lose their last
  // samples without a trace. A dispatch per sample gives each sample the whole budget. Elsewhere
  // (samplesTogether_) one dispatch takes them all: each invocation's fixed cost (the scene's
  // registers, its sums, its counters' subgroup sums and atomics) is paid once per pixel, not once
  // per sample: a 16-spp render of seed.json takes 0.6 of the time on Mesa 25 (docs/performance.md,
  // "Samples together"). The sums are added in the same order either way, so the image is bit for
  // bit the same.
  const bool split = push.sampleCount > 1 && !samplesTogether_;
  std::uint32_t dispatches = split ? push.sampleCount : 1u;
  for (std::uint32_t k = 0; k < dispatches; ++k) {
    gpu::PushConstants one = push;
    if (split) {
      one.sampleBase = push.sampleBase + k;
      one.sampleCount = 1;
      if (k > 0) {
        one.flags |= gpu::kFlagAccumulate;
        orderShaderWrites(cmd);
      }
    }
    for (const RowRun& run : runs) {
      // The runs' rows are disjoint, but each kernel writes the image through one descriptor
      // (kBindingImageOut) and reads it through another (kBindingImage), which the validation
      // layer's synchronization checks see as one range (on lavapipe dispatches run one after
      // another anyway).
      if (&run != &runs.front()) orderShaderWrites(cmd);
      one.tileOrigin = glm::uvec2(push.tileOrigin.x, run.row0);
      one.tileSize = glm::uvec2(push.tileSize.x, run.rows);
      one.param = spreadStride((run.rows + gpu::kWorkgroupSizeY - 1) / gpu::kWorkgroupSizeY);
      cmd.bindPipeline(vk::PipelineBindPoint::eCompute, (run.empty ? *fill : pipeline).handle());
      cmd.pushConstants<gpu::PushConstants>(*pipelineLayout_, vk::ShaderStageFlagBits::eCompute, 0, one);
      // Round up: the last partial workgroup covers the remaining pixels, the shader bounds-checks.
      cmd.dispatch((one.tileSize.x + gpu::kWorkgroupSizeX - 1) / gpu::kWorkgroupSizeX,
                   (one.tileSize.y + gpu::kWorkgroupSizeY - 1) / gpu::kWorkgroupSizeY, 1);
    }
  }
  if (timer) timer->stop(cmd);
  return culled;
}

RayStats Renderer::readStatsAndReset() {
  gpu::RayStats raw{};
  stats_->read(&raw, sizeof raw);
  gpu::RayStats zero{};
  stats_->write(&zero, sizeof zero);
  return RayStats::fromGpu(raw);
}

vk::Buffer Renderer::imageBuffer() const {
  return image_ ? image_->handle() : vk::Buffer();
}

vk::BufferView Renderer::imageTexelView() const {
  return image_ ? image_->texelView() : vk::BufferView();
}

Image Renderer::readImage() const {
  Image img(frameWidth_, frameHeight_);
  readBandImage(*image_, 0, frameHeight_, img);
  return img;
}

std::vector<std::uint32_t> Renderer::readPixelRays() const {
  std::vector<std::uint32_t> rays(static_cast<std::size_t>(frameWidth_) * frameHeight_);
  if (pixelRays_->size() < rays.size() * sizeof(std::uint32_t)) throw Error("no rays per pixel were counted");
  pixelRays_->read(rays.data(), rays.size() * sizeof(std::uint32_t));
  return rays;
}

RayStats Renderer::takeStats() {
  return readStatsAndReset();
}

} // namespace vkray
