// Command-line flags shared by render, view and bench: device choice and the overrides of the
// scene's render settings. Flags always win over the scene file.
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include <CLI/CLI.hpp>

#include "render/render_options.h"
#include "scene/model_scene.h"
#include "scene/scene.h"
#include "vk/device_flags.h"

namespace vkray {

struct RenderFlags {
  std::optional<std::uint32_t> width, height;
  std::optional<int> maxDepth, spp, minSpp, maxSpp;
  std::optional<long long> photons, seed;
  std::optional<std::string> method;
  std::optional<double> bailout, adaptiveThreshold, noiseThreshold, timeLimit;
  std::optional<std::string> antialiasing, numerics, fresnel, transmissiveShadows, bvh, precision, textureFilter;
};

// How a model file (.obj, .gltf, .glb) given in place of a scene is staged.
struct ModelFlags {
  bool floor = false;                    // --floor
  std::optional<std::string> background; // --background r,g,b (linear)
};

// A check that a real number lies in [lo, hi], whose message prints the bounds as written
// ("not in range 1 to 10000"; CLI::Range prints doubles with six decimals) and refuses NaN.
CLI::Validator realRange(double lo, double hi);
CLI::Validator positiveReal(double hi); // (0, hi], NaN refused
// A whole number in [lo, hi]; "many" and "1.5" are "not a whole number", not out of range.
CLI::Validator wholeRange(long long lo, long long hi);

// The renderer's own switches, for comparison runs: each maps onto a RenderOptions field.
struct KernelFlags {
  bool noSpecialize = false;              // --no-specialize
  bool noSpirvFolding = false;            // --no-spirv-folding
  bool noUnroll = false;                  // --no-unroll
  bool noRowCulling = false;              // --no-row-culling
  bool noEntryPoints = false;             // --no-entry-points
  bool noShadowEntryPoints = false;       // --no-shadow-entry-points
  std::string shadowEntryPoints = "auto"; // --shadow-entry-points, a ShadowEntries name
  bool oneSamplePerDispatch = false;      // --one-sample-per-dispatch
  std::string sceneMemory = "auto";       // --scene-memory, a SceneMemory name
};

void addDeviceFlags(CLI::App& app, DeviceFlags& flags);
void addKernelFlags(CLI::App& app, KernelFlags& flags);
void applyKernelFlags(const KernelFlags& flags, RenderOptions& options);
void addRenderFlags(CLI::App& app, RenderFlags& flags);
void applyRenderFlags(const RenderFlags& flags, RenderSettings& settings);
void addModelFlags(CLI::App& app, ModelFlags& flags);
// The flags as options for loadScene; either flag on a scene file (not a model) is an InputError.
ModelSceneOptions modelSceneOptions(const ModelFlags& flags, const std::filesystem::path& scene);

} // namespace vkray
