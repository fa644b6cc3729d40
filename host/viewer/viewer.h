// `vkray view`: opens a window on a scene and drives the same Renderer as the headless command,
// progressively, with an overlay, camera control and hot reload. Scripted runs (frames > 0) trace a
// fixed number of frames, save a screenshot and exit.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>

#include "render/renderer.h"
#include "scene/scene.h"

namespace vkray {

struct ViewerOptions {
  std::filesystem::path scene;
  // Command-line overrides of the scene's settings, re-applied after every reload.
  std::function<void(RenderSettings&)> applyOverrides;
  std::optional<int> samplesPerFrame; // --spp; default 1 (the scene's spp is a headless setting)

  std::string device;
  bool validate = false;
  bool syncValidate = false;
  bool pipelineCache = true;
  bool specialize = true;

  bool vsync = true;
  std::optional<std::uint32_t> windowWidth; // default: the scene's image size
  std::optional<std::uint32_t> windowHeight;
  double renderScale = 1.0;          // render resolution relative to the window
  std::optional<double> motionScale; // while the camera moves; default 0.5 on CPU devices, else 1
  std::uint32_t maxSamples = 4096;   // accumulation stops here
  bool overlay = true;               // shown at start (H toggles)
  bool countStats = true;            // ray counters at start

  std::uint32_t frames = 0;                   // scripted: trace this many frames, then exit
  std::filesystem::path screenshot;           // scripted: written at exit; interactive: where P saves
  std::optional<std::uint32_t> resizeToWidth; // scripted: resize the window halfway (tests)
  std::optional<std::uint32_t> resizeToHeight;
  double spinDegrees = 0.0; // orbit the camera by this much per frame (benchmarks)
  bool printStats = false;  // timing summary as `name: value` lines at exit
};

int runViewer(const ViewerOptions& options);

} // namespace vkray
