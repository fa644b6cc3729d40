// Reads a scene file (JSON with comments) into a Scene, validating every field. See
// docs/scene-format.md for the format; errors name the file, the JSON path and the problem.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>

#include "scene/model_scene.h"
#include "scene/scene.h"

namespace vkray {

// Scene files larger than this are refused before parsing (a scene is a description; geometry
// belongs in mesh files).
inline constexpr std::uintmax_t kMaxSceneFileBytes = 64ull << 20;

// A scene file, or a model file (.obj, .gltf, .glb: loadModelScene with `model`).
Scene loadScene(const std::filesystem::path& path, const ModelSceneOptions& model = {});

// `name` stands for the file in messages; relative mesh paths resolve against `baseDir`.
Scene loadSceneFromString(const std::string& text, const std::string& name, const std::filesystem::path& baseDir = ".");

} // namespace vkray
