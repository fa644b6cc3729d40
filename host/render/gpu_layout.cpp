// Compile-time checks that the C++ view of shaders/shared/gpu_types.h matches std430/std140: every
// size and offset the shaders rely on. A mismatch fails the build, not the image.
#include <cstddef>

#include "../../shaders/shared/gpu_types.h"

namespace vkray::gpu {

static_assert(sizeof(Material) == 80);
static_assert(offsetof(Material, color2) == 16 && offsetof(Material, phong) == 32);
static_assert(offsetof(Material, transmission) == 48 && offsetof(Material, absorption) == 64);
static_assert(sizeof(Light) == 32 && offsetof(Light, color) == 16);
static_assert(sizeof(Sphere) == 32 && offsetof(Sphere, meta) == 16);
static_assert(sizeof(Plane) == 32 && offsetof(Plane, meta) == 16);
static_assert(sizeof(Triangle) == 48 && offsetof(Triangle, v1) == 16 && offsetof(Triangle, v2) == 32);
static_assert(sizeof(Polygon) == 32 && offsetof(Polygon, meta) == 16);
// vec3 + uint pairs: std430 puts the uint in the vec3's fourth slot.
static_assert(sizeof(BvhNode) == 32);
static_assert(offsetof(BvhNode, offset) == 12 && offsetof(BvhNode, boundsMax) == 16 &&
              offsetof(BvhNode, countAxis) == 28);
static_assert(sizeof(BvhWideNode) == 64 && offsetof(BvhWideNode, ref1) == 28 && offsetof(BvhWideNode, max1) == 48);
// Records read as texels (16 bytes each).
static_assert(sizeof(TextureRef) == kTextureRefTexels * 16 && sizeof(TextureLevel) == 16 && sizeof(UvInfo) == 16);
static_assert(kUvRecordInfo == 3 && kUvRecordColors == kUvRecordTexels, "a uv record: 3 corners, UvInfo, colours");
static_assert(sizeof(TileEntryPoints) == 32 && kEntryStackSlots == 6, "stack words 0..3, then 4, 5, start, height");
static_assert(sizeof(FrameParams) == 16 * 16 && offsetof(FrameParams, sampleSeed) == 240);
static_assert(offsetof(FrameParams, bailout) == 112 && offsetof(FrameParams, adaptiveThreshold) == 116);
static_assert(offsetof(FrameParams, imageSize) == 128 && offsetof(FrameParams, maxDepth) == 140);
static_assert(offsetof(FrameParams, sphereCount) == 144 && offsetof(FrameParams, polygonCount) == 156);
static_assert(offsetof(FrameParams, lightCount) == 160 && offsetof(FrameParams, occluderPlaneCount) == 168);
static_assert(offsetof(FrameParams, bvhRoot) == 172 && offsetof(FrameParams, triangleBoundsMin) == 176);
static_assert(sizeof(RayStats) == 48);
static_assert(sizeof(SceneUbo) <= 65536, "the packed scene must fit the smallest maxUniformBufferRange");
static_assert(sizeof(PushConstants) == 68 && offsetof(PushConstants, pass) == 16 &&
              offsetof(PushConstants, imageRow0) == 32 && offsetof(PushConstants, splitBase) == 48 &&
              offsetof(PushConstants, splitBase2) == 64);
static_assert(sizeof(TreeRay) == 112 && offsetof(TreeRay, what) == 80 && offsetof(TreeRay, where) == 96,
              "TreeRay: seven 16-byte members, as std430 lays them out");
static_assert(sizeof(TreeRayHeader) == 16, "TreeRayBuffer: the records start 16 bytes in");
static_assert(sizeof(PushConstants) <= 128, "Vulkan guarantees 128 bytes of push constants");
// invocationPixel() (shaders/lib/camera.glsl) deals each row of 8 invocations a 4 x 2 pixel block.
static_assert(kWorkgroupSizeX == 8 && kWorkgroupSizeY % 2 == 0, "invocationPixel assumes 8-wide, even-high groups");

} // namespace vkray::gpu
