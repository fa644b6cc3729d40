// Bounding volume hierarchy over the bounded primitives (spheres, triangles, polygons): built on
// the host with a binned surface-area heuristic (Wald 2007, "On fast Construction of SAH-based
// Bounding Volume Hierarchies"), flattened depth first for the shader (shaders/lib/bvh.glsl).
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "../../shaders/shared/gpu_types.h"

namespace vkray {

struct Aabb {
  glm::vec3 min{std::numeric_limits<float>::infinity()};
  glm::vec3 max{-std::numeric_limits<float>::infinity()};

  void grow(const glm::vec3& p) {
    min = glm::min(min, p);
    max = glm::max(max, p);
  }
  void grow(const Aabb& b) {
    min = glm::min(min, b.min);
    max = glm::max(max, b.max);
  }
  bool empty() const { return min.x > max.x; }
  glm::vec3 center() const { return 0.5f * (min + max); }
  float surfaceArea() const {
    if (empty()) return 0.0f;
    glm::vec3 d = max - min;
    return 2.0f * (d.x * d.y + d.y * d.z + d.z * d.x);
  }
  bool contains(const Aabb& b) const {
    return glm::all(glm::lessThanEqual(min, b.min)) && glm::all(glm::greaterThanEqual(max, b.max));
  }
};

struct BvhPrimitive {
  Aabb bounds;           // must be finite (buildBvh throws otherwise)
  std::uint32_t ref = 0; // kind << kPrimKindShift | index, as in PrimRefs[]
};

struct BvhOptions {
  int bins = 16;       // SAH candidate planes per axis + 1 (at most 32)
  int maxLeafSize = 4; // a leaf never holds more (the depth guard keeps this true)
  // The shader's traversal stack holds this many: traversal never overflows.
  int maxDepth = static_cast<int>(gpu::kBvhStackSize);
  float traversalCost = 1.0f; // SAH cost of visiting a node, relative to one primitive test
  int threads = 0;            // worker threads; 0: std::thread::hardware_concurrency()
};

struct BvhStats {
  double buildMs = 0.0;
  std::size_t primitives = 0;
  std::size_t nodes = 0;
  std::size_t leaves = 0;
  int depth = 0; // longest root-to-leaf path, in nodes
  std::size_t maxLeafSize = 0;
  double sahCost = 0.0; // expected cost of a random ray, in primitive tests
  int threads = 1;      // threads the build used
};

struct Bvh {
  std::vector<gpu::BvhNode> nodes;     // nodes[0] is the root; empty when there are no primitives
  std::vector<std::uint32_t> primRefs; // leaf ranges index this
  BvhStats stats;
};

// Builds the tree. Every primitive ends up in exactly one leaf; leaves hold at most
// options.maxLeafSize primitives and no leaf is deeper than options.maxDepth.
Bvh buildBvh(const std::vector<BvhPrimitive>& primitives, const BvhOptions& options = {});

// Structural check of a flattened tree against the primitives it was built from: every node's
// bounds contain its children's (and its primitives'), every reference appears exactly once, the
// depth and leaf sizes respect the options. Returns an empty string when all holds, else the first
// violation in words. Used by the tests; cheap enough for a debug assertion.
std::string checkBvh(const Bvh& bvh, const std::vector<BvhPrimitive>& primitives, const BvhOptions& options = {});

// The shader's layout of a flattened tree (gpu::BvhWideNode): one record per interior node, in the
// same depth-first order, with both children's boxes and references. Returns the root's reference
// (kBvhNoRef for an empty tree; a leaf reference for a one-leaf tree, which needs no record).
std::uint32_t wideBvh(const Bvh& bvh, std::vector<gpu::BvhWideNode>& out);

// Bounds of a node as the shader sees them.
inline Aabb nodeBounds(const gpu::BvhNode& n) {
  return Aabb{n.boundsMin, n.boundsMax};
}
inline std::uint32_t nodeCount(const gpu::BvhNode& n) {
  return n.countAxis & 0xFFFFu;
}
inline std::uint32_t nodeAxis(const gpu::BvhNode& n) {
  return (n.countAxis >> 16) & 3u;
}

} // namespace vkray
