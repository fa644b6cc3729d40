// Support for the numerical robustness tests (numerics_test.cpp, numerics_image_test.cpp): the shared
// probe kernel (shaders/probe.comp, which runs the renderer's own shaders/lib functions), query
// builders, double-precision references computed from the same float32 inputs, seeded random
// sampling, and failure tallies that let one test run both numerics modes and compare them.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "image/image.h"
#include "render/probe.h"
#include "scene/scene.h"

namespace vkray::test::numerics {

using glm::dvec3;
using glm::vec3;

// Unit roundoff of float32 (half an ulp of 1): every rounded float operation has relative error <= kU.
inline constexpr double kU = 0x1p-24;

// The spacing of floats at |x| (0 -> the smallest normal spacing).
double ulpOf(double x);

inline dvec3 toDouble(const vec3& v) {
  return dvec3(v);
}
inline vec3 toFloat(const dvec3& v) {
  return vec3(v);
}
// The unit vector in double, rounded to float (as close to unit length as float allows).
inline vec3 unitFloat(const dvec3& v) {
  return vec3(glm::normalize(v));
}
double maxAbs(const dvec3& v);

// ---- The probe -----------------------------------------------------------------------------------
Probe& probe();
std::uint32_t modeCode(Numerics mode);
const char* modeName(Numerics mode);

// unitDir: the ray direction is unit length and the kernel's call (a = 1) is used for spheres.
gpu::ProbeQuery sphereQuery(vec3 o, vec3 d, vec3 center, float radius, Numerics mode, float tMax = 0.0f);
gpu::ProbeQuery planeQuery(vec3 o, vec3 d, vec3 n, float offsetD, Numerics mode, float tMax = 0.0f);
gpu::ProbeQuery triangleQuery(vec3 o, vec3 d, vec3 v0, vec3 v1, vec3 v2, Numerics mode, float tMax = 0.0f);
// The polygon's vertices are verts[first .. first + count) of the vertex array passed to runProbe.
gpu::ProbeQuery polygonQuery(vec3 o, vec3 d, vec3 n, std::uint32_t first, std::uint32_t count, Numerics mode,
                             float tMax = 0.0f);

// Runs the queries and fails the current test on any validation message.
std::vector<gpu::ProbeResult> runProbe(const std::vector<gpu::ProbeQuery>& queries,
                                       const std::vector<glm::vec4>& vertices = {});

inline bool hit(const gpu::ProbeResult& r) {
  return r.hit.x > 0.0f;
}
inline vec3 spawnOut(const gpu::ProbeResult& r) {
  return vec3(r.spawnOut);
}
inline vec3 spawnIn(const gpu::ProbeResult& r) {
  return vec3(r.spawnIn);
}
// Every float the probe returned is finite (no NaN, no Inf).
bool allFinite(const gpu::ProbeResult& r);

// ---- Double-precision references from float32 inputs --------------------------------------------

// Ray (o + t d, d not necessarily unit) against a sphere: both roots and the centre-to-line distance.
struct SphereRef {
  bool lineHits = false; // the line passes within the radius
  double dist = 0.0;     // distance of the centre from the line
  double t0 = 0.0;       // roots, t0 <= t1 (valid when lineHits)
  double t1 = 0.0;
  double nearest() const; // smallest positive root, or -1
};
SphereRef sphereRef(const dvec3& o, const dvec3& d, const dvec3& c, double r);

// Plane n.x + D = 0: t (may be negative or infinite).
double planeRef(const dvec3& o, const dvec3& d, const dvec3& n, double offsetD);

// Ray against a triangle in the shader's sheared frame (Woop et al. 2013), in double. bary are the
// exact barycentrics of the point where the ray's line meets the triangle's plane; baryTol bounds
// the error of the float32 barycentrics: the first-order error of the sheared coordinates (each
// one rounding of v - o, of the shear factor, of the product and of the difference) carried through
// the edge functions and the division by det, doubled for higher-order terms. It grows like
// u |v - o| / (triangle size x sin(angle)): the conditioning of the problem, not a fudge factor.
struct TriangleRef {
  double det = 0.0;
  dvec3 bary{0.0};
  double t = 0.0;
  double baryTol = 0.0;
  double minBary() const { return std::min(bary.x, std::min(bary.y, bary.z)); }
  bool inside() const { return det != 0.0 && minBary() > 0.0 && t > 0.0; }
  // Inside or outside by more than the tolerance (and in front of the origin).
  bool stable() const { return det != 0.0 && std::abs(minBary()) > baryTol; }
};
TriangleRef triangleRef(const dvec3& o, const dvec3& d, const dvec3& v0, const dvec3& v1, const dvec3& v2);

// Multiplier of the random sweeps' sizes: VKRAY_NUMERICS_SWEEP=N runs N times as many rays (default
// 1, which keeps the suite fast; larger values are for searching for rare failures).
int sweepScale();

// ---- Sampling ------------------------------------------------------------------------------------
class Rng {
public:
  explicit Rng(std::uint64_t seed) : engine_(seed) {}
  double uniform(double lo = 0.0, double hi = 1.0) { return std::uniform_real_distribution<double>(lo, hi)(engine_); }
  // 10^U(lo, hi): magnitudes spread evenly over decades (pbrt-v4's tests' pExp).
  double decades(double lo, double hi) { return std::pow(10.0, uniform(lo, hi)); }
  double sign() { return uniform() < 0.5 ? -1.0 : 1.0; }
  dvec3 unitVector();
  dvec3 hemisphere(const dvec3& n); // uniform over the hemisphere around n
  // Point with components of random sign and magnitude 10^U(lo, hi).
  dvec3 spreadPoint(double lo, double hi);

private:
  std::mt19937_64 engine_;
};

// Any unit vector perpendicular to n.
dvec3 perpendicular(const dvec3& n);

// ---- Meshes -------------------------------------------------------------------------------------
// Triangles (3 indices) and convex polygons (4 or more), vertices in float as the GPU sees them;
// shared vertices are the same float values in every face, as in any indexed mesh.
struct Mesh {
  std::vector<vec3> vertices;
  std::vector<std::vector<std::uint32_t>> faces; // wound outward
};

// Subdivided icosahedron: 20 * 4^level triangles on a sphere of the given radius around centre.
Mesh icosphere(const dvec3& center, double radius, int level);

// A cube of half-size h: three faces are single quad polygons, three are fans of four triangles
// around the face centre, so polygon/polygon, polygon/triangle and triangle/triangle edges meet.
Mesh mixedCube(const dvec3& center, double h);

// The mesh as scene-file objects ("triangle" / "polygon"), comma-separated, with one material.
std::string meshJson(const Mesh& mesh, const std::string& material);

// ---- Tallies ------------------------------------------------------------------------------------
// Counts cases and failures of one numerics mode; keeps the first few failures for the message.
struct Tally {
  explicit Tally(std::string caseName) : name(std::move(caseName)) {}
  std::string name;
  long cases = 0;
  long failures = 0;
  std::vector<std::string> examples;
  double worstRatio = 0.0; // largest measured error / stated tolerance over the checked cases
  void noteRatio(double ratio) { worstRatio = std::max(worstRatio, ratio); }
  // Counts one case; on failure, describe() says what went wrong (only called then).
  template <class Describe> void check(bool ok, Describe&& describe) {
    ++cases;
    if (ok) return;
    ++failures;
    if (examples.size() < 3) examples.push_back(describe());
  }
  std::string summary() const;
};

// Prints "name: robust f/n, naive f/n" for the test log.
void report(const std::string& name, const Tally& robust, const Tally& naive);

// Format helpers for failure messages.
std::string str(const dvec3& v);
std::string str(double x);

// A point as a JSON array with every digit of the double (scene text for sceneFromJson).
std::string point(const dvec3& p);

// ---- Whole-image properties ---------------------------------------------------------------------

// x -> scale * x + shift applied to everything with a position or a length: camera, lights, every
// primitive, checker squares and absorption (per unit length). Directions and colours stay.
Scene transformed(Scene scene, double scale, const dvec3& shift);

// Whether two pixels differ by more than `steps` sRGB 8-bit steps (encodeSrgb8, as in PNG files) in
// any channel; and the share of such pixels between two images of one size.
bool pixelOff(const glm::vec3& a, const glm::vec3& b, int steps = 6);
double shareOff(const Image& a, const Image& b, int steps = 6);

} // namespace vkray::test::numerics
