// Binned SAH build (Wald 2007) into a temporary binary tree, in parallel over subtrees, then
// flattened depth first into the shader's node array (pbrt's LinearBVHNode order).
#include "accel/bvh.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <exception>
#include <memory>
#include <thread>

#include "util/error.h"

namespace vkray {

namespace {

constexpr int kMaxBins = 32;
// Subtrees smaller than this are never handed to another thread: starting one costs more.
constexpr std::size_t kParallelMinPrims = 8192;

// Four-wide float vectors (GCC/Clang vector extensions): a box grows with one min and one max
// instruction instead of six scalar ones, which is most of the work of binning.
typedef float V4 __attribute__((vector_size(16)));
typedef std::int32_t V4i __attribute__((vector_size(16)));
inline V4 vmin(V4 a, V4 b) {
  return a < b ? a : b;
}
inline V4 vmax(V4 a, V4 b) {
  return a > b ? a : b;
}
inline V4 splat(float x) {
  return V4{x, x, x, x};
}
inline V4 toV4(const glm::vec3& v) {
  return V4{v.x, v.y, v.z, 0.0f};
}
inline glm::vec3 toVec3(V4 v) {
  return glm::vec3(v[0], v[1], v[2]);
}

// Lane 3 of a box is never read (it carries the primitive's reference in Prim, garbage in boxes).
struct Box {
  V4 lo = splat(std::numeric_limits<float>::infinity());
  V4 hi = splat(-std::numeric_limits<float>::infinity());
  void grow(V4 l, V4 h) {
    lo = vmin(lo, l);
    hi = vmax(hi, h);
  }
  void grow(const Box& b) { grow(b.lo, b.hi); }
  float area() const {
    V4 d = hi - lo;
    if (!(d[0] >= 0.0f)) return 0.0f; // empty
    return 2.0f * (d[0] * d[1] + d[1] * d[2] + d[2] * d[0]);
  }
};

// A primitive as the builder moves it around: 32 bytes, the reference split into two 16-bit
// halves stored as small whole floats in lane 3. Not as raw bits: those would often be denormals,
// and arithmetic on a denormal lane costs a microcode assist per instruction on x86.
struct Prim {
  V4 lo;
  V4 hi;
  V4 centroid2() const { return lo + hi; } // twice the centre: binning is scale invariant
  std::uint32_t ref() const { return static_cast<std::uint32_t>(lo[3]) | static_cast<std::uint32_t>(hi[3]) << 16; }
  void setRef(std::uint32_t r) {
    lo[3] = static_cast<float>(r & 0xFFFFu);
    hi[3] = static_cast<float>(r >> 16);
  }
};

// Node of the temporary tree. Interior: children `a`, `b` (a is below the split plane). Leaf:
// primitives [a, a + b) of the permuted array. Trivially constructible, so the preallocated array
// costs no initialisation pass.
struct BuildNode {
  V4 lo;
  V4 hi;
  std::uint32_t a;
  std::uint32_t b;
  std::uint32_t axis;
  std::uint32_t leaf;
};

// A range of primitives with its bounds and the bounds of its (doubled) centroids.
struct Range {
  std::size_t begin = 0;
  std::size_t end = 0;
  Box bounds;
  Box centroids;
  std::size_t size() const { return end - begin; }
};

struct SubtreeStats {
  int depth = 0;
  std::size_t leaves = 0;
  std::size_t maxLeaf = 0;
  void add(const SubtreeStats& o) {
    depth = std::max(depth, o.depth);
    leaves += o.leaves;
    maxLeaf = std::max(maxLeaf, o.maxLeaf);
  }
};

// Threads that may run at once. A thread that waits for a child thread gives its slot back while
// it waits, so both cores stay busy even when a split is lopsided.
class ThreadBudget {
public:
  explicit ThreadBudget(int threads) : free_(threads - 1) {}
  bool tryAcquire() {
    int f = free_.load(std::memory_order_relaxed);
    while (f > 0) {
      if (free_.compare_exchange_weak(f, f - 1, std::memory_order_acq_rel)) return true;
    }
    return false;
  }
  void release() { free_.fetch_add(1, std::memory_order_acq_rel); }
  // Takes a slot back after a wait, even if that briefly over-commits: no thread spins for it.
  void reclaim() { free_.fetch_sub(1, std::memory_order_acq_rel); }

private:
  std::atomic<int> free_;
};

struct Builder {
  std::vector<Prim> prims;
  const BvhOptions& options;
  std::unique_ptr<BuildNode[]> nodes; // preallocated: a binary tree over n leaves has 2n - 1 nodes
  std::atomic<std::uint32_t> next{1}; // node 0 is the root
  ThreadBudget budget;
  std::atomic<int> threadsUsed{1};

