// The hard cases of float32 ray tracing, run through the renderer's own intersection and offset
// functions (shaders/lib via shaders/probe.comp) on lavapipe, checked against double-precision
// references computed from the same float32 inputs. Each case runs in both numerics modes: robust
// (the default) must never fail; naive (textbook formulas, fixed epsilon) is expected to fail the
// cases the robust techniques exist for. Tolerances are stated where they are used, with the reason
// for their size; docs/numerics.md explains each technique and shows the failures as images.
#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <map>
#include <set>

#include <gtest/gtest.h>

#include "numerics_support.h"

namespace vkray::test::numerics {
namespace {

using Case = std::function<Tally(Numerics)>;

// Runs a case in both modes, prints the tallies, and asserts: robust never fails; naive fails
// (when naiveFails) at least once.
void runBoth(const std::string& name, const Case& run, bool naiveFails) {
  Tally robust = run(Numerics::Robust);
  Tally naive = run(Numerics::Naive);
  report(name, robust, naive);
  EXPECT_GT(robust.cases, 0) << name << ": no case was checked";
  EXPECT_EQ(robust.failures, 0) << "robust " << robust.summary();
  if (naiveFails) {
    EXPECT_GT(naive.failures, 0) << "naive numerics were expected to fail " << naive.summary();
  }
}

// Silhouette band of a sphere at distance D from the ray origin: the shader forms the centre-to-line
// vector l = f + (b'/a) d from values of size |f| ~ D with about six roundings, and the kernel's
// a = 1 for a float "unit" direction adds |d.d - 1| <= 3u more; the distance it compares with the
// radius is therefore off by at most ~12 u D. Rays whose exact distance from the centre is within
// 16 u (D + r) of the radius may fall either way; all others must be classified exactly.
double silhouetteBand(double distance, double radius) {
  return 16.0 * kU * (distance + radius);
}

// ---- 1. Far unit spheres --------------------------------------------------------------------------

Tally farUnitSpheres(Numerics mode) {
  Tally tally{"far unit spheres"};
  Rng rng(101);
  struct Ray {
    vec3 o, d, c;
  };
  std::vector<Ray> rays;
  std::vector<gpu::ProbeQuery> queries;
  for (double distance : {1e2, 1e3, 1e4, 1e5, 1e6}) {
    const int n = 600;
    for (int i = 0; i < n; ++i) {
      // Along the view axis, offsets from the centre spread evenly over [0, 2.5] radii.
      vec3 c(0.0f, 0.0f, static_cast<float>(-distance));
      double h = 2.5 * (i + 0.5) / n;
      double phi = rng.uniform(0.0, 6.283185307179586);
      dvec3 target = dvec3(c) + h * dvec3(std::cos(phi), std::sin(phi), 0.0);
      vec3 o(0.0f);
      vec3 d = unitFloat(target - dvec3(o));
      rays.push_back({o, d, c});
      queries.push_back(sphereQuery(o, d, c, 1.0f, mode));
    }
  }
  auto results = runProbe(queries);
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const Ray& ray = rays[i];
    const gpu::ProbeResult& res = results[i];
    dvec3 o(ray.o), d(ray.d), c(ray.c);
    SphereRef ref = sphereRef(o, d, c, 1.0);
    double band = silhouetteBand(glm::length(c - o), 1.0);
    if (std::abs(ref.dist - 1.0) <= band) continue;
    bool expectHit = ref.nearest() > 0.0;
    tally.check(hit(res) == expectHit, [&] {
      return std::string(expectHit ? "missed" : "false hit") + " at distance " + str(-c.z) + ", line " +
             str(ref.dist - 1.0) + " from the rim (band " + str(band) + ")";
    });
    if (!expectHit || !hit(res)) continue;
    // t: four ulps of its rounding plus the band's error in the centre-to-line distance carried
    // to t through the slope of the near root, dt/dist = dist / sqrt(r^2 - dist^2).
    double tRef = ref.nearest();
    double tol = 4.0 * ulpOf(tRef) + band * ref.dist / std::sqrt(1.0 - ref.dist * ref.dist);
    double err = std::abs(res.hit.x - tRef);
    tally.noteRatio(err / tol);
    tally.check(err <= tol, [&] {
      return "t " + str(res.hit.x) + " vs " + str(tRef) + " (" + str(err / ulpOf(tRef)) + " ulp) at distance " +
             str(-c.z) + ", offset " + str(ref.dist);
    });
  }
  return tally;
}

TEST(NumericsSphere, FarUnitSpheresHitExactlyWithinTheRadius) {
  runBoth("1 far unit spheres (1e2..1e6)", farUnitSpheres, true);
}

// ---- 2. Origin inside: at the centre, and spawned from the surface inward ---------------------------

// A random sphere, radius 1e-3..1e3, centre components up to 1e4 (pbrt-v4's shape tests' spread).
struct SphereShape {
  vec3 c;
  float r;
};
SphereShape randomSphere(Rng& rng, double rLo, double rHi, double cLo, double cHi) {
  return {toFloat(rng.spreadPoint(cLo, cHi)), static_cast<float>(rng.decades(rLo, rHi))};
}

// A ray from outside the sphere to a random point of the cap it sees, at most 70% of the way to the
// silhouette in angle, so it hits well away from tangency.
void rayToCap(Rng& rng, const SphereShape& s, vec3& o, vec3& d) {
  dvec3 c(s.c);
  dvec3 m = rng.unitVector();
  double dist = s.r * rng.decades(0.1, 2.0);
  o = toFloat(c + m * dist);
  dvec3 om = glm::normalize(dvec3(o) - c);
  double alpha = rng.uniform(0.0, 0.7) * std::acos(std::min(1.0, s.r / glm::length(dvec3(o) - c)));
  dvec3 p1 = perpendicular(om), p2 = glm::cross(om, p1);
  double phi = rng.uniform(0.0, 6.283185307179586);
  dvec3 k = std::cos(alpha) * om + std::sin(alpha) * (std::cos(phi) * p1 + std::sin(phi) * p2);
  d = unitFloat(c + double(s.r) * k - dvec3(o));
}

Tally originAtCenter(Numerics mode) {
  Tally tally{"origin at the centre"};
  Rng rng(201);
  std::vector<SphereShape> shapes;
  std::vector<vec3> dirs;
  std::vector<gpu::ProbeQuery> queries;
  for (int i = 0; i < 2000; ++i) {
    SphereShape s = randomSphere(rng, -3.0, 3.0, -2.0, 4.0);
    vec3 d = unitFloat(rng.unitVector());
    shapes.push_back(s);
    dirs.push_back(d);
    queries.push_back(sphereQuery(s.c, d, s.c, s.r, mode));
  }
  auto results = runProbe(queries);
  for (std::size_t i = 0; i < shapes.size(); ++i) {
    // f = o - c = 0 exactly, so t = r / |d| is one square root of r^2 and the kernel's a = 1 away
    // from exact: 4 ulps.
    double tRef = shapes[i].r / glm::length(dvec3(dirs[i]));
    double err = std::abs(results[i].hit.x - tRef);
    double tol = 4.0 * ulpOf(tRef);
    tally.noteRatio(err / tol);
    tally.check(hit(results[i]) && err <= tol, [&] {
      return "radius " + str(shapes[i].r) + " at " + str(dvec3(shapes[i].c)) + ": t " + str(results[i].hit.x);
    });
  }
  return tally;
}

TEST(NumericsSphere, OriginAtTheCentreFindsTheFarRoot) {
  runBoth("2a origin at the sphere centre", originAtCenter, false);
}

// From a hit on the outside, a ray continues inward from the origin the renderer would spawn
// (robust: spawnOrigin to the inner side; naive: the hit point itself): it must find the exit, the
// far root, never a spurious t ~ 0 at the entry point.
Tally originOnSurfaceInward(Numerics mode) {
  Tally tally{"origin on the surface, inward"};
  Rng rng(202);
  std::vector<SphereShape> shapes;
  std::vector<gpu::ProbeQuery> first;
  std::vector<vec3> firstDirs;
  for (int i = 0; i < 1500 * sweepScale(); ++i) {
    // Radii 1e-3..1e3, centres up to 1e4. The spawned origin sits the hit point's error bound,
    // 6u (r + |c|), inside; a sphere must be several times wider than that to have an inside at
    // float precision, so radii below 2^-19 |c| (about 5 bounds) are drawn again.
    SphereShape s = randomSphere(rng, -3.0, 3.0, -6.0, 4.0);
    while (s.r < 0x1p-19 * maxAbs(dvec3(s.c))) s = randomSphere(rng, -3.0, 3.0, -6.0, 4.0);
    vec3 o, d;
    rayToCap(rng, s, o, d);
    shapes.push_back(s);
    firstDirs.push_back(d);
    first.push_back(sphereQuery(o, d, s.c, s.r, mode));
  }
  auto hits = runProbe(first);
  struct Inward {
    std::size_t shape;
    vec3 o, d;
  };
  std::vector<Inward> inward;
  std::vector<gpu::ProbeQuery> second;
  for (std::size_t i = 0; i < shapes.size(); ++i) {
    const SphereShape& s = shapes[i];
    tally.check(hit(hits[i]), [&] { return "the outside ray missed radius " + str(s.r) + " at " + str(dvec3(s.c)); });
    if (!hit(hits[i])) continue;
    dvec3 n = glm::normalize(dvec3(hits[i].point) - dvec3(s.c));
    vec3 o = spawnIn(hits[i]);
    // Straight on (a refraction with equal indices) and three random inward directions.
    std::array<vec3, 4> dirs = {firstDirs[i], unitFloat(rng.hemisphere(-n)), unitFloat(rng.hemisphere(-n)),
                                unitFloat(rng.hemisphere(-n))};
    for (const vec3& d : dirs) {
      inward.push_back({i, o, d});
      second.push_back(sphereQuery(o, d, s.c, s.r, mode));
    }
  }
  auto exits = runProbe(second);
  for (std::size_t k = 0; k < inward.size(); ++k) {
    const SphereShape& s = shapes[inward[k].shape];
    dvec3 o(inward[k].o), d(inward[k].d), c(s.c);
    SphereRef ref = sphereRef(o, d, c, s.r);
    double tFar = ref.t1;
    // The exit distance is a root without cancellation: its error is the rounding of f = o - c
    // (values of size |c| + r) carried through b' and the square root, whose slope grows as the
    // chord shortens: 16 u (|c| + r) (1 + 2r / chord) plus four ulps of t.
    double scale = maxAbs(c) + s.r;
    double tol = 4.0 * ulpOf(tFar) + 16.0 * kU * scale * (1.0 + 2.0 * s.r / std::max(tFar, 1e-30));
    double err = std::abs(exits[k].hit.x - tFar);
    bool inside = glm::length(o - c) < s.r;
    if (mode == Numerics::Robust) {
      tally.check(inside, [&] {
        return "spawned origin outside radius " + str(s.r) + " at " + str(c) + " by " + str(glm::length(o - c) - s.r);
      });
    }
    if (hit(exits[k])) tally.noteRatio(err / tol);
    tally.check(hit(exits[k]) && err <= tol, [&] {
      return "radius " + str(s.r) + " at " + str(c) + ": t " + str(exits[k].hit.x) + ", exit at " + str(tFar);
    });
  }
  return tally;
}

TEST(NumericsSphere, OriginOnTheSurfaceInwardFindsTheFarRoot) {
  runBoth("2b origin on the surface, pointing inward", originOnSurfaceInward, true);
}

// ---- 3. Tangent rays ---------------------------------------------------------------------------------

Tally tangentRays(Numerics mode) {
  Tally tally{"tangent rays"};
  Rng rng(301);
  struct Ray {
    vec3 o, d, c;
    float r;
  };
  std::vector<Ray> rays;
  std::vector<gpu::ProbeQuery> queries;
  const double deltas[] = {0.0, 1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7};
  for (double distance : {1.0, 10.0, 1e2, 1e3, 1e4}) {
    for (double radius : {1e-2, 1.0, 1e2}) {
      if (radius > distance / 2) continue;
      for (int k = 0; k < 40; ++k) {
        vec3 o = toFloat(rng.spreadPoint(-2.0, 0.0));
        vec3 c = toFloat(dvec3(o) + distance * rng.unitVector());
        float r = static_cast<float>(radius);
        dvec3 axis = glm::normalize(dvec3(c) - dvec3(o));
        dvec3 e = glm::normalize(glm::cross(axis, rng.unitVector()));
        for (double delta : deltas) {
          for (double s : {-1.0, 1.0}) {
            // Aimed at a point (1 + s delta) radii from the centre, perpendicular to the view axis.
            dvec3 target = dvec3(c) + double(r) * (1.0 + s * delta) * e;
            vec3 d = unitFloat(target - dvec3(o));
            rays.push_back({o, d, c, r});
            queries.push_back(sphereQuery(o, d, c, r, mode));
          }
        }
      }
    }
  }
  auto results = runProbe(queries);
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const Ray& ray = rays[i];
    const gpu::ProbeResult& res = results[i];
    tally.check(allFinite(res), [&] { return "non-finite result for a ray tangent to radius " + str(ray.r); });
    dvec3 o(ray.o), d(ray.d), c(ray.c);
    SphereRef ref = sphereRef(o, d, c, ray.r);
    double band = silhouetteBand(glm::length(c - o), ray.r);
    if (std::abs(ref.dist - ray.r) <= band) continue;
    bool expectHit = ref.nearest() > 0.0;
    tally.check(hit(res) == expectHit, [&] {
      return std::string(expectHit ? "missed" : "false hit") + ": radius " + str(ray.r) + " at distance " +
             str(glm::length(c - o)) + ", line " + str(ref.dist - ray.r) + " from the rim (band " + str(band) + ")";
    });
  }
  return tally;
}

