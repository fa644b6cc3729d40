// Live viewer settings: effect toggles applied to the scene, and progressive accumulation.
#include "viewer/view_settings.h"

#include <algorithm>

namespace vkray {

Scene withEffects(const Scene& scene, const EffectToggles& effects) {
  Scene out = scene;
  if (!effects.shadows) {
    for (auto& light : out.lights) light.shadows = false;
  }
  for (auto& m : out.materials) {
    if (!effects.reflection) m.reflection = 0.0;
    if (!effects.refraction) m.transmission = 0.0;
    if (!effects.checker) m.checker.reset();
  }
  return out;
}

bool sameKnobs(const RenderSettings& a, const RenderSettings& b) {
  return a.maxDepth == b.maxDepth && a.spp == b.spp && a.bailout == b.bailout && a.antialiasing == b.antialiasing &&
         a.adaptiveThreshold == b.adaptiveThreshold && a.numerics == b.numerics && a.fresnel == b.fresnel &&
         a.transmissiveShadows == b.transmissiveShadows && a.bvh == b.bvh && a.precision == b.precision &&
         a.textureFilter == b.textureFilter && a.seed == b.seed;
}

DisplayMode nextDisplayMode(DisplayMode mode) {
  switch (mode) {
  case DisplayMode::Image:
    return DisplayMode::Error;
  case DisplayMode::Error:
    return DisplayMode::Cost;
  default:
    return DisplayMode::Image;
  }
}

Accumulation::Step Accumulation::next(std::uint32_t samplesPerFrame, std::uint32_t maxSamples) {
  Step step;
  if (samples_ >= maxSamples) return step;
  step.sampleBase = samples_;
  step.count = std::min(std::max(samplesPerFrame, 1u), maxSamples - samples_);
  step.accumulate = samples_ > 0;
  samples_ += step.count;
  return step;
}

} // namespace vkray
