#include "util/host_memory.h"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <sstream>

namespace vkray {

namespace {

std::optional<std::uint64_t> readNumber(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::uint64_t value = 0;
  if (in >> value) return value; // "max" (no limit) reads as nothing
  return std::nullopt;
}

// Limit less usage in `dir`, when the limit is a real one (v1 writes "no limit" as nearly 2^63).
std::optional<std::uint64_t> room(const std::filesystem::path& dir, const char* limitFile, const char* usageFile) {
  auto limit = readNumber(dir / limitFile);
  auto usage = readNumber(dir / usageFile);
  if (!limit || !usage || *limit >= (std::uint64_t{1} << 62)) return std::nullopt;
  return *limit > *usage ? *limit - *usage : 0;
}

} // namespace

std::optional<std::uint64_t> cgroupMemoryRoom(const std::filesystem::path& cgroupRoot,
                                              const std::string& procSelfCgroup) {
  std::istringstream lines(procSelfCgroup);
  std::string line;
  while (std::getline(lines, line)) {
    // "ID:CONTROLLERS:PATH": v2's single hierarchy is "0::PATH", v1's memory controller "N:memory:PATH".
    const auto first = line.find(':'), second = line.find(':', first + 1);
    if (first == std::string::npos || second == std::string::npos) continue;
    const std::string controllers = line.substr(first + 1, second - first - 1);
    const std::string path = line.substr(second + 1);
    const std::string relative = path.empty() || path == "/" ? "" : path.substr(path[0] == '/' ? 1 : 0);
    std::filesystem::path base;
    const char *limitFile = nullptr, *usageFile = nullptr;
    if (controllers.empty() && line.compare(0, first, "0") == 0) {
      base = cgroupRoot;
      limitFile = "memory.max";
      usageFile = "memory.current";
    } else if (("," + controllers + ",").find(",memory,") != std::string::npos) {
      base = cgroupRoot / "memory";
      limitFile = "memory.limit_in_bytes";
      usageFile = "memory.usage_in_bytes";
    } else {
      continue;
    }
    std::error_code ec;
    const std::filesystem::path dir =
        !relative.empty() && std::filesystem::is_directory(base / relative, ec) ? base / relative : base;
    if (auto r = room(dir, limitFile, usageFile)) return r;
  }
  return std::nullopt;
}

std::optional<std::uint64_t> hostMemoryAvailable() {
  std::optional<std::uint64_t> available;
  std::ifstream in("/proc/meminfo");
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::string name, unit;
    std::uint64_t value = 0;
    if (fields >> name >> value >> unit && name == "MemAvailable:" && unit == "kB") {
      available = value * 1024;
      break;
    }
  }
  std::ifstream cgroup("/proc/self/cgroup");
  std::stringstream text;
  text << cgroup.rdbuf();
  if (auto limit = cgroupMemoryRoom("/sys/fs/cgroup", text.str())) {
    available = available ? std::min(*available, *limit) : *limit;
  }
  return available;
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
