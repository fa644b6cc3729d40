// Ray-query kernel for `vkray bench meshes`: the work of Embree's rtcIntersect1 and rtcOccluded1,
// done by the renderer's own traversal and intersection (lib/scene.glsl), with no shading. One
// invocation per pixel makes the eye ray through the pixel centre and finds its closest hit; with
// SHADOWS on, a lit hit also sends a shadow ray to light 0, spawned off the surface as the renderer
// does, and asks only whether anything is in the way (any-hit).
//
// It uses the renderer's pipeline layout and bands (host/render/renderer.cpp, band_loop.cpp). Each pixel gets
// vec4(t or -1, hit kind, primitive index, shadow): -1 no shadow ray, 0 lit, 1 occluded.
#version 460
#extension GL_GOOGLE_include_directive : require

#include "shared/gpu_types.h"

layout(local_size_x = kWorkgroupSizeX, local_size_y = kWorkgroupSizeY, local_size_z = 1) in;

#include "lib/offset.glsl"
#include "lib/scene.glsl"

// One per pixel, written as a storage buffer (gpu_types.h, kBindingImageOut: cheaper than imageStore).
layout(std430, binding = kBindingImageOut) writeonly restrict buffer HitOut { vec4 hitOut[]; };
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
  vec4 result = vec4(-1.0, float(h.kind), float(h.index), -1.0);
  if (h.kind != kNoHit) {
    result.x = h.t;
    if (SHADOWS) {
      Surface s = surfaceAt(r, h);
      vec3 ng = dot(s.ng, dir) > 0.0 ? -s.ng : s.ng; // towards the eye
      vec3 lightPos = lightPosition(loadLight(0u));
      if (dot(ng, lightPos - s.p) > 0.0) {
        vec3 origin = ROBUST ? spawnOrigin(s.p, ng, s.errorBound) : s.p; // as localShade (shade.glsl)
        vec3 toLight = lightPos - origin;
        float dist = length(toLight);
        ShadowStart start = shadowEntryPoints(h.kind, h.index, 0u);
        Hit blocker = traceScene(makeTraceRay(origin, toLight / dist), dist, true, true, false, start);
        result.w = blocker.kind == kNoHit ? 0.0 : 1.0;
      }
    }
  }
  hitOut[(pixel.y - pc.imageRow0) * frame.imageSize.x + pixel.x] = result;
}