  Builder(std::size_t count, const BvhOptions& o, int threads)
      : prims(count), options(o), nodes(new BuildNode[2 * count]), budget(threads) {}

  // Largest subtree that can still be split down to full leaves within the depth cap when it
  // starts at `depth` (object-median splits halve the count per level).
  std::size_t capacityAt(int depth) const {
    int levels = options.maxDepth - depth;
    if (levels >= 40) return std::numeric_limits<std::size_t>::max();
    if (levels < 0) return 0;
    return static_cast<std::size_t>(options.maxLeafSize) << levels;
  }

  SubtreeStats makeLeaf(std::uint32_t self, const Range& r, int depth) {
    BuildNode& n = nodes[self];
    n.lo = r.bounds.lo;
    n.hi = r.bounds.hi;
    n.leaf = 1;
    n.a = static_cast<std::uint32_t>(r.begin);
    n.b = static_cast<std::uint32_t>(r.size());
    return SubtreeStats{depth, 1, r.size()};
  }

  // Recomputes the bounds of [begin, end) (after a median split, which does not bin).
  Range measure(std::size_t begin, std::size_t end) const {
    Range r;
    r.begin = begin;
    r.end = end;
    for (std::size_t i = begin; i < end; ++i) {
      r.bounds.grow(prims[i].lo, prims[i].hi);
      V4 c = prims[i].centroid2();
      r.centroids.grow(c, c);
    }
    return r;
  }

  // Object median along the axis of largest centroid extent: halves the count whatever the
  // geometry, which bounds the depth (the fallback for coincident centroids and the depth cap).
  std::pair<Range, Range> medianSplit(const Range& r, int& axis) {
    V4 extent = r.centroids.hi - r.centroids.lo;
    axis = extent[0] >= extent[1] && extent[0] >= extent[2] ? 0 : (extent[1] >= extent[2] ? 1 : 2);
    std::size_t mid = r.begin + r.size() / 2;
    if (extent[axis] > 0.0f) {
      auto first = prims.begin() + static_cast<std::ptrdiff_t>(r.begin);
      const int a = axis;
      std::nth_element(first, prims.begin() + static_cast<std::ptrdiff_t>(mid),
                       prims.begin() + static_cast<std::ptrdiff_t>(r.end),
                       [a](const Prim& p, const Prim& q) { return p.centroid2()[a] < q.centroid2()[a]; });
    }
    return {measure(r.begin, mid), measure(mid, r.end)};
  }

  struct Split {
    int axis = -1;
    int bin = 0;       // primitives in bins <= bin go left
    int bins = 0;      // bins used at this node
    V4 scale{};        // bin = (centroid2 - centroids.lo) * scale, per axis
    float cost = 0.0f; // SAH cost relative to one primitive test
  };

