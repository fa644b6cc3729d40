// A model file as a scene, and the framing that needs: bounds of what a scene holds, a camera that
// provably has it all in frame, default lights placed from the bounds. Pure functions of the Scene;
// docs/meshes.md ("A model file is a scene") describes the choices.
#pragma once

#include <filesystem>
#include <limits>
#include <optional>
#include <string>

#include <glm/glm.hpp>

#include "scene/scene.h"

namespace vkray {

// An axis-aligned box; empty until something is added.
struct Bounds {
  glm::dvec3 lo{std::numeric_limits<double>::infinity()};
  glm::dvec3 hi{-std::numeric_limits<double>::infinity()};

  bool empty() const { return !(lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z); }
  void add(const glm::dvec3& p) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  glm::dvec3 center() const { return 0.5 * (lo + hi); }
  // The box's circumscribed sphere: it holds every point of the box.
  double radius() const { return 0.5 * glm::length(hi - lo); }
};

// Spheres, polygons and triangles (planes are unbounded and left out).
Bounds sceneBounds(const Scene& scene);
// The triangles one mesh added.
Bounds meshBounds(const Scene& scene, const MeshInfo& mesh);

// The three-quarter view a model is shown from when nothing else says: up and to the right, in front.
inline constexpr glm::dvec3 kThreeQuarterView{0.6, 0.5, 0.8};
// Of the half-width and half-height of the image, the share that stays free around a fitted model.
inline constexpr double kFitMargin = 0.05;

// A camera looking from `from` (a direction) at the centre of `bounds`, fovY degrees vertical, far
// enough back that the bounding sphere's image lies inside the image shrunk by kFitMargin on every
// side: the sphere seen from distance d fills a cone of half-angle asin(r / d), and d is chosen so
// that tan of that angle is (1 - margin) times the smaller of tan(fovX / 2) and tan(fovY / 2).
// Throws InputError (naming `where`) when the bounds are empty.
Camera fitCamera(const Bounds& bounds, const glm::dvec3& from, double fovY, double aspect, const std::string& where);

// When scene.fitFrom is set: the camera refitted to every bounded object at the image's current
// aspect (after the command line changed width or height). Keeps camera.fovY and camera.up.
void refitCamera(Scene& scene);

// A key light (shadows) and a fill (none), placed around the bounds relative to the camera, and a
// soft ambient light.
void addDefaultLights(const Bounds& bounds, const Camera& camera, Scene& scene);

// Every format the mesh dispatch reads (mesh_import.h: meshReaderFor; .obj, .gltf, .glb): files
// `vkray render` and `vkray view` open as scenes.
bool isModelFile(const std::filesystem::path& path);

struct ModelSceneOptions {
  bool floor = false;                   // a ground plane just under the model
  std::optional<glm::dvec3> background; // linear RGB; default a dark blue-grey
};

// The model as a mesh object, with the file's camera (glTF) or a fitted one, the file's point and
// spot lights (glTF KHR_lights_punctual) or the default lights.
Scene loadModelScene(const std::filesystem::path& path, const ModelSceneOptions& options = {});

} // namespace vkray
