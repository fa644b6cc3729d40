// `vkray bench`: measured figures, never pass/fail. Subcommands:
//   time SCENE...   median GPU trace time and rays/s of repeated renders in one process
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "app/bench.h"
#include "render/renderer.h"
#include "scene/scene_loader.h"
#include "vk/context.h"

namespace vkray {

TimedRender timeRender(Renderer& renderer, const Scene& scene, const RenderSettings& settings,
                       const RenderOptions& options, int warmup, int runs) {
  TimedRender out;
  RenderOptions counted = options;
  counted.countStats = true;
  // One counted render for the ray statistics; timing runs without counters (they cost time).
  RenderResult stats = renderer.render(scene.camera, settings, counted);
  out.stats = stats.stats;
  out.image = std::move(stats.image);
  std::vector<double> times;
  for (int i = 0; i < warmup + runs; ++i) {
    RenderResult r = renderer.render(scene.camera, settings, options);
    if (i == 0) {
      for (const PipelineBuild& p : r.timings.pipelinesBuilt) {
        if (p.name.rfind("trace", 0) == 0 || p.name.rfind("hits", 0) == 0) out.compileMs += p.ms;
      }
    }
    if (i >= warmup) times.push_back(r.timings.traceMs);
  }
  out.medianMs = median(times);
  out.minMs = *std::min_element(times.begin(), times.end());
  out.maxMs = *std::max_element(times.begin(), times.end());
  return out;
}

int runBenchTime(const BenchTimeArgs& args) {
  vulkan::Context context(contextOptions(args.device));
  std::printf("device: %s (%s)\n", context.info().name.c_str(), context.info().driver.c_str());
  std::printf("%-28s %10s %10s %10s %12s %10s\n", "scene", "median ms", "min ms", "max ms", "rays", "Mrays/s");
  for (const auto& path : args.scenes) {
    Scene scene = loadScene(path);
    applyRenderFlags(args.render, scene.render);
    Renderer renderer(context, nullptr);
    renderer.setScene(scene);
    RenderOptions options;
    options.countStats = false;
    applyKernelFlags(args.kernel, options);
    TimedRender t = timeRender(renderer, scene, scene.render, options, 1, args.runs);
    std::printf("%-28s %10.2f %10.2f %10.2f %12llu %10.2f\n", path.filename().string().c_str(), t.medianMs, t.minMs,
                t.maxMs, static_cast<unsigned long long>(t.stats.total()),
                t.medianMs > 0 ? static_cast<double>(t.stats.total()) / (t.medianMs * 1e3) : 0.0);
  }
  return 0;
}

void scaleToHeight(RenderSettings& s, std::uint32_t height) {
  double aspect = static_cast<double>(s.width) / s.height;
  s.height = height;
  s.width = static_cast<std::uint32_t>(std::max(1.0, std::round(height * aspect)));
}

int runBenchSpecialize(const BenchSpecializeArgs& args) {
  std::vector<std::filesystem::path> scenes = args.scenes;
  if (scenes.empty()) {
    for (const auto& e : std::filesystem::directory_iterator(VKRAY_SCENES_DIR)) {
      if (e.path().extension() == ".json") scenes.push_back(e.path());
    }
    std::sort(scenes.begin(), scenes.end());
  }
  vulkan::Context context(contextOptions(args.device));
  std::printf("device: %s (%s); trace: median GPU time of %d runs after a warm-up; compile: creating the\n"
              "trace pipeline once (SPIR-V folding included; 'whole': the unfolded module and its constants)\n",
              context.info().name.c_str(), context.info().driver.c_str(), args.runs);
  std::printf("%-28s %9s %12s %12s %8s %12s | %11s %11s %11s %11s\n", "scene", "size", "special ms", "general ms",
              "ratio", "no-unroll ms", "compile ms", "no-unroll", "general", "whole");
  for (const auto& path : scenes) {
    Scene scene = loadScene(path);
    scaleToHeight(scene.render, args.height);
    Renderer renderer(context, nullptr);
    renderer.setScene(scene);
    RenderOptions special;
    special.countStats = false;
    RenderOptions general = special;
    general.specialize = false;
    RenderOptions rolled = special;
    rolled.unroll = false;
    RenderOptions whole = special;
    whole.foldSpirv = false;
    TimedRender a = timeRender(renderer, scene, scene.render, special, 1, args.runs);
    TimedRender b = timeRender(renderer, scene, scene.render, general, 1, args.runs);
    TimedRender c = timeRender(renderer, scene, scene.render, rolled, 1, args.runs);
    TimedRender w = timeRender(renderer, scene, scene.render, whole, 0, 1); // its compile time alone
    char size[32];
    std::snprintf(size, sizeof size, "%ux%u", scene.render.width, scene.render.height);
    std::printf("%-28s %9s %12.2f %12.2f %8.3f %12.2f | %11.0f %11.0f %11.0f %11.0f\n",
                path.filename().string().c_str(), size, a.medianMs, b.medianMs,
                b.medianMs > 0 ? a.medianMs / b.medianMs : 0.0, c.medianMs, a.compileMs, c.compileMs, b.compileMs,
                w.compileMs);
  }

  // An absent effect must cost nothing: the showcase with every mirror turned matte, at depth 10
  // and at depth 0.
  Scene matte = loadScene(std::filesystem::path(VKRAY_SCENES_DIR) / "showcase.json");
  for (Material& m : matte.materials) m.reflection = 0.0;
  scaleToHeight(matte.render, args.height);
  Renderer renderer(context, nullptr);
  renderer.setScene(matte);
  RenderOptions options;
  options.countStats = false;
  RenderSettings deep = matte.render;
  deep.maxDepth = 10;
  RenderSettings flat = matte.render;
  flat.maxDepth = 0;
  // Both settings build the same pipeline; the first series measured in a process runs slower on
  // lavapipe (measured: 1.07-1.15 with depth 10 first, 0.93-0.97 in separate processes), so each
  // is measured twice, interleaved, and the second series counts.
  TimedRender d10 = timeRender(renderer, matte, deep, options, 1, args.runs);
  TimedRender d0 = timeRender(renderer, matte, flat, options, 1, args.runs);
  d10 = timeRender(renderer, matte, deep, options, 1, args.runs);
  d0 = timeRender(renderer, matte, flat, options, 1, args.runs);
  std::printf(
      "\nshowcase without mirrors: max_depth 10 %.2f ms, max_depth 0 %.2f ms, ratio %.3f (reflection rays: %llu)\n",
      d10.medianMs, d0.medianMs, d0.medianMs > 0 ? d10.medianMs / d0.medianMs : 0.0,
      static_cast<unsigned long long>(d10.stats.reflection));
  return 0;
}

} // namespace vkray
