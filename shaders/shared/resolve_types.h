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
// Workgroups are one image row wide (up to the device's limits): the pass does little per pixel,
// and on lavapipe each workgroup has a fixed cost. At 640 x 480, 8 x 8 groups were 20 % slower
// than 64 x 4, and those 13 % slower than whole rows (2.5-2.6 against 2.9-3.1 ms, interleaved).
VKRAY_CONST(uint, kResolveSpecGroupX, 1u); // the workgroup's width (local_size_x_id)
VKRAY_CONST(uint, kResolveGroupX, 64u);    // its default (the shader's declared size)

#ifdef __cplusplus
} // namespace vkray::gpu
#endif

#endif
