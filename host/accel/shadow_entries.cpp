// Shadow entry points (see shadow_entries.h).
#include "accel/shadow_entries.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <thread>
#include <utility>

namespace vkray {
namespace {

// A convex region that holds the convex hull of some points, widened by a margin: their bounding
// box and slabs on up to four more axes. A box is kept unless it misses one of them (a separating
// axis); every axis gives a valid test, so a degenerate one is simply left out.
struct Region {
  glm::dvec3 lo, hi;
  std::array<glm::dvec3, 4> axis;
  std::array<double, 4> amin, amax;
  int axes = 0;

  Region(const glm::dvec3* points, int count, const glm::dvec3* candidates, int candidateCount, double margin) {
    lo = hi = points[0];
    for (int k = 1; k < count; ++k) {
      lo = glm::min(lo, points[k]);
      hi = glm::max(hi, points[k]);
    }
    lo -= margin;
    hi += margin;
    for (int c = 0; c < candidateCount; ++c) {
      const double len = glm::length(candidates[c]);
      if (!(len > 0.0) || !std::isfinite(len)) continue;
      const glm::dvec3 n = candidates[c] / len;
      double mn = glm::dot(n, points[0]), mx = mn;
      for (int k = 1; k < count; ++k) {
        mn = std::min(mn, glm::dot(n, points[k]));
        mx = std::max(mx, glm::dot(n, points[k]));
      }
      axis[axes] = n;
      amin[axes] = mn - margin;
      amax[axes] = mx + margin;
      ++axes;
    }
  }

