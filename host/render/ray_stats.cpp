// Ray counters on the host, generated from the one list (see ray_stats.h).
#include "render/ray_stats.h"

#include <algorithm>

namespace vkray {

namespace {
std::uint64_t combineSum(std::uint64_t a, std::uint64_t b) {
  return a + b;
}
std::uint64_t combineMax(std::uint64_t a, std::uint64_t b) {
  return std::max(a, b);
}
std::uint64_t averageSum(std::uint64_t v, std::uint64_t n) {
  return v / n;
}
std::uint64_t averageMax(std::uint64_t v, std::uint64_t) {
  return v;
}
} // namespace

RayStats& RayStats::operator+=(const RayStats& o) {
#define VKRAY_COMBINE(host, gpu, label, how) host = combine##how(host, o.host);
  VKRAY_RAY_COUNTERS(VKRAY_COMBINE)
#undef VKRAY_COMBINE
  return *this;
}

RayStats RayStats::fromGpu(const gpu::RayStats& raw) {
  RayStats s;
#define VKRAY_COPY(host, gpu, label, combine) s.host = raw.gpu;
  VKRAY_RAY_COUNTERS(VKRAY_COPY)
#undef VKRAY_COPY
  return s;
}

RayStats RayStats::perFrame(std::uint64_t frames) const {
  RayStats s;
  const std::uint64_t n = std::max<std::uint64_t>(frames, 1);
#define VKRAY_AVERAGE(host, gpu, label, how) s.host = average##how(host, n);
  VKRAY_RAY_COUNTERS(VKRAY_AVERAGE)
#undef VKRAY_AVERAGE
  return s;
}

std::vector<std::pair<std::string_view, std::uint64_t>> RayStats::named() const {
  std::vector<std::pair<std::string_view, std::uint64_t>> rows;
#define VKRAY_NAME(host, gpu, label, combine) rows.emplace_back(label, host);
  VKRAY_RAY_COUNTERS(VKRAY_NAME)
#undef VKRAY_NAME
  return rows;
}

} // namespace vkray
