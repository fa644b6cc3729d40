// Polygon triangulation (host/scene/triangulate.cpp), by properties: convex polygons give exactly
// the fan from their first corner (so meshes import as they always did); concave ones give triangles
// that lie inside the polygon and add up to its area (shoelace); a ring joined to its hole by a slit
// keeps the hole; repeated and collinear corners give no zero-area triangle; any input terminates.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <sstream>

#include <unistd.h>

#include <gtest/gtest.h>

#include "scene/mesh_import.h"
#include "scene/triangulate.h"

namespace vkray {
namespace {

namespace fs = std::filesystem;
using glm::dvec2;
using glm::dvec3;

const fs::path kAssimpModels = "/usr/share/assimp/models";

double cross(const dvec2& a, const dvec2& b) {
  return a.x * b.y - a.y * b.x;
}

// Twice the signed area (shoelace).
double shoelace(const std::vector<dvec2>& p) {
  double s = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i) s += cross(p[i], p[(i + 1) % p.size()]);
  return s;
}

// A plane polygon placed in space by an orthonormal frame: (x, y) -> origin + x e1 + y e2.
struct Frame {
  dvec3 origin{0.0};
  dvec3 e1{1, 0, 0};
  dvec3 e2{0, 1, 0};
  dvec3 at(const dvec2& p) const { return origin + p.x * e1 + p.y * e2; }
};

Frame randomFrame(std::mt19937& rng) {
  std::normal_distribution<double> g;
  dvec3 a = glm::normalize(dvec3(g(rng), g(rng), g(rng)));
  dvec3 b = glm::normalize(glm::cross(a, glm::normalize(dvec3(g(rng), g(rng), g(rng)))));
  return {dvec3(g(rng), g(rng), g(rng)) * 10.0, a, b};
}

std::vector<Corners> triangulate(const std::vector<dvec2>& p, const Frame& frame = {}) {
  std::vector<dvec3> corners;
  for (const dvec2& q : p) corners.push_back(frame.at(q));
  std::vector<Corners> out;
  triangulatePolygon(corners, out);
  return out;
}

double triangleArea2(const std::vector<dvec2>& p, const Corners& t) {
  return cross(p[t[1]] - p[t[0]], p[t[2]] - p[t[0]]);
}

// Even-odd rule, for a point not on the boundary.
bool insidePolygon(const std::vector<dvec2>& p, const dvec2& q) {
  bool in = false;
  for (std::size_t i = 0, j = p.size() - 1; i < p.size(); j = i++) {
    if ((p[i].y > q.y) != (p[j].y > q.y) && q.x < (p[j].x - p[i].x) * (q.y - p[i].y) / (p[j].y - p[i].y) + p[i].x) {
      in = !in;
    }
  }
  return in;
}

bool insideTriangle(const dvec2& a, const dvec2& b, const dvec2& c, const dvec2& q) {
  double d1 = cross(b - a, q - a), d2 = cross(c - b, q - b), d3 = cross(a - c, q - c);
  return (d1 > 0 && d2 > 0 && d3 > 0) || (d1 < 0 && d2 < 0 && d3 < 0);
}

// Segments ab and cd cross at a point inside both (not at an end).
bool properlyCross(const dvec2& a, const dvec2& b, const dvec2& c, const dvec2& d) {
  double d1 = cross(b - a, c - a), d2 = cross(b - a, d - a), d3 = cross(d - c, a - c), d4 = cross(d - c, b - c);
  return ((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0));
}

// A random simple polygon, star-shaped about the origin: corners at sorted random angles with random
// radii (most such polygons are concave), counter-clockwise.
std::vector<dvec2> randomStar(std::mt19937& rng, int n) {
  std::uniform_real_distribution<double> angle(0.0, 2.0 * std::numbers::pi);
  std::uniform_real_distribution<double> radius(0.2, 1.0);
  std::vector<double> a(static_cast<std::size_t>(n));
  for (double& x : a) x = angle(rng);
  std::sort(a.begin(), a.end());
  std::vector<dvec2> p;
  for (double x : a) {
    double r = radius(rng);
    p.emplace_back(r * std::cos(x), r * std::sin(x));
  }
  return p;
}

// The properties every triangulation of a simple polygon p must have.
void expectValidTriangulation(const std::vector<dvec2>& p, const std::vector<Corners>& tris) {
  const double area = shoelace(p);
  double sum = 0.0;
  for (const Corners& t : tris) {
    for (std::uint32_t c : t) ASSERT_LT(c, p.size());
    double a = triangleArea2(p, t);
    EXPECT_GT(a * (area > 0 ? 1 : -1), 0.0) << "a triangle wound against the polygon, or of zero area";
    sum += a;
    const dvec2 &a0 = p[t[0]], &a1 = p[t[1]], &a2 = p[t[2]];
    // Inside: the centroid is, no polygon corner is strictly inside, and no polygon edge crosses an
    // edge of the triangle.
    EXPECT_TRUE(insidePolygon(p, (a0 + a1 + a2) / 3.0)) << "a triangle outside the polygon";
    for (std::size_t i = 0; i < p.size(); ++i) {
      EXPECT_FALSE(insideTriangle(a0, a1, a2, p[i])) << "corner " << i << " inside a triangle";
      const dvec2& q0 = p[i];
      const dvec2& q1 = p[(i + 1) % p.size()];
      EXPECT_FALSE(properlyCross(a0, a1, q0, q1) || properlyCross(a1, a2, q0, q1) || properlyCross(a2, a0, q0, q1))
          << "edge " << i << " crosses a triangle";
    }
  }
  EXPECT_NEAR(sum, area, 1e-9 * std::abs(area)) << "the triangles do not add up to the polygon's area";
}

std::vector<Corners> fan(std::size_t n) {
  std::vector<Corners> out;
  for (std::uint32_t i = 1; i + 1 < n; ++i) out.push_back({0, i, i + 1});
  return out;
}

// ---- Convex: the fan ------------------------------------------------------------------------------

// Regular and random convex polygons, in random planes and both windings, become exactly the fan
// from their first corner: meshes of convex polygons import as they did before ear clipping.
TEST(Triangulate, ConvexPolygonsGiveTheFan) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  for (int trial = 0; trial < 400; ++trial) {
    int n = 3 + trial % 30;
    std::vector<double> a;
    for (int i = 0; i < n; ++i) {
      a.push_back(trial % 2 ? 2.0 * std::numbers::pi * i / n : 2.0 * std::numbers::pi * uniform(rng));
    }
    std::sort(a.begin(), a.end());
    a.erase(std::unique(a.begin(), a.end()), a.end());
    std::vector<dvec2> p;
    for (double x : a) p.emplace_back(3.0 * std::cos(x), 0.5 * std::sin(x)); // on an ellipse: convex
    if (trial % 3 == 0) std::reverse(p.begin(), p.end());
    SCOPED_TRACE("trial " + std::to_string(trial) + ", " + std::to_string(p.size()) + " corners");
    EXPECT_EQ(triangulate(p, randomFrame(rng)), fan(p.size()));
  }
}

