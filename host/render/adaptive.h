// Progressive rendering's host side: per-pixel moments, the error estimate, which pixels stay open
// and how many samples the next pass gives them. Pure host code (no device): the Renderer runs the
// passes (Renderer::renderProgressive), this decides them.
//
// A pass traces k more samples of every open pixel: min_spp / 2 twice, then as many as each open
// pixel already has (its count doubles, which keeps the Sobol-Owen sequence's power-of-two strata
// whole), never past max_spp. Once a pixel has min_spp samples, it stays open while the RMS of the
// estimated standard errors over its 3 x 3 neighbourhood is above the noise threshold: one pixel's
// estimate has few degrees of freedom, and a pixel whose samples all fell on one side of an edge
// looks noiseless where its neighbours do not.
//
// The estimate compares the mean of a pixel's earlier passes with the mean of its last pass (a
// split-half estimate): for a stratified sequence the samples' own variance overstates the error
// of their mean several times over, and spends samples where the mean has already converged. With a
// time limit, a
// pass is shortened (fewer samples) to fit what is left of the budget at the speed measured so far,
// and no pass starts that cannot trace one sample of every open pixel in it.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "image/image.h"
#include "render/render_options.h"
#include "scene/scene.h"

namespace vkray {

// Bad combinations of the progressive settings (min_spp above max_spp, a noise threshold with
// adaptive antialiasing): InputError naming the key.
void checkProgressiveSettings(const RenderSettings& settings);

// One pixel's running sums, in double: the host adds each pass's float sums to them.
struct PixelMoments {
  glm::dvec3 sum{0.0};
  glm::dvec3 squares{0.0};
  double samples = 0.0;
  double rays = 0.0;
  glm::dvec3 earlierSum{0.0}; // sum and samples before the last pass
  double earlierSamples = 0.0;
};

// The estimated standard error of the pixel's mean, the largest of R, G and B. From two parts (the
// earlier passes, mean A of n1 samples, and the last pass, mean B of n2) when the pixel has both:
// |A - B| sqrt(n1 n2) / n. From one pass, the unbiased sample variance over n. Infinite below two
// samples.
double standardError(const PixelMoments& m);

class ProgressiveImage {
public:
  ProgressiveImage(std::uint32_t width, std::uint32_t height);
  std::uint32_t width() const { return width_; }
  std::uint32_t height() const { return height_; }
  // Adds one pass's sums of a pixel: (sum rgb, samples) and (sum of squares rgb, rays).
  void add(std::uint32_t x, std::uint32_t y, const glm::vec4& sums, const glm::vec4& squaresAndRays);
  const PixelMoments& at(std::uint32_t x, std::uint32_t y) const {
    return pixels_[static_cast<std::size_t>(y) * width_ + x];
  }
  double error(std::uint32_t x, std::uint32_t y) const { return errors_[static_cast<std::size_t>(y) * width_ + x]; }
  // The pixel's error as the threshold judges it: the root of the mean of its own squared
  // standardError and the mean square over its 3 x 3 neighbourhood (pixels traced so far). One
  // split-half estimate has a single degree of freedom per channel, so the neighbourhood steadies
  // it; the pixel's own half keeps a noisy neighbour from holding a settled pixel open. Against the
  // neighbourhood's RMS alone this reaches the same 95th-percentile error with 10-18 % fewer
  // samples (docs/progressive.md); the RMS in turn needed a tenth fewer than the plain mean.
  double neighbourhoodError(std::uint32_t x, std::uint32_t y) const;
  // Of `open` (row-major pixel indices), those whose neighbourhood error is above `threshold`.
  std::vector<std::uint32_t> stillOpen(const std::vector<std::uint32_t>& open, double threshold) const;
  Image image() const; // the means (black where a pixel has no samples)
  PixelStats stats() const;

private:
  std::uint32_t width_, height_;
  std::vector<PixelMoments> pixels_;
  std::vector<double> errors_; // standardError of each pixel, updated by add()
};

// The samples each open pixel gets in the next pass. `samplesSoFar`: each open pixel's count (all
// open pixels have the same); msPerSample: GPU time per pixel-sample measured so far (0: none yet);
// spentMs: GPU time of the passes so far. 0: no pass (the cap is reached, or the time limit would
// be exceeded by even one sample each).
std::uint32_t nextPassSamples(const RenderSettings& settings, std::uint32_t samplesSoFar, std::size_t openPixels,
                              double msPerSample, double spentMs);

// How many times a render with these settings decides which pixels stay open (at most): with a
// time limit the passes may stop sooner.
std::uint32_t decisionCount(const RenderSettings& settings);

// The summary --stats prints, over the pixels rendered (converged: 1; the renderer knows better).
ProgressiveSummary summarize(const PixelStats& stats, int passes);

} // namespace vkray
