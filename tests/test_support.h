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

// Whether two kernel variants (specialized or not, shadows compiled in or out, the query kernel and
// the renderer) must give the same pixels bit for bit on the test device. Vulkan lets a compiler
// contract a * b + c into one fused operation outside `precise` code, and a compiler may contract
// the same expression differently in two variants of a kernel: llvmpipe's JIT compiles it alike in
// every variant, NVIDIA's compiler did not (tools/device-check on an H200, driver 580.159: 2 of 15
// bundled scenes differed in their last bits between the specialized and the general kernel). The
// CPU driver is the reference and is held to exact equality; other devices to kVariantTolerance.
bool variantsExact();
// How far two variants' values may be apart where variantsExact() is false: 1e-4 of a unit, a
// fortieth of an 8-bit level, far below anything a test tells apart (a shadow, a missed object).
constexpr float kVariantTolerance = 1e-4f;
// The same colour, as variantsExact() asks: bit for bit, or within kVariantTolerance per channel.
bool sameColour(const glm::vec3& a, const glm::vec3& b);
// Two variants' images of one scene agree: bit for bit where variantsExact(); elsewhere every pixel
// within kVariantTolerance of some pixel of the other image's 3 x 3 neighbourhood (a last bit may
// move an edge, a glass path or a checker line by a pixel, never add what no neighbour has).
void expectSameImageAcrossVariants(const Image& a, const Image& b);

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