// A convex OBJ face imports as its fan; a triangle is passed through as it is.
TEST(Triangulate, ObjConvexFaceIsTheFanAndConcaveFaceIsClipped) {
  fs::path file = fs::temp_directory_path() / ("vkray-triangulate-" + std::to_string(::getpid()) + ".obj");
  // A convex hexagon, then a concave quad (a chevron: its corner 1 is reflex, so the fan's diagonal
  // 0-2 would lie outside it).
  std::ofstream(file) << "v 0 0 0\nv 2 0 0\nv 3 1 0\nv 2 2 0\nv 0 2 0\nv -1 1 0\nf 1 2 3 4 5 6\n"
                         "v 0 0 1\nv 1 1 1\nv 2 0 1\nv 1 3 1\nf 7 8 9 10\n";
  MeshRequest request;
  request.file = file;
  request.shownAs = "test.obj";
  MeshData data = readObj(request);
  fs::remove(file);
  ASSERT_EQ(data.faces.size(), 4u + 2u);
  for (std::uint32_t i = 0; i < 4; ++i) {
    EXPECT_EQ(data.faces[i], (std::array<std::uint32_t, 3>{0, i + 1, i + 2}));
  }
  double area = 0.0;
  for (std::size_t f = 4; f < 6; ++f) {
    const auto& t = data.faces[f];
    dvec3 n = glm::cross(data.positions[t[1]] - data.positions[t[0]], data.positions[t[2]] - data.positions[t[0]]);
    EXPECT_GT(n.z, 0.0) << "wound as the face";
    area += 0.5 * n.z;
  }
  EXPECT_DOUBLE_EQ(area, 2.0) << "the chevron's area (the fan would cover 4)";
}

