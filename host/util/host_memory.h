// How much memory the host can still give this process, for refusing work that would not fit with
// a clear message before allocating it (instead of std::bad_alloc, or the kernel's OOM killer).
#pragma once

#include <cstdint>
#include <optional>
#include <string>

namespace vkray {

// MemAvailable from /proc/meminfo (what can be allocated without swapping), or nothing where that
// cannot be read.
std::optional<std::uint64_t> hostMemoryAvailable();

// Bytes for people: "1.5 GiB", "312 MiB".
std::string formatBytes(std::uint64_t bytes);

} // namespace vkray
