// Progressive rendering's host side: per-pixel moments, the error estimate, which pixels stay open
// and how many samples the next pass gives them. Pure host code (no device): the Renderer runs the
// passes (Renderer::renderProgressive), this decides them.
//
// A pass traces k more samples of every open pixel: min_spp / 4 twice, then as many as each open
// pixel already has (its count doubles, which keeps the Sobol-Owen sequence's power-of-two strata
// whole), never past max_spp. Once a pixel has min_spp samples, it stays open while its error,
// blended with the RMS of the estimated standard errors over its 3 x 3 neighbourhood, is above the
// noise threshold: one pixel's estimate has few degrees of freedom, and a pixel whose samples all
// fell on one side of an edge looks noiseless where its neighbours do not. At the first decision,
// and at every decision before it has kContrastGuardSamples samples, it also stays open where its
// neighbourhood has the contrast to hide a feature all its samples missed (kContrastShare).
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

// One pixel's running sums: the host adds each pass's sums to them.
struct PixelMoments {
  // Stored in float (72 bytes a pixel; the estimate's arithmetic is in double): a pass's sums come
  // from the kernel in float, and the few passes a pixel takes add little rounding to them.
  glm::vec3 sum{0.0f};
  float samples = 0.0f;
  glm::vec3 earlierSum{0.0f}; // sum and samples before the last pass
  float earlierSamples = 0.0f;
  glm::vec3 previousSum{0.0f}; // before the pass before the last
  float previousSamples = 0.0f;
  glm::vec3 halfSum{0.0f}; // the last pass's first half (firstHalf of its samples)
  float rays = 0.0f;
  // What blockVariance gives for these moments, and its degrees of freedom (0: none): kept by add(),
  // whose next call pools it as the previous decision's estimate instead of computing it again.
  float variance = 0.0f;
  float varianceDof = 0.0f;
};
static_assert(sizeof(PixelMoments) == 72);

// The blocks' estimate of the variance of the pixel's mean, the largest of R, G and B: the blocks
// are all before the pass before the last, that pass, and the last pass's two halves (empty ones
// left out). With J blocks of m_j samples and means x_j, around the mean x of all n samples, the
// per-sample variance is sum_j m_j (x_j - x)^2 / (J - 1) for independent samples, and the mean's
// is that over n. For two halves this is (A - B)^2 n1 n2 / n^2. `dof`: J - 1 (0: fewer than two
// blocks, and the result is 0).
double blockVariance(const PixelMoments& m, double* dof = nullptr);

// The estimated standard error of the pixel's mean: its blocks' estimate (blockVariance(m): `variance`
// with `dof`) pooled with the previous decision's (`previousVariance`, of the mean of
// m.earlierSamples, with `previousDof`), that one scaled to this sample count (as 1 / n), weighted
// by their degrees of freedom. Infinite below two samples or without two blocks.
double standardError(const PixelMoments& m, double variance, double dof, double previousVariance, double previousDof);

