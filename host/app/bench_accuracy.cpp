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
  const int runs = args.quick ? 1 : args.runs;
  const std::uint32_t height = args.quick ? 24 : args.height;
  const int refSpp = args.quick ? 16 : args.referenceSpp;

  std::ofstream csv(args.out / "accuracy.csv");
  if (!csv) throw InputError((args.out / "accuracy.csv").string(), "cannot write");
  csv << "scene,knob,value,width,height,spp,max_depth,bailout,numerics,precision,fresnel,antialiasing,"
         "trace_ms,trace_ms_min,rays,eye_rays,rmse,psnr_db,max_abs,share_off,pixels_off,rmse_1spp,share_off_1spp\n";
  // Header of the run: stated with the figures.
  std::ofstream meta(args.out / "run.txt");
  meta << "device: " << context.info().name << "\ndriver: " << context.info().driver << "\nruns: " << runs
       << " (median after one warm-up)\nheight: " << height << "\nreference spp: " << refSpp
       << "\nreference precision: " << (float64 ? "float64" : "float32 (no shaderFloat64)") << "\n";

  for (const auto& path : scenes) {
    Scene scene = loadScene(path);
    double aspect = static_cast<double>(scene.render.width) / scene.render.height;
    scene.render.height = height;
    scene.render.width = static_cast<std::uint32_t>(std::max(1.0, std::round(height * aspect)));
    scene.render.spp = 1;
    scene.render.antialiasing = Antialiasing::Stratified;
    const std::string name = path.stem().string();
    std::fprintf(stderr, "%s: %ux%u\n", name.c_str(), scene.render.width, scene.render.height);

    Renderer renderer(context, nullptr);
    const Features features = analyzeScene(scene, scene.render);
    renderer.setScene(scene, features);
    RenderOptions options;
    options.countStats = false;

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
    RenderOptions counted = options;
    counted.countStats = true;
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
    auto row = [&](const std::string& knob, const std::string& value, const RenderSettings& s, const TimedRender& t,
                   const ImageError& e, const ImageError& e1) {
      csv << name << ',' << knob << ",\"" << value << "\"," << s.width << ',' << s.height << ',' << s.spp << ','
          << s.maxDepth << ',' << fmt(s.bailout) << ',' << enumName(s.numerics) << ',' << enumName(s.precision) << ','
          << enumName(s.fresnel) << ',' << enumName(s.antialiasing) << ',' << fmt(t.medianMs) << ',' << fmt(t.minMs)
          << ',' << t.stats.total() << ',' << t.stats.eye << ',' << fmt(e.rmse) << ','
          << (std::isinf(e.psnr) ? std::string("inf") : fmt(e.psnr)) << ',' << fmt(e.maxAbs) << ','
          << fmt(e.fractionOff) << ',' << e.pixelsOff << ',' << fmt(e1.rmse) << ',' << fmt(e1.fractionOff) << '\n';
      csv.flush();
    };
    {
      TimedRender t = timeRender(renderer, scene, ref, options, 1, args.quick ? 1 : std::min(runs, 3));
      ImageError none;
      none.psnr = std::numeric_limits<double>::infinity();
      row("reference", "reference", ref, t, none, none);
    }

    float heatScale = 0.05f;
    for (const Point& p : pointsFor(features, scene, args.quick, float64)) {
      RenderSettings s = scene.render;
      p.apply(s);
      TimedRender t = timeRender(renderer, scene, s, options, 1, runs);
      ImageError e = compareImages(t.image, reference.image);
      bool oneSample = s.spp == 1;
      ImageError e1 = oneSample ? compareImages(t.image, reference1) : e;
      row(p.knob, p.value, s, t, e, e1);
      std::fprintf(stderr, "  %-10s %-22s %9.2f ms  rmse %.5f  off %.4f  (1 spp: rmse %.5f off %.4f)\n", p.knob.c_str(),
                   p.value.c_str(), t.medianMs, e.rmse, e.fractionOff, e1.rmse, e1.fractionOff);
      // Heat maps of where the error is, for the points the report discusses.
      bool telling = (p.knob == "numerics" && p.value == enumName(Numerics::Naive)) ||
                     (p.knob == "depth" && (p.value == "1" || p.value == "2")) || (p.knob == "spp" && p.value == "1") ||
                     (p.knob == "bailout" && p.value == "1/16") ||
                     (p.knob == "fresnel" && p.value == enumName(FresnelMode::Schlick)) ||
                     (p.knob == "adaptive" && p.value == "16");
      if (telling && !args.quick) {
        Image map = errorMap(t.image, oneSample ? reference1 : reference.image);
        for (auto& px : map.pixels) px = heat(px.x, heatScale);
        std::string file = name + "-error-" + p.knob + "-" + p.value + ".png";
        std::replace(file.begin(), file.end(), '/', '_');
        std::replace(file.begin(), file.end(), ' ', '_');
        // Heat maps are already display colours: store them so the PNG shows them as computed.
        for (auto& px : map.pixels) px = glm::vec3(srgbToLinear(px.x), srgbToLinear(px.y), srgbToLinear(px.z));
        writeImage(args.out / file, map);
      }
    }
  }
  std::fprintf(stderr, "wrote %s\n", (args.out / "accuracy.csv").string().c_str());
  return 0;
}

} // namespace vkray
