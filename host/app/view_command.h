// `vkray view`: its command-line arguments and how they become ViewerOptions (view_command.cpp).
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "app/cli_options.h"

namespace vkray {

struct ViewArgs {
  std::filesystem::path scene;
  DeviceFlags device;
  RenderFlags render;
  ModelFlags model;
  bool noVsync = false;
  std::string inspect; // --inspect X,Y
  bool noOverlay = false;
  bool noRayCounts = false;
  KernelFlags kernel;
  bool noDirectResolve = false;
  bool stats = false;
  std::uint32_t frames = 0;
  std::filesystem::path screenshot;
  std::uint32_t maxSamples = 4096;
  double scale = 1.0;
  std::optional<double> motionScale;
  double spin = 0.0;
  std::string resizeTo; // WxH
  std::filesystem::path windowScreenshot;
  std::string display = "image"; // image | error | cost
};

struct BenchViewArgs {
  std::vector<std::filesystem::path> scenes;
  DeviceFlags device;
  RenderFlags render;
  std::uint32_t frames = 40; // timed frames per row, after the warm-up
  double spin = 2.0;         // degrees per frame in the moving rows
  KernelFlags kernel;
};

// Registers the `view` subcommand's options on `app`, writing into `args`.
CLI::App* addViewCommand(CLI::App& app, ViewArgs& args);
int runView(const ViewArgs& args);

// `vkray bench view`: scripted viewer runs, still and moving, with and without counters and
// overlay; fps and where a frame's time goes, one row per run.
CLI::App* addBenchViewCommand(CLI::App& bench, BenchViewArgs& args);
int runBenchView(const BenchViewArgs& args);

} // namespace vkray
