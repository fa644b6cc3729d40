// Probe access, references and sampling for the numerical tests (see numerics_support.h).
#include "numerics_support.h"

#include <algorithm>
#include <array>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <map>
#include <memory>
#include <sstream>

#include <gtest/gtest.h>

#include "test_support.h"

namespace vkray::test::numerics {

double ulpOf(double x) {
  float f = std::abs(static_cast<float>(x));
  if (!(f < std::numeric_limits<float>::max())) return std::numeric_limits<double>::infinity();
  return static_cast<double>(std::nextafter(f, std::numeric_limits<float>::infinity())) - f;
}

double maxAbs(const dvec3& v) {
  return std::max(std::abs(v.x), std::max(std::abs(v.y), std::abs(v.z)));
}

Probe& probe() {
  static std::unique_ptr<Probe> p = std::make_unique<Probe>(gpu());
  return *p;
}

std::uint32_t modeCode(Numerics mode) {
  return mode == Numerics::Robust ? gpu::kNumericsRobust : gpu::kNumericsNaive;
}
const char* modeName(Numerics mode) {
  return mode == Numerics::Robust ? "robust" : "naive";
}

namespace {

gpu::ProbeQuery query(std::uint32_t op, vec3 o, vec3 d, float tMax, Numerics mode) {
  gpu::ProbeQuery q{};
  q.origin = glm::vec4(o, tMax);
  q.dir = glm::vec4(d, 0.0f);
  q.op = glm::uvec4(op, modeCode(mode), 0u, 0u);
  return q;
}

} // namespace

gpu::ProbeQuery sphereQuery(vec3 o, vec3 d, vec3 center, float radius, Numerics mode, float tMax) {
  gpu::ProbeQuery q = query(gpu::kProbeSphere, o, d, tMax, mode);
  q.a = glm::vec4(center, radius);
  q.op.z = 1u; // the kernel's call: unit directions, a = 1
  return q;
}

gpu::ProbeQuery planeQuery(vec3 o, vec3 d, vec3 n, float offsetD, Numerics mode, float tMax) {
  gpu::ProbeQuery q = query(gpu::kProbePlane, o, d, tMax, mode);
  q.a = glm::vec4(n, offsetD);
  return q;
}

gpu::ProbeQuery triangleQuery(vec3 o, vec3 d, vec3 v0, vec3 v1, vec3 v2, Numerics mode, float tMax) {
  gpu::ProbeQuery q = query(gpu::kProbeTriangle, o, d, tMax, mode);
  q.a = glm::vec4(v0, 0.0f);
  q.b = glm::vec4(v1, 0.0f);
  q.c = glm::vec4(v2, 0.0f);
  return q;
}

gpu::ProbeQuery polygonQuery(vec3 o, vec3 d, vec3 n, std::uint32_t first, std::uint32_t count, Numerics mode,
                             float tMax) {
  gpu::ProbeQuery q = query(gpu::kProbePolygon, o, d, tMax, mode);
  q.a = glm::vec4(n, 0.0f);
  q.op.z = first;
  q.op.w = count;
  return q;
}

std::vector<gpu::ProbeResult> runProbe(const std::vector<gpu::ProbeQuery>& queries,
                                       const std::vector<glm::vec4>& vertices) {
  if (queries.empty()) return {};
  std::vector<gpu::ProbeResult> results = probe().run(queries, vertices);
  expectNoValidationMessages();
  return results;
}

bool allFinite(const gpu::ProbeResult& r) {
  const glm::vec4* parts[] = {&r.hit, &r.point, &r.normal, &r.spawnOut, &r.spawnIn};
  for (const glm::vec4* p : parts) {
    for (int i = 0; i < 4; ++i) {
      if (!std::isfinite((*p)[i])) return false;
    }
  }
  return true;
}

// ---- References ---------------------------------------------------------------------------------

double SphereRef::nearest() const {
  if (!lineHits) return -1.0;
  if (t0 > 0.0) return t0;
  if (t1 > 0.0) return t1;
  return -1.0;
}

SphereRef sphereRef(const dvec3& o, const dvec3& d, const dvec3& c, double r) {
  // Double has 29 more bits than the float inputs; the same stable form (RTG ch. 7) keeps the
  // reference accurate for spheres far from the origin, where even double cancels in b^2 - ac.
  SphereRef s;
  dvec3 f = o - c;
  double a = glm::dot(d, d);
  double b = -glm::dot(f, d);
  dvec3 l = f + (b / a) * d;
  s.dist = glm::length(l);
  double disc = (r - s.dist) * (r + s.dist);
  s.lineHits = disc >= 0.0;
  if (!s.lineHits) return s;
  double q = b + (b < 0.0 ? -1.0 : 1.0) * std::sqrt(a * disc);
  double cc = glm::dot(f, f) - r * r;
  double ta = q != 0.0 ? cc / q : 0.0;
  double tb = q / a;
  s.t0 = std::min(ta, tb);
  s.t1 = std::max(ta, tb);
  return s;
}

double planeRef(const dvec3& o, const dvec3& d, const dvec3& n, double offsetD) {
  return -(glm::dot(n, o) + offsetD) / glm::dot(n, d);
}

TriangleRef triangleRef(const dvec3& o, const dvec3& d, const dvec3& v0, const dvec3& v1, const dvec3& v2) {
  TriangleRef ref;
  // The shader's axis choice (largest |d| component; ties as in watertightSetup), in double.
  dvec3 a = glm::abs(d);
  int kz = (a.x > a.y) ? ((a.x > a.z) ? 0 : 2) : ((a.y > a.z) ? 1 : 2);
  int kx = (kz + 1) % 3;
  int ky = (kx + 1) % 3;
  if (d[kz] < 0.0) std::swap(kx, ky);
  double sx = d[kx] / d[kz], sy = d[ky] / d[kz], sz = 1.0 / d[kz];
  const dvec3* v[3] = {&v0, &v1, &v2};
  double X[3], Y[3], Z[3], eX[3], eY[3];
  for (int i = 0; i < 3; ++i) {
    dvec3 r = *v[i] - o;
    X[i] = r[kx] - sx * r[kz];
    Y[i] = r[ky] - sy * r[kz];
    Z[i] = sz * r[kz];
    // float32: v - o, the shear factor, the product and the difference are each rounded once.
    eX[i] = kU * (std::abs(r[kx]) + 3.0 * std::abs(sx * r[kz]) + std::abs(X[i]));
    eY[i] = kU * (std::abs(r[ky]) + 3.0 * std::abs(sy * r[kz]) + std::abs(Y[i]));
  }
  // edgeFunction(p, q) = q.x p.y - q.y p.x, and its first-order error from the sheared coordinates'
  // errors plus the two rounded products and their rounded difference.
  auto edge = [&](int p, int q) { return X[q] * Y[p] - Y[q] * X[p]; };
  auto edgeError = [&](int p, int q) {
    return eX[q] * std::abs(Y[p]) + std::abs(X[q]) * eY[p] + eY[q] * std::abs(X[p]) + std::abs(Y[q]) * eX[p] +
           2.0 * kU * (std::abs(X[q] * Y[p]) + std::abs(Y[q] * X[p]));
  };
  dvec3 e(edge(1, 2), edge(2, 0), edge(0, 1));
  dvec3 err(edgeError(1, 2), edgeError(2, 0), edgeError(0, 1));
  ref.det = e.x + e.y + e.z;
  if (ref.det == 0.0) {
    ref.baryTol = std::numeric_limits<double>::infinity();
    return ref;
  }
  double detError = err.x + err.y + err.z + 2.0 * kU * (std::abs(e.x) + std::abs(e.y) + std::abs(e.z));
  ref.bary = e / ref.det;
  ref.t = (e.x * Z[0] + e.y * Z[1] + e.z * Z[2]) / ref.det;
  // b_i = e_i / det: first-order error (err_i + |b_i| detError) / |det| plus the rounded reciprocal
  // and product; doubled to cover the second-order terms.
  for (int i = 0; i < 3; ++i) {
    double tol = (err[i] + std::abs(ref.bary[i]) * detError) / std::abs(ref.det) + 2.0 * kU * std::abs(ref.bary[i]);
    ref.baryTol = std::max(ref.baryTol, 2.0 * tol);
  }
  return ref;
}

int sweepScale() {
  static const int scale = [] {
    const char* s = std::getenv("VKRAY_NUMERICS_SWEEP");
    int v = s ? std::atoi(s) : 1;
    return v > 0 ? v : 1;
  }();
  return scale;
}

// ---- Sampling -----------------------------------------------------------------------------------

dvec3 Rng::unitVector() {
  double z = uniform(-1.0, 1.0);
  double phi = uniform(0.0, 2.0 * 3.14159265358979323846);
  double s = std::sqrt(std::max(0.0, 1.0 - z * z));
  return dvec3(s * std::cos(phi), s * std::sin(phi), z);
}

dvec3 Rng::hemisphere(const dvec3& n) {
  dvec3 w = unitVector();
  return glm::dot(w, n) < 0.0 ? -w : w;
}

dvec3 Rng::spreadPoint(double lo, double hi) {
  return dvec3(sign() * decades(lo, hi), sign() * decades(lo, hi), sign() * decades(lo, hi));
}

dvec3 perpendicular(const dvec3& n) {
  dvec3 axis = std::abs(n.x) < 0.6 ? dvec3(1, 0, 0) : dvec3(0, 1, 0);
  return glm::normalize(glm::cross(n, axis));
}

// ---- Meshes -------------------------------------------------------------------------------------

Mesh icosphere(const dvec3& center, double radius, int level) {
  const double g = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<dvec3> v = {{-1, g, 0},  {1, g, 0},  {-1, -g, 0}, {1, -g, 0}, {0, -1, g},  {0, 1, g},
                          {0, -1, -g}, {0, 1, -g}, {g, 0, -1},  {g, 0, 1},  {-g, 0, -1}, {-g, 0, 1}};
  for (auto& p : v) p = glm::normalize(p);
  std::vector<std::array<std::uint32_t, 3>> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                                 {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                                 {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                                 {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (int l = 0; l < level; ++l) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> mid;
    auto midpoint = [&](std::uint32_t a, std::uint32_t b) {
      auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back(glm::normalize(v[a] + v[b]));
      auto idx = static_cast<std::uint32_t>(v.size() - 1);
      mid[key] = idx;
      return idx;
    };
    std::vector<std::array<std::uint32_t, 3>> next;
    for (auto& t : f) {
      std::uint32_t a = midpoint(t[0], t[1]), b = midpoint(t[1], t[2]), c = midpoint(t[2], t[0]);
      next.push_back({t[0], a, c});
      next.push_back({t[1], b, a});
      next.push_back({t[2], c, b});
      next.push_back({a, b, c});
    }
    f = next;
  }
  Mesh m;
  for (auto& p : v) m.vertices.push_back(toFloat(center + radius * p));
  for (auto& t : f) m.faces.push_back({t[0], t[1], t[2]});
  return m;
}

Mesh mixedCube(const dvec3& center, double h) {
  Mesh m;
  for (int i = 0; i < 8; ++i) {
    dvec3 corner((i & 1) ? h : -h, (i & 2) ? h : -h, (i & 4) ? h : -h);
    m.vertices.push_back(toFloat(center + corner));
  }
  // Faces wound outward (right-hand rule), as corner indices.
  const std::uint32_t quads[6][4] = {{1, 3, 7, 5}, {2, 6, 7, 3}, {4, 5, 7, 6},  // +x, +y, +z: polygons
                                     {0, 4, 6, 2}, {0, 1, 5, 4}, {0, 2, 3, 1}}; // -x, -y, -z: fans
  for (int f = 0; f < 6; ++f) {
    const auto& q = quads[f];
    if (f < 3) {
      m.faces.push_back({q[0], q[1], q[2], q[3]});
      continue;
    }
    dvec3 mid(0.0);
    for (int k = 0; k < 4; ++k) mid += dvec3(m.vertices[q[k]]) / 4.0;
    m.vertices.push_back(toFloat(mid));
    auto ci = static_cast<std::uint32_t>(m.vertices.size() - 1);
    for (int k = 0; k < 4; ++k) m.faces.push_back({q[k], q[(k + 1) % 4], ci});
  }
  return m;
}

std::string meshJson(const Mesh& mesh, const std::string& material) {
  std::ostringstream s;
  s.precision(9); // float values round-trip exactly
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
    const auto& face = mesh.faces[f];
    s << (f ? ",\n" : "") << R"({ "type": ")" << (face.size() == 3 ? "triangle" : "polygon") << R"(", "vertices": [)";
    for (std::size_t k = 0; k < face.size(); ++k) {
      const vec3& v = mesh.vertices[face[k]];
      s << (k ? ", " : "") << "[" << v.x << ", " << v.y << ", " << v.z << "]";
    }
    s << R"(], "material": ")" << material << R"(" })";
  }
  return s.str();
}

// ---- Tallies ------------------------------------------------------------------------------------

std::string Tally::summary() const {
  std::ostringstream s;
  s << name << ": " << failures << " of " << cases << " cases failed";
  for (const auto& e : examples) s << "\n    e.g. " << e;
  return s.str();
}

void report(const std::string& name, const Tally& robust, const Tally& naive) {
  std::printf("[ numerics ] %-44s robust %5ld / %-6ld naive %6ld / %-6ld worst error/tolerance %.3g | %.3g\n",
              name.c_str(), robust.failures, robust.cases, naive.failures, naive.cases, robust.worstRatio,
              naive.worstRatio);
  if (!naive.examples.empty()) std::printf("[ numerics ]     naive, e.g. %s\n", naive.examples.front().c_str());
  std::fflush(stdout);
}

std::string str(const dvec3& v) {
  char buf[128];
  std::snprintf(buf, sizeof buf, "(%.9g, %.9g, %.9g)", v.x, v.y, v.z);
  return buf;
}

std::string str(double x) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.9g", x);
  return buf;
}

std::string point(const dvec3& p) {
  char buf[128];
  std::snprintf(buf, sizeof buf, "[%.17g, %.17g, %.17g]", p.x, p.y, p.z);
  return buf;
}

Scene transformed(Scene scene, double scale, const dvec3& shift) {
  auto place = [&](const dvec3& p) { return scale * p + shift; };
  scene.camera.position = place(scene.camera.position);
  scene.camera.lookAt = place(scene.camera.lookAt);
  for (auto& l : scene.lights) l.position = place(l.position);
  for (auto& s : scene.spheres) {
    s.center = place(s.center);
    s.radius *= scale;
  }
  // n.x + D = 0 and x' = s x + t give n.x' + (s D - n.t) = 0.
  for (auto& p : scene.planes) p.offset = scale * p.offset - glm::dot(p.normal, shift);
  for (auto& poly : scene.polygons)
    for (auto& v : poly.vertices) v = place(v);
  for (auto& t : scene.triangles)
    for (auto& v : t.v) v = place(v);
  for (auto& m : scene.materials) {
    if (m.checker) m.checker->scale *= scale;
    m.absorption /= scale;
  }
  return scene;
}

bool pixelOff(const glm::vec3& a, const glm::vec3& b, int steps) {
  for (int c = 0; c < 3; ++c)
    if (std::abs(int(encodeSrgb8(a[c])) - int(encodeSrgb8(b[c]))) > steps) return true;
  return false;
}

double shareOff(const Image& a, const Image& b, int steps) {
  EXPECT_EQ(a.width, b.width);
  EXPECT_EQ(a.height, b.height);
  std::size_t off = 0;
  for (std::size_t i = 0; i < a.pixels.size() && i < b.pixels.size(); ++i)
    off += pixelOff(a.pixels[i], b.pixels[i], steps);
  return static_cast<double>(off) / static_cast<double>(a.pixels.size());
}

} // namespace vkray::test::numerics
