// PNG/PFM encoding and decoding; writes go through writeFileAtomic (util/atomic_file.h).
#include "image/image_io.h"

#include <algorithm>
#include <cerrno>
#include <csetjmp>
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

#include <png.h>

#include "image/decode.h"
#include "image/exr_io.h"
#include "util/error.h"
#include "util/file_extension.h"

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

// libpng's errors end in a longjmp back into encodeRgbPng; nothing between holds a destructor.
[[noreturn]] void pngError(png_structp png, png_const_charp) {
  std::longjmp(png_jmpbuf(png), 1);
}
void pngWarning(png_structp, png_const_charp) {}

void pngAppend(png_structp png, png_bytep data, png_size_t size) {
  auto* out = static_cast<std::vector<std::uint8_t>*>(png_get_io_ptr(png));
  out->insert(out->end(), data, data + size);
}

// 8-bit RGB rows to PNG with libpng: zlib level 1 and the Sub filter on every row. Measured on
// the bundled scenes at 800x600 (docs/performance.md, "Writing the image"), that is 5x faster
// than stb_image_write's default (level 8, the best of five filters per row) and the files come
// out smaller too (the showcase 152 KB against 161 KB): a rendered image's rows are smooth runs
// that Sub turns into near-zero bytes a fast deflate already packs well.
bool encodeRgbPng(const std::uint8_t* rgb, std::uint32_t width, std::uint32_t height, std::vector<std::uint8_t>& out) {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, pngError, pngWarning);
  if (!png) return false;
  png_infop info = png_create_info_struct(png);
  if (!info || setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    return false;
  }
  png_set_write_fn(png, &out, pngAppend, nullptr);
  png_set_IHDR(png, info, width, height, 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
               PNG_FILTER_TYPE_DEFAULT);
  png_set_sRGB(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
  png_set_compression_level(png, 1);
  png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_FILTER_SUB);
  png_write_info(png, info);
  for (std::uint32_t y = 0; y < height; ++y) {
    png_write_row(png, const_cast<png_bytep>(rgb + static_cast<std::size_t>(y) * width * 3));
  }
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return true;
}

} // namespace

std::vector<std::uint8_t> encodePng(const Image& image) {
  std::vector<std::uint8_t> rgb(static_cast<std::size_t>(image.width) * image.height * 3);
  for (std::size_t i = 0; i < image.pixels.size(); ++i) {
    for (int c = 0; c < 3; ++c) rgb[i * 3 + static_cast<std::size_t>(c)] = encodeSrgb8(image.pixels[i][c]);
  }
  std::vector<std::uint8_t> out;
  if (!encodeRgbPng(rgb.data(), image.width, image.height, out)) throw Error("PNG encoding failed");
  return out;
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
