// The scene as the tracing kernel sees it: descriptor bindings, specialization constants, and the two
// queries every ray makes (closest hit; occlusion up to a distance), over brute-force loops or a BVH.
#ifndef VKRAY_SCENE_GLSL
#define VKRAY_SCENE_GLSL

#include "../shared/gpu_types.h"
#include "common.glsl"

#extension GL_KHR_shader_subgroup_ballot : require // traverseBvh's lockstep

// ---- Specialization: what this scene calls for ---------------------------------------------------
layout(constant_id = kSpecHasSpheres) const bool HAS_SPHERES = true;
layout(constant_id = kSpecHasPlanes) const bool HAS_PLANES = true;
layout(constant_id = kSpecHasTriangles) const bool HAS_TRIANGLES = true;
layout(constant_id = kSpecHasPolygons) const bool HAS_POLYGONS = true;
layout(constant_id = kSpecUseBvh) const bool USE_BVH = false;
layout(constant_id = kSpecShadows) const bool SHADOWS = true;
layout(constant_id = kSpecReflection) const bool REFLECTION = true;
layout(constant_id = kSpecRefraction) const bool REFRACTION = true;
layout(constant_id = kSpecStackSize) const int STACK_SIZE = 16;
layout(constant_id = kSpecCountStats) const bool COUNT_STATS = true;
layout(constant_id = kSpecNumerics) const uint NUMERICS = kNumericsRobust;
layout(constant_id = kSpecFresnel) const uint FRESNEL = kFresnelExact;
layout(constant_id = kSpecShadowMode) const uint SHADOW_MODE = kShadowsAttenuated;
layout(constant_id = kSpecChecker) const bool CHECKER = true;
layout(constant_id = kSpecSmoothNormals) const bool SMOOTH_NORMALS = true;
layout(constant_id = kSpecSceneInUbo) const bool SCENE_IN_UBO = false;
layout(constant_id = kSpecShadingInUbo) const bool SHADING_IN_UBO = false;
layout(constant_id = kSpecCenterSample) const bool CENTER_SAMPLE = false;
layout(constant_id = kSpecSphereCount) const uint SPHERE_COUNT = kRuntimeCount;
layout(constant_id = kSpecPlaneCount) const uint PLANE_COUNT = kRuntimeCount;
layout(constant_id = kSpecTriangleCount) const uint TRIANGLE_COUNT = kRuntimeCount;
layout(constant_id = kSpecPolygonCount) const uint POLYGON_COUNT = kRuntimeCount;
layout(constant_id = kSpecLightCount) const uint LIGHT_COUNT = kRuntimeCount;
layout(constant_id = kSpecOccluderPlaneCount) const uint OCCLUDER_PLANE_COUNT = kRuntimeCount;
layout(constant_id = kSpecMaterialCount) const uint MATERIAL_COUNT = kRuntimeCount;
layout(constant_id = kSpecEntryPoints) const bool ENTRY_POINTS = false;

const bool ROBUST = NUMERICS == kNumericsRobust;

// ---- Buffers -------------------------------------------------------------------------------------
layout(std140, binding = kBindingFrame) uniform FrameBlock { FrameParams frameUbo; };
FrameParams frame; // frameUbo, copied by loadSceneRegisters() (below)
layout(std430, binding = kBindingMaterials) readonly buffer Materials { Material materials[]; };
layout(std430, binding = kBindingLights) readonly buffer Lights { Light lights[]; };
layout(std430, binding = kBindingSpheres) readonly buffer Spheres { Sphere spheres[]; };
layout(std430, binding = kBindingPlanes) readonly buffer Planes { Plane planes[]; };
layout(std430, binding = kBindingPolygons) readonly buffer Polygons { Polygon polygons[]; };
layout(std430, binding = kBindingPolyVertices) readonly buffer PolyVertices { vec4 polyVertices[]; };
// The mesh-sized arrays are texel buffers: a texel read at per-invocation addresses is one vector
// gather on lavapipe, where a storage-buffer read is a per-lane loop of scalar loads (2-3x slower
// traversal, docs/performance.md "Meshes"); and a texel buffer may hold maxTexelBufferElements
// texels (2 GiB of 16-byte texels on lavapipe) where a storage buffer is capped at
// maxStorageBufferRange. Triangles and BVH records are read as integers (RGBA32UI) and their
// coordinates reinterpreted: their fourth words are ids and indices, and small ones read through a
// float format would be denormals, which Vulkan lets a device flush to zero on the way in. The two
// hottest, BVH records and triangles, are storage texel buffers read with imageLoad: llvmpipe
// compiles a texelFetch as a call to a sampling function, an imageLoad into the kernel itself
// (7 % fewer instructions executed on the mesh scene).
layout(binding = kBindingTriangles, rgba32ui) uniform readonly restrict uimageBuffer triangleTexels; // 3 per Triangle
layout(binding = kBindingNormals) uniform samplerBuffer normalTexels;    // 1 per vertex normal
layout(binding = kBindingBvhNodes, rgba32ui) uniform readonly restrict uimageBuffer nodeTexels; // 4 per BvhWideNode
layout(binding = kBindingPrimRefs) uniform usamplerBuffer primRefTexels; // 1 per reference

