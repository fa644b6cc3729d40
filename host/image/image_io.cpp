// PNG/PFM encoding and decoding; writes go through writeFileAtomic (util/atomic_file.h).
#include "image/image_io.h"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <zlib.h>

#include "image/decode.h"
#include "image/exr_io.h"
#include "util/error.h"
#include "util/file_extension.h"
#include "util/parallel.h"

namespace vkray {

namespace fs = std::filesystem;

ImageFormat imageFormatFor(const fs::path& path) {
  const std::string ext = lowerExtension(path);
  if (ext == ".png") return ImageFormat::Png;
  if (ext == ".pfm") return ImageFormat::Pfm;
  if (ext == ".exr") return ImageFormat::Exr;
  throw InputError(path.string(), "unknown image format '" + ext + "' (use .png, .pfm or .exr)");
}

void checkOutputPath(const fs::path& path) {
  imageFormatFor(path);
  std::error_code ec;
  if (fs::is_directory(path, ec)) throw InputError(path.string(), "is a directory");
  fs::path dir = path.parent_path();
  if (dir.empty()) dir = ".";
  if (!fs::is_directory(dir, ec)) throw InputError(path.string(), "directory '" + dir.string() + "' does not exist");
  if (::access(dir.c_str(), W_OK) != 0) {
    throw InputError(path.string(), "cannot write to directory '" + dir.string() + "': " + std::strerror(errno));
  }
}

namespace {

// 8-bit RGB rows to PNG: the Sub filter on every row, zlib level 1, and the image deflated in
// pieces side by side. A rendered image's rows are smooth runs that Sub turns into near-zero bytes
// a fast deflate packs well (the showcase at 800x600: 152 KB, where stb_image_write's level 8 and
// best-of-five filters gave 161 KB in five times the time). Each piece of kPngPieceBytes of
// filtered rows is a raw deflate stream of its own, the pieces before the last ending on a byte
// boundary (Z_SYNC_FLUSH) so that they join into one stream, as pigz does; the pieces depend on the
// width alone, never on the machine's threads, so the file is the same bytes everywhere. A piece
// starts without the previous one's window, which costs a few hundred bytes per piece.
constexpr std::size_t kPngPieceBytes = std::size_t{1} << 17;
constexpr std::size_t kPngChunkBytes = std::size_t{1} << 20; // IDAT chunk size

void appendU32(std::vector<std::uint8_t>& out, std::uint32_t v) {
  for (int shift = 24; shift >= 0; shift -= 8) out.push_back(static_cast<std::uint8_t>(v >> shift));
}

void appendChunk(std::vector<std::uint8_t>& out, const char (&type)[5], const std::uint8_t* data, std::size_t size) {
  appendU32(out, static_cast<std::uint32_t>(size));
  const std::size_t at = out.size();
  out.insert(out.end(), type, type + 4);
  if (size > 0) out.insert(out.end(), data, data + size);
  appendU32(out, static_cast<std::uint32_t>(crc32(0L, out.data() + at, static_cast<uInt>(size + 4))));
}

struct DeflatedPiece {
  std::vector<std::uint8_t> bytes;
  std::uint32_t adler = 0; // of the piece's filtered bytes
  std::size_t filteredBytes = 0;
};

// Rows [row0, row1) filtered with Sub and deflated raw; `last` finishes the stream.
DeflatedPiece deflateRows(const std::uint8_t* rgb, std::uint32_t width, std::uint32_t row0, std::uint32_t row1,
                          bool last) {
  const std::size_t stride = std::size_t{3} * width;
  std::vector<std::uint8_t> filtered((stride + 1) * (row1 - row0));
  std::uint8_t* f = filtered.data();
  for (std::uint32_t y = row0; y < row1; ++y) {
    const std::uint8_t* row = rgb + y * stride;
    *f++ = 1; // Sub: each byte less the same channel's byte of the pixel to its left
    for (std::size_t i = 0; i < stride; ++i) *f++ = static_cast<std::uint8_t>(row[i] - (i >= 3 ? row[i - 3] : 0));
  }
  DeflatedPiece piece;
  piece.filteredBytes = filtered.size();
  piece.adler = static_cast<std::uint32_t>(adler32(1L, filtered.data(), static_cast<uInt>(filtered.size())));
  z_stream z{};
  if (deflateInit2(&z, 1, Z_DEFLATED, -15, 8, Z_DEFAULT_STRATEGY) != Z_OK) throw Error("PNG encoding failed (zlib)");
  piece.bytes.resize(deflateBound(&z, static_cast<uLong>(filtered.size())) + 16);
  z.next_in = filtered.data();
  z.avail_in = static_cast<uInt>(filtered.size());
  z.next_out = piece.bytes.data();
  z.avail_out = static_cast<uInt>(piece.bytes.size());
  const int result = deflate(&z, last ? Z_FINISH : Z_SYNC_FLUSH);
  const bool complete = last ? result == Z_STREAM_END : (result == Z_OK && z.avail_in == 0 && z.avail_out > 0);
  piece.bytes.resize(piece.bytes.size() - z.avail_out);
  deflateEnd(&z);
  if (!complete) throw Error("PNG encoding failed (zlib)");
  return piece;
}

std::vector<std::uint8_t> encodeRgbPng(const std::uint8_t* rgb, std::uint32_t width, std::uint32_t height) {
  const std::size_t rowBytes = std::size_t{3} * width + 1;
  const auto rowsPerPiece = static_cast<std::uint32_t>(std::max<std::size_t>(1, kPngPieceBytes / rowBytes));
  const std::uint32_t pieces = (height + rowsPerPiece - 1) / rowsPerPiece;
  std::vector<DeflatedPiece> deflated(pieces);
  parallelFor(pieces, 1, [&](std::size_t begin, std::size_t end) {
    for (std::size_t p = begin; p < end; ++p) {
      const auto row0 = static_cast<std::uint32_t>(p) * rowsPerPiece;
      deflated[p] = deflateRows(rgb, width, row0, std::min(height, row0 + rowsPerPiece), p + 1 == pieces);
    }
  });
  // The zlib stream: header (deflate, 32 KiB window, fastest), the pieces, the Adler-32 of all.
  std::vector<std::uint8_t> zlib = {0x78, 0x01};
  std::uint32_t adler = 1;
  for (const DeflatedPiece& piece : deflated) {
    zlib.insert(zlib.end(), piece.bytes.begin(), piece.bytes.end());
    adler = static_cast<std::uint32_t>(adler32_combine(adler, piece.adler, static_cast<z_off_t>(piece.filteredBytes)));
  }
  appendU32(zlib, adler);

  std::vector<std::uint8_t> out = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  std::vector<std::uint8_t> header;
  appendU32(header, width);
  appendU32(header, height);
  header.insert(header.end(), {8, 2, 0, 0, 0}); // 8 bits, RGB, deflate, adaptive filters, no interlace
  appendChunk(out, "IHDR", header.data(), header.size());
  const std::uint8_t perceptual = 0;
  appendChunk(out, "sRGB", &perceptual, 1);
  for (std::size_t at = 0; at < zlib.size(); at += kPngChunkBytes) {
    appendChunk(out, "IDAT", zlib.data() + at, std::min(kPngChunkBytes, zlib.size() - at));
  }
  appendChunk(out, "IEND", nullptr, 0);
  return out;
}

} // namespace

std::vector<std::uint8_t> encodePng(const Image& image) {
  if (image.width == 0 || image.height == 0) throw Error("PNG encoding failed: an image of no pixels"); // PNG has none
  if (image.pixels.size() != static_cast<std::size_t>(image.width) * image.height) {
    throw Error("PNG encoding failed: the image holds " + std::to_string(image.pixels.size()) + " pixels, not " +
                std::to_string(image.width) + "x" + std::to_string(image.height));
  }
  std::vector<std::uint8_t> rgb(static_cast<std::size_t>(image.width) * image.height * 3);
  // The sRGB bytes, a row range per thread (each writes its own bytes: the same result).
  static_assert(sizeof(glm::vec3) == 3 * sizeof(float));
  const float* linear = &image.pixels.data()->x;
  parallelFor(image.height, 64, [&](std::size_t row0, std::size_t row1) {
    const std::size_t first = row0 * image.width * 3;
    encodeSrgb8(linear + first, (row1 - row0) * image.width * 3, rgb.data() + first);
  });
  return encodeRgbPng(rgb.data(), image.width, image.height);
}

std::vector<std::uint8_t> encodePfm(const Image& image) {
  // PFM: "PF", size, negative scale for little-endian; rows from the bottom up.
  std::string header = "PF\n" + std::to_string(image.width) + " " + std::to_string(image.height) + "\n-1.0\n";
  std::vector<std::uint8_t> out(header.begin(), header.end());
  out.reserve(out.size() + image.pixels.size() * 12);
  for (std::uint32_t row = image.height; row-- > 0;) {
    const auto* p = reinterpret_cast<const std::uint8_t*>(&image.pixels[static_cast<std::size_t>(row) * image.width]);
    out.insert(out.end(), p, p + static_cast<std::size_t>(image.width) * 12);
  }
  static_assert(sizeof(glm::vec3) == 12);
  return out;
}

void writeImage(const fs::path& path, const Image& image, const ImageWriteOptions& options) {
  const ImageFormat format = imageFormatFor(path);
  if (format != ImageFormat::Exr && !options.exrLayers.empty()) {
    throw Error("writing " + path.string() + ": only an .exr file holds layers beside RGB");
  }
  switch (format) {
  case ImageFormat::Png:
    writeFileAtomic(path, encodePng(image));
    break;
  case ImageFormat::Pfm:
    writeFileAtomic(path, encodePfm(image));
    break;
  case ImageFormat::Exr:
    writeFileAtomic(path, encodeExr(image, options.exrHalf ? ExrPixels::Half : ExrPixels::Float, options.exrLayers));
    break;
  }
}

namespace {

Image readPfm(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.string(), "cannot open for reading");
  std::string magic;
  std::uint32_t w = 0, h = 0;
  double scale = 0.0;
  in >> magic >> w >> h >> scale;
  in.get();
  if (!in || (magic != "PF" && magic != "Pf") || w == 0 || h == 0 || w > 65536 || h > 65536) {
    throw InputError(path.string(), "not a PFM image");
  }
  int channels = magic == "PF" ? 3 : 1;
  std::vector<float> data(static_cast<std::size_t>(w) * h * static_cast<std::size_t>(channels));
  in.read(reinterpret_cast<char*>(data.data()), static_cast<std::streamsize>(data.size() * sizeof(float)));
  if (!in) throw InputError(path.string(), "truncated PFM data");
  if (scale > 0) { // big-endian data
    for (float& f : data) {
      std::uint32_t u;
      std::memcpy(&u, &f, 4);
      u = __builtin_bswap32(u);
      std::memcpy(&f, &u, 4);
    }
  }
  Image img(w, h);
  for (std::uint32_t y = 0; y < h; ++y) {
    for (std::uint32_t x = 0; x < w; ++x) {
      std::size_t src = (static_cast<std::size_t>(h - 1 - y) * w + x) * static_cast<std::size_t>(channels);
      img.at(x, y) = channels == 3 ? glm::vec3(data[src], data[src + 1], data[src + 2]) : glm::vec3(data[src]);
    }
  }
  return img;
}

} // namespace

Image readImage(const fs::path& path) {
  if (imageFormatFor(path) == ImageFormat::Pfm) return readPfm(path);
  if (imageFormatFor(path) == ImageFormat::Exr) return readExr(path);
  std::ifstream in(path, std::ios::binary);
  std::error_code ec;
  if (!in || fs::is_directory(path, ec)) throw InputError(path.string(), "cannot read the image file");
  std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  Rgba8Image decoded = decodePngOrJpeg(bytes.data(), bytes.size(), path.string());
  Image img(decoded.width, decoded.height);
  for (std::size_t i = 0; i < img.pixels.size(); ++i) {
    for (int c = 0; c < 3; ++c)
      img.pixels[i][c] = srgbToLinear(decoded.rgba[i * 4 + static_cast<std::size_t>(c)] / 255.0f);
  }
  return img;
}

} // namespace vkray
