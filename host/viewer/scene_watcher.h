// Scene hot reload: watches the scene file (and the mesh files it names) and reloads it when one
// changes on disk. A file that fails to load leaves the last good scene in place and an error to show.
#pragma once

#include <chrono>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "scene/model_scene.h"
#include "scene/scene.h"

namespace vkray {

class SceneWatcher {
public:
  // Loads the scene now; a broken file here is an error for the caller (there is no last good scene).
  explicit SceneWatcher(std::filesystem::path path, ModelSceneOptions model = {});

  const Scene& scene() const { return scene_; }
  // The last reload's error, empty after a successful load.
  const std::string& error() const { return error_; }

  // Checks the watched files' modification times, at most once per `interval`. Returns true when a
  // changed file was reloaded successfully (scene() is the new scene); on a load error, error() says
  // why and scene() is unchanged.
  bool poll(std::chrono::milliseconds interval = std::chrono::milliseconds(250));

private:
  using Stamp = std::optional<std::filesystem::file_time_type>;
  void watchFilesOf(const Scene& scene);
  std::vector<Stamp> currentStamps() const;

  std::filesystem::path path_;
  ModelSceneOptions model_;
  Scene scene_;
  std::string error_;
  std::vector<std::filesystem::path> files_; // the scene file first, then its meshes
  std::vector<Stamp> stamps_;
  std::chrono::steady_clock::time_point lastCheck_{};
};

} // namespace vkray
