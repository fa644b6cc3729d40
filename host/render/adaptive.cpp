// Progressive rendering's host side (see adaptive.h).
#include "render/adaptive.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "../../shaders/shared/resolve_types.h"
#include "util/error.h"
#include "util/host_memory.h"
#include "util/parallel.h"

namespace vkray {

// The viewer's converged share applies the same rule (shaders/convergence.comp).
static_assert(static_cast<float>(ProgressiveImage::kOwnShare) == gpu::kConvergenceOwnShare);
static_assert(static_cast<float>(ProgressiveImage::kContrastShare) == gpu::kConvergenceContrastShare);
static_assert(ProgressiveImage::kContrastGuardSamples == gpu::kConvergenceContrastGuardSamples);

void checkProgressiveSettings(const RenderSettings& s) {
  if (s.progressive() && s.minSpp > s.maxSpp) {
    throw InputError("render.min_spp",
                     "must not exceed max_spp (" + std::to_string(s.maxSpp) + "), got " + std::to_string(s.minSpp));
  }
  if (s.antialiasing == Antialiasing::Adaptive && s.spp > 1) {
    throw InputError("render.antialiasing",
                     "\"adaptive\" cannot be combined with a noise threshold, a time limit or the spp, error "
                     "and rays AOVs (they sample progressively): use one");
  }
}

double blockVariance(const PixelMoments& m, double* dof) {
  // The blocks as (sum, samples): earlier ones first, in the sequence's order.
  const glm::dvec3 sum(m.sum), earlierSum(m.earlierSum), previousSum(m.previousSum), halfSum(m.halfSum);
  const double samples = m.samples, earlierSamples = m.earlierSamples, previousSamples = m.previousSamples;
  const glm::dvec3 lastSum = sum - earlierSum;
  const double lastSamples = samples - earlierSamples;
  const double halfSamples = firstHalf(static_cast<std::uint32_t>(lastSamples));
  const std::array<std::pair<glm::dvec3, double>, 4> blocks{{
      {previousSum, previousSamples},
      {earlierSum - previousSum, earlierSamples - previousSamples},
      {halfSum, halfSamples},
      {lastSum - halfSum, lastSamples - halfSamples},
  }};
  int count = 0;
  for (const auto& b : blocks) count += b.second > 0.0 ? 1 : 0;
  if (dof) *dof = std::max(0, count - 1);
  if (count < 2) return 0.0;
  const glm::dvec3 mean = sum / samples;
  double worst = 0.0;
  for (int c = 0; c < 3; ++c) {
    double squares = 0.0; // sum_j m_j (x_j - x)^2
    for (const auto& [sum, samples] : blocks) {
      if (samples <= 0.0) continue;
      const double d = sum[c] / samples - mean[c];
      squares += samples * d * d;
    }
    worst = std::max(worst, squares / (count - 1) / samples);
  }
  return worst;
}

double standardError(const PixelMoments& m, double variance, double dof, double previousVariance, double previousDof) {
  if (m.samples < 2.0 || dof <= 0.0) return std::numeric_limits<double>::infinity();
  // The previous estimate was of the mean of earlierSamples; as 1 / n, it scales to this count.
  // (A stratified sequence converges faster than 1 / n, so it leans towards more samples.)
  const double pooled =
      previousDof > 0.0 && m.earlierSamples > 0.0
          ? (dof * variance + previousDof * previousVariance * (double(m.earlierSamples) / m.samples)) /
                (dof + previousDof)
          : variance;
  return std::sqrt(pooled);
}

ProgressiveImage::ProgressiveImage(std::uint32_t width, std::uint32_t height, std::uint32_t rowBegin,
                                   std::uint32_t rowEnd)
    : width_(width), height_(height), rowBegin_(std::min(rowBegin, height)),
      rowEnd_(std::clamp(rowEnd, rowBegin_, height)), pixels_(static_cast<std::size_t>(width) * (rowEnd_ - rowBegin_)),
      errors_(pixels_.size(), std::numeric_limits<float>::infinity()) {}

void ProgressiveImage::addPixel(std::uint32_t pixel, const glm::vec4& sums, const glm::vec4& halfAndRays) {
  const std::size_t i = index(pixel);
  PixelMoments& m = pixels_[i];
  // One call per pixel per pass: the blocks shift by one pass, and the estimate they gave so far
  // (kept by the last call) becomes the previous decision's.
  const double previousVariance = m.variance, previousDof = m.varianceDof;
  m.previousSum = m.earlierSum;
  m.previousSamples = m.earlierSamples;
  m.earlierSum = m.sum;
  m.earlierSamples = m.samples;
  m.sum += glm::vec3(sums);
  m.samples += sums.w;
  m.halfSum = glm::vec3(halfAndRays);
  m.rays += halfAndRays.w;
  double dof = 0.0;
  const double variance = blockVariance(m, &dof);
  m.variance = static_cast<float>(variance);
  m.varianceDof = static_cast<float>(dof);
  errors_[i] = static_cast<float>(standardError(m, variance, dof, previousVariance, previousDof));
}

template <class Visit> void ProgressiveImage::forTracedNeighbours(std::uint32_t x, std::uint32_t y, Visit visit) const {
  if (x > 0 && x + 1 < width_ && y > rowBegin_ && y + 1 < rowEnd_) {
    // Away from the edges the same nine in the same order, without the loops: their counters and
    // bounds were half of a decision's instructions.
    const std::size_t c = index(x, y), w = width_;
    for (const std::size_t j : {c - w - 1, c - w, c - w + 1, c - 1, c, c + 1, c + w - 1, c + w, c + w + 1})
      if (pixels_[j].samples > 0.0f) visit(j);
    return;
  }
  const std::uint32_t x0 = x > 0 ? x - 1 : 0, x1 = std::min(width_ - 1, x + 1);
  const std::uint32_t y0 = y > rowBegin_ ? y - 1 : rowBegin_, y1 = std::min(rowEnd_ - 1, y + 1);
  for (std::uint32_t v = y0; v <= y1; ++v) {
    for (std::uint32_t u = x0; u <= x1; ++u) {
      // A neighbour never traced (outside the rendered rows) has no say.
      const std::size_t j = index(u, v);
      if (pixels_[j].samples > 0.0f) visit(j);
    }
  }
}

double ProgressiveImage::neighbourhoodError(std::uint32_t x, std::uint32_t y) const {
  double sum = 0.0;
  int count = 0;
  forTracedNeighbours(x, y, [&](std::size_t j) {
    sum += double(errors_[j]) * errors_[j];
    ++count;
  });
  if (count == 0) return std::numeric_limits<double>::infinity();
  const double own = errors_[index(x, y)];
  return std::sqrt(kOwnShare * own * own + (1.0 - kOwnShare) * sum / count);
}

double ProgressiveImage::neighbourhoodContrast(std::uint32_t x, std::uint32_t y) const {
  glm::dvec3 lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
  forTracedNeighbours(x, y, [&](std::size_t j) {
    const glm::dvec3 mean = glm::dvec3(pixels_[j].sum) / double(pixels_[j].samples);
    lo = glm::min(lo, mean);
    hi = glm::max(hi, mean);
  });
  const glm::dvec3 range = hi - lo; // -inf where no pixel had samples
  return std::max({range.r, range.g, range.b, 0.0});
}

std::vector<std::uint32_t> ProgressiveImage::stillOpen(const std::vector<std::uint32_t>& open, double threshold,
                                                       bool first) const {
  // Each pixel's decision reads only the stored moments and estimates: decided in parallel, listed
  // in `open`'s order.
  std::vector<char> keep(open.size());
  parallelFor(open.size(), kPixelsPerThread, [&](std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k) {
      const std::uint32_t x = open[k] % width_, y = open[k] / width_;
      const float samples = pixels_[index(x, y)].samples;
      const bool guarded = first || samples < kContrastGuardSamples;
      const bool settled = samples >= 2.0f && neighbourhoodError(x, y) <= threshold &&
                           (!guarded || neighbourhoodContrast(x, y) / samples <= kContrastShare * threshold);
      keep[k] = settled ? 0 : 1;
    }
  });
  std::vector<std::uint32_t> next;
  next.reserve(static_cast<std::size_t>(std::count(keep.begin(), keep.end(), char{1})));
  for (std::size_t k = 0; k < open.size(); ++k)
    if (keep[k]) next.push_back(open[k]);
  return next;
}

