// Forward tracing: the Renderer's photon passes (shaders/forward.comp; renderer.h, renderForward).
#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>

#include "render/renderer.h"
#include "scene/scene_limits.h"
#include "util/clock.h"
#include "util/error.h"

namespace vkray {

namespace {

// Photons per workgroup (the kernel's 8 x 8 invocations, one photon each), and the most one
// dispatch may hold (65535 workgroups, the least maxComputeWorkGroupCount[0] a device may have).
constexpr std::uint64_t kGroupPhotons = gpu::kWorkgroupSizeX * gpu::kWorkgroupSizeY;
constexpr std::uint64_t kMaxDispatchPhotons = 65535 * kGroupPhotons;
// The first batch, per light, before the renderer has measured how fast photons go.
constexpr std::uint64_t kFirstBatch = 1u << 15;

// What forward tracing cannot do, one clear line each.
void checkForward(const Camera& camera, const RenderSettings& s, const RenderOptions& o) {
  if (!(camera.aperture > 0.0)) {
    throw InputError("camera.aperture", "forward tracing collects the light that passes through the camera's lens, "
                                        "and a pinhole (aperture 0) lets none through: give camera.aperture > 0");
  }
  if (s.noiseThreshold > 0.0) {
    throw InputError("render.noise_threshold",
                     "applies to backward tracing; forward tracing stops at render.photons or render.time_limit");
  }
  if (s.precision == Precision::Float64) throw InputError("render.precision", "forward tracing is float32 only");
  if (o.rowBegin > 0 || (o.rowEnd > 0 && o.rowEnd < s.height)) {
    throw InputError("--tile", "forward tracing's photons land anywhere in the image: render it whole");
  }
  if (o.pixelStats) throw InputError("--aov", "per-pixel statistics are backward tracing's samples; forward has none");
}

} // namespace

RenderResult Renderer::renderForward(const Camera& camera, const RenderSettings& settings,
                                     const RenderOptions& options) {
  checkForward(camera, settings, options);
  RenderOptions o = options;
  o.kernel = Kernel::Forward;
  o.progressive = false;
  o.pixelStats = false;
  o.pixelRays = false;
  o.recordTree = false;
  o.entryPoints = false;
  o.cullRows = false;
  prepare(camera, settings, o);

  RenderResult result;
  result.features = current_;
  result.timings.pipelineMs = kernels_.buildMs;
  result.timings.pipelineReused = kernels_.buildMs == 0.0;
  result.timings.pipelinesBuilt = kernels_.built;

  const std::uint32_t width = settings.width;
  const std::uint32_t height = settings.height;
  const auto lights = static_cast<std::uint32_t>(gpuScene_.lights.size());
  ForwardSummary& summary = result.forward;
  summary.lights = lights;
  result.image = Image(width, height);
  if (lights == 0) return result; // no light, no photon: black, as backward minus ambient and background

  const std::uint64_t words = gpu::kPhotonHeaderWords + std::uint64_t(width) * height * 6;
  const vk::DeviceSize bytes = words * sizeof(std::uint32_t);
  if (photonImage_->size() < bytes) {
    photonImage_.reset();
    photonImage_ = std::make_unique<vulkan::Buffer>(context_, bytes, vk::BufferUsageFlagBits::eStorageBuffer,
                                                    vulkan::MemoryUse::DeviceLocal, "photon image");
    updateDescriptors();
  }

  const bool timeLimited = settings.timeLimit > 0.0;
  const std::uint64_t cap = settings.photons > 0 ? settings.photons
                            : timeLimited        ? static_cast<std::uint64_t>(kMaxPhotons)
                                                 : RenderSettings::kDefaultPhotons;
  // Every contribution is scaled by 1 / (the photons planned), so a pixel's sum stays near its value
  // times (photons emitted / planned): far inside the 64-bit sums whatever the count.
  const double planned = timeLimited && settings.photons == 0 ? double(1u << 24) : double(cap);
  const float scale = static_cast<float>(1.0 / planned);

  std::uint64_t done = 0; // photons per light so far
  std::uint64_t batch = std::min(cap, kFirstBatch);
  double photonsPerMs = 0.0; // per light, measured
  const double budgetMs = timeLimited ? settings.timeLimit * 1e3 : 0.0;
  auto start = Clock::now();
  while (done < cap) {
    if (options.cancel && options.cancel->load()) throw CancelledError("interrupted");
    if (photonsPerMs > 0.0) {
      // Size the batch to the band budget; with a time limit, stop before a batch would pass it.
      batch = static_cast<std::uint64_t>(std::max(1.0, photonsPerMs * options.bandBudgetMs));
      if (timeLimited) {
        double leftMs = budgetMs - result.timings.traceMs;
        if (leftMs <= 0.0) break;
        batch = std::min<std::uint64_t>(batch, static_cast<std::uint64_t>(photonsPerMs * leftMs));
        if (batch == 0) break;
      }
    }
    if (options.maxBatchPhotons > 0) batch = std::min(batch, options.maxBatchPhotons);
    batch = std::clamp<std::uint64_t>(batch, 1, std::min(kMaxDispatchPhotons, cap - done));
    const std::uint64_t first = done;
    const std::uint64_t count = batch;
    BandTimes t = submitBand(context_, timer_, "forward tracing", 0, height, [&](const vk::raii::CommandBuffer& cmd) {
      if (first == 0) {
        cmd.fillBuffer(photonImage_->handle(), 0, bytes, 0u);
        vk::MemoryBarrier cleared(vk::AccessFlagBits::eTransferWrite,
                                  vk::AccessFlagBits::eShaderRead | vk::AccessFlagBits::eShaderWrite);
        cmd.pipelineBarrier(vk::PipelineStageFlagBits::eTransfer, vk::PipelineStageFlagBits::eComputeShader, {},
                            cleared, {}, {});
      }
      cmd.bindDescriptorSets(vk::PipelineBindPoint::eCompute, *pipelineLayout_, 0, {*descriptorSet_}, {});
      cmd.bindPipeline(vk::PipelineBindPoint::eCompute, kernels_.sample->handle());
      timer_.start(cmd);
      for (std::uint32_t light = 0; light < lights; ++light) {
        gpu::PushConstants push{};
        push.tileOrigin = glm::uvec2(light, 0);
        push.sampleBase = static_cast<std::uint32_t>(first);
        push.sampleCount = static_cast<std::uint32_t>(count);
        push.param = std::bit_cast<std::uint32_t>(scale);
        cmd.pushConstants<gpu::PushConstants>(*pipelineLayout_, vk::ShaderStageFlagBits::eCompute, 0, push);
        cmd.dispatch(static_cast<std::uint32_t>((count + kGroupPhotons - 1) / kGroupPhotons), 1, 1);
      }
      timer_.stop(cmd);
    });
    done += count;
    summary.batches++;
    result.timings.traceMs += t.gpuMs;
    result.timings.traceWallMs += t.wallMs;
    result.timings.bands++;
    summary.lastBatchMs = t.gpuMs;
    double ms = t.gpuMs > 0.0 ? t.gpuMs : t.wallMs;
    if (ms > 0.0) photonsPerMs = static_cast<double>(count) / ms;
    if (options.progress) {
      RenderProgress p;
      p.elapsedMs = msSince(start);
      p.fraction = timeLimited && budgetMs > 0.0 && settings.photons == 0
                       ? std::min(1.0, result.timings.traceMs / budgetMs)
                       : static_cast<double>(done) / static_cast<double>(cap);
      p.remainingMs = p.fraction > 0 ? p.elapsedMs * (1.0 - p.fraction) / p.fraction : 0.0;
      options.progress(p);
    }
  }

  auto readStart = Clock::now();
  std::vector<std::uint32_t> sums(words);
  photonImage_->read(sums.data(), bytes);
  result.timings.readbackMs += msSince(readStart);
  auto wide = [&](std::uint64_t at) { return std::uint64_t(sums[at]) | (std::uint64_t(sums[at + 1]) << 32); };
  summary.photonsPerLight = done;
  summary.emitted = done * lights;
  summary.struck = wide(0);
  summary.rays = wide(2);
  summary.nonFinite = sums[4];
  // A pixel's value: its fixed-point sum over the scale and the photons each light emitted.
  const double toValue = std::ldexp(1.0, -static_cast<int>(gpu::kPhotonFixedBits)) / (double(scale) * double(done));
  for (std::size_t i = 0; i < result.image.pixels.size(); ++i) {
    std::uint64_t at = gpu::kPhotonHeaderWords + 6 * i;
    result.image.pixels[i] =
        glm::vec3(static_cast<float>(double(wide(at)) * toValue), static_cast<float>(double(wide(at + 2)) * toValue),
                  static_cast<float>(double(wide(at + 4)) * toValue));
  }
  readStatsAndReset();
  return result;
}

} // namespace vkray