  bool meets(const glm::vec3& bmin, const glm::vec3& bmax) const {
    const glm::dvec3 b0(bmin), b1(bmax);
    if (b0.x > hi.x || b0.y > hi.y || b0.z > hi.z || b1.x < lo.x || b1.y < lo.y || b1.z < lo.z) return false;
    const glm::dvec3 c = 0.5 * (b0 + b1), h = 0.5 * (b1 - b0);
    for (int k = 0; k < axes; ++k) {
      const double centre = glm::dot(axis[k], c);
      const double radius = glm::dot(glm::abs(axis[k]), h);
      if (centre + radius < amin[k] || centre - radius > amax[k]) return false;
    }
    return true;
  }
};

double magnitude(const glm::dvec3& p) {
  return std::max({std::abs(p.x), std::abs(p.y), std::abs(p.z)});
}

// What hull(T, light) is widened by: kShadowEntryMargin of the coordinates' magnitude.
double triangleMargin(const glm::dvec3 v[3], const glm::dvec3& light) {
  const double scale =
      std::max({magnitude(v[0]), magnitude(v[1]), magnitude(v[2]), magnitude(light)}) + glm::length(light - v[0]);
  return kShadowEntryMargin * scale;
}

// hull(T, light): the triangle's plane and the three faces through the light.
Region triangleHull(const glm::dvec3 v[3], const glm::dvec3& light) {
  const glm::dvec3 points[4] = {v[0], v[1], v[2], light};
  const glm::dvec3 axes[4] = {glm::cross(v[1] - v[0], v[2] - v[0]), glm::cross(v[1] - v[0], light - v[0]),
                              glm::cross(v[2] - v[1], light - v[1]), glm::cross(v[0] - v[2], light - v[2])};
  return Region(points, 4, axes, 4, triangleMargin(v, light));
}

// A region around hull(box, light): the box of all nine points and the three axes across the
// box-to-light direction.
Region boxHull(const glm::vec3& bmin, const glm::vec3& bmax, const glm::dvec3& light) {
  const glm::dvec3 b0(bmin), b1(bmax);
  glm::dvec3 points[9];
  for (int k = 0; k < 8; ++k) points[k] = glm::dvec3(k & 1 ? b1.x : b0.x, k & 2 ? b1.y : b0.y, k & 4 ? b1.z : b0.z);
  points[8] = light;
  const glm::dvec3 d = light - 0.5 * (b0 + b1);
  const double scale =
      std::max({magnitude(b0), magnitude(b1), magnitude(light)}) + glm::length(d) + glm::length(b1 - b0);
  const glm::dvec3 axes[3] = {glm::cross(glm::dvec3(1, 0, 0), d), glm::cross(glm::dvec3(0, 1, 0), d),
                              glm::cross(glm::dvec3(0, 0, 1), d)};
  return Region(points, 9, axes, 3, kShadowEntryMargin * scale);
}

constexpr int kMaxEntries = static_cast<int>(gpu::kShadowEntryMax);
constexpr std::size_t kBvhStackLimit = 2 * gpu::kBvhStackSize; // depth-first below seven entries

// The texels of a (triangle, light) whose shadow rays nothing in the tree can stop.
const std::array<glm::uvec4, 2> kNothing = {
    glm::uvec4(gpu::kBvhNoRef), glm::uvec4(gpu::kBvhNoRef, gpu::kBvhNoRef, gpu::kBvhNoRef, gpu::kShadowNothingBetween)};

struct Entry {
  std::uint32_t ref = gpu::kBvhNoRef;
  glm::vec3 min{0.0f}, max{0.0f};
  float area = -1.0f; // of the box, for the order of opening; -1: not to be opened (a leaf, or no room)
};

Entry entry(std::uint32_t ref, const glm::vec3& min, const glm::vec3& max) {
  Entry e{ref, min, max, -1.0f};
  if (ref < gpu::kBvhLeafFlag) {
    const glm::vec3 d = max - min;
    e.area = d.x * d.y + d.y * d.z + d.z * d.x;
  }
  return e;
}

// A set of at most kMaxEntries subtrees that together hold every primitive a region may meet.
struct EntrySet {
  std::array<Entry, kMaxEntries> e;
  int n = 0;
};

double diagonal(const glm::vec3& min, const glm::vec3& max) {
  return glm::length(glm::dvec3(max) - glm::dvec3(min));
}

// Refines `set`, which covers a region holding `region`, to cover `region` alone: entries it
// misses are dropped, then the largest entry is opened (replaced by those of its children the
// region meets) while the set has room. An entry is never dropped for want of room, so the set
// stays conservative.
//
// An entry costs every ray a step, since its box was tested against the region, not the ray: from
// a node a step tests both children against the ray, from the two children as entries it takes
// two steps whatever the ray. Opening a node with one child in the region saves a step; opening
// one with both pays only where the rays hit both children, which they do where the children are
// large against the rays' source (`source`: the diagonal of the triangle or subtree box they
// leave). So a node grows the set only where each child's box is at least that large: a large
// triangle, a floor under a scene, keeps a set no larger than a walk from the root needs.
void refine(const Region& region, const std::vector<gpu::BvhWideNode>& nodes, EntrySet& set, double source) {
  int kept = 0;
  for (int i = 0; i < set.n; ++i) {
    if (region.meets(set.e[i].min, set.e[i].max)) {
      set.e[kept] = set.e[i];
      set.e[kept].area = entry(set.e[i].ref, set.e[i].min, set.e[i].max).area;
      ++kept;
    }
  }
  set.n = kept;
  while (true) {
    int pick = -1;
    float best = -1.0f;
    for (int i = 0; i < set.n; ++i) {
      if (set.e[i].area > best) {
        best = set.e[i].area;
        pick = i;
      }
    }
    if (pick < 0) break;
    const gpu::BvhWideNode& node = nodes[set.e[pick].ref];
    const bool in0 = region.meets(node.min0, node.max0);
    const bool in1 = region.meets(node.min1, node.max1);
    const bool grows = in0 && in1;
    if (set.n - 1 + int(in0) + int(in1) > kMaxEntries ||
        (grows && std::min(diagonal(node.min0, node.max0), diagonal(node.min1, node.max1)) < source)) {
      set.e[pick].area = -1.0f; // no room to open it, or no gain
      continue;
    }
    set.e[pick] = set.e[set.n - 1];
    --set.n;
    if (in0) set.e[set.n++] = entry(node.ref0, node.min0, node.max0);
    if (in1) set.e[set.n++] = entry(node.ref1, node.min1, node.max1);
  }
}

// The two texels of a set: the entry nearest `near` to start at (an occluder close to the
// surface ends the walk soonest), the farthest at the bottom of the stack.
std::array<glm::uvec4, 2> pack(EntrySet set, const glm::dvec3& near) {
  // Insertion sort by distance: at most seven entries.
  std::array<double, kMaxEntries> distance{};
  for (int i = 0; i < set.n; ++i) {
    const Entry e = set.e[i];
    const double d = glm::length(glm::clamp(near, glm::dvec3(e.min), glm::dvec3(e.max)) - near);
    int j = i;
    for (; j > 0 && distance[j - 1] > d; --j) {
      distance[j] = distance[j - 1];
      set.e[j] = set.e[j - 1];
    }
    distance[j] = d;
    set.e[j] = e;
  }
  std::array<std::uint32_t, 8> words;
  words.fill(gpu::kBvhNoRef);
  if (set.n > 0) words[0] = set.e[0].ref;
  for (int i = 1; i < set.n; ++i) words[i] = set.e[set.n - i].ref;
  words[7] = static_cast<std::uint32_t>(std::max(set.n - 1, 0));
  return {glm::uvec4(words[0], words[1], words[2], words[3]), glm::uvec4(words[4], words[5], words[6], words[7])};
}

glm::dvec3 vertex(const glm::vec4& v) {
  return glm::dvec3(glm::vec3(v));
}

// ---- Nothing between -------------------------------------------------------------------------------

// Which side of the plane through `a` with normal n = cross(b - a, c - a) a point lies on, and a
// bound on the rounding of that value. Every coordinate is a float held in a double, so the
// computed value is within 8 epsilon of the "permanent" (the same products with every term's
// absolute value; Shewchuk, "Adaptive Precision Floating-Point Arithmetic and Fast Robust
// Geometric Predicates", 1997): 16 epsilon is the bound used.
struct Plane {
  glm::dvec3 a, n, nAbs;
  Plane(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) : a(a) {
    const glm::dvec3 e1 = b - a, e2 = c - a;
    n = glm::cross(e1, e2);
    nAbs = glm::dvec3(std::abs(e1.y * e2.z) + std::abs(e1.z * e2.y), std::abs(e1.z * e2.x) + std::abs(e1.x * e2.z),
                      std::abs(e1.x * e2.y) + std::abs(e1.y * e2.x));
  }
  double value(const glm::dvec3& x) const { return glm::dot(n, x - a); }
  double bound(const glm::dvec3& x) const { return 16.0 * 0x1p-53 * glm::dot(nAbs, glm::abs(x - a)); }
  // +1 or -1 where the side is certain, 0 where rounding could decide it.
  int sign(const glm::dvec3& x) const {
    const double v = value(x);
    return v > bound(x) ? 1 : (v < -bound(x) ? -1 : 0);
  }
  // Whether x lies on side `s` (+1 or -1) or on the plane, as far as rounding can tell.
  bool onSideOrPlane(const glm::dvec3& x, int s) const { return s * value(x) >= -bound(x); }
};

// Whether triangle w (three vertices) and the tetrahedron k (four) widened by `margin` are
// separated along some axis: the faces of both, and the cross products of their edges (with the
// coordinate axes, which the caller has tested on w's box, the separating-axis theorem for two
// convex polyhedra).
bool separated(const glm::dvec3 w[3], const glm::dvec3 k[4], double margin) {
  auto apart = [&](const glm::dvec3& axis) {
    const double len = glm::length(axis);
    if (!(len > 0.0) || !std::isfinite(len)) return false; // no axis: a degenerate cross product
    double w0 = glm::dot(axis, w[0]), w1 = w0, k0 = glm::dot(axis, k[0]), k1 = k0;
    for (int i = 1; i < 3; ++i) {
      const double d = glm::dot(axis, w[i]);
      w0 = std::min(w0, d);
      w1 = std::max(w1, d);
    }
    for (int i = 1; i < 4; ++i) {
      const double d = glm::dot(axis, k[i]);
      k0 = std::min(k0, d);
      k1 = std::max(k1, d);
    }
    return w1 < k0 - margin * len || w0 > k1 + margin * len;
  };
  const glm::dvec3 we[3] = {w[1] - w[0], w[2] - w[1], w[0] - w[2]};
  const glm::dvec3 ke[6] = {k[1] - k[0], k[2] - k[1], k[0] - k[2], k[3] - k[0], k[3] - k[1], k[3] - k[2]};
  if (apart(glm::cross(ke[0], -ke[2])) || apart(glm::cross(ke[0], ke[3])) || apart(glm::cross(ke[1], ke[4])) ||
      apart(glm::cross(ke[2], ke[5])) || apart(glm::cross(we[0], we[1])))
    return true;
  for (const glm::dvec3& a : we)
    for (const glm::dvec3& b : ke)
      if (apart(glm::cross(a, b))) return true;
  return false;
}

// Whether triangle w meets the tetrahedron k = hull(v, p) only where it shares vertices with v (a
// mesh's neighbours of v). Both touch at a shared vertex `a`, so a plane that separates them
// passes through it: each plane through `a` and two more of their vertices (w's plane, a face of
// k, or one spanned by an edge of each) is tried, and it separates them when the vertices of w
// not on it lie strictly on one side and those of k strictly on the other, as the exact
// orientation (Plane::sign) says. Then w and k meet only in the plane, where w holds the shared
// vertices and its spanning ones, k the shared and its own: at most the shared edge or vertex,
// part of v itself, which no shadow ray leaving v meets again.
bool touchesOnlyAtShared(const glm::dvec3 w[3], const glm::dvec3 k[4]) {
  // The points: shared ones (in w and in v, k's first three), then w's own, then k's own.
  std::array<glm::dvec3, 7> point;
  std::array<int, 7> owner; // 0: shared, 1: w alone, 2: k alone
  int n = 0, shared = 0;
  bool wShared[3] = {false, false, false}, kShared[4] = {false, false, false, false};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      if (w[i] == k[j]) wShared[i] = kShared[j] = true;
    }
    if (wShared[i]) {
      point[n] = w[i];
      owner[n++] = 0;
      ++shared;
    }
  }
  if (shared == 0) return false;
  if (shared == 3) return true; // w is v again: it lies in v's plane, which the rays leave
  for (int i = 0; i < 3; ++i) {
    if (!wShared[i]) {
      point[n] = w[i];
      owner[n++] = 1;
    }
  }
  for (int j = 0; j < 4; ++j) {
    if (!kShared[j]) {
      point[n] = k[j];
      owner[n++] = 2;
    }
  }
  // Every shared point must lie in the plane, so with two shared the second spans it.
  for (int x = 1; x < n; ++x) {
    for (int y = x + 1; y < n; ++y) {
      if (shared == 2 && x != 1) continue;
      const Plane plane(point[0], point[x], point[y]);
      int wSide = 0, kSide = 0;
      bool apart = true;
      for (int z = 1; z < n && apart; ++z) {
        if (z == x || z == y) continue;
        const int s = plane.sign(point[z]);
        int& side = owner[z] == 1 ? wSide : kSide;
        apart = s != 0 && owner[z] != 0 && (side == 0 || side == s);
        side = s;
      }
      if (apart && wSide * kSide <= 0) return true;
    }
  }
  return false;
}