TEST(NumericsSphere, TangentRaysAreFiniteAndClassified) {
  runBoth("3 tangent rays", tangentRays, true);
}

// ---- 4 and 5. Spawned rays never re-hit the surface they leave ------------------------------------------

// Shadow/reflection rays from a sphere hit: spawnOut, then directions over the outgoing hemisphere
// (uniform, plus grazing ones 1e-4..1e-1 rad above the tangent plane). A sphere is convex, so no
// such ray truly meets it again; any hit the shader reports is acne.
struct SphereHitRay {
  SphereShape s;
  vec3 o, d;
};

void sphereSelfHits(Tally& tally, Numerics mode, Rng& rng, const std::vector<SphereHitRay>& rays, int perHit) {
  std::vector<gpu::ProbeQuery> first;
  for (const auto& r : rays) first.push_back(sphereQuery(r.o, r.d, r.s.c, r.s.r, mode));
  auto hits = runProbe(first);
  struct Out {
    std::size_t ray;
    vec3 o, d;
  };
  std::vector<Out> outs;
  std::vector<gpu::ProbeQuery> second;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const SphereShape& s = rays[i].s;
    // Rays within the silhouette band of the rim may fall either way (case 1); all others must hit.
    SphereRef ref = sphereRef(dvec3(rays[i].o), dvec3(rays[i].d), dvec3(s.c), s.r);
    bool mustHit = ref.dist < s.r - silhouetteBand(glm::length(dvec3(s.c) - dvec3(rays[i].o)), s.r);
    if (mustHit) {
      tally.check(hit(hits[i]), [&] { return "the eye ray missed radius " + str(s.r) + " at " + str(dvec3(s.c)); });
    }
    if (!hit(hits[i])) continue;
    dvec3 n = glm::normalize(dvec3(hits[i].point) - dvec3(s.c));
    vec3 o = spawnOut(hits[i]);
    if (mode == Numerics::Robust) {
      double gap = glm::length(dvec3(o) - dvec3(s.c)) - s.r;
      tally.check(gap > 0.0, [&] { return "spawned origin " + str(gap) + " below radius " + str(s.r); });
      // The offset scales with the hit point, not with the sphere: the bound gamma(8)(|p| + |g|) of
      // sphereSurface plus a one-ulp step, and the compensated sum's residual gamma(4)^2 (r + |c|).
      // 0.4 units for a ground of radius 1e6 before; 1e-5 now.
      double pMax = maxAbs(dvec3(hits[i].point));
      double allowed = 32.0 * kU * pMax + 256.0 * kU * kU * (s.r + maxAbs(dvec3(s.c)));
      tally.noteRatio(gap / allowed);
      tally.check(gap <= allowed, [&] {
        return "spawned origin " + str(gap) + " above radius " + str(s.r) + " (allowed " + str(allowed) + ")";
      });
    }
    for (int k = 0; k < perHit; ++k) {
      dvec3 w;
      if (k % 4 == 3) {
        double elevation = rng.decades(-4.0, -1.0);
        dvec3 t = glm::normalize(glm::cross(n, rng.unitVector()));
        w = std::cos(elevation) * t + std::sin(elevation) * n;
      } else {
        w = rng.hemisphere(n);
      }
      vec3 d = unitFloat(w);
      outs.push_back({i, o, d});
      second.push_back(sphereQuery(o, d, s.c, s.r, mode));
    }
  }
  auto again = runProbe(second);
  for (std::size_t k = 0; k < outs.size(); ++k) {
    const SphereShape& s = rays[outs[k].ray].s;
    tally.check(!hit(again[k]), [&] {
      return "re-hit radius " + str(s.r) + " at " + str(dvec3(s.c)) + " at t " + str(again[k].hit.x);
    });
  }
}

