// HostPages: an anonymous mapping on a 2 MiB boundary, with a guard page after it.
#include "vk/host_pages.h"

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>
#include <utility>

#include <sys/mman.h>
#include <unistd.h>

#include "util/error.h"

namespace vkray::vulkan {

namespace {

std::size_t pageBytes() {
  long page = sysconf(_SC_PAGESIZE);
  return page > 0 ? static_cast<std::size_t>(page) : 4096;
}

} // namespace

std::string transparentHugePages() {
  // One line such as "always [madvise] never": the bracketed word is the mode in force.
  std::ifstream file("/sys/kernel/mm/transparent_hugepage/enabled");
  std::string line;
  if (!std::getline(file, line)) return "unknown";
  auto open = line.find('['), close = line.find(']');
  return open != std::string::npos && close > open ? line.substr(open + 1, close - open - 1) : "unknown";
}

HostPages::HostPages(std::size_t bytes) {
  const std::size_t size = std::max<std::size_t>(1, (bytes + kHugePageBytes - 1) / kHugePageBytes) * kHugePageBytes;
  const std::size_t guard = pageBytes();
  // One huge page more than needed, so that the kept range can start on a 2 MiB boundary; the
  // rest is unmapped again, but for one inaccessible page after the range, which keeps the kernel
  // from merging the range with a neighbouring mapping (hugeBytes reads the range's own entry).
  const std::size_t mapped = size + kHugePageBytes;
  void* raw = mmap(nullptr, mapped, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (raw == MAP_FAILED) {
    throw DeviceError("mapping " + std::to_string(size >> 20) + " MiB of host memory: " + std::strerror(errno));
  }
  const auto start = reinterpret_cast<std::uintptr_t>(raw);
  const std::uintptr_t begin = (start + kHugePageBytes - 1) / kHugePageBytes * kHugePageBytes;
  const std::uintptr_t end = start + mapped;
  if (begin > start) munmap(raw, begin - start);
  const std::uintptr_t guardEnd = begin + size + guard;
  if (guardEnd <= end) {
    mprotect(reinterpret_cast<void*>(begin + size), guard, PROT_NONE);
    if (end > guardEnd) munmap(reinterpret_cast<void*>(guardEnd), end - guardEnd);
    guard_ = guard;
  } else if (end > begin + size) {
    munmap(reinterpret_cast<void*>(begin + size), end - (begin + size));
  }
  data_ = reinterpret_cast<void*>(begin);
  size_ = size;
  // Advice only: where transparent huge pages are off, the pages are small and all else the same.
  madvise(data_, size_, MADV_HUGEPAGE);
}

HostPages::HostPages(HostPages&& other) noexcept
    : data_(std::exchange(other.data_, nullptr)), size_(std::exchange(other.size_, 0)),
      guard_(std::exchange(other.guard_, 0)) {}

HostPages& HostPages::operator=(HostPages&& other) noexcept {
  if (this != &other) {
    release();
    data_ = std::exchange(other.data_, nullptr);
    size_ = std::exchange(other.size_, 0);
    guard_ = std::exchange(other.guard_, 0);
  }
  return *this;
}

HostPages::~HostPages() {
  release();
}

void HostPages::release() noexcept {
  if (data_) munmap(data_, size_ + guard_);
  data_ = nullptr;
  size_ = 0;
  guard_ = 0;
}

std::size_t HostPages::hugeBytes() const {
  if (!data_) return 0;
  // /proc/self/smaps: a header line "start-end perms ..." per mapping, then "Name: value kB" lines.
  std::ifstream smaps("/proc/self/smaps");
  const auto begin = reinterpret_cast<std::uintptr_t>(data_);
  std::string line;
  bool ours = false;
  while (std::getline(smaps, line)) {
    unsigned long long lo = 0, hi = 0;
    if (std::sscanf(line.c_str(), "%llx-%llx ", &lo, &hi) == 2 && line.find(':') > line.find(' ')) {
      ours = lo == begin && hi == begin + size_;
      continue;
    }
    unsigned long long kb = 0;
    if (ours && std::sscanf(line.c_str(), "AnonHugePages: %llu kB", &kb) == 1) {
      return std::min<std::size_t>(size_, static_cast<std::size_t>(kb) << 10);
    }
  }
  return 0;
}

} // namespace vkray::vulkan
