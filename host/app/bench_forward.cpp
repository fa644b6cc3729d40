// `vkray bench forward`: the lecture's claim measured. Per scene, with a thin lens put on the camera,
// renders backward at powers of two samples per pixel and forward at powers of two photons per
// light, interleaved run by run, and measures each one's RMS error against the same many-sample
// backward reference. Both sides leave out what forward tracing cannot produce (the ambient term and
// the background: no light path carries them), so they converge to the same image. It states the
// forward time needed to reach the error backward tracing reaches at 1 spp (extrapolated along the
// forward points' own error-time line, error ~ time^-1/2, when they do not reach it), and how the
// fraction of photons that strike the image falls as the aperture shrinks. --csv writes every point
// for tools/forward-plot.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>

#include "app/bench.h"
#include "render/renderer.h"
#include "scene/scene_limits.h"
#include "scene/scene_loader.h"
#include "util/error.h"
#include "vk/context.h"

namespace vkray {

namespace {

// RMS over pixels and channels of the difference to the reference (linear RGB).
double rmsError(const Image& image, const Image& reference) {
  double sum = 0.0;
  for (std::size_t i = 0; i < image.pixels.size(); ++i) {
    glm::dvec3 d = glm::dvec3(image.pixels[i]) - glm::dvec3(reference.pixels[i]);
    sum += glm::dot(d, d);
  }
  return std::sqrt(sum / (3.0 * static_cast<double>(image.pixels.size())));
}

struct Point {
  std::string method;
  std::uint64_t count = 0; // spp or photons per light
  RenderSettings settings;
  std::vector<double> ms;
  double error = 0.0;
  std::uint64_t rays = 0;
  double struckFraction = 0.0;
};

// A least-squares line through (log time, log error) of the points.
struct LogLine {
  double slope = std::nan(""), intercept = std::nan("");
  double timeFor(double error) const { return std::exp((std::log(error) - intercept) / slope); }
};

LogLine fit(const std::vector<Point>& points) {
  double n = 0, sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (const Point& p : points) {
    if (!(p.error > 0.0)) continue;
    double x = std::log(median(p.ms)), y = std::log(p.error);
    n += 1;
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
  }
  LogLine l;
  if (n < 2) return l;
  l.slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);
  l.intercept = (sy - l.slope * sx) / n;
  return l;
}

} // namespace

