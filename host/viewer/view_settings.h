// What the viewer's overlay can change while it runs: the accuracy knobs, each effect on or off, the
// samples traced per frame and where accumulation stops. Pure data and rules, no window.
#pragma once

#include <cstdint>

#include "scene/scene.h"

namespace vkray {

// Effects the viewer can switch off. Switched off means removed from the scene description before
// it reaches the Renderer, so Features compiles the effect out exactly as for a scene without it.
struct EffectToggles {
  bool shadows = true;    // lights cast shadows
  bool reflection = true; // mirror reflection (materials' reflection coefficients)
  bool refraction = true; // transmission through dielectrics
  bool checker = true;    // checker textures

  bool operator==(const EffectToggles&) const = default;
};

// With ray counting on, the viewer counts in one frame of this many (and the first of each stats
// interval): a counted frame costs 10-20 % more on lavapipe (viewer.cpp, takeCountTurn). At 30 fps
// a half-second interval has 15 frames, so 16 counts its first frame alone: as exact a figure (a
// frame's counts differ from the next's by the jitter alone, 0.07 % of the rays) for half the cost
// of one frame in 8.
constexpr std::uint32_t kRayCountEvery = 16;

// What the window shows (M cycles, --display): the image, or a map of a per-pixel quantity as a heat
// colour on a log scale: the estimated standard error of the pixel's mean (the block estimate of
// render --noise-threshold, host/viewer/convergence.h), or the rays traced per sample (cost).
enum class DisplayMode { Image, Error, Cost };
template <> struct EnumNames<DisplayMode> {
  static constexpr std::array<EnumName<DisplayMode>, 3> values{
      {{DisplayMode::Image, "image"}, {DisplayMode::Error, "error"}, {DisplayMode::Cost, "cost"}}};
};
DisplayMode nextDisplayMode(DisplayMode mode); // image -> error -> cost -> image

// The noise threshold the viewer judges convergence by when neither the scene nor the command line
// sets one (render.noise_threshold, --noise-threshold).
constexpr double kDefaultViewThreshold = 0.01;
// The scales of the maps: the error map spans threshold / 10 .. threshold * 10, the cost map
// kCostMapLow .. kCostMapHigh rays per sample (both logarithmic).
constexpr double kCostMapLow = 1.0;
constexpr double kCostMapHigh = 64.0;

struct ViewSettings {
  RenderSettings render;           // accuracy knobs; width and height follow the window
  EffectToggles effects;           //
  int samplesPerFrame = 1;         // samples per pixel added by each frame
  std::uint32_t maxSamples = 4096; // accumulation stops here (the image has converged enough)
  bool countStats = true;          // ray counters on, in 1 frame of kRayCountEvery (viewer.cpp)
  double renderScale = 1.0;        // render resolution relative to the window (blit scales up)
  double motionScale = 1.0;        // further scale while the camera moves (interactive frame rates)
  DisplayMode display = DisplayMode::Image;
};

// The scene with the switched-off effects taken out of its description.
Scene withEffects(const Scene& scene, const EffectToggles& effects);

// True when the two settings trace different images (anything but width and height, which the
// viewer sets from the window).
bool sameKnobs(const RenderSettings& a, const RenderSettings& b);

// Progressive refinement: which samples the next frame traces. Still frames add samples
// base, base + 1, ... of each pixel's sequence; any change restarts at sample 0.
class Accumulation {
public:
  struct Step {
    std::uint32_t sampleBase = 0; // first sample index this frame traces
    std::uint32_t count = 0;      // samples per pixel this frame (0: converged, nothing to trace)
    bool accumulate = false;      // add to the sums already in the image
  };

  void restart() { samples_ = 0; }
  // The next frame's samples; counts them as traced.
  Step next(std::uint32_t samplesPerFrame, std::uint32_t maxSamples);
  std::uint32_t samples() const { return samples_; }

private:
  std::uint32_t samples_ = 0; // samples per pixel in the image so far
};

} // namespace vkray
