// `vkray bench accuracy`: what accuracy costs in time. For each scene, a reference at the highest
// accuracy available, then every knob swept one at a time (and a few combinations): GPU time,
// rays, and error against the reference. Writes accuracy.csv and error heat maps; the plots and
// docs/accuracy.md come from tools/accuracy-report.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <limits>

#include "app/bench.h"
#include "image/image_io.h"
#include "image/metrics.h"
#include "render/renderer.h"
#include "scene/features.h"
#include "scene/scene_loader.h"
#include "util/error.h"
#include "vk/context.h"

// Callgrind's client requests (they do nothing outside valgrind; Debian ships the header with
// valgrind). Without it, --count-instructions is refused.
#if __has_include(<valgrind/callgrind.h>)
#include <valgrind/callgrind.h>
#define VKRAY_HAVE_CALLGRIND 1
#else
#define VKRAY_HAVE_CALLGRIND 0
#define CALLGRIND_START_INSTRUMENTATION
#define CALLGRIND_STOP_INSTRUMENTATION
#define CALLGRIND_ZERO_STATS
#define CALLGRIND_DUMP_STATS_AT(label) (void)(label)
#endif

namespace vkray {

namespace {

struct Point {
  std::string knob;  // depth, bailout, spp, adaptive, numerics, precision, fresnel, combined, reference
  std::string value; // as it appears in the table
  std::function<void(RenderSettings&)> apply;
};

std::string fmt(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

std::string fraction(double v) {
  if (v == 0.0) return "0";
  double inv = 1.0 / v;
  if (std::abs(inv - std::round(inv)) < 1e-9) return "1/" + std::to_string(static_cast<long>(std::round(inv)));
  return fmt(v);
}

// A blue-to-yellow-to-red ramp for heat maps, with the scale saturating at `full`.
glm::vec3 heat(float e, float full) {
  float x = std::clamp(e / full, 0.0f, 1.0f);
  glm::vec3 cold(0.02f, 0.02f, 0.12f), mid(0.9f, 0.75f, 0.1f), hot(1.0f, 0.05f, 0.02f);
  return x < 0.5f ? glm::mix(cold, mid, x * 2.0f) : glm::mix(mid, hot, x * 2.0f - 1.0f);
}

// A progressive point: 4 to 64 samples per pixel, the range of the spp points, and well below the
// reference's 256, whose first samples every point shares (a point near the reference's count
// would look better than it is).
void progressive(RenderSettings& s, double noiseThreshold, double timeLimit) {
  s.noiseThreshold = noiseThreshold;
  s.timeLimit = timeLimit;
  s.minSpp = 4;
  s.maxSpp = 64;
}

std::vector<Point> pointsFor(const Features& f, const Scene& scene, bool quick, bool float64) {
  std::vector<Point> p;
  auto add = [&](std::string knob, std::string value, std::function<void(RenderSettings&)> apply) {
    p.push_back({std::move(knob), std::move(value), std::move(apply)});
  };
  // A point setting an enum-valued knob, named by the enum's table.
  auto addEnum = [&](std::string knob, auto value, auto RenderSettings::*member) {
    add(std::move(knob), std::string(enumName(value)), [value, member](RenderSettings& s) { s.*member = value; });
  };
  add("baseline", "scene", [](RenderSettings&) {});
  if (quick) {
    // Seconds, for the test suite: one point per kind of knob.
    add("depth", "0", [](RenderSettings& s) { s.maxDepth = 0; });
    add("bailout", "1/16", [](RenderSettings& s) { s.bailout = 1.0 / 16; });
    add("spp", "4", [](RenderSettings& s) { s.spp = 4; });
    addEnum("numerics", Numerics::Naive, &RenderSettings::numerics);
    add("noise_threshold", "0.02", [](RenderSettings& s) { progressive(s, 0.02, 0.0); });
    add("time_limit", "0.05", [](RenderSettings& s) { progressive(s, 0.0, 0.05); });
    return p;
  }
  int maxDepth = f.anyTransmissiveMaterial ? 16 : 8;
  for (int d = 0; d <= maxDepth; ++d) {
    if (quick || d <= 8 || d == 10 || d == 12 || d == 16)
      add("depth", std::to_string(d), [d](RenderSettings& s) { s.maxDepth = d; });
  }
  for (double b : {0.0, 1.0 / 1024, 1.0 / 255, 1.0 / 64, 1.0 / 16}) {
    add("bailout", fraction(b), [b](RenderSettings& s) { s.bailout = b; });
  }
  for (int n : {1, 4, 16, 64}) {
    add("spp", std::to_string(n), [n](RenderSettings& s) {
      s.spp = n;
      s.antialiasing = Antialiasing::Stratified;
    });
  }
  for (int n : {4, 16, 64}) {
    add("adaptive", std::to_string(n), [n](RenderSettings& s) {
      s.spp = n;
      s.antialiasing = Antialiasing::Adaptive;
    });
  }
  // Progressive sampling: a noise threshold E (linear RGB) and a time limit S (GPU seconds).
  for (double e : {0.02, 0.01, 0.005, 0.0025})
    add("noise_threshold", fmt(e), [e](RenderSettings& s) { progressive(s, e, 0.0); });
  for (double t : {0.05, 0.1, 0.2, 0.4}) add("time_limit", fmt(t), [t](RenderSettings& s) { progressive(s, 0.0, t); });
  addEnum("numerics", Numerics::Naive, &RenderSettings::numerics);
  addEnum("numerics", Numerics::Robust, &RenderSettings::numerics);
  if (float64) addEnum("precision", Precision::Float64, &RenderSettings::precision);
  if (f.textures) {
    for (TextureFilter t : {TextureFilter::Nearest, TextureFilter::Bilinear, TextureFilter::Cone})
      addEnum("texture_filter", t, &RenderSettings::textureFilter);
  }
  if (f.anyTransmissiveMaterial) {
    addEnum("fresnel", FresnelMode::Schlick, &RenderSettings::fresnel);
    addEnum("fresnel", FresnelMode::Exact, &RenderSettings::fresnel);
  }
  {
    add("combined", "spp 4, depth 3", [](RenderSettings& s) {
      s.spp = 4;
      s.maxDepth = 3;
    });
    add("combined", "spp 16, bailout 1/64", [](RenderSettings& s) {
      s.spp = 16;
      s.bailout = 1.0 / 64;
    });
    add("combined", "adaptive 16, depth 4", [](RenderSettings& s) {
      s.spp = 16;
      s.antialiasing = Antialiasing::Adaptive;
      s.maxDepth = 4;
    });
    add("combined", "naive, spp 16", [](RenderSettings& s) {
      s.numerics = Numerics::Naive;
      s.spp = 16;
    });
  }
  (void)scene;
  return p;
}

} // namespace

namespace {

// One point of a scene: its settings, the counted render's figures, and every timed run.
struct Measured {
  std::string knob, value;
  RenderSettings settings;
  Image image;                    // the counted render's (the error is measured on it)
  RayStats stats;                 // the counted render's
  double sppMean = 0.0;           // progressive: the mean samples per pixel; otherwise the spp
  std::vector<double> ms;         // GPU trace time of each timed run
  std::vector<double> spp;        // time-limited points: each timed run's mean spp
  std::vector<ImageError> errors; // time-limited points: each timed run's error (their images differ)
};

double minOf(const std::vector<double>& v) {
  return v.empty() ? 0.0 : *std::min_element(v.begin(), v.end());
}
double maxOf(const std::vector<double>& v) {
  return v.empty() ? 0.0 : *std::max_element(v.begin(), v.end());
}

} // namespace

int runBenchAccuracy(const BenchAccuracyArgs& args) {
  std::vector<std::filesystem::path> scenes = args.scenes;
  if (scenes.empty()) {
    // The three looks, then three hard cases where naive numerics go wrong (docs/numerics.md), then
    // textures (the texture_filter points).
    for (const char* name : {"showcase.json", "glass.json", "seed.json", "numerics-cracks.json",
                             "numerics-far-sphere.json", "numerics-huge-ground.json", "textured.json"}) {
      scenes.push_back(std::filesystem::path(VKRAY_SCENES_DIR) / name);
      if (args.quick) break;
    }
  }
  std::error_code ec;
  std::filesystem::create_directories(args.out, ec);
  if (ec) throw InputError(args.out.string(), "cannot create the output directory: " + ec.message());

  vulkan::Context context(contextOptions(args.device));
  const bool float64 = context.float64Enabled();
  const int runs = args.quick ? 2 : args.runs;
  const std::uint32_t height = args.countInstructions ? args.countHeight : args.quick ? 24 : args.height;
  const int refSpp = args.quick ? 16 : args.referenceSpp;
  const bool counting = args.countInstructions;
  if (counting && !VKRAY_HAVE_CALLGRIND)
    throw InputError("--count-instructions",
                     "this build has no valgrind/callgrind.h (Debian: valgrind); rebuild with it");

  // --count-instructions: no timing and no reference; each point is rendered once to build its
  // pipelines, then once more between callgrind's client requests, which dump that render's
  // instructions to their own file named by the point (tools/accuracy-report --count-instructions
  // runs this under callgrind and sums each dump's JIT code). Outside valgrind the requests do nothing.
  const std::filesystem::path csvPath = args.out / (counting ? "instructions-points.csv" : "accuracy.csv");
  std::ofstream csv(csvPath);
  if (!csv) throw InputError(csvPath.string(), "cannot write");
  if (counting) {
    csv << "dump,scene,knob,value,width,height\n";
  } else {
    csv << "scene,knob,value,width,height,spp,max_depth,bailout,numerics,precision,fresnel,antialiasing,"
           "texture_filter,noise_threshold,time_limit,spp_mean,runs,trace_ms,trace_ms_min,trace_ms_max,rays,eye_rays,"
           "rmse,rmse_min,rmse_max,psnr_db,max_abs,share_off,pixels_off,rmse_1spp,share_off_1spp\n";
    // Header of the run: stated with the figures.
    std::ofstream meta(args.out / "run.txt");
    meta << "device: " << context.info().name << "\ndriver: " << context.info().driver << "\nruns: " << runs
         << " interleaved (run r of every point of a scene before run r+1 of any; one warm-up round)\nheight: "
         << height << "\nreference spp: " << refSpp
         << "\nreference precision: " << (float64 ? "float64" : "float32 (no shaderFloat64)") << "\n";
  }

  int dump = 0;
  for (const auto& path : scenes) {
    Scene scene = loadScene(path);
    double aspect = static_cast<double>(scene.render.width) / scene.render.height;
    scene.render.height = height;
    scene.render.width = static_cast<std::uint32_t>(std::max(1.0, std::round(height * aspect)));
    scene.render.spp = 1;
    scene.render.antialiasing = Antialiasing::Stratified;
    scene.render.noiseThreshold = 0.0;
    scene.render.timeLimit = 0.0;
    const std::string name = path.stem().string();
    std::fprintf(stderr, "%s: %ux%u\n", name.c_str(), scene.render.width, scene.render.height);

    Renderer renderer(context, nullptr);
    const Features features = analyzeScene(scene, scene.render);
    renderer.setScene(scene, features);
    RenderOptions options;
    options.countStats = false;
    // The timed runs render the 256-spp reference first, whose samples make the shadow table pay
    // (`--shadow-entry-points auto`), and every point after it traces with that table. The counted
    // renders at 64x48 would build it only from the point with enough pixel samples per triangle on
    // (the textured scene's 1-spp points counted 7.3 M instructions before it, 6.4 M after): so
    // they build it from the first, as the timed ones have it.
    if (counting) options.shadowEntryPoints = ShadowEntries::On;
    RenderOptions counted = options;
    counted.countStats = true;

    std::vector<Measured> points;
    for (const Point& p : pointsFor(features, scene, args.quick, float64)) {
      Measured m;
      m.knob = p.knob;
      m.value = p.value;
      m.settings = scene.render;
      p.apply(m.settings);
      points.push_back(std::move(m));
    }

    if (counting) {
      for (Measured& m : points) {
        // A time limit's cost is its limit, and under valgrind it would stop after far fewer samples.
        if (m.settings.timeLimit > 0.0) continue;
        renderer.render(scene.camera, m.settings, options); // builds the pipelines, uncounted
        const std::string label = "point " + std::to_string(++dump);
        CALLGRIND_START_INSTRUMENTATION;
        CALLGRIND_ZERO_STATS;
        renderer.render(scene.camera, m.settings, options);
        CALLGRIND_DUMP_STATS_AT(label.c_str());
        CALLGRIND_STOP_INSTRUMENTATION;
        csv << dump << ',' << name << ',' << m.knob << ",\"" << m.value << "\"," << m.settings.width << ','
            << m.settings.height << '\n';
        csv.flush();
        std::fprintf(stderr, "  %-15s %-22s counted (%s)\n", m.knob.c_str(), m.value.c_str(), label.c_str());
      }
      continue;
    }

    // The reference: deep, many samples, robust, float64 where the device has it, and a bailout of
    // 1e-6 rather than 0: at depth 16 a glass tree without bailout has up to 2^17 rays per sample,
    // which the kernel's ray budget cuts short (it counts them as `truncated`), while
    // the branches below 1e-6 change no pixel of the glass scene by more than 4e-5 (measured
    // against 1e-5; docs/accuracy.md).
    RenderSettings ref = scene.render;
    ref.maxDepth = std::max(16, scene.render.maxDepth);
    ref.bailout = 1e-6;
    ref.spp = refSpp;
    ref.numerics = Numerics::Robust;
    ref.fresnel = FresnelMode::Exact;
    ref.textureFilter = TextureFilter::Nearest; // point samples: their mean is the filtered texture
    ref.precision = float64 ? Precision::Float64 : Precision::Float32;
    RenderResult reference = renderer.render(scene.camera, ref, counted);
    if (reference.stats.truncated > 0) {
      throw Error(name + ": the reference lost " + std::to_string(reference.stats.truncated) +
                  " samples to the ray budget per sample; it would not be a reference");
    }
    writeImage(args.out / (name + "-reference.png"), reference.image);
    // The same reference with one centre sample per pixel: against it, a 1-spp point's error is
    // its knob's alone, without the aliasing every 1-spp image shares.
    RenderSettings ref1 = ref;
    ref1.spp = 1;
    Image reference1 = renderer.render(scene.camera, ref1, options).image;

    // One counted render of each point (its image, error and rays; it also builds the pipelines),
    // one untimed warm-up round, then the timed runs interleaved: run r of every point before run
    // r + 1 of any, so a slow spell of the shared machine spreads over all points instead of
    // landing on a few, and each point's min, median and max show how far its time can be trusted.
    for (Measured& m : points) {
      RenderResult r = renderer.render(scene.camera, m.settings, counted);
      m.image = std::move(r.image);
      m.stats = r.stats;
      m.sppMean = r.progressive.passes > 0 ? r.progressive.sppMean : m.settings.spp;
    }
    for (int run = -1; run < runs; ++run) {
      for (Measured& m : points) {
        RenderResult r = renderer.render(scene.camera, m.settings, options);
        if (run < 0) continue;
        m.ms.push_back(r.timings.traceMs);
        if (m.settings.timeLimit > 0.0) { // the samples a time limit allows vary run by run
          m.errors.push_back(compareImages(r.image, reference.image));
          m.spp.push_back(r.progressive.sppMean);
        }
      }
    }

    auto row = [&](const std::string& knob, const std::string& value, const RenderSettings& s, double sppMean,
                   int timedRuns, const std::vector<double>& ms, const RayStats& stats, const ImageError& e,
                   double rmseMin, double rmseMax, const ImageError& e1) {
      csv << name << ',' << knob << ",\"" << value << "\"," << s.width << ',' << s.height << ',' << s.spp << ','
          << s.maxDepth << ',' << fmt(s.bailout) << ',' << enumName(s.numerics) << ',' << enumName(s.precision) << ','
          << enumName(s.fresnel) << ',' << enumName(s.antialiasing) << ',' << enumName(s.textureFilter) << ','
          << fmt(s.noiseThreshold) << ',' << fmt(s.timeLimit) << ',' << fmt(sppMean) << ',' << timedRuns << ','
          << fmt(median(ms)) << ',' << fmt(minOf(ms)) << ',' << fmt(maxOf(ms)) << ',' << stats.total() << ','
          << stats.eye << ',' << fmt(e.rmse) << ',' << fmt(rmseMin) << ',' << fmt(rmseMax) << ','
          << (std::isinf(e.psnr) ? std::string("inf") : fmt(e.psnr)) << ',' << fmt(e.maxAbs) << ','
          << fmt(e.fractionOff) << ',' << e.pixelsOff << ',' << fmt(e1.rmse) << ',' << fmt(e1.fractionOff) << '\n';
      csv.flush();
    };
    {
      // The reference is not timed again (it is the longest render by far): its time is that of
      // its one counted render, `runs` 0 says so.
      ImageError none;
      none.psnr = std::numeric_limits<double>::infinity();
      std::vector<double> once{reference.timings.traceMs};
      row("reference", "reference", ref, ref.spp, 0, once, reference.stats, none, 0.0, 0.0, none);
    }

    float heatScale = 0.05f;
    for (Measured& m : points) {
      const RenderSettings& s = m.settings;
      ImageError e = compareImages(m.image, reference.image);
      double rmseMin = e.rmse, rmseMax = e.rmse;
      double sppMean = m.sppMean;
      if (!m.errors.empty()) { // time-limited: the run of median error stands for the point
        std::vector<std::size_t> order(m.errors.size());
        for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
        std::sort(order.begin(), order.end(),
                  [&](std::size_t a, std::size_t b) { return m.errors[a].rmse < m.errors[b].rmse; });
        e = m.errors[order[order.size() / 2]];
        rmseMin = m.errors[order.front()].rmse;
        rmseMax = m.errors[order.back()].rmse;
        sppMean = median(m.spp);
      }
      bool oneSample = s.spp == 1 && !s.progressive();
      ImageError e1 = oneSample ? compareImages(m.image, reference1) : e;
      row(m.knob, m.value, s, sppMean, static_cast<int>(m.ms.size()), m.ms, m.stats, e, rmseMin, rmseMax, e1);
      std::fprintf(stderr, "  %-15s %-22s %9.2f ms [%.2f, %.2f]  rmse %.5f  off %.4f  (1 spp: rmse %.5f off %.4f)\n",
                   m.knob.c_str(), m.value.c_str(), median(m.ms), minOf(m.ms), maxOf(m.ms), e.rmse, e.fractionOff,
                   e1.rmse, e1.fractionOff);
      // Heat maps of where the error is, for the points the report discusses.
      const std::string& knob = m.knob;
      const std::string& value = m.value;
      bool telling = (knob == "numerics" && value == enumName(Numerics::Naive)) ||
                     (knob == "depth" && (value == "1" || value == "2")) || (knob == "spp" && value == "1") ||
                     (knob == "bailout" && value == "1/16") ||
                     (knob == "fresnel" && value == enumName(FresnelMode::Schlick)) ||
                     (knob == "adaptive" && value == "16") || (knob == "noise_threshold" && value == "0.01");
      if (telling && !args.quick) {
        Image map = errorMap(m.image, oneSample ? reference1 : reference.image);
        for (auto& px : map.pixels) px = heat(px.x, heatScale);
        std::string file = name + "-error-" + knob + "-" + value + ".png";
        std::replace(file.begin(), file.end(), '/', '_');
        std::replace(file.begin(), file.end(), ' ', '_');
        // Heat maps are already display colours: store them so the PNG shows them as computed.
        for (auto& px : map.pixels) px = glm::vec3(srgbToLinear(px.x), srgbToLinear(px.y), srgbToLinear(px.z));
        writeImage(args.out / file, map);
      }
    }
  }
  std::fprintf(stderr, "wrote %s\n", csvPath.string().c_str());
  return 0;
}

} // namespace vkray
