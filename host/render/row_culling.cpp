// See row_culling.h.
#include "render/row_culling.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace vkray {

namespace {

// Relative margin of every sign decision: float rounding in the kernel is ~1e-7 relative, and the
// pixel of margin around the row is worth ~1e-3 of the direction.
constexpr double kMargin = 1e-5;

} // namespace

CullScene makeCullScene(const GpuScene& g, const CameraFrame& camera) {
  CullScene s;
  s.camera = camera;
  s.camera.position = camera.position - g.origin;
  s.bounds = g.bounds;
  for (const gpu::Plane& p : g.planes) s.planes.emplace_back(glm::dvec4(p.normalOffset));
  return s;
}

bool rowsSeeNothing(const CullScene& scene, std::uint32_t width, std::uint32_t height, std::uint32_t row0,
                    std::uint32_t rows) {
  const CameraFrame& cam = scene.camera;
  const glm::dvec3 o = cam.position;
  // The pyramid's four edges, one pixel outside the rows' pixels on every side, in order around it.
  const double x0 = -1.0;
  const double x1 = static_cast<double>(width) + 1.0;
  const double y0 = static_cast<double>(row0) - 1.0;
  const double y1 = static_cast<double>(row0) + static_cast<double>(rows) + 1.0;
  const std::array<glm::dvec3, 4> d = {cam.rayDirection(x0, y0, width, height), cam.rayDirection(x1, y0, width, height),
                                       cam.rayDirection(x1, y1, width, height),
                                       cam.rayDirection(x0, y1, width, height)};
  for (const glm::dvec3& e : d) {
    if (!std::isfinite(e.x) || !std::isfinite(e.y) || !std::isfinite(e.z)) return false;
  }

  // Planes: seen from the side the eye is on, a ray meets the plane iff it heads towards it; n.d is
  // linear in d, so over the pyramid it is extreme at an edge.
  for (const glm::dvec4& p : scene.planes) {
    const glm::dvec3 n(p);
    const double side = glm::dot(n, o) + p.w;
    if (std::abs(side) <= kMargin * (glm::length(o) + std::abs(p.w) + 1e-30)) return false; // eye (almost) on it
    for (const glm::dvec3& e : d) {
      const double towards = -std::copysign(1.0, side) * glm::dot(n, e); // > 0: heading to the plane
      if (towards > -kMargin * glm::length(e)) return false;
    }
  }

  // Bounded primitives: the box is outside the pyramid when all its corners are outside one of the
  // pyramid's side planes (through the eye and two adjacent edges).
  const Aabb& b = scene.bounds;
  if (b.empty()) return true;
  std::array<glm::dvec3, 8> corners;
  for (int i = 0; i < 8; ++i) {
    corners[i] = glm::dvec3((i & 1) ? b.max.x : b.min.x, (i & 2) ? b.max.y : b.min.y, (i & 4) ? b.max.z : b.min.z);
  }
  for (int k = 0; k < 4; ++k) {
    glm::dvec3 m = glm::cross(d[k], d[(k + 1) % 4]);
    const glm::dvec3& other = d[(k + 2) % 4];
    if (glm::dot(m, other) < 0.0) m = -m; // inward
    const double mLen = glm::length(m);
    if (!(mLen > 0.0)) continue;
    bool allOutside = true;
    for (const glm::dvec3& c : corners) {
      const glm::dvec3 v = c - o;
      if (!(glm::dot(m, v) < -kMargin * mLen * glm::length(v))) {
        allOutside = false;
        break;
      }
    }
    if (allOutside) return true;
  }
  return false;
}

std::vector<RowRun> splitRows(const CullScene& scene, std::uint32_t width, std::uint32_t height, std::uint32_t row0,
                              std::uint32_t rows, std::uint32_t step) {
  std::vector<RowRun> runs;
  for (std::uint32_t y = row0; y < row0 + rows; y += step) {
    const std::uint32_t n = std::min(step, row0 + rows - y);
    const bool empty = rowsSeeNothing(scene, width, height, y, n);
    if (!runs.empty() && runs.back().empty == empty) {
      runs.back().rows += n;
    } else {
      runs.push_back({y, n, empty});
    }
  }
  return runs;
}

} // namespace vkray