// Whether triangle w can stop no shadow ray that leaves a point of triangle v for light p (the
// segments from v's points to p, less their first point). Three ways, each enough alone:
//  - w lies on the far side of v's plane from the light (or in it): every segment leaves that
//    plane at its first point and stays on the light's side. A convex neighbour.
//  - v and the light lie on the same side of w's plane (v may touch it), the light strictly:
//    no segment crosses that plane. A concave neighbour, in a valley the light shines into.
//  - w lies farther than `margin` from hull(v, p), which holds every segment.
// The first two are decided exactly but for rounding below 16 epsilon of the coordinates (the
// bounds of Plane); a point within that of a plane counts as on it. Such a sliver is eight orders
// of magnitude below the offset of the kernel's shadow-ray origin off the surface, towards the light
// (spawnOrigin), so a ray from that origin cannot meet what the rounding might hide.
bool cannotStop(const glm::dvec3 w[3], const glm::dvec3 v[3], const glm::dvec3& p, const Plane& vPlane, int lightSide,
                double margin) {
  if (vPlane.onSideOrPlane(w[0], -lightSide) && vPlane.onSideOrPlane(w[1], -lightSide) &&
      vPlane.onSideOrPlane(w[2], -lightSide))
    return true;

  const Plane wPlane(w[0], w[1], w[2]);
  const int s = wPlane.sign(p);
  if (s != 0 && wPlane.onSideOrPlane(v[0], s) && wPlane.onSideOrPlane(v[1], s) && wPlane.onSideOrPlane(v[2], s))
    return true;
  const glm::dvec3 k[4] = {v[0], v[1], v[2], p};
  return touchesOnlyAtShared(w, k) || separated(w, k, margin);
}

