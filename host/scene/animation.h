// Animation: a scene file's "animation" section as plain keys, and the pure function that turns the
// keys into the static scene of one frame, so that everything downstream of the loader stays static.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "scene/scene.h"

namespace vkray {

class JsonNode;

enum class Interpolation {
  Linear,
  // Catmull-Rom through the keys, parameterised by frame number (the non-uniform form: the tangent at
  // key i is (p[i+1] - p[i-1]) / (f[i+1] - f[i-1]), one-sided at the first and last key), as cubic
  // Hermite segments. Timing follows the frames the keys are at, not the distance between values.
  Smooth,
};
template <> struct EnumNames<Interpolation> {
  static constexpr std::array<EnumName<Interpolation>, 2> values{
      {{Interpolation::Linear, "linear"}, {Interpolation::Smooth, "smooth"}}};
};

// One animated quantity: the keys that give it, frames strictly increasing.
template <typename T> struct Track {
  std::vector<int> frames;
  std::vector<T> values;
  bool empty() const { return frames.empty(); }
};

struct CameraTracks {
  Track<glm::dvec3> position, lookAt, up;
  Track<double> fovY;
};

struct ObjectTracks {
  std::string name;
  std::string path;            // "animation.objects.ball", for messages
  std::size_t object = 0;      // index into Scene::namedObjects
  Track<glm::dvec3> translate; // added to the placement
  Track<glm::dvec3> rotate;    // meshes: degrees about x, y, z (applied z, y, x), about the centre
  Track<glm::dvec3> scale;     // meshes: about the centre
  glm::dvec3 centre{0.0};      // meshes: centre of the bounding box of the static scene's triangles
};

struct LightTracks {
  std::string name;
  std::string path;
  std::size_t light = 0; // index into Scene::lights
  Track<glm::dvec3> position;
};

struct Animation {
  int frames = 1;
  double fps = 24.0;
  Interpolation interpolation = Interpolation::Linear;
  // Frame N samples with render.seed + N (each frame its own noise pattern) instead of every frame
  // with render.seed (one pattern that stays put on the screen).
  bool animatedSeed = false;
  CameraTracks camera;
  std::vector<ObjectTracks> objects;
  std::vector<LightTracks> lights;
  std::string file; // the scene file, for messages
};

// Reads "animation" against the loaded static scene (names resolve to its objects and lights).
Animation readAnimation(const JsonNode& node, const Scene& scene);

// The value of a track at `frame`: the keys' values held before the first key and after the last.
double interpolate(const Track<double>& track, double frame, Interpolation mode);
glm::dvec3 interpolate(const Track<glm::dvec3>& track, double frame, Interpolation mode);

// The static scene of frame `frame` (0 <= frame < animation.frames): the interpolated values
// written into a copy of `scene`. Throws InputError when an interpolated value is invalid there (a
// smooth curve that swings fov_y out of (0, 180) or a scale through 0).
Scene sceneAtFrame(const Scene& scene, const Animation& animation, int frame);

// How many frames a scene has: its animation's, or 1 for a static scene.
int frameCount(const Scene& scene);

} // namespace vkray
