// vkray: a Whitted ray tracer in a Vulkan compute shader. The command line: render | merge | view | bench | info.
#include <algorithm>
#include <cstdio>
#include <exception>
#include <new>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "app/bench.h"
#include "app/bench_meshes.h"
#include "app/commands.h"
#include "app/view_command.h"
#include "scene/json_reader.h"
#include "scene/scene_limits.h"
#include "util/error.h"

namespace {

// For a command line CLI11 refused: "did you mean --stats?" for the first flag the chosen
// subcommand does not know, or the subcommand a misspelt one is closest to.
std::string didYouMean(CLI::App& app, int argc, char** argv) {
  CLI::App* at = &app;
  for (bool deeper = true; deeper;) {
    deeper = false;
    for (CLI::App* sub : at->get_subcommands([](CLI::App*) { return true; })) {
      if (sub->parsed()) {
        at = sub;
        deeper = true;
        break;
      }
    }
  }
  std::vector<std::string> flags, subcommands;
  for (const CLI::Option* opt : at->get_options()) {
    for (const auto& name : opt->get_lnames()) flags.push_back("--" + name);
  }
  for (const CLI::App* sub : at->get_subcommands([](CLI::App*) { return true; })) {
    subcommands.push_back(sub->get_name());
  }
  for (int i = 1; i < argc; ++i) {
    std::string arg = argv[i];
    if (arg.rfind("--", 0) == 0) {
      arg = arg.substr(0, arg.find('='));
      if (std::find(flags.begin(), flags.end(), arg) != flags.end()) continue;
      std::string best = vkray::closestMatch(arg, flags);
      if (!best.empty()) return " (did you mean " + best + "?)";
    } else if (!subcommands.empty() && arg[0] != '-' && at->get_name() != argv[i]) {
      if (std::find(subcommands.begin(), subcommands.end(), arg) != subcommands.end()) continue;
      std::string best = vkray::closestMatch(arg, subcommands);
      if (!best.empty()) return " (did you mean '" + best + "'?)";
    }
  }
  return {};
}

} // namespace

