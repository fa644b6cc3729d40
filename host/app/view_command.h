// `vkray view`: its command-line arguments and how they become ViewerOptions (view_command.cpp).
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

#include <CLI/CLI.hpp>

#include "app/cli_options.h"

namespace vkray {

struct ViewArgs {
  std::filesystem::path scene;
  DeviceFlags device;
  RenderFlags render;
  bool noVsync = false;
  bool noOverlay = false;
  bool noRayCounts = false;
  bool noSpecialize = false;
  bool stats = false;
  std::uint32_t frames = 0;
  std::filesystem::path screenshot;
  std::uint32_t maxSamples = 4096;
  double scale = 1.0;
  std::optional<double> motionScale;
  double spin = 0.0;
  std::string resizeTo; // WxH
};

// Registers the `view` subcommand's options on `app`, writing into `args`.
CLI::App* addViewCommand(CLI::App& app, ViewArgs& args);
int runView(const ViewArgs& args);

} // namespace vkray
