// Specialization folded into the SPIR-V before the driver sees it. A kernel's specialization
// constants switch whole features off (shaders/lib/specialization.glsl), but a driver that compiles
// on the CPU handles every branch and function of the module before it drops the dead ones:
// lavapipe spends 1.5 s in its shader passes on the full trace kernel, against 0.2 s on the same
// kernel with the switched-off code already gone (docs/specialization.md, "What specializing costs
// to compile"). Folding sets each constant, turns the constants into plain ones, folds the
// expressions over them and removes the branches and functions they leave dead: SPIRV-Tools'
// own passes, in tens of milliseconds; the code that stays is the code the driver would have kept.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace vkray::vulkan {

class Specialization;

// Which passes foldSpecialization runs: part of the key of a folded module kept on disk
// (vk/fold_cache.h). Raise it whenever the passes or their options change.
inline constexpr std::uint32_t kFoldPassesVersion = 1;

struct FoldedSpirv {
  std::vector<std::uint32_t> code; // empty when folding failed (then use the original)
  std::string error;               // why it failed
};

FoldedSpirv foldSpecialization(std::span<const std::uint32_t> code, const Specialization& specialization);

} // namespace vkray::vulkan
