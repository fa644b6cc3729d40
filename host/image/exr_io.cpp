// OpenEXR output and input (see exr_io.h).
#include "image/exr_io.h"

#include <cstring>
#include <exception>
#include <string>

#include <Imath/half.h>
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfIO.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfThreading.h>

#include "util/error.h"
#include "util/parallel.h"

namespace vkray {

namespace {

// OpenEXR writes through a seekable stream; this one is a byte vector, handed to writeFileAtomic.
class MemoryStream : public Imf::OStream {
public:
  MemoryStream() : Imf::OStream("memory") {}
  void write(const char c[], int n) override {
    std::size_t end = pos_ + static_cast<std::size_t>(n);
    if (end > bytes_.size()) bytes_.resize(end);
    std::memcpy(bytes_.data() + pos_, c, static_cast<std::size_t>(n));
    pos_ = end;
  }
  std::uint64_t tellp() override { return pos_; }
  void seekp(std::uint64_t pos) override { pos_ = static_cast<std::size_t>(pos); }
  std::vector<std::uint8_t>& bytes() { return bytes_; }

private:
  std::vector<std::uint8_t> bytes_;
  std::size_t pos_ = 0;
};

} // namespace

std::vector<std::uint8_t> encodeExr(const Image& image, ExrPixels pixels, const std::vector<ExrChannel>& extra) {
  const int width = static_cast<int>(image.width), height = static_cast<int>(image.height);
  Imf::Header header(width, height);
  header.compression() = Imf::ZIP_COMPRESSION;
  const Imf::PixelType type = pixels == ExrPixels::Half ? Imf::HALF : Imf::FLOAT;
  for (const char* name : {"R", "G", "B"}) header.channels().insert(name, Imf::Channel(type));
  for (const ExrChannel& c : extra) {
    if (c.values.size() != image.pixels.size()) {
      throw Error("EXR channel " + c.name + " has " + std::to_string(c.values.size()) + " values for " +
                  std::to_string(image.pixels.size()) + " pixels");
    }
    if (header.channels().findChannel(c.name) != nullptr) throw Error("EXR channel " + c.name + " named twice");
    header.channels().insert(c.name, Imf::Channel(Imf::FLOAT));
  }
  Imf::FrameBuffer frame;
  std::vector<Imath::half> halves;
  if (pixels == ExrPixels::Half) {
    halves.resize(image.pixels.size() * 3);
    for (std::size_t i = 0; i < image.pixels.size(); ++i) {
      for (int c = 0; c < 3; ++c) halves[i * 3 + static_cast<std::size_t>(c)] = Imath::half(image.pixels[i][c]);
    }
  }
  const std::size_t pixelBytes = pixels == ExrPixels::Half ? 3 * sizeof(Imath::half) : sizeof(glm::vec3);
  char* base = pixels == ExrPixels::Half ? reinterpret_cast<char*>(halves.data())
                                         : reinterpret_cast<char*>(const_cast<glm::vec3*>(image.pixels.data()));
  const std::size_t channelBytes = pixelBytes / 3;
  const char* names[] = {"R", "G", "B"};
  for (std::size_t c = 0; c < 3; ++c) {
    frame.insert(names[c], Imf::Slice(type, base + c * channelBytes, pixelBytes, pixelBytes * image.width));
  }
  for (const ExrChannel& c : extra) {
    char* values = reinterpret_cast<char*>(const_cast<float*>(c.values.data()));
    frame.insert(c.name, Imf::Slice(Imf::FLOAT, values, sizeof(float), sizeof(float) * image.width));
  }
  // ZIP compresses blocks of 16 rows, each on its own: OpenEXR's thread pool compresses them side by
  // side and writes them in order, the same bytes as one thread (the textured scene's 800x600 float
  // RGB: 120 -> 65 ms on two threads). The pool is OpenEXR's one global pool, sized once.
  const int threads = static_cast<int>(hostThreads());
  static const bool pooled = [threads] {
    if (threads > 1) Imf::setGlobalThreadCount(threads);
    return true;
  }();
  (void)pooled;
  MemoryStream stream;
  try {
    Imf::OutputFile file(stream, header, threads > 1 ? threads : 0);
    file.setFrameBuffer(frame);
    file.writePixels(height);
  } catch (const std::exception& e) {
    throw Error(std::string("EXR encoding failed: ") + e.what());
  }
  return std::move(stream.bytes());
}

Image readExr(const std::filesystem::path& path) {
  try {
    Imf::InputFile file(path.c_str());
    const Imath::Box2i window = file.header().dataWindow();
    const long long w = static_cast<long long>(window.max.x) - window.min.x + 1;
    const long long h = static_cast<long long>(window.max.y) - window.min.y + 1;
    if (w <= 0 || h <= 0 || w > 65536 || h > 65536) throw InputError(path.string(), "EXR image of an absurd size");
    Image img(static_cast<std::uint32_t>(w), static_cast<std::uint32_t>(h));
    Imf::FrameBuffer frame;
    char* origin =
        reinterpret_cast<char*>(img.pixels.data()) -
        (static_cast<std::ptrdiff_t>(window.min.y) * w + window.min.x) * static_cast<std::ptrdiff_t>(sizeof(glm::vec3));
    const char* names[] = {"R", "G", "B"};
    for (std::size_t c = 0; c < 3; ++c) {
      frame.insert(names[c], Imf::Slice(Imf::FLOAT, origin + c * sizeof(float), sizeof(glm::vec3),
                                        sizeof(glm::vec3) * static_cast<std::size_t>(w), 1, 1, 0.0));
    }
    file.setFrameBuffer(frame);
    file.readPixels(window.min.y, window.max.y);
    return img;
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    throw InputError(path.string(), std::string("cannot read as EXR: ") + e.what());
  }
}

} // namespace vkray