// ---- Concave ---------------------------------------------------------------------------------------

TEST(Triangulate, ConcavePolygonsKeepAreaAndStayInside) {
  std::mt19937 rng(11);
  int concave = 0;
  for (int trial = 0; trial < 300; ++trial) {
    int n = 4 + trial % 60;
    std::vector<dvec2> p = randomStar(rng, n);
    if (trial % 2) std::reverse(p.begin(), p.end()); // clockwise too
    bool isConvex = true;
    for (std::size_t i = 0; i < p.size(); ++i) {
      const dvec2& a = p[(i + p.size() - 1) % p.size()];
      const dvec2& c = p[(i + 1) % p.size()];
      isConvex = isConvex && cross(p[i] - a, c - p[i]) * shoelace(p) > 0;
    }
    concave += !isConvex;
    SCOPED_TRACE("trial " + std::to_string(trial) + ", " + std::to_string(n) + " corners");
    std::vector<Corners> tris = triangulate(p, randomFrame(rng));
    EXPECT_EQ(tris.size(), p.size() - 2);
    expectValidTriangulation(p, tris);
    if (::testing::Test::HasFailure()) break;
  }
  EXPECT_GT(concave, 250) << "the test polygons should be mostly concave";
}

// A comb (deep teeth, many reflex corners) and a spiral, the hard cases for ear clipping.
TEST(Triangulate, CombAndSpiral) {
  std::vector<dvec2> comb;
  const int teeth = 50;
  for (int i = 0; i < teeth; ++i) {
    comb.emplace_back(2.0 * i, 0.0);
    comb.emplace_back(2.0 * i + 1.0, 10.0);
  }
  comb.emplace_back(2.0 * teeth, -1.0);
  comb.emplace_back(0.0, -1.0);
  expectValidTriangulation(comb, triangulate(comb));

  std::vector<dvec2> spiral; // an arm of width w winding out three turns, then back in
  const int steps = 120;
  for (int i = 0; i <= steps; ++i) {
    double t = 6.0 * std::numbers::pi * i / steps;
    spiral.emplace_back((1.0 + t) * std::cos(t), (1.0 + t) * std::sin(t));
  }
  for (int i = steps; i >= 0; --i) {
    double t = 6.0 * std::numbers::pi * i / steps;
    spiral.emplace_back((1.6 + t) * std::cos(t), (1.6 + t) * std::sin(t));
  }
  std::vector<Corners> tris = triangulate(spiral);
  EXPECT_EQ(tris.size(), spiral.size() - 2);
  expectValidTriangulation(spiral, tris);
}

