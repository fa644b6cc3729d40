// An independent double-precision Whitted tracer on the host: the expectation GPU images are
// checked against. Same shading model as docs/scene-format.md, written from the formulas, not from
// the shader: closest hit over all surfaces, Phong with shadow rays, mirror reflection, dielectric
// reflection/refraction with exact Fresnel and a stack of media.
#pragma once

#include <limits>
#include <optional>
#include <string>
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

// One ray of a Whitted tree as the reference traces it (the inspector's test, ray_tree_test.cpp).
// path names it from the eye: "eye", "eye/T" (refracted), "eye/T/R" (then reflected), "eye/L1"
// (the shadow ray to light 1).
struct RefTreeRay {
  std::string path;
  int kind = 0;        // 0 eye, 1 reflection, 2 refraction, 3 shadow (gpu::kTree*)
  int outcome = 0;     // gpu::kTree* outcomes: miss, surface, light reached, blocked, unshadowed
  int objectKind = -1; // the surface met or the blocker, as RefHit::kind; -1: none
  std::size_t objectIndex = 0;
  glm::dvec3 contribution{0.0}; // what this ray's shading adds to the radiance
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
  // The same, recording every ray of the tree.
  glm::dvec3 radiance(const glm::dvec3& o, const glm::dvec3& d, std::vector<RefTreeRay>& tree) const;

  Image render() const; // pixel centres, 1 sample

  const Scene& scene() const { return scene_; }

private:
  // tree: where to record the rays (null: not recorded); path: this ray's name there.
  glm::dvec3 trace(const glm::dvec3& o, const glm::dvec3& d, int depth, glm::dvec3 weight,
                   std::vector<std::uint32_t> media, std::vector<RefTreeRay>* tree = nullptr,
                   const std::string& path = "eye", int kind = 0) const;
  // localShade, with each light's shadow ray recorded under `path` when tree is set.
  glm::dvec3 shade(const RefHit& h, const glm::dvec3& d, const glm::dvec3& weight, std::vector<RefTreeRay>* tree,
                   const std::string& path) const;
  // blocker: the opaque surface that stopped the ray, if any.
  glm::dvec3 shadowTransmittance(const glm::dvec3& p, const glm::dvec3& light, RefHit* blocker = nullptr) const;
  glm::dvec3 baseColor(const RefHit& h) const;

  Scene scene_;
};

} // namespace vkray::test
