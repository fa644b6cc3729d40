// Buffer creation, memory-type choice, and staged transfers.
#include "vk/buffer.h"

#include <algorithm>
#include <cstring>
#include <optional>

#include "util/error.h"
#include "vk/context.h"

namespace vkray::vulkan {

namespace {

std::optional<std::uint32_t> findMemoryType(const vk::PhysicalDeviceMemoryProperties& props, std::uint32_t typeBits,
                                            vk::MemoryPropertyFlags want) {
  for (std::uint32_t i = 0; i < props.memoryTypeCount; ++i) {
    if ((typeBits & (1u << i)) && (props.memoryTypes[i].propertyFlags & want) == want) return i;
  }
  return std::nullopt;
}

std::string mib(vk::DeviceSize bytes) {
  return std::to_string((bytes + (1u << 20) - 1) >> 20) + " MiB";
}

// Device-local buffers at least this large live in HostPages on CPU devices that can import them:
// the mesh's BVH records and triangles, read at random by every ray. With 4 KiB pages their
// translations overflow the TLB (a 1 M-triangle mesh spans 22 k pages); on 2 MiB pages they fit.
// lavapipe's own allocations are shared-memory files, which the kernel does not back with huge
// pages unless the machine's shmem setting says so (docs/performance.md, "Huge pages").
constexpr vk::DeviceSize kHostImportMinBytes = 4u << 20;

} // namespace

Buffer::Buffer(const Context& context, vk::DeviceSize size, vk::BufferUsageFlags usage, MemoryUse use, std::string name)
    : context_(&context), name_(std::move(name)), size_(size == 0 ? 16 : size) {
  const DeviceInfo& info = context.info();
  if ((usage & vk::BufferUsageFlagBits::eStorageBuffer) && size_ > info.maxStorageBufferRange) {
    throw DeviceError(name_ + " needs " + mib(size_) + " but " + info.name + " binds at most " +
                      mib(info.maxStorageBufferRange) + " per storage buffer (maxStorageBufferRange)");
  }
  if (info.maxMemoryAllocationSize && size_ > info.maxMemoryAllocationSize) {
    throw DeviceError(name_ + " needs " + mib(size_) + " but " + info.name + " allocates at most " +
                      mib(info.maxMemoryAllocationSize) + " at once (maxMemoryAllocationSize)");
  }
  if (use == MemoryUse::DeviceLocal)
    usage |= vk::BufferUsageFlagBits::eTransferDst | vk::BufferUsageFlagBits::eTransferSrc;
  const std::string step = "creating buffer '" + name_ + "'";
  bool importHost = use == MemoryUse::DeviceLocal && context.hostImportEnabled() && size_ >= kHostImportMinBytes &&
                    kHugePageBytes % info.hostImportAlignment == 0;
  vulkanStep(step, [&] {
    const auto& device = context.device();
    using HT = vk::ExternalMemoryHandleTypeFlagBits;
    vk::ExternalMemoryBufferCreateInfo external(HT::eHostAllocationEXT);
    auto makeBuffer = [&] {
      buffer_ = vk::raii::Buffer(device, vk::BufferCreateInfo({}, size_, usage, vk::SharingMode::eExclusive, {},
                                                              importHost ? &external : nullptr));
      return buffer_.getMemoryRequirements();
    };
    auto req = makeBuffer();
    std::uint32_t typeBits = req.memoryTypeBits;
    if (importHost) {
      host_ = HostPages(std::max(req.size, size_));
      std::uint32_t importable =
          device.getMemoryHostPointerPropertiesEXT(HT::eHostAllocationEXT, host_.data()).memoryTypeBits;
      if (typeBits & importable) {
        typeBits &= importable;
      } else { // the driver's own memory after all, for a buffer made without the import's handle type
        host_ = HostPages();
        importHost = false;
        req = makeBuffer();
        typeBits = req.memoryTypeBits;
      }
    }
    auto props = context.physicalDevice().getMemoryProperties();
    using MP = vk::MemoryPropertyFlagBits;
    std::optional<std::uint32_t> type;
    switch (use) {
    case MemoryUse::DeviceLocal:
      // Mapped only where device memory is the host's own, cached (lavapipe, integrated GPUs). On a
      // discrete GPU a device-local, host-visible type is the PCIe BAR: a heap often of 256 MiB, and
      // uncached for the CPU, so a band read back through it crawls; there the staging copies are
      // the fast path.
      type = findMemoryType(props, typeBits, MP::eDeviceLocal | MP::eHostVisible | MP::eHostCoherent | MP::eHostCached);
      if (!type) type = findMemoryType(props, typeBits, MP::eDeviceLocal);
      break;
    case MemoryUse::Upload:
      type = findMemoryType(props, typeBits, MP::eHostVisible | MP::eHostCoherent);
      break;
    case MemoryUse::Readback:
      type = findMemoryType(props, typeBits, MP::eHostVisible | MP::eHostCached);
      if (!type) type = findMemoryType(props, typeBits, MP::eHostVisible | MP::eHostCoherent);
      break;
    }
    if (!type) type = findMemoryType(props, typeBits, {});
    if (!type) throw DeviceError(step + ": no memory type fits");
    auto flags = props.memoryTypes[*type].propertyFlags;
    coherent_ = static_cast<bool>(flags & MP::eHostCoherent);
    if (importHost) {
      vk::ImportMemoryHostPointerInfoEXT import(HT::eHostAllocationEXT, host_.data());
      memory_ = vk::raii::DeviceMemory(device, vk::MemoryAllocateInfo(host_.size(), *type, &import));
      mapped_ = host_.data(); // the same pages the device reads
    } else {
      memory_ = vk::raii::DeviceMemory(device, vk::MemoryAllocateInfo(req.size, *type));
    }
    buffer_.bindMemory(*memory_, 0);
    if (!mapped_ && (flags & MP::eHostVisible)) {
      mapped_ = memory_.mapMemory(0, VK_WHOLE_SIZE);
      vkMapped_ = true;
    }
  });
}

namespace {

std::uint32_t texelBytes(vk::Format format) {
  switch (format) {
  case vk::Format::eR32G32B32A32Sfloat:
  case vk::Format::eR32G32B32A32Uint:
    return 16;
  case vk::Format::eR32Uint:
  case vk::Format::eR32Sfloat: // the viewer's error estimates
    return 4;
  default:
    throw DeviceError("texel buffer format " + vk::to_string(format) + " is not one vkray uses");
  }
}

vk::DeviceSize checkedTexelBytes(const Context& context, vk::DeviceSize size, vk::Format format,
                                 const std::string& name) {
  std::uint32_t bytes = texelBytes(format);
  vk::DeviceSize texels = std::max<vk::DeviceSize>(1, (size + bytes - 1) / bytes);
  const DeviceInfo& info = context.info();
  if (texels > info.maxTexelBufferElements) {
    throw DeviceError(name + " needs " + std::to_string(texels) + " texels but " + info.name + " reads at most " +
                      std::to_string(info.maxTexelBufferElements) + " per texel buffer (maxTexelBufferElements)");
  }
  return texels * bytes;
}

} // namespace

Buffer::Buffer(const Context& context, vk::DeviceSize size, vk::Format texelFormat, MemoryUse use, std::string name,
               vk::BufferUsageFlags extraUsage)
    : Buffer(context, checkedTexelBytes(context, size, texelFormat, name),
             vk::BufferUsageFlagBits::eUniformTexelBuffer | vk::BufferUsageFlagBits::eStorageTexelBuffer | extraUsage,
             use, name) {
  vulkanStep("creating the texel view of '" + name_ + "'", [&] {
    view_ =
        vk::raii::BufferView(context.device(), vk::BufferViewCreateInfo({}, *buffer_, texelFormat, 0, VK_WHOLE_SIZE));
  });
}

Buffer::~Buffer() {
  if (vkMapped_ && *memory_) memory_.unmapMemory();
}

void Buffer::write(const void* data, vk::DeviceSize bytes, vk::DeviceSize offset) {
  if (bytes == 0) return;
  if (offset + bytes > size_) throw DeviceError("write past the end of buffer '" + name_ + "'");
  if (mapped_) {
    std::memcpy(static_cast<char*>(mapped_) + offset, data, bytes);
    if (!coherent_) {
      vulkanStep("flushing '" + name_ + "'", [&] {
        context_->device().flushMappedMemoryRanges(vk::MappedMemoryRange(*memory_, 0, VK_WHOLE_SIZE));
      });
    }
    return;
  }
  Buffer staging(*context_, bytes, vk::BufferUsageFlagBits::eTransferSrc, MemoryUse::Upload, name_ + " (staging)");
  staging.write(data, bytes);
  context_->submitAndWait("uploading '" + name_ + "'", [&](const vk::raii::CommandBuffer& cmd) {
    cmd.copyBuffer(staging.handle(), *buffer_, vk::BufferCopy(0, offset, bytes));
  });
}

void Buffer::read(void* out, vk::DeviceSize bytes, vk::DeviceSize offset) const {
  if (bytes == 0) return;
  if (offset + bytes > size_) throw DeviceError("read past the end of buffer '" + name_ + "'");
  if (mapped_) {
    if (!coherent_) {
      vulkanStep("invalidating '" + name_ + "'", [&] {
        context_->device().invalidateMappedMemoryRanges(vk::MappedMemoryRange(*memory_, 0, VK_WHOLE_SIZE));
      });
    }
    std::memcpy(out, static_cast<const char*>(mapped_) + offset, bytes);
    return;
  }
  Buffer staging(*context_, bytes, vk::BufferUsageFlagBits::eTransferDst, MemoryUse::Readback, name_ + " (readback)");
  context_->submitAndWait("reading back '" + name_ + "'", [&](const vk::raii::CommandBuffer& cmd) {
    cmd.copyBuffer(*buffer_, staging.handle(), vk::BufferCopy(offset, 0, bytes));
    // A fence makes the copy's writes available to the device only; the host needs this barrier.
    vk::MemoryBarrier toHost(vk::AccessFlagBits::eTransferWrite, vk::AccessFlagBits::eHostRead);
    cmd.pipelineBarrier(vk::PipelineStageFlagBits::eTransfer, vk::PipelineStageFlagBits::eHost, {}, toHost, {}, {});
  });
  staging.read(out, bytes);
}

} // namespace vkray::vulkan