int main(int argc, char** argv) {
  using namespace vkray;
  CLI::App app{"vkray: Whitted-style ray tracing in a Vulkan compute shader"};
  app.set_version_flag("--version", std::string("vkray ") + VKRAY_VERSION +
                                        (std::string(VKRAY_GIT_DESCRIBE).empty() ? "" : " (" VKRAY_GIT_DESCRIBE ")"));
  app.require_subcommand(1);

  RenderArgs render;
  auto* renderCmd = app.add_subcommand("render", "render a scene to an image file (.png, .pfm or .exr)");
  renderCmd->add_option("scene", render.scene, "scene file (JSON) or model file (.obj, .gltf, .glb, .ply)")->required();
  renderCmd->add_option("-o,--output", render.output,
                        "output image: .png (sRGB 8-bit), .pfm (linear float) or .exr (linear float; OpenEXR); "
                        "required unless --inspect");
  renderCmd->add_flag("--exr-half", render.exrHalf, "write the .exr's channels as 16-bit half instead of 32-bit float");
  // Through a callback: CLI11 reads an empty value into a std::optional as "not given", and
  // `--aov ''` is an empty list, an error.
  renderCmd->add_option_function<std::string>(
      "--aov", [&render](const std::string& list) { render.aov = list; },
      "also write AOV layers into the .exr: a comma-separated list of depth, normal, albedo, "
      "spp, error, rays, or all (32-bit float channels such as depth.Z, normal.X)");
  renderCmd->add_option_function<std::string>(
      "--inspect", [&render](const std::string& pixel) { render.inspect = pixel; },
      "print, as JSON, every ray the kernel traces for pixel X,Y (its whole Whitted tree: eye, shadow, "
      "reflection and refraction rays, what each met and what it added to the pixel)");
  renderCmd->add_option("--inspect-out", render.inspectOutput,
                        "write --inspect's JSON to this file instead of standard output");
  renderCmd->add_flag("--stats", render.stats, "print timings, ray counts and rays per second as 'name: value' lines");
  renderCmd->add_flag("--explain", render.explain, "say which effects the scene calls for and what is compiled out");
  renderCmd->add_flag("-q,--quiet", render.quiet, "no progress bar");
  renderCmd->add_option("--band-ms", render.bandMs, "target GPU time per submission in ms (watchdog safety)")
      ->check(realRange(1.0, 10000.0));
  auto* frameOpt = renderCmd->add_option("--frame", render.frame, "render frame N of the scene's animation");
  renderCmd
      ->add_option("--frames", render.frames,
                   "render frames A-B in one process; -o then needs a frame number pattern (out_%04d.png)")
      ->excludes(frameOpt);
  renderCmd->add_option("--tile", render.tile,
                        "render only band I of N horizontal bands (I from 1), to a .pfm tile for 'vkray merge'");
  addRenderFlags(*renderCmd, render.render);
  addKernelFlags(*renderCmd, render.kernel);
  addModelFlags(*renderCmd, render.model);
  addDeviceFlags(*renderCmd, render.device);

  MergeArgs merge;
  auto* mergeCmd = app.add_subcommand("merge", "join tiles from 'render --tile' into the whole image");
  mergeCmd->add_option("-o,--output", merge.output, "output image: .png, .pfm or .exr")->required();
  mergeCmd->add_flag("--exr-half", merge.exrHalf, "write the .exr's channels as 16-bit half instead of 32-bit float");
  mergeCmd->add_option("tiles", merge.tiles, "tile files (.pfm, each with its .tile.json)")->required();

  auto* benchCmd = app.add_subcommand("bench", "benchmarks that print figures and ratios");
  benchCmd->require_subcommand(1);
  BenchTimeArgs benchTime;
  auto* benchTimeCmd = benchCmd->add_subcommand("time", "median GPU trace time of repeated renders");
  benchTimeCmd->add_option("scenes", benchTime.scenes, "scene files")->required();
  benchTimeCmd->add_option("--runs", benchTime.runs, "timed runs per scene (after one warm-up)")
      ->check(wholeRange(1, 1000));
  addRenderFlags(*benchTimeCmd, benchTime.render);
  addKernelFlags(*benchTimeCmd, benchTime.kernel);
  addDeviceFlags(*benchTimeCmd, benchTime.device);

  BenchSpecializeArgs benchSpec;
  auto* benchSpecCmd = benchCmd->add_subcommand("specialize", "specialized vs all-features pipelines, per scene");
  benchSpecCmd->add_option("scenes", benchSpec.scenes, "scene files (default: every bundled scene)");
  benchSpecCmd->add_option("--runs", benchSpec.runs, "timed runs per point")->check(wholeRange(1, 1000));
  benchSpecCmd->add_option("--height", benchSpec.height, "image height (aspect kept)")->check(wholeRange(8, 4096));
  addDeviceFlags(*benchSpecCmd, benchSpec.device);

  ViewArgs view;
  auto* viewCmd = addViewCommand(app, view);
  BenchViewArgs benchView;
  auto* benchViewCmd = addBenchViewCommand(*benchCmd, benchView);

  BenchMeshesArgs benchMeshes;
  auto* benchMeshesCmd =
      benchCmd->add_subcommand("meshes", "BVH build and ray throughput on procedural meshes, with Embree alongside");
  benchMeshesCmd->add_option("--sizes", benchMeshes.sizes, "triangle counts (approximate)")->delimiter(',');
  benchMeshesCmd->add_option("--width", benchMeshes.width, "image width")->check(wholeRange(8, 16384));
  benchMeshesCmd->add_option("--height", benchMeshes.height, "image height")->check(wholeRange(8, 16384));
  benchMeshesCmd->add_option("--runs", benchMeshes.runs, "timed runs per point")->check(wholeRange(1, 1000));
  benchMeshesCmd
      ->add_option("--rounds", benchMeshes.rounds,
                   "measure every size this many times, interleaved (round r of every size before round r+1 of "
                   "any), and print each ratio's median and range over the rounds")
      ->check(wholeRange(1, 1000));
  benchMeshesCmd->add_flag("--no-embree", benchMeshes.noEmbree, "skip the Embree side");
  benchMeshesCmd->add_flag("--no-entry-points", benchMeshes.noEntryPoints,
                           "vkray's eye rays walk the BVH from the root, not from their tile's entry points");
  benchMeshesCmd->add_flag("--no-shadow-entry-points", benchMeshes.noShadowEntryPoints,
                           "vkray's shadow rays walk the BVH from the root, not from their triangle's shadow entry "
                           "points");
  benchMeshesCmd->add_flag("--no-nothing-between", benchMeshes.noNothingBetween,
                           "vkray's shadow rays walk from their entry points also where nothing lies between their "
                           "triangle and the light (the table's entry points alone: --shadow-entry-points entries)");
  benchMeshesCmd->add_option("--csv", benchMeshes.csv, "also write the table as CSV (tools/plot-mesh-bench)");
  addDeviceFlags(*benchMeshesCmd, benchMeshes.device);

  BenchAccuracyArgs benchAcc;
  auto* benchAccCmd = benchCmd->add_subcommand("accuracy", "error against time for every accuracy knob");
  benchAccCmd->add_option("scenes", benchAcc.scenes,
                          "scene files (default: showcase, glass, seed, numerics-cracks, numerics-far-sphere, "
                          "numerics-huge-ground, textured)");
  benchAccCmd->add_option("--out", benchAcc.out, "output directory (CSV, reference and heat-map images)");
  benchAccCmd->add_option("--runs", benchAcc.runs, "timed runs per point, interleaved")->check(wholeRange(1, 1000));
  benchAccCmd->add_option("--height", benchAcc.height, "image height (aspect kept)")->check(wholeRange(8, 4096));
  benchAccCmd->add_option("--reference-spp", benchAcc.referenceSpp, "samples per pixel of the reference")
      ->check(wholeRange(1, 4096));
  benchAccCmd->add_flag("--quick", benchAcc.quick, "tiny images and few points (seconds)");
  benchAccCmd->add_flag("--count-instructions", benchAcc.countInstructions,
                        "under callgrind: render each point once at --count-height between client requests, no "
                        "timing (tools/accuracy-report --count-instructions)");
  benchAccCmd->add_option("--count-height", benchAcc.countHeight, "image height of --count-instructions")
      ->check(wholeRange(8, 4096));
  addDeviceFlags(*benchAccCmd, benchAcc.device);

  BenchAdaptiveArgs benchAdaptive;
  auto* benchAdaptiveCmd = benchCmd->add_subcommand(
      "adaptive", "a noise threshold against uniform sampling: time to the same 95th-percentile error");
  benchAdaptiveCmd->add_option("scenes", benchAdaptive.scenes,
                               "scene files (default: showcase, glass, seed, textured)");
  benchAdaptiveCmd->add_option("--runs", benchAdaptive.runs, "timed runs per point, interleaved")
      ->check(wholeRange(1, 1000));
  auto* adaptiveHeight = benchAdaptiveCmd->add_option("--height", benchAdaptive.height, "image height (aspect kept)")
                             ->check(wholeRange(8, 4096));
  benchAdaptiveCmd
      ->add_flag("--scene-size", benchAdaptive.sceneSize,
                 "each scene at its own image size (the bundled ones: 800x600, seed 640x480), where less of "
                 "the picture is edges than at --height's default 180 rows; minutes per scene")
      ->excludes(adaptiveHeight);
  benchAdaptiveCmd->add_option("--reference-spp", benchAdaptive.referenceSpp, "samples per pixel of the reference")
      ->check(wholeRange(1, 4096));
  benchAdaptiveCmd
      ->add_option("--reference-seed", benchAdaptive.referenceSeed,
                   "render.seed of the reference: 0 (default) shares its first samples with every point, another "
                   "seed none (its own noise then adds to every error: raise --reference-spp)")
      ->check(wholeRange(0ll, 0xFFFFFFFFll));
  benchAdaptiveCmd->add_option("--thresholds", benchAdaptive.thresholds, "noise thresholds, comma-separated")
      ->delimiter(',')
      ->allow_extra_args(false) // one argument, split at the commas: the scenes that follow stay scenes
      ->check(positiveReal(1e6));
  benchAdaptiveCmd->add_option("--min-spp", benchAdaptive.minSpp, "the thresholds' min_spp")
      ->check(wholeRange(1, 4096));
  benchAdaptiveCmd
      ->add_option("--max-spp", benchAdaptive.maxSpps,
                   "the thresholds' max_spp, comma-separated: each threshold is measured at each (default 1024)")
      ->delimiter(',')
      ->allow_extra_args(false)
      ->check(wholeRange(1, 4096));
  benchAdaptiveCmd->add_option("--max-uniform-spp", benchAdaptive.maxUniformSpp, "largest uniform point")
      ->check(wholeRange(1, 4096));
  addDeviceFlags(*benchAdaptiveCmd, benchAdaptive.device);

  BenchForwardArgs benchForward;
  auto* benchForwardCmd = benchCmd->add_subcommand(
      "forward", "forward against backward tracing: error against time, and the photons the lens catches");
  benchForwardCmd->add_option("scenes", benchForward.scenes, "scene files (default: seed, glass)");
  benchForwardCmd->add_option("--runs", benchForward.runs, "timed runs per point, interleaved")
      ->check(wholeRange(1, 1000));
  benchForwardCmd->add_option("--height", benchForward.height, "image height (aspect kept)")
      ->check(wholeRange(8, 4096));
  benchForwardCmd->add_option("--aperture", benchForward.aperture, "lens radius, as a fraction of the focus distance")
      ->check(positiveReal(1.0));
  benchForwardCmd->add_option("--reference-spp", benchForward.referenceSpp, "samples per pixel of the reference")
      ->check(wholeRange(1, 4096));
  benchForwardCmd->add_option("--max-spp", benchForward.maxSpp, "largest backward point")->check(wholeRange(1, 4096));
  benchForwardCmd->add_option("--min-photons", benchForward.minPhotons, "smallest forward point (photons per light)")
      ->check(wholeRange(1ll, kMaxPhotons));
  benchForwardCmd->add_option("--max-photons", benchForward.maxPhotons, "largest forward point (x4 steps)")
      ->check(wholeRange(1ll, kMaxPhotons));
  benchForwardCmd->add_option("--csv", benchForward.csv, "write every point to this CSV (tools/forward-plot)");
  addDeviceFlags(*benchForwardCmd, benchForward.device);

  DeviceFlags infoFlags;
  auto* infoCmd = app.add_subcommand("info", "list Vulkan devices and the features vkray uses");
  infoCmd->add_option("--device", infoFlags.device, "also create a context on this device")->envname("VKRAY_DEVICE");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help prints as CLI11 does; a bad command line is one line and exit 1 like every other
    // error ("vkray: error: --spp: Value 4097 not in range 1 to 4096").
    if (e.get_exit_code() == 0) return app.exit(e);
    std::fprintf(stderr, "vkray: error: %s%s\n", e.what(), didYouMean(app, argc, argv).c_str());
    return 1;
  }

  try {
    if (*renderCmd) return runRender(render);
    if (*mergeCmd) return runMerge(merge);
    if (*infoCmd) return runInfo(infoFlags);
    if (*viewCmd) return runView(view);
    if (*benchTimeCmd) return runBenchTime(benchTime);
    if (*benchAccCmd) return runBenchAccuracy(benchAcc);
    if (*benchAdaptiveCmd) return runBenchAdaptive(benchAdaptive);
    if (*benchForwardCmd) return runBenchForward(benchForward);
    if (*benchMeshesCmd) return runBenchMeshes(benchMeshes);
    if (*benchSpecCmd) return runBenchSpecialize(benchSpec);
    if (*benchViewCmd) return runBenchView(benchView);
  } catch (const CancelledError&) {
    std::fprintf(stderr, "vkray: interrupted; no output written\n");
    return 130;
  } catch (const Error& e) {
    std::fprintf(stderr, "vkray: error: %s\n", e.what());
    return 1;
  } catch (const std::bad_alloc&) {
    // What vkray can foresee it refuses before allocating (checkProgressiveMemory); this is the rest.
    std::fprintf(stderr, "vkray: error: out of host memory\n");
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "vkray: internal error: %s\n", e.what());
    return 2;
  }
  return 0;
}
