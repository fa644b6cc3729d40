// A buffer and its memory, owned together. DeviceLocal buffers are written and read through a
// staging copy when the device cannot map them; on unified-memory devices (lavapipe) they map.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include <vulkan/vulkan_raii.hpp>

#include "vk/host_pages.h"

namespace vkray::vulkan {

class Context;

enum class MemoryUse {
  DeviceLocal, // fastest for the GPU; mapped directly when the device allows it
  Upload,      // host-visible, written by the CPU
  Readback,    // host-visible and cached where possible, read by the CPU
};

class Buffer {
public:
  // size 0 is rounded up (Vulkan forbids empty buffers). A storage buffer larger than the device's
  // maxStorageBufferRange throws, naming the limit.
  Buffer(const Context& context, vk::DeviceSize size, vk::BufferUsageFlags usage, MemoryUse use, std::string name);
  // A texel buffer (usable as a uniform or a storage texel buffer) read as texels of `texelFormat`,
  // with its view. More texels than the device's maxTexelBufferElements throws, naming the limit.
  // extraUsage: other ways the buffer is bound too (a storage buffer a kernel writes, say).
  Buffer(const Context& context, vk::DeviceSize size, vk::Format texelFormat, MemoryUse use, std::string name,
         vk::BufferUsageFlags extraUsage = {});
  Buffer(Buffer&&) noexcept = default;
  Buffer& operator=(Buffer&&) noexcept = default;
  ~Buffer();

  vk::Buffer handle() const { return *buffer_; }
  vk::BufferView texelView() const { return *view_; } // null unless made as a texel buffer
  vk::DeviceSize size() const { return size_; }
  const std::string& name() const { return name_; }
  bool mapped() const { return mapped_ != nullptr; }
  // The buffer's memory as the host sees it, to read in place where it is mapped and coherent (the
  // GPU's writes visible once its work has completed); null elsewhere: use read().
  const void* hostView() const { return mapped_ != nullptr && coherent_ ? mapped_ : nullptr; }
  // The pages this buffer's memory imports, or null where it lives in the driver's own memory.
  const HostPages* hostPages() const { return host_.data() ? &host_ : nullptr; }

  void write(const void* data, vk::DeviceSize bytes, vk::DeviceSize offset = 0);
  void read(void* out, vk::DeviceSize bytes, vk::DeviceSize offset = 0) const;
  // The buffer's first `count` elements: read in place through hostView() where it allows, else
  // copied out into `copy` (one queue submission), which must outlive the pointer's use.
  template <class T> const T* view(std::vector<T>& copy, std::size_t count) const {
    if (const void* in = hostView()) return static_cast<const T*>(in);
    copy.resize(count);
    read(copy.data(), count * sizeof(T));
    return copy.data();
  }

private:
  const Context* context_;
  std::string name_;
  vk::DeviceSize size_ = 0;
  bool coherent_ = true;
  bool vkMapped_ = false; // mapped_ came from vkMapMemory (not from host_)
  // Destruction runs upwards: the view, the buffer, the memory bound to it, then the host pages
  // that memory imports (if any).
  HostPages host_;
  vk::raii::DeviceMemory memory_{nullptr};
  vk::raii::Buffer buffer_{nullptr};
  vk::raii::BufferView view_{nullptr}; // destroyed before the buffer it views
  void* mapped_ = nullptr;
};

} // namespace vkray::vulkan