Tally groundSphere(Numerics mode, double radius) {
  Tally tally{"ground sphere"};
  Rng rng(401);
  const SphereShape ground{vec3(0.0f, static_cast<float>(-radius), 0.0f), static_cast<float>(radius)};
  const double r = ground.r, cy = ground.c.y; // the float sphere, exactly
  std::vector<SphereHitRay> rays;
  for (double height : {0.1, 0.3, 1.0, 3.0, 10.0}) {
    for (int i = 0; i < 300 * sweepScale(); ++i) {
      // Eye above the top of the sphere, looking at ground points 0.1..100 units away.
      vec3 o(static_cast<float>(rng.uniform(-1, 1)), static_cast<float>(height),
             static_cast<float>(rng.uniform(-1, 1)));
      double rho = rng.decades(-1.0, 2.0), phi = rng.uniform(0.0, 6.283185307179586);
      double x = o.x + rho * std::cos(phi), z = o.z + rho * std::sin(phi);
      double h2 = x * x + z * z;
      double y = cy + r - h2 / (r + std::sqrt(r * r - h2)); // no cancellation at any radius
      rays.push_back({ground, o, unitFloat(dvec3(x, y, z) - dvec3(o))});
    }
  }
  sphereSelfHits(tally, mode, rng, rays, 16);
  return tally;
}

TEST(NumericsSphere, HugeGroundSphereHasNoAcne) {
  runBoth(
      "4 radius-1e4 ground seen from 0.1..10", [](Numerics m) { return groundSphere(m, 1e4); }, true);
}

// A ground of radius 1e5..1e7 (the ray-tracing books' trick in place of a plane): before the
// compensated distance (sphereSurface), hit points re-projected through a centre 1e6 away carried
// errors of ~0.1 and offsets of ~0.4, which moved shadows and reflections visibly.
TEST(NumericsSphere, GroundSpheresOfRadius1e5To1e7) {
  runBoth(
      "4b radius 1e5, 1e6, 1e7 grounds from 0.1..10",
      [](Numerics m) {
        Tally all{"ground spheres 1e5..1e7"};
        for (double radius : {1e5, 1e6, 1e7}) {
          Tally one = groundSphere(m, radius);
          all.cases += one.cases;
          all.failures += one.failures;
          all.noteRatio(one.worstRatio);
          for (auto& e : one.examples)
            if (all.examples.size() < 3) all.examples.push_back(e);
        }
        return all;
      },
      true);
}

// Beads: spheres of radius 1e-4 seen from 1e-3 .. 1e2 away, at up to 1e3 from the origin.
Tally beads(Numerics mode) {
  Tally tally{"beads"};
  Rng rng(402);
  std::vector<SphereHitRay> rays;
  for (int i = 0; i < 1200 * sweepScale(); ++i) {
    SphereShape s{toFloat(rng.spreadPoint(-3.0, 3.0)), 1e-4f};
    dvec3 n = rng.unitVector();
    dvec3 target = dvec3(s.c) + 0.9 * static_cast<double>(s.r) * n; // inside the silhouette
    vec3 o = toFloat(target + (n + 0.5 * rng.unitVector()) * rng.decades(-3.0, 2.0));
    rays.push_back({s, o, unitFloat(target - dvec3(o))});
  }
  sphereSelfHits(tally, mode, rng, rays, 16);
  return tally;
}

TEST(NumericsSphere, BeadsOfRadiusTenToTheMinusFour) {
  runBoth("4c radius-1e-4 beads, 1e-3..1e2 away", beads, false);
}

// A sky dome: the camera inside a sphere of radius 1e3..1e7 whose centre is off the camera by up
// to half the radius. From the inside hit, the spawned origin must lie inside, within the bound
// of its hit point, and a ray sent back into the dome must meet it again at the far side (the
// chord), never at the point it leaves.
Tally skyDome(Numerics mode) {
  Tally tally{"sky dome"};
  Rng rng(403);
  struct Ray {
    SphereShape s;
    vec3 o, d;
  };
  std::vector<Ray> rays;
  std::vector<gpu::ProbeQuery> first;
  for (double radius : {1e3, 1e5, 1e7}) {
    for (int i = 0; i < 300 * sweepScale(); ++i) {
      SphereShape s{toFloat(rng.unitVector() * radius * rng.uniform(0.0, 0.5)), static_cast<float>(radius)};
      vec3 o = toFloat(rng.unitVector() * rng.decades(-1.0, 1.0));
      vec3 d = unitFloat(rng.unitVector());
      rays.push_back({s, o, d});
      first.push_back(sphereQuery(o, d, s.c, s.r, mode));
    }
  }
  auto hits = runProbe(first);
  std::vector<gpu::ProbeQuery> second;
  std::vector<std::pair<std::size_t, double>> chords;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const Ray& ray = rays[i];
    tally.check(hit(hits[i]), [&] { return "missed the dome of radius " + str(ray.s.r) + " from inside"; });
    if (!hit(hits[i])) continue;
    dvec3 c(ray.s.c);
    dvec3 n = glm::normalize(dvec3(hits[i].point) - c);
    vec3 o = spawnOut(hits[i]); // back to the side the eye ray came from: the inside
    double gap = ray.s.r - glm::length(dvec3(o) - c);
    if (mode == Numerics::Robust) {
      double allowed = 32.0 * kU * maxAbs(dvec3(hits[i].point)) + 256.0 * kU * kU * (ray.s.r + maxAbs(c));
      tally.check(gap > 0.0 && gap <= allowed, [&] {
        return "spawned origin " + str(gap) + " inside radius " + str(ray.s.r) + " (allowed " + str(allowed) + ")";
      });
    }
    // Back into the dome, 30..80 degrees off the inward normal: the chord is 2 r cos(angle).
    dvec3 in = -n;
    dvec3 w = glm::normalize(in + std::tan(rng.uniform(0.52, 1.4)) * perpendicular(in));
    vec3 d = unitFloat(w);
    dvec3 f = dvec3(o) - c;
    double b = glm::dot(f, dvec3(d));
    double chord = -b + std::sqrt(b * b - (glm::dot(f, f) - static_cast<double>(ray.s.r) * ray.s.r));
    chords.push_back({i, chord});
    second.push_back(sphereQuery(o, d, ray.s.c, ray.s.r, mode));
  }
  auto again = runProbe(second);
  for (std::size_t k = 0; k < chords.size(); ++k) {
    double t = again[k].hit.x, chord = chords[k].second;
    tally.check(std::abs(t - chord) <= 1e-3 * chord, [&] {
      return "back into the dome of radius " + str(rays[chords[k].first].s.r) + ": t " + str(t) + ", chord " +
             str(chord);
    });
  }
  return tally;
}

TEST(NumericsSphere, SkyDomesSeenFromInside) {
  runBoth("4d sky domes 1e3..1e7, camera inside", skyDome, false);
}

Tally reintersectSpheres(Numerics mode) {
  Tally tally{"sphere re-intersection sweep"};
  Rng rng(501);
  std::vector<SphereHitRay> rays;
  for (int i = 0; i < 1500 * sweepScale(); ++i) {
    SphereShape s = randomSphere(rng, -3.0, 3.0, -6.0, 4.0);
    vec3 o, d;
    rayToCap(rng, s, o, d);
    rays.push_back({s, o, d});
  }
  sphereSelfHits(tally, mode, rng, rays, 32);
  return tally;
}

TEST(NumericsReintersect, SpheresOfEverySizeAndPlace) {
  runBoth("5a sphere sweep (r 1e-3..1e3, |c| to 1e4)", reintersectSpheres, true);
}

// The exact normal of the plane through three float vertices.
dvec3 exactNormal(const vec3& a, const vec3& b, const vec3& c) {
  return glm::normalize(glm::cross(dvec3(b) - dvec3(a), dvec3(c) - dvec3(a)));
}

// A point of the triangle with uniformly distributed barycentrics.
dvec3 pointInTriangle(Rng& rng, const vec3& a, const vec3& b, const vec3& c) {
  double s = std::sqrt(rng.uniform()), t = rng.uniform();
  return (1 - s) * dvec3(a) + s * (1 - t) * dvec3(b) + s * t * dvec3(c);
}