// One light's part of the table, built top down from the root.
struct Builder {
  const ShadowEntryInput& in;
  const ShadowEntryOptions& options;
  const std::vector<std::uint32_t>& leaves; // leaves under each interior record
  std::vector<glm::uvec4>& table;

  std::uint32_t leafCount(std::uint32_t ref) const { return ref >= gpu::kBvhLeafFlag ? 1u : leaves[ref]; }

  void write(std::uint32_t triangle, std::size_t light, const std::array<glm::uvec4, 2>& texels) const {
    const std::size_t at = 2 * (triangle * in.lights.size() + light);
    table[at] = texels[0];
    table[at + 1] = texels[1];
  }

  // The leaf entries [first, end) of a leaf reference (bvh.glsl's leafEntries).
  static std::pair<std::uint32_t, std::uint32_t> leafEntries(std::uint32_t ref) {
    const std::uint32_t first = ref & gpu::kBvhLeafFirstMask;
    return {first, first + ((ref >> gpu::kBvhLeafCountShift) & 15u) + 1u};
  }

  // Calls f(triangle index) for every triangle under `ref`.
  template <typename F> void forTriangles(std::uint32_t ref, F&& f) const {
    if (ref < gpu::kBvhLeafFlag) {
      forTriangles(in.nodes[ref].ref0, f);
      forTriangles(in.nodes[ref].ref1, f);
      return;
    }
    const auto [first, end] = leafEntries(ref);
    for (std::uint32_t k = first; k < end; ++k) {
      const std::uint32_t prim = in.primRefs[k];
      if ((prim >> gpu::kPrimKindShift) == gpu::kPrimTriangle) f(prim & gpu::kPrimIndexMask);
    }
  }

