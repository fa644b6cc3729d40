// OpenEXR files (Debian's libopenexr-dev): linear RGB as the standard `R`, `G`, `B` channels, 32-bit
// float or, asked for, 16-bit half; ZIP-compressed scan lines. The float channels hold the render's
// linear values bit for bit, the same numbers a PFM holds. Extra channels (the AOV layers, named
// `layer.channel` by OpenEXR's convention, as `depth.Z`) are always 32-bit float.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "image/image.h"

namespace vkray {

enum class ExrPixels { Float, Half };

// One channel beside R, G and B: its full name and one value per pixel, row-major.
struct ExrChannel {
  std::string name;
  std::vector<float> values;
};

// `extra` channels must each hold image.width * image.height values and be named apart from each
// other and from R, G, B (Error otherwise: a caller's mistake, not the user's).
std::vector<std::uint8_t> encodeExr(const Image& image, ExrPixels pixels, const std::vector<ExrChannel>& extra = {});

// The R, G and B channels of an EXR file (a missing channel reads as 0), its data window's size;
// InputError naming the file for anything OpenEXR cannot read.
Image readExr(const std::filesystem::path& path);

} // namespace vkray
