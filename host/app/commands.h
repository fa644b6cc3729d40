// The subcommands of the vkray executable. Each returns the process exit code; errors propagate as
// vkray::Error to main(), which prints them as one line.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "app/cli_options.h"

namespace vkray {

struct RenderArgs {
  std::filesystem::path scene;
  std::filesystem::path output;
  DeviceFlags device;
  RenderFlags render;
  ModelFlags model;
  bool stats = false;
  bool explain = false;
  bool quiet = false;
  bool noSpecialize = false;
  bool noRowCulling = false;
  bool noEntryPoints = false;
  double bandMs = 100.0;
  std::string sceneMemory = "auto";
};

int runRender(const RenderArgs& args);
int runInfo(const DeviceFlags& device);

} // namespace vkray