  // Bins the centroids on all three axes in one pass and sweeps the SAH over the bin planes.
  // Small nodes use fewer bins: initialising and sweeping bins would cost more than the binning.
  Split findSplit(const Range& r) const {
    const std::size_t n = r.size();
    const int nb = static_cast<int>(std::min<std::size_t>(
        static_cast<std::size_t>(std::clamp(options.bins, 2, kMaxBins)), std::max<std::size_t>(n, 2)));
    Split best;
    best.bins = nb;
    V4 extent = r.centroids.hi - r.centroids.lo;
    for (int a = 0; a < 3; ++a) {
      // (1 - 2^-20) keeps the largest centroid in the last bin; a tiny extent would overflow.
      float s = static_cast<float>(nb) * (1.0f - 1.0f / 1048576.0f) / extent[a];
      best.scale[a] = extent[a] > 0.0f && std::isfinite(s) ? s : 0.0f;
    }
    best.scale[3] = 0.0f;
    // Plain arrays, initialised only as far as used (a Box array would construct all 96 bins).
    V4 binLo[3][kMaxBins];
    V4 binHi[3][kMaxBins];
    std::uint32_t counts[3][kMaxBins];
    const V4 inf = splat(std::numeric_limits<float>::infinity());
    for (int a = 0; a < 3; ++a) {
      for (int b = 0; b < nb; ++b) {
        binLo[a][b] = inf;
        binHi[a][b] = -inf;
        counts[a][b] = 0;
      }
    }
    const V4 cmin = r.centroids.lo;
    const V4 scale = best.scale;
    const V4i last = {nb - 1, nb - 1, nb - 1, nb - 1};
    for (std::size_t i = r.begin; i < r.end; ++i) {
      const Prim& p = prims[i];
      V4i b = __builtin_convertvector((p.centroid2() - cmin) * scale, V4i);
      b = b < last ? b : last;
      for (int a = 0; a < 3; ++a) {
        binLo[a][b[a]] = vmin(binLo[a][b[a]], p.lo);
        binHi[a][b[a]] = vmax(binHi[a][b[a]], p.hi);
        ++counts[a][b[a]];
      }
    }
    float bestCost = std::numeric_limits<float>::infinity();
    for (int a = 0; a < 3; ++a) {
      if (best.scale[a] == 0.0f) continue;
      float rightCost[kMaxBins];
      Box acc;
      std::uint32_t count = 0;
      for (int b = nb - 1; b > 0; --b) {
        acc.grow(binLo[a][b], binHi[a][b]);
        count += counts[a][b];
        rightCost[b] = count ? acc.area() * static_cast<float>(count) : -1.0f;
      }
      Box left;
      std::uint32_t leftCount = 0;
      for (int b = 0; b < nb - 1; ++b) {
        left.grow(binLo[a][b], binHi[a][b]);
        leftCount += counts[a][b];
        float rc = rightCost[b + 1];
        if (leftCount == 0 || rc < 0.0f) continue;
        float cost = left.area() * static_cast<float>(leftCount) + rc;
        if (cost < bestCost) {
          bestCost = cost;
          best.axis = a;
          best.bin = b;
        }
      }
    }
    float area = r.bounds.area();
    best.cost = area > 0.0f ? options.traversalCost + bestCost / area : std::numeric_limits<float>::infinity();
    return best;
  }

  // Partitions [begin, end) by bin on the split axis (the same arithmetic as the binning) and
  // measures both sides on the way.
  std::pair<Range, Range> partition(const Range& r, const Split& split) {
    const int axis = split.axis;
    const int last = split.bins - 1;
    auto isLeft = [&](const Prim& p) {
      V4 f = (p.centroid2() - r.centroids.lo) * split.scale;
      int b = static_cast<int>(f[axis]);
      return std::min(b, last) <= split.bin;
    };
    Range left;
    Range right;
    std::size_t i = r.begin;
    std::size_t j = r.end;
    auto growLeft = [&](const Prim& p) {
      left.bounds.grow(p.lo, p.hi);
      V4 c = p.centroid2();
      left.centroids.grow(c, c);
    };
    auto growRight = [&](const Prim& p) {
      right.bounds.grow(p.lo, p.hi);
      V4 c = p.centroid2();
      right.centroids.grow(c, c);
    };
    while (true) {
      while (i < j && isLeft(prims[i])) growLeft(prims[i++]);
      while (i < j && !isLeft(prims[j - 1])) growRight(prims[--j]);
      if (i >= j) break;
      std::swap(prims[i], prims[j - 1]);
      growLeft(prims[i++]);
      growRight(prims[--j]);
    }
    left.begin = r.begin;
    left.end = i;
    right.begin = i;
    right.end = r.end;
    return {left, right};
  }