Image ProgressiveImage::image() const {
  Image img(width_, height_);
  const std::size_t offset = static_cast<std::size_t>(rowBegin_) * width_;
  for (std::size_t i = 0; i < pixels_.size(); ++i) {
    const PixelMoments& m = pixels_[i];
    img.pixels[offset + i] = m.samples > 0.0f ? glm::vec3(glm::dvec3(m.sum) / double(m.samples)) : glm::vec3(0.0f);
  }
  return img;
}

PixelStats ProgressiveImage::stats() const {
  PixelStats s;
  const std::size_t all = static_cast<std::size_t>(width_) * height_;
  // Outside the stored rows: no samples, no rays, and no estimate (+inf, as an EXR layer shows it).
  s.samples.assign(all, 0.0f);
  s.error.assign(all, std::numeric_limits<float>::infinity());
  s.rays.assign(all, 0.0f);
  const std::size_t offset = static_cast<std::size_t>(rowBegin_) * width_;
  for (std::size_t i = 0; i < pixels_.size(); ++i) {
    s.samples[offset + i] = pixels_[i].samples;
    // A pixel with one sample (or none) has no estimate: +inf.
    s.error[offset + i] = errors_[i];
    s.rays[offset + i] = pixels_[i].rays;
  }
  return s;
}

