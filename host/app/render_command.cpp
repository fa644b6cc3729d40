// `vkray render`: load, analyse, build, render, write — in that order, as the design draws it.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <optional>

#include "app/commands.h"
#include "app/terminal.h"
#include "image/image_io.h"
#include "image/tile_io.h"
#include "render/aov.h"
#include "render/ray_tree.h"
#include "render/renderer.h"
#include "scene/animation.h"
#include "scene/features.h"
#include "scene/scene_fingerprint.h"
#include "scene/scene_loader.h"
#include "util/clock.h"
#include "util/error.h"
#include "vk/context.h"
#include "vk/host_pages.h"

namespace vkray {

namespace {

void printStat(const char* name, double ms) {
  std::printf("%s: %.2f ms\n", name, ms);
}

const char* const kNoDevice = "no Vulkan device found: install a Vulkan driver; for the CPU driver lavapipe: "
                              "apt-get install mesa-vulkan-drivers";

// The devices the installed drivers offer. A driver that finds no hardware (Mesa's Intel or
// Radeon driver on a machine without that GPU) fails vkEnumeratePhysicalDevices with
// VK_ERROR_INITIALIZATION_FAILED instead of listing nothing; both mean there is no device.
std::vector<vulkan::DeviceInfo> availableDevices() {
  try {
    auto devices = vulkan::Context::listDevices();
    if (devices.empty()) throw DeviceError(kNoDevice);
    return devices;
  } catch (const vk::InitializationFailedError&) {
    throw DeviceError(kNoDevice);
  } catch (const vk::SystemError& e) {
    throw DeviceError(std::string("listing Vulkan devices: ") + e.what());
  }
}

// The context, or, when creating it failed because no device exists at all, that said plainly.
vulkan::Context openContext(const vulkan::ContextOptions& options) {
  try {
    return vulkan::Context(options);
  } catch (const DeviceError&) {
    availableDevices(); // throws kNoDevice when that is the cause
    throw;
  }
}

// The frames a render covers: --frame N, --frames A-B, or frame 0.
struct FrameRange {
  int first = 0;
  int last = 0;
  bool given = false; // -o is then a pattern
};

int parseFrameNumber(const std::string& text, const std::string& flag, const std::string& whole) {
  if (text.empty() || text.size() > 9 || text.find_first_not_of("0123456789") != std::string::npos) {
    throw InputError(flag, "expected A-B with whole frame numbers >= 0, got '" + whole + "'");
  }
  return std::atoi(text.c_str());
}

FrameRange frameRange(const RenderArgs& args, int frames) {
  FrameRange r;
  std::string flag;
  if (args.frame) {
    r.first = r.last = *args.frame;
    r.given = true;
    flag = "--frame " + std::to_string(*args.frame);
    if (*args.frame < 0) throw InputError(flag, "frames are numbered from 0");
  } else if (!args.frames.empty()) {
    flag = "--frames " + args.frames;
    auto dash = args.frames.find('-');
    if (dash == std::string::npos) throw InputError("--frames", "expected A-B, got '" + args.frames + "'");
    r.first = parseFrameNumber(args.frames.substr(0, dash), "--frames", args.frames);
    r.last = parseFrameNumber(args.frames.substr(dash + 1), "--frames", args.frames);
    r.given = true;
    if (r.last < r.first)
      throw InputError(flag,
                       "the range runs backwards (" + std::to_string(r.last) + " < " + std::to_string(r.first) + ")");
  }
  if (r.last >= frames) {
    throw InputError(flag, frames == 1 ? "the scene has no animation: its one frame is 0"
                                       : "the animation has frames 0-" + std::to_string(frames - 1));
  }
  return r;
}

// The output file of one frame: the pattern's one printf-style %d / %0Nd conversion replaced by the
// frame number ("%%" is a literal %).
std::filesystem::path framePath(const std::string& pattern, int frame, bool& hasConversion) {
  std::string out;
  int conversions = 0;
  for (std::size_t i = 0; i < pattern.size(); ++i) {
    if (pattern[i] != '%') {
      out += pattern[i];
      continue;
    }
    if (i + 1 < pattern.size() && pattern[i + 1] == '%') {
      out += '%';
      ++i;
      continue;
    }
    std::size_t j = i + 1;
    bool zero = j < pattern.size() && pattern[j] == '0';
    std::size_t digits = j;
    while (digits < pattern.size() && std::isdigit(static_cast<unsigned char>(pattern[digits]))) ++digits;
    if (digits >= pattern.size() || pattern[digits] != 'd' || digits - j > 2) {
      throw InputError("-o " + pattern, "a frame number pattern is %d or %0Nd (as out_%04d.png), and %% a literal %");
    }
    int width = digits > j ? std::atoi(pattern.substr(j, digits - j).c_str()) : 0;
    std::string number = std::to_string(frame);
    if (static_cast<int>(number.size()) < width) number.insert(0, width - number.size(), zero ? '0' : ' ');
    out += number;
    ++conversions;
    i = digits;
  }
  if (conversions > 1) throw InputError("-o " + pattern, "has more than one frame number pattern");
  hasConversion = conversions == 1;
  return out;
}

// Band I of N from "--tile I/N".
struct TileRequest {
  std::uint32_t index = 0;
  std::uint32_t count = 0;
};

std::optional<TileRequest> tileRequest(const RenderArgs& args, const RenderSettings& settings) {
  if (args.tile.empty()) return std::nullopt;
  const std::string flag = "--tile " + args.tile;
  auto slash = args.tile.find('/');
  auto number = [&](const std::string& t) {
    if (t.empty() || t.size() > 6 || t.find_first_not_of("0123456789") != std::string::npos) {
      throw InputError(flag, "expected I/N with whole numbers, band I of N (I from 1)");
    }
    return static_cast<std::uint32_t>(std::atoi(t.c_str()));
  };
  if (slash == std::string::npos) throw InputError(flag, "expected I/N, band I of N (I from 1)");
  TileRequest t{number(args.tile.substr(0, slash)), number(args.tile.substr(slash + 1))};
  if (t.count == 0) throw InputError(flag, "N must be at least 1");
  if (t.index < 1 || t.index > t.count) {
    throw InputError(flag, "the band must be 1 to " + std::to_string(t.count) + ", got " + std::to_string(t.index));
  }
  if (t.count > settings.height) {
    throw InputError(flag, std::to_string(t.count) + " bands are more than the image's " +
                               std::to_string(settings.height) + " rows");
  }
  if (imageFormatFor(args.output) != ImageFormat::Pfm) {
    throw InputError("-o " + args.output.string(), "a tile is written as .pfm (linear float), for 'vkray merge'");
  }
  return t;
}

// The AOVs asked for, checked before any work: each names a layer of an EXR of the whole image.
std::vector<Aov> requestedAovs(const RenderArgs& args) {
  if (!args.aov) return {};
  std::vector<Aov> aovs = parseAovList(*args.aov);
  // A tile is a .pfm band for `vkray merge`, which carries RGB alone.
  if (!args.tile.empty()) {
    throw InputError("--aov", "tiles (--tile) are .pfm files, which hold no layers: render the whole image to "
                              "an .exr for AOVs");
  }
  if (imageFormatFor(args.output) != ImageFormat::Exr) {
    throw InputError("--aov", "the output '" + args.output.string() +
                                  "' is not an .exr file (PNG and PFM hold RGB alone, not layers)");
  }
  return aovs;
}

// --exr-half says how an EXR stores its channels: with another format it is a mistake, not a no-op.
void checkExrHalf(bool exrHalf, const std::filesystem::path& output) {
  if (exrHalf && imageFormatFor(output) != ImageFormat::Exr) {
    throw InputError("--exr-half", "the output '" + output.string() + "' is not an .exr file");
  }
}

void printStats(const RenderArgs& args, const Scene& scene, const vulkan::Context& context,
                const vulkan::PipelineCache* cache, Renderer& renderer, const RenderResult& result, double loadMs,
                double writeMs, Clock::time_point t0) {
  const auto& info = context.info();
  const auto& s = result.stats;
  std::printf("scene: %s\n", args.scene.string().c_str());
  std::printf("device: %s (%s)\n", info.name.c_str(), info.driver.c_str());
  std::printf("image: %ux%u\n", scene.render.width, scene.render.height);
  const ProgressiveSummary& prog = result.progressive;
  const ForwardSummary& fwd = result.forward;
  if (scene.render.method == Method::Forward) {
    // Forward tracing: how many photons the lights emitted and how few of them the lens caught.
    std::printf("method: forward\n");
    if (scene.render.timeLimit > 0.0) std::printf("time limit: %g s\n", scene.render.timeLimit);
    std::printf("lights: %u\n", fwd.lights);
    std::printf("photons per light: %llu\n", static_cast<unsigned long long>(fwd.photonsPerLight));
    std::printf("photons emitted: %llu\n", static_cast<unsigned long long>(fwd.emitted));
    std::printf("photons struck: %llu\n", static_cast<unsigned long long>(fwd.struck));
    std::printf("struck fraction: %.3g\n", fwd.struckFraction());
    std::printf("photon batches: %d\n", fwd.batches);
    std::printf("aperture: %g\n", scene.camera.aperture);
  } else if (prog.passes > 0) {
    // Progressive: what the noise threshold or time limit reached (host/render/adaptive.h).
    if (scene.render.noiseThreshold > 0.0) std::printf("noise threshold: %g\n", scene.render.noiseThreshold);
    if (scene.render.timeLimit > 0.0) std::printf("time limit: %g s\n", scene.render.timeLimit);
    std::printf("spp: mean %.1f, max %.0f (min %d, cap %d)\n", prog.sppMean, prog.sppMax, scene.render.minSpp,
                scene.render.maxSpp);
    std::printf("passes: %d\n", prog.passes);
    std::printf("error estimate: mean %.3g, p95 %.3g\n", prog.errorMean, prog.errorP95);
    if (scene.render.noiseThreshold > 0.0) std::printf("converged pixels: %.1f %%\n", 100.0 * prog.converged);
  } else {
    std::printf("spp: %d\n", scene.render.spp);
  }
  if (scene.render.method != Method::Forward && (scene.render.spp > 1 || prog.passes > 0)) {
    // Where the driver cuts long loops (Mesa 22's llvmpipe), each sample gets a dispatch of its own.
    if (renderer.samplesTogether()) {
      std::printf("dispatches: one per band or pass for all its samples (the driver runs loops to their end)\n");
    } else if (std::uint32_t limit = renderer.driverLoopLimit(); limit > 0) {
      std::printf("dispatches: one per sample (the driver ends an invocation's loops after %u turns)\n", limit);
    }
  }
  std::printf("max depth: %d\n", scene.render.maxDepth);
  if (scene.render.seed != 0) std::printf("seed: %u\n", scene.render.seed);
  if (!args.explain) { // --explain printed the same lines above
    for (const auto& line : result.features.explain()) std::printf("%s\n", line.c_str());
  }
  std::printf("scene memory: %s\n", renderer.usesUniformScene() ? "uniform buffers"
                                    : renderer.usesUniformShading()
                                        ? "materials, lights, planes uniform; primitives in storage and texel buffers"
                                        : "storage and texel buffers");
  printStat("load", loadMs);
  for (const MeshInfo& m : scene.meshes) {
    Bounds b = meshBounds(scene, m);
    std::printf("mesh %s: %zu triangles, %zu degenerate dropped, bounds [%g, %g, %g] to [%g, %g, %g]\n", m.file.c_str(),
                m.triangleCount, m.droppedDegenerate, b.lo.x, b.lo.y, b.lo.z, b.hi.x, b.hi.y, b.hi.z);
  }
  if (renderer.gpuScene().bvh.stats.nodes > 0) {
    const auto& b = renderer.gpuScene().bvh.stats;
    printStat("bvh build", b.buildMs);
    std::printf("bvh nodes: %zu\n", b.nodes);
    std::printf("bvh depth: %d\n", b.depth);
    const GpuScene& g = renderer.gpuScene();
    std::printf("bvh bytes: %zu\n", g.bvhBytes());
    if (!g.triangles.empty()) {
      std::printf("bytes per triangle: %.1f\n", static_cast<double>(g.meshBytes()) / g.triangles.size());
    }
    if (!g.shadowEntries.empty()) {
      std::printf("shadow entry points: built in %.2f ms, %.1f MiB (%zu triangles x %zu lights)", g.shadowEntryMs,
                  g.shadowEntries.size() * sizeof(glm::uvec4) / 1048576.0, g.triangles.size(), g.lights.size());
      if (g.shadowNothingBetween)
        std::printf(", nothing between in %zu pairs\n", g.shadowNothingPairs);
      else
        std::printf(", nothing between: %s\n", renderer.shadowNothingSkipped().c_str());
    } else if (!renderer.shadowEntriesSkipped().empty()) {
      std::printf("shadow entry points: %s\n", renderer.shadowEntriesSkipped().c_str());
    }
  }
  HostPageUse pages = renderer.sceneHostPages();
  if (pages.bytes > 0) {
    std::printf("scene buffers in vkray's pages: %.1f MiB, %.1f MiB of them on huge pages\n", pages.bytes / 1048576.0,
                pages.hugeBytes / 1048576.0);
  }
  printStat("upload", renderer.uploadMs());
  printStat("pipeline", result.timings.pipelineMs);
  // What each pipeline cost to create (specialize and compile); they build side by side.
  for (const PipelineBuild& p : result.timings.pipelinesBuilt) {
    std::printf("pipeline %s: %.2f ms (SPIR-V %.0f KiB", p.name.c_str(), p.ms, p.spirvBytes / 1024.0);
    if (p.foldMs > 0 && p.foldKept) std::printf(", folded SPIR-V read back in %.2f ms", p.foldMs);
    if (p.foldMs > 0 && !p.foldKept) std::printf(", specialization folded in %.2f ms", p.foldMs);
    if (p.firstDispatchMs > 0) std::printf(", first dispatch %.2f ms", p.firstDispatchMs);
    std::printf(")\n");
  }
  if (!cache) {
    std::printf("pipeline cache: off\n");
  } else if (std::size_t kept = cache->keptBytes(); kept == 0) {
    // The driver accepts the cache but stores nothing in it. lavapipe is such a driver: Mesa's own
    // on-disk shader cache keeps its machine code instead (each pipeline's first dispatch).
    std::printf("pipeline cache: 0 bytes kept by the driver (it keeps nothing in a VkPipelineCache)\n");
  } else {
    std::printf("pipeline cache: %zu bytes kept by the driver, %s\n", kept,
                cache->loadedFromDisk() ? "loaded from disk" : "empty before this run (first run on this device)");
  }
  printStat("trace", result.timings.traceMs);
  printStat("trace wall", result.timings.traceWallMs);
  std::printf("bands: %d\n", result.timings.bands);
  // Rows whose eye rays provably miss everything, filled with the background instead of traced.
  std::printf("culled rows: %u of %u\n", result.timings.culledRows, scene.render.height);
  printStat("readback", result.timings.readbackMs);
  if (result.progressive.passes > 0) printStat("decisions", result.timings.decideMs);
  printStat("write", writeMs);
  printStat("total", msSince(t0));
  if (scene.render.method == Method::Forward) {
    if (fwd.nonFinite > 0)
      std::printf("non-finite contributions: %llu\n", static_cast<unsigned long long>(fwd.nonFinite));
  } else {
    for (const auto& [name, value] : s.named()) {
      std::printf("%.*s: %llu\n", static_cast<int>(name.size()), name.data(), static_cast<unsigned long long>(value));
    }
  }
  const std::uint64_t rays = scene.render.method == Method::Forward ? fwd.rays : s.total();
  std::printf("rays: %llu\n", static_cast<unsigned long long>(rays));
  double seconds = result.timings.traceMs * 1e-3;
  double rps = seconds > 0 ? static_cast<double>(rays) / seconds : 0.0;
  std::printf("rays per second: %.0f\n", rps);
  std::printf("mrays/s: %.2f\n", rps * 1e-6);
}

} // namespace

int runRender(const RenderArgs& args) {
  auto t0 = Clock::now();
  Scene scene = loadScene(args.scene, modelSceneOptions(args.model, args.scene));
  applyRenderFlags(args.render, scene.render);
  refitCamera(scene); // a fitted camera frames the image as the flags shaped it
  double loadMs = msSince(t0);
  const FrameRange frames = frameRange(args, frameCount(scene));
  const std::vector<Aov> aovs = requestedAovs(args);
  const std::optional<TileRequest> tile = tileRequest(args, scene.render);
  checkExrHalf(args.exrHalf, args.output);
  // --inspect X,Y: the pixel's ray tree; with -o the image is rendered and written too.
  std::optional<glm::uvec2> inspected;
  if (args.inspect) {
    inspected = parsePixel(*args.inspect, scene.render.width, scene.render.height, "--inspect");
    if (frames.last > frames.first) throw InputError("--inspect", "inspects one frame: give --frame N, not --frames");
    if (scene.render.method == Method::Forward) {
      throw InputError("--inspect", "shows a pixel's backward ray tree; this render is --method forward");
    }
    if (tile) throw InputError("--inspect", "inspects a pixel of the whole image, not of a --tile");
    if (args.stats && args.inspectOutput.empty()) {
      throw InputError("--inspect", "prints its JSON on standard output, where --stats prints too: give "
                                    "--inspect-out FILE");
    }
    if (!args.inspectOutput.empty() && args.inspectOutput.parent_path() != "" &&
        !std::filesystem::is_directory(args.inspectOutput.parent_path())) {
      throw InputError("--inspect-out " + args.inspectOutput.string(),
                       "directory '" + args.inspectOutput.parent_path().string() + "' does not exist");
    }
  } else if (!args.inspectOutput.empty()) {
    throw InputError("--inspect-out", "needs --inspect X,Y");
  }
  if (args.output.empty() && !inspected) throw InputError("-o", "an output image is required (.png, .pfm or .exr)");
  const bool writesImage = !args.output.empty();
  // Every output checked, and a range given a pattern, before any time on the GPU.
  std::vector<std::filesystem::path> outputs;
  for (int f = frames.first; writesImage && f <= frames.last; ++f) {
    bool pattern = false;
    outputs.push_back(frames.given ? framePath(args.output.string(), f, pattern) : args.output);
    if (frames.last > frames.first && !pattern) {
      throw InputError("-o " + args.output.string(),
                       "renders frames " + std::to_string(frames.first) + "-" + std::to_string(frames.last) +
                           ": name them with a frame number pattern such as out_%04d.png");
    }
    checkOutputPath(outputs.back());
  }

  // A static scene is analysed once, here. An animated one is analysed per frame below (what moves
  // changes which planes can occlude), so its base scene only for --explain.
  std::optional<Features> features;
  if (!scene.animation || args.explain) features = analyzeScene(scene, scene.render);
  if (args.explain) {
    const std::string amount = scene.render.method == Method::Forward
                                   ? (scene.render.photons > 0     ? std::to_string(scene.render.photons)
                                      : scene.render.timeLimit > 0 ? std::string("as many")
                                                                   : std::to_string(RenderSettings::kDefaultPhotons)) +
                                         " photons per light"
                                   : std::to_string(scene.render.spp) + " spp";
    std::printf("%s, %ux%u, max_depth %d, %s:\n", args.scene.string().c_str(), scene.render.width, scene.render.height,
                scene.render.maxDepth, amount.c_str());
    for (const auto& line : features->explain()) std::printf("  %s\n", line.c_str());
    std::fflush(stdout);
  }

  vulkan::Context context = openContext(contextOptions(args.device));
  std::unique_ptr<vulkan::PipelineCache> cache;
  if (!args.device.noPipelineCache) {
    cache = std::make_unique<vulkan::PipelineCache>(context, vulkan::PipelineCache::defaultFile(context));
  }

  // One renderer for every frame: pipelines are built once and reused while the features agree.
  Renderer renderer(context, cache.get());
  const auto& interrupted = installInterruptFlag();
  RenderOptions options;
  applyKernelFlags(args.kernel, options);
  options.countStats = args.stats;
  options.bandBudgetMs = args.bandMs;
  options.cancel = &interrupted;
  options.pixelStats = needsPixelStats(aovs);
  // The rays layer is the kernel's ray counters, per pixel.
  if (std::find(aovs.begin(), aovs.end(), Aov::Rays) != aovs.end()) options.countStats = true;
  TileInfo tileInfo;
  if (tile) {
    tileRows(scene.render.height, tile->index, tile->count, tileInfo.rowBegin, tileInfo.rowEnd);
    options.rowBegin = tileInfo.rowBegin;
    options.rowEnd = tileInfo.rowEnd;
    tileInfo.width = scene.render.width;
    tileInfo.height = scene.render.height;
    tileInfo.scene = args.scene.string();
  }

  for (int f = frames.first; f <= frames.last; ++f) {
    const Scene frameScene = scene.animation ? sceneAtFrame(scene, *scene.animation, f) : scene;
    // A static scene's features are the ones analysed above; an animated frame's are its own.
    renderer.setScene(frameScene, scene.animation ? analyzeScene(frameScene, frameScene.render) : *features);
    if (inspected) {
      RayTree tree = renderer.inspect(frameScene.camera, frameScene.render, options, *inspected);
      if (context.validationEnabled() && context.validationMessageCount() > 0) {
        throw DeviceError("the validation layer reported " + std::to_string(context.validationMessageCount()) +
                          " message(s) while inspecting; no output written");
      }
      const std::string json = rayTreeJson(tree, frameScene) + "\n";
      if (args.inspectOutput.empty()) {
        std::fputs(json.c_str(), stdout);
        std::fflush(stdout);
      } else {
        writeFileAtomic(args.inspectOutput, std::vector<std::uint8_t>(json.begin(), json.end()));
      }
      if (!writesImage) return 0;
    }
    ProgressBar bar(!args.quiet);
    options.progress = [&](const RenderProgress& p) { bar.update(p); };
    RenderResult result = renderer.render(frameScene.camera, frameScene.render, options);
    bar.finish();
    ImageWriteOptions write{args.exrHalf, {}};
    if (!aovs.empty()) {
      checkPixelStats(aovs, result.pixels); // before the first-hit pass's time
      std::vector<FirstHit> firstHits;
      if (needsFirstHits(aovs)) {
        // The pixel-centre eye rays' first hits: one short pass on the same scene buffers.
        RenderOptions firstHitPass = options;
        firstHitPass.kernel = Kernel::Aov;
        firstHitPass.pixelStats = false;
        firstHitPass.progress = nullptr;
        firstHits = renderer.render(frameScene.camera, frameScene.render, firstHitPass).firstHits;
      }
      write.exrLayers = aovChannels(aovs, firstHits, result.pixels, result.image.pixels.size());
    }

    if (context.validationEnabled() && context.validationMessageCount() > 0) {
      throw DeviceError("the validation layer reported " + std::to_string(context.validationMessageCount()) +
                        " message(s); no output written");
    }
    if (result.stats.nonFinite > 0) {
      std::fprintf(stderr, "vkray: warning: %llu samples were NaN/Inf and were replaced by black\n",
                   static_cast<unsigned long long>(result.stats.nonFinite));
    }
    if (result.stats.truncated > 0) {
      std::fprintf(stderr,
                   "vkray: warning: %llu samples were cut short: their ray tree reached %u rays (or the driver's "
                   "loop limit): raise render.bailout or lower max_depth\n",
                   static_cast<unsigned long long>(result.stats.truncated), gpu::kMaxTreeRays);
    }

    auto tw = Clock::now();
    const std::filesystem::path& output = outputs[static_cast<std::size_t>(f - frames.first)];
    if (tile) {
      tileInfo.frame = f;
      tileInfo.fingerprint = sceneFingerprint(frameScene, f);
      writeTile(output, result.image, tileInfo);
    } else {
      writeImage(output, result.image, write);
    }
    double writeMs = msSince(tw);
    if (args.stats) {
      if (frames.given) std::printf("frame: %d\n", f);
      printStats(args, frameScene, context, cache.get(), renderer, result, loadMs, writeMs, t0);
    }
  }
  return 0;
}

int runMerge(const MergeArgs& args) {
  checkOutputPath(args.output);
  checkExrHalf(args.exrHalf, args.output);
  writeImage(args.output, mergeTiles(args.tiles), ImageWriteOptions{args.exrHalf, {}});
  return 0;
}

int runInfo(const DeviceFlags& flags) {
  auto devices = availableDevices();
  for (const auto& d : devices) {
    std::printf("device %u: %s\n", d.index, d.name.c_str());
    std::printf("  type: %s\n", d.type.c_str());
    std::printf("  driver: %s\n", d.driver.c_str());
    std::printf("  vulkan: %u.%u.%u\n", VK_API_VERSION_MAJOR(d.apiVersion), VK_API_VERSION_MINOR(d.apiVersion),
                VK_API_VERSION_PATCH(d.apiVersion));
    std::printf("  shaderFloat64: %s (float64 reference kernel)\n", d.shaderFloat64 ? "yes" : "no");
    std::printf("  timestamps: %s (GPU trace time)\n", d.timestamps ? "yes" : "no");
    std::printf("  subgroups: %u lanes; basic, arithmetic, ballot and shuffle in compute shaders: %s\n", d.subgroupSize,
                d.subgroupMissing.empty()
                    ? "yes (the BVH walk's lockstep, the ray counters, lanes sharing a pixel)"
                    : ("no, lacks " + d.subgroupMissing + " (vkray cannot use this device)").c_str());
    std::printf("  maxStorageBufferRange: %llu MiB (largest sphere, plane, polygon or material array)\n",
                static_cast<unsigned long long>(d.maxStorageBufferRange >> 20));
    std::printf(
        "  maxTexelBufferElements: %llu (texels of the triangle, normal and BVH arrays; pixels per image band)\n",
        static_cast<unsigned long long>(d.maxTexelBufferElements));
    std::printf("  maxMemoryAllocationSize: %llu MiB\n",
                static_cast<unsigned long long>(d.maxMemoryAllocationSize >> 20));
    if (d.hostImportAlignment != 0) {
      std::printf("  VK_EXT_external_memory_host: yes (scene buffers of 4 MiB or more in vkray's own pages, advised "
                  "for huge pages; this machine's transparent huge pages: %s)\n",
                  vulkan::transparentHugePages().c_str());
    } else {
      std::printf("  VK_EXT_external_memory_host: %s\n", d.type == "CPU" ? "no (scene buffers in the driver's memory)"
                                                                         : "not used (GPU memory is the driver's)");
    }
  }
  if (!flags.device.empty()) {
    vulkan::Context context = openContext(contextOptions(flags));
    std::printf("selected: %s\n", context.info().name.c_str());
  }
  return 0;
}

} // namespace vkray
