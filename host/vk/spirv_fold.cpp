// Specialization folded into the SPIR-V (see spirv_fold.h).
#include "vk/spirv_fold.h"

#include <unordered_map>

#include <spirv-tools/libspirv.hpp>
#include <spirv-tools/optimizer.hpp>

#include "vk/compute_pipeline.h"

namespace vkray::vulkan {

FoldedSpirv foldSpecialization(std::span<const std::uint32_t> code, const Specialization& specialization) {
  FoldedSpirv result;
  std::unordered_map<std::uint32_t, std::vector<std::uint32_t>> values;
  for (const auto& [id, value] : specialization.values()) values[id] = {value};
  spvtools::Optimizer optimizer(SPV_ENV_VULKAN_1_1);
  optimizer.SetMessageConsumer([&](spv_message_level_t level, const char*, const spv_position_t&, const char* text) {
    if (level <= SPV_MSG_ERROR && result.error.empty()) result.error = text;
  });
  optimizer.RegisterPass(spvtools::CreateSetSpecConstantDefaultValuePass(values))
      .RegisterPass(spvtools::CreateFreezeSpecConstantValuePass())
      .RegisterPass(spvtools::CreateFoldSpecConstantOpAndCompositePass())
      .RegisterPass(spvtools::CreateDeadBranchElimPass())
      .RegisterPass(spvtools::CreateEliminateDeadFunctionsPass());
  // Then what is left, in the driver's place: inlined, in SSA form, constants propagated and the
  // instructions simplified. lavapipe's shader passes then take a quarter of the time on the trace
  // kernel (seed: 380 -> 80-95 ms), and the module is kept (vk/fold_cache.h), so these 0.3 s are
  // paid once per specialization. None of them reassociates or contracts floating-point arithmetic:
  // the images stay the same bit for bit (tools/compare-renders).
  optimizer.RegisterPass(spvtools::CreateInlineExhaustivePass())
      .RegisterPass(spvtools::CreateEliminateDeadFunctionsPass())
      .RegisterPass(spvtools::CreateSSARewritePass())
      .RegisterPass(spvtools::CreateAggressiveDCEPass())
      .RegisterPass(spvtools::CreateCCPPass())
      .RegisterPass(spvtools::CreateDeadBranchElimPass())
      .RegisterPass(spvtools::CreateBlockMergePass())
      .RegisterPass(spvtools::CreateSimplificationPass())
      .RegisterPass(spvtools::CreateAggressiveDCEPass());
  // The module was validated when it was built (glslang) and the validation layer checks what the
  // driver gets; validating here again would cost more than the folding.
  spvtools::OptimizerOptions options;
  options.set_run_validator(false);
  if (!optimizer.Run(code.data(), code.size(), &result.code, options)) {
    result.code.clear();
    if (result.error.empty()) result.error = "SPIRV-Tools could not fold the specialization";
  }
  return result;
}

} // namespace vkray::vulkan
