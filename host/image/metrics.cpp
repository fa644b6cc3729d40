// Error metrics (see metrics.h).
#include "image/metrics.h"

#include <cmath>
#include <limits>

#include "util/error.h"

namespace vkray {

ImageError compareImages(const Image& image, const Image& reference) {
  if (image.width != reference.width || image.height != reference.height) {
    throw Error("cannot compare a " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                " image with a " + std::to_string(reference.width) + "x" + std::to_string(reference.height) + " one");
  }
  ImageError e;
  double sum = 0.0;
  for (std::size_t i = 0; i < image.pixels.size(); ++i) {
    bool off = false;
    for (int c = 0; c < 3; ++c) {
      double a = image.pixels[i][c];
      double b = reference.pixels[i][c];
      double d = a - b;
      sum += d * d;
      e.maxAbs = std::max(e.maxAbs, std::abs(d));
      double encoded = std::abs(double(linearToSrgb(static_cast<float>(a))) - linearToSrgb(static_cast<float>(b)));
      if (encoded > 1.0 / 255.0) off = true;
    }
    if (off) ++e.pixelsOff;
  }
  double n = static_cast<double>(image.pixels.size()) * 3.0;
  e.rmse = n > 0 ? std::sqrt(sum / n) : 0.0;
  e.psnr = e.rmse > 0 ? 20.0 * std::log10(1.0 / e.rmse) : std::numeric_limits<double>::infinity();
  e.fractionOff =
      image.pixels.empty() ? 0.0 : static_cast<double>(e.pixelsOff) / static_cast<double>(image.pixels.size());
  return e;
}

Image errorMap(const Image& image, const Image& reference) {
  if (image.width != reference.width || image.height != reference.height) throw Error("image sizes differ");
  Image out(image.width, image.height);
  for (std::size_t i = 0; i < image.pixels.size(); ++i) {
    glm::vec3 d = glm::abs(image.pixels[i] - reference.pixels[i]);
    out.pixels[i] = glm::vec3(std::max(d.x, std::max(d.y, d.z)));
  }
  return out;
}

} // namespace vkray
