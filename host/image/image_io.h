// Image files: PNG (8-bit sRGB) and PFM (linear float), chosen by extension. Writes are atomic: a
// temporary file in the target directory, renamed over the target only when complete.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "image/image.h"

namespace vkray {

enum class ImageFormat { Png, Pfm };

// Format for an output path, or InputError if the extension is not .png or .pfm.
ImageFormat imageFormatFor(const std::filesystem::path& path);

// Checks, before any work, that `path` can be written: known extension, existing writable
// directory, not a directory itself. Throws InputError otherwise.
void checkOutputPath(const std::filesystem::path& path);

std::vector<std::uint8_t> encodePng(const Image& image);
std::vector<std::uint8_t> encodePfm(const Image& image);

void writeImage(const std::filesystem::path& path, const Image& image);
Image readImage(const std::filesystem::path& path); // PNG decoded to linear, or PFM

// Writes bytes to path atomically (temp file + fsync + rename). Throws InputError naming the path.
void writeFileAtomic(const std::filesystem::path& path, const std::vector<std::uint8_t>& bytes);

} // namespace vkray
