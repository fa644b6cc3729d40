// Shared command-line flags (see cli_options.h).
#include "app/cli_options.h"

#include <charconv>
#include <cmath>
#include <sstream>

#include "scene/scene_limits.h"
#include "util/error.h"

namespace vkray {

CLI::Validator realRange(double lo, double hi) {
  std::ostringstream bounds;
  bounds << lo << " to " << hi;
  std::string text = bounds.str();
  return CLI::Validator(
      [lo, hi, text](std::string& input) -> std::string {
        double v = 0.0;
        if (!CLI::detail::lexical_cast(input, v)) return "Value " + input + " is not a number";
        if (!(v >= lo && v <= hi)) return "Value " + input + " not in range " + text;
        return {};
      },
      "REAL in [" + text + "]");
}

// A whole number in [lo, hi]: CLI::Range would call "many" or "1.5" out of range; this says what is
// wrong with it.
CLI::Validator wholeRange(long long lo, long long hi) {
  std::string text = std::to_string(lo) + " to " + std::to_string(hi);
  return CLI::Validator(
      [lo, hi, text](std::string& input) -> std::string {
        long long v = 0;
        const char* first = input.data();
        const char* last = first + input.size();
        if (first != last && *first == '+') ++first;
        auto [end, ec] = std::from_chars(first, last, v);
        if (end != last || first == last || (ec != std::errc() && ec != std::errc::result_out_of_range))
          return "Value " + input + " is not a whole number";
        if (ec == std::errc::result_out_of_range || v < lo || v > hi) return "Value " + input + " not in range " + text;
        return {};
      },
      "INT in [" + std::to_string(lo) + " - " + std::to_string(hi) + "]");
}

// A real number in (0, hi]: zero, negative numbers and NaN are refused.
CLI::Validator positiveReal(double hi) {
  std::ostringstream bound;
  bound << hi;
  std::string text = bound.str();
  return CLI::Validator(
      [hi, text](std::string& input) -> std::string {
        double v = 0.0;
        if (!CLI::detail::lexical_cast(input, v)) return "Value " + input + " is not a number";
        if (!(v > 0.0 && v <= hi)) return "Value " + input + " must be > 0 and at most " + text;
        return {};
      },
      "REAL in (0, " + text + "]");
}

void addDeviceFlags(CLI::App& app, DeviceFlags& f) {
  app.add_option("--device", f.device, "Vulkan device: index or name substring (see 'vkray info')")
      ->envname("VKRAY_DEVICE");
  app.add_flag("--validate", f.validate, "enable the Khronos validation layer; any message fails the run");
  app.add_flag("--sync-validation", f.syncValidate, "also enable its synchronization validation");
  app.add_flag("--no-pipeline-cache", f.noPipelineCache,
               "do not read or write the on-disk pipeline cache and folded SPIR-V");
  app.add_flag("--no-huge-pages", f.noHugePages,
               "keep large scene buffers in the driver's memory, not in vkray's own huge pages (for comparison)");
}

void addKernelFlags(CLI::App& app, KernelFlags& f) {
  app.add_flag("--no-specialize", f.noSpecialize, "compile every feature in (for comparison)");
  app.add_flag("--no-spirv-folding", f.noSpirvFolding,
               "give the driver the whole kernel and its specialization constants instead of folding them into the "
               "SPIR-V first (the same code, compiled slower; for comparison)");
  app.add_flag("--no-unroll", f.noUnroll,
               "keep the sizes of small scene arrays run-time values instead of baking them in (no unrolled "
               "loops; for comparison)");
  app.add_flag("--no-row-culling", f.noRowCulling,
               "trace rows whose eye rays provably miss everything instead of filling them (for comparison)");
  app.add_flag("--no-entry-points", f.noEntryPoints,
               "walk every eye ray's BVH traversal from the root, not from its tile's entry points (for comparison)");
  app.add_option("--shadow-entry-points", f.shadowEntryPoints,
                 "start shadow rays from triangles at their (triangle, light)'s BVH subtrees, found once per scene, "
                 "and skip the walk where nothing in the BVH lies between the triangle and the light: auto (each "
                 "when the render's shadow rays pay for it), on, entries (the subtrees alone) or off")
      ->check(CLI::IsMember(enumNameList<ShadowEntries>()));
  app.add_flag("--no-shadow-entry-points", f.noShadowEntryPoints,
               "the same as --shadow-entry-points off: every shadow ray walks the BVH from the root (for comparison)");
  app.add_flag("--one-sample-per-dispatch", f.oneSamplePerDispatch,
               "trace one sample of each pixel per dispatch, one invocation per pixel, as on a driver that cuts "
               "long loops short, instead of all of a band's samples in one dispatch (the same image; for "
               "comparison)");
  app.add_option("--scene-memory", f.sceneMemory,
                 "where the kernel reads small scenes from: auto, uniform or storage buffers")
      ->check(CLI::IsMember(enumNameList<SceneMemory>()));
}

void applyKernelFlags(const KernelFlags& f, RenderOptions& o) {
  o.specialize = !f.noSpecialize;
  o.foldSpirv = !f.noSpirvFolding;
  o.unroll = !f.noUnroll;
  o.cullRows = !f.noRowCulling;
  o.entryPoints = !f.noEntryPoints;
  o.shadowEntryPoints = f.noShadowEntryPoints ? ShadowEntries::Off : *parseEnum<ShadowEntries>(f.shadowEntryPoints);
  o.oneSamplePerDispatch = f.oneSamplePerDispatch;
  o.sceneMemory = *parseEnum<SceneMemory>(f.sceneMemory);
}

void addRenderFlags(CLI::App& app, RenderFlags& f) {
  app.add_option("--width", f.width, "image width in pixels")->check(wholeRange(1ll, kMaxImageSide));
  app.add_option("--height", f.height, "image height in pixels")->check(wholeRange(1ll, kMaxImageSide));
  app.add_option("--max-depth", f.maxDepth, "reflection/refraction bounces after the eye ray")
      ->check(wholeRange(0ll, kMaxDepthLimit));
  app.add_option("--spp", f.spp, "samples per pixel")->check(wholeRange(1ll, kMaxSpp));
  app.add_option("--bailout", f.bailout, "skip branches whose weight is below this (0: trace all)")
      ->check(realRange(0.0, 1.0));
  app.add_option("--aa", f.antialiasing, "antialiasing: stratified (every pixel gets spp) or adaptive")
      ->check(CLI::IsMember(enumNameList<Antialiasing>()));
  app.add_option("--adaptive-threshold", f.adaptiveThreshold, "adaptive AA: neighbour difference that triggers spp")
      ->check(realRange(0.0, 1.0));
  app.add_option("--noise-threshold", f.noiseThreshold,
                 "progressive: stop each pixel once its estimated standard error (linear RGB) is below this")
      ->check(positiveReal(1e6));
  app.add_option("--time-limit", f.timeLimit, "progressive: passes stop within this many seconds of GPU time")
      ->check(positiveReal(kMaxTimeLimitSeconds));
  app.add_option("--method", f.method, "backward (rays from the eye, default) or forward (photons from the lights)")
      ->check(CLI::IsMember(enumNameList<Method>()));
  app.add_option("--photons", f.photons, "forward: photons each light emits")->check(wholeRange(1ll, kMaxPhotons));
  app.add_option("--min-spp", f.minSpp, "progressive: samples every pixel gets first (default 4)")
      ->check(wholeRange(1ll, kMaxSpp));
  app.add_option("--max-spp", f.maxSpp, "progressive: the most samples a pixel gets (default 1024)")
      ->check(wholeRange(1ll, kMaxSpp));
  app.add_option("--seed", f.seed, "which scrambling of the sample sequences the pixels use (default 0)")
      ->check(wholeRange(0ll, 0xFFFFFFFFll));
  app.add_option("--numerics", f.numerics, "intersection numerics: robust (default) or naive")
      ->check(CLI::IsMember(enumNameList<Numerics>()));
  app.add_option("--fresnel", f.fresnel, "dielectric Fresnel: exact or schlick")
      ->check(CLI::IsMember(enumNameList<FresnelMode>()));
  app.add_option("--transmissive-shadows", f.transmissiveShadows, "shadows of glass: attenuated or opaque")
      ->check(CLI::IsMember(enumNameList<TransmissiveShadows>()));
  app.add_option("--precision", f.precision,
                 "intersection arithmetic: float32, or float64 (reference; needs shaderFloat64)")
      ->check(CLI::IsMember(enumNameList<Precision>()));
  app.add_option("--bvh", f.bvh, "acceleration structure: auto, on or off")
      ->check(CLI::IsMember(enumNameList<BvhMode>()));
  app.add_option("--texture-filter", f.textureFilter,
                 "texture sampling: nearest, bilinear, or cone (mip level from a ray cone; default)")
      ->check(CLI::IsMember(enumNameList<TextureFilter>()));
}

void applyRenderFlags(const RenderFlags& f, RenderSettings& s) {
  if (f.width) s.width = *f.width;
  if (f.height) s.height = *f.height;
  if (f.maxDepth) s.maxDepth = *f.maxDepth;
  if (f.spp) s.spp = *f.spp;
  if (f.bailout) s.bailout = *f.bailout;
  if (f.noiseThreshold) s.noiseThreshold = *f.noiseThreshold;
  if (f.timeLimit) s.timeLimit = *f.timeLimit;
  if (f.minSpp) s.minSpp = *f.minSpp;
  if (f.method) s.method = *parseEnum<Method>(*f.method);
  if (f.photons) s.photons = static_cast<std::uint64_t>(*f.photons);
  if (f.maxSpp) s.maxSpp = *f.maxSpp;
  if (f.seed) s.seed = static_cast<std::uint32_t>(*f.seed);
  if (f.adaptiveThreshold) s.adaptiveThreshold = *f.adaptiveThreshold;
  if (f.antialiasing) s.antialiasing = *parseEnum<Antialiasing>(*f.antialiasing);
  if (f.numerics) s.numerics = *parseEnum<Numerics>(*f.numerics);
  if (f.fresnel) s.fresnel = *parseEnum<FresnelMode>(*f.fresnel);
  if (f.transmissiveShadows) s.transmissiveShadows = *parseEnum<TransmissiveShadows>(*f.transmissiveShadows);
  if (f.precision) s.precision = *parseEnum<Precision>(*f.precision);
  if (f.bvh) s.bvh = *parseEnum<BvhMode>(*f.bvh);
  if (f.textureFilter) s.textureFilter = *parseEnum<TextureFilter>(*f.textureFilter);
}

void addModelFlags(CLI::App& app, ModelFlags& f) {
  app.add_flag("--floor", f.floor, "model files: a ground plane just under the model");
  app.add_option("--background", f.background, "model files: background colour r,g,b (linear, >= 0)");
}

namespace {

glm::dvec3 parseBackground(const std::string& text) {
  glm::dvec3 c(0.0);
  std::istringstream in(text);
  std::string part;
  int n = 0;
  while (std::getline(in, part, ',')) {
    double v = 0.0;
    if (n >= 3 || !CLI::detail::lexical_cast(part, v) || !(v >= 0.0 && v <= 1e6)) n = 4;
    if (n >= 3) break;
    c[n++] = v;
  }
  if (n != 3) throw InputError("--background", "expected r,g,b: three numbers in [0, 1e6], got '" + text + "'");
  return c;
}

} // namespace

ModelSceneOptions modelSceneOptions(const ModelFlags& f, const std::filesystem::path& scene) {
  ModelSceneOptions o;
  if (f.floor && !isModelFile(scene)) {
    throw InputError("--floor", "only for model files (.obj, .gltf, .glb); a scene file has its own objects");
  }
  if (f.background && !isModelFile(scene)) {
    throw InputError("--background", "only for model files (.obj, .gltf, .glb); a scene file sets its own");
  }
  o.floor = f.floor;
  if (f.background) o.background = parseBackground(*f.background);
  return o;
}

} // namespace vkray
