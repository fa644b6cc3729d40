// Ear clipping (Meisters 1975; the robustness measures follow Eberly, "Triangulation by Ear
// Clipping", 2002) in the plane of Newell's normal, with a fast path that keeps convex polygons the
// fan they always were, so meshes of triangles and convex polygons import exactly as before.
#include "scene/triangulate.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace vkray {

namespace {

using glm::dvec2;
using glm::dvec3;

double cross(const dvec2& a, const dvec2& b) {
  return a.x * b.y - a.y * b.x;
}

// Twice the signed area of (a, b, c): > 0 when they turn left.
double area2(const dvec2& a, const dvec2& b, const dvec2& c) {
  return cross(b - a, c - a);
}

// A strict left turn at b, beyond rounding: a corner on the line through its neighbours (to about
// 1e-14 of the angle) is flat, and a triangle on it would have no area.
bool turnsLeft(const dvec2& a, const dvec2& b, const dvec2& c) {
  dvec2 ab = b - a;
  dvec2 bc = c - b;
  return cross(ab, bc) > 1e-14 * (glm::dot(ab, ab) + glm::dot(bc, bc));
}

// Ear tests and point-in-triangle tests one ear clipping may spend before it gives up on the rest
// of a polygon (a tenth of a second; a second under the sanitizers): only self-intersecting inputs
// get near it.
constexpr std::size_t kWorkBudget = 20'000'000;

class EarClipper {
public:
  EarClipper(const std::vector<dvec2>& p, std::span<const std::uint32_t> corner, std::vector<Corners>& out)
      : p_(p), corner_(corner), out_(out), prev_(p.size()), next_(p.size()), convex_(p.size()),
        listed_(p.size(), false) {
    const std::size_t m = p.size();
    for (std::size_t i = 0; i < m; ++i) {
      prev_[i] = (i + m - 1) % m;
      next_[i] = (i + 1) % m;
    }
    // The corners that are not convex go in a uniform grid of about one per cell over the polygon's
    // bounds, so an ear test looks only at those near its triangle.
    std::size_t reflex = 0;
    lo_ = hi_ = p[0];
    for (std::size_t i = 0; i < m; ++i) {
      convex_[i] = turnsLeft(p_[prev_[i]], p_[i], p_[next_[i]]);
      reflex += !convex_[i];
      lo_ = glm::min(lo_, p[i]);
      hi_ = glm::max(hi_, p[i]);
    }
    side_ = std::clamp<std::size_t>(static_cast<std::size_t>(std::sqrt(static_cast<double>(reflex))), 1, 1024);
    dvec2 extent = hi_ - lo_;
    scale_ = dvec2(extent.x > 0 ? side_ / extent.x : 0.0, extent.y > 0 ? side_ / extent.y : 0.0);
    cells_.resize(side_ * side_);
    for (std::size_t i = 0; i < m; ++i) classify(i);
  }

  void run() {
    std::size_t remaining = p_.size();
    std::size_t i = pruneSpikes(remaining);
    if (remaining < 3) return;
    std::size_t stall = 0; // corners looked at since the last one was removed
    while (remaining > 3) {
      if (work_ > kWorkBudget) {
        fanRest(i);
        return;
      }
      if (isEar(i)) {
        std::size_t n = next_[i];
        emit(i);
        unlink(i);
        --remaining;
        stall = 0;
        i = n;
        continue;
      }
      i = next_[i];
      if (++stall < remaining) continue;
      // A whole lap without an ear: the polygon is not simple (or rounding says so). Remove a flat
      // corner if there is one (it covers nothing), else clip a convex corner regardless of what
      // its triangle contains; each lap of this kind removes a corner, so the loop ends.
      std::size_t pick = kNone;
      std::size_t j = i;
      work_ += 2 * remaining;
      for (std::size_t k = 0; k < remaining && pick == kNone; ++k, j = next_[j]) {
        if (!convex_[j] && !turnsLeft(p_[next_[j]], p_[j], p_[prev_[j]])) pick = j;
      }
      if (pick == kNone) {
        for (std::size_t k = 0; k < remaining && pick == kNone; ++k, j = next_[j]) {
          if (convex_[j]) pick = j;
        }
        if (pick == kNone) return; // every corner turns right: no triangle of this winding is left
        emit(pick);
      }
      i = next_[pick];
      unlink(pick);
      --remaining;
      stall = 0;
    }
    if (convex_[i]) emit(i);
  }

private:
  static constexpr std::size_t kNone = ~std::size_t(0);

