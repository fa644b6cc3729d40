// Benchmark helpers shared by the `vkray bench` subcommands.
#pragma once

#include <algorithm>
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
  KernelFlags kernel;
};

struct TimedRender {
  double medianMs = 0.0; // GPU trace time (timestamps), median of the timed runs
  double minMs = 0.0;
  double maxMs = 0.0;
  double compileMs = 0.0; // creating the timed runs' trace pipeline (0: it was built before)
  RayStats stats;         // from one extra run with counters on
  Image image;
};

inline double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// The image scaled to `height` rows, its aspect kept (at least one pixel wide).
void scaleToHeight(RenderSettings& settings, std::uint32_t height);

// One counted render (statistics and image), `warmup` untimed renders, then `runs` timed ones.
TimedRender timeRender(Renderer& renderer, const Scene& scene, const RenderSettings& settings,
                       const RenderOptions& options, int warmup, int runs);

int runBenchTime(const BenchTimeArgs& args);

struct BenchSpecializeArgs {
  std::vector<std::filesystem::path> scenes; // default: every scene in scenes/
  DeviceFlags device;
  int runs = 7;
  std::uint32_t height = 300; // images are scaled to this height (aspect kept)
};

// Specialized vs all-features trace time per scene, and the cost of an absent effect: a scene
// without mirrors at max_depth 10 against max_depth 0.
int runBenchSpecialize(const BenchSpecializeArgs& args);

struct BenchAccuracyArgs {
  std::vector<std::filesystem::path> scenes; // default: showcase, glass, seed and two hard cases
  std::filesystem::path out = "accuracy";
  DeviceFlags device;
  int runs = 5;               // timed runs per point, interleaved
  std::uint32_t height = 320; // the cheapest point takes ~15-20 ms on lavapipe (2 cores), the baselines 25+ ms
  int referenceSpp = 256;
  bool quick = false; // tiny images, few points: seconds (the test suite runs it)
  // Run under callgrind (tools/accuracy-report --count-instructions): no timing, each point rendered
  // once between client requests at countHeight, for its executed instructions.
  bool countInstructions = false;
  std::uint32_t countHeight = 48;
};

// Error against time for every accuracy knob (docs/accuracy.md).
int runBenchAccuracy(const BenchAccuracyArgs& args);

struct BenchAdaptiveArgs {
  std::vector<std::filesystem::path> scenes; // default: showcase, glass, seed, textured
  DeviceFlags device;
  int runs = 5;
  std::uint32_t height = 180;
  bool sceneSize = false; // each scene at its own image size instead of `height` rows
  int referenceSpp = 1024;
  // The reference's render.seed: 0 shares its first samples with every point (their errors are
  // understated alike, and a pixel at the reference's count has none); another seed makes it
  // independent of them, at the price of its own noise in every error.
  std::uint32_t referenceSeed = 0;
  std::vector<double> thresholds{0.016, 0.008, 0.004, 0.002};
  int minSpp = 4;                             // the thresholds' min_spp
  std::vector<int> maxSpps{1024};             // their max_spp: each threshold at each
  int minUniformSpp = 4, maxUniformSpp = 256; // uniform sampling at the powers of two between
};

// A noise threshold against uniform sampling at equal 95th-percentile error (docs/accuracy.md).
int runBenchAdaptive(const BenchAdaptiveArgs& args);

struct BenchForwardArgs {
  std::vector<std::filesystem::path> scenes; // default: seed, glass
  std::filesystem::path csv;                 // every point, for tools/forward-plot (empty: none)
  DeviceFlags device;
  int runs = 3;
  std::uint32_t height = 120;
  double aperture = 0.05; // lens radius as a fraction of the focus distance
  int referenceSpp = 1024;
  int maxSpp = 64;                     // backward points 1, 2, 4, ... spp
  std::uint64_t minPhotons = 1u << 16; // forward points, x4 each
  std::uint64_t maxPhotons = 1u << 24;
};

// Forward against backward tracing: error against time, and the struck fraction (docs/forward.md).
int runBenchForward(const BenchForwardArgs& args);

} // namespace vkray
