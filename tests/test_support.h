// Shared test support: one Vulkan context on lavapipe with the validation layer on (any message
// fails the test that caused it), a shared renderer, and small helpers to build scenes from JSON.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "render/renderer.h"
#include "scene/scene.h"
#include "vk/context.h"

namespace vkray::test {

// The process-wide context: device "llvmpipe" (override with VKRAY_TEST_DEVICE), validation on,
// synchronization validation on when VKRAY_SYNC_VALIDATION=1.
vulkan::Context& gpu();
// Options for a context like gpu()'s: the test device with validation on; synchronization validation
// and echoing messages to stderr as asked (a test that provokes messages on purpose turns echo off).
vulkan::ContextOptions testContextOptions(bool synchronizationValidation, bool echoValidation);

// A renderer on gpu(); pipelines are cached across tests that share a specialization.
Renderer& renderer();

// Parses a scene from JSON text (comments allowed); name appears in error messages.
Scene sceneFromJson(const std::string& json, const std::string& name = "test.json");

// Renders a scene with its own settings (tests adjust scene.render first), counting rays.
RenderResult render(const Scene& scene, RenderOptions options = {});

// Fails the current test if the validation layer reported anything since the last check.
void expectNoValidationMessages();

// The validation layer's messages since the last check, which then count as seen (for a test that
// provokes messages on purpose).
std::vector<std::string> takeValidationMessages();

// True when the suite runs with synchronization validation (VKRAY_SYNC_VALIDATION=1).
bool syncValidationRequested();

// Where the bundled scenes live (the source tree's scenes/).
std::string scenePath(const std::string& name);

// A directory of this test process for scratch files, $TMPDIR/vkray-NAME-PID, created if missing;
// freshScratchDir empties it first.
std::filesystem::path scratchDir(const std::string& name);
std::filesystem::path freshScratchDir(const std::string& name);

// A file's whole contents ("" when it cannot be read).
std::string slurp(const std::filesystem::path& path);

// build/vkray run with `args` (a shell-quoted string) on lavapipe; its standard output and error
// pass through files in `dir`.
struct CliRun {
  int exitCode = -1;
  std::string out, err;
};
CliRun runVkray(const std::string& args, const std::filesystem::path& dir);

} // namespace vkray::test