  // Walks the subtrees of `set` depth first into every box `meets` keeps, and calls visit(leaf
  // entry) for each primitive reached. True when the walk is complete; false as soon as `visit`
  // returns false, or once it has tested more than `maxBoxes` boxes (or would overflow its stack).
  template <typename Meets, typename Visit>
  bool walk(const EntrySet& set, Meets&& meets, Visit&& visit, int maxBoxes) const {
    std::array<std::uint32_t, kBvhStackLimit> stack;
    int sp = 0;
    int boxes = 0;
    for (int i = 0; i < set.n; ++i) {
      ++boxes;
      if (meets(set.e[i].min, set.e[i].max)) stack[sp++] = set.e[i].ref;
    }
    while (sp > 0) {
      const std::uint32_t ref = stack[--sp];
      if (ref < gpu::kBvhLeafFlag) {
        const gpu::BvhWideNode& node = in.nodes[ref];
        boxes += 2;
        if (boxes > maxBoxes || sp + 2 > static_cast<int>(stack.size())) return false;
        if (meets(node.min0, node.max0)) stack[sp++] = node.ref0;
        if (meets(node.min1, node.max1)) stack[sp++] = node.ref1;
        continue;
      }
      const auto [first, end] = leafEntries(ref);
      for (std::uint32_t e = first; e < end; ++e)
        if (!visit(in.primRefs[e])) return false;
    }
    return true;
  }