  void classify(std::size_t i) {
    convex_[i] = turnsLeft(p_[prev_[i]], p_[i], p_[next_[i]]);
    // Only corners that are not convex can lie inside an ear; they are kept in the grid (entries go
    // stale as corners are removed or turn convex, and are skipped).
    if (!convex_[i] && !listed_[i]) {
      listed_[i] = true;
      cells_[cellY(p_[i].y) * side_ + cellX(p_[i].x)].push_back(i);
    }
  }

  std::size_t cellX(double x) const { return cell((x - lo_.x) * scale_.x); }
  std::size_t cellY(double y) const { return cell((y - lo_.y) * scale_.y); }
  std::size_t cell(double t) const {
    return t >= static_cast<double>(side_) ? side_ - 1 : t > 0.0 ? static_cast<std::size_t>(t) : 0;
  }

  // A corner where the outline runs out and straight back (a zero-width spike) encloses nothing,
  // yet its tip would be taken for a convex corner with nothing in its way; such tips are removed,
  // and so is a corner that then repeats its neighbour, until none is left. Returns a corner that
  // is still there.
  std::size_t pruneSpikes(std::size_t& remaining) {
    std::vector<std::size_t> work(p_.size());
    for (std::size_t i = 0; i < work.size(); ++i) work[i] = i;
    std::size_t live = 0;
    while (!work.empty() && remaining >= 3) {
      std::size_t b = work.back();
      work.pop_back();
      if (removed(b)) continue;
      live = b;
      const dvec2 &a = p_[prev_[b]], &pb = p_[b], &c = p_[next_[b]];
      bool repeat = pb == a;
      bool spike = !turnsLeft(a, pb, c) && !turnsLeft(c, pb, a) && glm::dot(pb - a, c - pb) < 0.0;
      if (!repeat && !spike) continue;
      live = prev_[b];
      work.push_back(prev_[b]);
      work.push_back(next_[b]);
      unlink(b);
      --remaining;
    }
    return live;
  }

  bool isEar(std::size_t b) {
    if (!convex_[b]) return false;
    std::size_t a = prev_[b];
    std::size_t c = next_[b];
    const dvec2 &pa = p_[a], &pb = p_[b], &pc = p_[c];
    const dvec2 lo = glm::min(pa, glm::min(pb, pc));
    const dvec2 hi = glm::max(pa, glm::max(pb, pc));
    ++work_;
    for (std::size_t y = cellY(lo.y), y1 = cellY(hi.y); y <= y1; ++y) {
      for (std::size_t x = cellX(lo.x), x1 = cellX(hi.x); x <= x1; ++x) {
        const std::vector<std::size_t>& in = cells_[y * side_ + x];
        work_ += in.size();
        for (std::size_t r : in) {
          if (r == a || r == c || removed(r) || convex_[r]) continue;
          const dvec2& q = p_[r];
          // A corner repeated elsewhere (the two sides of a slit joining a hole to the outline) is
          // not in the way; anything else on or inside the triangle is.
          if (q == pa || q == pb || q == pc) continue;
          if (area2(pa, pb, q) >= 0.0 && area2(pb, pc, q) >= 0.0 && area2(pc, pa, q) >= 0.0) return false;
        }
      }
    }
    return true;
  }

  bool removed(std::size_t i) const { return next_[i] == kNone; }

  void emit(std::size_t b) { out_.push_back({corner_[prev_[b]], corner_[b], corner_[next_[b]]}); }