Tally reintersectTriangles(Numerics mode) {
  Tally tally{"triangle re-intersection sweep"};
  Rng rng(502);
  struct Tri {
    vec3 v[3];
    vec3 o, d;
  };
  std::vector<Tri> tris;
  std::vector<gpu::ProbeQuery> first;
  for (int i = 0; i < 1500 * sweepScale(); ++i) {
    // Size 1e-3..1e3 around a point with components up to 1e4; vertices anywhere in a ball, so
    // slivers and obtuse triangles come up too.
    dvec3 p = rng.spreadPoint(-6.0, 4.0);
    double size = rng.decades(-3.0, 3.0);
    Tri t;
    for (auto& v : t.v) v = toFloat(p + size * rng.uniform(0.3, 1.0) * rng.unitVector());
    if (glm::length(glm::cross(dvec3(t.v[1]) - dvec3(t.v[0]), dvec3(t.v[2]) - dvec3(t.v[0]))) < 1e-3 * size * size)
      continue;
    dvec3 target = pointInTriangle(rng, t.v[0], t.v[1], t.v[2]);
    t.o = toFloat(target + rng.unitVector() * size * rng.decades(0.0, 2.0));
    t.d = unitFloat(target - dvec3(t.o));
    tris.push_back(t);
    first.push_back(triangleQuery(t.o, t.d, t.v[0], t.v[1], t.v[2], mode));
  }
  auto hits = runProbe(first);
  struct Out {
    std::size_t tri;
    vec3 o, d;
  };
  std::vector<Out> outs;
  std::vector<gpu::ProbeQuery> second;
  for (std::size_t i = 0; i < tris.size(); ++i) {
    const Tri& t = tris[i];
    if (!hit(hits[i])) continue; // aimed inside, but near an edge the ray may truly miss
    dvec3 n = exactNormal(t.v[0], t.v[1], t.v[2]);
    dvec3 facing = glm::dot(n, dvec3(t.d)) < 0.0 ? n : -n;
    vec3 o = spawnOut(hits[i]);
    if (mode == Numerics::Robust) {
      double side = glm::dot(dvec3(o) - dvec3(t.v[0]), facing);
      tally.check(side > 0.0, [&] { return "spawned origin " + str(side) + " behind the triangle"; });
    }
    for (int k = 0; k < 32; ++k) {
      // Straight along the normal, close to it, and over the whole hemisphere.
      dvec3 w = k == 0 ? facing : (k < 4 ? facing + 1e-3 * rng.unitVector() : rng.hemisphere(facing));
      vec3 d = unitFloat(w);
      outs.push_back({i, o, d});
      second.push_back(triangleQuery(o, d, t.v[0], t.v[1], t.v[2], mode));
    }
  }
  auto again = runProbe(second);
  for (std::size_t k = 0; k < outs.size(); ++k) {
    const Tri& t = tris[outs[k].tri];
    tally.check(!hit(again[k]), [&] {
      return "re-hit the triangle " + str(dvec3(t.v[0])) + " size " + str(glm::length(dvec3(t.v[1]) - dvec3(t.v[0]))) +
             " at t " + str(again[k].hit.x);
    });
  }
  return tally;
}

TEST(NumericsReintersect, TrianglesOfEverySizeAndPlace) {
  runBoth("5b triangle sweep (1e-3..1e3, to 1e4)", reintersectTriangles, true);
}

// ---- 6. Shared edges and vertices far from the origin ----------------------------------------------------

// Rays from `origins` aimed at every vertex and at `perEdge` points along every edge; each ray is
// tested against all faces that touch its target. Escapes: rays that none of them hits.
void meshEscapes(Tally& tally, Numerics mode, const Mesh& mesh, const std::vector<vec3>& origins, int perEdge) {
  std::vector<glm::vec4> verts;
  for (const vec3& v : mesh.vertices) verts.emplace_back(v, 0.0f);
  std::map<std::uint32_t, std::set<std::size_t>> facesAtVertex;
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::set<std::size_t>> facesAtEdge;
  std::vector<vec3> normals;
  std::vector<std::uint32_t> firstVertex; // polygons: the face's vertices, copied after the mesh's
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
    const auto& face = mesh.faces[f];
    for (std::size_t k = 0; k < face.size(); ++k) {
      facesAtVertex[face[k]].insert(f);
      facesAtEdge[std::minmax(face[k], face[(k + 1) % face.size()])].insert(f);
    }
    normals.push_back(unitFloat(glm::cross(dvec3(mesh.vertices[face[1]]) - dvec3(mesh.vertices[face[0]]),
                                           dvec3(mesh.vertices[face[2]]) - dvec3(mesh.vertices[face[0]]))));
    firstVertex.push_back(static_cast<std::uint32_t>(verts.size()));
    for (auto i : face) verts.emplace_back(mesh.vertices[i], 0.0f);
  }
  struct Ray {
    vec3 o, d;
    std::vector<std::size_t> faces;
    std::string target;
  };
  std::vector<Ray> rays;
  for (const vec3& o : origins) {
    for (const auto& [vi, faces] : facesAtVertex) {
      rays.push_back({o,
                      unitFloat(dvec3(mesh.vertices[vi]) - dvec3(o)),
                      {faces.begin(), faces.end()},
                      "vertex " + str(dvec3(mesh.vertices[vi]))});
    }
    for (const auto& [e, faces] : facesAtEdge) {
      for (int k = 1; k <= perEdge; ++k) {
        double s = double(k) / (perEdge + 1);
        vec3 target = toFloat((1 - s) * dvec3(mesh.vertices[e.first]) + s * dvec3(mesh.vertices[e.second]));
        rays.push_back(
            {o, unitFloat(dvec3(target) - dvec3(o)), {faces.begin(), faces.end()}, "edge point " + str(dvec3(target))});
      }
    }
  }
  std::vector<gpu::ProbeQuery> queries;
  std::vector<std::size_t> rayOf;
  for (std::size_t r = 0; r < rays.size(); ++r) {
    for (std::size_t f : rays[r].faces) {
      const auto& face = mesh.faces[f];
      if (face.size() == 3) {
        queries.push_back(triangleQuery(rays[r].o, rays[r].d, mesh.vertices[face[0]], mesh.vertices[face[1]],
                                        mesh.vertices[face[2]], mode));
      } else {
        queries.push_back(polygonQuery(rays[r].o, rays[r].d, normals[f], firstVertex[f],
                                       static_cast<std::uint32_t>(face.size()), mode));
      }
      rayOf.push_back(r);
    }
  }
  auto results = runProbe(queries, verts);
  std::vector<int> hits(rays.size(), 0);
  for (std::size_t q = 0; q < queries.size(); ++q) hits[rayOf[q]] += hit(results[q]) ? 1 : 0;
  for (std::size_t r = 0; r < rays.size(); ++r) {
    tally.check(hits[r] > 0, [&] { return "escaped between the faces at " + rays[r].target; });
  }
}

// Two faces sharing an edge, seen from both sides: rays aimed along the shared edge.
void sharedEdgeEscapes(Tally& tally, Numerics mode, Rng& rng, const dvec3& center, double size, bool polygon) {
  // A regular pentagon in a random plane: triangle (q0, q1, q2) and, beyond the diagonal q0-q2,
  // either the triangle (q0, q2, q3) (a split quad) or the quad polygon (q0, q2, q3, q4).
  dvec3 n = rng.unitVector(), e1 = perpendicular(n), e2 = glm::cross(n, e1);
  Mesh m;
  for (int k = 0; k < 5; ++k) {
    double a = 6.283185307179586 * k / 5;
    m.vertices.push_back(toFloat(center + size * (std::cos(a) * e1 + std::sin(a) * e2)));
  }
  m.faces.push_back({0, 1, 2});
  if (polygon) {
    m.faces.push_back({0, 2, 3, 4});
  } else {
    m.faces.push_back({0, 2, 3});
  }
  std::vector<vec3> origins;
  for (int k = 0; k < 6; ++k) {
    double side = k % 2 ? 1.0 : -1.0;
    dvec3 o = center + side * n * size * rng.decades(0.0, 2.0) + size * rng.uniform(-1, 1) * e1;
    origins.push_back(toFloat(o));
  }
  // Targets along the interior of the shared edge q0-q2.
  std::vector<gpu::ProbeQuery> queries;
  std::vector<std::string> targets;
  std::vector<glm::vec4> polyVerts;
  for (auto i : m.faces.back()) polyVerts.emplace_back(m.vertices[i], 0.0f);
  vec3 polyNormal =
      unitFloat(glm::cross(dvec3(m.vertices[2]) - dvec3(m.vertices[0]), dvec3(m.vertices[3]) - dvec3(m.vertices[0])));
  const int perEdge = 63;
  for (const vec3& o : origins) {
    for (int k = 1; k <= perEdge; ++k) {
      double s = double(k) / (perEdge + 1);
      vec3 target = toFloat((1 - s) * dvec3(m.vertices[0]) + s * dvec3(m.vertices[2]));
      vec3 d = unitFloat(dvec3(target) - dvec3(o));
      queries.push_back(triangleQuery(o, d, m.vertices[0], m.vertices[1], m.vertices[2], mode));
      if (polygon) {
        queries.push_back(polygonQuery(o, d, polyNormal, 0, 4, mode));
      } else {
        queries.push_back(triangleQuery(o, d, m.vertices[0], m.vertices[2], m.vertices[3], mode));
      }
      targets.push_back(str(dvec3(target)));
    }
  }
  auto results = runProbe(queries, polyVerts);
  for (std::size_t r = 0; r < targets.size(); ++r) {
    bool any = hit(results[2 * r]) || hit(results[2 * r + 1]);
    tally.check(any, [&] {
      return std::string(polygon ? "triangle|polygon" : "split quad") + " size " + str(size) + ": escaped at " +
             targets[r];
    });
  }
}

