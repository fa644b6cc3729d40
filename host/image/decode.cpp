// PNG and JPEG decoding into 8-bit RGBA (libpng's simplified API, libjpeg-turbo's decompressor).
// Both libraries report errors by longjmp from inside; the JPEG path keeps that jump inside one
// function whose locals are plain data, and turns it into an InputError once outside.
#include "image/decode.h"

#include <csetjmp>
#include <cstdio>
#include <cstring>

#include <jpeglib.h>
#include <png.h>

#include "util/error.h"

namespace vkray {

namespace {

// A decoder's message made one line (libjpeg's and libpng's are already short; this is a guard).
std::string oneLine(std::string text) {
  for (char& c : text) {
    if (c == '\n' || c == '\r' || c == '\t') c = ' ';
  }
  while (!text.empty() && text.back() == ' ') text.pop_back();
  return text.empty() ? std::string("no reason given") : text;
}

void checkSize(std::uint64_t w, std::uint64_t h, const DecodeLimits& limits, const std::string& shownAs) {
  if (w == 0 || h == 0)
    throw InputError(shownAs, "the image has no pixels (" + std::to_string(w) + " x " + std::to_string(h) + ")");
  if (w > limits.maxSide || h > limits.maxSide || w * h > limits.maxPixels) {
    throw InputError(shownAs, "image of " + std::to_string(w) + " x " + std::to_string(h) +
                                  " pixels is larger than vkray accepts (" + std::to_string(limits.maxSide) +
                                  " per side, " + std::to_string(limits.maxPixels >> 20) + " Mi pixels)");
  }
}

Rgba8Image decodePng(const std::uint8_t* bytes, std::size_t size, const std::string& shownAs,
                     const DecodeLimits& limits) {
  png_image image;
  std::memset(&image, 0, sizeof image);
  image.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_memory(&image, bytes, size)) {
    std::string why = oneLine(image.message);
    png_image_free(&image);
    throw InputError(shownAs, "cannot decode the PNG image (" + why + ")");
  }
  try {
    checkSize(image.width, image.height, limits, shownAs);
  } catch (...) {
    png_image_free(&image);
    throw;
  }
  // 8-bit RGBA in the file's own encoding: libpng converts palettes, grey, 16-bit samples and a
  // gAMA chunk's gamma to sRGB-coded bytes, which the callers turn into linear values.
  image.format = PNG_FORMAT_RGBA;
  Rgba8Image out;
  out.width = image.width;
  out.height = image.height;
  out.rgba.resize(PNG_IMAGE_SIZE(image));
  if (!png_image_finish_read(&image, nullptr, out.rgba.data(), 0, nullptr)) {
    std::string why = oneLine(image.message);
    png_image_free(&image);
    throw InputError(shownAs, "cannot decode the PNG image (" + why + ")");
  }
  png_image_free(&image);
  return out;
}

// libjpeg's error manager, extended with where to jump and the message to carry out.
struct JpegErrors {
  jpeg_error_mgr base;
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX];
};

[[noreturn]] void jpegFail(j_common_ptr info) {
  auto* errors = reinterpret_cast<JpegErrors*>(info->err);
  info->err->format_message(info, errors->message);
  std::longjmp(errors->jump, 1);
}

void jpegQuiet(j_common_ptr, int) {} // warnings (a corrupt but readable stream) are not printed

// A progressive JPEG may hold any number of scans, each one a full pass over the coefficients: a
// small file can take minutes. Real encoders write about ten; more than a thousand is refused.
constexpr int kMaxJpegScans = 1000;

void jpegProgress(j_common_ptr info) {
  if (info->is_decompressor) {
    auto* d = reinterpret_cast<j_decompress_ptr>(info);
    if (d->input_scan_number > kMaxJpegScans) {
      auto* errors = reinterpret_cast<JpegErrors*>(info->err);
      std::snprintf(errors->message, sizeof errors->message, "more than %d progressive scans", kMaxJpegScans);
      std::longjmp(errors->jump, 1);
    }
  }
}

enum class JpegStep { Done, Failed, TooLarge };

// Everything between setjmp and the last libjpeg call lives in this function, and it holds no
// object with a destructor: a longjmp out of libjpeg skips nothing that needed to run. The pixel
// vector belongs to the caller; it is sized here once the header has been read.
struct JpegTarget {
  std::vector<std::uint8_t>* rgba;
  const DecodeLimits* limits;
  std::uint32_t width;
  std::uint32_t height;
  bool cmyk;
};