layout(std140, binding = kBindingSceneUbo) uniform SceneBlock { SceneUbo small; };
// Written by shaders/entry.comp as a storage buffer, read here as texels once per invocation.
layout(binding = kBindingEntryTexels) uniform usamplerBuffer entryTexels;

// Loop bounds: a specialization constant where the host baked the count in (the loop unrolls).
uint sphereCount() { return SPHERE_COUNT != kRuntimeCount ? SPHERE_COUNT : opaqueUniform(frame.counts.x); }
uint planeCount() { return PLANE_COUNT != kRuntimeCount ? PLANE_COUNT : opaqueUniform(frame.counts.y); }
uint triangleCount() { return TRIANGLE_COUNT != kRuntimeCount ? TRIANGLE_COUNT : opaqueUniform(frame.counts.z); }
uint polygonCount() { return POLYGON_COUNT != kRuntimeCount ? POLYGON_COUNT : opaqueUniform(frame.counts.w); }
uint occluderPlaneCount() {
  return OCCLUDER_PLANE_COUNT != kRuntimeCount ? OCCLUDER_PLANE_COUNT : opaqueUniform(frame.counts2.z);
}
uint lightCount() { return LIGHT_COUNT != kRuntimeCount ? LIGHT_COUNT : opaqueUniform(frame.counts2.x); }

// ---- Small scenes in registers -------------------------------------------------------------------
// llvmpipe reads a uniform buffer with one scalar load only in straight-line code at the top of the
// kernel: inside any branch or loop (where the whole trace runs) every read is an 8-lane gather with
// a bounds check, some 30 instructions per component even at a constant address. So
// loadSceneRegisters(), the first thing each kernel does, reads the frame's parameters and every
// small array whose count is baked in (kMaxUnrolledCount) into these globals, and the trace reads
// registers: a constant index (the unrolled loops) is the value itself, a per-lane one (a hit's
// material) a chain of selects. Only arrays read from the uniform block are cached, which the host
// chooses on CPU devices (or with --scene-memory uniform): a GPU reads uniforms through a constant
// cache, and keeping them live in registers would only cost it occupancy.
const bool CACHE_MATERIALS = (SCENE_IN_UBO || SHADING_IN_UBO) && MATERIAL_COUNT != kRuntimeCount;
const bool CACHE_LIGHTS = (SCENE_IN_UBO || SHADING_IN_UBO) && LIGHT_COUNT != kRuntimeCount;
const bool CACHE_PLANES = (SCENE_IN_UBO || SHADING_IN_UBO) && PLANE_COUNT != kRuntimeCount;
const bool CACHE_SPHERES = SCENE_IN_UBO && SPHERE_COUNT != kRuntimeCount;
const bool CACHE_TRIANGLES = SCENE_IN_UBO && TRIANGLE_COUNT != kRuntimeCount;
const bool CACHE_POLYGONS = SCENE_IN_UBO && POLYGON_COUNT != kRuntimeCount;
const uint kCachedMaterials = (CACHE_MATERIALS && MATERIAL_COUNT > 0u) ? MATERIAL_COUNT : 1u;
const uint kCachedLights = (CACHE_LIGHTS && LIGHT_COUNT > 0u) ? LIGHT_COUNT : 1u;
const uint kCachedPlanes = (CACHE_PLANES && PLANE_COUNT > 0u) ? PLANE_COUNT : 1u;
const uint kCachedSpheres = (CACHE_SPHERES && SPHERE_COUNT > 0u) ? SPHERE_COUNT : 1u;
const uint kCachedTriangles = (CACHE_TRIANGLES && TRIANGLE_COUNT > 0u) ? TRIANGLE_COUNT : 1u;
const uint kCachedPolygons = (CACHE_POLYGONS && POLYGON_COUNT > 0u) ? POLYGON_COUNT : 1u;

Material gMaterials[kCachedMaterials];
Light gLights[kCachedLights];
Plane gPlanes[kCachedPlanes];
Sphere gSpheres[kCachedSpheres];
Triangle gTriangles[kCachedTriangles];
Polygon gPolygons[kCachedPolygons];