// A star-shaped face of 20 000 random radii (about half its corners reflex) is clipped in full, not
// left to the fallback: n - 2 triangles, all wound as the face, adding up to its area.
TEST(Triangulate, LargeConcavePolygonsAreClippedInFull) {
  std::mt19937 rng(5);
  std::vector<dvec2> p = randomStar(rng, 20000);
  std::vector<Corners> tris = triangulate(p, randomFrame(rng));
  ASSERT_EQ(tris.size(), p.size() - 2);
  double sum = 0.0;
  int wrong = 0;
  for (const Corners& t : tris) {
    double a = triangleArea2(p, t);
    wrong += !(a > 0.0);
    sum += a;
  }
  EXPECT_EQ(wrong, 0);
  EXPECT_NEAR(sum, shoelace(p), 1e-9 * shoelace(p));
}

// ---- Rings -----------------------------------------------------------------------------------------

// A ring as one polygon: the outline, a slit in to the hole, the hole the other way round, and the
// slit back out (its two corners appear twice). The hole's centre is in no triangle.
TEST(Triangulate, RingJoinedByASlitKeepsItsHole) {
  for (int n : {4, 8, 33}) {
    std::vector<dvec2> p;
    for (int i = 0; i <= n; ++i) { // outline, counter-clockwise, back to its first corner
      double t = 2.0 * std::numbers::pi * (i % n) / n;
      p.emplace_back(2.0 * std::cos(t), 2.0 * std::sin(t));
    }
    for (int i = 0; i <= n; ++i) { // hole, clockwise, back to its first corner
      double t = -2.0 * std::numbers::pi * (i % n) / n;
      p.emplace_back(std::cos(t), std::sin(t));
    }
    SCOPED_TRACE(std::to_string(n) + " sides");
    std::vector<Corners> tris = triangulate(p);
    double sum = 0.0;
    for (const Corners& t : tris) {
      double a = triangleArea2(p, t);
      EXPECT_GT(a, 0.0);
      sum += a;
      EXPECT_FALSE(insideTriangle(p[t[0]], p[t[1]], p[t[2]], dvec2(0.0))) << "a triangle over the hole";
      EXPECT_FALSE(insideTriangle(p[t[0]], p[t[1]], p[t[2]], dvec2(0.3, -0.2))) << "a triangle over the hole";
    }
    EXPECT_NEAR(sum, shoelace(p), 1e-12 * shoelace(p)) << "outline minus hole";
  }
}

// assimp's concave_polygon.obj: one 66-corner face, a thin ring (LightWave's export of a ring with a
// slit). Its triangles cover the ring and not its hole.
TEST(Triangulate, AssimpConcavePolygonKeepsItsHole) {
  fs::path file = kAssimpModels / "OBJ" / "concave_polygon.obj";
  if (!fs::exists(file)) GTEST_SKIP() << file << " is absent (apt-get install assimp-testmodels)";
  MeshRequest request;
  request.file = file;
  request.shownAs = file.string();
  MeshData data = readObj(request);
  ASSERT_EQ(data.faces.size(), 64u);
  // The face lies in the plane x = -1.146; (y, z) is its 2-D frame. Its outline, as the file gives it:
  std::ifstream in(file);
  std::string line;
  std::vector<dvec2> polygon;
  while (std::getline(in, line)) {
    if (line.rfind("f ", 0) != 0) continue;
    std::istringstream corners(line.substr(2));
    std::string c;
    while (corners >> c) {
      const dvec3& v = data.positions.at(std::stoul(c) - 1);
      polygon.emplace_back(v.y, v.z);
    }
  }
  ASSERT_EQ(polygon.size(), 66u);
  double sum = 0.0;
  const dvec2 centre(2.4, 2.35); // of the hole (radius about 0.69; the ring is about 0.05 wide)
  for (const auto& f : data.faces) {
    dvec2 a(data.positions[f[0]].y, data.positions[f[0]].z);
    dvec2 b(data.positions[f[1]].y, data.positions[f[1]].z);
    dvec2 c(data.positions[f[2]].y, data.positions[f[2]].z);
    sum += cross(b - a, c - a);
    for (const dvec2& q : {centre, centre + dvec2(0.5, 0.0), centre + dvec2(0.0, -0.6), centre + dvec2(-0.4, 0.4)}) {
      EXPECT_FALSE(insideTriangle(a, b, c, q)) << "a triangle over the hole at (" << q.x << ", " << q.y << ")";
    }
    EXPECT_GT(std::abs(cross(b - a, c - a)), 0.0);
  }
  EXPECT_NEAR(std::abs(sum), std::abs(shoelace(polygon)), 1e-9) << "the ring's area";
  EXPECT_LT(std::abs(shoelace(polygon)) / 2.0, 0.3) << "a ring, not the disc (pi 0.74^2 = 1.7)";
}

