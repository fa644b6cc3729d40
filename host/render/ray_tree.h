// The ray-tree inspector: the rays the trace kernel traced for one pixel (recorded on the GPU with
// kSpecRecordTree, shaders/lib/tree_record.glsl), turned back into world space and the scene's own
// objects and lights, and written as JSON (`vkray render --inspect X,Y`, docs/ray-tree.md). The
// viewer draws the same tree.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "../../shaders/shared/gpu_types.h"
#include "render/gpu_scene.h"
#include "scene/scene.h"
#include "util/enum_names.h"

namespace vkray {

enum class TreeRayKind { Eye, Reflection, Refraction, Shadow };
template <> struct EnumNames<TreeRayKind> {
  static constexpr std::array<EnumName<TreeRayKind>, 4> values{{{TreeRayKind::Eye, "eye"},
                                                                {TreeRayKind::Reflection, "reflection"},
                                                                {TreeRayKind::Refraction, "refraction"},
                                                                {TreeRayKind::Shadow, "shadow"}}};
};

// What a ray met (gpu::kTree* outcomes).
enum class TreeOutcome { Background, Surface, Light, Blocked, Unshadowed };
template <> struct EnumNames<TreeOutcome> {
  static constexpr std::array<EnumName<TreeOutcome>, 5> values{{{TreeOutcome::Background, "background"},
                                                                {TreeOutcome::Surface, "surface"},
                                                                {TreeOutcome::Light, "light"},
                                                                {TreeOutcome::Blocked, "blocked"},
                                                                {TreeOutcome::Unshadowed, "unshadowed"}}};
};

// A primitive of the scene: its kind and index in the Scene's array of that kind.
struct TreeObject {
  ObjectKind kind = ObjectKind::Sphere; // Sphere, Plane, Polygon or Triangle
  std::size_t index = 0;
  bool operator==(const TreeObject&) const = default;
};

struct InspectedRay {
  TreeRayKind kind = TreeRayKind::Eye;
  TreeOutcome outcome = TreeOutcome::Background;
  std::optional<std::size_t> parent; // index into RayTree::rays
  std::uint32_t sample = 0;          // the pixel's sample this ray belongs to
  std::uint32_t depth = 0;           // bounces from the eye (shadow rays: their parent's)
  glm::dvec3 origin{0.0};            // world space
  glm::dvec3 direction{0.0};         // unit
  glm::dvec3 weight{0.0};
  glm::dvec3 contribution{0.0};     // linear RGB this ray's shading adds to the pixel (1/samples included)
  double distance = 0.0;            // to the point met (0 for the background)
  glm::dvec3 point{0.0};            // the surface point, the light's position or the blocker's point
  std::optional<TreeObject> object; // the surface met, or the blocker
  std::uint32_t material = 0;       // of the surface met
  std::optional<std::size_t> light; // shadow rays
  std::uint32_t cuts = 0;           // gpu::kTreeCut* bits: branches of this surface not traced
};

struct RayTree {
  glm::uvec2 pixel{0};
  std::uint32_t samples = 0;
  glm::dvec3 value{0.0}; // the pixel's linear RGB as the kernel computed it (mean of its samples)
  std::vector<InspectedRay> rays;
  std::uint32_t notRecorded = 0;   // rays beyond the record buffer's capacity
  bool stoppedAtRayBudget = false; // a tree ran into gpu::kMaxTreeRays
  std::uint32_t maxDepth = 0;      // the scene's max_depth, to tell the cap from a proven bailout
  glm::dvec3 contributionSum() const;
};

// The recorded rays (header and records as the kernel wrote them) in world space and the scene's
// terms. value: the pixel's sums (rgb, samples) from the same dispatch.
RayTree rayTreeFromRecords(const gpu::TreeRayHeader& header, const std::vector<gpu::TreeRay>& records,
                           const GpuScene& packed, glm::uvec2 pixel, const glm::vec4& sums, std::uint32_t maxDepth);

// The tree as JSON (one document, documented in docs/ray-tree.md): pixel, samples, value,
// contribution sum, and a `rays` array.
std::string rayTreeJson(const RayTree& tree, const Scene& scene);

// "X,Y" of `--inspect`: two non-negative integers inside a width x height image; InputError at
// `flag` otherwise.
glm::uvec2 parsePixel(const std::string& text, std::uint32_t width, std::uint32_t height, const std::string& flag);

} // namespace vkray
