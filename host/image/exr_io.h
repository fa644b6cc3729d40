// OpenEXR files (Debian's libopenexr-dev): linear RGB as the standard `R`, `G`, `B` channels, 32-bit
// float or, asked for, 16-bit half; ZIP-compressed scan lines. The float channels hold the render's
// linear values bit for bit, the same numbers a PFM holds.
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

#include "image/image.h"

namespace vkray {

enum class ExrPixels { Float, Half };

std::vector<std::uint8_t> encodeExr(const Image& image, ExrPixels pixels);

// The R, G and B channels of an EXR file (a missing channel reads as 0), its data window's size;
// InputError naming the file for anything OpenEXR cannot read.
Image readExr(const std::filesystem::path& path);

} // namespace vkray
