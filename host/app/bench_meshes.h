// `vkray bench meshes`: ray throughput and BVH figures for procedural meshes of growing size, with
// Embree 3 on the same triangles and rays side by side when vkray was built with it.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "app/cli_options.h"
#include "scene/mesh_import.h"

namespace vkray {

struct BenchMeshesArgs {
  std::vector<std::size_t> sizes{1000, 10000, 100000, 1000000}; // triangles (approximately)
  std::uint32_t width = 800;
  std::uint32_t height = 600;
  int runs = 5;
  int rounds = 1; // repeats of every size, interleaved; ratios as median and range
  bool noEmbree = false;
  bool noEntryPoints = false;       // eye rays walk from the root (RenderOptions::entryPoints)
  bool noShadowEntryPoints = false; // shadow rays walk from the root (RenderOptions::shadowEntryPoints)
  bool noNothingBetween = false;    // the table's entry points alone (ShadowEntries::Entries)
  std::filesystem::path csv;        // also write the table here (for tools/plot-mesh-bench)
  DeviceFlags device;
};

int runBenchMeshes(const BenchMeshesArgs& args);

// The benchmark's mesh: a bumpy torus of about `triangles` triangles around the origin (radius
// 1.3), no degenerate faces. Also used by tests.
MeshData proceduralTorus(std::size_t triangles);

} // namespace vkray
