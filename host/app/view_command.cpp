// `vkray view`: the interactive viewer's command line. The viewer itself lives in host/viewer/.
#include "app/view_command.h"

#include "util/error.h"
#include "viewer/viewer.h"

namespace vkray {

CLI::App* addViewCommand(CLI::App& app, ViewArgs& a) {
  auto* cmd = app.add_subcommand("view", "open a window on a scene: fly around, change settings live");
  cmd->add_option("scene", a.scene, "scene file (JSON); reloaded when it changes")->required();
  cmd->add_option("--frames", a.frames, "scripted: trace this many frames, save --screenshot, exit")
      ->check(CLI::Range(1u, 1u << 20));
  cmd->add_option("--screenshot", a.screenshot,
                  "screenshot file (.png or .pfm): written after --frames; otherwise where the P key saves");
  cmd->add_flag("--no-vsync", a.noVsync, "present without waiting for vertical blank (MAILBOX or IMMEDIATE)");
  cmd->add_option("--max-samples", a.maxSamples, "samples per pixel at which accumulation stops")
      ->check(CLI::Range(1u, 1u << 24));
  cmd->add_option("--scale", a.scale, "render resolution relative to the window (the blit scales it up)")
      ->check(CLI::IsMember({1.0, 0.5, 0.25}));
  cmd->add_option("--motion-scale", a.motionScale,
                  "further resolution scale while the camera moves (default 0.5 on CPU devices, else 1)")
      ->check(CLI::IsMember({1.0, 0.5, 0.25}));
  cmd->add_flag("--no-overlay", a.noOverlay, "start with the overlay hidden (H shows it)");
  cmd->add_flag("--no-ray-counts", a.noRayCounts, "start with the ray counters off (they cost about 20 %)");
  cmd->add_flag("--no-specialize", a.noSpecialize, "compile every feature in (for comparison)");
  cmd->add_flag("--stats", a.stats, "print frame timings as 'name: value' lines at exit");
  cmd->add_option("--spin", a.spin, "orbit the camera by this many degrees per frame (benchmarks)");
  cmd->add_option("--resize-to", a.resizeTo, "scripted: resize the window to WxH halfway through (tests)");
  addRenderFlags(*cmd, a.render);
  addDeviceFlags(*cmd, a.device);
  return cmd;
}

int runView(const ViewArgs& a) {
  ViewerOptions o;
  o.scene = a.scene;
  o.applyOverrides = [flags = a.render](RenderSettings& s) { applyRenderFlags(flags, s); };
  // --spp is what each frame adds; the scene's spp is for headless renders.
  o.samplesPerFrame = a.render.spp;
  o.windowWidth = a.render.width;
  o.windowHeight = a.render.height;
  o.device = a.device.device;
  o.validate = a.device.validate;
  o.syncValidate = a.device.syncValidate;
  o.pipelineCache = !a.device.noPipelineCache;
  o.specialize = !a.noSpecialize;
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

} // namespace vkray
