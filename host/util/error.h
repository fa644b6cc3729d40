// The one way vkray reports failure: exceptions derived from vkray::Error, caught once in main(),
// printed as one line. Each kind says where (file, JSON path, Vulkan step) and what went wrong.
#pragma once

#include <stdexcept>
#include <string>

namespace vkray {

class Error : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
};

// Bad input: a scene, mesh or command-line value. The message reads
// "scene.json: objects[3].radius: must be > 0, got -1".
class InputError : public Error {
public:
  InputError(const std::string& where, const std::string& problem)
      : Error(where.empty() ? problem : where + ": " + problem) {}
};

// A Vulkan call failed: says which call, in which step, and the VkResult.
class DeviceError : public Error {
public:
  using Error::Error;
};

// VK_ERROR_DEVICE_LOST: the device stopped (a watchdog, a driver fault); names the tile.
class DeviceLostError : public DeviceError {
public:
  using DeviceError::DeviceError;
};

// The user interrupted a render (Ctrl-C between tiles).
class CancelledError : public Error {
public:
  using Error::Error;
};

} // namespace vkray