  SubtreeStats build(std::uint32_t self, const Range& r, int depth) {
    const std::size_t n = r.size();
    if (n <= 1) return makeLeaf(self, r, depth);
    const auto maxLeaf = static_cast<std::size_t>(options.maxLeafSize);
    Split split = findSplit(r);
    const float leafCost = static_cast<float>(n);
    if (n <= maxLeaf && (split.axis < 0 || leafCost <= split.cost)) return makeLeaf(self, r, depth);

    int axis = split.axis;
    std::pair<Range, Range> children;
    const std::size_t childCapacity = capacityAt(depth + 1);
    bool sahOk = split.axis >= 0;
    if (sahOk) {
      children = partition(r, split);
      // A lopsided SAH split near the depth cap could leave a child that no longer fits: fall back
      // to the median, which always fits (the parent did). Same if rounding left a side empty.
      sahOk = children.first.size() > 0 && children.second.size() > 0 && children.first.size() <= childCapacity &&
              children.second.size() <= childCapacity;
    }
    if (!sahOk) children = medianSplit(r, axis);

    BuildNode& node = nodes[self];
    node.lo = r.bounds.lo;
    node.hi = r.bounds.hi;
    node.leaf = 0;
    node.axis = static_cast<std::uint32_t>(axis);
    const std::uint32_t first = next.fetch_add(2, std::memory_order_relaxed);
    node.a = first;
    node.b = first + 1;

    const bool firstIsBig = children.first.size() >= children.second.size();
    const Range& big = firstIsBig ? children.first : children.second;
    const Range& small = firstIsBig ? children.second : children.first;
    const std::uint32_t bigNode = firstIsBig ? first : first + 1;
    const std::uint32_t smallNode = firstIsBig ? first + 1 : first;
    if (small.size() >= kParallelMinPrims && budget.tryAcquire()) {
      // Another thread takes the smaller side; this one continues with the larger.
      threadsUsed.fetch_add(1, std::memory_order_relaxed);
      SubtreeStats other;
      std::exception_ptr error;
      std::thread worker([&] {
        try {
          other = build(smallNode, small, depth + 1);
        } catch (...) {
          error = std::current_exception();
        }
        budget.release();
      });
      SubtreeStats mine;
      try {
        mine = build(bigNode, big, depth + 1);
      } catch (...) {
        worker.join();
        throw;
      }
      // While waiting, this thread's slot is free for the worker's own subtrees.
      budget.release();
      worker.join();
      budget.reclaim();
      if (error) std::rethrow_exception(error);
      mine.add(other);
      return mine;
    }
    SubtreeStats stats = build(first, children.first, depth + 1);
    stats.add(build(first + 1, children.second, depth + 1));
    return stats;
  }

