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

std::vector<bool> planesThatCanOcclude(const Scene& scene) {
  std::vector<bool> result(scene.planes.size(), false);
  for (std::size_t p = 0; p < scene.planes.size(); ++p) {
    const Plane& plane = scene.planes[p];
    auto side = [&](const glm::dvec3& x) { return glm::dot(plane.normal, x) + plane.offset; };
    bool may = false;
    for (const PointLight& light : scene.lights) {
      if (!light.shadows) continue;
      double sl = side(light.position);
      if (sl == 0.0) {
        may = true; // a light in the plane: keep it simple and conservative
        break;
      }
      double dir = sl > 0.0 ? 1.0 : -1.0;
      // Is some surface point strictly on the other side from this light?
      auto opposite = [&](double signedDistance) { return dir * signedDistance < 0.0; };
      for (std::size_t q = 0; q < scene.planes.size() && !may; ++q) {
        if (q == p) continue;
        const Plane& other = scene.planes[q];
        if (glm::length(glm::cross(plane.normal, other.normal)) > 0.0) {
          may = true; // non-parallel planes cross: the other one has points on both sides
        } else if (opposite(side(-other.offset * other.normal))) {
          may = true;
        }
      }
      for (const Sphere& s : scene.spheres) {
        if (may) break;
        if (dir * side(s.center) - s.radius < 0.0) may = true;
      }
      for (const Polygon& poly : scene.polygons) {
        for (const auto& v : poly.vertices) may = may || opposite(side(v));
      }
      for (const Triangle& t : scene.triangles) {
        if (may) break;
        for (const auto& v : t.v) may = may || opposite(side(v));
      }
      if (may) break;
    }
    result[p] = may;
  }
  return result;
}

Features analyzeScene(const Scene& scene, const RenderSettings& settings) {
  Features f;
  f.spheres = !scene.spheres.empty();
  f.planes = !scene.planes.empty();
  f.planeCount = static_cast<int>(scene.planes.size());
  f.triangles = !scene.triangles.empty();
  f.polygons = !scene.polygons.empty();
  f.smoothNormals = std::any_of(scene.triangles.begin(), scene.triangles.end(),
                                [](const Triangle& t) { return t.normals.has_value(); });
  f.thinLens = scene.camera.aperture > 0.0;
  f.aperture = scene.camera.aperture;
  f.focusDistance = scene.camera.focusDistanceOrDefault();
  f.textures = std::any_of(scene.triangles.begin(), scene.triangles.end(), [&](const Triangle& t) {
    return t.uvs.has_value() && scene.materials[t.material].baseColorTexture.has_value();
  });
  f.vertexColors = std::any_of(scene.triangles.begin(), scene.triangles.end(),
                               [](const Triangle& t) { return t.colors.has_value(); });
  f.alphaMask = std::any_of(scene.triangles.begin(), scene.triangles.end(),
                            [&](const Triangle& t) { return scene.materials[t.material].alphaCutoff > 0.0; });
  for (const Material& m : scene.materials) {
    if (m.checker) f.checker = true;
    if (m.reflection > 0.0) f.anyReflectiveMaterial = true;
    if (m.transmission > 0.0) f.anyTransmissiveMaterial = true;
    if (m.diffuse <= 0.0 && m.specular > 0.0) f.specularOnlyMaterial = true;
    f.maxBranchWeight = std::max(f.maxBranchWeight, std::min(1.0, m.reflection + m.transmission));
  }
  f.lights = static_cast<int>(scene.lights.size());
  f.shadowLights = static_cast<int>(
      std::count_if(scene.lights.begin(), scene.lights.end(), [](const PointLight& l) { return l.shadows; }));
  f.occluderPossible = scene.objectCount() >= 2;
  f.shadows = f.shadowLights > 0 && f.occluderPossible;
  auto occluding = planesThatCanOcclude(scene);
  f.occluderPlanes = static_cast<int>(std::count(occluding.begin(), occluding.end(), true));
  f.boundedPrimitives = scene.boundedPrimitiveCount();
  f.applySettings(settings);
  return f;
}

void Features::applySettings(const RenderSettings& settings) {
  forward = settings.method == Method::Forward;
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
  useBvh = boundedPrimitives > 0 &&
           (settings.bvh == BvhMode::On || (settings.bvh == BvhMode::Auto && boundedPrimitives >= kBvhAutoThreshold));
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
  // Said only when on: a scene without textures explains itself as before.
  if (textures) lines.push_back("textures: on (base-colour textures on triangles; sampling compiled in)");
  if (vertexColors) lines.push_back("vertex colours: on (they multiply the base colour)");
  if (alphaMask) lines.push_back("alpha mask: on (cut-out triangles, for shadow rays too)");
  if (forward) {
    lines.push_back(std::string("method: forward — photons from ") + plural(static_cast<std::size_t>(lights), "light") +
                    ", counted where they pass through the lens" +
                    (thinLens ? "" : " (this camera is a pinhole: none can; give camera.aperture > 0)") +
                    "; no ambient term or background (no light path carries them)");
  }
  if (thinLens) {
    lines.push_back("depth of field: on (thin lens, radius " + fmt(aperture) + ", in focus at " + fmt(focusDistance) +
                    "; BVH entry points and row culling off)");
  }

  if (shadows) {
    std::string line = "shadows: on (" + plural(static_cast<std::size_t>(shadowLights), "light") + ")";
    int skipped = planes ? planeCount - occluderPlanes : 0;
    if (skipped > 0) {
      line += "; " + plural(static_cast<std::size_t>(skipped), "plane") + " cannot cast a shadow and " +
              (skipped == 1 ? "is" : "are") + " left out of shadow rays";
    }
    lines.push_back(line);
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
