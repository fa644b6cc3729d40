#include "util/host_memory.h"

#include <cstdio>
#include <fstream>
#include <sstream>

namespace vkray {

std::optional<std::uint64_t> hostMemoryAvailable() {
  std::ifstream in("/proc/meminfo");
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::string name, unit;
    std::uint64_t value = 0;
    if (fields >> name >> value >> unit && name == "MemAvailable:" && unit == "kB") return value * 1024;
  }
  return std::nullopt;
}

std::string formatBytes(std::uint64_t bytes) {
  char text[32];
  const double mib = static_cast<double>(bytes) / (1024.0 * 1024.0);
  if (mib >= 1024.0) {
    std::snprintf(text, sizeof(text), "%.1f GiB", mib / 1024.0);
  } else {
    std::snprintf(text, sizeof(text), "%.0f MiB", mib);
  }
  return text;
}

} // namespace vkray