// cachedX(i): element i of a cached array as a chain of selects over the registers; a constant i
// (an unrolled loop) folds to the element itself.
#define VKRAY_DEFINE_CACHED_READ(Type, name, array, count)                                          \
  Type name(uint i) {                                                                              \
    Type picked = array[0];                                                                        \
    for (uint k = 1u; k < count; ++k) picked = i == k ? array[k] : picked;                         \
    return picked;                                                                                 \
  }
VKRAY_DEFINE_CACHED_READ(Material, cachedMaterial, gMaterials, kCachedMaterials)
VKRAY_DEFINE_CACHED_READ(Light, cachedLight, gLights, kCachedLights)
VKRAY_DEFINE_CACHED_READ(Plane, cachedPlane, gPlanes, kCachedPlanes)
VKRAY_DEFINE_CACHED_READ(Sphere, cachedSphere, gSpheres, kCachedSpheres)
VKRAY_DEFINE_CACHED_READ(Triangle, cachedTriangle, gTriangles, kCachedTriangles)
VKRAY_DEFINE_CACHED_READ(Polygon, cachedPolygon, gPolygons, kCachedPolygons)

// The cached values pass through opaqueUniform (common.glsl): read straight from the uniform block
// at constant offsets, values that decide a branch (a material's diffuse factor, say) would invite
// lavapipe's dispatch-time uniform inlining, which then recompiles the kernel on every new pipeline.
vec4 opaqueVec4(vec4 v) { return uintBitsToFloat(floatBitsToUint(v) + gDynamicZero); }
uvec4 opaqueVec4(uvec4 v) { return v + gDynamicZero; }

// Call first in main(), after gDynamicZero is set, before any branch.
void loadSceneRegisters() {
  frame = frameUbo;
  for (uint k = 0u; CACHE_MATERIALS && k < kCachedMaterials; ++k) {
    Material m = small.materials[k];
    gMaterials[k] = Material(opaqueVec4(m.color), opaqueVec4(m.color2), opaqueVec4(m.phong),
                             opaqueVec4(m.transmission), opaqueVec4(m.absorption));
  }
  for (uint k = 0u; CACHE_LIGHTS && k < kCachedLights; ++k) {
    gLights[k] = Light(opaqueVec4(small.lights[k].position), opaqueVec4(small.lights[k].color));
  }
  for (uint k = 0u; CACHE_PLANES && k < kCachedPlanes; ++k) {
    gPlanes[k] = Plane(opaqueVec4(small.planes[k].normalOffset), opaqueVec4(small.planes[k].meta));
  }
  for (uint k = 0u; CACHE_SPHERES && k < kCachedSpheres; ++k) {
    gSpheres[k] = Sphere(opaqueVec4(small.spheres[k].centerRadius), opaqueVec4(small.spheres[k].meta));
  }
  for (uint k = 0u; CACHE_TRIANGLES && k < kCachedTriangles; ++k) {
    Triangle t = small.triangles[k];
    gTriangles[k] = Triangle(opaqueVec4(t.v0), opaqueVec4(t.v1), opaqueVec4(t.v2));
  }
  for (uint k = 0u; CACHE_POLYGONS && k < kCachedPolygons; ++k) {
    Polygon q = small.polygons[k];
    gPolygons[k] = Polygon(opaqueVec4(q.plane), opaqueVec4(q.meta));
  }
}

// Scene array access. The specialization constants leave one way of each: registers, the uniform
// block, or the storage buffers.
Material loadMaterial(uint i) {
  if (CACHE_MATERIALS) return cachedMaterial(i);
  if (SCENE_IN_UBO || SHADING_IN_UBO) return small.materials[i];
  return materials[i];
}
Light loadLight(uint i) {
  if (CACHE_LIGHTS) return cachedLight(i);
  if (SCENE_IN_UBO || SHADING_IN_UBO) return small.lights[i];
  return lights[i];
}
Sphere loadSphere(uint i) {
  if (CACHE_SPHERES) return cachedSphere(i);
  if (SCENE_IN_UBO) return small.spheres[i];
  return spheres[i];
}
Plane loadPlane(uint i) {
  if (CACHE_PLANES) return cachedPlane(i);
  if (SCENE_IN_UBO || SHADING_IN_UBO) return small.planes[i];
  return planes[i];
}
Triangle loadTriangle(uint i) {
  if (CACHE_TRIANGLES) return cachedTriangle(i);
  if (SCENE_IN_UBO) return small.triangles[i];
  int t = int(3u * i);
  return Triangle(uintBitsToFloat(imageLoad(triangleTexels, t)), uintBitsToFloat(imageLoad(triangleTexels, t + 1)),
                  uintBitsToFloat(imageLoad(triangleTexels, t + 2)));
}
vec3 loadShadingNormal(uint i) { return texelFetch(normalTexels, int(i)).xyz; }
Polygon loadPolygon(uint i) {
  if (CACHE_POLYGONS) return cachedPolygon(i);
  if (SCENE_IN_UBO) return small.polygons[i];
  return polygons[i];
}
vec3 loadPolyVertex(uint i) {
  if (SCENE_IN_UBO) return small.polyVertices[i].xyz;
  return polyVertices[i].xyz;
}

