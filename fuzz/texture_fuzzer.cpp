// libFuzzer target: the texture decoding path (scene/texture.h): data URI parsing, libpng's PNG
// and JPEG decoders, the sRGB conversion and the mip chain. An input starting with "data:" is a
// data URI, anything else image bytes. It must decode or be refused with vkray::InputError;
// anything else (a crash, a sanitizer report, a hang) is a bug.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "scene/texture.h"
#include "util/error.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    auto levels = vkray::decodeTextureData(std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.png");
    // Every level is there and the last is 1 x 1.
    if (levels.empty() || levels.back().width != 1 || levels.back().height != 1) __builtin_trap();
  } catch (const vkray::InputError&) {
  }
  return 0;
}
