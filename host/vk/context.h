// The Vulkan context: instance (with the validation layer and a messenger that counts what it
// reports), the chosen physical device, a logical device with one compute queue, and a command pool
// for one-shot submissions. Construction creates everything; destruction releases it in reverse.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <vulkan/vulkan_raii.hpp>

namespace vkray::vulkan {

struct ContextOptions {
  bool validation = false;                     // VK_LAYER_KHRONOS_validation
  bool synchronizationValidation = false;      // its synchronization checks too (implies validation)
  bool echoValidation = true;                  // print each message on stderr as it arrives
  std::string device;                          // index or case-insensitive name substring; empty: best
  std::vector<std::string> instanceExtensions; // e.g. GLFW's surface extensions
  std::vector<std::string> deviceExtensions;   // e.g. VK_KHR_swapchain
  // Large device-local buffers in vkray's own huge pages where a CPU device can import them
  // (VK_EXT_external_memory_host; host/vk/host_pages.h). Off: the driver's memory, for comparison.
  bool hostPages = true;
  // Extra queue-family requirement (the viewer asks for present support).
  std::function<bool(const vk::raii::PhysicalDevice&, std::uint32_t family)> queueFamilyFilter;
};

struct DeviceInfo {
  std::uint32_t index = 0;
  std::string name;
  std::string type;   // "discrete GPU", "integrated GPU", "CPU", ...
  std::string driver; // driver name and version as the driver reports it
  std::uint32_t apiVersion = 0;
  bool shaderFloat64 = false;
  bool storageImageWriteWithoutFormat = false; // imageStore to an image declared without a format
  bool timestamps = false;
  std::uint64_t maxStorageBufferRange = 0;
  std::uint64_t maxTexelBufferElements = 0;
  std::uint64_t maxMemoryAllocationSize = 0;
  std::uint32_t maxComputeWorkGroupCount[3] = {0, 0, 0};
  std::uint32_t maxComputeWorkGroupSizeX = 0;
  std::uint32_t maxComputeWorkGroupInvocations = 0;
  std::uint32_t maxPushConstantsSize = 0;
  // VK_EXT_external_memory_host on a CPU device: large buffers can live in memory vkray allocates
  // itself (host/vk/buffer.cpp). 0 where not offered.
  std::uint64_t hostImportAlignment = 0;
  std::uint32_t subgroupSize = 0;
  // The subgroup operations the kernels use that the device lacks in compute shaders, in words
  // ("" when it has them all): see missingSubgroupSupport.
  std::string subgroupMissing;
};

// The kernels vote, count and pass values across a subgroup (the BVH walk's lockstep ballots, the
// ray counters' sums, the lanes that share a pixel in a progressive pass): they need basic,
// arithmetic, ballot and shuffle operations in compute shaders. Names what is
// missing ("ballot, arithmetic"), or "" when nothing is.
std::string missingSubgroupSupport(const vk::PhysicalDeviceSubgroupProperties& properties);

// Messages the validation layer reported (warnings and errors).
class ValidationLog {
public:
  explicit ValidationLog(bool echo) : echo_(echo) {}
  void add(std::string message);
  std::size_t count() const;
  std::vector<std::string> messages() const;
  void clear();

private:
  bool echo_;
  mutable std::mutex mutex_;
  std::vector<std::string> messages_;
};

class Context {
public:
  explicit Context(const ContextOptions& options);
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;
  ~Context();

  const vk::raii::Instance& instance() const { return instance_; }
  const vk::raii::PhysicalDevice& physicalDevice() const { return physicalDevice_; }
  const vk::raii::Device& device() const { return device_; }
  const vk::raii::Queue& queue() const { return queue_; }
  std::uint32_t queueFamily() const { return queueFamily_; }
  const vk::raii::CommandPool& commandPool() const { return commandPool_; }
  const DeviceInfo& info() const { return info_; }
  bool float64Enabled() const { return float64Enabled_; }
  // Shaders may write storage images declared without a format (the viewer's swapchain images).
  bool storageWriteWithoutFormatEnabled() const { return info_.storageImageWriteWithoutFormat; }
  double timestampPeriodNs() const { return timestampPeriodNs_; }
  std::uint32_t timestampValidBits() const { return timestampValidBits_; }
  bool validationEnabled() const { return validation_; }
  // VK_EXT_external_memory_host is enabled: buffers may import memory vkray allocated.
  bool hostImportEnabled() const { return hostImport_; }

  // Records with `record`, submits, and waits. `step` names the work in error messages; a lost
  // device throws DeviceLostError.
  void submitAndWait(std::string_view step, const std::function<void(const vk::raii::CommandBuffer&)>& record) const;

  // How many turns the loops of an invocation may run in all before the driver ends them (Mesa 22's
  // llvmpipe: 65535 per SIMD group), or 0 where loops run to their end (Mesa 25, GPUs). Measured
  // on first use by a one-invocation kernel (vk/loop_limit.cpp), then kept: the renderer gives a
  // dispatch several samples per invocation only where nothing cuts them short.
  std::uint32_t loopLimit() const;

  std::size_t validationMessageCount() const { return log_->count(); }
  std::vector<std::string> validationMessages() const { return log_->messages(); }
  ValidationLog& validationLog() const { return *log_; }

  // Every physical device the loader offers, without creating a logical device.
  static std::vector<DeviceInfo> listDevices();

private:
  // Declaration order is destruction order in reverse: the log outlives the instance (the layer
  // reports leaked objects while the instance is destroyed), the device outlives its pool.
  std::unique_ptr<ValidationLog> log_;
  vk::raii::Context context_;
  vk::raii::Instance instance_{nullptr};
  vk::raii::DebugUtilsMessengerEXT messenger_{nullptr};
  vk::raii::PhysicalDevice physicalDevice_{nullptr};
  vk::raii::Device device_{nullptr};
  vk::raii::Queue queue_{nullptr};
  vk::raii::CommandPool commandPool_{nullptr};
  std::uint32_t queueFamily_ = 0;
  DeviceInfo info_;
  bool float64Enabled_ = false;
  bool validation_ = false;
  bool hostImport_ = false;
  double timestampPeriodNs_ = 1.0;
  std::uint32_t timestampValidBits_ = 0;
  mutable std::mutex loopLimitMutex_;
  mutable std::optional<std::uint32_t> loopLimit_;
};

// Runs f and turns a Vulkan failure into a DeviceError naming the step ("uploading the scene: ...").
template <typename F> auto vulkanStep(std::string_view step, F&& f) -> decltype(f());

// The message a lost device or failed call reports: "step: vkCall: VK_ERROR_...".
[[noreturn]] void rethrowVulkanError(std::string_view step, const vk::SystemError& e);

// With VKRAY_LOG_STEPS=1 in the environment, each named step says on standard error when it
// starts and how long it took ("vkray [  1.234 s] creating pipeline 'trace' ...", then "... done in
// 412.3 ms"), and a GPU wait says every second that it is still waiting: a step that never returns
// names itself, whether the driver is compiling or the device is running (docs/reliability.md).
bool stepLogEnabled();
class StepLog {
public:
  explicit StepLog(std::string_view step);
  ~StepLog();
  StepLog(const StepLog&) = delete;
  StepLog& operator=(const StepLog&) = delete;

private:
  std::string step_; // empty when the log is off
  int exceptions_ = 0;
  double startS_ = 0.0;
};

template <typename F> auto vulkanStep(std::string_view step, F&& f) -> decltype(f()) {
  try {
    StepLog log(step);
    return f();
  } catch (const vk::SystemError& e) {
    rethrowVulkanError(step, e);
  }
}

} // namespace vkray::vulkan