#define VKRAY_POLYGON_VERTEX(i) loadPolyVertex(i)
#include "intersect.glsl"

// The float64 variant of the kernel (built with -DVKRAY_FLOAT64) intersects in double: the
// accuracy report's reference. It ignores NUMERICS; shading stays in float.
#ifdef VKRAY_FLOAT64
#extension GL_ARB_gpu_shader_fp64 : enable
#include "intersect64.glsl"
#endif

// ---- Hits ----------------------------------------------------------------------------------------
const uint kNoHit = 0xFFFFFFFFu;

struct Hit {
  float t;    // the query's tMax when nothing was hit
  uint kind;  // kPrimSphere / kPrimTriangle / kPrimPolygon / kPrimPlane, or kNoHit
  uint index; // into the array of that kind
  vec3 bary;  // triangles: barycentric weights of v0, v1, v2
};

// Everything shading needs about a hit, built once for the closest hit (pbrt's second step).
struct Surface {
  vec3 p;           // hit point
  vec3 ng;          // geometric normal, unit, as stored (outward for spheres)
  vec3 ns;          // shading normal, unit, on the same side as ng
  float errorBound; // distance of p from the true surface along ng, at most
  uint material;
  uint kind;        // kPrim* of the primitive hit
};

// A ray with its per-ray precomputation for the watertight triangle test and the BVH slabs.
struct TraceRay {
  Ray ray;
  WatertightRay w;
  vec3 invDir;
};

TraceRay makeTraceRay(vec3 origin, vec3 dir) {
  TraceRay r;
  r.ray = Ray(origin, dir);
  if (HAS_TRIANGLES || HAS_POLYGONS) r.w = watertightSetup(dir);
  // An exactly-zero component would give (0 * inf) = NaN in the slab test; a tiny one gives the same
  // classification for every box the ray does not lie in the face plane of.
  vec3 safe = mix(dir, vec3(1e-30), equal(dir, vec3(0.0)));
  r.invDir = 1.0 / safe;
  return r;
}

// This invocation's pixel in the dispatch (before the tile's origin). lavapipe runs a workgroup as
// SIMD batches of 8 consecutive invocations, rows of the 8 x 8 group; each batch takes a 4 x 2 block
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
  vec2 size = vec2(frame.imageSize.xy);
  float x = 2.0 * pixelPos.x / size.x - 1.0;
  float y = 1.0 - 2.0 * pixelPos.y / size.y;
  return frame.cameraForward.xyz + x * frame.cameraRight.xyz + y * frame.cameraUp.xyz;
}

// The same ray's unit direction.
vec3 eyeRayDir(vec2 pixelPos) { return normalize(imagePlaneDir(pixelPos)); }

float sphereT(TraceRay r, uint i, float tMax) {
  vec4 s = loadSphere(i).centerRadius;
#ifdef VKRAY_FLOAT64
  return intersectSphere64(r.ray, s.xyz, s.w, tMax);
#endif
  return ROBUST ? intersectSphereRobust(r.ray, 1.0, s.xyz, s.w, tMax)
                : intersectSphereNaive(r.ray, s.xyz, s.w, tMax);
}

float triangleT(TraceRay r, uint i, float tMax, out vec3 bary) {
  Triangle tri = loadTriangle(i);
#ifdef VKRAY_FLOAT64
  return intersectTriangle64(r.ray, tri.v0.xyz, tri.v1.xyz, tri.v2.xyz, tMax, bary);
#endif
  return ROBUST ? intersectTriangleRobust(r.ray, r.w, tri.v0.xyz, tri.v1.xyz, tri.v2.xyz, tMax, bary)
                : intersectTriangleNaive(r.ray, tri.v0.xyz, tri.v1.xyz, tri.v2.xyz, tMax, bary);
}

