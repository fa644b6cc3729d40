// vkray: a Whitted ray tracer in a Vulkan compute shader. The command line: render | view | bench | info.
#include <cstdio>
#include <exception>

#include <CLI/CLI.hpp>

#include "app/bench.h"
#include "app/commands.h"
#include "util/error.h"

int main(int argc, char** argv) {
  using namespace vkray;
  CLI::App app{"vkray: Whitted-style ray tracing in a Vulkan compute shader"};
  app.require_subcommand(1);

  RenderArgs render;
  auto* renderCmd = app.add_subcommand("render", "render a scene to an image file (.png or .pfm)");
  renderCmd->add_option("scene", render.scene, "scene file (JSON)")->required();
  renderCmd->add_option("-o,--output", render.output, "output image: .png (sRGB 8-bit) or .pfm (linear float)")
      ->required();
  renderCmd->add_flag("--stats", render.stats, "print timings, ray counts and rays per second as 'name: value' lines");
  renderCmd->add_flag("--explain", render.explain, "say which effects the scene calls for and what is compiled out");
  renderCmd->add_flag("-q,--quiet", render.quiet, "no progress bar");
  renderCmd->add_flag("--no-specialize", render.noSpecialize, "compile every feature in (for comparison)");
  renderCmd->add_option("--band-ms", render.bandMs, "target GPU time per submission in ms (watchdog safety)")
      ->check(CLI::Range(1.0, 10000.0));
  renderCmd
      ->add_option("--scene-memory", render.sceneMemory,
                   "where the kernel reads small scenes from: auto, uniform or storage buffers")
      ->check(CLI::IsMember({"auto", "uniform", "storage"}));
  addRenderFlags(*renderCmd, render.render);
  addDeviceFlags(*renderCmd, render.device);

  auto* benchCmd = app.add_subcommand("bench", "benchmarks that print figures and ratios");
  benchCmd->require_subcommand(1);
  BenchTimeArgs benchTime;
  auto* benchTimeCmd = benchCmd->add_subcommand("time", "median GPU trace time of repeated renders");
  benchTimeCmd->add_option("scenes", benchTime.scenes, "scene files")->required();
  benchTimeCmd->add_option("--runs", benchTime.runs, "timed runs per scene (after one warm-up)")
      ->check(CLI::Range(1, 1000));
  benchTimeCmd->add_flag("--no-specialize", benchTime.noSpecialize, "compile every feature in");
  benchTimeCmd->add_option("--scene-memory", benchTime.sceneMemory, "auto, uniform or storage")
      ->check(CLI::IsMember({"auto", "uniform", "storage"}));
  addRenderFlags(*benchTimeCmd, benchTime.render);
  addDeviceFlags(*benchTimeCmd, benchTime.device);

  DeviceFlags infoFlags;
  auto* infoCmd = app.add_subcommand("info", "list Vulkan devices and the features vkray uses");
  infoCmd->add_option("--device", infoFlags.device, "also create a context on this device")->envname("VKRAY_DEVICE");

  CLI11_PARSE(app, argc, argv);

  try {
    if (*renderCmd) return runRender(render);
    if (*infoCmd) return runInfo(infoFlags);
    if (*benchTimeCmd) return runBenchTime(benchTime);
  } catch (const CancelledError&) {
    std::fprintf(stderr, "vkray: interrupted; no output written\n");
    return 130;
  } catch (const Error& e) {
    std::fprintf(stderr, "vkray: error: %s\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "vkray: internal error: %s\n", e.what());
    return 2;
  }
  return 0;
}
