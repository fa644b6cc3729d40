// Memory vkray maps itself for buffers that import it (VK_EXT_external_memory_host on CPU devices):
// whole 2 MiB pages, aligned, advised for transparent huge pages, so that a large scene's BVH and
// triangles, read at random by every ray, need few TLB entries (docs/performance.md, "Huge pages").
#pragma once

#include <cstddef>
#include <string>

namespace vkray::vulkan {

constexpr std::size_t kHugePageBytes = std::size_t{2} << 20;

// This machine's transparent-huge-page mode ("always", "madvise" or "never"), or "unknown".
std::string transparentHugePages();

class HostPages {
public:
  HostPages() = default;
  // `bytes` rounded up to whole huge pages. Throws DeviceError when the mapping fails.
  explicit HostPages(std::size_t bytes);
  HostPages(HostPages&& other) noexcept;
  HostPages& operator=(HostPages&& other) noexcept;
  HostPages(const HostPages&) = delete;
  HostPages& operator=(const HostPages&) = delete;
  ~HostPages();

  void* data() const { return data_; }
  std::size_t size() const { return size_; }
  // How much of the range the kernel backs with huge pages now (from /proc/self/smaps; 0 where
  // that cannot be read, or where transparent huge pages are off).
  std::size_t hugeBytes() const;

private:
  void release() noexcept;

  void* data_ = nullptr;
  std::size_t size_ = 0;
  std::size_t guard_ = 0; // bytes of the inaccessible page after the range (0: none)
};

} // namespace vkray::vulkan