int runBenchForward(const BenchForwardArgs& args) {
  vulkan::Context context(contextOptions(args.device));
  std::printf("device: %s (%s)\n", context.info().name.c_str(), context.info().driver.c_str());
  std::vector<std::filesystem::path> scenes = args.scenes;
  if (scenes.empty()) {
    for (const char* name : {"seed.json", "glass.json"})
      scenes.push_back(std::filesystem::path(VKRAY_SCENES_DIR) / name);
  }
  std::ofstream csv;
  if (!args.csv.empty()) {
    csv.open(args.csv);
    if (!csv) throw InputError("--csv", "cannot write '" + args.csv.string() + "'");
    csv << "scene,method,count,median_ms,min_ms,max_ms,rms_error,rays,struck_fraction\n";
  }
  for (const auto& path : scenes) {
    Scene scene = loadScene(path);
    scaleToHeight(scene.render, args.height);
    scene.render.antialiasing = Antialiasing::Stratified;
    scene.render.noiseThreshold = 0.0;
    scene.render.timeLimit = 0.0;
    scene.render.method = Method::Backward;
    // What only backward tracing has: left out of both sides.
    scene.background = glm::dvec3(0.0);
    scene.ambientLight = glm::dvec3(0.0);
    const double distance = scene.camera.focusDistanceOrDefault();
    scene.camera.aperture = args.aperture * distance;
    Renderer renderer(context, nullptr);
    renderer.setScene(scene);
    RenderOptions options;
    options.countStats = false;

    RenderSettings refSettings = scene.render;
    refSettings.spp = args.referenceSpp;
    Image reference = renderer.render(scene.camera, refSettings, options).image;

    std::vector<Point> backward, forward;
    for (int spp = 1; spp <= args.maxSpp; spp *= 2) {
      Point p;
      p.method = "backward";
      p.count = static_cast<std::uint64_t>(spp);
      p.settings = scene.render;
      p.settings.spp = spp;
      backward.push_back(p);
    }
    for (std::uint64_t n = args.minPhotons; n <= args.maxPhotons; n *= 4) {
      Point p;
      p.method = "forward";
      p.count = n;
      p.settings = scene.render;
      p.settings.method = Method::Forward;
      p.settings.photons = n;
      forward.push_back(p);
    }
    std::vector<Point*> all;
    for (Point& p : backward) all.push_back(&p);
    for (Point& p : forward) all.push_back(&p);
    for (Point* p : all) {
      RenderOptions counted = options;
      counted.countStats = true;
      RenderResult r = renderer.render(scene.camera, p->settings, counted);
      p->error = rmsError(r.image, reference);
      p->rays = p->settings.method == Method::Forward ? r.forward.rays : r.stats.total();
      p->struckFraction = r.forward.struckFraction();
    }
    // An untimed round first (pipelines, the driver's caches), then the timed rounds, interleaved.
    for (int run = -1; run < args.runs; ++run) {
      for (Point* p : all) {
        double ms = renderer.render(scene.camera, p->settings, options).timings.traceMs;
        if (run >= 0) p->ms.push_back(ms);
      }
    }

    std::printf("\n%s, %ux%u, lens radius %.4g (%.3g of the focus distance %.3g), reference %d spp backward; "
                "ambient and background left out; %d interleaved runs (GPU trace ms: median [min, max])\n",
                path.filename().string().c_str(), scene.render.width, scene.render.height, scene.camera.aperture,
                args.aperture, distance, args.referenceSpp, args.runs);
    std::printf("%-9s %14s %11s %14s %24s %12s\n", "method", "spp|photons", "RMS error", "rays", "trace ms", "struck");
    for (Point* p : all) {
      std::printf("%-9s %14llu %11.5f %14llu %10.2f [%.2f, %.2f]", p->method.c_str(),
                  static_cast<unsigned long long>(p->count), p->error, static_cast<unsigned long long>(p->rays),
                  median(p->ms), *std::min_element(p->ms.begin(), p->ms.end()),
                  *std::max_element(p->ms.begin(), p->ms.end()));
      if (p->method == "forward") std::printf(" %12.3g", p->struckFraction);
      std::printf("\n");
      if (csv) {
        csv << path.filename().string() << ',' << p->method << ',' << p->count << ',' << median(p->ms) << ','
            << *std::min_element(p->ms.begin(), p->ms.end()) << ',' << *std::max_element(p->ms.begin(), p->ms.end())
            << ',' << p->error << ',' << p->rays << ',' << p->struckFraction << '\n';
      }
    }
    // Forward's time to backward's 1-spp error: from the largest forward point along the Monte Carlo
    // law (error ~ photons^-1/2 ~ time^-1/2), unless a point reached it; the fitted slope beside it
    // says how well the points follow that law.
    const Point& one = backward.front();
    const Point& last = forward.back();
    LogLine line = fit(forward);
    const Point* reached = nullptr;
    for (const Point& p : forward) {
      if (p.error <= one.error) {
        reached = &p;
        break;
      }
    }
    const double needMs = reached ? median(reached->ms) : median(last.ms) * std::pow(last.error / one.error, 2.0);
    const double needPhotons =
        reached ? double(reached->count) : double(last.count) * std::pow(last.error / one.error, 2.0);
    std::printf("backward 1 spp: RMS error %.5f in %.2f ms\n", one.error, median(one.ms));
    std::printf("forward: error ~ time^%.2f (fitted); to RMS error %.5f: %.3g photons per light, %.4g ms (%s), "
                "%.3g x backward's time\n",
                line.slope, one.error, needPhotons, needMs,
                reached ? "reached" : "extrapolated from the largest point, error ~ time^-1/2",
                needMs / median(one.ms));

    // The struck fraction as the lens shrinks: halving the radius, with 4x the photons each step so
    // that about as many strike.
    std::printf("%-28s %12s %10s %14s\n", "aperture (of focus distance)", "photons", "struck", "per lens area");
    std::uint64_t photons = std::max<std::uint64_t>(1u << 16, args.maxPhotons / 4);
    for (int step = 0; step < 4; ++step, photons *= 4) {
      const double a = args.aperture / double(1 << step);
      Camera lens = scene.camera;
      lens.aperture = a * distance;
      RenderSettings fs = scene.render;
      fs.method = Method::Forward;
      fs.photons = std::min<std::uint64_t>(photons, kMaxPhotons);
      RenderResult r = renderer.render(lens, fs, options);
      const double fraction = r.forward.struckFraction();
      std::printf("%-28.5g %12llu %10.3g %14.3g\n", a, static_cast<unsigned long long>(fs.photons), fraction,
                  fraction / (a * a));
      if (csv) {
        csv << path.filename().string() << ",aperture," << a << ',' << r.timings.traceMs << ",0,0,0," << r.forward.rays
            << ',' << fraction << '\n';
      }
    }
  }
  std::printf("\nRMS error: linear RGB against the reference. forward: photons per light; struck: the fraction of "
              "emitted photons that reached a pixel through the lens\n");
  return 0;
}

} // namespace vkray
