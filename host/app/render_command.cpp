// `vkray render`: load, analyse, build, render, write — in that order, as the design draws it.
#include <chrono>
#include <cstdio>

#include "app/commands.h"
#include "app/terminal.h"
#include "image/image_io.h"
#include "render/renderer.h"
#include "scene/features.h"
#include "scene/scene_loader.h"
#include "util/error.h"
#include "vk/context.h"
#include "vk/host_pages.h"

namespace vkray {

namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

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

} // namespace

int runRender(const RenderArgs& args) {
  auto t0 = Clock::now();
  Scene scene = loadScene(args.scene, modelSceneOptions(args.model, args.scene));
  applyRenderFlags(args.render, scene.render);
  refitCamera(scene); // a fitted camera frames the image as the flags shaped it
  double loadMs = msSince(t0);
  // Fail on an unwritable output before spending any time on the GPU.
  checkOutputPath(args.output);

  Features features = analyzeScene(scene, scene.render);
  if (args.explain) {
    std::printf("%s, %ux%u, max_depth %d, %d spp:\n", args.scene.string().c_str(), scene.render.width,
                scene.render.height, scene.render.maxDepth, scene.render.spp);
    for (const auto& line : features.explain()) std::printf("  %s\n", line.c_str());
    std::fflush(stdout);
  }

  vulkan::Context context = openContext(contextOptions(args.device));
  std::unique_ptr<vulkan::PipelineCache> cache;
  if (!args.device.noPipelineCache) {
    cache = std::make_unique<vulkan::PipelineCache>(context, vulkan::PipelineCache::defaultFile(context));
  }

  Renderer renderer(context, cache.get());
  renderer.setScene(scene);

  const auto& interrupted = installInterruptFlag();
  ProgressBar bar(!args.quiet);
  RenderOptions options;
  options.specialize = !args.noSpecialize;
  options.cullRows = !args.noRowCulling;
  options.entryPoints = !args.noEntryPoints;
  options.countStats = args.stats;
  options.bandBudgetMs = args.bandMs;
  options.sceneMemory = args.sceneMemory == "uniform"   ? SceneMemory::Uniform
                        : args.sceneMemory == "storage" ? SceneMemory::Storage
                                                        : SceneMemory::Auto;
  options.cancel = &interrupted;
  options.progress = [&](const RenderProgress& p) { bar.update(p); };
  RenderResult result = renderer.render(scene.camera, scene.render, options);
  bar.finish();

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
                 "vkray: warning: %llu samples were cut short by the driver's loop limit (llvmpipe stops a "
                 "shader after 65535 loop iterations): raise render.bailout or lower max_depth\n",
                 static_cast<unsigned long long>(result.stats.truncated));
  }

  auto tw = Clock::now();
  writeImage(args.output, result.image);
  double writeMs = msSince(tw);

  if (args.stats) {
    const auto& info = context.info();
    const auto& s = result.stats;
    std::printf("scene: %s\n", args.scene.string().c_str());
    std::printf("device: %s (%s)\n", info.name.c_str(), info.driver.c_str());
    std::printf("image: %ux%u\n", scene.render.width, scene.render.height);
    std::printf("spp: %d\n", scene.render.spp);
    std::printf("max depth: %d\n", scene.render.maxDepth);
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
      std::printf("mesh %s: %zu triangles, %zu degenerate dropped, bounds [%g, %g, %g] to [%g, %g, %g]\n",
                  m.file.c_str(), m.triangleCount, m.droppedDegenerate, b.lo.x, b.lo.y, b.lo.z, b.hi.x, b.hi.y, b.hi.z);
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
    }
    Renderer::HostPageUse pages = renderer.sceneHostPages();
    if (pages.bytes > 0) {
      std::printf("scene buffers in vkray's pages: %.1f MiB, %.1f MiB of them on huge pages\n", pages.bytes / 1048576.0,
                  pages.hugeBytes / 1048576.0);
    }
    printStat("upload", renderer.uploadMs());
    printStat("pipeline", result.timings.pipelineMs);
    if (!cache) {
      std::printf("pipeline cache: off\n");
    } else if (std::size_t kept = cache->keptBytes(); kept == 0) {
      // The driver accepts the cache but stores nothing in it: every run compiles the kernel anew.
      std::printf("pipeline cache: 0 bytes kept by the driver (it recompiles every run)\n");
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
    printStat("write", writeMs);
    printStat("total", msSince(t0));
    std::printf("eye rays: %llu\n", static_cast<unsigned long long>(s.eye));
    std::printf("shadow rays: %llu\n", static_cast<unsigned long long>(s.shadow));
    std::printf("reflection rays: %llu\n", static_cast<unsigned long long>(s.reflection));
    std::printf("refraction rays: %llu\n", static_cast<unsigned long long>(s.refraction));
    std::printf("rays: %llu\n", static_cast<unsigned long long>(s.total()));
    std::printf("bailout saved: %llu\n", static_cast<unsigned long long>(s.bailoutSaved));
    std::printf("stack overflow: %llu\n", static_cast<unsigned long long>(s.stackOverflow));
    std::printf("truncated samples: %llu\n", static_cast<unsigned long long>(s.truncated));
    std::printf("refined pixels: %llu\n", static_cast<unsigned long long>(s.refinedPixels));
    std::printf("deepest bounce: %u\n", s.maxDepth);
    double seconds = result.timings.traceMs * 1e-3;
    double rps = seconds > 0 ? static_cast<double>(s.total()) / seconds : 0.0;
    std::printf("rays per second: %.0f\n", rps);
    std::printf("mrays/s: %.2f\n", rps * 1e-6);
  }
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
    std::printf("  subgroups: %u lanes; basic, arithmetic and ballot in compute shaders: %s\n", d.subgroupSize,
                d.subgroupMissing.empty()
                    ? "yes (the BVH walk's lockstep, the ray counters)"
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
    vulkan::ContextOptions options;
    options.device = flags.device;
    vulkan::Context context = openContext(options);
    std::printf("selected: %s\n", context.info().name.c_str());
  }
  return 0;
}

} // namespace vkray
