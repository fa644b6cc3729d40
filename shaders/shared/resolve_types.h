// The viewer's resolve pass (shaders/resolve.comp): its bindings and specialization constants, shared
// by C++ (host/viewer/presenter.cpp) and GLSL like gpu_types.h, whose workgroup size it reuses.
#ifndef VKRAY_RESOLVE_TYPES_H
#define VKRAY_RESOLVE_TYPES_H

#include "gpu_types.h"

#ifdef __cplusplus
namespace vkray::gpu {
#endif

VKRAY_CONST(uint, kResolveBindingSums, 0u);    // storage texel buffer: the Renderer's (sum rgb, samples)
VKRAY_CONST(uint, kResolveBindingDisplay, 1u); // storage image: the swapchain image, or one blitted to it
VKRAY_CONST(uint, kResolveBindingOverlay, 2u); // sampled image: the overlay's layer (direct variant only)
VKRAY_CONST(uint, kResolveSpecEncodeSrgb, 0u); // 1: write sRGB-encoded values (UNORM target)
// Rows of 64: the pass does little per pixel, and on lavapipe each workgroup has a fixed cost
// (8 x 8 groups made the pass 20 % slower at 640 x 480).
VKRAY_CONST(uint, kResolveGroupX, 64u);
VKRAY_CONST(uint, kResolveGroupY, 4u);

#ifdef __cplusplus
} // namespace vkray::gpu
#endif

#endif
