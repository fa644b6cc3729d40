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

// What the resolve pass shows (host/viewer/view_settings.h, DisplayMode): the image, or a map of a
// per-pixel quantity (kResolveBindingMap) as a heat colour on a log scale from MAP_LOW to MAP_HIGH.
VKRAY_CONST(uint, kResolveBindingMap, 3u);  // uint[]: the error estimates (float bits) or rays per pixel
VKRAY_CONST(uint, kResolveSpecDisplay, 2u); // kDisplay*
VKRAY_CONST(uint, kResolveSpecMapLow, 3u);  // float: the value shown at the scale's bottom (blue)
VKRAY_CONST(uint, kResolveSpecMapHigh, 4u); // float: the value shown at its top (red)
VKRAY_CONST(uint, kDisplayImage, 0u);
VKRAY_CONST(uint, kDisplayError, 1u); // the block estimate of the standard error (shaders/convergence.comp)
VKRAY_CONST(uint, kDisplayCost, 2u);  // rays traced per sample (Renderer's rays per pixel / samples)

// ---- The convergence pass (shaders/convergence.comp, host/viewer/convergence.h) -----------------
// Step 0 estimates each pixel's standard error from the sums and their copies taken the last two
// times the sample count doubled (three blocks of the pixel's samples); step 1 bins the estimates
// and counts the pixels converged at the threshold (kConvergenceOwnShare, below). Workgroups are
// image rows, as the resolve pass's.
VKRAY_CONST(uint, kConvergenceBindingSums, 0u);      // storage texel buffer (RGBA32F): the sums now
VKRAY_CONST(uint, kConvergenceBindingHalf, 1u);      // storage texel buffer (RGBA32F): their earlier copy
VKRAY_CONST(uint, kConvergenceBindingErrors, 2u);    // storage texel buffer (R32F): the estimates
VKRAY_CONST(uint, kConvergenceBindingHistogram, 3u); // uint[kHistogramWords]: the reduction (below)
VKRAY_CONST(uint, kConvergenceBindingEarliest, 4u);  // storage texel buffer (RGBA32F): the copy before that
VKRAY_CONST(uint, kConvergenceSpecStep, 0u);         // 0: estimate; 1: reduce
VKRAY_CONST(uint, kConvergenceSpecGroupX, 1u);       // the workgroup's width
VKRAY_CONST(uint, kConvergenceSpecThreshold, 2u);    // float: the noise threshold
// The histogram buffer's words: a zero the shader reads at run time (its push constant made opaque
// to lavapipe's uniform inlining, docs/performance.md), the pixels counted, those converged, those
// without an estimate yet (fewer than 2 samples, or none since the copy), then kHistogramBins bins
// of log2(error), kHistogramBinsPerOctave to an octave from 2^kHistogramLowLog2 up (the first bin
// also holds everything below, exact zeros included; the last everything above).
VKRAY_CONST(uint, kHistogramZero, 0u);
VKRAY_CONST(uint, kHistogramPixels, 1u);
VKRAY_CONST(uint, kHistogramConverged, 2u);
VKRAY_CONST(uint, kHistogramUnestimated, 3u);
VKRAY_CONST(uint, kHistogramFirstBin, 4u);
VKRAY_CONST(uint, kHistogramBins, 128u);
VKRAY_CONST(uint, kHistogramBinsPerOctave, 4u);
VKRAY_CONST(int, kHistogramLowLog2, -24);
VKRAY_CONST(uint, kHistogramWords, 132u); // kHistogramFirstBin + kHistogramBins
// A pixel has converged when kConvergenceOwnShare of its own squared estimate plus the rest of the
// mean square over its 3 x 3 neighbourhood is at most the threshold squared, and, with fewer than
// kConvergenceContrastGuardSamples samples, the range of the neighbourhood's means over its samples
// is at most kConvergenceContrastShare of the threshold: the headless rule (ProgressiveImage::kOwnShare,
// kContrastGuardSamples and kContrastShare, host/render/adaptive.h, which checks that they agree).
VKRAY_CONST(float, kConvergenceOwnShare, 0.8);
VKRAY_CONST(float, kConvergenceContrastShare, 0.25);
VKRAY_CONST(float, kConvergenceContrastGuardSamples, 16.0);

// Push constants: uvec2(width, height) of the image.

#ifdef __cplusplus
} // namespace vkray::gpu
#endif

#endif