Tally sharedEdgesFar(Numerics mode) {
  Tally tally{"shared edges at 1e5"};
  Rng rng(601);
  for (double size : {1.0, 10.0, 100.0, 1000.0}) {
    for (int k = 0; k < 6; ++k) {
      dvec3 center = dvec3(rng.sign(), rng.sign(), rng.sign()) *
                     dvec3(rng.uniform(1e5, 2e5), rng.uniform(1e5, 2e5), rng.uniform(1e5, 2e5));
      sharedEdgeEscapes(tally, mode, rng, center, size, k % 2 == 1);
    }
  }
  return tally;
}

TEST(NumericsWatertight, SharedEdgeOfASplitQuadAt1e5) {
  runBoth("6a shared edges at 1e5 (tri|tri, tri|polygon)", sharedEdgesFar, true);
}

Tally closedMeshesFar(Numerics mode) {
  Tally tally{"closed meshes at 1e5, from inside"};
  Rng rng(602);
  for (double size : {1.0, 10.0, 100.0}) {
    dvec3 center(1.2e5, -1.1e5, 1.3e5);
    for (int shape = 0; shape < 2; ++shape) {
      Mesh mesh = shape == 0 ? icosphere(center, size, 2) : mixedCube(center, size);
      std::vector<vec3> origins = {toFloat(center)};
      for (int k = 0; k < 3; ++k) origins.push_back(toFloat(center + 0.5 * size * rng.unitVector()));
      meshEscapes(tally, mode, mesh, origins, 5);
    }
  }
  return tally;
}

TEST(NumericsWatertight, ClosedMeshesAt1e5SeenFromInside) {
  runBoth("6b closed meshes at 1e5 from inside", closedMeshesFar, true);
}

// ---- 7. Degenerate, needle, tiny, huge and grazing triangles --------------------------------------------

Tally degenerateTriangles(Numerics mode) {
  Tally tally{"degenerate triangles"};
  Rng rng(701);
  struct Tri {
    vec3 v[3];
    vec3 o, d;
  };
  std::vector<Tri> rays;
  std::vector<gpu::ProbeQuery> queries;
  for (dvec3 p : {dvec3(0.0), dvec3(1, 2, 3), dvec3(1e3, -2e3, 5e2), dvec3(0.25, -1e4, 3)}) {
    // Power-of-two steps keep the collinear points exact in float: p, p + e, p + 2e (and 4e).
    vec3 a = toFloat(p), e(0.5f, 0.25f, -0.125f);
    std::vector<std::array<vec3, 3>> shapes = {
        {a, a, a}, {a, a, a + e}, {a, a + e, a + 2.0f * e}, {a + 4.0f * e, a, a + e}, {a, a + e, a}};
    for (const auto& s : shapes) {
      dvec3 cr = glm::cross(dvec3(s[1]) - dvec3(s[0]), dvec3(s[2]) - dvec3(s[0]));
      EXPECT_EQ(cr, dvec3(0.0)) << "test set-up: the float vertices must be exactly collinear";
      for (int k = 0; k < 60; ++k) {
        // Aimed at a vertex, or at a point along the degenerate segment.
        dvec3 target = k % 3 == 0 ? dvec3(s[(k / 3) % 3]) : glm::mix(dvec3(s[0]), dvec3(s[2]), rng.uniform());
        vec3 o = toFloat(target + rng.unitVector() * rng.decades(-1.0, 1.0));
        vec3 d = unitFloat(target - dvec3(o));
        rays.push_back({{s[0], s[1], s[2]}, o, d});
        queries.push_back(triangleQuery(o, d, s[0], s[1], s[2], mode));
      }
    }
  }
  auto results = runProbe(queries);
  for (std::size_t i = 0; i < rays.size(); ++i) {
    tally.check(allFinite(results[i]) && !hit(results[i]), [&] {
      return "degenerate " + str(dvec3(rays[i].v[0])) + str(dvec3(rays[i].v[1])) + str(dvec3(rays[i].v[2])) + ": t " +
             str(results[i].hit.x);
    });
  }
  return tally;
}

TEST(NumericsTriangle, DegenerateTrianglesNeverHit) {
  runBoth("7a degenerate triangles", degenerateTriangles, false);
}

// Rays at barycentric targets in [-0.25, 1.25] (about half inside) from origins made by `origin`;
// hit/miss must match the reference wherever the target is farther than baryTol from an edge, and
// barycentrics of hits must be within baryTol.
void triangleAccuracy(Tally& tally, Numerics mode, Rng& rng, const std::array<vec3, 3>& v, int count,
                      const std::function<vec3(const dvec3& target)>& origin, const std::string& what) {
  std::vector<vec3> os, ds;
  std::vector<gpu::ProbeQuery> queries;
  for (int k = 0; k < count; ++k) {
    double b1 = rng.uniform(-0.25, 1.25), b2 = rng.uniform(-0.25, 1.25);
    if (b1 + b2 > 1.25) {
      b1 = 1.0 - b1;
      b2 = 1.0 - b2;
    }
    dvec3 target = (1.0 - b1 - b2) * dvec3(v[0]) + b1 * dvec3(v[1]) + b2 * dvec3(v[2]);
    vec3 o = origin(target);
    vec3 d = unitFloat(target - dvec3(o));
    os.push_back(o);
    ds.push_back(d);
    queries.push_back(triangleQuery(o, d, v[0], v[1], v[2], mode));
  }
  auto results = runProbe(queries);
  for (std::size_t i = 0; i < os.size(); ++i) {
    const gpu::ProbeResult& res = results[i];
    tally.check(allFinite(res), [&] { return what + ": non-finite result"; });
    TriangleRef ref = triangleRef(dvec3(os[i]), dvec3(ds[i]), dvec3(v[0]), dvec3(v[1]), dvec3(v[2]));
    if (!ref.stable()) continue;
    bool expectHit = ref.inside();
    tally.check(hit(res) == expectHit, [&] {
      return what + ": " + (expectHit ? "missed" : "false hit") + ", barycentrics " + str(ref.bary) + " (tolerance " +
             str(ref.baryTol) + ")";
    });
    if (!expectHit || !hit(res)) continue;
    double err = maxAbs(dvec3(res.hit.y, res.hit.z, res.hit.w) - ref.bary);
    tally.noteRatio(err / ref.baryTol);
    tally.check(err <= ref.baryTol, [&] {
      return what + ": barycentrics " + str(dvec3(res.hit.y, res.hit.z, res.hit.w)) + " vs " + str(ref.bary) +
             " (tolerance " + str(ref.baryTol) + ")";
    });
  }
}

// Triangle (p, p + L e1, p + L (e1/2 + w e2)) in a random plane.
std::array<vec3, 3> thinTriangle(Rng& rng, const dvec3& p, double length, double width, dvec3& normal) {
  normal = rng.unitVector();
  dvec3 e1 = perpendicular(normal), e2 = glm::cross(normal, e1);
  return {toFloat(p), toFloat(p + length * e1), toFloat(p + length * (0.5 * e1 + width * e2))};
}