  // Whether the ray from t's centroid to light p meets another triangle under the entries of
  // `set`: most pairs that are not "nothing between" (a light on the inner side of a closed mesh)
  // show it on this one ray, before nothingBetween() looks at every neighbour. Only a shortcut:
  // an answer that is wrong either way costs time, never a shadow (a walk cut short counts as
  // blocked).
  bool probeBlocked(std::uint32_t t, const glm::dvec3 v[3], const glm::dvec3& p, const EntrySet& set) const {
    const glm::dvec3 o = (v[0] + v[1] + v[2]) / 3.0;
    const glm::dvec3 d = p - o;
    const glm::dvec3 inv = 1.0 / d; // +-inf on an axis the ray does not move along
    auto crosses = [&](const glm::vec3& bmin, const glm::vec3& bmax) {
      double enter = 0.0, leave = 1.0;
      for (int i = 0; i < 3; ++i) {
        double t0 = (double(bmin[i]) - o[i]) * inv[i], t1 = (double(bmax[i]) - o[i]) * inv[i];
        if (std::isnan(t0) || std::isnan(t1)) return true; // on a face of the box: keep it
        enter = std::max(enter, std::min(t0, t1));
        leave = std::min(leave, std::max(t0, t1));
      }
      return enter <= leave;
    };
    // Moller-Trumbore in double, the segment's ends left out: true where the ray misses.
    auto misses = [&](std::uint32_t prim) {
      if ((prim >> gpu::kPrimKindShift) != gpu::kPrimTriangle || (prim & gpu::kPrimIndexMask) == t) return true;
      const gpu::Triangle& tri = in.triangles[prim & gpu::kPrimIndexMask];
      const glm::dvec3 a = vertex(tri.v0), e1 = vertex(tri.v1) - a, e2 = vertex(tri.v2) - a;
      const glm::dvec3 q = glm::cross(d, e2);
      const double det = glm::dot(e1, q);
      if (det == 0.0) return true;
      const glm::dvec3 s = (o - a) / det;
      const double b1 = glm::dot(s, q);
      const glm::dvec3 r = glm::cross(s, e1);
      const double b2 = glm::dot(d, r);
      const double along = glm::dot(e2, r);
      return !(b1 >= 0.0 && b2 >= 0.0 && b1 + b2 <= 1.0 && along > 1e-9 && along < 1.0);
    };
    return !walk(set, crosses, misses, std::numeric_limits<int>::max());
  }

  // Whether nothing in the tree but triangle t itself can stop a shadow ray from t to light p:
  // every primitive under the entries of `set` (which cover hull(t, p)) whose box meets the hull
  // is t or a triangle cannotStop() clears. Other kinds of primitive, and hulls that meet more
  // boxes than kNothingBetweenBoxes (a triangle with a long way to its light), are not looked at
  // further: the walk decides for them.
  static constexpr int kNothingBetweenBoxes = 512;
  bool nothingBetween(std::uint32_t t, const glm::dvec3 v[3], const glm::dvec3& p, const EntrySet& set,
                      bool probe = true) const {
    const Plane plane(v[0], v[1], v[2]);
    const int lightSide = plane.sign(p);
    if (lightSide == 0) return false; // the light in the triangle's plane: no lit side
    if (probe && probeBlocked(t, v, p, set)) return false;
    const double margin = triangleMargin(v, p);
    const Region hull = triangleHull(v, p);
    auto meets = [&](const glm::vec3& bmin, const glm::vec3& bmax) { return hull.meets(bmin, bmax); };
    auto cleared = [&](std::uint32_t prim) {
      if ((prim >> gpu::kPrimKindShift) != gpu::kPrimTriangle) return false;
      const std::uint32_t u = prim & gpu::kPrimIndexMask;
      if (u == t) return true;
      const gpu::Triangle& tri = in.triangles[u];
      const glm::vec3 a(tri.v0), b(tri.v1), c(tri.v2);
      if (!hull.meets(glm::min(glm::min(a, b), c), glm::max(glm::max(a, b), c)))
        return true; // its box lies beyond the widened hull
      const glm::dvec3 w[3] = {glm::dvec3(a), glm::dvec3(b), glm::dvec3(c)};
      return cannotStop(w, v, p, plane, lightSide, margin);
    };
    return walk(set, meets, cleared, kNothingBetweenBoxes);
  }

