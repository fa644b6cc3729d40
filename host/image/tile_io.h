// Tiles: a band of rows of one image, written as a PFM of just those rows plus a sidecar
// "<file>.tile.json" saying where the band belongs. Any PFM reader reads the tile's pixels; merge
// reads the sidecars, checks the tiles belong together and assembles the whole image.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "image/image.h"

namespace vkray {

struct TileInfo {
  std::uint32_t width = 0;  // of the whole image
  std::uint32_t height = 0; // of the whole image
  std::uint32_t rowBegin = 0;
  std::uint32_t rowEnd = 0; // exclusive
  int frame = 0;
  std::string fingerprint; // sceneFingerprint (scene, settings, frame, size)
  std::string scene;       // the scene file, for messages
};

// Rows [r0, r1) of band `index` (1-based) of `count` equal horizontal bands of `height` rows.
void tileRows(std::uint32_t height, std::uint32_t index, std::uint32_t count, std::uint32_t& r0, std::uint32_t& r1);

std::filesystem::path tileSidecarPath(const std::filesystem::path& tile);

// Writes rows [info.rowBegin, info.rowEnd) of `whole` to `path` (a .pfm) and the sidecar, both atomically.
void writeTile(const std::filesystem::path& path, const Image& whole, const TileInfo& info);

// Reads the tiles, checks they are one image (same fingerprint, size and frame; every row exactly
// once) and returns it. Throws InputError naming the tile at fault.
Image mergeTiles(const std::vector<std::filesystem::path>& tiles);

} // namespace vkray
