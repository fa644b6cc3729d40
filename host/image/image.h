// An image in linear RGB floats, row-major, (0, 0) at the top-left.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

namespace vkray {

struct Image {
  std::uint32_t width = 0;
  std::uint32_t height = 0;
  std::vector<glm::vec3> pixels; // width * height

  Image() = default;
  Image(std::uint32_t w, std::uint32_t h, glm::vec3 fill = glm::vec3(0.0f))
      : width(w), height(h), pixels(static_cast<std::size_t>(w) * h, fill) {}

  glm::vec3& at(std::uint32_t x, std::uint32_t y) { return pixels[static_cast<std::size_t>(y) * width + x]; }
  const glm::vec3& at(std::uint32_t x, std::uint32_t y) const {
    return pixels[static_cast<std::size_t>(y) * width + x];
  }
};

// sRGB transfer function (IEC 61966-2-1), on [0, 1].
float linearToSrgb(float linear);
float srgbToLinear(float encoded);

// 8-bit sRGB value of a linear value: clamped, encoded, rounded to nearest; NaN gives 0.
std::uint8_t encodeSrgb8(float linear);
// The same for `count` values at once (the table found once, the lookup inlined): PNG output.
void encodeSrgb8(const float* linear, std::size_t count, std::uint8_t* out);
// The same by the formula itself, a pow per call (encodeSrgb8 finds its bytes from a table of the
// formula's 255 thresholds: the same bytes, several times faster).
std::uint8_t encodeSrgb8Formula(float linear);

} // namespace vkray
