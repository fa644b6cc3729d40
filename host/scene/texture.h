// Textures as plain decoded images: linear RGBA float texels (decoded from sRGB once, here) with
// their mip chain, wrap modes and the sampling the kernel does, written once more on the host for
// the tests. Nothing here knows about Vulkan; GpuScene packs the levels into one texel buffer.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

namespace vkray {

enum class TextureWrap : std::uint32_t { Repeat = 0, Clamp = 1, Mirror = 2 }; // values as the kernel reads them

// What a minified texture's footprint reads, as glTF's sampler minFilter names it (the ray cone
// still picks the level). Trilinear is LINEAR_MIPMAP_LINEAR and the default when a file says nothing.
enum class TextureMinFilter : std::uint32_t {
  Trilinear,            // bilinear in the two levels around the cone's level, blended
  NearestBetweenLevels, // NEAREST_MIPMAP_LINEAR: the nearest texel in each of the two levels, blended
  NearestLevel,         // LINEAR_MIPMAP_NEAREST: bilinear in the one level nearest the cone's
  NearestLevelNearest,  // NEAREST_MIPMAP_NEAREST
  Linear,               // LINEAR: no mipmaps, bilinear in the image itself
  Nearest,              // NEAREST: no mipmaps, the nearest texel of the image itself
};

struct TextureLevel {
  std::uint32_t width = 0;
  std::uint32_t height = 0;
  std::vector<glm::vec4> texels; // row-major, top row first (glTF's uv (0, 0) is the top-left corner)

  const glm::vec4& at(std::uint32_t x, std::uint32_t y) const { return texels[std::size_t(y) * width + x]; }
};

struct Texture {
  std::string name;                 // the file or "file: images[2]", for messages and --stats
  std::vector<TextureLevel> levels; // levels[0] the image itself, then halved down to 1 x 1
  TextureWrap wrapS = TextureWrap::Repeat;
  TextureWrap wrapT = TextureWrap::Repeat;
  bool nearest = false; // the file asks for nearest magnification (glTF sampler magFilter NEAREST)
  TextureMinFilter minFilter = TextureMinFilter::Trilinear;

  std::size_t texelCount() const;
};

// Largest image side and texel count vkray accepts; larger is refused as absurd (a corrupt header
// would otherwise allocate gigabytes).
inline constexpr std::uint32_t kMaxTextureSide = 16384;
inline constexpr std::uint64_t kMaxTextureTexels = 64ull << 20;

// sRGB transfer function, inverse (IEC 61966-2-1): 8-bit code to linear.
float srgbToLinear(std::uint8_t code);

// Decodes PNG or JPEG bytes (libpng, libjpeg-turbo: image/decode.h) into level 0: colour from sRGB to linear, alpha
// kept linear. InputError naming `shownAs` for undecodable data or an absurd size.
TextureLevel decodeImage(const std::uint8_t* bytes, std::size_t size, const std::string& shownAs);
// The same from a file (InputError when it cannot be read).
TextureLevel readImageFile(const std::filesystem::path& file, const std::string& shownAs);

// "data:[<mime>][;base64],<payload>" to bytes; InputError naming `shownAs` for anything else.
std::vector<std::uint8_t> decodeDataUri(std::string_view uri, const std::string& shownAs);

// The decoding path of untrusted texture data, as the fuzz target drives it: bytes that start
// with "data:" are a data URI, decoded first; then the image is decoded and its mip chain built.
std::vector<TextureLevel> decodeTextureData(std::string_view bytes, const std::string& shownAs);

// The mip chain below `base`: each level halves each side (rounding down, at least 1) and each of
// its texels is the area-weighted mean of the texels of the level above it covers, so odd (NPOT)
// sides are filtered exactly and every level keeps the image's mean.
std::vector<TextureLevel> buildMipChain(TextureLevel base);

// Texel coordinate i wrapped into [0, n).
std::uint32_t wrapCoord(std::int64_t i, std::uint32_t n, TextureWrap wrap);

// The kernel's samplers (shaders/lib/texture.glsl), for the tests: uv in texture space (u right,
// v down, [0, 1] over the image).
glm::vec4 sampleNearest(const Texture& t, std::uint32_t level, glm::dvec2 uv);
glm::vec4 sampleBilinear(const Texture& t, std::uint32_t level, glm::dvec2 uv);

// KHR_texture_transform: uv' = T(offset) R(rotation) S(scale) uv.
struct TextureTransform {
  glm::dvec2 offset{0.0};
  double rotation = 0.0; // radians, counter-clockwise in uv as the extension defines it
  glm::dvec2 scale{1.0};

  glm::dvec2 apply(glm::dvec2 uv) const;
  bool identity() const { return offset == glm::dvec2(0.0) && rotation == 0.0 && scale == glm::dvec2(1.0); }
};

} // namespace vkray
