// The subcommands of the vkray executable. Each returns the process exit code; errors propagate as
// vkray::Error to main(), which prints them as one line.
#pragma once

#include <filesystem>
#include <optional>
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
  KernelFlags kernel;
  double bandMs = 100.0;
  std::optional<int> frame;            // --frame N
  std::string frames;                  // --frames A-B
  std::string tile;                    // --tile I/N
  bool exrHalf = false;                // --exr-half
  std::optional<std::string> aov;      // --aov LIST|all (render/aov.h)
  std::optional<std::string> inspect;  // --inspect X,Y (render/ray_tree.h)
  std::filesystem::path inspectOutput; // --inspect-out FILE (default: standard output)
};

struct MergeArgs {
  std::filesystem::path output;
  bool exrHalf = false; // --exr-half
  std::vector<std::filesystem::path> tiles;
};

int runRender(const RenderArgs& args);
int runMerge(const MergeArgs& args);
int runInfo(const DeviceFlags& device);

} // namespace vkray
