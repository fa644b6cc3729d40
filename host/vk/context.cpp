// Vulkan context creation: instance, validation messenger, device choice, logical device.
#include "vk/context.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <sstream>

#include "util/error.h"

namespace vkray::vulkan {

namespace {

constexpr const char* kValidationLayer = "VK_LAYER_KHRONOS_validation";
constexpr const char* kInstallHint =
    "install a Vulkan driver; for the CPU driver lavapipe: apt-get install mesa-vulkan-drivers";

VKAPI_ATTR VkBool32 VKAPI_CALL onValidationMessage(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                   VkDebugUtilsMessageTypeFlagsEXT /*types*/,
                                                   const VkDebugUtilsMessengerCallbackDataEXT* data, void* user) {
  if (severity < VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT) return VK_FALSE;
  auto* log = static_cast<ValidationLog*>(user);
  std::string text = data && data->pMessage ? data->pMessage : "(no message)";
  if (data && data->pMessageIdName) text = std::string(data->pMessageIdName) + ": " + text;
  log->add(std::move(text));
  return VK_FALSE;
}

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string typeName(vk::PhysicalDeviceType t) {
  switch (t) {
  case vk::PhysicalDeviceType::eDiscreteGpu:
    return "discrete GPU";
  case vk::PhysicalDeviceType::eIntegratedGpu:
    return "integrated GPU";
  case vk::PhysicalDeviceType::eVirtualGpu:
    return "virtual GPU";
  case vk::PhysicalDeviceType::eCpu:
    return "CPU";
  default:
    return "other";
  }
}

int typeRank(vk::PhysicalDeviceType t) {
  switch (t) {
  case vk::PhysicalDeviceType::eDiscreteGpu:
    return 0;
  case vk::PhysicalDeviceType::eIntegratedGpu:
    return 1;
  case vk::PhysicalDeviceType::eVirtualGpu:
    return 2;
  case vk::PhysicalDeviceType::eCpu:
    return 3;
  default:
    return 4;
  }
}

bool listsExtension(const std::vector<vk::ExtensionProperties>& available, std::string_view name) {
  return std::any_of(available.begin(), available.end(),
                     [&](const vk::ExtensionProperties& p) { return name == p.extensionName.data(); });
}

vk::PhysicalDeviceSubgroupProperties subgroupProperties(const vk::raii::PhysicalDevice& pd) {
  return pd.getProperties2<vk::PhysicalDeviceProperties2, vk::PhysicalDeviceSubgroupProperties>()
      .get<vk::PhysicalDeviceSubgroupProperties>();
}

} // namespace

std::string missingSubgroupSupport(const vk::PhysicalDeviceSubgroupProperties& properties) {
  if (!(properties.supportedStages & vk::ShaderStageFlagBits::eCompute)) return "subgroups in compute shaders";
  using Op = vk::SubgroupFeatureFlagBits;
  std::string missing;
  for (auto [op, name] : {std::pair{Op::eBasic, "basic"},
                          {Op::eArithmetic, "arithmetic"},
                          {Op::eBallot, "ballot"},
                          {Op::eShuffle, "shuffle"}}) {
    if (!(properties.supportedOperations & op)) missing += (missing.empty() ? "" : ", ") + std::string(name);
  }
  return missing;
}

namespace {

DeviceInfo describe(const vk::raii::PhysicalDevice& pd, std::uint32_t index) {
  DeviceInfo info;
  info.index = index;
  auto chain = pd.getProperties2<vk::PhysicalDeviceProperties2, vk::PhysicalDeviceDriverProperties>();
  const auto& props = chain.get<vk::PhysicalDeviceProperties2>().properties;
  const auto& driver = chain.get<vk::PhysicalDeviceDriverProperties>();
  const vk::PhysicalDeviceSubgroupProperties subgroups = subgroupProperties(pd);
  info.subgroupSize = subgroups.subgroupSize;
  info.subgroupMissing = missingSubgroupSupport(subgroups);
  info.name = props.deviceName.data();
  info.type = typeName(props.deviceType);
  info.driver = std::string(driver.driverName.data()) + " " + driver.driverInfo.data();
  info.apiVersion = props.apiVersion;
  info.shaderFloat64 = pd.getFeatures().shaderFloat64 == VK_TRUE;
  info.storageImageWriteWithoutFormat = pd.getFeatures().shaderStorageImageWriteWithoutFormat == VK_TRUE;
  info.timestamps = props.limits.timestampComputeAndGraphics == VK_TRUE;
  info.maxStorageBufferRange = props.limits.maxStorageBufferRange;
  info.maxTexelBufferElements = props.limits.maxTexelBufferElements;
  info.maxComputeWorkGroupCount[0] = props.limits.maxComputeWorkGroupCount[0];
  info.maxComputeWorkGroupCount[1] = props.limits.maxComputeWorkGroupCount[1];
  info.maxComputeWorkGroupCount[2] = props.limits.maxComputeWorkGroupCount[2];
  info.maxPushConstantsSize = props.limits.maxPushConstantsSize;
  info.maxComputeWorkGroupSizeX = props.limits.maxComputeWorkGroupSize[0];
  info.maxComputeWorkGroupInvocations = props.limits.maxComputeWorkGroupInvocations;
  auto maint3 = pd.getProperties2<vk::PhysicalDeviceProperties2, vk::PhysicalDeviceMaintenance3Properties>();
  info.maxMemoryAllocationSize = maint3.get<vk::PhysicalDeviceMaintenance3Properties>().maxMemoryAllocationSize;
  if (props.deviceType == vk::PhysicalDeviceType::eCpu) {
    if (listsExtension(pd.enumerateDeviceExtensionProperties(), VK_EXT_EXTERNAL_MEMORY_HOST_EXTENSION_NAME)) {
      auto host = pd.getProperties2<vk::PhysicalDeviceProperties2, vk::PhysicalDeviceExternalMemoryHostPropertiesEXT>();
      info.hostImportAlignment =
          host.get<vk::PhysicalDeviceExternalMemoryHostPropertiesEXT>().minImportedHostPointerAlignment;
    }
  }
  return info;
}

vk::raii::Instance createInstance(const vk::raii::Context& context, const ContextOptions& options, ValidationLog* log,
                                  bool validation) {
  vk::ApplicationInfo app("vkray", 1, "vkray", 1, VK_API_VERSION_1_2);
  std::vector<const char*> layers;
  std::vector<const char*> extensions;
  for (const auto& e : options.instanceExtensions) extensions.push_back(e.c_str());
  if (validation) {
    auto available = context.enumerateInstanceLayerProperties();
    bool found = std::any_of(available.begin(), available.end(), [](const vk::LayerProperties& p) {
      return std::string(p.layerName.data()) == kValidationLayer;
    });
    if (!found) {
      throw DeviceError(std::string("validation requested but ") + kValidationLayer +
                        " is not installed (apt-get install vulkan-validationlayers)");
    }
    layers.push_back(kValidationLayer);
    extensions.push_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
  }
  vk::InstanceCreateInfo info({}, &app, layers, extensions);
  // The messenger chained here also reports during vkCreateInstance/vkDestroyInstance, which is when
  // the layer lists objects the application leaked.
  vk::DebugUtilsMessengerCreateInfoEXT messengerInfo(
      {}, vk::DebugUtilsMessageSeverityFlagBitsEXT::eWarning | vk::DebugUtilsMessageSeverityFlagBitsEXT::eError,
      vk::DebugUtilsMessageTypeFlagBitsEXT::eGeneral | vk::DebugUtilsMessageTypeFlagBitsEXT::eValidation |
          vk::DebugUtilsMessageTypeFlagBitsEXT::ePerformance,
      &onValidationMessage, log);
  std::vector<vk::ValidationFeatureEnableEXT> enables;
  if (options.synchronizationValidation) enables.push_back(vk::ValidationFeatureEnableEXT::eSynchronizationValidation);
  vk::ValidationFeaturesEXT features(enables, {});
  if (validation) {
    info.pNext = &messengerInfo;
    if (!enables.empty()) messengerInfo.pNext = &features;
  }
  try {
    return vk::raii::Instance(context, info);
  } catch (const vk::IncompatibleDriverError&) {
    throw DeviceError(std::string("no Vulkan driver found: ") + kInstallHint);
  } catch (const vk::SystemError& e) {
    rethrowVulkanError("creating the Vulkan instance", e);
  }
}

} // namespace

void ValidationLog::add(std::string message) {
  std::lock_guard lock(mutex_);
  if (echo_) std::fprintf(stderr, "vkray: validation: %s\n", message.c_str());
  messages_.push_back(std::move(message));
}

std::size_t ValidationLog::count() const {
  std::lock_guard lock(mutex_);
  return messages_.size();
}

std::vector<std::string> ValidationLog::messages() const {
  std::lock_guard lock(mutex_);
  return messages_;
}

void ValidationLog::clear() {
  std::lock_guard lock(mutex_);
  messages_.clear();
}

namespace {

// Seconds since the first use of the step log (the process's first Vulkan step, near its start).
double stepClockS() {
  using Clock = std::chrono::steady_clock;
  static const Clock::time_point origin = Clock::now();
  return std::chrono::duration<double>(Clock::now() - origin).count();
}

} // namespace

bool stepLogEnabled() {
  static const bool enabled = [] {
    const char* v = std::getenv("VKRAY_LOG_STEPS");
    return v != nullptr && *v != '\0' && std::string_view(v) != "0";
  }();
  return enabled;
}

// One fprintf per line: lines from the threads that build pipelines side by side do not interleave.
StepLog::StepLog(std::string_view step) {
  if (!stepLogEnabled()) return;
  step_ = step;
  exceptions_ = std::uncaught_exceptions();
  startS_ = stepClockS();
  std::fprintf(stderr, "vkray [%8.3f s] %s ...\n", startS_, step_.c_str());
}

StepLog::~StepLog() {
  if (step_.empty()) return;
  const double now = stepClockS();
  const char* how = std::uncaught_exceptions() > exceptions_ ? "failed after" : "done in";
  std::fprintf(stderr, "vkray [%8.3f s] %s ... %s %.1f ms\n", now, step_.c_str(), how, (now - startS_) * 1e3);
}

void rethrowVulkanError(std::string_view step, const vk::SystemError& e) {
  std::string what = std::string(step) + ": " + e.what();
  if (e.code() == vk::make_error_code(vk::Result::eErrorDeviceLost)) {
    throw DeviceLostError(what + " (VK_ERROR_DEVICE_LOST: the device stopped responding)");
  }
  throw DeviceError(what);
}

Context::Context(const ContextOptions& options) : log_(std::make_unique<ValidationLog>(options.echoValidation)) {
  validation_ = options.validation || options.synchronizationValidation;
  instance_ = createInstance(context_, options, log_.get(), validation_);
  if (validation_) {
    vk::DebugUtilsMessengerCreateInfoEXT messengerInfo(
        {}, vk::DebugUtilsMessageSeverityFlagBitsEXT::eWarning | vk::DebugUtilsMessageSeverityFlagBitsEXT::eError,
        vk::DebugUtilsMessageTypeFlagBitsEXT::eGeneral | vk::DebugUtilsMessageTypeFlagBitsEXT::eValidation |
            vk::DebugUtilsMessageTypeFlagBitsEXT::ePerformance,
        &onValidationMessage, log_.get());
    messenger_ = vulkanStep("creating the validation messenger",
                            [&] { return vk::raii::DebugUtilsMessengerEXT(instance_, messengerInfo); });
  }

  // Choose the device: by index or name when asked, else the best kind (discrete first).
  vk::raii::PhysicalDevices devices =
      vulkanStep("listing devices", [&] { return vk::raii::PhysicalDevices(instance_); });
  if (devices.empty()) throw DeviceError(std::string("no Vulkan device found: ") + kInstallHint);

  auto familyFor = [&](const vk::raii::PhysicalDevice& pd) -> int {
    auto families = pd.getQueueFamilyProperties();
    int best = -1;
    for (std::uint32_t i = 0; i < families.size(); ++i) {
      if (!(families[i].queueFlags & vk::QueueFlagBits::eCompute)) continue;
      if (options.queueFamilyFilter && !options.queueFamilyFilter(pd, i)) continue;
      // Prefer a family that can also do graphics/transfer work (the viewer blits from it).
      if (best < 0 || (families[i].queueFlags & vk::QueueFlagBits::eGraphics)) {
        if (best < 0 || !(families[static_cast<std::size_t>(best)].queueFlags & vk::QueueFlagBits::eGraphics)) {
          best = static_cast<int>(i);
        }
      }
    }
    return best;
  };
  auto hasExtensions = [&](const vk::raii::PhysicalDevice& pd) {
    auto available = pd.enumerateDeviceExtensionProperties();
    return std::all_of(options.deviceExtensions.begin(), options.deviceExtensions.end(),
                       [&](const std::string& want) { return listsExtension(available, want); });
  };
  auto subgroupGaps = [](const vk::raii::PhysicalDevice& pd) { return missingSubgroupSupport(subgroupProperties(pd)); };

  int chosen = -1;
  if (!options.device.empty()) {
    bool numeric = std::all_of(options.device.begin(), options.device.end(), ::isdigit);
    std::string names;
    for (std::uint32_t i = 0; i < devices.size(); ++i) {
      std::string name = devices[i].getProperties().deviceName.data();
      names += (names.empty() ? "" : ", ") + std::to_string(i) + ": " + name;
      bool match =
          numeric ? std::to_string(i) == options.device : lower(name).find(lower(options.device)) != std::string::npos;
      if (match && chosen < 0) chosen = static_cast<int>(i);
    }
    if (chosen < 0) throw DeviceError("--device '" + options.device + "' matches no device (have " + names + ")");
    if (familyFor(devices[static_cast<std::size_t>(chosen)]) < 0) {
      throw DeviceError("device '" +
                        std::string(devices[static_cast<std::size_t>(chosen)].getProperties().deviceName.data()) +
                        "' has no suitable compute queue");
    }
    if (!hasExtensions(devices[static_cast<std::size_t>(chosen)])) {
      throw DeviceError("device '" +
                        std::string(devices[static_cast<std::size_t>(chosen)].getProperties().deviceName.data()) +
                        "' lacks a required extension");
    }
    if (std::string gaps = subgroupGaps(devices[static_cast<std::size_t>(chosen)]); !gaps.empty()) {
      throw DeviceError(
          "device '" + std::string(devices[static_cast<std::size_t>(chosen)].getProperties().deviceName.data()) +
          "' lacks subgroup operations the kernels use: " + gaps + " (VkPhysicalDeviceSubgroupProperties)");
    }
  } else {
    int bestRank = 1 << 30;
    for (std::uint32_t i = 0; i < devices.size(); ++i) {
      if (familyFor(devices[i]) < 0 || !hasExtensions(devices[i]) || !subgroupGaps(devices[i]).empty()) continue;
      int rank = typeRank(devices[i].getProperties().deviceType);
      if (rank < bestRank) {
        bestRank = rank;
        chosen = static_cast<int>(i);
      }
    }
    if (chosen < 0) {
      throw DeviceError(std::string("no Vulkan device with a suitable compute queue and subgroup basic, arithmetic and "
                                    "ballot operations in compute shaders: ") +
                        kInstallHint);
    }
  }
  physicalDevice_ = std::move(devices[static_cast<std::size_t>(chosen)]);
  info_ = describe(physicalDevice_, static_cast<std::uint32_t>(chosen));
  queueFamily_ = static_cast<std::uint32_t>(familyFor(physicalDevice_));

  auto props = physicalDevice_.getProperties();
  timestampPeriodNs_ = props.limits.timestampPeriod;
  timestampValidBits_ = physicalDevice_.getQueueFamilyProperties()[queueFamily_].timestampValidBits;

  float priority = 1.0f;
  vk::DeviceQueueCreateInfo queueInfo({}, queueFamily_, 1, &priority);
  vk::PhysicalDeviceFeatures features;
  // Double precision is used only by the float64 reference kernel, where the device has it.
  float64Enabled_ = info_.shaderFloat64;
  features.shaderFloat64 = float64Enabled_ ? VK_TRUE : VK_FALSE;
  // The viewer's resolve pass writes the swapchain image (any format) directly where this exists.
  features.shaderStorageImageWriteWithoutFormat = info_.storageImageWriteWithoutFormat ? VK_TRUE : VK_FALSE;
  std::vector<const char*> extensions;
  for (const auto& e : options.deviceExtensions) extensions.push_back(e.c_str());
  hostImport_ = options.hostPages && info_.hostImportAlignment != 0;
  if (hostImport_) extensions.push_back(VK_EXT_EXTERNAL_MEMORY_HOST_EXTENSION_NAME);
  vk::DeviceCreateInfo deviceInfo({}, queueInfo, {}, extensions, &features);
  device_ = vulkanStep("creating the logical device", [&] { return vk::raii::Device(physicalDevice_, deviceInfo); });
  queue_ = vulkanStep("getting the queue", [&] { return device_.getQueue(queueFamily_, 0); });
  commandPool_ = vulkanStep("creating the command pool", [&] {
    return vk::raii::CommandPool(
        device_, vk::CommandPoolCreateInfo(vk::CommandPoolCreateFlagBits::eResetCommandBuffer, queueFamily_));
  });
}

Context::~Context() {
  // Let in-flight work finish before members are destroyed; errors here cannot be reported.
  if (*device_) {
    try {
      device_.waitIdle();
    } catch (...) {
    }
  }
}

void Context::submitAndWait(std::string_view step,
                            const std::function<void(const vk::raii::CommandBuffer&)>& record) const {
  vulkanStep(step, [&] {
    vk::raii::CommandBuffers buffers(device_,
                                     vk::CommandBufferAllocateInfo(*commandPool_, vk::CommandBufferLevel::ePrimary, 1));
    const vk::raii::CommandBuffer& cmd = buffers.front();
    cmd.begin(vk::CommandBufferBeginInfo(vk::CommandBufferUsageFlagBits::eOneTimeSubmit));
    record(cmd);
    cmd.end();
    vk::raii::Fence fence(device_, vk::FenceCreateInfo());
    vk::CommandBuffer handle = *cmd;
    queue_.submit(vk::SubmitInfo({}, {}, handle), *fence);
    // Wait without a timeout limit but in slices, so a hang shows as a hang, not a busy loop.
    for (int waited = 1; device_.waitForFences(*fence, VK_TRUE, 1'000'000'000ull) == vk::Result::eTimeout; ++waited) {
      if (stepLogEnabled()) {
        std::fprintf(stderr, "vkray [%8.3f s] %.*s: still waiting for the device after %d s\n", stepClockS(),
                     static_cast<int>(step.size()), step.data(), waited);
      }
    }
  });
}

std::vector<DeviceInfo> Context::listDevices() {
  vk::raii::Context context;
  ContextOptions options;
  vk::raii::Instance instance = createInstance(context, options, nullptr, false);
  vk::raii::PhysicalDevices devices(instance);
  std::vector<DeviceInfo> out;
  for (std::uint32_t i = 0; i < devices.size(); ++i) out.push_back(describe(devices[i], i));
  return out;
}

} // namespace vkray::vulkan
