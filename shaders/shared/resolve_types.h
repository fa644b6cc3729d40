// The viewer's resolve pass (shaders/resolve.comp): its bindings and specialization constants, shared
// by C++ (host/viewer/presenter.cpp) and GLSL like gpu_types.h, whose workgroup size it reuses.
#ifndef VKRAY_RESOLVE_TYPES_H
#define VKRAY_RESOLVE_TYPES_H

#include "gpu_types.h"

#ifdef __cplusplus
namespace vkray::gpu {
#endif

VKRAY_CONST(uint, kResolveBindingSums, 0u);    // sampler2D: copy of the Renderer's (sum rgb, samples)
VKRAY_CONST(uint, kResolveBindingDisplay, 1u); // storage image the swapchain is blitted from
VKRAY_CONST(uint, kResolveSpecEncodeSrgb, 0u); // 1: write sRGB-encoded values (UNORM target)

#ifdef __cplusplus
} // namespace vkray::gpu
#endif

#endif