// An origin `dist` away from the target on the normal's side, tilted up to ~40 degrees.
std::function<vec3(const dvec3&)> faceOn(Rng& rng, const dvec3& normal, double dist) {
  return [&rng, normal, dist](const dvec3& target) {
    dvec3 dir = glm::normalize(normal + 0.8 * glm::cross(normal, rng.unitVector()));
    return toFloat(target + dist * dir);
  };
}

Tally hardTriangles(Numerics mode) {
  Tally tally{"needle, tiny, huge and grazing triangles"};
  Rng rng(702);
  dvec3 n;
  for (double width : {1e-2, 1e-3, 1e-4}) {
    for (dvec3 p : {dvec3(0.0), dvec3(3, -2, 1), dvec3(50, 20, -30)}) {
      auto v = thinTriangle(rng, p, 1.0, width, n);
      triangleAccuracy(tally, mode, rng, v, 300, faceOn(rng, n, 1.0), "needle " + str(width));
    }
  }
  for (dvec3 p : {dvec3(0.0), dvec3(0.5, 0.25, -1), dvec3(10, 5, 3)}) {
    auto v = thinTriangle(rng, p, 1e-4, 1.0, n);
    triangleAccuracy(tally, mode, rng, v, 300, faceOn(rng, n, 1e-3), "tiny 1e-4 seen from 1e-3");
    triangleAccuracy(tally, mode, rng, v, 300, faceOn(rng, n, 1.0), "tiny 1e-4 seen from 1");
  }
  for (dvec3 p : {dvec3(0.0), dvec3(-1e3, 2e3, 500)}) {
    auto v = thinTriangle(rng, p, 1e4, 1.0, n);
    triangleAccuracy(tally, mode, rng, v, 300, faceOn(rng, n, 1e4), "huge 1e4");
  }
  // Grazing: the ray meets the plane at angle theta, from one unit away.
  for (double theta : {1e-1, 1e-2, 1e-3, 1e-4}) {
    for (double size : {1.0, 1e-3}) {
      for (dvec3 p : {dvec3(0.0), dvec3(2, 1, -3)}) {
        auto v = thinTriangle(rng, p, size, 1.0, n);
        auto grazing = [&rng, n, theta, size](const dvec3& target) {
          dvec3 t = glm::normalize(glm::cross(n, rng.unitVector()));
          dvec3 dir = std::cos(theta) * t + std::sin(theta) * n;
          return toFloat(target + size * rng.uniform(0.5, 2.0) * dir);
        };
        triangleAccuracy(tally, mode, rng, v, 300, grazing, "grazing " + str(theta) + " rad, size " + str(size));
      }
    }
  }
  return tally;
}

TEST(NumericsTriangle, NeedleTinyHugeAndGrazingTriangles) {
  runBoth("7b needle, tiny, huge, grazing triangles", hardTriangles, true);
}

// ---- 8. Planes -----------------------------------------------------------------------------------------

Tally parallelPlanes(Numerics mode) {
  Tally tally{"parallel rays and origins on planes"};
  Rng rng(801);
  struct Ray {
    vec3 o, d, n;
    float D;
  };
  std::vector<Ray> rays;
  // n.d is exactly zero in float (products of powers of two, or of equal values), however the
  // driver rounds or fuses the dot product.
  const std::array<std::pair<vec3, std::function<vec3()>>, 4> setups = {{
      {vec3(0, 1, 0), [&] { return vec3(float(rng.uniform(-1, 1)), 0.0f, float(rng.uniform(-1, 1))); }},
      {vec3(-1, 0, 0), [&] { return vec3(0.0f, float(rng.uniform(-1, 1)), float(rng.uniform(-1, 1))); }},
      {unitFloat(dvec3(1, 1, 0)), [&] { return vec3(0.5f, -0.5f, float(rng.uniform(-1, 1))); }},
      {unitFloat(dvec3(0, -1, 1)), [&] { return vec3(float(rng.uniform(-1, 1)), 0.25f, 0.25f); }},
  }};
  for (const auto& [n, dir] : setups) {
    for (int k = 0; k < 100; ++k) {
      // Planes at distances up to 1e4; the origin above, below, or on the plane (axis normals).
      float D = static_cast<float>(rng.sign() * rng.decades(-2.0, 4.0));
      vec3 o = toFloat(rng.spreadPoint(-2.0, 3.0));
      if (k % 3 == 0 && (n == vec3(0, 1, 0) || n == vec3(-1, 0, 0))) {
        if (n.y == 1.0f) o.y = -D;
        if (n.x == -1.0f) o.x = D;
      }
      rays.push_back({o, dir(), n, D});
    }
  }
  // Origin exactly on an axis plane, any direction: t = 0 is no hit.
  for (int k = 0; k < 200; ++k) {
    float D = static_cast<float>(rng.sign() * rng.decades(-2.0, 4.0));
    vec3 o = toFloat(rng.spreadPoint(-2.0, 3.0));
    o.y = -D;
    rays.push_back({o, unitFloat(rng.unitVector()), vec3(0, 1, 0), D});
  }
  std::vector<gpu::ProbeQuery> queries;
  for (const auto& r : rays) queries.push_back(planeQuery(r.o, r.d, r.n, r.D, mode));
  auto results = runProbe(queries);
  for (std::size_t i = 0; i < rays.size(); ++i) {
    tally.check(allFinite(results[i]) && !hit(results[i]), [&] {
      return "plane " + str(dvec3(rays[i].n)) + " D " + str(rays[i].D) + ", origin " + str(dvec3(rays[i].o)) +
             ", dir " + str(dvec3(rays[i].d)) + ": t " + str(results[i].hit.x);
    });
  }
  return tally;
}

TEST(NumericsPlane, ParallelRaysAndOriginsOnThePlaneMiss) {
  runBoth("8a plane: parallel rays, origin on the plane", parallelPlanes, false);
}

Tally nearParallelPlanes(Numerics mode) {
  Tally tally{"near-parallel rays, huge t"};
  Rng rng(802);
  struct Ray {
    vec3 o, d, n;
    float D;
  };
  std::vector<Ray> rays;
  for (int k = 0; k < 40; ++k) {
    for (int e = 1; e <= 30; e += (e < 12 ? 1 : 6)) {
      double eps = std::pow(10.0, -e);
      // The floor y = 0 (n.d and n.o + D are exact: t is one rounded division) ...
      vec3 o(float(rng.uniform(-1e3, 1e3)), float(rng.decades(-3.0, 2.0)), float(rng.uniform(-1e3, 1e3)));
      dvec3 t = glm::normalize(dvec3(rng.uniform(-1, 1), 0.0, rng.uniform(-1, 1)));
      rays.push_back({o, unitFloat(t - eps * dvec3(0, 1, 0)), vec3(0, 1, 0), 0.0f});
      // ... and a tilted plane, where the dot products round.
      vec3 n = unitFloat(dvec3(0.3, 1.0, -0.2));
      float D = static_cast<float>(rng.uniform(-10, 10));
      dvec3 tn = glm::normalize(glm::cross(dvec3(n), rng.unitVector()));
      vec3 o2 = toFloat(rng.spreadPoint(-1.0, 2.0));
      double side = glm::dot(dvec3(n), dvec3(o2)) + D > 0.0 ? -1.0 : 1.0;
      rays.push_back({o2, unitFloat(tn + side * eps * dvec3(n)), n, D});
    }
  }
  std::vector<gpu::ProbeQuery> queries;
  for (const auto& r : rays) queries.push_back(planeQuery(r.o, r.d, r.n, r.D, mode));
  auto results = runProbe(queries);
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const Ray& r = rays[i];
    dvec3 o(r.o), d(r.d), n(r.n);
    double tRef = planeRef(o, d, n, r.D);
    if (!(tRef > 0.0) || tRef >= 3.0e38) continue;
    // t = -(n.o + D) / (n.d): each dot product is off by 3 u times the sum of its terms' sizes, the
    // division by one rounding, so t is within 4 u t (1 + kappa_num + kappa_den) plus two ulps,
    // kappa being each sum's condition number (1 for the floor).
    double num = glm::dot(n, o) + r.D, den = glm::dot(n, d);
    double kNum = (std::abs(n.x * o.x) + std::abs(n.y * o.y) + std::abs(n.z * o.z) + std::abs(r.D)) / std::abs(num);
    double kDen = (std::abs(n.x * d.x) + std::abs(n.y * d.y) + std::abs(n.z * d.z)) / std::abs(den);
    double tol = 2.0 * ulpOf(tRef) + 4.0 * kU * tRef * (1.0 + kNum + kDen);
    if (tol > 0.5 * tRef) continue; // too ill-conditioned in float to say more than "finite"
    double err = std::abs(results[i].hit.x - tRef);
    tally.check(allFinite(results[i]), [&] { return "non-finite result at t " + str(tRef); });
    if (hit(results[i])) tally.noteRatio(err / tol);
    tally.check(hit(results[i]) && err <= tol, [&] {
      return "n.d " + str(den) + ": t " + str(results[i].hit.x) + " vs " + str(tRef) + " (tolerance " + str(tol) + ")";
    });
  }
  return tally;
}