float polygonT(TraceRay r, uint i, float tMax) {
  Polygon poly = loadPolygon(i);
#ifdef VKRAY_FLOAT64
  // Inside test as in float (edge functions are exact for the sign that matters), t in double.
  float tf = intersectPolygonRobust(r.ray, r.w, poly.plane.xyz, poly.meta.x, poly.meta.y, tMax);
  if (tf < 0.0) return -1.0;
  dvec3 n = dvec3(poly.plane.xyz);
  double td = dot(n, dvec3(loadPolyVertex(poly.meta.x)) - dvec3(r.ray.origin)) / dot(n, dvec3(r.ray.dir));
  return (td > 0.0 && td < double(tMax)) ? max(float(td), 1.4e-45) : -1.0;
#endif
  return ROBUST ? intersectPolygonRobust(r.ray, r.w, poly.plane.xyz, poly.meta.x, poly.meta.y, tMax)
                : intersectPolygonNaive(r.ray, poly.plane.xyz, poly.meta.x, poly.meta.y, tMax);
}

float planeT(TraceRay r, uint i, float tMax) {
  vec4 pl = loadPlane(i).normalOffset;
#ifdef VKRAY_FLOAT64
  return intersectPlane64(r.ray, pl.xyz, pl.w, tMax);
#endif
  return ROBUST ? intersectPlaneRobust(r.ray, pl.xyz, pl.w, tMax)
                : intersectPlaneNaive(r.ray, pl.xyz, pl.w, tMax);
}

// Tests one BVH leaf reference (or brute-force primitive) and keeps the closest hit.
void testPrimitive(TraceRay r, uint kind, uint index, inout Hit hit) {
  if (HAS_SPHERES && kind == kPrimSphere) {
    float t = sphereT(r, index, hit.t);
    if (t > 0.0) hit = Hit(t, kPrimSphere, index, vec3(0.0));
  } else if (HAS_TRIANGLES && kind == kPrimTriangle) {
    vec3 bary;
    float t = triangleT(r, index, hit.t, bary);
    if (t > 0.0) hit = Hit(t, kPrimTriangle, index, bary);
  } else if (HAS_POLYGONS && kind == kPrimPolygon) {
    float t = polygonT(r, index, hit.t);
    if (t > 0.0) hit = Hit(t, kPrimPolygon, index, vec3(0.0));
  }
}

// The invocation's tile's entry points (gpu_types.h), loaded by loadEntryPoints(); with them an eye
// ray's walk starts from the subtrees its tile's frustum reaches instead of the root.
uvec4 gEntryStack = uvec4(kBvhNoRef);
uvec4 gEntryStart = uvec4(kBvhNoRef, kBvhNoRef, kBvhNoRef, 0u); // stack words 4, 5; start; height

// Call in main() with the invocation's pixel, when ENTRY_POINTS; `row0` is the band's first row.
void loadEntryPoints(uvec2 pixel, uint row0) {
  if (!ENTRY_POINTS) return;
  uint tilesX = (frame.imageSize.x + kEntryTileSize - 1u) / kEntryTileSize;
  uint tile = ((pixel.y - row0) / kEntryTileSize) * tilesX + pixel.x / kEntryTileSize;
  gEntryStack = texelFetch(entryTexels, int(2u * tile));
  gEntryStart = texelFetch(entryTexels, int(2u * tile + 1u));
}

// A BVH leaf entry: the primitive's kind and index. In a scene whose bounded primitives are all
// triangles the host stores them in leaf order (host/render/gpu_scene.cpp, orderByLeaves), so the
// entry is the triangle itself and the PrimRefs[] read is skipped.
void leafPrimitive(uint entry, out uint kind, out uint index) {
  if (!HAS_SPHERES && !HAS_POLYGONS) {
    kind = kPrimTriangle;
    index = entry;
  } else {
    uint ref = texelFetch(primRefTexels, int(entry)).x;
    kind = ref >> kPrimKindShift;
    index = ref & kPrimIndexMask;
  }
}

// The entries [first, end) of a leaf reference (BvhWideNode).
void leafEntries(uint leaf, out uint first, out uint end) {
  first = leaf & kBvhLeafFirstMask;
  end = first + ((leaf >> kBvhLeafCountShift) & 15u) + 1u; // a leaf holds at least one
}

// ---- Traversal: every invocation walks the tree on its own ----------------------------------------

// min and max as compare-and-select. NIR's fmin/fmax must return the other operand of a NaN, which
// llvmpipe spells as min + unordered compare + blend; the slab distances are never NaN (invDir is
// finite, see makeTraceRay), and `precise` keeps NIR from turning the selects back into fmin/fmax,
// so LLVM emits one minps/maxps for each.
vec3 slabMin(vec3 a, vec3 b) {
  precise bvec3 lt = lessThan(a, b);
  return mix(b, a, lt);
}
vec3 slabMax(vec3 a, vec3 b) {
  precise bvec3 gt = greaterThan(a, b);
  return mix(b, a, gt);
}
float slabMin(float a, float b) {
  precise bool lt = a < b;
  return lt ? a : b;
}
float slabMax(float a, float b) {
  precise bool gt = a > b;
  return gt ? a : b;
}

