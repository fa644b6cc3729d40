// The BVH (host/accel/bvh.h) on random and adversarial inputs: every primitive reachable exactly
// once, every node's box contains its children, depth and leaf size within the shader's limits, and
// closest hits through the tree equal brute force over the same rays bit for bit (BvhBuild, host).
// On the GPU (GpuBvh): the kernel's traversal finds the same primitive as its brute-force loops for
// every eye ray, and the same shadows.
#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <random>
#include <set>
#include <vector>

#include <gtest/gtest.h>

#include "accel/bvh.h"
#include "accel/bvh_records.h"
#include "accel/shadow_entries.h"
#include "render/gpu_scene.h"
#include "scene/scene_loader.h"
#include "test_support.h"
#include "util/error.h"

namespace vkray {
namespace {

using glm::vec3;

struct Tri {
  vec3 v0, v1, v2;
};

// ---- A host mirror of the kernel's queries ---------------------------------------------------------

// The watertight test of shaders/lib/intersect.glsl (Woop, Benthin & Wald 2013) in float, the same
// operations in the same order: the same inputs give the same t whichever order triangles are tested.
float intersectWatertight(const vec3& o, const vec3& d, const Tri& tri, float tMax) {
  vec3 a = glm::abs(d);
  int kz = (a.x > a.y) ? ((a.x > a.z) ? 0 : 2) : ((a.y > a.z) ? 1 : 2);
  int kx = (kz + 1) % 3;
  int ky = (kx + 1) % 3;
  if (d[kz] < 0.0f) std::swap(kx, ky);
  vec3 shear(d[kx] / d[kz], d[ky] / d[kz], 1.0f / d[kz]);
  auto sheared = [&](const vec3& v) {
    vec3 r = v - o;
    float rz = r[kz];
    return vec3(r[kx] - shear.x * rz, r[ky] - shear.y * rz, shear.z * rz);
  };
  auto edge = [](const vec3& p, const vec3& q) {
    volatile float x = q.x * p.y; // volatile: no fused multiply-add, as `precise` in the shader
    volatile float y = q.y * p.x;
    return x - y;
  };
  vec3 A = sheared(tri.v0), B = sheared(tri.v1), C = sheared(tri.v2);
  float U = edge(B, C), V = edge(C, A), W = edge(A, B);
  if ((U < 0.0f || V < 0.0f || W < 0.0f) && (U > 0.0f || V > 0.0f || W > 0.0f)) return -1.0f;
  float det = U + V + W;
  vec3 e1 = tri.v1 - tri.v0, e2 = tri.v2 - tri.v0;
  if (det == 0.0f || glm::cross(e1, e2) == vec3(0.0f)) return -1.0f;
  float T = U * A.z + V * B.z + W * C.z;
  float t = T * (1.0f / det);
  return t > 0.0f && t < tMax ? t : -1.0f;
}

struct HostHit {
  float t = INFINITY;
  std::uint32_t prim = ~0u;
};

HostHit bruteForce(const std::vector<Tri>& tris, const vec3& o, const vec3& d) {
  HostHit h;
  for (std::uint32_t i = 0; i < tris.size(); ++i) {
    float t = intersectWatertight(o, d, tris[i], h.t);
    if (t > 0.0f) h = {t, i};
  }
  return h;
}

// The kernel's slab test (scene.glsl hitsBox) and its near-child-first traversal with a stack of
// kBvhStackSize entries; the stack may not overflow.
bool hitsBox(const vec3& o, const vec3& invDir, const gpu::BvhNode& n, float tMax) {
  vec3 t0 = (n.boundsMin - o) * invDir;
  vec3 t1 = (n.boundsMax - o) * invDir;
  vec3 tNear = glm::min(t0, t1), tFar = glm::max(t0, t1);
  float enter = std::max(std::max(tNear.x, tNear.y), std::max(tNear.z, 0.0f));
  float leave = std::min(std::min(tFar.x, tFar.y), std::min(tFar.z, tMax)) * 1.0000003576f;
  return enter <= leave;
}

HostHit traverse(const Bvh& bvh, const std::vector<Tri>& tris, const vec3& o, const vec3& d, int& maxStack) {
  HostHit h;
  if (bvh.nodes.empty()) return h;
  vec3 safe(d.x == 0.0f ? 1e-30f : d.x, d.y == 0.0f ? 1e-30f : d.y, d.z == 0.0f ? 1e-30f : d.z);
  vec3 invDir = 1.0f / safe;
  std::uint32_t stack[32];
  int sp = 0;
  std::uint32_t node = 0;
  while (true) {
    const gpu::BvhNode& n = bvh.nodes[node];
    if (hitsBox(o, invDir, n, h.t)) {
      std::uint32_t count = nodeCount(n);
      if (count == 0) {
        bool neg = d[static_cast<int>(nodeAxis(n))] < 0.0f;
        if (sp == 32) {
          maxStack = 33;
          return h;
        }
        stack[sp++] = neg ? node + 1 : n.offset;
        maxStack = std::max(maxStack, sp);
        node = neg ? n.offset : node + 1;
        continue;
      }
      for (std::uint32_t k = 0; k < count; ++k) {
        std::uint32_t prim = bvh.primRefs[n.offset + k] & gpu::kPrimIndexMask;
        float t = intersectWatertight(o, d, tris[prim], h.t);
        if (t > 0.0f) h = {t, prim};
      }
    }
    if (sp == 0) return h;
    node = stack[--sp];
  }
}

// ---- Inputs ----------------------------------------------------------------------------------------

std::vector<BvhPrimitive> primitivesOf(const std::vector<Tri>& tris) {
  std::vector<BvhPrimitive> prims;
  for (std::uint32_t i = 0; i < tris.size(); ++i) {
    Aabb b;
    b.grow(tris[i].v0);
    b.grow(tris[i].v1);
    b.grow(tris[i].v2);
    prims.push_back({b, gpu::kPrimTriangle << gpu::kPrimKindShift | i});
  }
  return prims;
}

std::vector<Tri> randomSoup(std::size_t n, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> pos(-10.0f, 10.0f);
  std::uniform_real_distribution<float> off(-0.8f, 0.8f);
  std::vector<Tri> tris;
  for (std::size_t i = 0; i < n; ++i) {
    vec3 c(pos(rng), pos(rng), pos(rng));
    tris.push_back({c + vec3(off(rng), off(rng), off(rng)), c + vec3(off(rng), off(rng), off(rng)),
                    c + vec3(off(rng), off(rng), off(rng))});
  }
  return tris;
}

// A closed bumpy torus (ring radius 3, tube about 1), u x v quads as two triangles sharing edges.
std::vector<Tri> torus(int u, int v) {
  auto p = [&](int i, int j) {
    float a = 2.0f * static_cast<float>(M_PI) * static_cast<float>(i % u) / static_cast<float>(u);
    float b = 2.0f * static_cast<float>(M_PI) * static_cast<float>(j % v) / static_cast<float>(v);
    float r = 1.0f + 0.15f * std::sin(5.0f * a) * std::sin(3.0f * b);
    return vec3((3.0f + r * std::cos(b)) * std::cos(a), r * std::sin(b), (3.0f + r * std::cos(b)) * std::sin(a));
  };
  std::vector<Tri> tris;
  for (int i = 0; i < u; ++i) {
    for (int j = 0; j < v; ++j) {
      tris.push_back({p(i, j), p(i, j + 1), p(i + 1, j + 1)});
      tris.push_back({p(i, j), p(i + 1, j + 1), p(i + 1, j)});
    }
  }
  return tris;
}

// Every triangle in one place: the same triangle n times (no split plane separates them).
std::vector<Tri> allInOnePlace(std::size_t n) {
  return std::vector<Tri>(n, Tri{vec3(-1, -1, 0), vec3(1, -1, 0), vec3(0, 1, 0.5f)});
}

// Long thin triangles: slivers from one side of the scene to the other, in a fan and crossing.
std::vector<Tri> longThin(std::size_t n, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<Tri> tris;
  for (std::size_t i = 0; i < n; ++i) {
    vec3 a(u(rng) * 50.0f, u(rng) * 2.0f, u(rng) * 2.0f);
    vec3 b(-a.x, u(rng) * 2.0f, u(rng) * 2.0f);
    vec3 c = a + vec3(0.0f, 1e-3f, 2e-3f * u(rng));
    tris.push_back(i % 2 ? Tri{a, b, c} : Tri{vec3(a.y, a.x, a.z), vec3(b.y, b.x, b.z), vec3(c.y, c.x, c.z)});
  }
  return tris;
}

// Sizes growing geometrically (by 2% each, 1 to 10^5): a pure SAH build peels the large ones off
// near the root, so the tree is far deeper than balanced.
std::vector<Tri> geometricSizes(std::size_t n) {
  std::vector<Tri> tris;
  float s = 1.0f;
  for (std::size_t i = 0; i < n; ++i, s *= 1.02f)
    tris.push_back({vec3(s, 0, 0), vec3(s, 0.5f * s, 0), vec3(s, 0, 0.5f * s)});
  return tris;
}

// ---- Independent structural check ------------------------------------------------------------------

// Walks the flattened array as the shader does and checks, without checkBvh: every primitive in
// exactly one leaf, every node reached once, parents contain children and leaves their primitives,
// depth <= 32 and leaves of at most 4.
void expectWellFormed(const Bvh& bvh, const std::vector<BvhPrimitive>& prims) {
  if (prims.empty()) {
    EXPECT_TRUE(bvh.nodes.empty());
    EXPECT_TRUE(bvh.primRefs.empty());
    return;
  }
  ASSERT_FALSE(bvh.nodes.empty());
  std::vector<int> leafOf(prims.size(), 0);
  std::vector<int> nodeSeen(bvh.nodes.size(), 0);
  struct Item {
    std::uint32_t node;
    int depth;
  };
  std::vector<Item> todo{{0, 1}};
  int maxDepth = 0;
  while (!todo.empty()) {
    Item it = todo.back();
    todo.pop_back();
    ASSERT_LT(it.node, bvh.nodes.size());
    ++nodeSeen[it.node];
    maxDepth = std::max(maxDepth, it.depth);
    const gpu::BvhNode& n = bvh.nodes[it.node];
    std::uint32_t count = nodeCount(n);
    if (count > 0) {
      EXPECT_LE(count, 4u);
      ASSERT_LE(n.offset + count, bvh.primRefs.size());
      for (std::uint32_t k = 0; k < count; ++k) {
        std::uint32_t ref = bvh.primRefs[n.offset + k];
        auto it2 = std::find_if(prims.begin(), prims.end(), [&](const BvhPrimitive& p) { return p.ref == ref; });
        ASSERT_NE(it2, prims.end()) << "unknown reference " << ref;
        auto index = static_cast<std::size_t>(it2 - prims.begin());
        ++leafOf[index];
        EXPECT_TRUE(nodeBounds(n).contains(prims[index].bounds)) << "leaf " << it.node << " primitive " << index;
      }
    } else {
      std::uint32_t a = it.node + 1, b = n.offset;
      ASSERT_LT(a, bvh.nodes.size());
      ASSERT_LT(b, bvh.nodes.size());
      ASSERT_GT(b, a);
      EXPECT_TRUE(nodeBounds(n).contains(nodeBounds(bvh.nodes[a]))) << "node " << it.node;
      EXPECT_TRUE(nodeBounds(n).contains(nodeBounds(bvh.nodes[b]))) << "node " << it.node;
      todo.push_back({a, it.depth + 1});
      todo.push_back({b, it.depth + 1});
    }
  }
  EXPECT_LE(maxDepth, 32);
  EXPECT_EQ(maxDepth, bvh.stats.depth);
  EXPECT_EQ(std::count(leafOf.begin(), leafOf.end(), 1), static_cast<long>(prims.size()))
      << "every primitive must be in exactly one leaf";
  EXPECT_EQ(std::count(nodeSeen.begin(), nodeSeen.end(), 1), static_cast<long>(bvh.nodes.size()))
      << "every node must be reached exactly once";
  // The library's own checker agrees.
  EXPECT_EQ(checkBvh(bvh, prims), "");
}

// Rays for the hit comparison: random rays through the scene's box from outside and inside, axis-
// aligned rays (zero direction components), and rays aimed exactly at vertices and edge midpoints.
struct TestRay {
  vec3 o, d;
};

std::vector<TestRay> raysFor(const std::vector<Tri>& tris, std::size_t n, std::uint32_t seed) {
  Aabb box;
  for (const Tri& t : tris) {
    box.grow(t.v0);
    box.grow(t.v1);
    box.grow(t.v2);
  }
  if (box.empty()) box = Aabb{vec3(-1.0f), vec3(1.0f)};
  vec3 c = box.center(), ext = box.max - box.min + vec3(1e-3f);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::uniform_int_distribution<std::size_t> pick(0, std::max<std::size_t>(tris.size(), 1) - 1);
  auto unit = [&] {
    vec3 v;
    do v = vec3(u(rng), u(rng), u(rng));
    while (glm::length(v) < 0.1f || glm::length(v) > 1.0f);
    return glm::normalize(v);
  };
  std::vector<TestRay> rays;
  for (std::size_t i = 0; i < n; ++i) {
    vec3 inside = c + 0.5f * ext * vec3(u(rng), u(rng), u(rng));
    switch (i % 5) {
    case 0: // from outside, towards a random point of the box
      rays.push_back({c + 1.5f * glm::length(ext) * unit(), vec3(0)});
      rays.back().d = glm::normalize(inside - rays.back().o);
      break;
    case 1: // from inside, any direction
      rays.push_back({inside, unit()});
      break;
    case 2: { // axis-aligned
      vec3 d(0.0f);
      d[static_cast<int>(i / 5 % 3)] = (i / 15) % 2 ? 1.0f : -1.0f;
      rays.push_back({inside, d});
      break;
    }
    default: { // exactly at a vertex or an edge midpoint of some triangle
      if (tris.empty()) {
        rays.push_back({inside, unit()});
        break;
      }
      const Tri& t = tris[pick(rng)];
      vec3 target = i % 5 == 3 ? t.v1 : 0.5f * (t.v0 + t.v2);
      vec3 o = target + 0.7f * glm::length(ext) * unit();
      rays.push_back({o, glm::normalize(target - o)});
    }
    }
  }
  return rays;
}

// Closest hits through the tree are the brute-force hits: the same t bit for bit, and the same
// triangle unless two triangles are hit at exactly that t (a shared edge or vertex, or coincident
// triangles), when either is right.
void expectSameHitsAsBruteForce(const std::vector<Tri>& tris, const Bvh& bvh, std::size_t rayCount,
                                std::uint32_t seed) {
  int ties = 0, hits = 0, maxStack = 0;
  for (const TestRay& r : raysFor(tris, rayCount, seed)) {
    HostHit brute = bruteForce(tris, r.o, r.d);
    HostHit tree = traverse(bvh, tris, r.o, r.d, maxStack);
    ASSERT_EQ(std::memcmp(&brute.t, &tree.t, sizeof(float)), 0)
        << "t " << brute.t << " (brute force, triangle " << brute.prim << ") vs " << tree.t << " (BVH, triangle "
        << tree.prim << "); ray " << r.o.x << "," << r.o.y << "," << r.o.z << " dir " << r.d.x << "," << r.d.y << ","
        << r.d.z;
    if (brute.prim != tree.prim) {
      ++ties;
      ASSERT_NE(tree.prim, ~0u);
      EXPECT_EQ(intersectWatertight(r.o, r.d, tris[tree.prim], INFINITY), brute.t) << "not a tie";
    }
    hits += brute.prim != ~0u ? 1 : 0;
  }
  EXPECT_LE(maxStack, 32) << "the kernel's traversal stack would overflow";
  EXPECT_LE(ties, static_cast<int>(rayCount)); // reported for information
  if (tris.size() > 1) {
    EXPECT_GT(hits, 0) << "the rays must hit something to test anything";
  }
}

struct Case {
  const char* name;
  std::vector<Tri> tris;
};

std::vector<Case> cases() {
  return {
      {"random soup", randomSoup(3000, 1)},
      {"closed torus", torus(60, 30)},
      {"all in one place", allInOnePlace(257)},
      {"long thin", longThin(800, 2)},
      {"geometric sizes", geometricSizes(600)},
      {"one triangle", {Tri{vec3(0, 0, 0), vec3(1, 0, 0), vec3(0, 1, 0)}}},
      {"no triangles", {}},
  };
}

TEST(BvhBuild, EveryPrimitiveReachableOnceAndBoxesNest) {
  for (const Case& c : cases()) {
    SCOPED_TRACE(c.name);
    auto prims = primitivesOf(c.tris);
    Bvh bvh = buildBvh(prims);
    expectWellFormed(bvh, prims);
    EXPECT_EQ(bvh.stats.primitives, c.tris.size());
    EXPECT_EQ(bvh.stats.nodes, bvh.nodes.size());
  }
}

// The shader's two-box records (wideBvh) are the same tree: walking them from the root reaches
// every leaf exactly once, each child's box is the node's own, and an empty or one-leaf tree needs
// no record.
TEST(BvhBuild, WideRecordsHoldTheSameTree) {
  for (const Case& c : cases()) {
    SCOPED_TRACE(c.name);
    Bvh bvh = buildBvh(primitivesOf(c.tris));
    std::vector<gpu::BvhWideNode> wide;
    std::uint32_t root = wideBvh(bvh, wide);
    if (bvh.nodes.empty()) {
      EXPECT_EQ(root, gpu::kBvhNoRef);
      EXPECT_TRUE(wide.empty());
      continue;
    }
    std::size_t leaves = 0;
    for (const auto& n : bvh.nodes) leaves += nodeCount(n) != 0;
    EXPECT_EQ(wide.size(), bvh.nodes.size() - leaves);
    // Walk both trees together: (wide reference, flat node index).
    std::vector<std::pair<std::uint32_t, std::uint32_t>> todo{{root, 0u}};
    std::vector<int> entrySeen(bvh.primRefs.size(), 0);
    std::size_t leavesSeen = 0;
    while (!todo.empty()) {
      auto [ref, flat] = todo.back();
      todo.pop_back();
      const gpu::BvhNode& n = bvh.nodes[flat];
      if (nodeCount(n) != 0) {
        ASSERT_NE(ref & gpu::kBvhLeafFlag, 0u);
        EXPECT_EQ(ref & gpu::kBvhLeafFirstMask, n.offset);
        EXPECT_EQ(((ref >> gpu::kBvhLeafCountShift) & 15u) + 1u, nodeCount(n));
        for (std::uint32_t e = n.offset; e < n.offset + nodeCount(n); ++e) ++entrySeen[e];
        ++leavesSeen;
        continue;
      }
      ASSERT_LT(ref, wide.size());
      const gpu::BvhWideNode& w = wide[ref];
      const gpu::BvhNode& a = bvh.nodes[flat + 1];
      const gpu::BvhNode& b = bvh.nodes[n.offset];
      EXPECT_EQ(w.min0, a.boundsMin);
      EXPECT_EQ(w.max0, a.boundsMax);
      EXPECT_EQ(w.min1, b.boundsMin);
      EXPECT_EQ(w.max1, b.boundsMax);
      todo.emplace_back(w.ref0, flat + 1);
      todo.emplace_back(w.ref1, n.offset);
    }
    EXPECT_EQ(leavesSeen, leaves);
    for (int seen : entrySeen) EXPECT_EQ(seen, 1);
  }
}

// How far packBvhRecords may move a bound outwards: a block of 256 ulps (2^-15 of the coordinate), or
// up to the smallest normal at zero; 2^-14 and 2^-125 leave room for the byte on top.
float packingSlack(float v) {
  return std::abs(v) * 0x1p-14f + 0x1p-125f;
}

// The kernels' three-texel records (packBvhRecords): both references come back as they were, and each
// box holds the exact one, larger by no more than the rounding the packing allows (a block of 256 ulps,
// 2^-15 of a coordinate, or the smallest normal's neighbourhood at zero).
TEST(BvhBuild, PackedRecordsKeepTheReferencesAndHoldTheBoxes) {
  for (const Case& c : cases()) {
    SCOPED_TRACE(c.name);
    Bvh bvh = buildBvh(primitivesOf(c.tris));
    std::vector<gpu::BvhWideNode> wide;
    wideBvh(bvh, wide);
    std::vector<glm::uvec4> texels = packBvhRecords(wide);
    ASSERT_EQ(texels.size(), wide.size() * gpu::kBvhRecordTexels);
    for (std::uint32_t i = 0; i < wide.size(); ++i) {
      const gpu::BvhWideNode& w = wide[i];
      gpu::BvhWideNode p = unpackBvhRecord(texels, i);
      ASSERT_EQ(p.ref0, w.ref0) << "record " << i;
      ASSERT_EQ(p.ref1, w.ref1) << "record " << i;
      for (int k = 0; k < 3; ++k) {
        ASSERT_LE(p.min0[k], w.min0[k]);
        ASSERT_GE(p.max0[k], w.max0[k]);
        ASSERT_LE(p.min1[k], w.min1[k]);
        ASSERT_GE(p.max1[k], w.max1[k]);
        ASSERT_LE(w.min0[k] - p.min0[k], packingSlack(w.min0[k]));
        ASSERT_LE(p.max0[k] - w.max0[k], packingSlack(w.max0[k]));
        ASSERT_LE(w.min1[k] - p.min1[k], packingSlack(w.min1[k]));
        ASSERT_LE(p.max1[k] - w.max1[k], packingSlack(w.max1[k]));
      }
    }
  }
}

// A bound that carries a byte stays on its side of the value for every byte, at zero (either sign),
// among denormals (which a device may flush to zero: an outward bound is never one), at the largest
// coordinates a scene may have and beyond them (refused).
TEST(BvhBuild, BoundsCarryingAByteStayOutsideTheValue) {
  const float values[] = {0.0f,    -0.0f, 1e-45f, -1e-45f, 1e-39f, -1e-39f,  0x1p-126f, -0x1p-126f, 1e-30f,
                          -1e-30f, 0.5f,  -0.5f,  1.0f,    -1.0f,  3.14159f, -2.71828f, 1e18f,      -1e18f};
  for (float v : values) {
    for (std::uint32_t byte = 0; byte < 256; ++byte) {
      float lo = std::bit_cast<float>(lowerBoundWithByte(v, byte));
      float hi = std::bit_cast<float>(upperBoundWithByte(v, byte));
      ASSERT_EQ(lowerBoundWithByte(v, byte) & 0xFFu, byte);
      ASSERT_EQ(upperBoundWithByte(v, byte) & 0xFFu, byte);
      ASSERT_TRUE(std::isfinite(lo) && std::isfinite(hi)) << v;
      ASSERT_LE(lo, v) << v << " byte " << byte;
      ASSERT_GE(hi, v) << v << " byte " << byte;
      // Flushed to zero, a denormal bound moves towards zero: only one moved towards zero may be one.
      if (v > 0.0f) {
        ASSERT_EQ(std::fpclassify(hi), FP_NORMAL) << v;
      }
      if (v < 0.0f) {
        ASSERT_EQ(std::fpclassify(lo), FP_NORMAL) << v;
      }
      ASSERT_LE(v - lo, packingSlack(v));
      ASSERT_LE(hi - v, packingSlack(v));
    }
  }
  EXPECT_THROW(lowerBoundWithByte(2e38f, 0u), Error);
  EXPECT_THROW(upperBoundWithByte(-std::numeric_limits<float>::infinity(), 0u), Error);
  EXPECT_THROW(upperBoundWithByte(std::numeric_limits<float>::quiet_NaN(), 0u), Error);
}

TEST(BvhBuild, ClosestHitsEqualBruteForceBitForBit) {
  for (const Case& c : cases()) {
    SCOPED_TRACE(c.name);
    Bvh bvh = buildBvh(primitivesOf(c.tris));
    expectSameHitsAsBruteForce(c.tris, bvh, 3000, 7);
  }
}

// A depth cap that binds: 600 triangles of geometric sizes with leaves of 1 and at most 11 levels
// (2^10 >= 600) still give a valid tree of depth <= 11 and the same hits.
TEST(BvhBuild, DepthCapHoldsOnAdversarialInput) {
  auto tris = geometricSizes(600);
  BvhOptions options;
  options.maxLeafSize = 1;
  options.maxDepth = 11;
  Bvh bvh = buildBvh(primitivesOf(tris), options);
  EXPECT_EQ(checkBvh(bvh, primitivesOf(tris), options), "");
  EXPECT_LE(bvh.stats.depth, 11);
  // Uncapped, the SAH tree is deeper: the cap is what holds the depth.
  BvhOptions deep = options;
  deep.maxDepth = 1000;
  EXPECT_GT(buildBvh(primitivesOf(tris), deep).stats.depth, 11);
  expectSameHitsAsBruteForce(tris, bvh, 1000, 3);
  // Too many primitives for the cap: refused, not a tree that overflows the shader's stack.
  options.maxDepth = 4;
  EXPECT_THROW(buildBvh(primitivesOf(tris), options), Error);
}

TEST(BvhBuild, NonFiniteBoundsAreRefused) {
  auto prims = primitivesOf(randomSoup(10, 3));
  prims[4].bounds.max.y = INFINITY;
  EXPECT_THROW(buildBvh(prims), Error);
}

// The parallel build makes the same decisions as the serial one: the same array, byte for byte.
TEST(BvhBuild, ParallelBuildEqualsSerialBuild) {
  auto prims = primitivesOf(randomSoup(40000, 5));
  BvhOptions serial;
  serial.threads = 1;
  BvhOptions parallel;
  parallel.threads = 4;
  Bvh a = buildBvh(prims, serial);
  Bvh b = buildBvh(prims, parallel);
  ASSERT_EQ(a.nodes.size(), b.nodes.size());
  EXPECT_EQ(std::memcmp(a.nodes.data(), b.nodes.data(), a.nodes.size() * sizeof(gpu::BvhNode)), 0);
  EXPECT_EQ(a.primRefs, b.primRefs);
}

// The SAH pays off: on a mesh the expected cost per ray is far below testing every triangle.
TEST(BvhBuild, SahTreeIsMuchCheaperThanBruteForce) {
  auto tris = torus(100, 50);
  Bvh bvh = buildBvh(primitivesOf(tris));
  EXPECT_LT(bvh.stats.sahCost, 0.01 * static_cast<double>(tris.size())) << bvh.stats.sahCost;
  EXPECT_LE(bvh.stats.depth, 32);
}

// packScene with a BVH stores triangles in leaf order (orderByLeaves): afterwards primRefs[i] is
// triangle i, the triangles are the same set, and each keeps its own material and shading normals.
TEST(BvhBuild, LeafOrderKeepsEveryTriangleWithItsNormals) {
  Scene scene;
  auto tris = torus(20, 10);
  for (std::size_t i = 0; i < tris.size(); ++i) {
    Triangle t;
    t.v[0] = tris[i].v0;
    t.v[1] = tris[i].v1;
    t.v[2] = tris[i].v2;
    t.material = static_cast<std::uint32_t>(i);
    if (i % 3 == 0) {
      glm::dvec3 n = glm::normalize(glm::cross(t.v[1] - t.v[0], t.v[2] - t.v[0]));
      t.normals = std::array<glm::dvec3, 3>{n, n, glm::dvec3(static_cast<double>(i), 0, 1)};
    }
    scene.triangles.push_back(t);
  }
  scene.camera.position = {0, 0, 10};
  GpuScene g = packScene(scene, scene.camera.position, true);
  ASSERT_EQ(g.triangles.size(), tris.size());
  std::set<std::uint32_t> materials;
  for (std::uint32_t i = 0; i < g.bvh.primRefs.size(); ++i) {
    EXPECT_EQ(g.bvh.primRefs[i], gpu::kPrimTriangle << gpu::kPrimKindShift | i);
    const gpu::Triangle& t = g.triangles[i];
    std::uint32_t m = gpu::triangleMaterial(t);
    materials.insert(m);
    const Tri& original = tris[m];
    EXPECT_EQ(vec3(t.v0), vec3(glm::dvec3(original.v0) - scene.camera.position));
    std::uint32_t normalBase = gpu::triangleNormalBase(t);
    if (m % 3 == 0) {
      ASSERT_NE(normalBase, gpu::kNoNormals);
      EXPECT_EQ(g.normals[normalBase + 2].x, static_cast<float>(m)) << "triangle " << m;
    } else {
      EXPECT_EQ(normalBase, gpu::kNoNormals);
    }
  }
  EXPECT_EQ(materials.size(), tris.size());
}

// ---- GPU: the kernel's traversal against its brute-force loops -------------------------------------

glm::dvec3 idColor(std::uint32_t id) {
  return glm::dvec3((id & 255u) / 255.0, ((id >> 8) & 255u) / 255.0, (((id >> 16) & 255u) + 1) / 255.0);
}

std::uint32_t colorId(const glm::vec3& c) {
  auto byte = [](float x) { return static_cast<std::uint32_t>(std::lround(x * 255.0f)); };
  return byte(c.r) | byte(c.g) << 8 | (byte(c.b) - 1) << 16;
}

// A scene of every bounded kind, each primitive with a material of its own colour: with ambient
// light 1 and nothing else, a pixel's colour names the primitive its eye ray hit. Triangles 0..n-1,
// then spheres, then polygons.
Scene idScene(const std::vector<Tri>& tris, bool lit, BvhMode bvh) {
  Scene scene;
  scene.camera.position = {1.0, 6.0, 9.0};
  scene.camera.lookAt = {0.0, 0.0, 0.0};
  scene.camera.fovY = 50.0;
  scene.render.width = 96;
  scene.render.height = 72;
  scene.render.maxDepth = 0;
  scene.render.bvh = bvh;
  scene.background = glm::dvec3(0.0);
  scene.ambientLight = glm::dvec3(lit ? 0.2 : 1.0);
  std::uint32_t id = 0;
  auto material = [&] {
    Material m;
    m.color = idColor(id++);
    m.ambient = 1.0;
    m.diffuse = lit ? 0.8 : 0.0;
    m.specular = 0.0;
    scene.materials.push_back(m);
    return static_cast<std::uint32_t>(scene.materials.size() - 1);
  };
  for (const Tri& t : tris) {
    Triangle tri;
    tri.v[0] = t.v0;
    tri.v[1] = t.v1;
    tri.v[2] = t.v2;
    tri.material = material();
    scene.triangles.push_back(tri);
  }
  for (int i = 0; i < 6; ++i) {
    double a = i * M_PI / 3.0;
    scene.spheres.push_back({glm::dvec3(2.0 * std::cos(a), 0.3, 2.0 * std::sin(a)), 0.6, material()});
  }
  Polygon floor;
  floor.vertices = {{-6, -1.5, -6}, {-6, -1.5, 6}, {6, -1.5, 6}, {6, -1.5, -6}};
  floor.normal = {0, 1, 0};
  floor.material = material();
  scene.polygons.push_back(floor);
  if (lit) scene.lights.push_back(PointLight{glm::dvec3(3.0, 8.0, 2.0), glm::dvec3(1.0), true});
  return scene;
}

// Whether two triangles share a vertex (a ray exactly on their common edge or vertex hits both at
// the same t, and then either is a correct closest hit).
bool touching(const Tri& a, const Tri& b) {
  for (const vec3& p : {a.v0, a.v1, a.v2}) {
    for (const vec3& q : {b.v0, b.v1, b.v2}) {
      if (p == q) return true;
    }
  }
  return false;
}

TEST(GpuBvh, EyeRayHitsEqualBruteForce) {
  auto tris = torus(48, 24); // 2304 triangles
  Image viaBvh = test::render(idScene(tris, false, BvhMode::On)).image;
  Image brute = test::render(idScene(tris, false, BvhMode::Off)).image;
  // Two descent steps between votes (as in trees from kBvhTwoStepDepth deep on): the same hits.
  RenderOptions twoSteps;
  twoSteps.bvhStepsPerVote = 2;
  Image viaTwoSteps = test::render(idScene(tris, false, BvhMode::On), twoSteps).image;
  test::expectNoValidationMessages();
  EXPECT_TRUE(viaTwoSteps.pixels == viaBvh.pixels) << "two steps per vote changed a hit";
  ASSERT_EQ(viaBvh.pixels.size(), brute.pixels.size());
  const std::uint32_t prims = static_cast<std::uint32_t>(tris.size()) + 7;
  std::set<std::uint32_t> seen;
  int ties = 0;
  for (std::size_t i = 0; i < brute.pixels.size(); ++i) {
    const glm::vec3 a = brute.pixels[i], b = viaBvh.pixels[i];
    if (a == glm::vec3(0.0f)) {
      EXPECT_EQ(b, a) << "pixel " << i << ": the BVH hit something brute force missed";
      continue;
    }
    std::uint32_t ida = colorId(a), idb = colorId(b);
    ASSERT_LT(ida, prims) << "pixel " << i;
    seen.insert(ida);
    if (ida == idb) continue;
    // Only a tie between neighbouring triangles may resolve differently.
    ASSERT_LT(idb, tris.size()) << "pixel " << i << ": brute force hit " << ida << ", the BVH " << idb;
    ASSERT_LT(ida, tris.size()) << "pixel " << i << ": brute force hit " << ida << ", the BVH " << idb;
    EXPECT_TRUE(touching(tris[ida], tris[idb])) << "pixel " << i << ": " << ida << " vs " << idb;
    ++ties;
  }
  EXPECT_GT(seen.size(), 500u) << "the view must show many primitives";
  EXPECT_LE(ties, 10) << "more ties than rays exactly on edges can explain";
  std::printf("[ bvh ] %zu primitives seen, %d edge ties resolved differently\n", seen.size(), ties);
}

// Shadow rays stop at the first hit (any-hit) in both paths; they must agree on what is in shadow.
TEST(GpuBvh, ShadowsEqualBruteForce) {
  auto tris = torus(48, 24);
  Image viaBvh = test::render(idScene(tris, true, BvhMode::On)).image;
  RenderOptions fromEntries;
  fromEntries.shadowEntryPoints = ShadowEntries::On; // shadow rays from their triangles' entry points
  Image viaEntries = test::render(idScene(tris, true, BvhMode::On), fromEntries).image;
  Image brute = test::render(idScene(tris, true, BvhMode::Off)).image;
  RenderOptions twoSteps = fromEntries;
  twoSteps.bvhStepsPerVote = 2; // two descent steps between votes, as in deep trees
  Image viaTwoSteps = test::render(idScene(tris, true, BvhMode::On), twoSteps).image;
  Scene unshadowed = idScene(tris, true, BvhMode::On);
  unshadowed.lights[0].shadows = false;
  Image noShadows = test::render(unshadowed).image;
  test::expectNoValidationMessages();
  int differing = 0, shadowed = 0;
  for (std::size_t i = 0; i < brute.pixels.size(); ++i) {
    if (brute.pixels[i] != viaBvh.pixels[i]) ++differing;
    if (brute.pixels[i] != viaEntries.pixels[i]) ++differing;
    if (brute.pixels[i] != viaTwoSteps.pixels[i]) ++differing;
    if (brute.pixels[i] != noShadows.pixels[i]) ++shadowed;
  }
  EXPECT_EQ(differing, 0);
  EXPECT_GT(shadowed, 200) << "the scene must have shadows to compare";
}

// The ray-query kernel `vkray bench meshes` times against Embree (shaders/hits.comp) must do the
// renderer's work: the same eye rays hit the same kind of primitive, and a pixel the renderer draws
// in shadow is one whose shadow ray the query kernel finds blocked.
TEST(GpuBvh, QueryKernelAgreesWithTheRenderer) {
  auto tris = torus(48, 24);
  Image ids = test::render(idScene(tris, false, BvhMode::On)).image;
  Scene lit = idScene(tris, true, BvhMode::On);
  Image shadowed = test::render(lit).image;
  Scene unshadowed = lit;
  unshadowed.lights[0].shadows = false;
  Image unlit = test::render(unshadowed).image;
  RenderOptions query;
  query.kernel = Kernel::Hits;
  RenderResult hits = test::render(lit, query);
  test::expectNoValidationMessages();
  ASSERT_EQ(hits.hits.size(), ids.pixels.size());
  const std::uint32_t triangles = static_cast<std::uint32_t>(tris.size());
  std::size_t blocked = 0, drawnInShadow = 0, hitCount = 0;
  for (std::size_t i = 0; i < ids.pixels.size(); ++i) {
    const glm::vec4& h = hits.hits[i];
    if (ids.pixels[i] == glm::vec3(0.0f)) {
      EXPECT_EQ(h.x, -1.0f) << "pixel " << i << ": the query kernel hit what the renderer missed";
      EXPECT_EQ(h.w, -1.0f) << "pixel " << i;
      continue;
    }
    ++hitCount;
    EXPECT_GT(h.x, 0.0f) << "pixel " << i;
    std::uint32_t id = colorId(ids.pixels[i]);
    std::uint32_t kind = id < triangles       ? gpu::kPrimTriangle
                         : id < triangles + 6 ? gpu::kPrimSphere
                                              : gpu::kPrimPolygon;
    EXPECT_EQ(static_cast<std::uint32_t>(h.y), kind) << "pixel " << i;
    bool dark = !test::sameColour(shadowed.pixels[i], unlit.pixels[i]); // another variant: variantsExact
    blocked += h.w > 0.0f;
    drawnInShadow += dark;
    if (dark) {
      EXPECT_EQ(h.w, 1.0f) << "pixel " << i << ": drawn in shadow, but its shadow ray was not blocked";
    }
  }
  EXPECT_GT(hitCount, 3000u);
  EXPECT_GT(drawnInShadow, 200u) << "the scene must have shadows to compare";
  // A blocked ray whose light adds less than a rounding step leaves the pixel unchanged.
  EXPECT_LE(blocked - drawnInShadow, blocked / 100) << blocked << " blocked, " << drawnInShadow << " drawn dark";
}

// Eye rays that start at their tile's entry points (shaders/entry.comp) find exactly the hits of a
// walk from the root: the same hit or miss, the same distance bit for bit, the same kind of
// primitive, in every pixel. Views chosen to stress the tiles' frusta: partial tiles at the image's
// edges, a wide and a narrow field of view, the eye inside a closed mesh (every tile reaches
// geometry all around), the eye away from the frame the scene was packed in (the viewer's case),
// and a band split (the first band's tiles are numbered from its own first row).
TEST(GpuBvh, EntryPointsFindTheSameHitsAsTheRoot) {
  auto tris = torus(48, 24);
  struct View {
    const char* name;
    glm::dvec3 eye, lookAt;
    double fovY;
    std::uint32_t width, height;
    bool moveAfterUpload; // render from `eye` after uploading the scene for the default camera
  };
  const View views[] = {
      {"default", {1.0, 6.0, 9.0}, {0.0, 0.0, 0.0}, 50.0, 96, 72, false},
      {"partial tiles, wide", {0.5, 2.0, 2.5}, {0.0, 0.0, 0.0}, 150.0, 101, 37, false},
      {"narrow", {1.0, 6.0, 9.0}, {3.0, 0.0, 0.0}, 4.0, 64, 64, false},
      // Pixels of 6e-7 radians: a tile's corner rays nearly parallel, their rounding a tenth of a pixel.
      {"0.05 degrees, 1500 rows", {1.0, 6.0, 9.0}, {3.0, 0.0, 0.0}, 0.05, 24, 1500, false},
      {"inside the tube", {0.0, 0.0, 3.0}, {1.0, 0.0, 3.0}, 90.0, 80, 60, false},
      {"eye moved after upload", {-5.0, 2.0, 4.0}, {0.0, 0.0, 0.0}, 60.0, 96, 72, true},
      {"bands", {1.0, 6.0, 9.0}, {0.0, 0.0, 0.0}, 4.0, 2100, 44, false}, // first band: 32 rows
  };
  Renderer& renderer = test::renderer();
  for (const View& v : views) {
    SCOPED_TRACE(v.name);
    Scene scene = idScene(tris, true, BvhMode::On);
    scene.render.width = v.width;
    scene.render.height = v.height;
    Camera camera = scene.camera;
    camera.position = v.eye;
    camera.lookAt = v.lookAt;
    camera.fovY = v.fovY;
    if (!v.moveAfterUpload) scene.camera = camera;
    renderer.setScene(scene);
    RenderOptions from;
    from.kernel = Kernel::Hits;
    RenderOptions root = from;
    root.entryPoints = false;
    RenderResult a = renderer.render(camera, scene.render, from);
    RenderResult b = renderer.render(camera, scene.render, root);
    // The same in bands of 8 rows after the first (a budget no measured band meets).
    RenderOptions banded = from;
    banded.bandBudgetMs = 1e-3;
    RenderResult c = renderer.render(camera, scene.render, banded);
    test::expectNoValidationMessages();
    if (v.width > 1000) {
      EXPECT_EQ(c.timings.bands, 3);
    }
    ASSERT_EQ(a.hits.size(), b.hits.size());
    ASSERT_EQ(c.hits.size(), b.hits.size());
    std::size_t hits = 0;
    for (std::size_t i = 0; i < b.hits.size(); ++i) {
      for (const RenderResult* r : {&a, &c}) {
        const glm::vec4& h = r->hits[i];
        const glm::vec4& want = b.hits[i];
        ASSERT_EQ(std::memcmp(&h.x, &want.x, sizeof(float)), 0)
            << "pixel " << i << ": t " << h.x << " from the entry points, " << want.x << " from the root";
        ASSERT_EQ(h.y, want.y) << "pixel " << i << ": another kind of primitive";
        ASSERT_EQ(h.w, want.w) << "pixel " << i << ": the shadow ray decided otherwise";
      }
      hits += b.hits[i].x > 0.0f;
    }
    EXPECT_GT(hits, b.hits.size() / 10) << "the view must show the scene";
  }
}

// ---- Shadow entry points (host/accel/shadow_entries.h) ---------------------------------------------

// The references under `refs`: every primitive a walk from them can reach.
std::set<std::uint32_t> reachable(const GpuScene& g, const std::vector<std::uint32_t>& refs) {
  std::set<std::uint32_t> prims;
  std::vector<std::uint32_t> todo(refs.begin(), refs.end());
  while (!todo.empty()) {
    std::uint32_t ref = todo.back();
    todo.pop_back();
    if (ref < gpu::kBvhLeafFlag) {
      todo.push_back(g.bvhNodes[ref].ref0);
      todo.push_back(g.bvhNodes[ref].ref1);
      continue;
    }
    std::uint32_t first = ref & gpu::kBvhLeafFirstMask;
    std::uint32_t end = first + ((ref >> gpu::kBvhLeafCountShift) & 15u) + 1u;
    for (std::uint32_t k = first; k < end; ++k) prims.insert(g.bvh.primRefs[k]);
  }
  return prims;
}

// Whether the segment from `o` along unit `d` to distance `tMax` meets the sphere (in double).
bool segmentMeetsSphere(const glm::dvec3& o, const glm::dvec3& d, double tMax, const glm::dvec3& c, double r) {
  double t = std::clamp(glm::dot(c - o, d), 0.0, tMax);
  return glm::length(o + t * d - c) <= r;
}

// Whether the segment from o to e meets triangle v, in double: Moller-Trumbore with the segment's
// ends left out (t in (1e-9, 1 - 1e-9)) and the triangle's edges widened by 1e-12 (a graze counts).
bool segmentMeetsTriangle(const glm::dvec3& o, const glm::dvec3& e, const glm::dvec3 v[3]) {
  const glm::dvec3 d = e - o, e1 = v[1] - v[0], e2 = v[2] - v[0];
  const glm::dvec3 p = glm::cross(d, e2);
  const double det = glm::dot(e1, p);
  if (det == 0.0) return false; // the segment parallel to the triangle's plane
  const glm::dvec3 s = o - v[0];
  const double u = glm::dot(s, p) / det;
  const glm::dvec3 q = glm::cross(s, e1);
  const double w = glm::dot(d, q) / det;
  const double t = glm::dot(e2, q) / det;
  return u >= -1e-12 && w >= -1e-12 && u + w <= 1.0 + 1e-12 && t > 1e-9 && t < 1.0 - 1e-9;
}

glm::dvec3 corner(const glm::vec4& v) {
  return glm::dvec3(glm::vec3(v));
}

// Points of triangle v that the "nothing between" checks send segments from: the centroid, points
// near each corner and the middle of each edge, and random ones, all 1e-3 or more inside.
std::vector<glm::dvec3> pointsOn(const glm::dvec3 v[3], std::mt19937& rng) {
  std::vector<glm::dvec3> points;
  auto at = [&](double a, double b, double c) { points.push_back(a * v[0] + b * v[1] + c * v[2]); };
  at(1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0);
  at(0.998, 0.001, 0.001), at(0.001, 0.998, 0.001), at(0.001, 0.001, 0.998);
  at(0.4995, 0.4995, 0.001), at(0.001, 0.4995, 0.4995), at(0.4995, 0.001, 0.4995);
  std::uniform_real_distribution<double> unit(0.001, 1.0);
  for (int k = 0; k < 5; ++k) {
    double a = unit(rng), b = unit(rng), c = unit(rng);
    const double sum = a + b + c;
    at(a / sum, b / sum, c / sum);
  }
  return points;
}

// A (triangle, light) marked "nothing between": no segment from a point of the triangle to the
// light meets another triangle or a sphere, in double precision.
void expectNothingBetween(const GpuScene& g, std::uint32_t t, const glm::dvec3& light, std::mt19937& rng) {
  const gpu::Triangle& tri = g.triangles[t];
  const glm::dvec3 v[3] = {corner(tri.v0), corner(tri.v1), corner(tri.v2)};
  for (const glm::dvec3& q : pointsOn(v, rng)) {
    for (std::uint32_t u = 0; u < g.triangles.size(); ++u) {
      if (u == t) continue;
      const glm::dvec3 w[3] = {corner(g.triangles[u].v0), corner(g.triangles[u].v1), corner(g.triangles[u].v2)};
      ASSERT_FALSE(segmentMeetsTriangle(q, light, w))
          << "triangle " << t << " is marked nothing-between, but triangle " << u << " stops a ray to the light";
    }
    const double dist = glm::length(light - q);
    for (std::uint32_t s = 0; s < g.spheres.size(); ++s) {
      const glm::vec4 cr = g.spheres[s].centerRadius;
      ASSERT_FALSE(segmentMeetsSphere(q, (light - q) / dist, dist, glm::dvec3(glm::vec3(cr)), cr.w))
          << "triangle " << t << " is marked nothing-between, but sphere " << s << " stops a ray to the light";
    }
  }
}

// Every shadow ray from a point of triangle T to light P (from on the triangle and from just off
// either side of it, as the kernel's origins lie) that meets a triangle or sphere meets one a walk
// from T's entry points reaches: brute force over every primitive. Where the pair is marked
// "nothing between" instead, no segment from T to P meets anything (in double; the kernel's
// origins then never leave a walk to decide). Lights in the hole of the torus, far away, close to
// the surface and in a corner of the soup; subtrees shared by up to 0 (each triangle its own), 1,
// 8 and 64 leaves.
TEST(ShadowEntries, EveryOccluderIsReachableFromTheEntryPoints) {
  struct Case {
    const char* name;
    std::vector<Tri> tris;
    bool local; // small triangles: each hull meets a small part of the scene
  };
  // Long thin triangles all cross the middle of the scene: every hull meets most of it.
  const Case cases[] = {
      {"torus", torus(18, 10), true}, {"soup", randomSoup(300, 7), true}, {"long thin", longThin(200, 3), false}};
  const glm::dvec3 lights[] = {{0.0, 0.2, 0.0}, {90.0, 140.0, -60.0}, {3.0, 1.6, 0.4}, {-9.0, 9.0, -9.0}};
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    Scene scene = idScene(c.tris, true, BvhMode::On);
    scene.lights.clear();
    for (const glm::dvec3& p : lights) scene.lights.push_back(PointLight{p, glm::dvec3(1.0), true});
    GpuScene g = packScene(scene, scene.camera.position, true);
    ASSERT_EQ(g.lights.size(), std::size(lights));
    for (std::uint32_t share : {0u, 1u, 8u, 64u}) {
      SCOPED_TRACE("subtrees of up to " + std::to_string(share) + " leaves share their entries");
      ShadowEntryOptions options;
      options.shareBelow = share;
      g.shadowEntries.clear();
      buildShadowEntries(g, options);
      ASSERT_EQ(g.shadowEntries.size(), 2 * g.triangles.size() * g.lights.size());
      std::size_t blocked = 0, segments = 0, reached = 0, nothing = 0;
      for (std::uint32_t t = 0; t < g.triangles.size(); ++t) {
        const gpu::Triangle& tri = g.triangles[t];
        const glm::dvec3 v0(glm::vec3(tri.v0)), v1(glm::vec3(tri.v1)), v2(glm::vec3(tri.v2));
        const glm::dvec3 n = glm::normalize(glm::cross(v1 - v0, v2 - v0));
        for (std::uint32_t l = 0; l < g.lights.size(); ++l) {
          const std::size_t at = 2 * (t * g.lights.size() + l);
          if (g.shadowEntries[at + 1].w == gpu::kShadowNothingBetween) {
            ASSERT_EQ(g.shadowEntries[at].x, gpu::kBvhNoRef);
            ++nothing;
            expectNothingBetween(g, t, glm::dvec3(glm::vec3(g.lights[l].position)), rng);
            if (HasFatalFailure()) return;
            continue;
          }
          const auto refs = shadowEntryRefs(g.shadowEntries[at], g.shadowEntries[at + 1]);
          ASSERT_FALSE(refs.empty()) << "triangle " << t << " has no entry points";
          ASSERT_LE(refs.size(), gpu::kShadowEntryMax);
          const std::set<std::uint32_t> prims = reachable(g, refs);
          reached += prims.size();
          ASSERT_TRUE(prims.count(gpu::kPrimTriangle << gpu::kPrimKindShift | t)) << "its own triangle";
          const glm::dvec3 light(glm::vec3(g.lights[l].position));
          for (int k = 0; k < 7; ++k) {
            // Vertices, the centroid, points inside, each nudged off the surface by a relative 1e-6.
            double a = unit(rng), b = unit(rng);
            if (a + b > 1.0) a = 1.0 - a, b = 1.0 - b;
            if (k < 3) a = k == 1, b = k == 2;
            if (k == 3) a = b = 1.0 / 3.0;
            const double side = k % 3 == 0 ? 0.0 : (k % 3 == 1 ? 1e-6 : -1e-6);
            const glm::dvec3 q = v0 + a * (v1 - v0) + b * (v2 - v0) + side * (1.0 + glm::length(v0)) * n;
            const double dist = glm::length(light - q);
            const glm::dvec3 d = (light - q) / dist;
            ++segments;
            bool hit = false;
            for (std::uint32_t u = 0; u < g.triangles.size(); ++u) {
              if (u == t) continue;
              const gpu::Triangle& w = g.triangles[u];
              Tri other{vec3(w.v0), vec3(w.v1), vec3(w.v2)};
              if (intersectWatertight(vec3(q), vec3(d), other, static_cast<float>(dist)) > 0.0f) {
                hit = true;
                ASSERT_TRUE(prims.count(gpu::kPrimTriangle << gpu::kPrimKindShift | u))
                    << "triangle " << u << " blocks a shadow ray from triangle " << t << " to light " << l
                    << " but no entry point reaches it";
              }
            }
            for (std::uint32_t s = 0; s < g.spheres.size(); ++s) {
              const glm::vec4 cr = g.spheres[s].centerRadius;
              if (segmentMeetsSphere(q, d, dist, glm::dvec3(glm::vec3(cr)), 1.0001 * cr.w)) {
                hit = true;
                ASSERT_TRUE(prims.count(gpu::kPrimSphere << gpu::kPrimKindShift | s))
                    << "sphere " << s << " blocks a shadow ray from triangle " << t << " to light " << l
                    << " but no entry point reaches it";
              }
            }
            blocked += hit;
          }
        }
      }
      // Not vacuous: some rays are blocked, and the entry points leave much of the scene out; on
      // the torus a good share of the pairs has nothing between (of four lights, one in the hole).
      EXPECT_GT(blocked, segments / 20) << blocked << " of " << segments << " segments blocked";
      EXPECT_EQ(nothing, g.shadowNothingPairs);
      if (std::string(c.name) == "torus") {
        EXPECT_GT(nothing, g.triangles.size() / 2) << "pairs marked nothing-between, of " << 4 * g.triangles.size();
      }
      const double perPair = static_cast<double>(reached) / (g.triangles.size() * g.lights.size());
      const std::size_t total = g.triangles.size() + g.spheres.size() + g.polygons.size();
      // (Subtrees of 64 leaves are a large part of these small scenes.)
      if (c.local && share <= 8) {
        EXPECT_LT(perPair, 0.6 * total) << "primitives reachable per (triangle, light) on average, of " << total;
      }
    }
  }
}

// "Nothing between" on the cases that decide it: neighbours that cannot shadow (a flat floor, a
// roof ridge, a valley the light shines into) and ones that do (a valley face the light grazes
// below its neighbour's plane, a triangle hovering within the margin, a sphere in the way). The
// triangles are found by their first vertex; the scene is packed around the origin.
TEST(ShadowEntries, NothingBetweenWhereNoNeighbourCanShadow) {
  struct Case {
    const char* name;
    std::vector<Tri> tris;
    glm::dvec3 light;
    std::vector<bool> nothing; // per triangle of `tris`
  };
  const Case cases[] = {
      {"flat floor",
       {{vec3(-1, 0, -1), vec3(-1, 0, 1), vec3(1, 0, 1)}, {vec3(1, 0, 1), vec3(1, 0, -1), vec3(-1, 0, -1)}},
       {0.3, 5.0, 0.2},
       {true, true}},
      {"roof ridge",
       {{vec3(0, 1, -1), vec3(0, 1, 1), vec3(-1, 0, 0)}, {vec3(0, 1, 1), vec3(0, 1, -1), vec3(1, 0, 0)}},
       {0.5, 6.0, 0.1},
       {true, true}},
      {"valley in the light",
       {{vec3(0, 0, -1), vec3(0, 0, 1), vec3(-1, 1, 0)}, {vec3(0, 0, 1), vec3(0, 0, -1), vec3(1, 1, 0)}},
       {0.2, 6.0, -0.1},
       {true, true}},
      // The light low on the right, below the right face's plane: the left face's rays to it cross
      // the right face.
      {"valley grazed",
       {{vec3(0, 0, -1), vec3(0, 0, 1), vec3(-1, 1, 0)}, {vec3(0, 0, 1), vec3(0, 0, -1), vec3(1, 1, 0)}},
       {20.0, 3.0, 0.0},
       {false, true}},
      // A small triangle 1e-5 above the floor's: it shadows part of it.
      {"hovering",
       {{vec3(-1, 0, -1), vec3(-1, 0, 1), vec3(1, 0, 1)},
        {vec3(-0.2f, 1e-5f, 0.3f), vec3(-0.1f, 1e-5f, 0.5f), vec3(0.1f, 1e-5f, 0.4f)}},
       {0.0, 5.0, 0.0},
       {false, true}},
  };
  // idScene's triangles alone, without its spheres and floor.
  auto bare = [](const std::vector<Tri>& tris, const glm::dvec3& light) {
    Scene scene = idScene(tris, true, BvhMode::On);
    scene.spheres.clear();
    scene.polygons.clear();
    scene.lights = {PointLight{light, glm::dvec3(1.0), true}};
    return scene;
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    GpuScene g = packScene(bare(c.tris, c.light), glm::dvec3(0.0), true);
    buildShadowEntries(g);
    ASSERT_EQ(g.shadowEntries.size(), 2 * c.tris.size());
    std::mt19937 rng(5);
    for (std::size_t i = 0; i < c.tris.size(); ++i) {
      std::uint32_t t = 0;
      while (t < g.triangles.size() && glm::vec3(g.triangles[t].v0) != c.tris[i].v0) ++t;
      ASSERT_LT(t, g.triangles.size());
      const bool marked = g.shadowEntries[2 * t + 1].w == gpu::kShadowNothingBetween;
      EXPECT_EQ(marked, c.nothing[i]) << "triangle " << i;
      if (marked) expectNothingBetween(g, t, c.light, rng);
    }
  }
  // The grazed valley's left face is shadowed by its neighbour in fact: the expectation is not
  // only the builder's caution.
  const glm::dvec3 right[3] = {{0, 0, 1}, {0, 0, -1}, {1, 1, 0}};
  EXPECT_TRUE(segmentMeetsTriangle(glm::dvec3(-0.5, 0.5, 0.0), glm::dvec3(20.0, 3.0, 0.0), right));

  // A sphere between a floor and its light: a primitive the builder does not clear.
  Scene scene = bare(cases[0].tris, {0.0, 5.0, 0.0});
  Sphere ball;
  ball.center = {0.0, 2.0, 0.0};
  ball.radius = 0.5;
  ball.material = 0;
  scene.spheres.push_back(ball);
  GpuScene g = packScene(scene, glm::dvec3(0.0), true);
  buildShadowEntries(g);
  EXPECT_EQ(g.shadowNothingPairs, 0u);
}

// Real meshes (the bundled scenes' OBJ, glTF and PLY files, with their analytic sphere and their
// lights, and models from Debian's assimp-testmodels with the lights vkray gives a bare model): a
// sample of the marked pairs, checked by brute force as above. The meshes are closed or open,
// welded or not, smooth or faceted; a mark must hold on each.
TEST(ShadowEntries, NothingBetweenHoldsOnRealMeshes) {
  const std::string models = "/usr/share/assimp/models/";
  for (const std::string& file : {test::scenePath("meshes.json"), test::scenePath("textured.json"),
                                  models + "OBJ/spider.obj", models + "PLY/Wuson.ply", models + "OBJ/regr01.obj"}) {
    SCOPED_TRACE(file);
    Scene scene = loadScene(file);
    GpuScene g = packScene(scene, scene.camera.position, true);
    buildShadowEntries(g);
    ASSERT_FALSE(g.shadowEntries.empty());
    const std::size_t pairs = g.triangles.size() * g.lights.size();
    // (On the models most pairs face away from their light or lie in another part's shadow.)
    EXPECT_GT(g.shadowNothingPairs, pairs / 100) << "of " << pairs << " pairs";
    std::mt19937 rng(3);
    std::size_t checked = 0;
    for (std::size_t pair = 0; pair < pairs; pair += 1 + rng() % 8) {
      if (g.shadowEntries[2 * pair + 1].w != gpu::kShadowNothingBetween) continue;
      const auto t = static_cast<std::uint32_t>(pair / g.lights.size());
      const gpu::Light& light = g.lights[pair % g.lights.size()];
      expectNothingBetween(g, t, glm::dvec3(glm::vec3(light.position)), rng);
      if (HasFatalFailure()) return;
      ++checked;
    }
    EXPECT_GT(checked, 10u);
  }
}

// Scenes the table leaves alone: no BVH, no light that casts shadows, too many lights.
TEST(ShadowEntries, BuiltOnlyWhereTheKernelCanUseThem) {
  Scene scene = idScene(torus(8, 4), true, BvhMode::On);
  GpuScene g = packScene(scene, scene.camera.position, true);
  buildShadowEntries(g);
  EXPECT_EQ(g.shadowEntries.size(), 2 * g.triangles.size());
  // A light without shadows gets no entries (its shadow rays are never traced); with none that
  // casts shadows there is no table.
  scene.lights.push_back(PointLight{glm::dvec3(-3.0, 5.0, 1.0), glm::dvec3(1.0), false});
  GpuScene mixed = packScene(scene, scene.camera.position, true);
  buildShadowEntries(mixed);
  ASSERT_EQ(mixed.shadowEntries.size(), 4 * mixed.triangles.size());
  for (std::size_t t = 0; t < mixed.triangles.size(); ++t) {
    // Entry points, or the mark that nothing lies between the triangle and the light.
    EXPECT_TRUE(mixed.shadowEntries[4 * t].x != gpu::kBvhNoRef ||
                mixed.shadowEntries[4 * t + 1].w == gpu::kShadowNothingBetween)
        << "triangle " << t << ", the light with shadows";
    EXPECT_EQ(mixed.shadowEntries[4 * t + 2].x, gpu::kBvhNoRef) << "triangle " << t << ", the light without";
    EXPECT_EQ(mixed.shadowEntries[4 * t + 3].w, 0u) << "triangle " << t << ", the light without: from the root";
  }
  scene.lights[0].shadows = false;
  GpuScene unshadowed = packScene(scene, scene.camera.position, true);
  buildShadowEntries(unshadowed);
  EXPECT_TRUE(unshadowed.shadowEntries.empty());
  scene.lights.pop_back();
  scene.lights[0].shadows = true;
  GpuScene noBvh = packScene(scene, scene.camera.position, false);
  buildShadowEntries(noBvh);
  EXPECT_TRUE(noBvh.shadowEntries.empty());
  for (std::uint32_t i = 0; i < gpu::kShadowEntryLightsMax; ++i)
    scene.lights.push_back(PointLight{glm::dvec3(i, 5.0, 0.0), glm::dvec3(1.0), true});
  GpuScene many = packScene(scene, scene.camera.position, true);
  buildShadowEntries(many);
  EXPECT_TRUE(many.shadowEntries.empty());
}

// On the GPU: shadow rays from their entry points decide exactly as from the root, in the query
// kernel and in the renderer's, with opaque and with transmissive occluders (several crossings,
// each segment starting from the triangle it left), and with several lights.
TEST(GpuBvh, ShadowEntryPointsCastTheSameShadows) {
  Renderer& renderer = test::renderer();
  for (bool glass : {false, true}) {
    SCOPED_TRACE(glass ? "transmissive occluders" : "opaque occluders");
    Scene scene = idScene(torus(48, 24), true, BvhMode::On);
    scene.lights.push_back(PointLight{glm::dvec3(-4.0, 3.0, 5.0), glm::dvec3(0.6), true});
    scene.lights.push_back(PointLight{glm::dvec3(0.0, 0.3, 0.0), glm::dvec3(0.4), true}); // in the hole
    if (glass) {
      for (std::size_t i = 0; i < scene.materials.size(); i += 2) scene.materials[i].transmission = 0.6;
    }
    scene.render.width = 120;
    scene.render.height = 90;
    renderer.setScene(scene);
    RenderOptions off;
    off.shadowEntryPoints = ShadowEntries::Off;
    RenderOptions on;
    on.shadowEntryPoints = ShadowEntries::On;
    RenderResult a = renderer.render(scene.camera, scene.render, off);
    EXPECT_TRUE(renderer.gpuScene().shadowEntries.empty()) << "off builds no table";
    RenderResult b = renderer.render(scene.camera, scene.render, on);
    ASSERT_FALSE(renderer.gpuScene().shadowEntries.empty()) << "on builds the table";
    EXPECT_GT(renderer.gpuScene().shadowNothingPairs, renderer.gpuScene().triangles.size() / 4)
        << "on marks the pairs with nothing between, and the torus has many";
    EXPECT_TRUE(b.features.useBvh);
    test::expectNoValidationMessages();
    ASSERT_EQ(a.image.pixels.size(), b.image.pixels.size());
    std::size_t shadowed = 0;
    for (std::size_t i = 0; i < a.image.pixels.size(); ++i) {
      ASSERT_EQ(std::memcmp(&a.image.pixels[i], &b.image.pixels[i], sizeof(glm::vec3)), 0) << "pixel " << i;
    }
    EXPECT_EQ(a.stats.shadow, b.stats.shadow);
    EXPECT_GT(a.stats.shadow, 0u);
    if (!glass) {
      RenderOptions qOff = off, qOn = on;
      qOff.kernel = qOn.kernel = Kernel::Hits;
      RenderResult c = renderer.render(scene.camera, scene.render, qOff);
      RenderResult d = renderer.render(scene.camera, scene.render, qOn);
      ASSERT_EQ(c.hits.size(), d.hits.size());
      for (std::size_t i = 0; i < c.hits.size(); ++i) {
        ASSERT_EQ(c.hits[i].w, d.hits[i].w) << "pixel " << i << ": the shadow ray decided otherwise";
        shadowed += c.hits[i].w > 0.0f;
      }
      EXPECT_GT(shadowed, c.hits.size() / 50) << "the view must show shadows";
    }
  }
}

// Naive numerics start shadow rays on the surface and show the acne that comes of it: the kernel
// walks the tree for the pairs marked "nothing between" there too, so the table changes nothing.
TEST(GpuBvh, NaiveShadowRaysIgnoreNothingBetween) {
  Renderer& renderer = test::renderer();
  // 3000 times the usual size, so that naive hit points are off by more than their epsilon.
  const double k = 3000.0;
  std::vector<Tri> tris = torus(48, 24);
  for (Tri& t : tris) t = Tri{t.v0 * float(k), t.v1 * float(k), t.v2 * float(k)};
  Scene scene = idScene(tris, true, BvhMode::On);
  scene.spheres.clear();
  scene.polygons.clear();
  scene.camera.position *= k;
  scene.lights = {PointLight{glm::dvec3(-4.0, 3.0, 5.0) * k, glm::dvec3(0.6), true}};
  scene.render.width = 120;
  scene.render.height = 90;
  scene.render.numerics = Numerics::Naive;
  renderer.setScene(scene);
  RenderOptions off, on;
  off.shadowEntryPoints = ShadowEntries::Off;
  on.shadowEntryPoints = ShadowEntries::On;
  RenderResult a = renderer.render(scene.camera, scene.render, off);
  RenderResult b = renderer.render(scene.camera, scene.render, on);
  EXPECT_GT(renderer.gpuScene().shadowNothingPairs, 0u);
  test::expectNoValidationMessages();
  ASSERT_EQ(a.image.pixels.size(), b.image.pixels.size());
  for (std::size_t i = 0; i < a.image.pixels.size(); ++i)
    ASSERT_EQ(std::memcmp(&a.image.pixels[i], &b.image.pixels[i], sizeof(glm::vec3)), 0) << "pixel " << i;
  EXPECT_EQ(a.stats.shadow, b.stats.shadow);
  // Not vacuous: there is acne to keep, pixels the robust origins light.
  scene.render.numerics = Numerics::Robust;
  RenderResult robust = renderer.render(scene.camera, scene.render, off);
  std::size_t acne = 0;
  for (std::size_t i = 0; i < a.image.pixels.size(); ++i)
    acne += glm::length(robust.image.pixels[i]) > glm::length(a.image.pixels[i]) + 1e-3f;
  EXPECT_GT(acne, 10u) << "pixels lit with robust origins and dark with naive ones";
}

// Auto builds the table once the render's samples pay for it, and keeps it for the scene.
TEST(GpuBvh, ShadowEntryPointsAreBuiltWhenTheyPay) {
  Renderer& renderer = test::renderer();
  Scene scene = idScene(torus(48, 24), true, BvhMode::On); // 2304 triangles
  scene.render.width = 48;
  scene.render.height = 36; // 1728 pixels: a sample of each is under one shadow ray per triangle
  renderer.setScene(scene);
  RenderOptions automatic;
  RenderResult one = renderer.render(scene.camera, scene.render, automatic);
  EXPECT_TRUE(renderer.gpuScene().shadowEntries.empty());
  EXPECT_NE(renderer.shadowEntriesSkipped().find("too few pixel samples"), std::string::npos)
      << renderer.shadowEntriesSkipped();
  // 8 x 1728 pixel samples: 6 per triangle, enough for the entry points (4), not for the marks (32).
  scene.render.spp = 8;
  renderer.render(scene.camera, scene.render, automatic);
  EXPECT_FALSE(renderer.gpuScene().shadowEntries.empty()) << renderer.shadowEntriesSkipped();
  EXPECT_FALSE(renderer.gpuScene().shadowNothingBetween);
  EXPECT_NE(renderer.shadowNothingSkipped().find("too few pixel samples"), std::string::npos)
      << renderer.shadowNothingSkipped();
  // 64 x 1728: 48 per triangle, and the table is built again with the marks.
  scene.render.spp = 64;
  renderer.render(scene.camera, scene.render, automatic);
  EXPECT_TRUE(renderer.gpuScene().shadowNothingBetween);
  EXPECT_GT(renderer.gpuScene().shadowNothingPairs, 0u);
  scene.render.spp = 1;
  RenderResult again = renderer.render(scene.camera, scene.render, automatic);
  EXPECT_FALSE(renderer.gpuScene().shadowEntries.empty()) << "kept for the scene";
  EXPECT_TRUE(renderer.gpuScene().shadowNothingBetween) << "kept for the scene";
  // The viewer accumulates without end: both parts at its first frame, for a mesh whose marks
  // take a small part of a second.
  renderer.setScene(scene);
  RenderOptions viewer = automatic;
  viewer.progressive = true;
  renderer.prepare(scene.camera, scene.render, viewer);
  EXPECT_TRUE(renderer.gpuScene().shadowNothingBetween) << renderer.shadowNothingSkipped();
  EXPECT_GT(renderer.gpuScene().shadowNothingPairs, 0u);
  // Over 250 000 pairs the viewer's first frame does not wait for the marks.
  Scene large = idScene(torus(361, 360), true, BvhMode::On); // 259 920 triangles, one light
  large.render.width = 48;
  large.render.height = 36;
  renderer.setScene(large);
  renderer.prepare(large.camera, large.render, viewer);
  EXPECT_FALSE(renderer.gpuScene().shadowEntries.empty()) << renderer.shadowEntriesSkipped();
  EXPECT_FALSE(renderer.gpuScene().shadowNothingBetween);
  EXPECT_NE(renderer.shadowNothingSkipped().find("would hold up the first frame"), std::string::npos)
      << renderer.shadowNothingSkipped();
  test::expectNoValidationMessages();
  for (std::size_t i = 0; i < one.image.pixels.size(); ++i) {
    ASSERT_EQ(std::memcmp(&one.image.pixels[i], &again.image.pixels[i], sizeof(glm::vec3)), 0) << "pixel " << i;
  }
}

} // namespace
} // namespace vkray