TEST(NumericsPlane, NearParallelRaysHitAtHugeT) {
  runBoth("8b plane: near-parallel rays, t to 1e30", nearParallelPlanes, true);
}

// Rays spawned from plane hits (the renderer's "origin on the plane") leave without re-hitting,
// on either side: reflection/shadow rays from spawnOut, transmitted rays from spawnIn.
Tally planeSelfHits(Numerics mode) {
  Tally tally{"plane re-intersection"};
  Rng rng(803);
  struct Ray {
    vec3 o, d, n;
    float D;
  };
  std::vector<Ray> rays;
  std::vector<gpu::ProbeQuery> first;
  for (int k = 0; k < 1500 * sweepScale(); ++k) {
    vec3 n = unitFloat(rng.unitVector());
    float D = static_cast<float>(rng.sign() * rng.decades(-2.0, 4.0));
    dvec3 onPlane = -double(D) * dvec3(n) + rng.spreadPoint(-2.0, 4.0);
    onPlane -= (glm::dot(dvec3(n), onPlane) + D) * dvec3(n);
    vec3 o = toFloat(onPlane + rng.unitVector() * rng.decades(-2.0, 4.0));
    vec3 d = unitFloat(onPlane - dvec3(o));
    rays.push_back({o, d, n, D});
    first.push_back(planeQuery(o, d, n, D, mode));
  }
  auto hits = runProbe(first);
  std::vector<std::size_t> from;
  std::vector<gpu::ProbeQuery> second;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    if (!hit(hits[i])) continue;
    dvec3 n(rays[i].n);
    dvec3 facing = glm::dot(n, dvec3(rays[i].d)) < 0.0 ? n : -n;
    for (int k = 0; k < 16; ++k) {
      bool through = k % 4 == 3;
      vec3 o = through ? spawnIn(hits[i]) : spawnOut(hits[i]);
      vec3 d = unitFloat(rng.hemisphere(through ? -facing : facing));
      from.push_back(i);
      second.push_back(planeQuery(o, d, rays[i].n, rays[i].D, mode));
    }
  }
  auto again = runProbe(second);
  for (std::size_t k = 0; k < second.size(); ++k) {
    const Ray& r = rays[from[k]];
    tally.check(!hit(again[k]), [&] {
      return "re-hit plane D " + str(r.D) + " from " + str(dvec3(second[k].origin)) + " at t " + str(again[k].hit.x);
    });
  }
  return tally;
}

TEST(NumericsPlane, SpawnedRaysNeverReHitThePlane) {
  runBoth("8c plane: spawned rays never re-hit", planeSelfHits, true);
}

// ---- 9. Parallel mirrors -------------------------------------------------------------------------------

// Two mirrors facing each other (planes or square polygons) and rays bouncing between them 16
// times as the kernel's reflection loop does: the nearest hit of the two, the next origin from
// spawnOut, the mirror direction (computed here on the host).
// Every bounce must reach the other mirror: a hit on the mirror just left is a self-hit, a hit
// short of half the distance to the other mirror, or none, means the bounce did not advance.
Tally parallelMirrors(Numerics mode) {
  Tally tally{"parallel mirrors, depth 16"};
  Rng rng(901);
  for (bool polygons : {false, true}) {
    for (double offset : {0.0, 1e2, 1e3, 1e4}) {
      for (double gap : {1e-4, 1e-3, 1e-2, 1e-1, 1.0, 1e2}) {
        // The offset must stay inside the gap: the hit points' error bound is about 24u times the
        // distance from the origin (6u of |o| + |D| + t + |p|), so gaps below 2^-17 of it (about 5
        // bounds) are not resolvable in float and are left out.
        if (gap < 0x1p-17 * offset) continue;
        vec3 n = unitFloat(rng.unitVector());
        dvec3 center = offset * rng.unitVector();
        float dA = static_cast<float>(-glm::dot(dvec3(n), center));
        float dB = static_cast<float>(-glm::dot(dvec3(n), center) - gap);
        dvec3 e1 = perpendicular(dvec3(n)), e2 = glm::cross(dvec3(n), e1);
        double half = 100.0 * gap; // polygons: squares much wider than a bounce travels
        std::vector<glm::vec4> verts;
        for (float D : {dA, dB}) {
          dvec3 c = center + (-double(D) - glm::dot(dvec3(n), center)) * dvec3(n);
          for (dvec3 corner : {-e1 - e2, e1 - e2, e1 + e2, -e1 + e2})
            verts.emplace_back(toFloat(c + half * corner), 0.0f);
        }
        const int rays = 48;
        std::vector<vec3> o(rays), d(rays);
        std::vector<int> last(rays, -1);
        std::vector<bool> alive(rays, true);
        for (int k = 0; k < rays; ++k) {
          o[k] = toFloat(center + dvec3(n) * gap * rng.uniform(0.2, 0.8) + gap * rng.uniform(-1, 1) * e1);
          dvec3 w;
          do w = rng.unitVector();
          while (std::abs(glm::dot(w, dvec3(n))) < 0.2);
          d[k] = unitFloat(w);
        }
        for (int bounce = 0; bounce <= 16; ++bounce) {
          std::vector<gpu::ProbeQuery> queries;
          for (int k = 0; k < rays; ++k) {
            for (int m = 0; m < 2; ++m) {
              if (polygons) {
                queries.push_back(polygonQuery(o[k], d[k], n, 4u * m, 4u, mode));
              } else {
                queries.push_back(planeQuery(o[k], d[k], n, m == 0 ? dA : dB, mode));
              }
            }
          }
          auto results = runProbe(queries, verts);
          for (int k = 0; k < rays; ++k) {
            if (!alive[k]) continue;
            const gpu::ProbeResult& a = results[2 * k];
            const gpu::ProbeResult& b = results[2 * k + 1];
            int m = -1;
            if (hit(a) && (!hit(b) || a.hit.x <= b.hit.x)) m = 0;
            if (hit(b) && (!hit(a) || b.hit.x < a.hit.x)) m = 1;
            // Which mirror the ray truly goes to: the one ahead of it, at the reference distance.
            int ahead = glm::dot(dvec3(d[k]), dvec3(n)) > 0.0 ? 1 : 0;
            double tAhead = planeRef(dvec3(o[k]), dvec3(d[k]), dvec3(n), ahead == 0 ? dA : dB);
            const gpu::ProbeResult& h = m == 1 ? b : a;
            bool ok = m == ahead && h.hit.x >= 0.5 * tAhead;
            tally.check(ok, [&] {
              return std::string(polygons ? "polygon" : "plane") + " mirrors " + str(gap) + " apart at " + str(offset) +
                     ", bounce " + std::to_string(bounce) + ": " +
                     (m < 0 ? std::string("escaped")
                            : (m == last[k] ? "self-hit at t " + str(h.hit.x)
                                            : "hit at t " + str(h.hit.x) + " of " + str(tAhead)));
            });
            if (!ok) {
              alive[k] = false;
              continue;
            }
            dvec3 nf = glm::dot(dvec3(n), dvec3(d[k])) < 0.0 ? dvec3(n) : -dvec3(n);
            d[k] = unitFloat(dvec3(d[k]) - 2.0 * glm::dot(dvec3(d[k]), nf) * nf);
            o[k] = spawnOut(h);
            last[k] = m;
          }
        }
      }
    }
  }
  return tally;
}

TEST(NumericsMirrors, ParallelMirrorsToDepth16) {
  runBoth("9 parallel mirrors, 16 bounces", parallelMirrors, true);
}