// Entry distance of the ray into a box, +inf when it misses it or enters beyond tMax. The far
// distance is widened by 1 + 2 gamma(3) so rounding in the slab arithmetic never culls a box the ray
// truly touches (Ize, "Robust BVH Ray Traversal", JCGT 2(2), 2013): without it a ray along a shared
// mesh edge can miss both triangles' boxes.
float boxEntry(TraceRay r, vec3 bmin, vec3 bmax, float tMax) {
  vec3 t0 = (bmin - r.ray.origin) * r.invDir;
  vec3 t1 = (bmax - r.ray.origin) * r.invDir;
  vec3 tNear = slabMin(t0, t1);
  vec3 tFar = slabMax(t0, t1);
  float enter = slabMax(slabMax(tNear.x, tNear.y), slabMax(tNear.z, 0.0));
  float leave = slabMin(slabMin(tFar.x, tFar.y), slabMin(tFar.z, tMax)) * 1.0000003576;
  return enter <= leave ? enter : uintBitsToFloat(0x7F800000u);
}

// Whether `c` holds in any active lane of the subgroup. The whole ballot is compared: a subgroup may
// have up to 128 lanes (64 on some GPUs), not only the 32 of its first word.
bool anyLane(bool c) {
  return subgroupBallot(c) != uvec4(0u);
}