std::uint32_t nextPassSamples(const RenderSettings& s, std::uint32_t samplesSoFar, std::size_t openPixels,
                              double msPerSample, double spentMs) {
  // Without a threshold or limit (per-pixel statistics asked for), every pixel gets spp.
  const auto cap = static_cast<std::uint32_t>(std::max(1, s.progressive() ? s.maxSpp : s.spp));
  if (openPixels == 0 || samplesSoFar >= cap) return 0;
  std::uint32_t k;
  if (!s.progressive()) {
    k = samplesSoFar == 0 ? std::max(1u, cap / 2) : cap - samplesSoFar; // two halves: an estimate
  } else if (samplesSoFar == 0) {
    // With a noise threshold every pixel gets min_spp in three passes (a quarter, a quarter, a
    // half), so the first decision has four blocks to compare and the second pass's estimate to
    // pool; a time limit alone starts at one sample, which also measures the speed.
    k = s.noiseThreshold > 0.0 ? static_cast<std::uint32_t>(std::max(1, s.minSpp / 4)) : 1u;
  } else {
    k = samplesSoFar; // the count doubles
  }
  k = std::min(k, cap - samplesSoFar);
  if (s.timeLimit > 0.0 && msPerSample > 0.0) {
    const double leftMs = s.timeLimit * 1e3 - spentMs;
    const double perSample = msPerSample * static_cast<double>(openPixels); // one sample of each
    const double fit = leftMs / perSample;
    if (fit < 1.0) return 0;
    k = std::min<std::uint32_t>(k, static_cast<std::uint32_t>(std::min(fit, 1e9)));
  }
  return k;
}

std::vector<std::uint32_t> nextPasses(const RenderSettings& s, std::uint32_t samplesSoFar, std::size_t openPixels,
                                      double msPerSample, double spentMs, bool together) {
  std::vector<std::uint32_t> passes;
  std::uint32_t k = nextPassSamples(s, samplesSoFar, openPixels, msPerSample, spentMs);
  if (k == 0) return passes;
  passes.push_back(k);
  if (!together || !(s.noiseThreshold > 0.0) || s.timeLimit > 0.0) return passes;
  std::uint32_t samples = samplesSoFar + k;
  // A decision follows the pass that brings every pixel to min_spp.
  while (passes.size() < kPassesAtOnceMax && samples < static_cast<std::uint32_t>(s.minSpp)) {
    k = nextPassSamples(s, samples, openPixels, msPerSample, spentMs);
    if (k == 0) break;
    passes.push_back(k);
    samples += k;
  }
  return passes;
}

std::uint32_t decisionCount(const RenderSettings& s) {
  if (!(s.noiseThreshold > 0.0)) return 0;
  RenderSettings noLimit = s;
  noLimit.timeLimit = 0.0;
  std::uint32_t samples = 0, decisions = 0;
  while (std::uint32_t k = nextPassSamples(noLimit, samples, 1, 0.0, 0.0)) {
    samples += k;
    if (samples >= static_cast<std::uint32_t>(s.minSpp)) ++decisions;
  }
  return decisions;
}

std::uint64_t progressiveHostBytes(std::uint32_t width, std::uint32_t height, std::uint32_t tracedRows) {
  const std::uint64_t traced = std::uint64_t{width} * tracedRows, all = std::uint64_t{width} * height;
  // Per traced pixel: its moments and estimate, and its entry in the open list and the next one.
  // Per pixel of the image: the means (vec3) and the statistics (samples, error, rays).
  return traced * (ProgressiveImage::kBytesPerPixel + 2 * sizeof(std::uint32_t)) +
         all * (sizeof(glm::vec3) + 3 * sizeof(float));
}

void checkProgressiveMemory(std::uint32_t width, std::uint32_t height, std::uint32_t tracedRows,
                            std::uint64_t available) {
  const std::uint64_t needed = progressiveHostBytes(width, height, tracedRows);
  if (needed <= available) return;
  throw Error("sampling progressively (a noise threshold, a time limit, or the spp, error or rays AOVs) at " +
              std::to_string(width) + "x" + std::to_string(height) + " keeps " + formatBytes(needed) +
              " of per-pixel sums in host memory, and " + formatBytes(available) +
              " is available: render fewer pixels, or in tiles (--tile I/N, then vkray merge)");
}

ProgressiveSummary summarize(const PixelStats& stats, int passes) {
  ProgressiveSummary p;
  p.passes = passes;
  std::vector<double> errors;
  double sppSum = 0.0;
  std::size_t traced = 0;
  for (std::size_t i = 0; i < stats.samples.size(); ++i) {
    if (stats.samples[i] <= 0.0f) continue; // rows outside the tile
    ++traced;
    sppSum += stats.samples[i];
    p.sppMax = std::max(p.sppMax, static_cast<double>(stats.samples[i]));
    errors.push_back(stats.error[i]);
  }
  if (traced == 0) return p;
  p.sppMean = sppSum / static_cast<double>(traced);
  p.converged = 1.0;
  double sum = 0.0;
  for (double e : errors) sum += std::isfinite(e) ? e : 0.0;
  p.errorMean = sum / static_cast<double>(errors.size());
  // The 95th percentile's element alone, not a sort of every pixel's (2 M at 1920 x 1080).
  const auto p95 =
      errors.begin() + static_cast<std::ptrdiff_t>(std::min(
                           errors.size() - 1, static_cast<std::size_t>(0.95 * static_cast<double>(errors.size()))));
  std::nth_element(errors.begin(), p95, errors.end());
  p.errorP95 = *p95;
  return p;
}

} // namespace vkray
