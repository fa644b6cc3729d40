// The camera: which pixel an invocation traces, the pinhole's eye ray through a point of the image
// plane, and the thin lens's (THIN_LENS: depth of field).
#ifndef VKRAY_CAMERA_GLSL
#define VKRAY_CAMERA_GLSL

#include "bindings.glsl"

// Which pixel of the dispatch an invocation traces, for the workgroup tile `group`: each SIMD batch
// of 8 lanes takes a 4 x 2 block of pixels instead of a row of 8, so that its lanes' rays stay
// closer together and walk, hit and bounce more alike (docs/performance.md, "Pixel blocks"). The
// workgroup covers the same 8 x 8 pixels (row culling's unit), and no pixel's value depends on
// which lane traces it.
uvec2 invocationPixelIn(uvec2 group) {
  uvec2 l = gl_LocalInvocationID.xy;
  uvec2 inGroup = uvec2((l.x & 3u) + 4u * (l.y & 1u), 2u * (l.y >> 1u) + (l.x >> 2u));
  return group * uvec2(kWorkgroupSizeX, kWorkgroupSizeY) + inGroup;
}
uvec2 invocationPixel() { return invocationPixelIn(gl_WorkGroupID.xy); }

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

// A point of [0, 1)^2 mapped to the unit disk, area-preserving and with little distortion, so the
// sample sequence's stratification carries over to the lens (Shirley & Chiu, "A Low Distortion Map
// Between Disk and Square", 1997; the form of pbrt-v4's SampleUniformDiskConcentric).
vec2 concentricDisk(vec2 u) {
  vec2 o = 2.0 * u - 1.0;
  if (o.x == 0.0 && o.y == 0.0) return vec2(0.0);
  const float kQuarterPi = 0.78539816339;
  float r, theta;
  if (abs(o.x) > abs(o.y)) {
    r = o.x;
    theta = kQuarterPi * (o.y / o.x);
  } else {
    r = o.y;
    theta = 2.0 * kQuarterPi - kQuarterPi * (o.x / o.y);
  }
  return r * vec2(cos(theta), sin(theta));
}

// The thin lens's eye ray through a point of the image plane: it starts at the lens point `lensUv`
// (in [0, 1)^2, mapped to the disk of radius frame.cameraOrigin.w around the eye, in the plane of
// cameraRight and cameraUp) and passes through the point the pinhole ray meets on the plane in focus
// (frame.focusDistance along cameraForward), so that plane stays sharp and everything else blurs by
// the thin-lens circle of confusion (pbrt-v4, PerspectiveCamera::GenerateRay). Unit direction.
void thinLensRay(vec2 pixelPos, vec2 lensUv, out vec3 origin, out vec3 dir) {
  vec3 d = imagePlaneDir(pixelPos); // cameraForward is a unit vector: d's depth along it is 1
  vec3 focus = frame.focusDistance * d;
  vec2 lens = frame.cameraOrigin.w * concentricDisk(lensUv);
  vec3 offset = lens.x * normalize(frame.cameraRight.xyz) + lens.y * normalize(frame.cameraUp.xyz);
  origin = frame.cameraOrigin.xyz + offset;
  dir = normalize(focus - offset);
}

#endif
