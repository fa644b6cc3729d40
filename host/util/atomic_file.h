// Files replaced whole or not at all: the bytes go to a hidden temporary in the target's directory,
// ".NAME.tmp-PID-XXXXXX", renamed over NAME once complete. A process killed in between (SIGKILL,
// power loss) leaves that temporary behind; the next write to NAME removes those whose PID no
// longer runs (a live writer's file is never touched). Images, tiles and JSON files go through
// writeFileAtomic; the pipeline and folded-SPIR-V caches through writeFileAtomicQuietly.
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <vector>

namespace vkray {

// Writes, flushes to disk (fsync) and renames. Throws InputError naming the path.
void writeFileAtomic(const std::filesystem::path& path, std::span<const std::uint8_t> bytes);
inline void writeFileAtomic(const std::filesystem::path& path, const std::vector<std::uint8_t>& bytes) {
  writeFileAtomic(path, std::span<const std::uint8_t>(bytes));
}

// For caches, which a failed write only leaves unwritten: no fsync (a cache lost in a power cut is
// rebuilt), and false instead of an exception; the temporary is removed either way.
bool writeFileAtomicQuietly(const std::filesystem::path& path, std::span<const std::uint8_t> bytes) noexcept;

} // namespace vkray