JpegStep runJpeg(const std::uint8_t* bytes, std::size_t size, JpegTarget& target, JpegErrors& errors) {
  jpeg_decompress_struct info;
  std::memset(&info, 0, sizeof info); // so that a jump out of jpeg_create_decompress finds no pool to free
  jpeg_progress_mgr progress;
  info.err = jpeg_std_error(&errors.base);
  errors.base.error_exit = jpegFail;
  errors.base.emit_message = jpegQuiet;
  errors.message[0] = '\0';
  // As libjpeg's own example: the jump target is set before the first call that may use it.
  if (setjmp(errors.jump)) {
    jpeg_destroy_decompress(&info);
    return JpegStep::Failed;
  }
  jpeg_create_decompress(&info);
  progress.progress_monitor = jpegProgress;
  info.progress = &progress;
  jpeg_mem_src(&info, bytes, static_cast<unsigned long>(size));
  jpeg_read_header(&info, TRUE);
  const std::uint64_t w = info.image_width, h = info.image_height;
  if (w == 0 || h == 0 || w > target.limits->maxSide || h > target.limits->maxSide ||
      w * h > target.limits->maxPixels) {
    target.width = info.image_width;
    target.height = info.image_height;
    jpeg_destroy_decompress(&info);
    return JpegStep::TooLarge;
  }
  target.cmyk = info.jpeg_color_space == JCS_CMYK || info.jpeg_color_space == JCS_YCCK;
  info.out_color_space = target.cmyk ? JCS_CMYK : JCS_EXT_RGBA;
  jpeg_start_decompress(&info);
  target.width = info.output_width;
  target.height = info.output_height;
  // resize() may throw std::bad_alloc; the limits above keep it to 256 MiB at most.
  target.rgba->resize(std::size_t(target.width) * target.height * 4);
  const std::size_t stride = std::size_t(target.width) * 4;
  while (info.output_scanline < info.output_height) {
    JSAMPROW row = target.rgba->data() + stride * info.output_scanline;
    jpeg_read_scanlines(&info, &row, 1);
  }
  jpeg_finish_decompress(&info);
  jpeg_destroy_decompress(&info);
  return JpegStep::Done;
}

Rgba8Image decodeJpeg(const std::uint8_t* bytes, std::size_t size, const std::string& shownAs,
                      const DecodeLimits& limits) {
  Rgba8Image out;
  JpegTarget target{&out.rgba, &limits, 0, 0, false};
  JpegErrors errors;
  switch (runJpeg(bytes, size, target, errors)) {
  case JpegStep::Failed:
    throw InputError(shownAs, "cannot decode the JPEG image (" + oneLine(errors.message) + ")");
  case JpegStep::TooLarge:
    checkSize(target.width, target.height, limits, shownAs);
    throw InputError(shownAs, "the JPEG image's size was refused"); // not reached: checkSize threw
  case JpegStep::Done:
    break;
  }
  out.width = target.width;
  out.height = target.height;
  if (target.cmyk) {
    // Adobe writes CMYK inverted (255 = no ink), as nearly every CMYK JPEG in the wild is:
    // R = C' * K' / 255 with C' and K' as stored.
    for (std::size_t i = 0; i < out.rgba.size(); i += 4) {
      const unsigned k = out.rgba[i + 3];
      for (int c = 0; c < 3; ++c) out.rgba[i + c] = static_cast<std::uint8_t>((out.rgba[i + c] * k + 127) / 255);
      out.rgba[i + 3] = 255;
    }
  }
  return out;
}

} // namespace

EncodedFormat sniffFormat(const std::uint8_t* bytes, std::size_t size) {
  static const std::uint8_t kPng[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  if (size >= 8 && std::memcmp(bytes, kPng, 8) == 0) return EncodedFormat::Png;
  if (size >= 3 && bytes[0] == 0xFF && bytes[1] == 0xD8 && bytes[2] == 0xFF) return EncodedFormat::Jpeg;
  return EncodedFormat::Unknown;
}

Rgba8Image decodePngOrJpeg(const std::uint8_t* bytes, std::size_t size, const std::string& shownAs,
                           const DecodeLimits& limits) {
  if (size == 0) throw InputError(shownAs, "the image is empty");
  switch (sniffFormat(bytes, size)) {
  case EncodedFormat::Png:
    return decodePng(bytes, size, shownAs, limits);
  case EncodedFormat::Jpeg:
    return decodeJpeg(bytes, size, shownAs, limits);
  case EncodedFormat::Unknown:
    break;
  }
  throw InputError(shownAs, "not a PNG or JPEG image (its first bytes are neither signature)");
}

} // namespace vkray