// The other side of the offset: a transmitted ray spawned through the front face of a thin slab
// (two parallel planes or polygons) must still meet the back face; an offset larger than the slab
// would step over it. Then, spawned through the back face, it must leave without hitting either.
Tally thinSlabs(Numerics mode) {
  Tally tally{"thin slabs"};
  Rng rng(902);
  for (bool polygons : {false, true}) {
    for (double offset : {0.0, 1e2, 1e3, 1e4}) {
      for (double gap : {1e-4, 1e-3, 1e-2, 1e-1, 1.0, 1e2}) {
        if (gap < 0x1p-17 * offset) continue; // as for the mirrors
        vec3 n = unitFloat(rng.unitVector());
        dvec3 center = offset * rng.unitVector();
        float dA = static_cast<float>(-glm::dot(dvec3(n), center));
        float dB = static_cast<float>(-glm::dot(dvec3(n), center) - gap);
        dvec3 e1 = perpendicular(dvec3(n)), e2 = glm::cross(dvec3(n), e1);
        std::vector<glm::vec4> verts;
        for (float D : {dA, dB}) {
          dvec3 c = center + (-double(D) - glm::dot(dvec3(n), center)) * dvec3(n);
          for (dvec3 corner : {-e1 - e2, e1 - e2, e1 + e2, -e1 + e2})
            verts.emplace_back(toFloat(c + (10.0 + 100.0 * gap) * corner), 0.0f);
        }
        auto query = [&](vec3 o, vec3 d, int m) {
          return polygons ? polygonQuery(o, d, n, 4u * m, 4u, mode) : planeQuery(o, d, n, m == 0 ? dA : dB, mode);
        };
        std::vector<vec3> o, d;
        std::vector<gpu::ProbeQuery> first;
        for (int k = 0; k < 48; ++k) {
          dvec3 w;
          do w = rng.unitVector();
          while (glm::dot(w, dvec3(n)) < 0.2);
          d.push_back(unitFloat(w));
          // From below plane A (the side away from B), aimed at a point of A near the centre.
          dvec3 target = center + rng.uniform(-1, 1) * e1 + rng.uniform(-1, 1) * e2;
          o.push_back(toFloat(target - dvec3(d.back()) * rng.decades(-1.0, 1.0) * std::max(gap, 1.0)));
          first.push_back(query(o.back(), d.back(), 0));
        }
        auto entry = runProbe(first, verts);
        std::vector<gpu::ProbeQuery> second, third;
        std::vector<int> ray;
        for (int k = 0; k < 48; ++k) {
          if (!hit(entry[k])) continue;
          ray.push_back(k);
          second.push_back(query(spawnIn(entry[k]), d[k], 1));
          second.push_back(query(spawnIn(entry[k]), d[k], 0));
        }
        auto inside = runProbe(second, verts);
        for (std::size_t i = 0; i < ray.size(); ++i) {
          const gpu::ProbeResult& back = inside[2 * i];
          const gpu::ProbeResult& front = inside[2 * i + 1];
          double tRef = planeRef(dvec3(second[2 * i].origin), dvec3(d[ray[i]]), dvec3(n), dB);
          bool ok = hit(back) && !hit(front) && back.hit.x >= 0.5 * tRef;
          tally.check(ok, [&] {
            return std::string(polygons ? "polygon" : "plane") + " slab " + str(gap) + " thick at " + str(offset) +
                   ": " +
                   (hit(front)  ? "re-hit the front face"
                    : hit(back) ? "back face at t " + str(back.hit.x) + " of " + str(tRef)
                                : "stepped over the back face");
          });
          if (ok) third.push_back(query(spawnIn(back), d[ray[i]], 1));
          if (ok) third.push_back(query(spawnIn(back), d[ray[i]], 0));
        }
        auto after = runProbe(third, verts);
        for (std::size_t i = 0; i < after.size(); ++i) {
          tally.check(!hit(after[i]), [&] {
            return "slab " + str(gap) + " thick at " + str(offset) + ": leaving ray re-hit at t " + str(after[i].hit.x);
          });
        }
      }
    }
  }
  return tally;
}

TEST(NumericsMirrors, ThinSlabsAreNeverSteppedOver) {
  runBoth("9b thin slabs, transmitted rays", thinSlabs, true);
}

// ---- 10. Concave corner -------------------------------------------------------------------------------

// A floor (plane y = 0 or a polygon) meeting a wall (polygon or two triangles, x = 0, 2 high), the
// light behind the wall: every floor point in front of it lies in the wall's shadow, down to the
// corner. A shadow ray from a floor point x away from the wall crosses it about 1.5 x above the
// floor, at t ~ x: a fixed epsilon on t lets the light leak in along the corner.
Tally concaveCorner(Numerics mode) {
  Tally tally{"concave corner"};
  Rng rng(1001);
  for (double scale : {1e-3, 1.0, 1e3}) {
    for (dvec3 shift : {dvec3(0.0), dvec3(1e3, -500, 2e3)}) {
      for (int variant = 0; variant < 2; ++variant) {
        bool polygonFloor = variant == 1;
        vec3 T = toFloat(shift);
        auto at = [&](double x, double y, double z) { return toFloat(dvec3(T) + scale * dvec3(x, y, z)); };
        std::vector<glm::vec4> verts;
        // Wall x = T.x: corners at y = T.y .. T.y + 2, z = T.z -/+ 5 (exact: T's own coordinates).
        vec3 w0 = at(0, 0, -5), w1 = at(0, 0, 5), w2 = at(0, 2, 5), w3 = at(0, 2, -5);
        w0.x = w1.x = w2.x = w3.x = T.x;
        w0.y = w1.y = T.y;
        for (vec3 w : {w0, w1, w2, w3}) verts.emplace_back(w, 0.0f);
        // Floor polygon y = T.y, in front of the wall.
        vec3 f0 = at(0, 0, -5), f1 = at(10, 0, -5), f2 = at(10, 0, 5), f3 = at(0, 0, 5);
        f0.x = f3.x = T.x;
        for (vec3* f : {&f0, &f1, &f2, &f3}) f->y = T.y;
        for (vec3 f : {f0, f3, f2, f1}) verts.emplace_back(f, 0.0f); // wound to face +y
        vec3 light = at(-2, 3, 0.4), eye = at(3, 2, 0.5);
        struct Ray {
          vec3 d;
          double x;
        };
        std::vector<Ray> rays;
        std::vector<gpu::ProbeQuery> first;
        for (int k = 0; k < 100; ++k) {
          double x = rng.decades(-7.0, -1.0);
          dvec3 target(dvec3(T).x + scale * x, T.y, dvec3(T).z + scale * rng.uniform(-2, 2));
          vec3 d = unitFloat(target - dvec3(eye));
          rays.push_back({d, x});
          if (polygonFloor) {
            first.push_back(polygonQuery(eye, d, vec3(0, 1, 0), 4, 4, mode));
          } else {
            first.push_back(planeQuery(eye, d, vec3(0, 1, 0), -T.y, mode));
          }
        }
        auto floorHits = runProbe(first, verts);
        std::vector<gpu::ProbeQuery> shadow;
        std::vector<std::size_t> from;
        for (std::size_t k = 0; k < rays.size(); ++k) {
          if (!hit(floorHits[k])) continue;
          // The floor point in double, from the float ray; its distance from the wall must exceed
          // the float error of the computed hit point, 8 u (|eye| + t + |p|), to be decidable.
          double tRef = planeRef(dvec3(eye), dvec3(rays[k].d), dvec3(0, 1, 0), -T.y);
          dvec3 p = dvec3(eye) + tRef * dvec3(rays[k].d);
          double band = 8.0 * kU * (maxAbs(dvec3(eye)) + tRef + maxAbs(p));
          if (p.x - T.x <= band) continue;
          vec3 o = spawnOut(floorHits[k]);
          dvec3 toLight = dvec3(light) - dvec3(o);
          float dist = static_cast<float>(glm::length(toLight));
          vec3 d = unitFloat(toLight);
          from.push_back(k);
          if (variant == 0) {
            shadow.push_back(polygonQuery(o, d, vec3(1, 0, 0), 0, 4, mode, dist));
          } else {
            // The wall as two triangles sharing the diagonal w0-w2.
            shadow.push_back(triangleQuery(o, d, w0, w1, w2, mode, dist));
            shadow.push_back(triangleQuery(o, d, w0, w2, w3, mode, dist));
          }
        }
        auto blocked = runProbe(shadow, verts);
        std::size_t per = variant == 0 ? 1 : 2;
        for (std::size_t s = 0; s < from.size(); ++s) {
          bool any = hit(blocked[per * s]) || (per == 2 && hit(blocked[per * s + 1]));
          tally.check(any, [&] {
            return "scale " + str(scale) + " at " + str(dvec3(T)) + ": floor point " + str(rays[from[s]].x * scale) +
                   " from the wall is lit";
          });
        }
      }
    }
  }
  return tally;
}

TEST(NumericsCorner, WallShadowsTheFloorRightUpToTheCorner) {
  runBoth("10 concave corner: the wall's shadow", concaveCorner, true);
}

} // namespace
} // namespace vkray::test::numerics