  // Depth-first emission: the first child directly after its parent, the second wherever the
  // first subtree ends (the parent stores that index).
  void flatten(std::uint32_t index, Bvh& out) const {
    const BuildNode& b = nodes[index];
    auto self = static_cast<std::uint32_t>(out.nodes.size());
    gpu::BvhNode n{};
    n.boundsMin = toVec3(b.lo);
    n.boundsMax = toVec3(b.hi);
    if (b.leaf) {
      n.offset = b.a;
      n.countAxis = b.b;
      out.nodes.push_back(n);
      return;
    }
    n.countAxis = b.axis << 16;
    out.nodes.push_back(n);
    flatten(b.a, out);
    out.nodes[self].offset = static_cast<std::uint32_t>(out.nodes.size());
    flatten(b.b, out);
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

Bvh buildBvh(const std::vector<BvhPrimitive>& primitives, const BvhOptions& options) {
  auto start = std::chrono::steady_clock::now();
  if (options.maxLeafSize < 1 || options.maxLeafSize > 0xFFFF) throw Error("BVH: maxLeafSize must be in 1..65535");
  if (options.maxDepth < 1) throw Error("BVH: maxDepth must be at least 1");
  Bvh bvh;
  bvh.stats.primitives = primitives.size();
  if (!primitives.empty()) {
    // The depth cap holds for any count that fits: maxLeafSize << (maxDepth - 1) primitives.
    if (options.maxDepth <= 40 &&
        primitives.size() > (static_cast<std::size_t>(options.maxLeafSize) << (options.maxDepth - 1))) {
      throw Error("BVH: " + std::to_string(primitives.size()) + " primitives cannot fit a tree of depth " +
                  std::to_string(options.maxDepth) + " with leaves of " + std::to_string(options.maxLeafSize));
    }
    int threads = options.threads > 0 ? options.threads : static_cast<int>(std::thread::hardware_concurrency());
    Builder builder(primitives.size(), options, std::max(1, threads));
    Range root;
    root.begin = 0;
    root.end = primitives.size();
    for (std::size_t i = 0; i < primitives.size(); ++i) {
      const Aabb& b = primitives[i].bounds;
      if (!(std::isfinite(b.min.x) && std::isfinite(b.min.y) && std::isfinite(b.min.z) && std::isfinite(b.max.x) &&
            std::isfinite(b.max.y) && std::isfinite(b.max.z)) ||
          glm::any(glm::greaterThan(b.min, b.max))) {
        throw Error("BVH: primitive " + std::to_string(i) +
                    " has non-finite or empty bounds (coordinates beyond float range?)");
      }
      Prim& p = builder.prims[i];
      p.lo = toV4(b.min);
      p.hi = toV4(b.max);
      p.setRef(primitives[i].ref);
      root.bounds.grow(p.lo, p.hi);
      V4 c = p.centroid2();
      root.centroids.grow(c, c);
    }
    SubtreeStats s = builder.build(0, root, 1);
    bvh.stats.depth = s.depth;
    bvh.stats.leaves = s.leaves;
    bvh.stats.maxLeafSize = s.maxLeaf;
    bvh.stats.threads = builder.threadsUsed.load();
    bvh.nodes.reserve(builder.next.load());
    builder.flatten(0, bvh);
    bvh.primRefs.resize(primitives.size());
    for (std::size_t i = 0; i < primitives.size(); ++i) bvh.primRefs[i] = builder.prims[i].ref();
  }
  bvh.stats.nodes = bvh.nodes.size();
  bvh.stats.buildMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  bvh.stats.sahCost = sahCost(bvh, options);
  return bvh;
}

std::uint32_t wideBvh(const Bvh& bvh, std::vector<gpu::BvhWideNode>& out) {
  out.clear();
  const auto& nodes = bvh.nodes;
  if (nodes.empty()) return gpu::kBvhNoRef;
  std::vector<std::uint32_t> record(nodes.size(), gpu::kBvhNoRef);
  std::uint32_t interior = 0;
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    if (nodeCount(nodes[i]) == 0) record[i] = interior++;
  }
  auto ref = [&](std::uint32_t i) {
    std::uint32_t count = nodeCount(nodes[i]);
    if (count == 0) return record[i];
    if (count > 16 || nodes[i].offset > gpu::kBvhLeafFirstMask) {
      throw Error("BVH leaf of " + std::to_string(count) + " entries from entry " + std::to_string(nodes[i].offset) +
                  " does not fit the shader's leaf reference (at most 16 entries, first below 2^27)");
    }
    return gpu::kBvhLeafFlag | (count - 1) << gpu::kBvhLeafCountShift | nodes[i].offset;
  };
  out.resize(interior);
  for (std::uint32_t i = 0; i < nodes.size(); ++i) {
    if (nodeCount(nodes[i]) != 0) continue;
    const gpu::BvhNode& a = nodes[i + 1]; // depth first: the first child follows its parent
    const gpu::BvhNode& b = nodes[nodes[i].offset];
    out[record[i]] =
        gpu::BvhWideNode{a.boundsMin, ref(i + 1), a.boundsMax, ref(nodes[i].offset), b.boundsMin, 0u, b.boundsMax, 0u};
  }
  return ref(0);
}

std::string checkBvh(const Bvh& bvh, const std::vector<BvhPrimitive>& primitives, const BvhOptions& options) {
  if (primitives.empty()) return bvh.nodes.empty() && bvh.primRefs.empty() ? "" : "nodes for an empty input";
  if (bvh.nodes.empty()) return "no nodes";
  if (bvh.primRefs.size() != primitives.size()) {
    return "primRefs has " + std::to_string(bvh.primRefs.size()) + " entries for " + std::to_string(primitives.size()) +
           " primitives";
  }
  // The same reference may stand for only one primitive in the input; map it back.
  std::vector<std::size_t> seen(primitives.size(), 0);
  std::vector<std::pair<std::uint32_t, std::size_t>> byRef;
  byRef.reserve(primitives.size());
  for (std::size_t i = 0; i < primitives.size(); ++i) byRef.emplace_back(primitives[i].ref, i);
  std::sort(byRef.begin(), byRef.end());
  for (std::size_t i = 1; i < byRef.size(); ++i) {
    if (byRef[i].first == byRef[i - 1].first) return "input references repeat";
  }
  auto lookup = [&](std::uint32_t ref) -> long long {
    auto it = std::lower_bound(byRef.begin(), byRef.end(), std::make_pair(ref, std::size_t{0}));
    return it != byRef.end() && it->first == ref ? static_cast<long long>(it->second) : -1;
  };
  std::vector<bool> visited(bvh.nodes.size(), false);
  struct Item {
    std::uint32_t node;
    int depth;
  };
  std::vector<Item> stack{{0, 1}};
  std::size_t reachedRefs = 0;
  while (!stack.empty()) {
    Item it = stack.back();
    stack.pop_back();
    if (it.node >= bvh.nodes.size()) return "child index " + std::to_string(it.node) + " out of range";
    if (visited[it.node]) return "node " + std::to_string(it.node) + " reached twice";
    visited[it.node] = true;
    if (it.depth > options.maxDepth) return "node " + std::to_string(it.node) + " deeper than maxDepth";
    const gpu::BvhNode& n = bvh.nodes[it.node];
    Aabb box = nodeBounds(n);
    std::uint32_t count = nodeCount(n);
    if (count > 0) {
      if (count > static_cast<std::uint32_t>(options.maxLeafSize)) {
        return "leaf " + std::to_string(it.node) + " holds " + std::to_string(count) + " primitives";
      }
      if (static_cast<std::size_t>(n.offset) + count > bvh.primRefs.size()) return "leaf range out of primRefs";
      for (std::uint32_t k = 0; k < count; ++k) {
        long long p = lookup(bvh.primRefs[n.offset + k]);
        if (p < 0) return "leaf references an unknown primitive";
        if (++seen[static_cast<std::size_t>(p)] > 1) return "primitive " + std::to_string(p) + " in two leaves";
        if (!box.contains(primitives[static_cast<std::size_t>(p)].bounds)) {
          return "leaf " + std::to_string(it.node) + " does not contain primitive " + std::to_string(p);
        }
        ++reachedRefs;
      }
      continue;
    }
    std::uint32_t a = it.node + 1;
    std::uint32_t b = n.offset;
    if (b <= it.node || a >= bvh.nodes.size() || b >= bvh.nodes.size()) {
      return "interior node " + std::to_string(it.node) + " has bad children";
    }
    if (!box.contains(nodeBounds(bvh.nodes[a])) || !box.contains(nodeBounds(bvh.nodes[b]))) {
      return "node " + std::to_string(it.node) + " does not contain its children";
    }
    stack.push_back({b, it.depth + 1});
    stack.push_back({a, it.depth + 1});
  }
  if (reachedRefs != primitives.size()) {
    return std::to_string(reachedRefs) + " of " + std::to_string(primitives.size()) + " primitives reachable";
  }
  for (std::size_t i = 0; i < visited.size(); ++i) {
    if (!visited[i]) return "node " + std::to_string(i) + " unreachable";
  }
  return "";
}

} // namespace vkray
