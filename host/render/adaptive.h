// Progressive rendering's host side: per-pixel moments, the error estimate, which pixels stay open
// and how many samples the next pass gives them. Pure host code (no device): the Renderer runs the
// passes (Renderer::renderProgressive), this decides them.
//
// A pass traces k more samples of every open pixel: min_spp / 4 twice, then as many as each open
// pixel already has (its count doubles, which keeps the Sobol-Owen sequence's power-of-two strata
// whole), never past max_spp. Once a pixel has min_spp samples, it stays open while its error,
// blended with the RMS of the estimated standard errors over its 3 x 3 neighbourhood, is above the
// noise threshold: one pixel's estimate has few degrees of freedom, and a pixel whose samples all
// fell on one side of an edge looks noiseless where its neighbours do not.
//
// The estimate compares the means of whole blocks of the sequence instead of the samples' own
// variance: for a stratified sequence that variance overstates the error of their mean several
// times over, and spends samples where the mean has already converged. Each pass's sums come in two
// halves, so a decision sees four blocks, in quarters of the samples while counts double: all before
// the pass before the last, that pass, and the last pass's two halves (three degrees of freedom per
// channel), pooled with the estimate the previous decision made. With a time limit, a pass is
// shortened (fewer samples) to fit what is left of the budget at the speed measured so far, and no
// pass starts that cannot trace one sample of every open pixel in it.
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

// How many of a pass's k samples make its first half: the kernel adds the samples before the
// pass's first sample plus this (PushConstants::splitBase) to the half's sum, and the estimate's
// blocks are cut there.
constexpr std::uint32_t firstHalf(std::uint32_t k) {
  return k / 2;
}

// One pixel's running sums, in double: the host adds each pass's float sums to them.
struct PixelMoments {
  glm::dvec3 sum{0.0};
  double samples = 0.0;
  double rays = 0.0;
  glm::dvec3 earlierSum{0.0}; // sum and samples before the last pass
  double earlierSamples = 0.0;
  glm::dvec3 previousSum{0.0}; // before the pass before the last
  double previousSamples = 0.0;
  glm::dvec3 halfSum{0.0}; // the last pass's first half (firstHalf of its samples)
  // What blockVariance gave before the last pass (the variance of the mean of earlierSamples), and
  // its degrees of freedom (0: none).
  double previousVariance = 0.0;
  double previousDof = 0.0;
};

// The blocks' estimate of the variance of the pixel's mean, the largest of R, G and B: the blocks
// are all before the pass before the last, that pass, and the last pass's two halves (empty ones
// left out). With J blocks of m_j samples and means x_j, around the mean x of all n samples, the
// per-sample variance is sum_j m_j (x_j - x)^2 / (J - 1) for independent samples, and the mean's
// is that over n. For two halves this is (A - B)^2 n1 n2 / n^2. `dof`: J - 1 (0: fewer than two
// blocks, and the result is 0).
double blockVariance(const PixelMoments& m, double* dof = nullptr);

// The estimated standard error of the pixel's mean: blockVariance pooled with the previous
// decision's, scaled to this sample count (as 1 / n), weighted by their degrees of freedom.
// Infinite below two samples or without two blocks.
double standardError(const PixelMoments& m);

class ProgressiveImage {
public:
  ProgressiveImage(std::uint32_t width, std::uint32_t height);
  std::uint32_t width() const { return width_; }
  std::uint32_t height() const { return height_; }
  // Adds one pass's sums of a pixel: (sum rgb, samples) and (sum rgb of the pass's first
  // firstHalf(samples) samples, rays).
  void add(std::uint32_t x, std::uint32_t y, const glm::vec4& sums, const glm::vec4& halfAndRays);
  const PixelMoments& at(std::uint32_t x, std::uint32_t y) const {
    return pixels_[static_cast<std::size_t>(y) * width_ + x];
  }
  double error(std::uint32_t x, std::uint32_t y) const { return errors_[static_cast<std::size_t>(y) * width_ + x]; }
  // The pixel's error as the threshold judges it: the root of kOwnShare of its own squared
  // standardError plus the rest of the mean square over its 3 x 3 neighbourhood (pixels traced so
  // far). One estimate has a few degrees of freedom per channel, so the neighbourhood steadies it;
  // the pixel's own share keeps a noisy neighbour from holding a settled pixel open
  // (docs/progressive.md, "The estimate").
  static constexpr double kOwnShare = 0.8;
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
