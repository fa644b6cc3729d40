// `vkray bench meshes`: ray throughput and BVH figures for procedural meshes of growing size, with
// Embree 3 on the same triangles and rays side by side when vkray was built with it.
#pragma once

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "app/bench.h"
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

// The shadow rays' time from the timed pairs: the median of each pair's difference (eye and shadow
// rays less eye rays alone), or 0 where that is noise: at or below zero, or, given three runs or
// more, no larger than half the range of the eye-only runs' times. The differences spread by about
// a millisecond on lavapipe; where the shadow rays cost less (the 1 k mesh with its "nothing
// between" marks, or a small image) the median says nothing about them. With one or two runs there
// is no spread to judge by. (Inline: the tests check it without the bench's Embree side.)
inline double resolvedShadowMs(const std::vector<double>& eyeMs, const std::vector<double>& pairMs) {
  double noise = 0.0;
  if (eyeMs.size() >= 3) {
    auto [least, largest] = std::minmax_element(eyeMs.begin(), eyeMs.end());
    noise = 0.5 * (*largest - *least);
  }
  const double shadowMs = median(pairMs);
  return shadowMs > noise ? shadowMs : 0.0;
}

// The benchmark's mesh: a bumpy torus of about `triangles` triangles around the origin (radius
// 1.3), no degenerate faces. Also used by tests.
MeshData proceduralTorus(std::size_t triangles);

} // namespace vkray
