// Decoding PNG and JPEG files into 8-bit RGBA, through Debian's libpng (simplified API) and
// libjpeg-turbo: the decoders every distribution fuzzes and patches, in place of a header-only one.
// Failures throw InputError with one line naming the file and what the decoder found.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace vkray {

struct Rgba8Image {
  std::uint32_t width = 0;
  std::uint32_t height = 0;
  std::vector<std::uint8_t> rgba; // width * height * 4, rows top to bottom, colour as stored (sRGB)
};

// What an image may be before any pixel is decoded: the header's size is checked against these, so
// a 2-byte file claiming 10^5 x 10^5 pixels is refused without allocating.
struct DecodeLimits {
  std::uint32_t maxSide = 16384;
  std::uint64_t maxPixels = std::uint64_t(64) << 20;
};

enum class EncodedFormat { Png, Jpeg, Unknown };

// By the first bytes (PNG's 8-byte signature, JPEG's SOI marker), not by a file name.
EncodedFormat sniffFormat(const std::uint8_t* bytes, std::size_t size);

Rgba8Image decodePngOrJpeg(const std::uint8_t* bytes, std::size_t size, const std::string& shownAs,
                           const DecodeLimits& limits = {});

} // namespace vkray
