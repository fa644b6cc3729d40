// How a command asks for its Vulkan context (the device flags every subcommand shares), and the one
// place those flags become ContextOptions.
#pragma once

#include <string>

#include "vk/context.h"

namespace vkray {

struct DeviceFlags {
  std::string device;        // --device: index or name substring; empty: the best device
  bool validate = false;     // --validate
  bool syncValidate = false; // --sync-validation
  bool noPipelineCache = false;
  bool noHugePages = false; // --no-huge-pages
};

// The context the flags ask for: device choice, validation, synchronization validation, host pages.
inline vulkan::ContextOptions contextOptions(const DeviceFlags& f) {
  vulkan::ContextOptions o;
  o.device = f.device;
  o.validation = f.validate;
  o.synchronizationValidation = f.syncValidate;
  o.hostPages = !f.noHugePages;
  return o;
}

} // namespace vkray