  // `set` covers the region of the node's parent; `tasks` (the top of the tree) collects the
  // nodes at `splitDepth` instead of descending into them, for the threads.
  struct Task {
    std::uint32_t ref;
    glm::vec3 min, max;
    EntrySet set;
  };
  void visit(std::uint32_t ref, const glm::vec3& bmin, const glm::vec3& bmax, EntrySet set, std::size_t light,
             int depth, int splitDepth, std::vector<Task>* tasks) const {
    if (tasks != nullptr && depth == splitDepth) {
      tasks->push_back({ref, bmin, bmax, set});
      return;
    }
    const glm::dvec3 p = in.lights[light];
    refine(boxHull(bmin, bmax, p), in.nodes, set, diagonal(bmin, bmax));
    const bool leaf = ref >= gpu::kBvhLeafFlag;
    if (options.shareBelow > 0 && leafCount(ref) <= options.shareBelow) {
      const auto texels = pack(set, 0.5 * (glm::dvec3(bmin) + glm::dvec3(bmax)));
      bool lastMarked = false; // the subtree's triangles are neighbours: after a mark, skip the probe
      forTriangles(ref, [&](std::uint32_t t) {
        const gpu::Triangle& tri = in.triangles[t];
        const glm::dvec3 v[3] = {vertex(tri.v0), vertex(tri.v1), vertex(tri.v2)};
        lastMarked = options.nothingBetween && nothingBetween(t, v, p, set, !lastMarked);
        write(t, light, lastMarked ? kNothing : texels);
      });
      return;
    }
    if (leaf) {
      forTriangles(ref, [&](std::uint32_t t) {
        const gpu::Triangle& tri = in.triangles[t];
        const glm::dvec3 v[3] = {vertex(tri.v0), vertex(tri.v1), vertex(tri.v2)};
        EntrySet own = set;
        refine(triangleHull(v, p), in.nodes, own,
               std::max({glm::length(v[1] - v[0]), glm::length(v[2] - v[1]), glm::length(v[0] - v[2])}));
        write(t, light,
              options.nothingBetween && nothingBetween(t, v, p, own) ? kNothing
                                                                     : pack(own, (v[0] + v[1] + v[2]) / 3.0));
      });
      return;
    }
    const gpu::BvhWideNode& node = in.nodes[ref];
    visit(node.ref0, node.min0, node.max0, set, light, depth + 1, splitDepth, tasks);
    visit(node.ref1, node.min1, node.max1, set, light, depth + 1, splitDepth, tasks);
  }
};

} // namespace

std::vector<glm::uvec4> shadowEntryTable(const ShadowEntryInput& in, const ShadowEntryOptions& options) {
  const std::size_t pairs = in.triangles.size() * in.lights.size();
  std::vector<glm::uvec4> table(2 * pairs, glm::uvec4(gpu::kBvhNoRef, gpu::kBvhNoRef, gpu::kBvhNoRef, 0u));
  if (pairs == 0 || in.root == gpu::kBvhNoRef) return table;

  // Leaves under each record: the records are flattened depth first, children after their parent.
  std::vector<std::uint32_t> leaves(in.nodes.size(), 0u);
  for (std::size_t i = in.nodes.size(); i-- > 0;) {
    auto count = [&](std::uint32_t ref) { return ref >= gpu::kBvhLeafFlag ? 1u : leaves[ref]; };
    leaves[i] = count(in.nodes[i].ref0) + count(in.nodes[i].ref1);
  }
  Builder builder{in, options, leaves, table};

  // The top of the tree on this thread, the subtrees below splitDepth shared among the workers.
  int threads = options.threads > 0 ? options.threads : static_cast<int>(std::thread::hardware_concurrency());
  threads = std::max(1, std::min<int>(threads, static_cast<int>(in.triangles.size() / 2048) + 1));
  const int splitDepth = threads > 1 ? 6 : -1;
  std::vector<Builder::Task> tasks;
  std::vector<std::size_t> taskLight;
  for (std::size_t l = 0; l < in.lights.size(); ++l) {
    if (!in.casts[l]) continue; // the kernel traces no shadow rays to it
    EntrySet start;
    start.e[0] = entry(in.root, in.rootBox.min, in.rootBox.max);
    start.n = 1;
    builder.visit(in.root, in.rootBox.min, in.rootBox.max, start, l, 0, splitDepth, &tasks);
    taskLight.resize(tasks.size(), l);
  }
  std::atomic<std::size_t> next{0};
  auto work = [&] {
    for (std::size_t i; (i = next.fetch_add(1)) < tasks.size();) {
      const Builder::Task& t = tasks[i];
      builder.visit(t.ref, t.min, t.max, t.set, taskLight[i], 0, -1, nullptr);
    }
  };
  std::vector<std::thread> pool;
  for (int w = 1; w < threads; ++w) pool.emplace_back(work);
  work();
  for (auto& th : pool) th.join();
  return table;
}

std::vector<std::uint32_t> shadowEntryRefs(const glm::uvec4& a, const glm::uvec4& b) {
  std::vector<std::uint32_t> refs;
  if (a.x == gpu::kBvhNoRef) return refs;
  refs.push_back(a.x);
  const std::uint32_t stacked[6] = {a.y, a.z, a.w, b.x, b.y, b.z};
  for (std::uint32_t i = 0; i < std::min<std::uint32_t>(b.w, 6u); ++i) refs.push_back(stacked[i]);
  return refs;
}

} // namespace vkray
