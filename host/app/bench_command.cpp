// `vkray bench`: measured figures, never pass/fail. Subcommands:
//   time SCENE...   median GPU trace time and rays/s of repeated renders in one process
#include <algorithm>
#include <cstdio>

#include "app/bench.h"
#include "render/renderer.h"
#include "scene/scene_loader.h"
#include "vk/context.h"

namespace vkray {

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

TimedRender timeRender(Renderer& renderer, const Scene& scene, const RenderSettings& settings,
                       const RenderOptions& options, int warmup, int runs) {
  TimedRender out;
  RenderOptions counted = options;
  counted.countStats = true;
  // One counted render for the ray statistics; timing runs without counters (they cost time).
  RenderResult stats = renderer.render(scene.camera, settings, counted);
  out.stats = stats.stats;
  out.image = std::move(stats.image);
  for (int i = 0; i < warmup; ++i) renderer.render(scene.camera, settings, options);
  std::vector<double> times;
  for (int i = 0; i < runs; ++i) times.push_back(renderer.render(scene.camera, settings, options).timings.traceMs);
  out.medianMs = median(times);
  out.minMs = *std::min_element(times.begin(), times.end());
  out.maxMs = *std::max_element(times.begin(), times.end());
  return out;
}

int runBenchTime(const BenchTimeArgs& args) {
  vulkan::ContextOptions ctxOptions;
  ctxOptions.device = args.device.device;
  ctxOptions.validation = args.device.validate;
  vulkan::Context context(ctxOptions);
  std::printf("device: %s (%s)\n", context.info().name.c_str(), context.info().driver.c_str());
  std::printf("%-28s %10s %10s %10s %12s %10s\n", "scene", "median ms", "min ms", "max ms", "rays", "Mrays/s");
  for (const auto& path : args.scenes) {
    Scene scene = loadScene(path);
    applyRenderFlags(args.render, scene.render);
    Renderer renderer(context, nullptr);
    renderer.setScene(scene);
    RenderOptions options;
    options.countStats = false;
    options.specialize = !args.noSpecialize;
    options.sceneMemory = args.sceneMemory == "uniform"   ? SceneMemory::Uniform
                          : args.sceneMemory == "storage" ? SceneMemory::Storage
                                                          : SceneMemory::Auto;
    TimedRender t = timeRender(renderer, scene, scene.render, options, 1, args.runs);
    std::printf("%-28s %10.2f %10.2f %10.2f %12llu %10.2f\n", path.filename().string().c_str(), t.medianMs, t.minMs,
                t.maxMs, static_cast<unsigned long long>(t.stats.total()),
                t.medianMs > 0 ? static_cast<double>(t.stats.total()) / (t.medianMs * 1e3) : 0.0);
  }
  return 0;
}

} // namespace vkray
