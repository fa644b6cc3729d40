// Animation keys from JSON, their interpolation, and the static scene of frame N.
#include "scene/animation.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/gtc/matrix_transform.hpp>

#include "scene/json_reader.h"
#include "scene/mesh_import.h"
#include "util/error.h"

namespace vkray {

namespace {

using glm::dvec3;

inline constexpr long long kMaxFrames = 1000000;

const char* kindName(ObjectKind kind) {
  switch (kind) {
  case ObjectKind::Sphere:
    return "a sphere";
  case ObjectKind::Plane:
    return "a plane";
  case ObjectKind::Polygon:
    return "a polygon";
  case ObjectKind::Triangle:
    return "a triangle";
  case ObjectKind::Mesh:
    return "a mesh";
  }
  return "an object";
}

// A key's frame: in range and after the previous key's.
int readFrame(const JsonNode& key, int frames, int previous) {
  int f = static_cast<int>(key.at("frame").integer(0, frames - 1));
  if (f <= previous) {
    key.at("frame").fail("keys must be in increasing frame order: " + std::to_string(f) +
                         " does not come after the previous key's " + std::to_string(previous));
  }
  return f;
}

template <typename T> void addKey(Track<T>& track, int frame, T value) {
  track.frames.push_back(frame);
  track.values.push_back(value);
}

dvec3 readScale(const JsonNode& node) {
  dvec3 s = node.isArray() ? node.vec3() : dvec3(node.number());
  for (int i = 0; i < 3; ++i) {
    if (!(s[i] > 0.0)) node.fail("must be > 0, got " + formatNumber(s[i]));
  }
  return s;
}

void readCameraKeys(const JsonNode& node, Animation& a) {
  node.expectArray();
  int previous = -1;
  for (std::size_t i = 0; i < node.size(); ++i) {
    JsonNode key = node[i];
    // The lens is the camera's, fixed over the frames (an unset focus_distance follows look_at).
    for (const char* lens : {"aperture", "focus_distance"}) {
      if (auto v = key.find(lens)) v->fail("is not animated; give it in camera (the same for every frame)");
    }
    key.allowKeys({"frame", "position", "look_at", "up", "fov_y"});
    int f = readFrame(key, a.frames, previous);
    previous = f;
    bool any = false;
    if (auto v = key.find("position")) addKey(a.camera.position, f, v->vec3()), any = true;
    if (auto v = key.find("look_at")) addKey(a.camera.lookAt, f, v->vec3()), any = true;
    if (auto v = key.find("up")) addKey(a.camera.up, f, v->nonZeroVec3()), any = true;
    if (auto v = key.find("fov_y")) {
      double fov = v->number();
      if (!(fov > 0.0 && fov < 180.0)) v->fail("must be in (0, 180) degrees, got " + formatNumber(fov));
      addKey(a.camera.fovY, f, fov);
      any = true;
    }
    if (!any) key.fail("gives nothing to animate (position, look_at, up or fov_y)");
  }
}

// Centre of the axis-aligned bounds of a mesh's triangles as the static scene places them.
dvec3 meshCentre(const Scene& scene, const NamedObject& o) {
  dvec3 lo(std::numeric_limits<double>::infinity());
  dvec3 hi(-std::numeric_limits<double>::infinity());
  for (std::size_t t = o.first; t < o.first + o.count; ++t) {
    for (const dvec3& v : scene.triangles[t].v) {
      lo = glm::min(lo, v);
      hi = glm::max(hi, v);
    }
  }
  return o.count > 0 ? 0.5 * (lo + hi) : dvec3(0.0);
}

// The scene's object or light called `name`; refused at `keys` with the names there are.
template <class Named>
typename std::vector<Named>::const_iterator findNamed(const std::vector<Named>& named, const std::string& name,
                                                      const JsonNode& keys, const std::string& what) {
  auto it = std::find_if(named.begin(), named.end(), [&](const Named& n) { return n.name == name; });
  if (it == named.end()) {
    std::string known;
    for (const Named& n : named) known += (known.empty() ? "" : ", ") + n.name;
    keys.fail("no " + what + " is named '" + name + "'" +
              (known.empty() ? " (no " + what + " has a \"name\")" : " (named " + what + "s: " + known + ")"));
  }
  return it;
}

void readObjectKeys(const JsonNode& node, const Scene& scene, Animation& a) {
  for (auto& [name, keys] : node.members()) {
    auto it = findNamed(scene.namedObjects, name, keys, "object");
    ObjectTracks tracks;
    tracks.name = name;
    tracks.path = keys.path();
    tracks.object = static_cast<std::size_t>(it - scene.namedObjects.begin());
    const bool mesh = it->kind == ObjectKind::Mesh;
    if (mesh) tracks.centre = meshCentre(scene, *it);
    keys.expectArray();
    int previous = -1;
    for (std::size_t i = 0; i < keys.size(); ++i) {
      JsonNode key = keys[i];
      key.allowKeys({"frame", "translate", "rotate", "scale"});
      int f = readFrame(key, a.frames, previous);
      previous = f;
      bool any = false;
      if (auto v = key.find("translate")) addKey(tracks.translate, f, v->vec3()), any = true;
      for (const char* meshOnly : {"rotate", "scale"}) {
        auto v = key.find(meshOnly);
        if (!v) continue;
        if (!mesh) v->fail(std::string("animates meshes only; '") + name + "' is " + kindName(it->kind));
        if (meshOnly[0] == 'r')
          addKey(tracks.rotate, f, v->vec3());
        else
          addKey(tracks.scale, f, readScale(*v));
        any = true;
      }
      if (!any) key.fail(mesh ? "gives nothing to animate (translate, rotate or scale)" : "gives no translate");
    }
    a.objects.push_back(std::move(tracks));
  }
}

void readLightKeys(const JsonNode& node, const Scene& scene, Animation& a) {
  for (auto& [name, keys] : node.members()) {
    auto it = findNamed(scene.namedLights, name, keys, "light");
    LightTracks tracks;
    tracks.name = name;
    tracks.path = keys.path();
    tracks.light = it->index;
    keys.expectArray();
    int previous = -1;
    for (std::size_t i = 0; i < keys.size(); ++i) {
      JsonNode key = keys[i];
      key.allowKeys({"frame", "position"});
      int f = readFrame(key, a.frames, previous);
      previous = f;
      addKey(tracks.position, f, key.at("position").vec3());
    }
    a.lights.push_back(std::move(tracks));
  }
}

template <typename T> T tangent(const Track<T>& t, std::size_t i) {
  const std::size_t n = t.frames.size();
  std::size_t a = i == 0 ? 0 : i - 1;
  std::size_t b = i + 1 == n ? i : i + 1;
  return (t.values[b] - t.values[a]) / static_cast<double>(t.frames[b] - t.frames[a]);
}

template <typename T> T evaluate(const Track<T>& t, double frame, Interpolation mode) {
  // Held before the first key and after the last (and at a key, exactly its value).
  if (frame <= t.frames.front()) return t.values.front();
  if (frame >= t.frames.back()) return t.values.back();
  std::size_t i =
      static_cast<std::size_t>(std::upper_bound(t.frames.begin(), t.frames.end(), frame) - t.frames.begin()) - 1;
  const double f0 = t.frames[i];
  const double h = t.frames[i + 1] - f0;
  const double u = (frame - f0) / h;
  const T& p0 = t.values[i];
  const T& p1 = t.values[i + 1];
  if (mode == Interpolation::Linear) return p0 + (p1 - p0) * u;
  // Cubic Hermite basis with Catmull-Rom tangents (in value per frame, hence the factor h).
  const double u2 = u * u;
  const double u3 = u2 * u;
  const double h00 = 2.0 * u3 - 3.0 * u2 + 1.0;
  const double h10 = u3 - 2.0 * u2 + u;
  const double h01 = -2.0 * u3 + 3.0 * u2;
  const double h11 = u3 - u2;
  return h00 * p0 + (h10 * h) * tangent(t, i) + h01 * p1 + (h11 * h) * tangent(t, i + 1);
}

[[noreturn]] void failAt(const Animation& a, const std::string& path, int frame, const std::string& problem) {
  throw InputError(a.file, path + ": at frame " + std::to_string(frame) + " " + problem);
}

} // namespace

double interpolate(const Track<double>& track, double frame, Interpolation mode) {
  return evaluate(track, frame, mode);
}

dvec3 interpolate(const Track<dvec3>& track, double frame, Interpolation mode) {
  return evaluate(track, frame, mode);
}

Animation readAnimation(const JsonNode& node, const Scene& scene) {
  node.allowKeys({"frames", "fps", "interpolation", "animated_seed", "camera", "objects", "lights"});
  Animation a;
  a.file = scene.path.string();
  a.frames = static_cast<int>(node.at("frames").integer(1, kMaxFrames));
  if (auto v = node.find("fps")) a.fps = v->number(1e-3, 1e6);
  if (auto v = node.find("interpolation")) {
    a.interpolation = v->enumValue<Interpolation>();
  }
  if (auto v = node.find("animated_seed")) a.animatedSeed = v->boolean();
  if (auto v = node.find("camera")) readCameraKeys(*v, a);
  if (auto v = node.find("objects")) readObjectKeys(*v, scene, a);
  if (auto v = node.find("lights")) readLightKeys(*v, scene, a);
  return a;
}

int frameCount(const Scene& scene) {
  return scene.animation ? scene.animation->frames : 1;
}

Scene sceneAtFrame(const Scene& scene, const Animation& a, int frame) {
  if (frame < 0 || frame >= a.frames) {
    throw InputError(a.file, "frame " + std::to_string(frame) + " is outside the animation's frames 0-" +
                                 std::to_string(a.frames - 1));
  }
  const Interpolation mode = a.interpolation;
  const double f = frame;
  Scene out = scene;
  if (a.animatedSeed) out.render.seed = scene.render.seed + static_cast<std::uint32_t>(frame); // wraps past 2^32 - 1

  Camera& cam = out.camera;
  if (!a.camera.position.empty()) cam.position = interpolate(a.camera.position, f, mode);
  if (!a.camera.lookAt.empty()) cam.lookAt = interpolate(a.camera.lookAt, f, mode);
  if (!a.camera.up.empty()) cam.up = interpolate(a.camera.up, f, mode);
  if (!a.camera.fovY.empty()) cam.fovY = interpolate(a.camera.fovY, f, mode);
  if (!(cam.fovY > 0.0 && cam.fovY < 180.0)) {
    failAt(a, "animation.camera", frame, "fov_y is " + formatNumber(cam.fovY) + ", outside (0, 180) degrees");
  }
  if (glm::length(cam.up) == 0.0) failAt(a, "animation.camera", frame, "up is the zero vector");
  if (glm::length(cam.lookAt - cam.position) == 0.0) {
    failAt(a, "animation.camera", frame, "look_at coincides with position");
  }

  for (const ObjectTracks& t : a.objects) {
    const NamedObject& o = scene.namedObjects[t.object];
    const dvec3 move = t.translate.empty() ? dvec3(0.0) : interpolate(t.translate, f, mode);
    switch (o.kind) {
    case ObjectKind::Sphere:
      out.spheres[o.first].center += move;
      break;
    case ObjectKind::Plane:
      out.planes[o.first].offset -= glm::dot(out.planes[o.first].normal, move);
      break;
    case ObjectKind::Polygon:
      for (dvec3& v : out.polygons[o.first].vertices) v += move;
      break;
    case ObjectKind::Triangle:
      for (dvec3& v : out.triangles[o.first].v) v += move;
      break;
    case ObjectKind::Mesh: {
      if (t.rotate.empty() && t.scale.empty()) {
        for (std::size_t i = o.first; i < o.first + o.count; ++i) {
          for (dvec3& v : out.triangles[i].v) v += move;
        }
        break;
      }
      const dvec3 rotate = t.rotate.empty() ? dvec3(0.0) : interpolate(t.rotate, f, mode);
      const dvec3 scale = t.scale.empty() ? dvec3(1.0) : interpolate(t.scale, f, mode);
      for (int k = 0; k < 3; ++k) {
        if (!(scale[k] > 0.0)) failAt(a, t.path, frame, "scale interpolates to " + formatNumber(scale[k]) + " (<= 0)");
      }
      // About the centre: move the centre to the origin, rotate and scale, move it back and on.
      const glm::dmat4 m =
          composeTransform(t.centre + move, rotate, scale) * glm::translate(glm::dmat4(1.0), -t.centre);
      const glm::dmat3 normalMatrix = glm::transpose(glm::inverse(glm::dmat3(m)));
      for (std::size_t i = o.first; i < o.first + o.count; ++i) {
        Triangle& tri = out.triangles[i];
        for (dvec3& v : tri.v) v = dvec3(m * glm::dvec4(v, 1.0));
        if (tri.normals) {
          for (dvec3& n : *tri.normals) n = glm::normalize(normalMatrix * n);
        }
      }
      break;
    }
    }
  }

  for (const LightTracks& t : a.lights) out.lights[t.light].position = interpolate(t.position, f, mode);
  return out;
}

} // namespace vkray
