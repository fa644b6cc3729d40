// Tile files and their merge (see tile_io.h).
#include "image/tile_io.h"

#include <algorithm>
#include <fstream>
#include <map>
#include <sstream>

#include <nlohmann/json.hpp>

#include "image/image_io.h"
#include "util/error.h"

namespace vkray {

namespace fs = std::filesystem;

namespace {

constexpr const char* kTileFormat = "vkray-tile";
constexpr int kTileVersion = 1;

struct Tile {
  fs::path path;
  TileInfo info;
};

TileInfo readSidecar(const fs::path& tile) {
  const fs::path side = tileSidecarPath(tile);
  std::ifstream in(side, std::ios::binary);
  if (!in) throw InputError(tile.string(), "no tile description " + side.filename().string() + " beside it");
  std::stringstream text;
  text << in.rdbuf();
  TileInfo info;
  try {
    auto j = nlohmann::json::parse(text.str());
    if (j.at("format").get<std::string>() != kTileFormat || j.at("version").get<int>() != kTileVersion) {
      throw InputError(side.string(), "not a vkray tile description (format vkray-tile, version 1)");
    }
    info.width = j.at("width").get<std::uint32_t>();
    info.height = j.at("height").get<std::uint32_t>();
    info.rowBegin = j.at("row_begin").get<std::uint32_t>();
    info.rowEnd = j.at("row_end").get<std::uint32_t>();
    info.frame = j.at("frame").get<int>();
    info.fingerprint = j.at("fingerprint").get<std::string>();
    info.scene = j.at("scene").get<std::string>();
  } catch (const nlohmann::json::exception& e) {
    throw InputError(side.string(), std::string("not a vkray tile description: ") + e.what());
  }
  if (info.width == 0 || info.height == 0 || info.rowBegin >= info.rowEnd || info.rowEnd > info.height) {
    throw InputError(side.string(), "rows " + std::to_string(info.rowBegin) + "-" + std::to_string(info.rowEnd) +
                                        " do not fit an image of " + std::to_string(info.height) + " rows");
  }
  return info;
}

std::string rowsText(const TileInfo& t) {
  return "rows " + std::to_string(t.rowBegin) + "-" + std::to_string(t.rowEnd - 1);
}

} // namespace

void tileRows(std::uint32_t height, std::uint32_t index, std::uint32_t count, std::uint32_t& r0, std::uint32_t& r1) {
  r0 = static_cast<std::uint32_t>(static_cast<std::uint64_t>(index - 1) * height / count);
  r1 = static_cast<std::uint32_t>(static_cast<std::uint64_t>(index) * height / count);
}

fs::path tileSidecarPath(const fs::path& tile) {
  return fs::path(tile.string() + ".tile.json");
}

void writeTile(const fs::path& path, const Image& whole, const TileInfo& info) {
  Image band(whole.width, info.rowEnd - info.rowBegin);
  std::copy(whole.pixels.begin() + static_cast<std::ptrdiff_t>(info.rowBegin) * whole.width,
            whole.pixels.begin() + static_cast<std::ptrdiff_t>(info.rowEnd) * whole.width, band.pixels.begin());
  nlohmann::json j = {{"format", kTileFormat}, {"version", kTileVersion},         {"width", info.width},
                      {"height", info.height}, {"row_begin", info.rowBegin},      {"row_end", info.rowEnd},
                      {"frame", info.frame},   {"fingerprint", info.fingerprint}, {"scene", info.scene}};
  std::string text = j.dump(2) + "\n";
  // The description first, so a tile whose pixels exist always has one; if the pixels then cannot
  // be written, the description goes too (no partial output).
  const fs::path side = tileSidecarPath(path);
  writeFileAtomic(side, std::vector<std::uint8_t>(text.begin(), text.end()));
  try {
    writeFileAtomic(path, encodePfm(band));
  } catch (...) {
    std::error_code ec;
    fs::remove(side, ec);
    throw;
  }
}

Image mergeTiles(const std::vector<fs::path>& paths) {
  if (paths.empty()) throw InputError("merge", "no tiles given");
  std::vector<Tile> tiles;
  std::map<fs::path, fs::path> given; // each file once: its canonical path -> as given
  for (const fs::path& p : paths) {
    if (imageFormatFor(p) != ImageFormat::Pfm) throw InputError(p.string(), "a tile is a .pfm file");
    tiles.push_back({p, readSidecar(p)});
    std::error_code ec;
    fs::path canonical = fs::weakly_canonical(p, ec);
    if (ec) canonical = fs::absolute(p).lexically_normal();
    auto [at, added] = given.emplace(canonical, p);
    if (!added) {
      throw InputError(p.string(), at->second == p ? std::string("is given twice")
                                                   : "is the same file as " + at->second.string() + ", given before");
    }
  }
  const TileInfo& first = tiles.front().info;
  for (const Tile& t : tiles) {
    if (t.info.width != first.width || t.info.height != first.height) {
      throw InputError(t.path.string(), "belongs to a " + std::to_string(t.info.width) + "x" +
                                            std::to_string(t.info.height) + " image, " + tiles.front().path.string() +
                                            " to a " + std::to_string(first.width) + "x" +
                                            std::to_string(first.height) + " one");
    }
    if (t.info.frame != first.frame) {
      throw InputError(t.path.string(), "is of frame " + std::to_string(t.info.frame) + ", " +
                                            tiles.front().path.string() + " of frame " + std::to_string(first.frame));
    }
    if (t.info.fingerprint != first.fingerprint) {
      throw InputError(t.path.string(), "has fingerprint " + t.info.fingerprint + ", " + tiles.front().path.string() +
                                            " has " + first.fingerprint +
                                            " (rendered from a different scene or with different settings)");
    }
  }
  std::sort(tiles.begin(), tiles.end(), [](const Tile& a, const Tile& b) { return a.info.rowBegin < b.info.rowBegin; });
  std::uint32_t next = 0;
  for (std::size_t i = 0; i < tiles.size(); ++i) {
    const TileInfo& t = tiles[i].info;
    if (t.rowBegin > next) {
      throw InputError(tiles[i].path.string(),
                       "leaves a gap: no tile has rows " + std::to_string(next) + "-" + std::to_string(t.rowBegin - 1));
    }
    if (t.rowBegin < next) {
      throw InputError(tiles[i].path.string(),
                       rowsText(t) + " overlap " + tiles[i - 1].path.string() + "'s " + rowsText(tiles[i - 1].info));
    }
    next = t.rowEnd;
  }
  if (next != first.height) {
    throw InputError(tiles.back().path.string(),
                     "leaves a gap: no tile has rows " + std::to_string(next) + "-" + std::to_string(first.height - 1));
  }
  Image whole(first.width, first.height);
  for (const Tile& t : tiles) {
    Image band = readImage(t.path);
    if (band.width != t.info.width || band.height != t.info.rowEnd - t.info.rowBegin) {
      throw InputError(t.path.string(), "is " + std::to_string(band.width) + "x" + std::to_string(band.height) +
                                            ", its description says " + std::to_string(t.info.width) + "x" +
                                            std::to_string(t.info.rowEnd - t.info.rowBegin));
    }
    std::copy(band.pixels.begin(), band.pixels.end(),
              whole.pixels.begin() + static_cast<std::ptrdiff_t>(t.info.rowBegin) * whole.width);
  }
  return whole;
}

} // namespace vkray
