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
#include "scene/model_scene.h"
#include "scene/scene.h"
#include "viewer/convergence.h"
#include "viewer/view_settings.h"
#include "vk/device_flags.h"

namespace vkray {

// Per-frame averages of a scripted run (warm-up frames left out), for --stats and `bench view`.
struct ViewerSummary {
  std::string device;
  std::string presentMode;
  std::string resolvePath; // "direct" (into the swapchain image) or "blit", as of the last frame
  std::uint32_t renderWidth = 0, renderHeight = 0;
  std::uint32_t windowWidth = 0, windowHeight = 0;
  std::uint32_t frames = 0; // frames timed
  double frameMs = 0.0;     // wall time between frames
  double traceMs = 0.0;     // GPU (timestamps): the Renderer's dispatch
  double resolveMs = 0.0;   // GPU: sums copied to an image and resolved to display colour
  double blitMs = 0.0;      // GPU: blit to the swapchain image (a layout transition on the direct path)
  double overlayMs = 0.0;   // GPU: the overlay's render pass
  double presentMs = 0.0;   // CPU: in acquire and present (on lavapipe this includes waiting for the GPU)
  double hostMs = 0.0;      // CPU: the frame loop itself (input, overlay UI, recording, submission)
  double waitMs = 0.0;      // CPU: blocked on frame fences
  bool rayCounts = false;
  std::uint64_t countedFrames = 0; // frames traced with the ray counters (a sample of them, viewer.cpp)
  double raysPerFrame = 0.0;
  double mraysPerSecond = 0.0;              // rays / trace time
  std::uint32_t samples = 0;                // samples per pixel at the end
  double minimizedMs = 0.0;                 // time the window spent minimized (nothing traced)
  DisplayMode display = DisplayMode::Image; // what the window showed at the end
  double noiseThreshold = 0.0;              // convergence judged at this threshold
  bool defaultThreshold = false;            // kDefaultViewThreshold: neither scene nor flag set one
  ConvergenceFigures convergence;           // of the last frame
  std::optional<glm::uvec2> inspectedPixel; // the pixel whose ray tree the overlay shows
  std::size_t inspectedRays = 0;            // rays in that tree
  double fps() const { return frameMs > 0 ? 1000.0 / frameMs : 0.0; }
  double gpuMs() const { return traceMs + resolveMs + blitMs + overlayMs; }
};

struct ViewerOptions {
  std::filesystem::path scene;
  ModelSceneOptions model; // when `scene` is a model file (--floor, --background)
  // Command-line overrides of the scene's settings, re-applied after every reload.
  std::function<void(RenderSettings&)> applyOverrides;
  std::optional<int> samplesPerFrame; // --spp; default 1 (the scene's spp is a headless setting)

  DeviceFlags device;   // the context (contextOptions) and the pipeline cache
  RenderOptions render; // specialize, cullRows, entryPoints, sceneMemory; the viewer sets the rest per frame

  bool vsync = true;
  bool directResolve = true;                // the resolve pass writes the swapchain image where it can (presenter.h)
  std::optional<std::uint32_t> windowWidth; // default: the scene's image size
  std::optional<std::uint32_t> windowHeight;
  double renderScale = 1.0;                 // render resolution relative to the window
  std::optional<double> motionScale;        // while the camera moves; default 0.5 on CPU devices, else 1
  std::uint32_t maxSamples = 4096;          // accumulation stops here
  bool overlay = true;                      // shown at start (H toggles)
  bool countStats = true;                   // ray counters at start
  DisplayMode display = DisplayMode::Image; // at start (M cycles); a scripted run's screenshot holds
                                            // a map's values (error, or rays per sample) in each channel

  std::uint32_t frames = 0;                   // scripted: trace this many frames, then exit
  std::filesystem::path screenshot;           // scripted: written at exit; interactive: where P saves
  std::optional<std::uint32_t> resizeToWidth; // scripted: resize the window halfway (tests)
  std::optional<std::uint32_t> resizeToHeight;
  double spinDegrees = 0.0; // orbit the camera by this much per frame (benchmarks)
  bool printStats = false;  // timing summary as `name: value` lines at exit
  // Scripted: the window's last frame as shown (overlay included), read back from the swapchain image.
  std::filesystem::path windowScreenshot;
  // The pixel (of the render size) whose ray tree is shown at start, as a click on it would (tests, docs).
  std::optional<glm::uvec2> inspect;
  ViewerSummary* summary = nullptr; // filled at exit when set
};

int runViewer(const ViewerOptions& options);
// The summary as `name: value` lines on stdout (--stats).
void printViewerSummary(const ViewerSummary& summary);

} // namespace vkray
