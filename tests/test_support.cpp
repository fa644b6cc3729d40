// Shared GPU context, renderer and helpers for the tests (see test_support.h).
#include "test_support.h"

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <sstream>

#include "scene/scene_loader.h"

namespace vkray::test {

namespace {

std::size_t gSeenMessages = 0;

} // namespace

vulkan::ContextOptions testContextOptions(bool synchronizationValidation, bool echoValidation) {
  vulkan::ContextOptions options;
  const char* device = std::getenv("VKRAY_TEST_DEVICE");
  options.device = device && *device ? device : "llvmpipe";
  options.validation = true;
  options.synchronizationValidation = synchronizationValidation;
  options.echoValidation = echoValidation;
  return options;
}

vulkan::Context& gpu() {
  static std::unique_ptr<vulkan::Context> context = [] {
    return std::make_unique<vulkan::Context>(testContextOptions(syncValidationRequested(), true));
  }();
  return *context;
}

Renderer& renderer() {
  static std::unique_ptr<Renderer> r = std::make_unique<Renderer>(gpu(), nullptr);
  return *r;
}

Scene sceneFromJson(const std::string& json, const std::string& name) {
  return loadSceneFromString(json, name, VKRAY_SOURCE_DIR "/scenes");
}

bool variantsExact() {
  return gpu().info().type == "CPU";
}

bool sameColour(const glm::vec3& a, const glm::vec3& b) {
  if (variantsExact()) return a == b;
  const glm::vec3 d = glm::abs(a - b);
  return std::max(d.x, std::max(d.y, d.z)) <= kVariantTolerance;
}

void expectSameImageAcrossVariants(const Image& a, const Image& b) {
  ASSERT_EQ(a.width, b.width);
  ASSERT_EQ(a.height, b.height);
  if (variantsExact()) {
    EXPECT_EQ(a.pixels, b.pixels);
    return;
  }
  int unexplained = 0;
  for (std::uint32_t y = 0; y < a.height; ++y) {
    for (std::uint32_t x = 0; x < a.width; ++x) {
      bool explained = false;
      for (int dy = -1; dy <= 1 && !explained; ++dy) {
        for (int dx = -1; dx <= 1 && !explained; ++dx) {
          const int nx = static_cast<int>(x) + dx, ny = static_cast<int>(y) + dy;
          if (nx < 0 || ny < 0 || nx >= static_cast<int>(a.width) || ny >= static_cast<int>(a.height)) continue;
          explained = sameColour(a.at(static_cast<std::uint32_t>(nx), static_cast<std::uint32_t>(ny)), b.at(x, y));
        }
      }
      if (!explained) {
        ++unexplained;
        ADD_FAILURE() << "pixel " << x << "," << y << ": no neighbour of the other variant's image is within "
                      << kVariantTolerance;
        if (unexplained > 10) return;
      }
    }
  }
}

RenderResult render(const Scene& scene, RenderOptions options) {
  Renderer& r = renderer();
  r.setScene(scene);
  RenderResult result = r.render(scene.camera, scene.render, options);
  expectNoValidationMessages();
  EXPECT_EQ(result.stats.nonFinite, 0u) << "a sample was NaN/Inf";
  return result;
}

void expectNoValidationMessages() {
  auto messages = gpu().validationMessages();
  for (std::size_t i = gSeenMessages; i < messages.size(); ++i) {
    ADD_FAILURE() << "validation layer: " << messages[i];
  }
  gSeenMessages = messages.size();
}

std::vector<std::string> takeValidationMessages() {
  auto messages = gpu().validationMessages();
  std::vector<std::string> fresh(
      messages.begin() + static_cast<std::ptrdiff_t>(std::min(gSeenMessages, messages.size())), messages.end());
  gSeenMessages = messages.size();
  return fresh;
}

bool syncValidationRequested() {
  const char* sync = std::getenv("VKRAY_SYNC_VALIDATION");
  return sync && std::string(sync) == "1";
}

std::string scenePath(const std::string& name) {
  return std::string(VKRAY_SOURCE_DIR "/scenes/") + name;
}

std::filesystem::path scratchDir(const std::string& name) {
  auto dir = std::filesystem::temp_directory_path() / ("vkray-" + name + "-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  return dir;
}

std::filesystem::path freshScratchDir(const std::string& name) {
  auto dir = std::filesystem::temp_directory_path() / ("vkray-" + name + "-" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

std::string slurp(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

CliRun runVkray(const std::string& args, const std::filesystem::path& dir) {
  const std::filesystem::path out = dir / "vkray-stdout", err = dir / "vkray-stderr";
  std::string cmd = std::string("VKRAY_DEVICE=llvmpipe '") + VKRAY_BINARY + "' " + args + " >'" + out.string() +
                    "' 2>'" + err.string() + "'";
  int status = std::system(cmd.c_str());
  CliRun r;
  r.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  r.out = slurp(out);
  r.err = slurp(err);
  return r;
}

} // namespace vkray::test
