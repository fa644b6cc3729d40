// sRGB encoding shared by PNG output, the viewer and the error metrics.
#include "image/image.h"

#include <algorithm>
#include <cmath>

namespace vkray {

float linearToSrgb(float v) {
  v = std::clamp(v, 0.0f, 1.0f);
  return v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
}

float srgbToLinear(float e) {
  e = std::clamp(e, 0.0f, 1.0f);
  return e <= 0.04045f ? e / 12.92f : std::pow((e + 0.055f) / 1.055f, 2.4f);
}

std::uint8_t encodeSrgb8(float linear) {
  if (!(linear == linear)) linear = 0.0f; // NaN never reaches a file
  return static_cast<std::uint8_t>(std::lround(linearToSrgb(linear) * 255.0f));
}

} // namespace vkray
