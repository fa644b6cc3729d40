// `vkray view`: the interactive viewer's command line. The viewer itself lives in host/viewer/.
#include "app/view_command.h"

#include <cstdio>

#include "render/ray_tree.h"
#include "scene/scene_loader.h"
#include "util/error.h"
#include "viewer/viewer.h"

namespace vkray {

CLI::App* addViewCommand(CLI::App& app, ViewArgs& a) {
  auto* cmd = app.add_subcommand("view", "open a window on a scene: fly around, change settings live");
  cmd->add_option("scene", a.scene,
                  "scene file (JSON) or model file (.obj, .gltf, .glb, .ply); reloaded when it changes")
      ->required();
  cmd->add_option("--frames", a.frames, "scripted: trace this many frames, save --screenshot, exit")
      ->check(wholeRange(1u, 1u << 20));
  cmd->add_option("--screenshot", a.screenshot,
                  "screenshot file (.png, .pfm or .exr): written after --frames; otherwise where the P key saves");
  cmd->add_flag("--no-vsync", a.noVsync, "present without waiting for vertical blank (MAILBOX or IMMEDIATE)");
  cmd->add_option("--max-samples", a.maxSamples, "samples per pixel at which accumulation stops")
      ->check(wholeRange(1u, 1u << 24));
  cmd->add_option("--scale", a.scale, "render resolution relative to the window (the blit scales it up)")
      ->check(CLI::IsMember({1.0, 0.5, 0.25}));
  cmd->add_option("--motion-scale", a.motionScale,
                  "further resolution scale while the camera moves (default 0.5 on CPU devices, else 1)")
      ->check(CLI::IsMember({1.0, 0.5, 0.25}));
  cmd->add_flag("--no-overlay", a.noOverlay, "start with the overlay hidden (H shows it)");
  cmd->add_flag("--no-ray-counts", a.noRayCounts,
                "start with the ray counters off (on, they count one frame in 16, which costs 10-20 % more)");
  cmd->add_flag("--no-direct-resolve", a.noDirectResolve,
                "always resolve into an intermediate image and blit it, even where the window's images could "
                "be written directly (for comparison)");
  cmd->add_flag("--stats", a.stats, "print frame timings as 'name: value' lines at exit");
  cmd->add_option("--spin", a.spin, "orbit the camera by this many degrees per frame (benchmarks)");
  cmd->add_option("--resize-to", a.resizeTo, "scripted: resize the window to WxH halfway through (tests)");
  cmd->add_option("--screenshot-window", a.windowScreenshot,
                  "scripted: also save the window as shown, overlay included (.png, .pfm or .exr)");
  cmd->add_option("--display", a.display,
                  "what the window shows at start (M cycles): the image, the estimated error per pixel or the rays "
                  "traced per sample (cost), as heat maps; in a map, --screenshot holds its values")
      ->check(CLI::IsMember(enumNameList<DisplayMode>()));
  cmd->add_option("--inspect", a.inspect,
                  "show pixel X,Y's ray tree at start, as clicking on it does (in pixels of the rendered image)");
  addRenderFlags(*cmd, a.render);
  addKernelFlags(*cmd, a.kernel);
  addModelFlags(*cmd, a.model);
  addDeviceFlags(*cmd, a.device);
  return cmd;
}

namespace {

// What `view` and `bench view` set alike: the scene, the render, kernel and device flags.
ViewerOptions baseViewerOptions(const std::filesystem::path& scene, const RenderFlags& render,
                                const KernelFlags& kernel, const DeviceFlags& device) {
  ViewerOptions o;
  o.scene = scene;
  o.applyOverrides = [flags = render](RenderSettings& s) {
    applyRenderFlags(flags, s);
    s.method = Method::Backward; // the viewer traces backward; forward tracing is headless (docs/forward.md)
  };
  // --spp is what each frame adds; the scene's spp is for headless renders.
  o.samplesPerFrame = render.spp;
  o.windowWidth = render.width;
  o.windowHeight = render.height;
  o.device = device;
  applyKernelFlags(kernel, o.render);
  return o;
}

} // namespace

int runView(const ViewArgs& a) {
  ViewerOptions o = baseViewerOptions(a.scene, a.render, a.kernel, a.device);
  o.model = modelSceneOptions(a.model, a.scene);
  o.directResolve = !a.noDirectResolve;
  o.vsync = !a.noVsync;
  o.renderScale = a.scale;
  o.motionScale = a.motionScale;
  o.maxSamples = a.maxSamples;
  o.overlay = !a.noOverlay;
  o.countStats = !a.noRayCounts;
  o.frames = a.frames;
  o.screenshot = a.screenshot;
  o.spinDegrees = a.spin;
  o.printStats = a.stats;
  o.windowScreenshot = a.windowScreenshot;
  o.display = parseEnum<DisplayMode>(a.display).value_or(DisplayMode::Image);
  // The image's size is known once the window is: the viewer checks the pixel lies inside it.
  if (!a.inspect.empty()) o.inspect = parsePixel(a.inspect, UINT32_MAX, UINT32_MAX, "--inspect");
  if (!a.resizeTo.empty()) {
    unsigned w = 0, h = 0;
    char x = 0;
    if (std::sscanf(a.resizeTo.c_str(), "%u%c%u", &w, &x, &h) != 3 || x != 'x' || w == 0 || h == 0) {
      throw InputError("--resize-to", "expected WIDTHxHEIGHT, got '" + a.resizeTo + "'");
    }
    if (a.frames == 0) throw InputError("--resize-to", "needs --frames (it is for scripted runs)");
    o.resizeToWidth = w;
    o.resizeToHeight = h;
  }
  return runViewer(o);
}

CLI::App* addBenchViewCommand(CLI::App& bench, BenchViewArgs& a) {
  auto* cmd = bench.add_subcommand("view", "viewer frames per second and where a frame's time goes (needs a display)");
  cmd->add_option("scenes", a.scenes, "scene files")->required();
  cmd->add_option("--frames", a.frames, "timed frames per row (after 5 warm-up frames)")
      ->check(wholeRange(1u, 100000u));
  cmd->add_option("--spin", a.spin, "degrees the camera orbits per frame in the moving rows");
  addRenderFlags(*cmd, a.render);
  addKernelFlags(*cmd, a.kernel);
  addDeviceFlags(*cmd, a.device);
  return cmd;
}

int runBenchView(const BenchViewArgs& a) {
  struct Row {
    const char* name;
    bool counters, overlay, moving;
    std::optional<double> motionScale; // default: the viewer's (0.5 on CPU devices)
    double scale = 1.0;
  };
  // The viewer's defaults first, then one change at a time.
  const Row rows[] = {
      {"still, overlay, ray counts", true, true, false, std::nullopt},
      {"still, overlay", false, true, false, std::nullopt},
      {"still", false, false, false, std::nullopt},
      {"moving, overlay", false, true, true, std::nullopt},
      {"moving, overlay, full res", false, true, true, 1.0},
      {"still, overlay, --scale 0.5", false, true, false, std::nullopt, 0.5},
  };
  for (const auto& path : a.scenes) {
    bool header = false;
    for (const Row& row : rows) {
      ViewerOptions o = baseViewerOptions(path, a.render, a.kernel, a.device);
      o.vsync = false; // the frame rate of the work, not of the display
      o.countStats = row.counters;
      o.overlay = row.overlay;
      o.spinDegrees = row.moving ? a.spin : 0.0;
      o.motionScale = row.motionScale;
      o.renderScale = row.scale;
      o.frames = a.frames + 5; // the viewer leaves the first 5 out of its figures
      ViewerSummary v;
      o.summary = &v;
      runViewer(o);
      if (!header) {
        Scene scene = loadScene(path);
        applyRenderFlags(a.render, scene.render);
        std::printf("%s: window %ux%u, max_depth %d, %s, %s\n", path.string().c_str(), v.windowWidth, v.windowHeight,
                    scene.render.maxDepth, v.device.c_str(), v.presentMode.c_str());
        std::printf("%-27s %9s %6s %8s %7s %7s %6s %7s %6s %7s %7s  %s\n", "", "render", "fps", "frame", "trace",
                    "resolve", "blit", "overlay", "host", "present", "trace%", "path");
        header = true;
      }
      char size[32];
      std::snprintf(size, sizeof size, "%ux%u", v.renderWidth, v.renderHeight);
      // GPU parts from timestamps; host = the loop's own CPU time; present = in acquire + present,
      // which on lavapipe includes waiting for the frame's GPU work; path = the last frame's resolve
      // path (presenter.h: a moving camera's smaller render is blitted).
      std::printf("%-27s %9s %6.1f %8.2f %7.2f %7.2f %6.2f %7.2f %6.2f %7.2f %6.0f%%  %s\n", row.name, size, v.fps(),
                  v.frameMs, v.traceMs, v.resolveMs, v.blitMs, v.overlayMs, v.hostMs, v.presentMs,
                  v.frameMs > 0 ? 100.0 * v.traceMs / v.frameMs : 0.0, v.resolvePath.c_str());
      std::fflush(stdout);
    }
  }
  return 0;
}

} // namespace vkray
