// Scene analysis (see features.h).
#include "scene/features.h"

#include <algorithm>
#include <cstdio>

#include "../../shaders/shared/gpu_types.h"

namespace vkray {

namespace {

std::string plural(std::size_t n, const char* word) {
  return std::to_string(n) + " " + word + (n == 1 ? "" : "s");
}

std::string fmt(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}

} // namespace

Features analyzeScene(const Scene& scene, const RenderSettings& settings) {
  Features f;
  f.spheres = !scene.spheres.empty();
  f.planes = !scene.planes.empty();
  f.triangles = !scene.triangles.empty();
  f.polygons = !scene.polygons.empty();
  f.smoothNormals = std::any_of(scene.triangles.begin(), scene.triangles.end(),
                                [](const Triangle& t) { return t.normals.has_value(); });
  for (const Material& m : scene.materials) {
    if (m.checker) f.checker = true;
    if (m.reflection > 0.0) f.anyReflectiveMaterial = true;
    if (m.transmission > 0.0) f.anyTransmissiveMaterial = true;
    f.maxBranchWeight = std::max(f.maxBranchWeight, std::min(1.0, m.reflection + m.transmission));
  }
  f.lights = static_cast<int>(scene.lights.size());
  f.shadowLights = static_cast<int>(
      std::count_if(scene.lights.begin(), scene.lights.end(), [](const PointLight& l) { return l.shadows; }));
  f.occluderPossible = scene.objectCount() >= 2;
  f.shadows = f.shadowLights > 0 && f.occluderPossible;
  f.boundedPrimitives = scene.boundedPrimitiveCount();
  f.applySettings(settings);
  return f;
}

void Features::applySettings(const RenderSettings& settings) {
  // A dielectric reflects too (Fresnel, total internal reflection).
  reflection = anyReflectiveMaterial || anyTransmissiveMaterial;
  refraction = anyTransmissiveMaterial;
  requestedDepth = settings.maxDepth;
  usableDepth = 0;
  if (reflection && maxBranchWeight > 0.0) {
    // Depth k carries weight at most maxBranchWeight^k; past the bailout nothing more is traced.
    // The 1e-6 slack keeps this conservative against float rounding of the weights on the GPU.
    double w = 1.0;
    while (usableDepth < settings.maxDepth) {
      double next = w * maxBranchWeight;
      if (settings.bailout > 0.0 && next < settings.bailout * (1.0 - 1e-6)) break;
      w = next;
      ++usableDepth;
    }
  }
  if (usableDepth == 0) {
    reflection = false;
    refraction = false;
  }
  stackSize = std::clamp(usableDepth, 1, static_cast<int>(gpu::kMaxStackSize));
  stackTruncated = refraction && usableDepth > static_cast<int>(gpu::kMaxStackSize);
  useBvh = boundedPrimitives > 0 && (settings.bvh == BvhMode::On ||
                                     (settings.bvh == BvhMode::Auto && boundedPrimitives >= kBvhAutoThreshold));
}

std::vector<std::string> Features::explain() const {
  std::vector<std::string> lines;
  std::string prims;
  auto add = [&](bool present, const char* name) {
    if (present) prims += (prims.empty() ? "" : ", ") + std::string(name);
  };
  add(spheres, "spheres");
  add(planes, "planes");
  add(polygons, "polygons");
  add(triangles, smoothNormals ? "triangles (smooth normals)" : "triangles");
  lines.push_back("primitives: " + (prims.empty() ? std::string("none") : prims) +
                  " (code for absent kinds is compiled out)");

  if (shadows) {
    lines.push_back("shadows: on (" + plural(static_cast<std::size_t>(shadowLights), "light") + ")");
  } else if (lights == 0) {
    lines.push_back("shadows: off — no lights");
  } else if (shadowLights == 0) {
    lines.push_back("shadows: off — every light has shadows: false");
  } else {
    lines.push_back("shadows: off — a single object cannot shadow itself");
  }

  if (reflection) {
    std::string line = "reflection: on, up to depth " + std::to_string(usableDepth);
    if (usableDepth < requestedDepth) {
      line += " (max_depth " + std::to_string(requestedDepth) + ", but weights <= " + fmt(maxBranchWeight) +
              " per bounce fall below the bailout after " + std::to_string(usableDepth) + ")";
    }
    lines.push_back(line);
  } else if (requestedDepth == 0) {
    lines.push_back("reflection: off — max_depth is 0");
  } else if (!anyReflectiveMaterial && !anyTransmissiveMaterial) {
    lines.push_back("reflection: off — no reflective or transmissive material");
  } else {
    lines.push_back("reflection: off — the first bounce already weighs less than the bailout");
  }

  if (refraction) {
    std::string line = "refraction: on (full ray tree, up to " + std::to_string(stackSize) + " pending branches)";
    if (stackTruncated) line += "; branches beyond depth " + std::to_string(stackSize) + " are dropped and counted";
    lines.push_back(line);
  } else if (anyTransmissiveMaterial) {
    lines.push_back("refraction: off — transmissive materials exist but max_depth/bailout allow no bounce");
  } else {
    lines.push_back("refraction: off — no transmissive material");
  }

  if (useBvh) {
    lines.push_back("acceleration: BVH over " + plural(boundedPrimitives, "bounded primitive") +
                    (planes ? "; planes tested separately" : ""));
  } else {
    lines.push_back("acceleration: none, every ray tests all " + plural(boundedPrimitives, "bounded primitive"));
  }
  return lines;
}

} // namespace vkray
