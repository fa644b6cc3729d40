// Caps on what a scene may ask for. Each is checked where the value is read, with a message that
// states the cap; docs/scene-format.md lists them.
#pragma once

#include <cstddef>
#include <cstdint>

#include "../../shaders/shared/gpu_types.h"

namespace vkray {

inline constexpr long long kMaxImageSide = 16384;           // pixels, width and height
inline constexpr long long kMaxDepthLimit = 64;             // max_depth
inline constexpr long long kMaxSpp = 4096;                  // samples per pixel
inline constexpr double kMaxTimeLimitSeconds = 7 * 86400.0; // time_limit: a week
// photons per light (forward tracing): photon indices are 32-bit
inline constexpr long long kMaxPhotons = 4'000'000'000ll;
inline constexpr std::size_t kMaxPolygonVertices = 64;
inline constexpr std::size_t kMaxPrimitives = 1u << 24;
inline constexpr std::size_t kMaxMaterialCount = gpu::kMaxMaterials;
// Coordinates and radii, in magnitude. The kernel squares lengths in float32 (|f|^2 - r^2 in the
// sphere test, edge cross products in the triangle test): with every coordinate and radius within
// 1e18, a squared distance between two points is at most 12e36, inside float32's 3.4e38.
inline constexpr double kMaxCoordinate = 1e18;

} // namespace vkray
