// Benchmark helpers shared by the `vkray bench` subcommands.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "app/cli_options.h"
#include "image/image.h"
#include "render/renderer.h"

namespace vkray {

struct BenchTimeArgs {
  std::vector<std::filesystem::path> scenes;
  DeviceFlags device;
  RenderFlags render;
  int runs = 7;
  bool noSpecialize = false;
  std::string sceneMemory = "auto";
};

struct TimedRender {
  double medianMs = 0.0; // GPU trace time (timestamps), median of the timed runs
  double minMs = 0.0;
  double maxMs = 0.0;
  RayStats stats; // from one extra run with counters on
  Image image;
};

double median(std::vector<double> v);

// One counted render (statistics and image), `warmup` untimed renders, then `runs` timed ones.
TimedRender timeRender(Renderer& renderer, const Scene& scene, const RenderSettings& settings,
                       const RenderOptions& options, int warmup, int runs);

int runBenchTime(const BenchTimeArgs& args);

} // namespace vkray