// "While-while" order (Aila & Laine, "Understanding the Efficiency of Ray Traversal on GPUs",
// HPG 2009): an invocation descends interior records until it holds a leaf, then tests the leaf's
// primitives. Each record holds both children's boxes (BvhWideNode), so a step tests the two, goes
// to the nearer child entered and stacks the other only when both are; a missed child costs no step.
//
// On lavapipe this beats walking the tree as a subgroup packet (one node read per 8 rays, shared by
// broadcast; Wald et al. 2001), which vkray did while nodes were storage-buffer reads
// (docs/performance.md, "Meshes").
void traverseBvh(TraceRay r, inout Hit hit, bool anyHit, bool fromEntryPoints) {
  // The builder caps the depth at kBvhStackSize; a walk from entry points starts with up to
  // kEntryStackSlots of them stacked.
  uint stack[kBvhStackSize + kEntryStackSlots];
  int sp = 0;
  uint ref = opaqueUniform(frame.counts2.w); // the root
  if (ENTRY_POINTS) {
    // Constant slots: plain vector stores, written whether or not this ray starts from them.
    stack[0] = gEntryStack.x;
    stack[1] = gEntryStack.y;
    stack[2] = gEntryStack.z;
    stack[3] = gEntryStack.w;
    stack[4] = gEntryStart.x;
    stack[5] = gEntryStart.y;
    if (fromEntryPoints) {
      ref = gEntryStart.z;
      sp = int(gEntryStart.w);
    }
  }
  if (ref == kBvhNoRef) return; // an empty tree, or a tile whose frustum meets nothing
  // Every loop here is tested at the bottom, with a `break` as its last statement: llvmpipe leaves
  // a loop only at its back edge, so a loop tested at the top runs one more whole turn, every lane
  // masked off, after its last lane is done (docs/performance.md, "Loops end at the bottom").
  //
  // The lanes of a subgroup walk in lockstep: a lane that holds a leaf (or has finished) stays in
  // the loops, its steps selected away, and a loop ends when a ballot says no lane has work left in
  // it. A lane that left a loop on its own would be masked off, and llvmpipe writes the stack under
  // the mask lane by lane, a branch per lane on whether that lane is active; with lanes leaving at
  // every step those branches mispredict, and each misprediction throws away the next step's
  // record loads already in flight. Kept in the loops, the mask stays the same for the whole walk
  // and the branches are predicted (1 M triangles: eye rays 25 % faster; docs/performance.md,
  // "Lanes in lockstep"). Each lane still leaves a loop only when it has no work of its own in it,
  // so its walk is complete whichever lanes a ballot sees (a GPU's subgroups differ); how far it
  // gets before setting a leaf aside (below) may differ, and so the order of its tests, which
  // leaves the closest distance the same.
  //
  // A lane that reaches its first leaf while others still descend would only wait for them, so it
  // sets the leaf aside (`postponed`) and goes on with the top of its stack: speculative
  // while-while (Aila & Laine 2009, section 4). The descent loop ends when every lane holds a leaf,
  // has one set aside, or is finished; the leaf loop then tests the leaf set aside and the one held
  // in one run. The closest hit is the same in any order (a box is culled only beyond the nearest
  // hit found so far). At 1 M triangles a batch of eight eye rays takes 10 % fewer turns of the
  // descent loop, 10 % fewer instructions in all (docs/performance.md, "Leaves set aside").
  uint postponed = kBvhNoRef;
  while (true) {
    if (anyLane(ref < kBvhLeafFlag)) {
      while (true) {
        bool descending = ref < kBvhLeafFlag; // else the step changes nothing of this lane's
        int base = int(4u * (descending ? ref : 0u));
        uvec4 a = imageLoad(nodeTexels, base);
        uvec4 b = imageLoad(nodeTexels, base + 1);
        uvec4 c = imageLoad(nodeTexels, base + 2);
        uvec4 d = imageLoad(nodeTexels, base + 3);
        float enter0 = boxEntry(r, uintBitsToFloat(a.xyz), uintBitsToFloat(b.xyz), hit.t);
        float enter1 = boxEntry(r, uintBitsToFloat(c.xyz), uintBitsToFloat(d.xyz), hit.t);
        uint ref0 = a.w;
        uint ref1 = b.w;
        bool in0 = !isinf(enter0);
        bool in1 = !isinf(enter1);
        // Branch-free step. The farther child is written to the free slot on top of the stack by
        // every lane, and kept (sp advanced) only where both children are entered. The builder caps
        // the depth at kBvhStackSize, so sp stays below it here.
        bool firstNearer = enter0 <= enter1;
        uint farther = firstNearer ? ref1 : ref0;
        stack[sp] = farther;
        uint popped = stack[max(sp - 1, 0)];
        bool neither = !in0 && !in1;
        uint nearer = (in0 && (firstNearer || !in1)) ? ref0 : ref1; // the nearer child entered
        uint next = neither ? (sp > 0 ? popped : kBvhNoRef) : nearer;
        int nextSp = sp + ((in0 && in1) ? 1 : ((neither && sp > 0) ? -1 : 0));
        // A first leaf is set aside where the stack holds more: the lane goes on with its top, the
        // farther child just stacked or the entry below it. (Popping takes nothing from the stack
        // a step has not already read, and pushes nothing, so the depth bound above still holds.)
        bool setAside = !neither && nearer >= kBvhLeafFlag && postponed == kBvhNoRef && nextSp > 0;
        postponed = (descending && setAside) ? nearer : postponed;
        next = setAside ? ((in0 && in1) ? farther : popped) : next;
        nextSp = setAside ? nextSp - 1 : nextSp;
        ref = descending ? next : ref;
        sp = descending ? nextSp : sp;
        // Done when every lane holds a leaf or one set aside, or is finished.
        if (!anyLane(ref < kBvhLeafFlag && postponed == kBvhNoRef)) break;
      }
    }
    // The leaf set aside, then the one held (a lane may hold an interior record instead, where the
    // loop ended while it was still looking for a second leaf: that one waits for the next turn).
    bool holdsLeaf = ref != kBvhNoRef && ref >= kBvhLeafFlag;
    uint leaf = postponed != kBvhNoRef ? postponed : (holdsLeaf ? ref : kBvhNoRef);
    uint nextLeaf = (postponed != kBvhNoRef && holdsLeaf) ? ref : kBvhNoRef;
    postponed = kBvhNoRef;
    if (leaf != kBvhNoRef) {
      uint entry;
      uint end;
      leafEntries(leaf, entry, end);
      while (true) {
        uint kind;
        uint index;
        leafPrimitive(entry, kind, index);
        testPrimitive(r, kind, index, hit);
        if (anyHit && hit.kind != kNoHit) break;
        ++entry;
        if (entry >= end) {
          if (nextLeaf == kBvhNoRef) break;
          leafEntries(nextLeaf, entry, end);
          nextLeaf = kBvhNoRef;
        }
      }
    }
    if (anyHit && hit.kind != kNoHit) {
      sp = 0; // found an occluder: this lane is done
      ref = kBvhNoRef;
    } else if (holdsLeaf) {
      ref = sp > 0 ? stack[--sp] : kBvhNoRef;
    }
    if (!anyLane(ref != kBvhNoRef)) break; // every lane is done
  }
}