  void unlink(std::size_t b) {
    std::size_t a = prev_[b];
    std::size_t c = next_[b];
    next_[a] = c;
    prev_[c] = a;
    next_[b] = prev_[b] = kNone;
    classify(a);
    classify(c);
  }

  // Out of budget: the rest as a fan from corner i, keeping only left-turning triangles.
  void fanRest(std::size_t i) {
    for (std::size_t j = next_[i]; next_[j] != i; j = next_[j]) {
      if (turnsLeft(p_[i], p_[j], p_[next_[j]])) out_.push_back({corner_[i], corner_[j], corner_[next_[j]]});
    }
  }

  const std::vector<dvec2>& p_;
  std::span<const std::uint32_t> corner_;
  std::vector<Corners>& out_;
  std::vector<std::size_t> prev_, next_;
  std::vector<bool> convex_, listed_;
  dvec2 lo_, hi_, scale_; // the grid: bounds, cells per unit
  std::size_t side_ = 1;  // cells along each axis
  std::vector<std::vector<std::size_t>> cells_;
  std::size_t work_ = 0;
};

} // namespace

void triangulatePolygon(std::span<const dvec3> corners, std::vector<Corners>& out) {
  const std::size_t n = corners.size();
  if (n < 3) return;
  if (n == 3) {
    out.push_back({0, 1, 2});
    return;
  }
  // Consecutive repeats (the closing corner included) are one corner.
  std::vector<std::uint32_t> kept;
  kept.reserve(n);
  for (std::uint32_t i = 0; i < n; ++i) {
    if (kept.empty() || corners[i] != corners[kept.back()]) kept.push_back(i);
  }
  while (kept.size() > 1 && corners[kept.back()] == corners[kept.front()]) kept.pop_back();
  const std::size_t m = kept.size();
  if (m < 3) return;

  // Newell's normal (Sutherland et al. 1974): the best-fit plane of a non-planar polygon, and for a
  // planar one its area vector.
  dvec3 normal(0.0);
  for (std::size_t i = 0; i < m; ++i) {
    const dvec3& a = corners[kept[i]];
    const dvec3& b = corners[kept[(i + 1) % m]];
    normal += dvec3((a.y - b.y) * (a.z + b.z), (a.z - b.z) * (a.x + b.x), (a.x - b.x) * (a.y + b.y));
  }
  if (!std::isfinite(normal.x) || !std::isfinite(normal.y) || !std::isfinite(normal.z)) return;
  // Project onto the two axes across the normal's largest component, mirrored where that component
  // is negative, so the polygon winds counter-clockwise in 2-D (dropping an axis is exact, and keeps
  // the triangulation independent of the polygon's position).
  dvec3 absN = glm::abs(normal);
  int k = absN.x >= absN.y && absN.x >= absN.z ? 0 : absN.y >= absN.z ? 1 : 2;
  if (!(absN[k] > 0.0)) return; // every corner on one line: no area
  int u = (k + 1) % 3;
  int v = (k + 2) % 3;
  double mirror = normal[k] > 0.0 ? 1.0 : -1.0;
  std::vector<dvec2> p(m);
  for (std::size_t i = 0; i < m; ++i) p[i] = dvec2(corners[kept[i]][u], mirror * corners[kept[i]][v]);

  // Strictly convex (every corner a left turn, turning once around): the fan from the first corner.
  bool convex = true;
  double turning = 0.0;
  for (std::size_t i = 0; i < m && convex; ++i) {
    const dvec2& a = p[(i + m - 1) % m];
    const dvec2& b = p[i];
    const dvec2& c = p[(i + 1) % m];
    convex = turnsLeft(a, b, c);
    turning += std::atan2(cross(b - a, c - b), glm::dot(b - a, c - b));
  }
  if (convex && turning < 3.0 * std::numbers::pi) {
    for (std::size_t i = 1; i + 1 < m; ++i) out.push_back({kept[0], kept[i], kept[i + 1]});
    return;
  }
  EarClipper(p, kept, out).run();
}

} // namespace vkray
