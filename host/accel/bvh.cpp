// Binned SAH build, emitting nodes directly in the flattened depth-first order.
#include "accel/bvh.h"

#include <algorithm>
#include <array>
#include <chrono>

namespace vkray {

namespace {

struct Builder {
  std::vector<BvhPrimitive>& prims;
  std::vector<glm::vec3> centroids;
  const BvhOptions& options;
  Bvh& out;

  // Builds the subtree of prims[begin, end) at node index `self` (already allocated).
  void build(std::uint32_t self, std::size_t begin, std::size_t end, int depth) {
    Aabb bounds;
    Aabb centroidBounds;
    for (std::size_t i = begin; i < end; ++i) {
      bounds.grow(prims[i].bounds);
      centroidBounds.grow(centroids[i]);
    }
    out.stats.depth = std::max(out.stats.depth, depth);
    std::size_t count = end - begin;

    int axis = -1;
    std::size_t mid = begin;
    float leafCost = static_cast<float>(count);
    bool forcedLeaf = depth >= options.maxDepth;
    if (count > 1 && !forcedLeaf) {
      glm::vec3 extent = centroidBounds.max - centroidBounds.min;
      float bestCost = std::numeric_limits<float>::infinity();
      int bestAxis = -1;
      int bestSplit = 0;
      const int nb = options.bins;
      for (int a = 0; a < 3; ++a) {
        if (!(extent[a] > 0.0f)) continue;
        std::array<Aabb, 64> binBounds{};
        std::array<std::size_t, 64> binCount{};
        float scale = static_cast<float>(nb) / extent[a];
        for (std::size_t i = begin; i < end; ++i) {
          int b = std::min(nb - 1, static_cast<int>((centroids[i][a] - centroidBounds.min[a]) * scale));
          binBounds[static_cast<std::size_t>(b)].grow(prims[i].bounds);
          ++binCount[static_cast<std::size_t>(b)];
        }
        // Sweep from the right to get suffix areas, then from the left for the costs.
        std::array<float, 64> rightArea{};
        std::array<std::size_t, 64> rightCount{};
        Aabb acc;
        std::size_t n = 0;
        for (int b = nb - 1; b > 0; --b) {
          acc.grow(binBounds[static_cast<std::size_t>(b)]);
          n += binCount[static_cast<std::size_t>(b)];
          rightArea[static_cast<std::size_t>(b)] = acc.surfaceArea();
          rightCount[static_cast<std::size_t>(b)] = n;
        }
        Aabb left;
        std::size_t leftN = 0;
        for (int b = 0; b < nb - 1; ++b) {
          left.grow(binBounds[static_cast<std::size_t>(b)]);
          leftN += binCount[static_cast<std::size_t>(b)];
          std::size_t rightN = rightCount[static_cast<std::size_t>(b + 1)];
          if (leftN == 0 || rightN == 0) continue;
          float cost = left.surfaceArea() * static_cast<float>(leftN) +
                       rightArea[static_cast<std::size_t>(b + 1)] * static_cast<float>(rightN);
          if (cost < bestCost) {
            bestCost = cost;
            bestAxis = a;
            bestSplit = b;
          }
        }
      }
      float area = bounds.surfaceArea();
      float splitCost = area > 0.0f ? options.traversalCost + bestCost / area : std::numeric_limits<float>::infinity();
      bool tooBig = count > static_cast<std::size_t>(options.maxLeafSize);
      if (bestAxis >= 0 && (splitCost < leafCost || tooBig)) {
        axis = bestAxis;
        float scale = static_cast<float>(nb) / extent[axis];
        float minC = centroidBounds.min[axis];
        auto it = std::partition(prims.begin() + static_cast<std::ptrdiff_t>(begin),
                                 prims.begin() + static_cast<std::ptrdiff_t>(end), [&](const BvhPrimitive& p) {
                                   float c = p.bounds.center()[axis];
                                   return std::min(nb - 1, static_cast<int>((c - minC) * scale)) <= bestSplit;
                                 });
        mid = static_cast<std::size_t>(it - prims.begin());
        // Centroids must follow their primitives.
        for (std::size_t i = begin; i < end; ++i) centroids[i] = prims[i].bounds.center();
      } else if (tooBig) {
        // All centroids coincide (or no split separates them): split the range in half. The
        // children overlap, but the tree stays shallow and every primitive stays reachable.
        axis = 0;
        mid = begin + count / 2;
      }
    }
    // Leaves hold at most 0xFFFF references (16-bit count); a forced leaf beyond that splits anyway.
    if (axis < 0 && count > 0xFFFF) {
      axis = 0;
      mid = begin + count / 2;
    }

    gpu::BvhNode& node = out.nodes[self];
    node.boundsMin = bounds.min;
    node.boundsMax = bounds.max;
    if (axis < 0 || mid == begin || mid == end) {
      node.offset = static_cast<std::uint32_t>(out.primRefs.size());
      node.countAxis = static_cast<std::uint32_t>(count);
      for (std::size_t i = begin; i < end; ++i) out.primRefs.push_back(prims[i].ref);
      ++out.stats.leaves;
      out.stats.maxLeafSize = std::max(out.stats.maxLeafSize, count);
      return;
    }
    // First child directly after this node; the second wherever the first subtree ends.
    std::uint32_t firstChild = static_cast<std::uint32_t>(out.nodes.size());
    out.nodes.emplace_back();
    build(firstChild, begin, mid, depth + 1);
    std::uint32_t secondChild = static_cast<std::uint32_t>(out.nodes.size());
    out.nodes.emplace_back();
    build(secondChild, mid, end, depth + 1);
    gpu::BvhNode& parent = out.nodes[self]; // re-fetch: the vector may have grown
    parent.offset = secondChild;
    parent.countAxis = static_cast<std::uint32_t>(axis) << 16;
  }
};

// SAH cost of the finished tree, in primitive tests per ray (for --stats).
double sahCost(const Bvh& bvh, const BvhOptions& options) {
  if (bvh.nodes.empty()) return 0.0;
  double rootArea = nodeBounds(bvh.nodes[0]).surfaceArea();
  if (rootArea <= 0.0) return static_cast<double>(bvh.primRefs.size());
  double cost = 0.0;
  for (const auto& n : bvh.nodes) {
    double p = nodeBounds(n).surfaceArea() / rootArea;
    cost += p * (nodeCount(n) > 0 ? static_cast<double>(nodeCount(n)) : options.traversalCost);
  }
  return cost;
}

} // namespace

Bvh buildBvh(std::vector<BvhPrimitive> primitives, const BvhOptions& options) {
  auto start = std::chrono::steady_clock::now();
  Bvh bvh;
  if (!primitives.empty()) {
    bvh.nodes.reserve(2 * primitives.size());
    bvh.primRefs.reserve(primitives.size());
    Builder builder{primitives, {}, options, bvh};
    builder.centroids.reserve(primitives.size());
    for (const auto& p : primitives) builder.centroids.push_back(p.bounds.center());
    bvh.nodes.emplace_back();
    builder.build(0, 0, primitives.size(), 1);
  }
  bvh.stats.nodes = bvh.nodes.size();
  bvh.stats.sahCost = sahCost(bvh, options);
  bvh.stats.buildMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return bvh;
}

} // namespace vkray