// Closest hit in (0, tMax). anyHit: stop at the first hit (callers then read only `kind`); a loop
// whose count is baked in is unrolled, and stopping it early would only mask the remaining tests
// on CPU drivers (3 % of the showcase's instructions), so it runs to the end. shadowRay: skip the
// planes the host proved cannot stand between a surface and a light (host/scene/features.cpp).
// eyeRay: a ray from the eye through this invocation's pixel, which may start from the tile's entry
// points (loadEntryPoints).
Hit traceScene(TraceRay r, float tMax, bool anyHit, bool shadowRay, bool eyeRay) {
  Hit hit = Hit(tMax, kNoHit, 0u, vec3(0.0));
  uint planes = HAS_PLANES ? (shadowRay ? occluderPlaneCount() : planeCount()) : 0u;
  if (planes > 0u) {
    uint i = 0u;
    while (true) {
      float t = planeT(r, i, hit.t);
      if (t > 0.0) {
        hit = Hit(t, kPrimPlane, i, vec3(0.0));
        // (Before a BVH walk the return pays: the walk is a loop that a finished lane leaves.)
        if (anyHit && (USE_BVH || (shadowRay ? OCCLUDER_PLANE_COUNT : PLANE_COUNT) == kRuntimeCount)) return hit;
      }
      if (++i >= planes) break;
    }
  }
  if (USE_BVH) {
    traverseBvh(r, hit, anyHit, ENTRY_POINTS && eyeRay);
  } else {
    uint spheres = HAS_SPHERES ? sphereCount() : 0u;
    if (spheres > 0u) {
      uint i = 0u;
      while (true) {
        testPrimitive(r, kPrimSphere, i, hit);
        if (anyHit && SPHERE_COUNT == kRuntimeCount && hit.kind != kNoHit) return hit;
        if (++i >= spheres) break;
      }
    }
    uint triangles = HAS_TRIANGLES ? triangleCount() : 0u;
    if (triangles > 0u) {
      uint i = 0u;
      while (true) {
        testPrimitive(r, kPrimTriangle, i, hit);
        if (anyHit && TRIANGLE_COUNT == kRuntimeCount && hit.kind != kNoHit) return hit;
        if (++i >= triangles) break;
      }
    }
    uint polygons = HAS_POLYGONS ? polygonCount() : 0u;
    if (polygons > 0u) {
      uint i = 0u;
      while (true) {
        testPrimitive(r, kPrimPolygon, i, hit);
        if (anyHit && POLYGON_COUNT == kRuntimeCount && hit.kind != kNoHit) return hit;
        if (++i >= polygons) break;
      }
    }
  }
  return hit;
}

// Builds the surface record of the closest hit (called once per ray, not per candidate).
Surface surfaceAt(TraceRay r, Hit hit) {
  Surface s;
  s.kind = hit.kind;
  if (hit.kind == kPrimSphere) {
    Sphere sph = loadSphere(hit.index);
#ifdef VKRAY_FLOAT64
    sphereSurface64(r.ray, hit.t, sph.centerRadius.xyz, sph.centerRadius.w, s.p, s.ng, s.errorBound);
#else
    sphereSurface(r.ray, hit.t, sph.centerRadius.xyz, sph.centerRadius.w, s.p, s.ng, s.errorBound);
#endif
    s.ns = s.ng;
    s.material = sph.meta.x;
  } else if (hit.kind == kPrimTriangle) {
    Triangle tri = loadTriangle(hit.index);
#ifdef VKRAY_FLOAT64
    if (true) {
      triangleSurface64(hit.bary, tri.v0.xyz, tri.v1.xyz, tri.v2.xyz, s.p, s.ng, s.errorBound);
#else
    if (ROBUST) {
      triangleSurface(hit.bary, tri.v0.xyz, tri.v1.xyz, tri.v2.xyz, s.p, s.ng, s.errorBound);
#endif
    } else {
      vec3 unused;
      triangleSurface(hit.bary, tri.v0.xyz, tri.v1.xyz, tri.v2.xyz, unused, s.ng, s.errorBound);
      s.p = r.ray.origin + hit.t * r.ray.dir;
    }
    s.ns = s.ng;
    uint normalBase = floatBitsToUint(tri.v1.w);
    if (SMOOTH_NORMALS && normalBase != kNoNormals) {
      vec3 n = hit.bary.x * loadShadingNormal(normalBase) + hit.bary.y * loadShadingNormal(normalBase + 1u) +
               hit.bary.z * loadShadingNormal(normalBase + 2u);
      float len = length(n);
      if (len > 0.0) s.ns = n / len; // zero-length interpolated normal: keep the geometric one
    }
    s.material = floatBitsToUint(tri.v0.w);
  } else if (hit.kind == kPrimPolygon) {
    Polygon poly = loadPolygon(hit.index);
    polygonSurface(r.ray, hit.t, loadPolyVertex(poly.meta.x), s.p, s.errorBound);
    s.ng = poly.plane.xyz;
    s.ns = s.ng;
    s.material = poly.meta.z;
  } else {
    Plane pl = loadPlane(hit.index);
    planeSurface(r.ray, hit.t, pl.normalOffset.xyz, pl.normalOffset.w, s.p, s.errorBound);
    s.ng = pl.normalOffset.xyz;
    s.ns = s.ng;
    s.material = pl.meta.x;
  }
  return s;
}

#endif
