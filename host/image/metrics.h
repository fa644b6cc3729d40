// Error metrics between an image and a reference, as the accuracy report states them.
#pragma once

#include "image/image.h"

namespace vkray {

struct ImageError {
  double rmse = 0.0;         // root mean square error over all channels, linear RGB
  double psnr = 0.0;         // 20 log10(1 / rmse) dB, peak 1.0 linear; +inf when identical
  double maxAbs = 0.0;       // largest absolute channel difference, linear RGB
  double fractionOff = 0.0;  // share of pixels with a channel off by > 1/255 after sRGB encoding
  std::size_t pixelsOff = 0; // count of those pixels
};

// Throws Error when the sizes differ.
ImageError compareImages(const Image& image, const Image& reference);

// Per-pixel absolute error (max over channels), for heat maps.
Image errorMap(const Image& image, const Image& reference);

} // namespace vkray
