// Image files: PNG (8-bit sRGB), PFM (linear float) and OpenEXR (linear float or half; exr_io.h),
// chosen by extension. Writes are atomic: a
// temporary file in the target directory, renamed over the target only when complete.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "image/exr_io.h"
#include "image/image.h"
#include "util/atomic_file.h" // writeFileAtomic

namespace vkray {

enum class ImageFormat { Png, Pfm, Exr };

// Format for an output path, or InputError if the extension is not .png, .pfm or .exr.
ImageFormat imageFormatFor(const std::filesystem::path& path);

// Checks, before any work, that `path` can be written: known extension, existing writable
// directory, not a directory itself. Throws InputError otherwise.
void checkOutputPath(const std::filesystem::path& path);

std::vector<std::uint8_t> encodePng(const Image& image);
std::vector<std::uint8_t> encodePfm(const Image& image);

struct ImageWriteOptions {
  bool exrHalf = false; // EXR channels as 16-bit half instead of 32-bit float
  // EXR only: channels beside R, G, B (the AOV layers; render/aov.h). Another format with layers is
  // a caller's mistake (Error): PNG and PFM hold RGB alone.
  std::vector<ExrChannel> exrLayers;
};

void writeImage(const std::filesystem::path& path, const Image& image, const ImageWriteOptions& options = {});
Image readImage(const std::filesystem::path& path); // PNG decoded to linear, PFM or EXR

} // namespace vkray
