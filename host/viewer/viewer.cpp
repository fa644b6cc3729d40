// The viewer's frame loop: it owns the window's pieces (swapchain, presenter, overlay, frames in
// flight) and the camera and settings, and each frame turns input into changes, applies them to the
// Renderer, traces and presents.
#include "viewer/viewer.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>

#include "../../shaders/shared/resolve_types.h"
#include "image/image_io.h"
#include "scene/features.h"
#include "util/error.h"
#include "viewer/camera_controller.h"
#include "viewer/convergence.h"
#include "viewer/frames.h"
#include "viewer/overlay.h"
#include "viewer/presenter.h"
#include "viewer/scene_watcher.h"
#include "viewer/swapchain.h"
#include "viewer/view_settings.h"
#include "viewer/window.h"
#include "vk/buffer.h"
#include "vk/compute_pipeline.h"
#include "vk/context.h"

namespace vkray {

namespace {

using Clock = std::chrono::steady_clock;

double msBetween(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

bool sameCamera(const Camera& a, const Camera& b) {
  return a.position == b.position && a.lookAt == b.lookAt && a.up == b.up && a.fovY == b.fovY;
}

std::string presentModeName(vk::PresentModeKHR mode) {
  switch (mode) {
  case vk::PresentModeKHR::eFifo:
    return "vsync (FIFO)";
  case vk::PresentModeKHR::eMailbox:
    return "no vsync (MAILBOX)";
  case vk::PresentModeKHR::eImmediate:
    return "no vsync (IMMEDIATE)";
  default:
    return vk::to_string(mode);
  }
}

// Waits for the device before the GPU objects declared ahead of it are destroyed, also when the loop
// exits by an exception.
struct IdleOnExit {
  const vulkan::Context& context;
  ~IdleOnExit() {
    try {
      context.device().waitIdle();
    } catch (...) {
    }
  }
};

// Per-frame averages over an interval, for the overlay and the --stats summary.
struct FrameTimes {
  double wallMs = 0.0;
  double hostMs = 0.0;
  double waitMs = 0.0;    // blocked on fences
  double presentMs = 0.0; // in acquire and present
  FrameGpuTimes gpu;
  std::uint32_t frames = 0;    // wall/host/present samples
  std::uint32_t gpuFrames = 0; // GPU samples

  void add(const FrameRing::Completed& c) {
    gpu.trace += c.sum.trace;
    gpu.resolve += c.sum.resolve;
    gpu.blit += c.sum.blit;
    gpu.overlay += c.sum.overlay;
    gpuFrames += c.frames;
  }
  double per(double sum, std::uint32_t n) const { return n > 0 ? sum / n : 0.0; }
};

class FrameLoop {
public:
  FrameLoop(const ViewerOptions& options, Window& window, const vulkan::Context& context, vulkan::PipelineCache* cache,
            SceneWatcher& watcher, Scene scene)
      : o_(options), window_(window), context_(context), watcher_(watcher), scene_(std::move(scene)),
        swapchain_(context, window.createSurface(context.instance()), options.vsync), renderer_(context, cache),
        presenter_(context, cache, swapchain_.encodeInShader(), options.directResolve), convergence_(context, cache),
        frames_(context), camera_(scene_.camera) {
    settings_.render = scene_.render;
    settings_.samplesPerFrame = options.samplesPerFrame.value_or(1);
    settings_.maxSamples = options.maxSamples;
    settings_.countStats = options.countStats;
    settings_.renderScale = options.renderScale;
    settings_.display = options.display;
    // A CPU device cannot trace full frames at interactive rates: while the camera moves, fewer pixels.
    settings_.motionScale = options.motionScale.value_or(context.info().type == "CPU" ? 0.5 : 1.0);
    if (scripted()) {
      // A scripted run traces exactly the frames asked for.
      settings_.maxSamples = std::max<std::uint32_t>(settings_.maxSamples, o_.frames * settings_.samplesPerFrame);
    }
    lastFramebuffer_ = window.framebufferSize();
    if (!swapchain_.recreate(lastFramebuffer_)) swapchainStale_ = true;
    overlay_ = std::make_unique<Overlay>(context, window, swapchain_);
    overlay_->visible = options.overlay;
    presenter_.attach(swapchain_, overlay_->layerView());
    inspectPixel_ = options.inspect;
  }

  int run();

private:
  bool scripted() const { return o_.frames > 0; }
  vk::Extent2D renderSize() const;
  void recreateSwapchain(vk::Extent2D framebuffer);
  bool handleInput(const InputFrame& input, double dtSeconds);
  void handleAction(ViewerAction action);
  void applyChanges(const ViewSettings& edited, bool sceneReloaded, bool cameraChanged);
  // The settings of the frames' renders at the current size (applyChanges prepares with them).
  RenderSettings frameSettings() const;
  // Traces inspectPixel_'s ray tree (the Renderer's recording kernel, one pixel) into rayTree_;
  // the frames' pipelines are prepared again and the image restarts.
  void inspectPending();
  void quiesce();
  void collectStats();
  void publishStats(bool force);
  // A changed scene file: follows what was edited in it (into `edited`) and says whether it reloaded.
  bool followReload(ViewSettings& edited);
  // Scripted runs: counts the frame, resizes halfway when asked, and says whether the script is done.
  bool scriptFinished(const Accumulation::Step& step);
  void recordFrame(FrameRing::Slot& slot, const Accumulation::Step& step, std::uint32_t imageIndex, bool captureWindow,
                   bool countRays, bool measure);
  // The noise threshold convergence is judged by: the scene's or --noise-threshold, else the default.
  double threshold() const {
    return settings_.render.noiseThreshold > 0.0 ? settings_.render.noiseThreshold : kDefaultViewThreshold;
  }
  // Points the resolve pass at what the display mode shows.
  void applyDisplay();
  bool takeCountTurn(const Accumulation::Step& step);
  bool finishesScript(const Accumulation::Step& step) const;
  void prepareWindowCapture();
  void saveWindowScreenshot(const std::filesystem::path& path);
  void saveScreenshot(const std::filesystem::path& path);
  void saveCamera();
  std::filesystem::path nextScreenshotPath() const;
  OverlayModel overlayModel() const;
  ViewerSummary summarize() const;

  const ViewerOptions& o_;
  Window& window_;
  const vulkan::Context& context_;
  SceneWatcher& watcher_;
  Scene scene_; // the last good scene with the command-line overrides applied

  // GPU objects, in dependency order; IdleOnExit, declared last, is destroyed first.
  Swapchain swapchain_;
  Renderer renderer_;
  Presenter presenter_;
  ConvergenceMeter convergence_;
  FrameRing frames_;
  std::unique_ptr<Overlay> overlay_;
  std::unique_ptr<vulkan::Buffer> windowPixels_; // --screenshot-window: the last frame as shown
  IdleOnExit idle_{context_};

  CameraController camera_;
  ViewSettings settings_;
  Accumulation accumulation_;
  bool swapchainStale_ = false;
  static constexpr double kMotionHoldMs = 150.0;
  std::optional<Clock::time_point> lastCameraChange_;
  bool moving_ = false;                // the camera changed within kMotionHoldMs: render at motionScale
  vk::Extent2D lastFramebuffer_{0, 0}; // the window size the swapchain was made for
  bool prepared_ = false;
  std::uint32_t tracedFrames_ = 0; // scripted: frames traced at the current render size
  bool lastResolveDirect_ = false; // the last frame's resolve wrote the swapchain image (presenter.h)
  double minimizedMs_ = 0.0;       // time spent minimized, tracing nothing
  bool resizeRequested_ = false;
  Clock::time_point resizeRequestedAt_{};
  vk::Extent2D windowPixelsExtent_{0, 0};
  bool windowCaptured_ = false;
  bool pixelRays_ = false;                        // the Renderer counts rays per pixel (the cost map)
  DisplayMode shownDisplay_ = DisplayMode::Image; // what the resolve pass is built to show
  // The convergence figures: measured in one frame per statistics interval (and a script's last),
  // read once that frame has completed.
  bool measureDue_ = true;
  bool measurePending_ = false;
  ConvergenceFigures figures_;

  // Statistics for the overlay: averages over the last interval, and totals for --stats.
  FrameTimes interval_;
  RayStats intervalRays_;
  FrameTimes shown_;
  // The sample count the overlay shows: updated with the figures, twice a second, or at once when
  // accumulation restarts; a panel that changes in nothing is not redrawn (Overlay::recordLayer).
  std::uint32_t shownSamples_ = 0;
  FrameTimes total_;
  std::uint64_t totalRays_ = 0;
  // Rays are counted in a sample of the frames (takeCountTurn): those in the interval and in total.
  std::uint32_t countedInInterval_ = 0;
  std::uint64_t totalCounted_ = 0;
  std::uint32_t framesSinceCount_ = 0;
  Clock::time_point statsTaken_ = Clock::now();
  RayStats raysPerFrame_;
  double raysPerSecond_ = 0.0;
  std::string status_;
  std::optional<glm::uvec2> inspectPixel_; // a click (or --inspect) waiting to be inspected
  std::optional<RayTree> rayTree_;         // the last inspected pixel's tree
  bool restartRequested_ = false;          // prepare and restart the image at the next applyChanges
};

vk::Extent2D FrameLoop::renderSize() const {
  vk::Extent2D e = swapchain_.extent();
  auto scaled = [&](std::uint32_t v) {
    double scale = settings_.renderScale * (moving_ ? settings_.motionScale : 1.0);
    return std::max<std::uint32_t>(1, static_cast<std::uint32_t>(std::lround(v * scale)));
  };
  return {scaled(e.width), scaled(e.height)};
}

void FrameLoop::recreateSwapchain(vk::Extent2D framebuffer) {
  quiesce();
  // The overlay's framebuffers name the old image views: gone first. Presentation may still hold the
  // old images; re-creation with oldSwapchain hands them over.
  overlay_->detach();
  presenter_.detach();
  swapchainStale_ = !swapchain_.recreate(framebuffer);
  lastFramebuffer_ = framebuffer;
  if (!swapchainStale_) {
    overlay_->attach(swapchain_);
    presenter_.attach(swapchain_, overlay_->layerView());
  }
}

void FrameLoop::quiesce() {
  auto start = Clock::now();
  frames_.waitAll();
  interval_.waitMs += msBetween(start, Clock::now());
}

bool FrameLoop::handleInput(const InputFrame& input, double dtSeconds) {
  CameraInput in;
  in.viewportHeight = window_.heightInCursorUnits(); // drags come in the cursor's units
  in.dtSeconds = dtSeconds;
  if (!overlay_->wantsMouse() && input.click) {
    // The clicked point of the window, in pixels of the rendered image (the presenter scales it).
    const vk::Extent2D size = renderSize();
    auto at = [](double f, std::uint32_t n) {
      return static_cast<std::uint32_t>(std::clamp(f * n, 0.0, static_cast<double>(n - 1)));
    };
    inspectPixel_ = glm::uvec2(at(input.click->x, size.width), at(input.click->y, size.height));
  }
  if (!overlay_->wantsMouse()) {
    bool pan = input.rightDown || input.middleDown || (input.leftDown && input.shift);
    bool orbit = input.leftDown && !pan;
    if (pan || orbit) in.drag = input.cursorDelta;
    in.panDrag = pan;
    in.orbitDrag = orbit;
    in.scroll = input.scroll;
  }
  if (!overlay_->wantsKeyboard()) {
    in.move = input.move;
    in.fast = input.shift;
    for (ViewerAction a : input.actions) handleAction(a);
  }
  return camera_.apply(in);
}

void FrameLoop::handleAction(ViewerAction action) {
  switch (action) {
  case ViewerAction::ToggleFly:
    camera_.setMode(camera_.mode() == CameraMode::Orbit ? CameraMode::Fly : CameraMode::Orbit);
    break;
  case ViewerAction::ResetCamera:
    camera_.reset();
    break;
  case ViewerAction::SaveCamera:
  case ViewerAction::Screenshot:
    // A file that cannot be written is reported, and the viewer goes on.
    try {
      if (action == ViewerAction::SaveCamera)
        saveCamera();
      else
        saveScreenshot(nextScreenshotPath());
    } catch (const InputError& e) {
      status_ = e.what();
      std::fprintf(stderr, "vkray: %s\n", e.what());
    }
    break;
  case ViewerAction::ToggleOverlay:
    overlay_->visible = !overlay_->visible;
    break;
  case ViewerAction::CycleDisplay:
    settings_.display = nextDisplayMode(settings_.display);
    break;
  case ViewerAction::Quit:
    window_.requestClose();
    break;
  }
}

void FrameLoop::applyChanges(const ViewSettings& edited, bool sceneReloaded, bool cameraChanged) {
  const bool effectsChanged = !(edited.effects == settings_.effects);
  // Samples per frame and the cap need no restart: the next frame continues the same sequence.
  const bool knobsChanged = !sameKnobs(edited.render, settings_.render) || edited.countStats != settings_.countStats ||
                            edited.renderScale != settings_.renderScale;
  settings_ = edited;
  // "Moving" lasts a little past the last change, so a slow drag does not flip the resolution.
  const auto now = Clock::now();
  if (cameraChanged) lastCameraChange_ = now;
  moving_ = lastCameraChange_ && msBetween(*lastCameraChange_, now) < kMotionHoldMs;
  const vk::Extent2D size = renderSize();
  const bool sizeChanged = size != presenter_.size();
  // The cost map needs every sample's rays counted: entering it restarts the image, leaving it
  // only changes the pipelines (the samples are the same either way).
  const bool pixelRays = settings_.display == DisplayMode::Cost;
  const bool pixelRaysChanged = pixelRays != pixelRays_;
  const bool restart = sceneReloaded || effectsChanged || knobsChanged || cameraChanged || sizeChanged || !prepared_ ||
                       restartRequested_ || (pixelRaysChanged && pixelRays);
  const bool displayChanged = settings_.display != shownDisplay_ || threshold() != convergence_.threshold();
  if (!restart && !pixelRaysChanged && !displayChanged) return;

  // The Renderer's parameters, image and counters are shared by every frame: nothing may be in flight.
  quiesce();
  if (!restart && !pixelRaysChanged) {
    applyDisplay();
    return;
  }
  if (sceneReloaded || effectsChanged || !prepared_) renderer_.setScene(withEffects(scene_, settings_.effects));
  const RenderSettings r = frameSettings();
  RenderOptions options = o_.render;
  options.progressive = true;
  options.countStats = settings_.countStats;
  options.pixelRays = pixelRays;
  renderer_.prepare(camera_.camera(), r, options);
  pixelRays_ = pixelRays;
  presenter_.bind(renderer_.imageBuffer(), renderer_.imageTexelView(), size);
  applyDisplay();
  if (!restart) return;
  accumulation_.restart();
  convergence_.restart();
  // A measurement of the image before the restart is of no use any more.
  figures_ = ConvergenceFigures();
  measurePending_ = false;
  measureDue_ = true;
  // A scripted run's frames all belong to the final image: a new size or scene starts the count again.
  if (sizeChanged || sceneReloaded) tracedFrames_ = 0;
  prepared_ = true;
  restartRequested_ = false;
}

RenderSettings FrameLoop::frameSettings() const {
  const vk::Extent2D size = renderSize();
  RenderSettings r = settings_.render;
  r.width = size.width;
  r.height = size.height;
  r.spp = settings_.samplesPerFrame;
  // Progressive sampling already antialiases every pixel; adaptive refinement is a headless pass.
  r.antialiasing = Antialiasing::Stratified;
  // Frames sample every pixel alike; the noise threshold only judges convergence (ConvergenceMeter),
  // and the time limit is a headless one.
  r.noiseThreshold = 0.0;
  r.timeLimit = 0.0;
  return r;
}

void FrameLoop::inspectPending() {
  const glm::uvec2 pixel = *inspectPixel_;
  inspectPixel_.reset();
  RenderSettings r = frameSettings();
  if (pixel.x >= r.width || pixel.y >= r.height) {
    throw InputError("--inspect", "pixel " + std::to_string(pixel.x) + "," + std::to_string(pixel.y) +
                                      " is outside the " + std::to_string(r.width) + " x " + std::to_string(r.height) +
                                      " image");
  }
  // The pixel-centre ray's tree: what one sample of the pixel traces.
  r.spp = 1;
  quiesce();
  rayTree_ = renderer_.inspect(camera_.camera(), r, o_.render, pixel);
  status_ = "pixel " + std::to_string(pixel.x) + "," + std::to_string(pixel.y) + ": " +
            std::to_string(rayTree_->rays.size()) + " rays";
  // The recording kernel replaced the frames' pipelines and wrote into the image: start again.
  restartRequested_ = true;
  applyChanges(settings_, false, false);
}

void FrameLoop::applyDisplay() {
  convergence_.bind(renderer_.imageBuffer(), renderer_.imageTexelView(), presenter_.size(), threshold());
  const double t = threshold();
  switch (settings_.display) {
  case DisplayMode::Image:
    presenter_.setDisplay(gpu::kDisplayImage);
    break;
  case DisplayMode::Error:
    presenter_.setDisplay(gpu::kDisplayError, convergence_.errors(), static_cast<float>(t / 10.0),
                          static_cast<float>(t * 10.0));
    break;
  case DisplayMode::Cost:
    presenter_.setDisplay(gpu::kDisplayCost, renderer_.pixelRaysBuffer(), static_cast<float>(kCostMapLow),
                          static_cast<float>(kCostMapHigh));
    break;
  }
  shownDisplay_ = settings_.display;
}

void FrameLoop::collectStats() {
  // Counters and GPU times then cover the same completed frames: the caller waited for all of them.
  interval_.add(frames_.takeCompleted());
  intervalRays_ += renderer_.takeStats();
}

void FrameLoop::publishStats(bool force) {
  auto now = Clock::now();
  if (!force && msBetween(statsTaken_, now) < 500.0) return;
  quiesce();
  collectStats();
  if (measurePending_) {
    figures_ = convergence_.read();
    measurePending_ = false;
    measureDue_ = true;
  }
  const std::uint32_t n = countedInInterval_;
  if (n > 0) {
    const RayStats& s = intervalRays_;
    raysPerFrame_ = s.perFrame(n);
    // The counted frames' rays per frame, over the interval's average trace time.
    const double traceMs = interval_.per(interval_.gpu.trace, interval_.gpuFrames);
    raysPerSecond_ = traceMs > 0.0 ? static_cast<double>(s.total()) / n / (traceMs * 1e-3) : 0.0;
  }
  if (interval_.frames > 0) shown_ = interval_;
  shownSamples_ = accumulation_.samples();
  total_.wallMs += interval_.wallMs;
  total_.hostMs += interval_.hostMs;
  total_.waitMs += interval_.waitMs;
  total_.presentMs += interval_.presentMs;
  total_.frames += interval_.frames;
  total_.add({interval_.gpu, interval_.gpuFrames});
  totalRays_ += intervalRays_.total();
  totalCounted_ += countedInInterval_;
  interval_ = FrameTimes();
  intervalRays_ = RayStats();
  countedInInterval_ = 0;
  statsTaken_ = now;
  char title[256];
  double frameMs = shown_.per(shown_.wallMs, shown_.frames);
  std::snprintf(title, sizeof title, "vkray - %s - %.1f fps - %u spp", o_.scene.filename().string().c_str(),
                frameMs > 0 ? 1000.0 / frameMs : 0.0, accumulation_.samples());
  window_.setTitle(title);
}

void FrameLoop::recordFrame(FrameRing::Slot& slot, const Accumulation::Step& step, std::uint32_t imageIndex,
                            bool captureWindow, bool countRays, bool measure) {
  const vk::raii::CommandBuffer& cmd = slot.cmd;
  vulkan::vulkanStep("recording a frame", [&] {
    cmd.begin(vk::CommandBufferBeginInfo(vk::CommandBufferUsageFlagBits::eOneTimeSubmit));
    frames_.resetStamps(cmd);
    frames_.stamp(cmd, FrameRing::kStart, vk::PipelineStageFlagBits::eTopOfPipe);
    // The previous frame's trace (which wrote the sums and counters) and its resolve (which read the
    // sums) come before this frame's trace adds to the same sums and counters.
    vk::MemoryBarrier previousFrame(vk::AccessFlagBits::eShaderWrite,
                                    vk::AccessFlagBits::eShaderRead | vk::AccessFlagBits::eShaderWrite);
    cmd.pipelineBarrier(vk::PipelineStageFlagBits::eComputeShader | vk::PipelineStageFlagBits::eTransfer,
                        vk::PipelineStageFlagBits::eComputeShader, {}, previousFrame, {}, {});
    if (step.count > 0) renderer_.recordSamples(cmd, step.sampleBase, step.count, step.accumulate, countRays);
    frames_.stamp(cmd, FrameRing::kTraced, vk::PipelineStageFlagBits::eComputeShader);
    const Presenter::Target target{imageIndex, swapchain_.image(imageIndex), swapchain_.extent()};
    lastResolveDirect_ = presenter_.direct(target);
    // Direct path: the panel goes on its layer (when it changed) and the resolve composites it.
    if (lastResolveDirect_) overlay_->recordLayer(cmd);
    frames_.stamp(cmd, FrameRing::kLayered, vk::PipelineStageFlagBits::eColorAttachmentOutput);
    // The error estimates (for the error map, or a measurement) and the sums' copy when the count
    // doubled; timed with the resolve pass.
    convergence_.record(cmd, accumulation_.samples(), settings_.display == DisplayMode::Error, measure);
    presenter_.recordResolve(cmd, target);
    frames_.stamp(cmd, FrameRing::kResolved, vk::PipelineStageFlagBits::eComputeShader);
    presenter_.recordBlit(cmd, target);
    frames_.stamp(cmd, FrameRing::kBlitted, vk::PipelineStageFlagBits::eTransfer);
    if (!lastResolveDirect_) overlay_->record(cmd, imageIndex);
    frames_.stamp(cmd, FrameRing::kDone, vk::PipelineStageFlagBits::eBottomOfPipe);
    if (captureWindow) {
      Presenter::recordWindowReadback(cmd, swapchain_.image(imageIndex), swapchain_.extent(), windowPixels_->handle());
    }
    // Screenshots and counters are read by the host (directly or through a staging copy).
    vk::MemoryBarrier toHost(vk::AccessFlagBits::eShaderWrite,
                             vk::AccessFlagBits::eHostRead | vk::AccessFlagBits::eTransferRead);
    cmd.pipelineBarrier(vk::PipelineStageFlagBits::eComputeShader,
                        vk::PipelineStageFlagBits::eHost | vk::PipelineStageFlagBits::eTransfer, {}, toHost, {}, {});
    cmd.end();
  });
}

// Counting rays costs 10-20 % of a trace on lavapipe (the counters' sums and atomics run lane by
// lane), and the overlay shows averages twice a second. So with counting on, the first traced
// frame of each interval and then every kRayCountEvery-th one count, through the counting
// pipeline, and the others use the same kernel without counters; per-frame figures are averages
// over the counted frames. Returns whether the frame about to be recorded counts, and books it.
bool FrameLoop::takeCountTurn(const Accumulation::Step& step) {
  if (step.count == 0) return false; // nothing traced
  const bool counts = settings_.countStats && (countedInInterval_ == 0 || framesSinceCount_ + 1 >= kRayCountEvery);
  if (counts) {
    ++countedInInterval_;
    framesSinceCount_ = 0;
  } else {
    ++framesSinceCount_;
  }
  return counts;
}

// Whether the frame about to be recorded is a scripted run's last (the loop's exit test, ahead of time).
bool FrameLoop::finishesScript(const Accumulation::Step& step) const {
  if (!scripted()) return false;
  const bool wantResize = o_.resizeToWidth && o_.resizeToHeight;
  if (wantResize && swapchain_.extent() != vk::Extent2D(*o_.resizeToWidth, *o_.resizeToHeight)) return false;
  return tracedFrames_ + (step.count > 0 ? 1u : 0u) >= o_.frames;
}

void FrameLoop::prepareWindowCapture() {
  if (!swapchain_.readable()) {
    throw DeviceError("--screenshot-window: the window's images cannot be read back on " + context_.info().name);
  }
  const vk::Extent2D e = swapchain_.extent();
  if (windowPixels_ && windowPixelsExtent_ == e) return;
  quiesce(); // a frame in flight may still use the old buffer
  windowPixels_ = std::make_unique<vulkan::Buffer>(context_, vk::DeviceSize(e.width) * e.height * 4,
                                                   vk::BufferUsageFlagBits::eTransferDst, vulkan::MemoryUse::Readback,
                                                   "window screenshot");
  windowPixelsExtent_ = e;
}

void FrameLoop::saveWindowScreenshot(const std::filesystem::path& path) {
  quiesce();
  const vk::Format format = swapchain_.format();
  bool bgra = format == vk::Format::eB8G8R8A8Unorm || format == vk::Format::eB8G8R8A8Srgb;
  bool rgba = format == vk::Format::eR8G8B8A8Unorm || format == vk::Format::eR8G8B8A8Srgb;
  if (!bgra && !rgba) {
    throw DeviceError("--screenshot-window: cannot read the window's format " + vk::to_string(format));
  }
  const vk::Extent2D e = windowPixelsExtent_;
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(e.width) * e.height * 4);
  windowPixels_->read(bytes.data(), bytes.size());
  // The bytes are sRGB-encoded either way (the resolve pass encodes for a UNORM image, the hardware
  // for an sRGB one); decoded here so that the PNG writer's encoding gives the same bytes back.
  Image image(e.width, e.height);
  for (std::size_t i = 0; i < image.pixels.size(); ++i) {
    const std::uint8_t* p = &bytes[i * 4];
    glm::vec3 encoded = bgra ? glm::vec3(p[2], p[1], p[0]) : glm::vec3(p[0], p[1], p[2]);
    for (int c = 0; c < 3; ++c) image.pixels[i][c] = srgbToLinear(encoded[c] / 255.0f);
  }
  writeImage(path, image);
  std::printf("vkray: saved the window to %s\n", path.string().c_str());
  std::fflush(stdout);
}

void FrameLoop::saveScreenshot(const std::filesystem::path& path) {
  quiesce();
  // The Renderer's image, not the swapchain's: no overlay, full float precision until encoding. A
  // map's screenshot holds its values (the error, or rays per sample) in every channel.
  Image image = renderer_.readImage();
  if (settings_.display == DisplayMode::Error) {
    const std::vector<float> errors = convergence_.readErrors();
    for (std::size_t i = 0; i < image.pixels.size(); ++i) image.pixels[i] = glm::vec3(errors[i]);
  } else if (settings_.display == DisplayMode::Cost) {
    const std::vector<std::uint32_t> rays = renderer_.readPixelRays();
    const float samples = static_cast<float>(std::max(1u, accumulation_.samples()));
    for (std::size_t i = 0; i < image.pixels.size(); ++i) image.pixels[i] = glm::vec3(float(rays[i]) / samples);
  }
  writeImage(path, image);
  status_ = "saved " + path.string() + " (" + std::to_string(accumulation_.samples()) + " samples/pixel)";
  std::printf("vkray: %s\n", status_.c_str());
  std::fflush(stdout);
}

std::filesystem::path FrameLoop::nextScreenshotPath() const {
  if (!o_.screenshot.empty()) return o_.screenshot;
  std::string stem = o_.scene.stem().string();
  for (int i = 1;; ++i) {
    char name[64];
    std::snprintf(name, sizeof name, "-%03d.png", i);
    std::filesystem::path p = stem + name;
    if (!std::filesystem::exists(p)) return p;
  }
}

void FrameLoop::saveCamera() {
  std::string json = cameraJson(camera_.camera());
  std::printf("%s\n", json.c_str());
  std::fflush(stdout);
  window_.setClipboard(json);
  std::filesystem::path file = o_.scene.stem().string() + "-camera.json";
  writeFileAtomic(file, std::vector<std::uint8_t>(json.begin(), json.end()));
  status_ = "camera copied to the clipboard and saved to " + file.string();
}

OverlayModel FrameLoop::overlayModel() const {
  OverlayModel m;
  m.scenePath = o_.scene.string();
  m.device = context_.info().name;
  m.presentMode = presentModeName(swapchain_.presentMode());
  m.renderSize = presenter_.size();
  m.samples = shownSamples_;
  m.frameMs = shown_.per(shown_.wallMs, shown_.frames);
  m.hostMs = shown_.per(shown_.hostMs, shown_.frames);
  m.traceMs = shown_.per(shown_.gpu.trace, shown_.gpuFrames);
  m.resolveMs = shown_.per(shown_.gpu.resolve, shown_.gpuFrames);
  m.blitMs = shown_.per(shown_.gpu.blit, shown_.gpuFrames);
  m.overlayMs = shown_.per(shown_.gpu.overlay, shown_.gpuFrames);
  m.raysPerSecond = raysPerSecond_;
  m.raysPerFrame = raysPerFrame_;
  m.features = renderer_.currentFeatures().explain();
  m.cameraJson = cameraJson(camera_.camera());
  m.cameraMode = camera_.mode();
  m.reloadError = watcher_.error();
  m.status = status_;
  m.display = settings_.display;
  m.noiseThreshold = threshold();
  m.defaultThreshold = !(settings_.render.noiseThreshold > 0.0);
  m.convergence = figures_;
  if (rayTree_) {
    m.rayTree = &*rayTree_;
    m.camera = makeCameraFrame(camera_.camera(), m.renderSize.width, m.renderSize.height);
  }
  return m;
}

ViewerSummary FrameLoop::summarize() const {
  const FrameTimes& t = total_;
  ViewerSummary v;
  v.minimizedMs = minimizedMs_;
  v.device = context_.info().name;
  v.presentMode = presentModeName(swapchain_.presentMode());
  v.resolvePath = lastResolveDirect_ ? "direct" : "blit";
  v.renderWidth = presenter_.size().width;
  v.renderHeight = presenter_.size().height;
  v.windowWidth = swapchain_.extent().width;
  v.windowHeight = swapchain_.extent().height;
  v.frames = t.frames;
  v.frameMs = t.per(t.wallMs, t.frames);
  v.traceMs = t.per(t.gpu.trace, t.gpuFrames);
  v.resolveMs = t.per(t.gpu.resolve, t.gpuFrames);
  v.blitMs = t.per(t.gpu.blit, t.gpuFrames);
  v.overlayMs = t.per(t.gpu.overlay, t.gpuFrames);
  v.presentMs = t.per(t.presentMs, t.frames);
  v.hostMs = t.per(t.hostMs, t.frames);
  v.waitMs = t.per(t.waitMs, t.frames);
  v.rayCounts = settings_.countStats;
  v.countedFrames = totalCounted_;
  if (v.rayCounts) {
    v.raysPerFrame = totalCounted_ > 0 ? static_cast<double>(totalRays_) / static_cast<double>(totalCounted_) : 0.0;
    const double traceMs = t.per(t.gpu.trace, t.gpuFrames);
    v.mraysPerSecond = traceMs > 0 ? v.raysPerFrame / (traceMs * 1e3) : 0.0;
  }
  v.samples = accumulation_.samples();
  v.display = settings_.display;
  v.noiseThreshold = threshold();
  v.defaultThreshold = !(settings_.render.noiseThreshold > 0.0);
  v.convergence = figures_;
  if (rayTree_) {
    v.inspectedPixel = rayTree_->pixel;
    v.inspectedRays = rayTree_->rays.size();
  }
  return v;
}

bool FrameLoop::followReload(ViewSettings& edited) {
  // Scripted runs check every frame, so a test's edit is seen on the next frame.
  const std::string errorBefore = watcher_.error();
  bool reloaded = watcher_.poll(scripted() ? std::chrono::milliseconds(0) : std::chrono::milliseconds(250));
  if (reloaded) {
    Scene next = watcher_.scene();
    if (o_.applyOverrides) o_.applyOverrides(next.render);
    // What was edited in the file is followed (camera, settings); the rest of the user's changes stay.
    camera_.setHome(next.camera, !sameCamera(next.camera, scene_.camera));
    if (!sameKnobs(next.render, scene_.render)) edited.render = next.render;
    scene_ = std::move(next);
    status_ = "reloaded " + o_.scene.string();
    std::printf("vkray: %s\n", status_.c_str());
    std::fflush(stdout);
  } else if (!watcher_.error().empty() && watcher_.error() != errorBefore) {
    std::fprintf(stderr, "vkray: reload failed, keeping the last good scene: %s\n", watcher_.error().c_str());
  }
  return reloaded;
}

bool FrameLoop::scriptFinished(const Accumulation::Step& step) {
  if (step.count > 0) ++tracedFrames_;
  const bool wantResize = o_.resizeToWidth && o_.resizeToHeight;
  if (wantResize && !resizeRequested_ && tracedFrames_ * 2 >= o_.frames) {
    window_.setSize(*o_.resizeToWidth, *o_.resizeToHeight);
    resizeRequested_ = true;
    resizeRequestedAt_ = Clock::now();
  }
  const bool resized = !wantResize || swapchain_.extent() == vk::Extent2D(*o_.resizeToWidth, *o_.resizeToHeight);
  if (wantResize && resizeRequested_ && !resized && msBetween(resizeRequestedAt_, Clock::now()) > 10000.0) {
    throw Error("the window was not resized to " + std::to_string(*o_.resizeToWidth) + "x" +
                std::to_string(*o_.resizeToHeight) + " within 10 s");
  }
  return resized && tracedFrames_ >= o_.frames;
}

int FrameLoop::run() {
  auto previous = Clock::now();
  // Frames before this are not timed in --stats (the first ones wait for pipeline creation).
  const std::uint32_t warmup = scripted() ? std::min<std::uint32_t>(5, o_.frames / 5) : 0;
  std::uint32_t frameIndex = 0;
  bool idle = false;
  while (!window_.shouldClose()) {
    const vk::Extent2D framebuffer = window_.framebufferSize();
    const bool minimized = window_.iconified() || framebuffer.width == 0 || framebuffer.height == 0;
    // Nothing to trace and nothing happening: sleep until an event (or a reload check is due).
    window_.pollEvents(minimized || (idle && !scripted()), 0.25);
    auto frameStart = Clock::now();
    const double waitedBefore = interval_.waitMs;
    double dt = std::chrono::duration<double>(frameStart - previous).count();
    previous = frameStart;
    InputFrame input = window_.takeInput();
    if (minimized) { // nothing is seen: trace nothing, and wait for events
      minimizedMs_ += dt * 1000.0;
      continue;
    }

    const vk::Extent2D fb = window_.framebufferSize();
    if (window_.takeResized() || swapchainStale_ || fb != lastFramebuffer_) recreateSwapchain(fb);
    if (swapchainStale_) continue;

    shownSamples_ = std::min(shownSamples_, accumulation_.samples()); // a restart shows at once
    overlay_->newFrame();
    const Camera cameraBefore = camera_.camera();
    handleInput(input, dt);
    ViewSettings edited = settings_;
    OverlayRequests req = overlay_->build(overlayModel(), edited);
    if (req.toggleFly) handleAction(ViewerAction::ToggleFly);
    if (req.resetCamera) handleAction(ViewerAction::ResetCamera);
    if (req.saveCamera) handleAction(ViewerAction::SaveCamera);
    if (req.screenshot) handleAction(ViewerAction::Screenshot);
    if (req.closeRayTree) rayTree_.reset();

    const bool reloaded = followReload(edited);
    if (o_.spinDegrees != 0.0) camera_.orbit(o_.spinDegrees * 3.14159265358979323846 / 180.0, 0.0);
    applyChanges(edited, reloaded, !sameCamera(cameraBefore, camera_.camera()));
    if (inspectPixel_) inspectPending();
    publishStats(false);

    auto beginStart = Clock::now();
    FrameRing::Slot& slot = frames_.begin();
    auto acquireStart = Clock::now();
    interval_.waitMs += msBetween(beginStart, acquireStart);
    std::optional<std::uint32_t> image = swapchain_.acquire(*slot.imageAcquired);
    double presentMs = msBetween(acquireStart, Clock::now());
    if (!image) {
      swapchainStale_ = true;
      continue;
    }
    Accumulation::Step step = accumulation_.next(settings_.samplesPerFrame, settings_.maxSamples);
    const bool captureWindow = !o_.windowScreenshot.empty() && finishesScript(step);
    if (captureWindow) prepareWindowCapture();
    // A script's last frame is measured, so that its figures are those of the final image.
    const bool measure = measureDue_ || finishesScript(step);
    recordFrame(slot, step, *image, captureWindow, takeCountTurn(step), measure);
    if (measure) {
      measureDue_ = false;
      measurePending_ = true;
    }
    windowCaptured_ = windowCaptured_ || captureWindow;
    frames_.submit(swapchain_.renderFinished(*image));
    auto presentStart = Clock::now();
    if (!swapchain_.present(*image, swapchain_.renderFinished(*image))) swapchainStale_ = true;
    auto frameEnd = Clock::now();
    presentMs += msBetween(presentStart, frameEnd);
    if (frameIndex == 0) {
      std::printf("vkray: viewing %s on %s, %s; H shows the controls, Esc quits\n", o_.scene.string().c_str(),
                  context_.info().name.c_str(), presentModeName(swapchain_.presentMode()).c_str());
      std::fflush(stdout);
    }
    idle = step.count == 0 && input.actions.empty() && input.cursorDelta == glm::dvec2(0.0) && input.scroll == 0.0;

    interval_.wallMs += dt * 1000.0;
    interval_.presentMs += presentMs;
    interval_.hostMs += std::max(0.0, msBetween(frameStart, frameEnd) - presentMs - (interval_.waitMs - waitedBefore));
    ++interval_.frames;
    if (++frameIndex == warmup) {
      // The summary leaves out the warm-up frames (the first waits for pipeline creation).
      publishStats(true);
      total_ = FrameTimes();
      totalRays_ = 0;
      totalCounted_ = 0;
    }

    if (scripted() && scriptFinished(step)) break;
  }

  publishStats(true);
  if (context_.validationEnabled() && context_.validationMessageCount() > 0) {
    throw DeviceError("the validation layer reported " + std::to_string(context_.validationMessageCount()) +
                      " message(s); no screenshot written");
  }
  if (scripted() && !o_.screenshot.empty()) saveScreenshot(o_.screenshot);
  if (windowCaptured_) saveWindowScreenshot(o_.windowScreenshot);
  const ViewerSummary summary = summarize();
  if (o_.printStats) printViewerSummary(summary);
  if (o_.summary) *o_.summary = summary;
  return 0;
}

} // namespace

void printViewerSummary(const ViewerSummary& v) {
  std::printf("device: %s\n", v.device.c_str());
  std::printf("present mode: %s\n", v.presentMode.c_str());
  std::printf("resolve path: %s\n", v.resolvePath.c_str());
  std::printf("render size: %ux%u\n", v.renderWidth, v.renderHeight);
  std::printf("window size: %ux%u\n", v.windowWidth, v.windowHeight);
  std::printf("frames timed: %u\n", v.frames);
  std::printf("frame: %.2f ms\n", v.frameMs);
  std::printf("fps: %.1f\n", v.fps());
  std::printf("trace: %.2f ms\n", v.traceMs);
  std::printf("resolve: %.2f ms\n", v.resolveMs);
  std::printf("blit: %.2f ms\n", v.blitMs);
  std::printf("overlay: %.2f ms\n", v.overlayMs);
  std::printf("gpu total: %.2f ms\n", v.gpuMs());
  // On a CPU device the presentation copy to the window runs after the frame's GPU work, in series.
  std::printf("frame minus gpu: %.2f ms\n", v.frameMs - v.gpuMs());
  std::printf("acquire and present: %.2f ms\n", v.presentMs);
  std::printf("host: %.2f ms\n", v.hostMs);
  std::printf("wait: %.2f ms\n", v.waitMs);
  if (v.rayCounts) {
    std::printf("ray-counted frames: %llu\n", static_cast<unsigned long long>(v.countedFrames));
    std::printf("rays per frame: %.0f\n", v.raysPerFrame);
    std::printf("mrays/s: %.2f\n", v.mraysPerSecond);
  }
  std::printf("samples: %u\n", v.samples);
  if (v.inspectedPixel) {
    std::printf("inspected pixel: %u,%u (%zu rays)\n", v.inspectedPixel->x, v.inspectedPixel->y, v.inspectedRays);
  }
  std::printf("minimized: %.0f ms\n", v.minimizedMs);
  std::printf("display: %s\n", std::string(enumName(v.display)).c_str());
  std::printf("noise threshold: %g%s\n", v.noiseThreshold, v.defaultThreshold ? " (default)" : "");
  const ConvergenceFigures& c = v.convergence;
  if (c.measured) {
    // The last frame's estimate (convergence.h); none while no pixel has two samples.
    std::printf("error samples: %u\n", c.samples);
    std::printf("error mean: %.6g\n", c.errorMean);
    std::printf("error p95: %.6g\n", c.errorP95);
    std::printf("converged: %.2f %%\n", 100.0 * c.converged);
  }
}

int runViewer(const ViewerOptions& o) {
  if (!o.screenshot.empty()) checkOutputPath(o.screenshot);
  if (!o.windowScreenshot.empty()) {
    if (o.frames == 0) throw InputError("--screenshot-window", "needs --frames (it is for scripted runs)");
    checkOutputPath(o.windowScreenshot);
  }
  // The scene loads before any window opens: a broken file stops here with its one-line error.
  SceneWatcher watcher(o.scene, o.model);
  GlfwSession glfw;
  Scene scene = watcher.scene();
  if (o.applyOverrides) o.applyOverrides(scene.render);
  Window window(glfw, o.windowWidth.value_or(scene.render.width), o.windowHeight.value_or(scene.render.height),
                "vkray - " + o.scene.filename().string());

  vulkan::ContextOptions co = contextOptions(o.device);
  co.instanceExtensions = glfw.requiredInstanceExtensions();
  co.deviceExtensions = {VK_KHR_SWAPCHAIN_EXTENSION_NAME};
  // The queue also blits and draws the overlay; whether it can present to this window is checked
  // once the surface exists (the filter runs before there is an instance to make one with).
  co.queueFamilyFilter = [](const vk::raii::PhysicalDevice& pd, std::uint32_t family) {
    return static_cast<bool>(pd.getQueueFamilyProperties()[family].queueFlags & vk::QueueFlagBits::eGraphics);
  };
  vulkan::Context context(co);
  std::unique_ptr<vulkan::PipelineCache> cache;
  if (!o.device.noPipelineCache) {
    cache = std::make_unique<vulkan::PipelineCache>(context, vulkan::PipelineCache::defaultFile(context));
  }
  FrameLoop loop(o, window, context, cache.get(), watcher, std::move(scene));
  return loop.run();
}

} // namespace vkray
