// Compute pipelines with specialization, and the persistent pipeline cache.
#include "vk/compute_pipeline.h"

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <vector>

#include "util/atomic_file.h"
#include "vk/context.h"
#include "vk/fold_cache.h"
#include "vk/spirv_fold.h"

namespace vkray::vulkan {

ComputePipeline::ComputePipeline(const Context& context, std::span<const std::uint32_t> spirv,
                                 vk::PipelineLayout layout, const Specialization& specialization,
                                 const vk::raii::PipelineCache* cache, const std::string& name,
                                 SpecializationFolding folding, const FoldCache* foldCache) {
  auto start = std::chrono::steady_clock::now();
  FoldedSpirv folded;
  if (folding == SpecializationFolding::FoldSpirv) {
    const std::uint64_t key = foldCache ? FoldCache::key(spirv, specialization) : 0;
    if (foldCache) folded.code = foldCache->load(key);
    foldKept_ = !folded.code.empty();
    if (!foldKept_) {
      folded = foldSpecialization(spirv, specialization);
      if (foldCache && !folded.code.empty()) foldCache->store(key, folded.code);
    }
    if (folded.code.empty()) {
      // Never fatal: the driver specializes the original module the same way, only slower.
      std::fprintf(stderr, "vkray: warning: pipeline '%s' handed to the driver unfolded: %s\n", name.c_str(),
                   folded.error.c_str());
    } else {
      spirv = folded.code;
    }
    foldMs_ = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  }
  spirvBytes_ = spirv.size_bytes();
  std::vector<vk::SpecializationMapEntry> entries;
  std::vector<std::uint32_t> data;
  for (const auto& [id, value] : specialization.values()) {
    entries.emplace_back(id, static_cast<std::uint32_t>(data.size() * sizeof(std::uint32_t)), sizeof(std::uint32_t));
    data.push_back(value);
  }
  vk::SpecializationInfo specInfo(entries, vk::ArrayProxyNoTemporaries<const std::uint32_t>(data));
  vulkanStep("creating pipeline '" + name + "'", [&] {
    vk::raii::ShaderModule module(context.device(), vk::ShaderModuleCreateInfo({}, spirv.size_bytes(), spirv.data()));
    vk::PipelineShaderStageCreateInfo stage({}, vk::ShaderStageFlagBits::eCompute, *module, "main", &specInfo);
    vk::ComputePipelineCreateInfo info({}, stage, layout);
    pipeline_ = cache ? vk::raii::Pipeline(context.device(), *cache, info)
                      : vk::raii::Pipeline(context.device(), nullptr, info);
  });
  creationMs_ = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

namespace {

std::vector<char> readAll(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) return {};
  return std::vector<char>(std::istreambuf_iterator<char>(in), {});
}

} // namespace

PipelineCache::PipelineCache(const Context& context, std::filesystem::path file)
    : context_(&context), file_(std::move(file)),
      foldCache_(
          std::make_unique<FoldCache>(file_.empty() ? std::filesystem::path() : file_.parent_path() / "folded")) {
  std::vector<char> data;
  if (!file_.empty()) data = readAll(file_);
  // The driver checks the header (vendor, device, cache UUID) and ignores data from another driver.
  vulkanStep("creating the pipeline cache", [&] {
    try {
      cache_ = vk::raii::PipelineCache(context.device(), vk::PipelineCacheCreateInfo({}, data.size(), data.data()));
      loadedBytes_ = data.size();
    } catch (const vk::SystemError&) {
      cache_ = vk::raii::PipelineCache(context.device(), vk::PipelineCacheCreateInfo());
      loadedBytes_ = 0;
    }
  });
}

PipelineCache::~PipelineCache() {
  save();
}

std::size_t PipelineCache::keptBytes() const {
  constexpr std::size_t kHeaderBytes = 32;
  std::size_t size = 0;
  try {
    size = cache_.getData().size();
  } catch (const vk::SystemError&) {
    return 0;
  }
  return size > kHeaderBytes ? size - kHeaderBytes : 0;
}

void PipelineCache::save() const {
  if (file_.empty() || !*cache_) return;
  try {
    std::vector<std::uint8_t> data = cache_.getData();
    std::error_code ec;
    std::filesystem::create_directories(file_.parent_path(), ec);
    writeFileAtomicQuietly(file_, data);
  } catch (...) {
  }
}

std::filesystem::path PipelineCache::defaultFile(const Context& context) {
  std::filesystem::path dir;
  if (const char* d = std::getenv("VKRAY_CACHE_DIR"); d && *d) {
    dir = d;
  } else if (const char* x = std::getenv("XDG_CACHE_HOME"); x && *x) {
    dir = std::filesystem::path(x) / "vkray";
  } else if (const char* h = std::getenv("HOME"); h && *h) {
    dir = std::filesystem::path(h) / ".cache" / "vkray";
  } else {
    return {};
  }
  auto props = context.physicalDevice().getProperties();
  char name[96];
  std::snprintf(name, sizeof name, "pipelines-%04x-%04x-%08x.bin", props.vendorID, props.deviceID, props.driverVersion);
  return dir / name;
}

} // namespace vkray::vulkan
