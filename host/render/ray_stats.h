// The ray counters as the host reads them: one field per entry of VKRAY_RAY_COUNTERS (the single
// list, in shaders/shared/gpu_types.h), their copy from the GPU, their sums and their names.
#pragma once

#include <cstdint>
#include <string_view>
#include <utility>
#include <vector>

#include "../../shaders/shared/gpu_types.h"

namespace vkray {

struct RayStats {
#define VKRAY_HOST_COUNTER_FIELD(host, gpu, label, combine) std::uint64_t host = 0;
  VKRAY_RAY_COUNTERS(VKRAY_HOST_COUNTER_FIELD)
#undef VKRAY_HOST_COUNTER_FIELD

  // Rays traced: eye, shadow, reflection and refraction.
  std::uint64_t total() const {
    return eye + shadow + reflection + refraction;
  }
  // Counts of several dispatches: sums, and the maximum for maxima (the deepest bounce).
  RayStats& operator+=(const RayStats& o);
  static RayStats fromGpu(const gpu::RayStats& raw);
  // The average of `frames` frames' counts: sums divided, maxima kept.
  RayStats perFrame(std::uint64_t frames) const;
  // Every counter as (name, value), in the list's order: the --stats lines and the overlay's rows.
  std::vector<std::pair<std::string_view, std::uint64_t>> named() const;
};

} // namespace vkray
