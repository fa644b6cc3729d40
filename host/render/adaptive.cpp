// Progressive rendering's host side (see adaptive.h).
#include "render/adaptive.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "../../shaders/shared/resolve_types.h"
#include "util/error.h"

namespace vkray {

// The viewer's converged share applies the same rule (shaders/convergence.comp).
static_assert(static_cast<float>(ProgressiveImage::kOwnShare) == gpu::kConvergenceOwnShare);

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
  const glm::dvec3 lastSum = m.sum - m.earlierSum;
  const double lastSamples = m.samples - m.earlierSamples;
  const double halfSamples = firstHalf(static_cast<std::uint32_t>(lastSamples));
  const std::array<std::pair<glm::dvec3, double>, 4> blocks{{
      {m.previousSum, m.previousSamples},
      {m.earlierSum - m.previousSum, m.earlierSamples - m.previousSamples},
      {m.halfSum, halfSamples},
      {lastSum - m.halfSum, lastSamples - halfSamples},
  }};
  int count = 0;
  for (const auto& b : blocks) count += b.second > 0.0 ? 1 : 0;
  if (dof) *dof = std::max(0, count - 1);
  if (count < 2) return 0.0;
  const glm::dvec3 mean = m.sum / m.samples;
  double worst = 0.0;
  for (int c = 0; c < 3; ++c) {
    double squares = 0.0; // sum_j m_j (x_j - x)^2
    for (const auto& [sum, samples] : blocks) {
      if (samples <= 0.0) continue;
      const double d = sum[c] / samples - mean[c];
      squares += samples * d * d;
    }
    worst = std::max(worst, squares / (count - 1) / m.samples);
  }
  return worst;
}

double standardError(const PixelMoments& m) {
  if (m.samples < 2.0) return std::numeric_limits<double>::infinity();
  double dof = 0.0;
  const double v = blockVariance(m, &dof);
  if (dof <= 0.0) return std::numeric_limits<double>::infinity();
  // The previous estimate was of the mean of earlierSamples; as 1 / n, it scales to this count.
  // (A stratified sequence converges faster than 1 / n, so it leans towards more samples.)
  const double pooled =
      m.previousDof > 0.0 && m.earlierSamples > 0.0
          ? (dof * v + m.previousDof * m.previousVariance * (m.earlierSamples / m.samples)) / (dof + m.previousDof)
          : v;
  return std::sqrt(pooled);
}

ProgressiveImage::ProgressiveImage(std::uint32_t width, std::uint32_t height)
    : width_(width), height_(height), pixels_(static_cast<std::size_t>(width) * height),
      errors_(pixels_.size(), std::numeric_limits<double>::infinity()) {}

void ProgressiveImage::add(std::uint32_t x, std::uint32_t y, const glm::vec4& sums, const glm::vec4& halfAndRays) {
  std::size_t i = static_cast<std::size_t>(y) * width_ + x;
  PixelMoments& m = pixels_[i];
  // One call per pixel per pass: the blocks shift by one pass, and the estimate they gave so far
  // becomes the previous decision's.
  m.previousVariance = blockVariance(m, &m.previousDof);
  m.previousSum = m.earlierSum;
  m.previousSamples = m.earlierSamples;
  m.earlierSum = m.sum;
  m.earlierSamples = m.samples;
  m.sum += glm::dvec3(glm::vec3(sums));
  m.samples += sums.w;
  m.halfSum = glm::dvec3(glm::vec3(halfAndRays));
  m.rays += halfAndRays.w;
  errors_[i] = standardError(m);
}

double ProgressiveImage::neighbourhoodError(std::uint32_t x, std::uint32_t y) const {
  const std::uint32_t x0 = x > 0 ? x - 1 : 0, x1 = std::min(width_ - 1, x + 1);
  const std::uint32_t y0 = y > 0 ? y - 1 : 0, y1 = std::min(height_ - 1, y + 1);
  double sum = 0.0;
  int count = 0;
  for (std::uint32_t v = y0; v <= y1; ++v) {
    for (std::uint32_t u = x0; u <= x1; ++u) {
      // A neighbour never traced (outside the rendered rows) has no say.
      const std::size_t j = static_cast<std::size_t>(v) * width_ + u;
      if (pixels_[j].samples <= 0.0) continue;
      sum += errors_[j] * errors_[j];
      ++count;
    }
  }
  if (count == 0) return std::numeric_limits<double>::infinity();
  const double own = errors_[static_cast<std::size_t>(y) * width_ + x];
  return std::sqrt(kOwnShare * own * own + (1.0 - kOwnShare) * sum / count);
}

std::vector<std::uint32_t> ProgressiveImage::stillOpen(const std::vector<std::uint32_t>& open, double threshold) const {
  std::vector<std::uint32_t> next;
  for (std::uint32_t i : open) {
    if (pixels_[i].samples < 2.0 || !(neighbourhoodError(i % width_, i / width_) <= threshold)) next.push_back(i);
  }
  return next;
}

Image ProgressiveImage::image() const {
  Image img(width_, height_);
  for (std::size_t i = 0; i < pixels_.size(); ++i) {
    const PixelMoments& m = pixels_[i];
    img.pixels[i] = m.samples > 0.0 ? glm::vec3(m.sum / m.samples) : glm::vec3(0.0f);
  }
  return img;
}

PixelStats ProgressiveImage::stats() const {
  PixelStats s;
  s.samples.resize(pixels_.size());
  s.error.resize(pixels_.size());
  s.rays.resize(pixels_.size());
  for (std::size_t i = 0; i < pixels_.size(); ++i) {
    s.samples[i] = static_cast<float>(pixels_[i].samples);
    // A pixel with one sample (or none) has no estimate: +inf, as an EXR layer shows it.
    s.error[i] = static_cast<float>(errors_[i]);
    s.rays[i] = static_cast<float>(pixels_[i].rays);
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
  std::sort(errors.begin(), errors.end());
  double sum = 0.0;
  for (double e : errors) sum += std::isfinite(e) ? e : 0.0;
  p.errorMean = sum / static_cast<double>(errors.size());
  p.errorP95 = errors[std::min(errors.size() - 1, static_cast<std::size_t>(0.95 * static_cast<double>(errors.size())))];
  return p;
}

} // namespace vkray
