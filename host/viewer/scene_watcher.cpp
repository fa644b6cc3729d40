// Scene hot reload by polling modification times (see scene_watcher.h). Polling rather than inotify:
// editors that save by renaming a new file over the old one keep working, and it is portable.
#include "viewer/scene_watcher.h"

#include <system_error>

#include "scene/scene_loader.h"
#include "util/error.h"

namespace vkray {

SceneWatcher::SceneWatcher(std::filesystem::path path, ModelSceneOptions model)
    : path_(std::move(path)), model_(std::move(model)), scene_(loadScene(path_, model_)) {
  watchFilesOf(scene_);
  stamps_ = currentStamps();
  lastCheck_ = std::chrono::steady_clock::now();
}

void SceneWatcher::watchFilesOf(const Scene& scene) {
  files_.assign(1, path_);
  if (isModelFile(path_)) return; // the model is the scene file itself
  for (const auto& mesh : scene.meshes) {
    std::filesystem::path file(mesh.file);
    if (file.is_relative()) file = path_.parent_path() / file;
    files_.push_back(file);
  }
}

std::vector<SceneWatcher::Stamp> SceneWatcher::currentStamps() const {
  std::vector<Stamp> stamps;
  for (const auto& f : files_) {
    std::error_code ec;
    auto t = std::filesystem::last_write_time(f, ec);
    stamps.push_back(ec ? Stamp() : Stamp(t));
  }
  return stamps;
}

bool SceneWatcher::poll(std::chrono::milliseconds interval) {
  auto now = std::chrono::steady_clock::now();
  if (now - lastCheck_ < interval) return false;
  lastCheck_ = now;
  auto stamps = currentStamps();
  if (stamps == stamps_) return false;
  stamps_ = stamps;
  try {
    Scene next = loadScene(path_, model_);
    scene_ = std::move(next);
    error_.clear();
    // The reloaded scene may name other meshes: watch those from now on.
    watchFilesOf(scene_);
    stamps_ = currentStamps();
    return true;
  } catch (const Error& e) {
    error_ = e.what();
    return false;
  }
}

} // namespace vkray
