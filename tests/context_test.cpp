// Device choice (host/vk/context.cpp): what the kernels need of a device is named when it is missing.
#include <gtest/gtest.h>

#include "test_support.h"
#include "vk/context.h"

namespace vkray {
namespace {

vk::PhysicalDeviceSubgroupProperties subgroups(vk::ShaderStageFlags stages, vk::SubgroupFeatureFlags ops) {
  vk::PhysicalDeviceSubgroupProperties p;
  p.subgroupSize = 32;
  p.supportedStages = stages;
  p.supportedOperations = ops;
  return p;
}

TEST(DeviceChoice, MissingSubgroupOperationsAreNamed) {
  using Op = vk::SubgroupFeatureFlagBits;
  using Stage = vk::ShaderStageFlagBits;
  const vk::SubgroupFeatureFlags all = Op::eBasic | Op::eArithmetic | Op::eBallot | Op::eShuffle;
  EXPECT_EQ(vulkan::missingSubgroupSupport(subgroups(Stage::eCompute, all)), "");
  EXPECT_EQ(vulkan::missingSubgroupSupport(subgroups(Stage::eCompute | Stage::eFragment, all | Op::eVote)), "");
  EXPECT_EQ(vulkan::missingSubgroupSupport(subgroups(Stage::eCompute, Op::eBasic | Op::eArithmetic | Op::eShuffle)),
            "ballot");
  EXPECT_EQ(vulkan::missingSubgroupSupport(subgroups(Stage::eCompute, Op::eBasic | Op::eVote)),
            "arithmetic, ballot, shuffle");
  EXPECT_EQ(vulkan::missingSubgroupSupport(subgroups(Stage::eCompute, {})), "basic, arithmetic, ballot, shuffle");
  EXPECT_EQ(vulkan::missingSubgroupSupport(subgroups(Stage::eFragment, all)), "subgroups in compute shaders");
}

TEST(GpuDeviceChoice, TheTestDeviceHasWhatTheKernelsUse) {
  const vulkan::DeviceInfo& info = test::gpu().info();
  EXPECT_EQ(info.subgroupMissing, "");
  EXPECT_GE(info.subgroupSize, 1u);
}

} // namespace
} // namespace vkray
