// sRGB encoding shared by PNG output, the viewer and the error metrics.
#include "image/image.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <vector>

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
// found by bisection over the bit patterns of the non-negative floats (ordered like the floats);
// thresholds[256] is +inf. The formula is monotone, so "count the thresholds at or below x" gives
// its byte exactly; a test checks that against the formula around every threshold and across [0, 1].
std::array<float, 257> makeThresholds() {
  std::array<float, 257> t{};
  t[0] = 0.0f;
  for (int k = 1; k < 256; ++k) {
    std::uint32_t lo = 0, hi = std::bit_cast<std::uint32_t>(1.0f); // formula(lo) < k <= formula(hi)
    while (hi - lo > 1) {
      std::uint32_t mid = lo + (hi - lo) / 2;
      (encodeSrgb8Formula(std::bit_cast<float>(mid)) >= k ? hi : lo) = mid;
    }
    t[static_cast<std::size_t>(k)] = std::bit_cast<float>(hi);
  }
  t[256] = std::numeric_limits<float>::infinity();
  return t;
}

// The floats of [0, 1) in buckets of 2^15 bit patterns (exponent and the top 8 bits of the
// mantissa: 32 512 buckets), each holding the byte of its first float. A bucket spans 0.4 % of its
// values or less, and neighbouring thresholds lie at least 0.9 % apart (at 1.0; more everywhere
// below), so a bucket holds at most one threshold and one comparison finishes the lookup.
constexpr int kBucketShift = 15;
constexpr std::uint32_t kBuckets = 0x3F800000u >> kBucketShift; // the buckets below 1.0

struct SrgbTable {
  std::array<float, 257> thresholds = makeThresholds();
  std::vector<std::uint8_t> bucketByte = std::vector<std::uint8_t>(kBuckets);
  SrgbTable() {
    std::uint32_t k = 0;
    for (std::uint32_t b = 0; b < kBuckets; ++b) {
      const float first = std::bit_cast<float>(b << kBucketShift);
      while (k < 255 && thresholds[k + 1] <= first) ++k;
      bucketByte[b] = static_cast<std::uint8_t>(k);
      // At most one threshold inside the bucket (the comparison in encodeSrgb8 takes one step).
      const float last = std::bit_cast<float>(((b + 1) << kBucketShift) - 1);
      if (k + 2 <= 256 && thresholds[k + 2] <= last)
        throw std::logic_error("sRGB table: a bucket holds two thresholds");
    }
  }
};

const SrgbTable& srgbTable() {
  static const SrgbTable table;
  return table;
}

// The byte of one value: a table lookup and one comparison instead of a pow, or of a binary search
// whose branches the CPU cannot predict (that took 25 ms of an 800x600 PNG's 34 ms).
inline std::uint8_t lookUpSrgb8(const SrgbTable& table, float linear) {
  if (!(linear > 0.0f)) return 0; // zero, negative, NaN
  if (!(linear < 1.0f)) return 255;
  const std::uint32_t k = table.bucketByte[std::bit_cast<std::uint32_t>(linear) >> kBucketShift];
  return static_cast<std::uint8_t>(k + (linear >= table.thresholds[k + 1] ? 1u : 0u));
}

} // namespace

std::uint8_t encodeSrgb8(float linear) {
  return lookUpSrgb8(srgbTable(), linear);
}

void encodeSrgb8(const float* linear, std::size_t count, std::uint8_t* out) {
  const SrgbTable& table = srgbTable();
  for (std::size_t i = 0; i < count; ++i) out[i] = lookUpSrgb8(table, linear[i]);
}

} // namespace vkray
