// The viewer's resolve pass: turns the Renderer's per-pixel sums into displayable colour (average,
// clamp, sRGB encode). Built twice (CMakeLists.txt): by default it writes a half-float image that is
// then blitted (and scaled) to the swapchain; with VKRAY_RESOLVE_DIRECT it writes the swapchain image
// itself, whatever its 8-bit format, with the overlay's panel composited, which saves the blit, an
// image and the overlay's render pass where the device allows it (host/viewer/presenter.h).
#version 450
#extension GL_GOOGLE_include_directive : require

#include "shared/resolve_types.h"

layout(local_size_x = kResolveGroupX, local_size_x_id = kResolveSpecGroupX, local_size_y = 1, local_size_z = 1) in;

layout(constant_id = kResolveSpecEncodeSrgb) const bool ENCODE_SRGB = true;
layout(constant_id = kResolveSpecDisplay) const uint DISPLAY = kDisplayImage;
layout(constant_id = kResolveSpecMapLow) const float MAP_LOW = 0.001;
layout(constant_id = kResolveSpecMapHigh) const float MAP_HIGH = 0.1;

// The Renderer's sums, read where they are: a storage texel buffer, which lavapipe reads with one
// 16-byte load per lane inline (a storage-buffer read would be a per-lane loop per component, once
// 80 % of this pass's time; copying them into a sampled image cost about 1 ms a frame).
layout(binding = kResolveBindingSums, rgba32f) uniform readonly restrict imageBuffer sums;
// The map's values (DISPLAY != kDisplayImage): float bits of the error estimates, or rays per pixel.
layout(std430, binding = kResolveBindingMap) readonly restrict buffer MapValues { uint mapWords[]; };
#ifdef VKRAY_RESOLVE_DIRECT
// The swapchain image: no format named (shaderStorageImageWriteWithoutFormat), so one pipeline
// writes BGRA and RGBA images alike; the store rounds to 8 bits.
layout(binding = kResolveBindingDisplay) writeonly uniform image2D display;
// The overlay's panel, drawn by Dear ImGui on a transparent image of the same size when it changes
// (host/viewer/overlay.h): premultiplied colour and coverage, so `layer + (1 - coverage) * picture`
// is what drawing the panel on the picture gives, and an unchanged panel costs no render pass.
layout(binding = kResolveBindingOverlay) uniform sampler2D overlayLayer;
#else
// Half floats hold both sRGB-encoded values (for a UNORM swapchain, which the blit copies as they
// are) and linear ones (for an sRGB swapchain, which the blit encodes) without visible banding.
layout(binding = kResolveBindingDisplay, rgba16f) writeonly uniform image2D display;
#endif

// IEC 61966-2-1, as host/image/image.cpp encodes PNGs, with the power x^(1/2.4) of the upper
// segment replaced by a fit in x and its square, fourth and eighth roots: three sqrt and four FMAs,
// where llvmpipe spells pow as a log2 and an exp2 polynomial (a third of this pass's time at
// 640 x 480). Minimax over [0.0031308, 1], its largest error is 3.2e-5, 0.008 of an 8-bit level, so
// the 8-bit value is the exact encoding's except where that lies within 0.008 levels of a rounding
// boundary (tools/fit-srgb prints the fit and its error). Branch-free (mix): CPU drivers run both
// sides of a branch anyway.
const float kSrgbFit0 = -0.00407524128;
const float kSrgbFit1 = -0.0201908946;
const float kSrgbFit2 = 0.653998077;
const float kSrgbFit3 = 0.688680351;
const float kSrgbFit4 = -0.318444014;
vec3 linearToSrgb(vec3 v) {
  v = clamp(v, 0.0, 1.0);
  vec3 r2 = sqrt(v);
  vec3 r4 = sqrt(r2);
  vec3 r8 = sqrt(r4);
  vec3 hi = kSrgbFit0 + kSrgbFit1 * v + kSrgbFit2 * r2 + kSrgbFit3 * r4 + kSrgbFit4 * r8;
  return mix(hi, 12.92 * v, lessThanEqual(v, vec3(0.0031308)));
}

// A heat colour for t in [0, 1]: black, blue, cyan, green, yellow, red, white at the stops
// (linear RGB, as the image's colour before encoding).
vec3 heat(float t) {
  const vec3 stops[7] = vec3[7](vec3(0.0), vec3(0.0, 0.0, 1.0), vec3(0.0, 1.0, 1.0), vec3(0.0, 1.0, 0.0),
                                vec3(1.0, 1.0, 0.0), vec3(1.0, 0.0, 0.0), vec3(1.0));
  float x = clamp(t, 0.0, 1.0) * 6.0;
  int k = min(int(x), 5);
  return mix(stops[k], stops[k + 1], x - float(k));
}

// The map's value on its log scale: MAP_LOW at the bottom of the ramp's coloured part (blue, 1/6),
// MAP_HIGH at its top (red, 5/6); zero is black, beyond the top whitens.
vec3 mapColour(float value) {
  float t = (log2(max(value, 1e-30)) - log2(MAP_LOW)) / (log2(MAP_HIGH) - log2(MAP_LOW));
  return value > 0.0 ? heat(1.0 / 6.0 + t * (4.0 / 6.0)) : vec3(0.0);
}

void main() {
  // The image size comes from the image itself: no push constant decides a branch (lavapipe's
  // dispatch-time inlining of uniform values crashes on those, see docs/performance.md).
  ivec2 size = imageSize(display);
  ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(pixel, size))) return;
  vec4 s = imageLoad(sums, pixel.y * size.x + pixel.x); // row-major, as wide as the image written
  // A pixel not traced yet (no samples) has a zero sum: black.
  vec3 rgb = pixelRadianceSum(s) / max(pixelSampleCount(s), 1.0);
  uint i = uint(pixel.y * size.x + pixel.x);
  if (DISPLAY == kDisplayError) rgb = mapColour(uintBitsToFloat(mapWords[i]));
  if (DISPLAY == kDisplayCost) rgb = mapColour(float(mapWords[i]) / max(pixelSampleCount(s), 1.0));
  rgb = ENCODE_SRGB ? linearToSrgb(rgb) : clamp(rgb, 0.0, 1.0);
#ifdef VKRAY_RESOLVE_DIRECT
  // ImGui blends in the swapchain's UNORM values, which hold sRGB-encoded colour: so does this.
  vec4 panel = texelFetch(overlayLayer, pixel, 0);
  rgb = panel.rgb + (1.0 - panel.a) * rgb;
#endif
  imageStore(display, pixel, vec4(rgb, 1.0));
}
