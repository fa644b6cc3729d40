// A compute pipeline built from embedded SPIR-V with specialization constants, and the on-disk
// pipeline cache that lets a second run skip the driver's compile.
#pragma once

#include <bit>
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <span>
#include <string>

#include <vulkan/vulkan_raii.hpp>

namespace vkray::vulkan {

class Context;
class FoldCache;

// Specialization constants by id; every value is 32 bits (VkBool32, int, uint or float).
class Specialization {
public:
  void set(std::uint32_t id, std::uint32_t value) { values_[id] = value; }
  void set(std::uint32_t id, bool value) { values_[id] = value ? 1u : 0u; }
  void set(std::uint32_t id, int value) { values_[id] = static_cast<std::uint32_t>(value); }
  void set(std::uint32_t id, float value) { values_[id] = std::bit_cast<std::uint32_t>(value); }
  const std::map<std::uint32_t, std::uint32_t>& values() const { return values_; }
  bool operator<(const Specialization& o) const { return values_ < o.values_; }
  bool operator==(const Specialization& o) const { return values_ == o.values_; }

private:
  std::map<std::uint32_t, std::uint32_t> values_;
};

// How specialization reaches the driver: as specialization constants alone, or also folded into
// the SPIR-V first (vk/spirv_fold.h), which spares a CPU driver compiling switched-off code.
enum class SpecializationFolding { DriverOnly, FoldSpirv };

class ComputePipeline {
public:
  // cache and foldCache may be null; with a foldCache a folded module is looked up there first
  // and kept there after folding.
  ComputePipeline(const Context& context, std::span<const std::uint32_t> spirv, vk::PipelineLayout layout,
                  const Specialization& specialization, const vk::raii::PipelineCache* cache, const std::string& name,
                  SpecializationFolding folding = SpecializationFolding::DriverOnly,
                  const FoldCache* foldCache = nullptr);
  vk::Pipeline handle() const { return *pipeline_; }
  double creationMs() const { return creationMs_; }      // folding included
  double foldMs() const { return foldMs_; }              // folding, or reading the folded module back
  bool foldKept() const { return foldKept_; }            // the folded module came from the FoldCache
  std::size_t spirvBytes() const { return spirvBytes_; } // what the driver was given

private:
  vk::raii::Pipeline pipeline_{nullptr};
  double creationMs_ = 0.0;
  double foldMs_ = 0.0;
  bool foldKept_ = false;
  std::size_t spirvBytes_ = 0;
};

// A VkPipelineCache loaded from and saved back to a file keyed by the device and driver.
class PipelineCache {
public:
  // An empty path keeps the cache in memory only.
  PipelineCache(const Context& context, std::filesystem::path file);
  ~PipelineCache();
  PipelineCache(const PipelineCache&) = delete;
  PipelineCache& operator=(const PipelineCache&) = delete;

  const vk::raii::PipelineCache& cache() const { return cache_; }
  bool loadedFromDisk() const { return loadedBytes_ > 0; }
  std::size_t loadedBytes() const { return loadedBytes_; }
  const std::filesystem::path& file() const { return file_; }
  // What the driver keeps of compiled pipelines: the cache's data past its 32-byte header
  // (VkPipelineCacheHeaderVersionOne). 0 means it recompiles every run (Mesa 22's lavapipe).
  std::size_t keptBytes() const;
  // Writes the cache now (atomically); also done on destruction. Failures are ignored: a cache
  // that cannot be saved only costs the next run a compile.
  void save() const;

  // $VKRAY_CACHE_DIR, else $XDG_CACHE_HOME/vkray, else ~/.cache/vkray; file per device + driver.
  static std::filesystem::path defaultFile(const Context& context);

  // Folded SPIR-V kept beside the file, in folded/ (none when the file is empty). The module does
  // not depend on the device, only on the build's kernels and the constants.
  const FoldCache& foldCache() const { return *foldCache_; }

private:
  const Context* context_;
  std::filesystem::path file_;
  std::size_t loadedBytes_ = 0;
  vk::raii::PipelineCache cache_{nullptr};
  std::unique_ptr<FoldCache> foldCache_;
};

} // namespace vkray::vulkan
