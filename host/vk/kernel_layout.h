// One small compute kernel's resource layout, built in one place: its descriptor-set layout (one
// descriptor per binding, all for the compute stage), its pipeline layout (that set and an optional
// push-constant range at offset 0) and a pool with room for one such set. The renderer's
// own layout (render/descriptors.h) is richer; this serves the probe, the loop-limit probe and the
// viewer's resolve and convergence passes.
#pragma once

#include <cstdint>
#include <initializer_list>
#include <vector>

#include <vulkan/vulkan_raii.hpp>

namespace vkray::vulkan {

class Context;

struct KernelBinding {
  std::uint32_t binding;
  vk::DescriptorType type;
};

class KernelLayout {
public:
  KernelLayout() = default;
  // pushBytes 0: no push constants.
  KernelLayout(const Context& context, std::initializer_list<KernelBinding> bindings, std::uint32_t pushBytes);

  vk::PipelineLayout pipelineLayout() const { return *pipelineLayout_; }
  // `count` sets of this layout from its own pool (freeable one by one).
  vk::raii::DescriptorSets allocate(std::uint32_t count = 1) const;
  // `count` sets from another pool made by makePool.
  vk::raii::DescriptorSets allocate(const vk::raii::DescriptorPool& pool, std::uint32_t count) const;
  // A further pool with room for `sets` sets of this layout.
  vk::raii::DescriptorPool makePool(std::uint32_t sets) const;

private:
  const Context* context_ = nullptr;
  std::vector<vk::DescriptorPoolSize> perSet_; // the descriptors one set needs, by type
  vk::raii::DescriptorSetLayout setLayout_{nullptr};
  vk::raii::PipelineLayout pipelineLayout_{nullptr};
  vk::raii::DescriptorPool pool_{nullptr};
};

} // namespace vkray::vulkan