// The running sums of the pixels in rows [rowBegin, rowEnd) of a width x height image (a tile's
// rows and its margin; all rows by default): the host adds each pass's sums to them. Coordinates
// are the image's; pixels outside the rows are never traced.
class ProgressiveImage {
public:
  ProgressiveImage(std::uint32_t width, std::uint32_t height, std::uint32_t rowBegin = 0, std::uint32_t rowEnd = ~0u);
  // The host memory one stored pixel takes (its moments and its estimate).
  static constexpr std::size_t kBytesPerPixel = sizeof(PixelMoments) + sizeof(float);
  std::uint32_t width() const { return width_; }
  std::uint32_t height() const { return height_; }
  // Adds one pass's sums of a pixel: (sum rgb, samples) and (sum rgb of the pass's first
  // firstHalf(samples) samples, rays). It writes that pixel's moments and estimate only, so calls
  // for different pixels may run on different threads at once (the renderer adds a pass so).
  void add(std::uint32_t x, std::uint32_t y, const glm::vec4& sums, const glm::vec4& halfAndRays) {
    addPixel(y * width_ + x, sums, halfAndRays);
  }
  // The same for the pixel at row-major index `pixel` of the image (y * width + x): the renderer's
  // lists hold those, and two divisions per call were a tenth of adding a pass.
  void addPixel(std::uint32_t pixel, const glm::vec4& sums, const glm::vec4& halfAndRays);
  // Asks the CPU to bring the pixel's moments and estimate into its caches ahead of addPixel. A
  // pass's list visits its tiles in spread order (renderer.cpp, spreadGroups), which the hardware
  // prefetcher cannot follow, and a third of addPixel's time was its first load of the moments.
  static constexpr std::size_t kPrefetchAhead = 8; // pixels ahead, in the caller's order
  void prefetchPixel(std::uint32_t pixel) const {
    const std::size_t i = index(pixel);
    const char* m = reinterpret_cast<const char*>(&pixels_[i]);
    __builtin_prefetch(m, 1);
    __builtin_prefetch(m + sizeof(PixelMoments) - 1, 1);
    __builtin_prefetch(&errors_[i], 1);
  }
  // The fewest pixels worth a thread of their own in the host's per-pixel loops (parallelFor): a
  // pixel's add or decision takes well under a microsecond, starting a thread tens of them.
  static constexpr std::size_t kPixelsPerThread = 16384;
  const PixelMoments& at(std::uint32_t x, std::uint32_t y) const { return pixels_[index(x, y)]; }
  // standardError, as stored (in float).
  double error(std::uint32_t x, std::uint32_t y) const { return errors_[index(x, y)]; }
  // The pixel's error as the threshold judges it: the root of kOwnShare of its own squared
  // standardError plus the rest of the mean square over its 3 x 3 neighbourhood (pixels traced so
  // far). One estimate has a few degrees of freedom per channel, so the neighbourhood steadies it;
  // the pixel's own share keeps a noisy neighbour from holding a settled pixel open
  // (docs/progressive.md, "The estimate").
  static constexpr double kOwnShare = 0.8;
  double neighbourhoodError(std::uint32_t x, std::uint32_t y) const;
  // The largest, over R, G and B, of the range (max - min) of the means over the pixel's 3 x 3
  // neighbourhood (pixels traced so far): the contrast a feature the pixel's samples missed could
  // have with what they saw.
  double neighbourhoodContrast(std::uint32_t x, std::uint32_t y) const;
  // A guarded decision stops a pixel only where neighbourhoodContrast / samples is also at most this
  // share of the threshold. n samples of the Owen-scrambled Sobol sequence put one in every strip of
  // 1/n of the pixel along either axis, so a feature they all missed (a checker line running along
  // the pixel row) is thinner than 1/n of the pixel and moves its mean by at most about its contrast
  // over n; the block estimate cannot see it, since every block missed it too.
  static constexpr double kContrastShare = 0.25;
  // The decisions that ask: the first, and every one before a pixel has this many samples. From 16
  // samples on, the replayed tail of the error is where min_spp 16 without the question had it
  // (docs/progressive.md, "min_spp").
  static constexpr float kContrastGuardSamples = 16.0f;
  // Of `open` (row-major pixel indices), those whose neighbourhood error is above `threshold` (and,
  // at the `first` decision or below kContrastGuardSamples, whose neighbourhood contrast could hide a
  // missed feature), in `open`'s order. Decided on every hardware thread (parallelFor) once the list
  // is long enough: each decision only reads.
  std::vector<std::uint32_t> stillOpen(const std::vector<std::uint32_t>& open, double threshold,
                                       bool first = false) const;
  Image image() const; // the whole image's means (black where a pixel has no samples)
  PixelStats stats() const;

private:
  std::size_t index(std::uint32_t x, std::uint32_t y) const {
    return static_cast<std::size_t>(y - rowBegin_) * width_ + x;
  }
  // The stored index of the pixel at row-major image index `pixel` (y * width + x).
  std::size_t index(std::uint32_t pixel) const { return pixel - static_cast<std::size_t>(rowBegin_) * width_; }
  // Calls visit(index) for each pixel of (x, y)'s 3 x 3 neighbourhood (itself included) that has
  // been traced: inside the image and the stored rows, with samples.
  template <class Visit> void forTracedNeighbours(std::uint32_t x, std::uint32_t y, Visit visit) const;
  std::uint32_t width_, height_, rowBegin_, rowEnd_;
  std::vector<PixelMoments> pixels_;
  std::vector<float> errors_; // standardError of each pixel, updated by add()
};

// Host memory a progressive render of a width x height image keeps while it runs, with the rows it
// traces (`tracedRows`: a tile's and its margin): the moments of those rows, the open lists, and
// the whole image's means and statistics.
std::uint64_t progressiveHostBytes(std::uint32_t width, std::uint32_t height, std::uint32_t tracedRows);

// Throws Error when `needed` bytes exceed `available` (the host's, hostMemoryAvailable), saying
// what needs them and how to need less.
void checkProgressiveMemory(std::uint32_t width, std::uint32_t height, std::uint32_t tracedRows,
                            std::uint64_t available);

// The samples each open pixel gets in the next pass. `samplesSoFar`: each open pixel's count (all
// open pixels have the same); msPerSample: GPU time per pixel-sample measured so far (0: none yet);
// spentMs: GPU time of the passes so far. 0: no pass (the cap is reached, or the time limit would
// be exceeded by even one sample each).
std::uint32_t nextPassSamples(const RenderSettings& settings, std::uint32_t samplesSoFar, std::size_t openPixels,
                              double msPerSample, double spentMs);

// The most passes of the schedule one list pass takes at once (trace.comp, listPass).
constexpr std::size_t kPassesAtOnceMax = 3;

// The samples of each pass of the schedule that the next list pass takes: nextPassSamples' pass
// alone, or with `together`, under a noise threshold and without a time limit, every pass before the
// first decision (min_spp / 4, min_spp / 4 and min_spp / 2; at most kPassesAtOnceMax). Nothing is
// decided between them, so running them as one changes no sum; it saves each pixel the fixed cost of
// two passes. A time limit keeps them apart, to stop between them. Empty: no pass.
std::vector<std::uint32_t> nextPasses(const RenderSettings& settings, std::uint32_t samplesSoFar,
                                      std::size_t openPixels, double msPerSample, double spentMs, bool together);

// How many times a render with these settings decides which pixels stay open (at most): with a
// time limit the passes may stop sooner.
std::uint32_t decisionCount(const RenderSettings& settings);

// The summary --stats prints, over the pixels rendered (converged: 1; the renderer knows better).
ProgressiveSummary summarize(const PixelStats& stats, int passes);

} // namespace vkray