// ---- Degenerate input ------------------------------------------------------------------------------

// Repeated corners (next to each other, and the first repeated at the end) and corners on the line
// through their neighbours cover nothing: no zero-area triangle comes out, and the area is kept.
TEST(Triangulate, RepeatedAndCollinearCornersGiveNoZeroAreaTriangle) {
  struct Case {
    const char* name;
    std::vector<dvec2> p;
  };
  const Case cases[] = {
      {"repeated corners", {{0, 0}, {0, 0}, {1, 0}, {1, 1}, {1, 1}, {1, 1}, {0, 1}, {0, 0}}},
      {"midpoints on every side", {{0, 0}, {1, 0}, {2, 0}, {2, 1}, {2, 2}, {1, 2}, {0, 2}, {0, 1}}},
      {"collinear run on a concave L",
       {{0, 0}, {1, 0}, {2, 0}, {3, 0}, {3, 1}, {1, 1}, {1, 3}, {0, 3}, {0, 2}, {0, 1}}},
      {"a spike out and back", {{0, 0}, {2, 0}, {2, 1}, {3, 1}, {2, 1}, {2, 2}, {0, 2}}},
      {"collinear thirds", {{0, 0}, {0.1, 0}, {0.2, 0}, {0.3, 0}, {0.3, 0.1}, {0.0, 0.1}}},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    std::vector<Corners> tris = triangulate(c.p);
    double sum = 0.0;
    for (const Corners& t : tris) {
      double a = triangleArea2(c.p, t);
      EXPECT_GT(a, 1e-12) << "a zero-area triangle (" << t[0] << ", " << t[1] << ", " << t[2] << ")";
      sum += a;
    }
    EXPECT_NEAR(sum, shoelace(c.p), 1e-12);
  }
  // No area at all: every corner the same, or on one line.
  EXPECT_TRUE(triangulate({{1, 1}, {1, 1}, {1, 1}, {1, 1}}).empty());
  EXPECT_TRUE(triangulate({{0, 0}, {1, 1}, {2, 2}, {3, 3}, {1, 1}}).empty());
  EXPECT_TRUE(triangulate({{0, 0}, {1, 0}}).empty());
}

// Self-intersecting polygons (a bow tie, a pentagram, random corners) have no right answer, but
// they must not hang, and whatever comes out uses only their corners and has area.
TEST(Triangulate, SelfIntersectingPolygonsTerminate) {
  std::vector<std::vector<dvec2>> polygons = {
      {{0, 0}, {1, 1}, {1, 0}, {0, 1}},
      {{0, 1}, {0.588, -0.809}, {-0.951, 0.309}, {0.951, 0.309}, {-0.588, -0.809}},
  };
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int n : {6, 20, 100, 1000, 3000}) {
    std::vector<dvec2> p;
    for (int i = 0; i < n; ++i) p.emplace_back(u(rng), u(rng));
    polygons.push_back(p);
  }
  for (const auto& p : polygons) {
    SCOPED_TRACE(std::to_string(p.size()) + " corners");
    std::vector<Corners> tris = triangulate(p, randomFrame(rng));
    EXPECT_LE(tris.size(), p.size() - 2);
    for (const Corners& t : tris) {
      for (std::uint32_t c : t) ASSERT_LT(c, p.size());
      EXPECT_NE(triangleArea2(p, t), 0.0);
    }
  }
}

} // namespace
} // namespace vkray
