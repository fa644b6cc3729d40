// The pinhole camera: which pixel an invocation traces and the eye ray through a point of the image
// plane.
#ifndef VKRAY_CAMERA_GLSL
#define VKRAY_CAMERA_GLSL

#include "bindings.glsl"

// of pixels instead of a row of 8, so that its lanes' rays stay closer together and walk, hit and
// bounce more alike (docs/performance.md, "Pixel blocks"). The workgroup covers the same 8 x 8
// pixels (row culling's unit), and no pixel's value depends on which lane traces it.
uvec2 invocationPixel() {
  uvec2 l = gl_LocalInvocationID.xy;
  uvec2 inGroup = uvec2((l.x & 3u) + 4u * (l.y & 1u), 2u * (l.y >> 1u) + (l.x >> 2u));
  return gl_WorkGroupID.xy * uvec2(kWorkgroupSizeX, kWorkgroupSizeY) + inGroup;
}

// Direction, unnormalized, of the eye ray through a point of the image plane given in pixels (x
// right, y down, (0,0) top-left).
vec3 imagePlaneDir(vec2 pixelPos) {
  vec2 size = vec2(frame.imageSize);
  float x = 2.0 * pixelPos.x / size.x - 1.0;
  float y = 1.0 - 2.0 * pixelPos.y / size.y;
  return frame.cameraForward.xyz + x * frame.cameraRight.xyz + y * frame.cameraUp.xyz;
}

// The same ray's unit direction.
vec3 eyeRayDir(vec2 pixelPos) { return normalize(imagePlaneDir(pixelPos)); }

#endif
