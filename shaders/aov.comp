// First-hit AOV kernel for `vkray render --aov`: one invocation per pixel makes the eye ray through
// the pixel centre (as hits.comp does) and writes what it meets first, with no shading and no
// secondary rays. Centre-sample AOVs are unambiguous at edges, where a depth or normal averaged
// over the pixel's samples would describe no surface at all.
//
// It uses the renderer's pipeline layout and bands (host/render/renderer.cpp, band_loop.cpp); the
// image window holds two texels per pixel, at 2 i and 2 i + 1 for the band's pixel i:
//   vec4(depth, normal): depth is the distance from the eye along the ray (the direction is unit
//     length), +inf where nothing is hit; normal the world-space shading normal turned towards
//     the eye, 0 where nothing is hit;
//   vec4(albedo, hit): the material's base colour at the hit (checker, texture and vertex colours
//     applied, as shading sees it), 0 where nothing is hit; hit 1 or 0.
#version 460
#extension GL_GOOGLE_include_directive : require

#include "shared/gpu_types.h"

layout(local_size_x = kWorkgroupSizeX, local_size_y = kWorkgroupSizeY, local_size_z = 1) in;

#include "lib/shade.glsl"

// Two per pixel, written as a storage buffer (gpu_types.h, kBindingImageOut: cheaper than imageStore).
layout(std430, binding = kBindingImageOut) writeonly restrict buffer AovOut { vec4 aovOut[]; };
layout(std430, binding = kBindingStats) readonly buffer StatsBuffer { RayStats stats; };
layout(push_constant) uniform Push { PushConstants pc; };

void main() {
  gDynamicZero = stats.zero;
  loadSceneRegisters(); // before any branch (scene_access.glsl)
  uvec2 local = invocationPixel(); // a 4 x 2 block per SIMD batch (camera.glsl)
  uvec2 pixel = pc.tileOrigin + local;
  if (!all(lessThan(local, pc.tileSize)) || !all(lessThan(pixel, frame.imageSize))) return;
  loadEntryPoints(pixel, pc.imageRow0);

  // The pinhole's ray through the pixel centre, whatever camera.aperture: one sharp ray per pixel
  // (a thin lens blurs only the shading kernel's image, trace.comp's traceSample).
  vec3 dir = eyeRayDir(vec2(pixel) + 0.5);
  TraceRay r = makeTraceRay(frame.cameraOrigin.xyz, dir);
  Hit h = traceScene(r, kInfinity, false, false, true);
  const float positiveInfinity = uintBitsToFloat(0x7F800000u); // a miss's depth (IEEE 754 +inf)
  vec4 depthNormal = vec4(positiveInfinity, 0.0, 0.0, 0.0);
  vec4 albedoHit = vec4(0.0);
  if (h.kind != kNoHit) {
    Surface s = surfaceAt(r, h);
    // Facing the eye as the trace kernel turns it (trace.comp): by the geometric normal's side.
    vec3 ns = dot(s.ng, dir) < 0.0 ? s.ns : -s.ns;
    depthNormal = vec4(h.t, ns);
    // The eye ray's cone at the hit, as trace.comp sets it for texture LOD (RTG ch. 20).
    if (TEXTURES) gConeFootprint = frame.coneSpread * h.t / max(abs(dot(s.ng, dir)), 1e-6);
    albedoHit = vec4(baseColor(loadMaterial(s.material), s), 1.0);
  }
  int texel = 2 * int((pixel.y - pc.imageRow0) * frame.imageSize.x + pixel.x);
  aovOut[texel] = depthNormal;
  aovOut[texel + 1] = albedoHit;
}
