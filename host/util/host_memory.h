// How much memory the host can still give this process, for refusing work that would not fit with
// a clear message before allocating it (instead of std::bad_alloc, or the kernel's OOM killer).
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

namespace vkray {

// The least of MemAvailable (/proc/meminfo: what can be allocated without swapping) and the room
// left under this process's control-group memory limit, where it has one (a container's limit is
// not in MemAvailable); nothing where neither can be read.
std::optional<std::uint64_t> hostMemoryAvailable();

// The room left under the memory limit of the control group that `procSelfCgroup` (the text of
// /proc/self/cgroup) names, read under `cgroupRoot` (/sys/fs/cgroup): cgroup v2's memory.max less
// memory.current, or v1's memory.limit_in_bytes less memory.usage_in_bytes. Where the group's
// directory is not there (a cgroup namespace shows it as the root), the root's own files. Nothing
// without a limit.
std::optional<std::uint64_t> cgroupMemoryRoom(const std::filesystem::path& cgroupRoot,
                                              const std::string& procSelfCgroup);

// Bytes for people: "1.5 GiB", "312 MiB".
std::string formatBytes(std::uint64_t bytes);

} // namespace vkray
