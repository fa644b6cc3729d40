// Texture decoding, mip chain and reference sampling (see texture.h).
#include "scene/texture.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <iterator>

#include "image/decode.h"
#include "util/error.h"

namespace vkray {

namespace {

const std::array<float, 256>& srgbTable() {
  static const std::array<float, 256> table = [] {
    std::array<float, 256> t{};
    for (int i = 0; i < 256; ++i) {
      double c = i / 255.0;
      t[static_cast<std::size_t>(i)] =
          static_cast<float>(c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4));
    }
    return t;
  }();
  return table;
}

// One axis of the box filter: the weights of source texels [first, first + count) for dest texel i.
struct Footprint {
  std::uint32_t first = 0;
  std::vector<double> weights;
};

std::vector<Footprint> footprints(std::uint32_t src, std::uint32_t dst) {
  std::vector<Footprint> out(dst);
  double ratio = static_cast<double>(src) / dst;
  for (std::uint32_t i = 0; i < dst; ++i) {
    double lo = i * ratio;
    double hi = (i + 1) * ratio;
    auto first = static_cast<std::uint32_t>(std::floor(lo));
    auto last = std::min(src - 1, static_cast<std::uint32_t>(std::ceil(hi)) - 1);
    out[i].first = first;
    for (std::uint32_t j = first; j <= last; ++j) {
      double overlap = std::min<double>(hi, j + 1.0) - std::max<double>(lo, j);
      out[i].weights.push_back(std::max(overlap, 0.0) / ratio);
    }
  }
  return out;
}

TextureLevel halve(const TextureLevel& src) {
  TextureLevel dst;
  dst.width = std::max(1u, src.width / 2);
  dst.height = std::max(1u, src.height / 2);
  const auto fx = footprints(src.width, dst.width);
  const auto fy = footprints(src.height, dst.height);
  // Rows first (in double), then columns.
  std::vector<glm::dvec4> rows(std::size_t(dst.width) * src.height);
  for (std::uint32_t y = 0; y < src.height; ++y) {
    for (std::uint32_t x = 0; x < dst.width; ++x) {
      glm::dvec4 sum(0.0);
      for (std::size_t k = 0; k < fx[x].weights.size(); ++k)
        sum += fx[x].weights[k] * glm::dvec4(src.at(fx[x].first + static_cast<std::uint32_t>(k), y));
      rows[std::size_t(y) * dst.width + x] = sum;
    }
  }
  dst.texels.resize(std::size_t(dst.width) * dst.height);
  for (std::uint32_t y = 0; y < dst.height; ++y) {
    for (std::uint32_t x = 0; x < dst.width; ++x) {
      glm::dvec4 sum(0.0);
      for (std::size_t k = 0; k < fy[y].weights.size(); ++k)
        sum += fy[y].weights[k] * rows[(fy[y].first + k) * dst.width + x];
      dst.texels[std::size_t(y) * dst.width + x] = glm::vec4(sum);
    }
  }
  return dst;
}

int base64Value(char c) {
  if (c >= 'A' && c <= 'Z') return c - 'A';
  if (c >= 'a' && c <= 'z') return c - 'a' + 26;
  if (c >= '0' && c <= '9') return c - '0' + 52;
  if (c == '+' || c == '-') return 62;
  if (c == '/' || c == '_') return 63;
  return -1;
}

} // namespace

std::size_t Texture::texelCount() const {
  std::size_t n = 0;
  for (const auto& l : levels) n += l.texels.size();
  return n;
}

float srgbToLinear(std::uint8_t code) {
  return srgbTable()[code];
}

TextureLevel decodeImage(const std::uint8_t* bytes, std::size_t size, const std::string& shownAs) {
  if (size > 0x7FFFFFFFu) throw InputError(shownAs, "the image is larger than 2 GiB");
  Rgba8Image decoded = decodePngOrJpeg(bytes, size, shownAs, DecodeLimits{kMaxTextureSide, kMaxTextureTexels});
  TextureLevel level;
  level.width = decoded.width;
  level.height = decoded.height;
  level.texels.resize(std::size_t(level.width) * level.height);
  for (std::size_t i = 0; i < level.texels.size(); ++i) {
    const std::uint8_t* p = decoded.rgba.data() + 4 * i;
    level.texels[i] = glm::vec4(srgbToLinear(p[0]), srgbToLinear(p[1]), srgbToLinear(p[2]), p[3] / 255.0f);
  }
  return level;
}

TextureLevel readImageFile(const std::filesystem::path& file, const std::string& shownAs) {
  std::ifstream in(file, std::ios::binary);
  std::error_code ec;
  if (!in || std::filesystem::is_directory(file, ec)) throw InputError(shownAs, "cannot read the image file");
  std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return decodeImage(bytes.data(), bytes.size(), shownAs);
}

