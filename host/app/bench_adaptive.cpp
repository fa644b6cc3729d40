// `vkray bench adaptive`: what a noise threshold saves. Per scene, renders at several thresholds
// and uniform sampling at powers of two, interleaved run by run (the machines are noisy), measures
// each one's 95th-percentile error against a many-sample reference, and states the uniform spp and
// trace time that reach the same 95th percentile (interpolated in log-log between the powers of two
// that bracket it) beside the threshold's own, and their ratio.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "app/bench.h"
#include "render/renderer.h"
#include "scene/scene_loader.h"
#include "vk/context.h"

namespace vkray {

namespace {

// The 95th percentile over the pixels of the largest channel difference to the reference.
double p95Error(const Image& image, const Image& reference) {
  std::vector<double> e(image.pixels.size());
  for (std::size_t i = 0; i < e.size(); ++i) {
    glm::vec3 d = glm::abs(image.pixels[i] - reference.pixels[i]);
    e[i] = std::max({d.x, d.y, d.z});
  }
  std::sort(e.begin(), e.end());
  return e[std::min(e.size() - 1, static_cast<std::size_t>(0.95 * static_cast<double>(e.size())))];
}

struct Point {
  std::string label;
  RenderSettings settings;
  std::vector<double> ms; // GPU trace time of each timed run
  double p95 = 0.0;
  double sppMean = 0.0;
  double converged = 1.0; // share of the pixels whose estimate met the threshold (the rest met max_spp)
  std::uint64_t rays = 0;
};

// Where log(value) lies between two bracketing points, in log(error): the spp or time uniform
// sampling needs for `target` (NaN when no two uniform points bracket it).
double interpolate(const std::vector<Point>& uniform, double target, double (*value)(const Point&)) {
  for (std::size_t i = 0; i + 1 < uniform.size(); ++i) {
    const Point &a = uniform[i], &b = uniform[i + 1];
    if (a.p95 >= target && target >= b.p95 && a.p95 > b.p95) {
      double t = std::log(a.p95 / target) / std::log(a.p95 / b.p95);
      return std::exp(std::log(value(a)) + t * std::log(value(b) / value(a)));
    }
  }
  return std::nan("");
}

} // namespace

int runBenchAdaptive(const BenchAdaptiveArgs& args) {
  vulkan::Context context(contextOptions(args.device));
  std::printf("device: %s (%s)\n", context.info().name.c_str(), context.info().driver.c_str());
  std::vector<std::filesystem::path> scenes = args.scenes;
  if (scenes.empty()) {
    for (const char* name : {"showcase.json", "glass.json", "seed.json", "textured.json"})
      scenes.push_back(std::filesystem::path(VKRAY_SCENES_DIR) / name);
  }
  for (const auto& path : scenes) {
    Scene scene = loadScene(path);
    if (!args.sceneSize) scaleToHeight(scene.render, args.height);
    scene.render.antialiasing = Antialiasing::Stratified;
    Renderer renderer(context, nullptr);
    renderer.setScene(scene);
    RenderOptions options;
    options.countStats = false;

    // The reference: uniform, many samples. With seed 0 it shares its first samples with every
    // point below, which understates their errors alike (4x the largest uniform point keeps that
    // small); with --reference-seed it shares none.
    RenderSettings refSettings = scene.render;
    refSettings.spp = args.referenceSpp;
    refSettings.seed = args.referenceSeed;
    Image reference = renderer.render(scene.camera, refSettings, options).image;

    std::vector<Point> uniform, adaptive;
    for (int spp = args.minUniformSpp; spp <= args.maxUniformSpp; spp *= 2) {
      Point p;
      p.label = std::to_string(spp) + " spp";
      p.settings = scene.render;
      p.settings.spp = spp;
      uniform.push_back(p);
    }
    for (double e : args.thresholds) {
      for (int cap : args.maxSpps) {
        Point p;
        char label[32];
        std::snprintf(label, sizeof label, "E %g", e);
        p.label = label;
        p.settings = scene.render;
        p.settings.noiseThreshold = e;
        p.settings.minSpp = std::min(args.minSpp, cap);
        p.settings.maxSpp = cap;
        adaptive.push_back(p);
      }
    }
    // One counted run of each for its error and rays (and the pipelines), then the timed runs,
    // interleaved: run r of every point before run r + 1 of any.
    std::vector<Point*> all;
    for (Point& p : uniform) all.push_back(&p);
    for (Point& p : adaptive) all.push_back(&p);
    for (Point* p : all) {
      RenderOptions counted = options;
      counted.countStats = true;
      RenderResult r = renderer.render(scene.camera, p->settings, counted);
      p->p95 = p95Error(r.image, reference);
      p->rays = r.stats.total() - r.timings.culledEyeRays; // the rays the device traced
      p->sppMean = r.progressive.passes > 0 ? r.progressive.sppMean : p->settings.spp;
      p->converged = r.progressive.passes > 0 ? r.progressive.converged : 1.0;
    }
    // One untimed round first: a point's first uncounted render builds its pipeline and wakes
    // the driver's caches (first runs measured up to 4x the median).
    for (int run = -1; run < args.runs; ++run) {
      if (run < 0) {
        for (Point* p : all) renderer.render(scene.camera, p->settings, options);
        continue;
      }
      for (Point* p : all) p->ms.push_back(renderer.render(scene.camera, p->settings, options).timings.traceMs);
    }

    const std::string seed = args.referenceSeed ? " (seed " + std::to_string(args.referenceSeed) + ")" : "";
    std::printf("\n%s, %ux%u, reference %d spp%s, %d interleaved runs (GPU trace ms: median [min, max])\n",
                path.filename().string().c_str(), scene.render.width, scene.render.height, args.referenceSpp,
                seed.c_str(), args.runs);
    std::printf("%-12s %9s %10s %12s %24s\n", "uniform", "spp", "p95 error", "rays", "trace ms");
    for (const Point& p : uniform) {
      std::printf("%-12s %9d %10.5f %12llu %10.2f [%.2f, %.2f]\n", p.label.c_str(), p.settings.spp, p.p95,
                  static_cast<unsigned long long>(p.rays), median(p.ms), *std::min_element(p.ms.begin(), p.ms.end()),
                  *std::max_element(p.ms.begin(), p.ms.end()));
    }
    std::printf("%-12s %9s %10s %12s %24s %14s %12s %7s %8s %10s %8s %8s %10s\n", "threshold", "spp mean", "p95 error",
                "rays", "trace ms", "uniform spp", "uniform ms", "ratio", "samples", "rays/spp", "ms/ray", "max_spp",
                "converged");
    for (const Point& p : adaptive) {
      const double ms = median(p.ms);
      const double uSpp =
          interpolate(uniform, p.p95, [](const Point& u) { return static_cast<double>(u.settings.spp); });
      const double uMs = interpolate(uniform, p.p95, [](const Point& u) { return median(u.ms); });
      const double uRays = interpolate(uniform, p.p95, [](const Point& u) { return static_cast<double>(u.rays); });
      // The time ratio as the product of three: samples, rays per sample, time per ray.
      const double samples = p.sppMean / uSpp;
      const double raysRatio = static_cast<double>(p.rays) / uRays;
      std::printf("%-12s %9.1f %10.5f %12llu %10.2f [%.2f, %.2f] %14.1f %12.2f %7.2f %8.2f %10.2f %8.2f %8d %9.2f%%\n",
                  p.label.c_str(), p.sppMean, p.p95, static_cast<unsigned long long>(p.rays), ms,
                  *std::min_element(p.ms.begin(), p.ms.end()), *std::max_element(p.ms.begin(), p.ms.end()), uSpp, uMs,
                  ms / uMs, samples, raysRatio / samples, (ms / uMs) / raysRatio, p.settings.maxSpp,
                  100.0 * p.converged);
    }
  }
  std::printf(
      "\nratio: the threshold's median trace time over uniform sampling's at the same 95th-percentile error "
      "(nan: outside the uniform points' range); it is the product of the last three: samples (the "
      "threshold's mean spp over uniform's), rays/spp and ms/ray (each the threshold's over uniform's); converged: "
      "the share of pixels whose error estimate met the threshold (the others stopped at max_spp); rays: those "
      "traced, without the eye rays of rows that see nothing (row culling answers them untraced)\n");
  return 0;
}

} // namespace vkray
