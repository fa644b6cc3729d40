// sRGB encoding shared by PNG output, the viewer and the error metrics.
#include "image/image.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>

namespace vkray {

float linearToSrgb(float v) {
  v = std::clamp(v, 0.0f, 1.0f);
  return v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
}

float srgbToLinear(float e) {
  e = std::clamp(e, 0.0f, 1.0f);
  return e <= 0.04045f ? e / 12.92f : std::pow((e + 0.055f) / 1.055f, 2.4f);
}

std::uint8_t encodeSrgb8Formula(float linear) {
  if (!(linear == linear)) linear = 0.0f; // NaN never reaches a file
  return static_cast<std::uint8_t>(std::lround(linearToSrgb(linear) * 255.0f));
}

namespace {

// thresholds[k]: the smallest float in [0, 1] that the formula encodes to k or more (k = 1..255),
// found by bisection over the bit patterns of the non-negative floats (ordered like the floats).
// The formula is monotone, so "count the thresholds at or below x" gives its byte exactly; a
// test checks that against the formula around every threshold and across [0, 1].
std::array<float, 256> makeThresholds() {
  std::array<float, 256> t{};
  t[0] = 0.0f;
  for (int k = 1; k < 256; ++k) {
    std::uint32_t lo = 0, hi = std::bit_cast<std::uint32_t>(1.0f); // formula(lo) < k <= formula(hi)
    while (hi - lo > 1) {
      std::uint32_t mid = lo + (hi - lo) / 2;
      (encodeSrgb8Formula(std::bit_cast<float>(mid)) >= k ? hi : lo) = mid;
    }
    t[static_cast<std::size_t>(k)] = std::bit_cast<float>(hi);
  }
  return t;
}

} // namespace

std::uint8_t encodeSrgb8(float linear) {
  static const std::array<float, 256> thresholds = makeThresholds();
  if (!(linear > 0.0f)) return 0; // zero, negative, NaN
  // 8 comparisons instead of a pow: PNG output encodes a value per channel and pixel.
  auto it = std::upper_bound(thresholds.begin() + 1, thresholds.end(), linear);
  return static_cast<std::uint8_t>(it - thresholds.begin() - 1);
}

} // namespace vkray
