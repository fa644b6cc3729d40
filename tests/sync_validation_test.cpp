// The synchronization validation the GPU suite runs under (ctest's gpu-sync group,
// VKRAY_SYNC_VALIDATION=1) is live: a deliberately broken barrier in a test-only command sequence
// (fill a buffer, then copy from it) is reported as a hazard, and the correct barrier is not. Without
// this, a layer that silently failed to enable its synchronization checks would pass every test.
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "test_support.h"
#include "vk/buffer.h"
#include "vk/context.h"

namespace vkray::test {
namespace {

enum class Barrier {
  Correct, // transfer write -> transfer read
  Missing, // none at all
  Wrong,   // covers compute-shader reads, not the copy that follows
};

// Fills `src` with a transfer command, then copies it to `dst`, with the given barrier between.
void fillThenCopy(const vulkan::Context& context, Barrier barrier) {
  const vk::DeviceSize size = 4096;
  vulkan::Buffer src(context, size, vk::BufferUsageFlagBits::eTransferSrc | vk::BufferUsageFlagBits::eTransferDst,
                     vulkan::MemoryUse::DeviceLocal, "sync-test source");
  vulkan::Buffer dst(context, size, vk::BufferUsageFlagBits::eTransferDst, vulkan::MemoryUse::DeviceLocal,
                     "sync-test destination");
  context.submitAndWait("the sync-validation test's commands", [&](const vk::raii::CommandBuffer& cmd) {
    cmd.fillBuffer(src.handle(), 0, size, 0x3f800000u);
    if (barrier == Barrier::Correct) {
      vk::MemoryBarrier b(vk::AccessFlagBits::eTransferWrite, vk::AccessFlagBits::eTransferRead);
      cmd.pipelineBarrier(vk::PipelineStageFlagBits::eTransfer, vk::PipelineStageFlagBits::eTransfer, {}, b, {}, {});
    } else if (barrier == Barrier::Wrong) {
      // The destination scope is the compute shader's reads: the copy is outside it.
      vk::MemoryBarrier b(vk::AccessFlagBits::eTransferWrite, vk::AccessFlagBits::eShaderRead);
      cmd.pipelineBarrier(vk::PipelineStageFlagBits::eTransfer, vk::PipelineStageFlagBits::eComputeShader, {}, b, {},
                          {});
    }
    cmd.copyBuffer(src.handle(), dst.handle(), vk::BufferCopy(0, 0, size));
  });
}

bool anyHazard(const std::vector<std::string>& messages) {
  for (const auto& m : messages) {
    if (m.find("SYNC-HAZARD-READ-AFTER-WRITE") != std::string::npos) return true;
  }
  return false;
}

std::string joined(const std::vector<std::string>& messages) {
  std::string out;
  for (const auto& m : messages) out += m + "\n";
  return out;
}

// A context of the test's own with synchronization validation on, whatever the suite runs with.
TEST(GpuSyncValidation, BrokenBarriersAreReportedAndTheCorrectOneIsNot) {
  // Echo off: the messages are expected; the test prints them if they are wrong.
  vulkan::Context context(testContextOptions(true, false));

  fillThenCopy(context, Barrier::Correct);
  EXPECT_EQ(context.validationMessageCount(), 0u) << joined(context.validationMessages());

  for (Barrier broken : {Barrier::Missing, Barrier::Wrong}) {
    SCOPED_TRACE(broken == Barrier::Missing ? "no barrier" : "a barrier for the wrong stage");
    context.validationLog().clear();
    fillThenCopy(context, broken);
    auto messages = context.validationMessages();
    EXPECT_TRUE(anyHazard(messages)) << "not reported as a read-after-write hazard:\n" << joined(messages);
  }
  context.validationLog().clear();
}

// The control: with plain validation the same missing barrier goes unreported, so the hazards above
// come from the synchronization checks, and only a run with them on can catch one.
TEST(GpuSyncValidation, PlainValidationDoesNotSeeTheMissingBarrier) {
  vulkan::Context context(testContextOptions(false, false));
  fillThenCopy(context, Barrier::Missing);
  EXPECT_EQ(context.validationMessageCount(), 0u) << joined(context.validationMessages());
}

// In the gpu-sync group, the suite's own shared context has the checks on: the same broken barrier
// on it is reported (the layer echoes the expected message to stderr).
TEST(GpuSyncValidation, TheSuitesContextHasTheChecksOn) {
  if (!syncValidationRequested()) GTEST_SKIP() << "runs in the gpu-sync group (VKRAY_SYNC_VALIDATION=1)";
  expectNoValidationMessages();
  fillThenCopy(gpu(), Barrier::Missing);
  auto messages = takeValidationMessages();
  EXPECT_TRUE(anyHazard(messages)) << "the suite's context did not report a missing barrier:\n" << joined(messages);
  fillThenCopy(gpu(), Barrier::Correct);
  expectNoValidationMessages();
}

} // namespace
} // namespace vkray::test
