// Framing and default lighting for scenes that do not say (see model_scene.h).
#include "scene/model_scene.h"

#include <algorithm>
#include <cmath>

#include "scene/mesh_import.h"
#include "scene/scene_limits.h"
#include "util/error.h"

namespace vkray {

using glm::dvec3;

Bounds sceneBounds(const Scene& scene) {
  Bounds b;
  for (const Sphere& s : scene.spheres) {
    b.add(s.center - dvec3(s.radius));
    b.add(s.center + dvec3(s.radius));
  }
  for (const Polygon& p : scene.polygons) {
    for (const dvec3& v : p.vertices) b.add(v);
  }
  for (const Triangle& t : scene.triangles) {
    for (const dvec3& v : t.v) b.add(v);
  }
  return b;
}

Bounds meshBounds(const Scene& scene, const MeshInfo& mesh) {
  Bounds b;
  for (std::size_t i = mesh.firstTriangle; i < mesh.firstTriangle + mesh.triangleCount; ++i) {
    for (const dvec3& v : scene.triangles[i].v) b.add(v);
  }
  return b;
}

Camera fitCamera(const Bounds& bounds, const dvec3& from, double fovY, double aspect, const std::string& where) {
  if (bounds.empty()) throw InputError(where, "nothing to frame: the scene has no sphere, polygon, triangle or mesh");
  double r = bounds.radius();
  if (!(r > 0.0)) r = 1.0; // a single point: any distance shows it
  double tanHalf = std::tan(glm::radians(fovY) * 0.5);
  double tanFit = (1.0 - kFitMargin) * std::min(1.0, aspect) * tanHalf;
  double distance = r / std::sin(std::atan(tanFit));
  Camera c;
  c.fovY = fovY;
  c.lookAt = bounds.center();
  c.position = c.lookAt + glm::normalize(from) * distance;
  return c;
}

void refitCamera(Scene& scene) {
  if (!scene.fitFrom) return;
  Camera fitted = fitCamera(sceneBounds(scene), *scene.fitFrom, scene.camera.fovY,
                            static_cast<double>(scene.render.width) / scene.render.height, scene.path.string());
  fitted.up = scene.camera.up;
  fitted.aperture = scene.camera.aperture;
  fitted.focusDistance = scene.camera.focusDistance;
  scene.camera = fitted;
}

void addDefaultLights(const Bounds& bounds, const Camera& camera, Scene& scene) {
  // The camera's frame: lights sit relative to the view so the model is lit from the front.
  dvec3 back = glm::normalize(camera.position - camera.lookAt);
  dvec3 right = glm::cross(camera.up, back);
  right = glm::length(right) > 0.0 ? glm::normalize(right) : dvec3(1, 0, 0);
  dvec3 up = glm::cross(back, right);
  double r = std::max(bounds.radius(), 1e-6);
  dvec3 c = bounds.center();
  PointLight key; // above and to the left of the camera
  key.position = c + 4.0 * r * glm::normalize(-0.6 * right + 1.0 * up + 0.8 * back);
  key.color = dvec3(0.8);
  key.shadows = true;
  PointLight fill; // low on the other side, no second shadow
  fill.position = c + 4.0 * r * glm::normalize(0.9 * right + 0.1 * up + 0.6 * back);
  fill.color = dvec3(0.3);
  fill.shadows = false;
  scene.lights.push_back(key);
  scene.lights.push_back(fill);
  scene.ambientLight = dvec3(0.2);
}

bool isModelFile(const std::filesystem::path& path) {
  return meshReaderFor(path) != nullptr;
}

Scene loadModelScene(const std::filesystem::path& path, const ModelSceneOptions& options) {
  Scene scene;
  scene.path = path;
  scene.background = options.background.value_or(dvec3(0.1, 0.12, 0.15));
  MeshRequest request;
  request.file = path;
  request.shownAs = path.string();
  request.importPresent = true;
  request.defaultMissingMaterials = true;
  std::optional<Camera> camera = importMesh(request, scene);
  const Bounds bounds = meshBounds(scene, scene.meshes.back());
  if (camera) {
    scene.camera = *camera;
  } else {
    scene.camera = fitCamera(bounds, kThreeQuarterView, 40.0,
                             static_cast<double>(scene.render.width) / scene.render.height, request.shownAs);
    scene.fitFrom = kThreeQuarterView;
  }
  if (scene.lights.empty()) {
    addDefaultLights(bounds, scene.camera, scene);
  } else {
    scene.ambientLight = dvec3(0.1);
  }
  if (options.floor) {
    // Just under the model (a thousandth of its size), so it stands on the floor without touching it.
    Plane floor;
    floor.normal = dvec3(0.0, 1.0, 0.0);
    floor.offset = -(bounds.lo.y - 1e-3 * std::max(bounds.radius(), 1e-6));
    Material m;
    m.name = "(floor)";
    m.color = dvec3(0.6);
    m.diffuse = 0.8;
    m.ambient = 0.8;
    floor.material = static_cast<std::uint32_t>(scene.materials.size());
    scene.materials.push_back(m);
    scene.planes.push_back(floor);
  }
  if (scene.materials.size() > kMaxMaterialCount) {
    throw InputError(request.shownAs, "too many materials: " + std::to_string(scene.materials.size()) + " (at most " +
                                          std::to_string(kMaxMaterialCount) + ")");
  }
  return scene;
}

} // namespace vkray
