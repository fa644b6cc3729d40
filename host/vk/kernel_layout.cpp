// One small compute kernel's resource layout (see kernel_layout.h).
#include "vk/kernel_layout.h"

#include <vector>

#include "vk/context.h"

namespace vkray::vulkan {

KernelLayout::KernelLayout(const Context& context, std::initializer_list<KernelBinding> bindings,
                           std::uint32_t pushBytes)
    : context_(&context) {
  std::vector<vk::DescriptorSetLayoutBinding> layoutBindings;
  for (const KernelBinding& b : bindings) {
    layoutBindings.emplace_back(b.binding, b.type, 1, vk::ShaderStageFlagBits::eCompute);
    bool counted = false;
    for (vk::DescriptorPoolSize& size : perSet_) {
      if (size.type == b.type) {
        ++size.descriptorCount;
        counted = true;
      }
    }
    if (!counted) perSet_.emplace_back(b.type, 1);
  }
  const auto& device = context.device();
  setLayout_ = vk::raii::DescriptorSetLayout(device, vk::DescriptorSetLayoutCreateInfo({}, layoutBindings));
  vk::DescriptorSetLayout layouts[] = {*setLayout_};
  vk::PushConstantRange push(vk::ShaderStageFlagBits::eCompute, 0, pushBytes);
  pipelineLayout_ = vk::raii::PipelineLayout(device, pushBytes > 0 ? vk::PipelineLayoutCreateInfo({}, layouts, push)
                                                                   : vk::PipelineLayoutCreateInfo({}, layouts));
  pool_ = makePool(1);
}

vk::raii::DescriptorPool KernelLayout::makePool(std::uint32_t sets) const {
  std::vector<vk::DescriptorPoolSize> sizes = perSet_;
  for (vk::DescriptorPoolSize& size : sizes) size.descriptorCount *= sets;
  return vk::raii::DescriptorPool(
      context_->device(),
      vk::DescriptorPoolCreateInfo(vk::DescriptorPoolCreateFlagBits::eFreeDescriptorSet, sets, sizes));
}

vk::raii::DescriptorSets KernelLayout::allocate(std::uint32_t count) const {
  return allocate(pool_, count);
}

vk::raii::DescriptorSets KernelLayout::allocate(const vk::raii::DescriptorPool& pool, std::uint32_t count) const {
  std::vector<vk::DescriptorSetLayout> layouts(count, *setLayout_);
  return vk::raii::DescriptorSets(context_->device(), vk::DescriptorSetAllocateInfo(*pool, layouts));
}

} // namespace vkray::vulkan