std::vector<std::uint8_t> decodeDataUri(std::string_view uri, const std::string& shownAs) {
  if (uri.substr(0, 5) != "data:") throw InputError(shownAs, "not a data URI");
  std::size_t comma = uri.find(',');
  if (comma == std::string_view::npos) throw InputError(shownAs, "data URI without a ',' before its data");
  std::string_view header = uri.substr(5, comma - 5);
  std::string_view payload = uri.substr(comma + 1);
  bool base64 = header.size() >= 7 && header.substr(header.size() - 7) == ";base64";
  std::vector<std::uint8_t> out;
  if (!base64) {
    // Percent-encoded text (RFC 2397 without ;base64).
    auto hex = [](char c) {
      int l = c | 32;
      return c >= '0' && c <= '9' ? c - '0' : (l >= 'a' && l <= 'f' ? l - 'a' + 10 : -1);
    };
    for (std::size_t i = 0; i < payload.size(); ++i) {
      if (payload[i] != '%') {
        out.push_back(static_cast<std::uint8_t>(payload[i]));
        continue;
      }
      int hi = i + 2 < payload.size() ? hex(payload[i + 1]) : -1;
      int lo = i + 2 < payload.size() ? hex(payload[i + 2]) : -1;
      if (hi < 0 || lo < 0) throw InputError(shownAs, "data URI has a bad %-escape");
      out.push_back(static_cast<std::uint8_t>(hi * 16 + lo));
      i += 2;
    }
    return out;
  }
  out.reserve(payload.size() / 4 * 3);
  std::uint32_t acc = 0;
  int bits = 0;
  for (std::size_t i = 0; i < payload.size(); ++i) {
    char c = payload[i];
    if (c == '=') {
      for (std::size_t k = i; k < payload.size(); ++k) {
        if (payload[k] != '=') throw InputError(shownAs, "data URI has data after its '=' padding");
      }
      break;
    }
    int v = base64Value(c);
    if (v < 0) throw InputError(shownAs, "data URI is not valid base64 (character " + std::to_string(i) + ")");
    acc = (acc << 6) | static_cast<std::uint32_t>(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(static_cast<std::uint8_t>((acc >> bits) & 0xFFu));
    }
  }
  return out;
}

std::vector<TextureLevel> decodeTextureData(std::string_view bytes, const std::string& shownAs) {
  if (bytes.substr(0, 5) == "data:") {
    std::vector<std::uint8_t> decoded = decodeDataUri(bytes, shownAs);
    return buildMipChain(decodeImage(decoded.data(), decoded.size(), shownAs));
  }
  return buildMipChain(decodeImage(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size(), shownAs));
}

std::vector<TextureLevel> buildMipChain(TextureLevel base) {
  std::vector<TextureLevel> levels;
  levels.push_back(std::move(base));
  while (levels.back().width > 1 || levels.back().height > 1) levels.push_back(halve(levels.back()));
  return levels;
}

std::uint32_t wrapCoord(std::int64_t i, std::uint32_t n, TextureWrap wrap) {
  auto m = static_cast<std::int64_t>(n);
  switch (wrap) {
  case TextureWrap::Clamp:
    return static_cast<std::uint32_t>(std::clamp<std::int64_t>(i, 0, m - 1));
  case TextureWrap::Mirror: {
    std::int64_t k = ((i % (2 * m)) + 2 * m) % (2 * m);
    return static_cast<std::uint32_t>(k < m ? k : 2 * m - 1 - k);
  }
  case TextureWrap::Repeat:
    break;
  }
  return static_cast<std::uint32_t>(((i % m) + m) % m);
}

glm::vec4 sampleNearest(const Texture& t, std::uint32_t level, glm::dvec2 uv) {
  const TextureLevel& l = t.levels[std::min<std::size_t>(level, t.levels.size() - 1)];
  auto x = static_cast<std::int64_t>(std::floor(uv.x * l.width));
  auto y = static_cast<std::int64_t>(std::floor(uv.y * l.height));
  return l.at(wrapCoord(x, l.width, t.wrapS), wrapCoord(y, l.height, t.wrapT));
}

glm::vec4 sampleBilinear(const Texture& t, std::uint32_t level, glm::dvec2 uv) {
  const TextureLevel& l = t.levels[std::min<std::size_t>(level, t.levels.size() - 1)];
  double x = uv.x * l.width - 0.5;
  double y = uv.y * l.height - 0.5;
  double x0 = std::floor(x), y0 = std::floor(y);
  auto fx = static_cast<float>(x - x0), fy = static_cast<float>(y - y0);
  auto ix = static_cast<std::int64_t>(x0), iy = static_cast<std::int64_t>(y0);
  std::uint32_t xa = wrapCoord(ix, l.width, t.wrapS), xb = wrapCoord(ix + 1, l.width, t.wrapS);
  std::uint32_t ya = wrapCoord(iy, l.height, t.wrapT), yb = wrapCoord(iy + 1, l.height, t.wrapT);
  glm::vec4 top = glm::mix(l.at(xa, ya), l.at(xb, ya), fx);
  glm::vec4 bottom = glm::mix(l.at(xa, yb), l.at(xb, yb), fx);
  return glm::mix(top, bottom, fy);
}

glm::dvec2 TextureTransform::apply(glm::dvec2 uv) const {
  double c = std::cos(rotation), s = std::sin(rotation);
  glm::dvec2 q = uv * scale;
  return glm::dvec2(c * q.x + s * q.y, -s * q.x + c * q.y) + offset;
}

} // namespace vkray
