// Shadow entry points: where a shadow ray from a triangle to a point light starts its BVH walk.
//
// A shadow ray leaves a point of triangle T for light P, so every point of it lies in the
// tetrahedron hull(T, P). Only subtrees whose boxes meet that hull can hold an occluder: for most
// triangles of a mesh a small subtree around T itself plus whatever stands between it and the
// light. The table gives each (triangle, light) up to gpu::kShadowEntryMax such subtrees, and the
// kernel starts the ray's walk from them instead of descending from the root (shaders/lib/bvh.glsl,
// traverseBvh): the idea of Haines and Greenberg's light buffer (1986), on a BVH. The walk finds
// the same occluders: a box that does not meet the hull, widened by a margin far above the rounding
// of the shadow ray's origin and of the kernel's tests, holds nothing the ray can hit.
//
// The table is built top down, one light at a time: each node's entries are its parent's, refined
// for a region that holds the hull of the node's box and the light (slabs on the coordinate axes
// and on the three axes across the box-to-light direction). A subtree of at most `shareBelow`
// leaves hands its entries to every triangle in it; with shareBelow 0 every triangle refines its
// own for its exact hull(T, P). docs/performance.md ("Shadow entry points per triangle and light")
// measures what each choice keeps of the saving and what it costs to build.
//
// Nothing between: where no primitive of the tree but T's own neighbours meets hull(T, P), and
// none of those can stop a ray from a point of T to P (it lies behind T's plane, or T faces P
// across its plane, or a plane through a shared vertex separates it from the hull; exact
// orientation signs), the pair holds a mark instead of entries and the kernel skips the walk:
// the same answer, no steps. Looking for them costs about six times the entries' build; the
// renderer asks for them where the render's shadow rays pay for that (docs/meshes.md, "Nothing
// between").
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "../../shaders/shared/gpu_types.h"
#include "accel/bvh.h"

namespace vkray {

struct ShadowEntryOptions {
  // A subtree of at most this many leaves gives all its triangles the same entries; 0: each
  // triangle its own, refined for its exact hull (the most saved on the walk, the dearest build).
  std::uint32_t shareBelow = 8;
  // Mark the (triangle, light) pairs whose shadow rays nothing in the tree can stop, so that the
  // kernel skips their walk (see "Nothing between" above).
  bool nothingBetween = true;
  int threads = 0; // worker threads; 0: std::thread::hardware_concurrency()
};

// The shader's BVH (GpuScene::bvhNodes, wideBvh) and what the table is built for.
struct ShadowEntryInput {
  const std::vector<gpu::BvhWideNode>& nodes;
  std::uint32_t root;                         // the root's reference
  Aabb rootBox;                               // the root's box
  const std::vector<std::uint32_t>& primRefs; // leaf entries: kind << kPrimKindShift | index
  const std::vector<gpu::Triangle>& triangles;
  const std::vector<glm::dvec3>& lights; // point lights in the triangles' frame
  const std::vector<bool>& casts;        // per light: whether it casts shadows (else no entries for it)
};

// Two texels per (triangle, light), triangle-major: (start, stack 0, 1, 2) and (stack 3, 4, 5,
// stack height), the stack's bottom first, kBvhNoRef where unused (gpu::ShadowStart). A triangle
// no leaf refers to, and a light that casts no shadows, keep (kBvhNoRef, ...): from the root.
std::vector<glm::uvec4> shadowEntryTable(const ShadowEntryInput& in, const ShadowEntryOptions& options = {});

// The subtrees (references) a table entry names: the start and the stacked ones.
std::vector<std::uint32_t> shadowEntryRefs(const glm::uvec4& a, const glm::uvec4& b);

// The relative margin the hull is widened by: the shadow ray's origin lies within its hit point's
// rounding error (plus one offset) of the triangle, and the kernel's float tests round at about
// 1e-7 of the coordinates; 2^-13 leaves three orders of magnitude above both.
constexpr double kShadowEntryMargin = 1.0 / 8192.0;

} // namespace vkray
