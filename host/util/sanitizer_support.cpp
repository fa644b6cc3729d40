// Sanitizer builds only (VKRAY_SANITIZE): keeps the Vulkan driver and layers that the loader
// dlopen()s mapped until exit. The loader dlclose()s them when an instance is destroyed; a leak
// inside one is then reported by LeakSanitizer with "<unknown module>" instead of the library's
// name, and tools/lsan-suppressions.txt (which names Mesa's and the layer's libraries) cannot match
// it. Loading each once more with RTLD_NODELETE here means the loader's dlclose() never unmaps it.
#include <dlfcn.h>

#include <initializer_list>

namespace {

struct PinVulkanLibraries {
  PinVulkanLibraries() {
    for (const char* name :
         {"libvulkan_lvp.so", "libVkLayer_khronos_validation.so", "libVkLayer_MESA_device_select.so"}) {
      ::dlopen(name, RTLD_NOW | RTLD_NODELETE); // absent libraries are fine: nothing to pin
    }
  }
} gPinVulkanLibraries;

} // namespace
