// A file name's extension in lower case (".OBJ" -> ".obj"), the way every loader and writer picks a
// format by name.
#pragma once

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <string>

namespace vkray {

inline std::string lowerExtension(const std::filesystem::path& p) {
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

} // namespace vkray
