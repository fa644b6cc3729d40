// Folded SPIR-V kept on disk between runs (see fold_cache.h).
#include "vk/fold_cache.h"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>
#include <system_error>

#include <spirv-tools/libspirv.h>

#include "util/atomic_file.h"
#include "util/fnv_hash.h"
#include "vk/compute_pipeline.h"
#include "vk/spirv_fold.h"

namespace vkray::vulkan {

namespace {

// A file: this header, then the folded module's words.
constexpr std::uint32_t kMagic = 0x53464b56u; // "VKFS"
constexpr std::uint32_t kFormat = 2u;         // 2: module hashed a word at a time
struct Header {
  std::uint32_t magic;
  std::uint32_t format;
  std::uint64_t key;   // what went in (FoldCache::key)
  std::uint64_t words; // the module's length
  std::uint64_t check; // hash of the module's words
};
constexpr std::uint32_t kSpirvMagic = 0x07230203u;
constexpr std::uint64_t kMaxWords = 64ull << 20; // 256 MiB: anything larger is not one of ours

std::uint64_t hashWords(std::span<const std::uint32_t> words) {
  Fnv1a f;
  f.words(words.data(), words.size_bytes());
  return f.value();
}

} // namespace

FoldCache::FoldCache(std::filesystem::path dir, std::size_t maxFiles) : dir_(std::move(dir)), maxFiles_(maxFiles) {}

std::uint64_t FoldCache::key(std::span<const std::uint32_t> code, const Specialization& specialization) {
  Fnv1a f;
  f.u64(kFormat);
  f.u64(kFoldPassesVersion);
  const char* tools = spvSoftwareVersionDetailsString();
  f.bytes(tools, std::strlen(tools));
  f.u64(code.size());
  f.words(code.data(), code.size_bytes());
  f.u64(specialization.values().size());
  for (const auto& [id, value] : specialization.values()) {
    f.u64(id);
    f.u64(value);
  }
  return f.value();
}

std::filesystem::path FoldCache::fileFor(std::uint64_t key) const {
  char name[40];
  std::snprintf(name, sizeof name, "folded-%016llx.spv", static_cast<unsigned long long>(key));
  return dir_ / name;
}

std::vector<std::uint32_t> FoldCache::load(std::uint64_t key) const {
  if (dir_.empty()) return {};
  const std::filesystem::path file = fileFor(key);
  std::ifstream in(file, std::ios::binary);
  if (!in) return {};
  Header h{};
  if (!in.read(reinterpret_cast<char*>(&h), sizeof h)) return {};
  if (h.magic != kMagic || h.format != kFormat || h.key != key || h.words < 5 || h.words > kMaxWords) return {};
  std::vector<std::uint32_t> code(h.words);
  if (!in.read(reinterpret_cast<char*>(code.data()), static_cast<std::streamsize>(code.size() * 4))) return {};
  if (in.peek() != std::char_traits<char>::eof()) return {}; // longer than its header says
  if (code[0] != kSpirvMagic || hashWords(code) != h.check) return {};
  // Mark it used, for eviction (least recently used first).
  std::error_code ec;
  std::filesystem::last_write_time(file, std::filesystem::file_time_type::clock::now(), ec);
  return code;
}

void FoldCache::store(std::uint64_t key, std::span<const std::uint32_t> folded) const {
  if (dir_.empty() || folded.empty()) return;
  std::error_code ec;
  std::filesystem::create_directories(dir_, ec);
  if (ec) return;
  const Header h{kMagic, kFormat, key, folded.size(), hashWords(folded)};
  std::vector<std::uint8_t> bytes(sizeof h + folded.size_bytes());
  std::memcpy(bytes.data(), &h, sizeof h);
  std::memcpy(bytes.data() + sizeof h, folded.data(), folded.size_bytes());
  if (!writeFileAtomicQuietly(fileFor(key), bytes)) return;
  evict();
}

void FoldCache::evict() const {
  std::error_code ec;
  std::vector<std::pair<std::filesystem::file_time_type, std::filesystem::path>> files;
  for (std::filesystem::directory_iterator it(dir_, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.rfind("folded-", 0) != 0 || it->path().extension() != ".spv") continue;
    std::error_code tec;
    auto t = it->last_write_time(tec);
    if (!tec) files.emplace_back(t, it->path());
  }
  if (files.size() <= maxFiles_) return;
  std::sort(files.begin(), files.end());
  for (std::size_t i = 0; i + maxFiles_ < files.size(); ++i) std::filesystem::remove(files[i].second, ec);
}

} // namespace vkray::vulkan
