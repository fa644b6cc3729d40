// An independent double-precision Whitted tracer on the host: the expectation GPU images are
// checked against. Same shading model as docs/scene-format.md, written from the formulas, not from
// the shader: closest hit over all surfaces, Phong with shadow rays, mirror reflection, dielectric
// reflection/refraction with exact Fresnel and a stack of media.
#pragma once

#include <limits>
#include <optional>
#include <vector>

#include <glm/glm.hpp>

#include "image/image.h"
#include "scene/scene.h"

namespace vkray::test {

struct RefHit {
  double t = std::numeric_limits<double>::infinity();
  int kind = -1; // 0 sphere, 1 plane, 2 polygon, 3 triangle
  std::size_t index = 0;
  glm::dvec3 p{0.0};
  glm::dvec3 n{0.0}; // geometric normal as stored (outward for spheres)
  std::uint32_t material = 0;
  bool hit() const { return kind >= 0; }
};

class ReferenceTracer {
public:
  explicit ReferenceTracer(const Scene& scene);

  // Closest hit with t in (tMin, tMax).
  RefHit closestHit(const glm::dvec3& o, const glm::dvec3& d, double tMin = 1e-9,
                    double tMax = std::numeric_limits<double>::infinity()) const;

  // Eye ray through image point (px, py) in pixels (y down).
  glm::dvec3 eyeDirection(double px, double py) const;
  glm::dvec3 eyeOrigin() const { return scene_.camera.position; }

  // Local (Phong) colour at a hit seen along d: ambient + lights with shadow rays.
  glm::dvec3 localShade(const RefHit& h, const glm::dvec3& d) const;

  // Full Whitted radiance of a ray.
  glm::dvec3 radiance(const glm::dvec3& o, const glm::dvec3& d) const;

  Image render() const; // pixel centres, 1 sample

  const Scene& scene() const { return scene_; }

private:
  glm::dvec3 trace(const glm::dvec3& o, const glm::dvec3& d, int depth, glm::dvec3 weight,
                   std::vector<std::uint32_t> media) const;
  glm::dvec3 shadowTransmittance(const glm::dvec3& p, const glm::dvec3& light) const;
  glm::dvec3 baseColor(const RefHit& h) const;

  Scene scene_;
};

} // namespace vkray::test
