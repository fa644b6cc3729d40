// The one description of everything the host and the shaders exchange: buffer structs (std430),
// binding numbers, specialization-constant ids, push constants and the workgroup size. Compiled as
// C++ (glm types, static_asserts in host/render/gpu_layout.cpp) and as GLSL (#include).
//
// Layout rule: every struct is made of vec4/uvec4 (or a vec3 followed by a 4-byte scalar), so std430
// and the C++ layout agree without hidden padding.
#ifndef VKRAY_GPU_TYPES_H
#define VKRAY_GPU_TYPES_H

#ifdef __cplusplus
#include <bit>
#include <cstdint>
#include <glm/glm.hpp>
namespace vkray::gpu {
using vec3 = glm::vec3;
using vec4 = glm::vec4;
using uvec2 = glm::uvec2;
using uvec4 = glm::uvec4;
using uint = std::uint32_t;
#define VKRAY_CONST(type, name, value) inline constexpr type name = value
#else
#define VKRAY_CONST(type, name, value) const type name = value
#endif

// ---- Dispatch ------------------------------------------------------------------------------------
VKRAY_CONST(uint, kWorkgroupSizeX, 8u);
VKRAY_CONST(uint, kWorkgroupSizeY, 8u);

// ---- Descriptor bindings (set 0) -----------------------------------------------------------------
VKRAY_CONST(uint, kBindingFrame, 0u);        // uniform FrameParams
VKRAY_CONST(uint, kBindingMaterials, 1u);    // Material[]
VKRAY_CONST(uint, kBindingLights, 2u);       // Light[]
VKRAY_CONST(uint, kBindingSpheres, 3u);      // Sphere[]
VKRAY_CONST(uint, kBindingPlanes, 4u);       // Plane[]
VKRAY_CONST(uint, kBindingTriangles, 5u);    // texels: Triangle[] (3 RGBA32UI each)
VKRAY_CONST(uint, kBindingPolygons, 6u);     // Polygon[]
VKRAY_CONST(uint, kBindingPolyVertices, 7u); // vec4[] polygon vertices (xyz)
VKRAY_CONST(uint, kBindingNormals, 8u);      // texels: shading normals, 3 per smooth triangle
VKRAY_CONST(uint, kBindingBvhNodes, 9u);     // texels: BvhWideNode[] (kBvhRecordTexels RGBA32UI each)
VKRAY_CONST(uint, kBindingPrimRefs, 10u);    // texels (R32UI): leaf references, kind << 30 | index
VKRAY_CONST(uint, kBindingImage, 11u);       // texels (RGBA32F): sum of linear RGB, samples; row-major
VKRAY_CONST(uint, kBindingStats, 12u);       // RayStats
VKRAY_CONST(uint, kBindingPrevImage, 13u);   // texels (RGBA32F): the base image the refine pass reads
// The same small arrays packed into one uniform buffer (kSpecSceneInUbo), see SceneUbo below.
VKRAY_CONST(uint, kBindingSceneUbo, 14u);
VKRAY_CONST(uint, kBindingEntryPoints, 15u); // uvec4[]: each 8 x 8 tile's BVH entry points (below)
// The same buffer as texels (RGBA32UI), as the trace kernels read it: on lavapipe an SSBO read
// assembles each lane's value through memory, a texel read is one gather.
VKRAY_CONST(uint, kBindingEntryTexels, 16u);
// Textures (kSpecTextures), all texel buffers: a scene's images in one buffer, sampled by hand
// (shaders/lib/texture.glsl), so no image descriptors and one layout for every pipeline.
VKRAY_CONST(uint, kBindingTexCoords, 17u);   // texels (RGBA32F): 4 per textured triangle (below)
VKRAY_CONST(uint, kBindingTextureInfo, 18u); // texels (RGBA32UI): texture references, then levels
VKRAY_CONST(uint, kBindingTexels, 19u);      // texels (RGBA32F): every level of every texture, linear RGBA
// uint[]: rays traced per pixel (eye, shadow, reflection, refraction), summed over its samples like
// Image[]: written by the sample pass only where kSpecPixelRays is on (the viewer's cost map).
VKRAY_CONST(uint, kBindingPixelRays, 20u);
// TreeRayBuffer: the rays one pixel's samples traced, recorded by the trace kernel where
// kSpecRecordTree is on (`render --inspect`, the viewer's ray-tree overlay).
VKRAY_CONST(uint, kBindingRayTree, 21u);
// uint[]: forward tracing's image (shaders/forward.comp): kPhotonHeaderWords of counters (photons
// struck, lo/hi; rays traced, lo/hi; non-finite contributions), then per pixel and channel a 64-bit
// fixed-point sum (lo, hi) of the contributions times 2^kPhotonFixedBits.
VKRAY_CONST(uint, kBindingPhotonImage, 22u);
// vec4[]: the image window's buffer again (kBindingImage), as a storage buffer for the kernels'
// writes. On lavapipe a storage texel buffer's imageStore is a helper function of ~60 instructions a
// lane (a per-lane, per-component scatter with format conversion), a storage buffer's vec4 store
// ~30, inline; imageLoad, inline either way, stays the faster read.
VKRAY_CONST(uint, kBindingImageOut, 23u);
VKRAY_CONST(uint, kBindingCount, 24u);
VKRAY_CONST(uint, kPhotonHeaderWords, 8u);
VKRAY_CONST(uint, kPhotonFixedBits, 24u);

// Capacities of the uniform copy, 64 KiB in all (the smallest maxUniformBufferRange of the devices
// vkray targets). On CPU drivers a UBO read is one vector gather, an SSBO read a per-lane scalar
// loop, so small scenes are read from here. One block rather than one per array: Mesa 22.3's
// lavapipe corrupts memory when it inlines values from a uniform buffer bound at slot 4 or above.
VKRAY_CONST(uint, kUboMaterials, 128u);    // 10 KiB
VKRAY_CONST(uint, kUboLights, 64u);        // 2 KiB
VKRAY_CONST(uint, kUboSpheres, 512u);      // 16 KiB
VKRAY_CONST(uint, kUboPlanes, 64u);        // 2 KiB
VKRAY_CONST(uint, kUboTriangles, 512u);    // 24 KiB
VKRAY_CONST(uint, kUboPolygons, 128u);     // 4 KiB
VKRAY_CONST(uint, kUboPolyVertices, 384u); // 6 KiB

// ---- Specialization constants (ids) --------------------------------------------------------------
// Each switches code on or off at pipeline creation, so the driver compiles out absent effects.
VKRAY_CONST(uint, kSpecHasSpheres, 0u);
VKRAY_CONST(uint, kSpecHasPlanes, 1u);
VKRAY_CONST(uint, kSpecHasTriangles, 2u);
VKRAY_CONST(uint, kSpecHasPolygons, 3u);
VKRAY_CONST(uint, kSpecUseBvh, 4u);
VKRAY_CONST(uint, kSpecShadows, 5u);
VKRAY_CONST(uint, kSpecReflection, 6u);
VKRAY_CONST(uint, kSpecRefraction, 7u);
VKRAY_CONST(uint, kSpecStackSize, 8u); // pending branches of the Whitted tree (>= 1)
VKRAY_CONST(uint, kSpecCountStats, 9u);
VKRAY_CONST(uint, kSpecNumerics, 10u);      // kNumericsRobust / kNumericsNaive
VKRAY_CONST(uint, kSpecFresnel, 11u);       // kFresnelExact / kFresnelSchlick
VKRAY_CONST(uint, kSpecShadowMode, 12u);    // kShadowsOpaque / kShadowsAttenuated
VKRAY_CONST(uint, kSpecChecker, 13u);       // any material has a checker
VKRAY_CONST(uint, kSpecSmoothNormals, 14u); // any triangle has shading normals
VKRAY_CONST(uint, kSpecSceneInUbo, 15u);    // read the small arrays from the *Ubo bindings
VKRAY_CONST(uint, kSpecCenterSample, 16u);  // one sample through each pixel centre (no sequence)
// Counts of the brute-force arrays and of the lights. A small count baked in lets the driver unroll
// the loop, so every scene read has a constant address (a scalar load on lavapipe, where a
// loop-indexed read is an 8-lane gather). kRuntimeCount: read the count from FrameParams instead.
VKRAY_CONST(uint, kSpecSphereCount, 17u);
VKRAY_CONST(uint, kSpecPlaneCount, 18u);
VKRAY_CONST(uint, kSpecTriangleCount, 19u);
VKRAY_CONST(uint, kSpecPolygonCount, 20u);
VKRAY_CONST(uint, kSpecLightCount, 21u);
VKRAY_CONST(uint, kSpecOccluderPlaneCount, 22u); // planes that can cast a shadow (listed first)
// The adaptive refine pass's pipeline (kPassRefine): on CPU drivers a branch on the pass at run
// time would run the other pass's whole body too, masked off (it doubled the trace).
VKRAY_CONST(uint, kSpecRefinePass, 23u);
// Materials, lights and planes read from the uniform block even when the primitives are not.
VKRAY_CONST(uint, kSpecShadingInUbo, 24u);
// Materials up to kMaxUnrolledCount are read into registers (scene_access.glsl, loadSceneRegisters).
VKRAY_CONST(uint, kSpecMaterialCount, 25u);
// Eye rays start their BVH walk at their tile's entry points (shaders/entry.comp) instead of the root.
VKRAY_CONST(uint, kSpecEntryPoints, 26u);
// Some material has a base-colour texture (and some triangle texture coordinates).
VKRAY_CONST(uint, kSpecTextures, 27u);
VKRAY_CONST(uint, kSpecTextureFilter, 28u); // kTextureNearest / kTextureBilinear / kTextureCone
// Some triangle's material is glTF alphaMode MASK: the triangle test skips cut-out hits.
VKRAY_CONST(uint, kSpecAlphaMask, 29u);
// Some triangle has vertex colours (glTF COLOR_0).
VKRAY_CONST(uint, kSpecVertexColors, 30u);
// The progressive renderer's pass (kPassList, host/render/adaptive.h): each invocation traces the
// pixel of one entry of a list of open pixels and writes its sums, whole and of the pass's first half.
VKRAY_CONST(uint, kSpecListPass, 31u);
// The sample pass adds each pixel's rays to PixelRays[] (kBindingPixelRays): the viewer's cost map.
// Off in every headless pipeline, where the count and its store compile out.
VKRAY_CONST(uint, kSpecPixelRays, 32u);
// The camera has a thin lens (camera.aperture > 0): each sample's eye ray starts at a point of the
// lens disk and passes through the plane in focus (depth of field). Off: the pinhole, and no lens
// code at all, so a scene without an aperture renders bit for bit as before the lens existed.
VKRAY_CONST(uint, kSpecThinLens, 33u);
// The sample pass records every ray it traces into TreeRayBuffer (kBindingRayTree): the ray-tree
// inspector, run on one pixel. Off in every other pipeline, where the recorder compiles out to
// nothing (tests/ray_tree_test.cpp compares the folded SPIR-V with a build without it).
VKRAY_CONST(uint, kSpecRecordTree, 34u);
// Shadow rays from a triangle start their BVH walk at the (triangle, light)'s shadow entry points
// (host/accel/shadow_entries.h) instead of the root.
VKRAY_CONST(uint, kSpecShadowEntries, 35u);
// Descent steps of the BVH walk between two votes of its subgroup (1 or 2; shaders/lib/bvh.glsl,
// traverseBvh). Two where the tree is at least kBvhTwoStepDepth deep: a vote costs about a tenth of
// a step on lavapipe, and in a deep tree a lane rarely finishes its descent after the first of two.
VKRAY_CONST(uint, kSpecBvhStepsPerVote, 36u);
// Some material has a Phong highlight and no diffuse term (glass, a polished metal): a light there is
// sampled only where its highlight can show (kNegligibleHighlight, shade.glsl). Off, the test and the
// highlight computed ahead of it compile out.
VKRAY_CONST(uint, kSpecSpecularOnly, 37u);
VKRAY_CONST(uint, kSpecCount, 38u);
VKRAY_CONST(int, kBvhTwoStepDepth, 16);
VKRAY_CONST(uint, kRuntimeCount, 0xFFFFFFFFu);
VKRAY_CONST(uint, kMaxUnrolledCount, 16u); // arrays up to this size get their count baked in

VKRAY_CONST(uint, kNumericsRobust, 0u);
VKRAY_CONST(uint, kNumericsNaive, 1u);
VKRAY_CONST(uint, kFresnelExact, 0u);
VKRAY_CONST(uint, kFresnelSchlick, 1u);
VKRAY_CONST(uint, kShadowsOpaque, 0u);
VKRAY_CONST(uint, kShadowsAttenuated, 1u);
VKRAY_CONST(uint, kTextureNearest, 0u);  // level 0, nearest texel
VKRAY_CONST(uint, kTextureBilinear, 1u); // level 0, bilinear
VKRAY_CONST(uint, kTextureCone, 2u);     // trilinear between the levels a ray cone picks

// Textures: the records TextureRef and TextureLevel in TextureInfo[], and a textured triangle's uv
// record in TexCoords[] (structs below).
VKRAY_CONST(uint, kTextureRefTexels, 3u); // TextureInfo texels per TextureRef
// A uv record: kUvRecordTexels RGBA32F texels, the corners' texture coordinates and the record's
// UvInfo, then, where UvInfo says so, kUvRecordColorTexels with the corners' vertex colours.
VKRAY_CONST(uint, kUvRecordCorners, 0u);     // texels 0..2: corner k's uvs, xy set 0, zw set 1
VKRAY_CONST(uint, kUvRecordInfo, 3u);        // texel 3: UvInfo
VKRAY_CONST(uint, kUvRecordTexels, 4u);      // without vertex colours
VKRAY_CONST(uint, kUvRecordColors, 4u);      // texels 4..6: corner k's colour (linear RGBA; glTF COLOR_0)
VKRAY_CONST(uint, kUvRecordColorTexels, 3u); // the vertex colours after them
VKRAY_CONST(uint, kWrapRepeat, 0u);
VKRAY_CONST(uint, kWrapClamp, 1u);
VKRAY_CONST(uint, kWrapMirror, 2u);
// TextureRef's sampler word: wrap s in bits 0-1 and wrap t in bits 2-3 (kWrap*), then flags.
VKRAY_CONST(uint, kSamplerWrapMask, 3u);
VKRAY_CONST(uint, kSamplerWrapTShift, 2u);
VKRAY_CONST(uint, kSamplerMagNearest, 16u);    // bit 4: a magnified sample reads the nearest texel
VKRAY_CONST(uint, kSamplerMinLevelsShift, 5u); // bits 5-6: the levels a minified sample reads (kMinLevels*)
VKRAY_CONST(uint, kSamplerMinNearest, 128u);   // bit 7: a minified sample reads nearest texels
VKRAY_CONST(uint, kMinLevelsBlend, 0u);        // the two levels around the lod, blended
VKRAY_CONST(uint, kMinLevelsNearest, 1u);      // the level nearest the lod
VKRAY_CONST(uint, kMinLevelsBase, 2u);         // level 0 alone

// ---- Limits shared by host validation and shader arrays ------------------------------------------
VKRAY_CONST(uint, kMaxStackSize, 16u); // deepest explicit stack compiled into a pipeline
VKRAY_CONST(uint, kMaxMediaDepth, 4u); // nested transmissive media tracked per ray
// Rays one sample's Whitted tree may trace (eye ray, reflections, refractions; shadow rays apart).
// Only glass trees grow past max_depth + 1; the one of a 16-deep reference with bailout 1e-6 stays
// under it, a bailout-0 tree at depth 16 (2^17 rays) does not and is counted as truncated.
VKRAY_CONST(uint, kMaxTreeRays, 8192u);
VKRAY_CONST(uint, kNoMedium, 0xFFFFu);      // empty slot in the packed media stack
VKRAY_CONST(uint, kMaxMaterials, 65535u);   // material ids are packed in 16 bits
VKRAY_CONST(uint, kNoNormals, 0xFFFFFFFFu); // Triangle.v1.w: flat triangle
VKRAY_CONST(float, kNaiveEpsilon, 1e-4);    // the textbook fixed t-epsilon of naive numerics
// A light that can only add a Phong highlight (the surface has no diffuse term) is not sampled,
// shadow ray and all, where the highlight would add less than this to the pixel in every channel
// (linear RGB, the branch's weight included): glass and other specular-only finishes
// (shaders/lib/shade.glsl, localShade; docs/performance.md, "Highlights too faint to see").
VKRAY_CONST(float, kNegligibleHighlight, 1e-7);

// BVH leaf references pack the primitive kind into the top two bits.
VKRAY_CONST(uint, kPrimSphere, 0u);
VKRAY_CONST(uint, kPrimTriangle, 1u);
VKRAY_CONST(uint, kPrimPolygon, 2u);
VKRAY_CONST(uint, kPrimKindShift, 30u);
VKRAY_CONST(uint, kPrimIndexMask, 0x3FFFFFFFu);
// BvhWideNode references (see there).
VKRAY_CONST(uint, kBvhLeafFlag, 0x80000000u);
VKRAY_CONST(uint, kBvhLeafCountShift, 27u); // 4 bits: leaves of 1 to 16 entries
VKRAY_CONST(uint, kBvhLeafFirstMask, 0x07FFFFFFu);
VKRAY_CONST(uint, kBvhNoRef, 0xFFFFFFFFu); // an empty tree's root
VKRAY_CONST(uint, kPrimPlane, 3u);         // never in the BVH; used to tag hits
// A record's texels in kBindingBvhNodes (host/accel/bvh_records.h): both boxes, the references in
// the low bytes of eight of their coordinates.
VKRAY_CONST(uint, kBvhRecordTexels, 3u);
VKRAY_CONST(uint, kBvhStackSize, 32u); // the builder caps tree depth at this (host/accel/bvh.h)
// Shadow entry points (host/accel/shadow_entries.h): two texels per (triangle, light) after the
// BVH records, (start, stack 0, 1, 2) and (stack 3, 4, 5, stack height), the stack bottom first,
// kBvhNoRef where unused. kEntryStackSlots bounds the stacked ones.
VKRAY_CONST(uint, kShadowEntryMax, 7u);
// A (triangle, light) whose shadow rays nothing in the BVH can stop: start kBvhNoRef and this as
// the stack height (host/accel/shadow_entries.h, "nothing between"); the walk is skipped.
VKRAY_CONST(uint, kShadowNothingBetween, 0xFFFFFFFFu);
VKRAY_CONST(uint, kShadowEntryLightsMax, 4u); // lights a scene may have for shadow entry points

// Entry points (shaders/entry.comp): for each tile of kEntryTileSize x kEntryTileSize pixels (one
// workgroup of the trace kernels), the BVH subtrees its eye rays' frustum reaches, at most
// kEntryPointsMax, nearest first. One TileEntryPoints per tile (below), tiles row-major from the
// band's first row (PushConstants.imageRow0): the walk's stack, the entry point to start at and the
// stack's height. An eye ray loads them as its walk's starting state.
VKRAY_CONST(uint, kEntryTileSize, 8u);
VKRAY_CONST(uint, kEntryStackSlots, 6u);
VKRAY_CONST(uint, kEntryPointsMax, 7u); // kEntryStackSlots + 1

// ---- Render passes (kSpecRefinePass; the push constant `pass` says the same) and flags ----------
// The image holds, per pixel, vec4(sum of sample radiances, sample count); the host divides.
VKRAY_CONST(uint, kPassSample, 0u);       // sampleCount samples per pixel (sampleBase, sampleBase + 1, ...)
VKRAY_CONST(uint, kPassRefine, 1u);       // adaptive AA: resample pixels whose neighbours differ
VKRAY_CONST(uint, kPassList, 2u);         // progressive: sampleCount samples of each listed pixel
VKRAY_CONST(uint, kFlagCenterSample, 1u); // the single sample goes through the pixel centre
VKRAY_CONST(uint, kFlagAccumulate, 2u);   // add to the sums already in the image
// The list pass: the first halves of the passes whose bit (kFlagNoHalf0 << pass) is set are empty (a
// pass of one sample) and their texels are neither read nor written; the host takes them as zero. A
// list pass's last pass always writes its half (it carries the rays traced).
VKRAY_CONST(uint, kFlagNoHalf0, 4u);

// ---- Buffer structs ------------------------------------------------------------------------------
struct Material {
  vec4 color;        // rgb: base colour (linear); a: ambient coefficient
  vec4 color2;       // rgb: checker's second colour; a: checker square size (0: no checker)
  vec4 phong;        // x: diffuse, y: specular, z: shininess (Phong exponent), w: reflection 0..1
  vec4 transmission; // x: transmission 0..1, y: index of refraction, z: texture reference + 1 (bits;
                     // 0: none), w: alpha cutoff (alphaMode MASK; 0: not masked)
  vec4 absorption;   // rgb: Beer-Lambert absorption per unit length; a: base colour alpha (MASK)
};

struct Light {
  vec4 position; // xyz: position (camera-relative); w: 1 if it casts shadows, else 0
  vec4 color;    // rgb: intensity (linear); a: unused
};

struct Sphere {
  vec4 centerRadius; // xyz: centre (camera-relative), rounded to float; w: radius
  uvec4 meta;        // x: material; yzw: the centre's low part (float bits): centre - xyz, from double
};

struct Plane {
  vec4 normalOffset; // xyz: unit normal n; w: D in n.x + D = 0 (camera-relative)
  uvec4 meta;        // x: material; yzw: unused
};

struct Triangle {
  vec4 v0; // xyz: vertex 0; w: material id (uintBitsToFloat)
  vec4 v1; // xyz: vertex 1; w: first of 3 shading normals in Normals[] or kNoNormals (bits)
  vec4 v2; // xyz: vertex 2; w: first uv record texel in TexCoords[] + 1 (bits; 0: none)
};

struct Polygon {
  vec4 plane; // xyz: unit normal; w: D (n.x + D = 0)
  uvec4 meta; // x: first vertex in PolyVertices[]; y: vertex count; z: material; w: bound radius (float bits)
};

// A textured material's texture (Material.transmission.z): kTextureRefTexels RGBA32UI texels of
// TextureInfo[], floats as their bits. The uv transform is uv' = T R S uv written as rows (a b e;
// c d f), as host/scene/texture.h's TextureTransform::apply.
struct TextureRef {
  uvec4 levels; // x: first TextureLevel in TextureInfo[]; y: level count; z: sampler word (kSampler*); w: uv set
  uvec4 row0;   // xyz: the transform's row 0 (a b e); w: lod offset, 0.5 log2(width * height * |det(transform)|)
                // of level 0 (log2 texels per unit of uv)
  uvec4 row1;   // xyz: the transform's row 1 (c d f); w: unused
};

// One mip level of a texture: an RGBA32UI texel of TextureInfo[], after every TextureRef.
struct TextureLevel {
  uvec4 extent; // x: first texel in Texels[] (row-major, linear RGBA); y: width, z: height (texels); w: unused
};

// Texel kUvRecordInfo of a triangle's uv record (RGBA32F, TexCoords[]).
struct UvInfo {
  vec4 lodAndFlags; // x, y: uv set 0's, set 1's lod bias, 0.5 log2(uv area / world area) (log2 uv units per
                    // world unit; the triangle's part of the ray-cone lod, RTG eq. 20.4); z: 1 when vertex
                    // colours follow, else 0; w: 1 when the corners hold texture coordinates, else 0
};

// Flattened BVH node (pbrt's LinearBVHNode layout), the host's form of the tree: depth first, the
// first child follows its parent, so an interior node stores only the index of its second child.
// The shader reads the BvhWideNode records made from it (host/accel/bvh.h, wideBvh).
struct BvhNode {
  vec3 boundsMin;
  uint offset; // leaf: first PrimRef; interior: index of the second child
  vec3 boundsMax;
  uint countAxis; // bits 0..15: primitive count (0: interior); bits 16..17: split axis
};

// The BVH as the shader walks it: one record per interior node of the tree above, holding both
// children's boxes and references (Aila & Laine, "Understanding the Efficiency of Ray Traversal on
// GPUs", HPG 2009), so a step tests two boxes, goes to the nearer child entered and stacks the other
// only when both are. A reference is an interior record's index, or kBvhLeafFlag | (count - 1) <<
// kBvhLeafCountShift | first leaf entry. The host's form: the kernels read it packed into
// kBvhRecordTexels texels (host/accel/bvh_records.h) and decode it into this struct (loadBvhNode).
struct BvhWideNode {
  vec3 min0;
  uint ref0;
  vec3 max0;
  uint ref1;
  vec3 min1;
  uint unused0;
  vec3 max1;
  uint unused1;
};

// A tile's entry points (see kEntryTileSize): two uvec4 of EntryPoints[], written by entry.comp
// and read as texels by the trace kernels.
struct TileEntryPoints {
  uvec4 stack;    // the walk's stack words 0..3, bottom first (the farthest entry point at the bottom)
  uvec4 stackTop; // xy: stack words 4, 5; z: the entry point to start at (kBvhNoRef: the frustum meets nothing);
                  // w: the stack's height (words in use)
};

// A shadow ray's entry points (kShadowEntryMax): the two texels of its (triangle, light).
struct ShadowStart {
  uvec4 a; // x: the subtree to start at (kBvhNoRef: the root); yzw: stack words 0, 1, 2
  uvec4 b; // xyz: stack words 3, 4, 5; w: the stack's height (kShadowNothingBetween: no walk)
};

#ifndef __cplusplus
// clang-format off
// Named reads of the records above, so kernels say what they read, not which vec4 slot holds it.
vec3 baseColor(Material m) { return m.color.rgb; }
float ambientFactor(Material m) { return m.color.a; }
vec3 checkerColor(Material m) { return m.color2.rgb; }
float checkerSize(Material m) { return m.color2.a; } // 0: no checker
float diffuseFactor(Material m) { return m.phong.x; }
float specularFactor(Material m) { return m.phong.y; }
float phongExponent(Material m) { return m.phong.z; }
float reflectance(Material m) { return m.phong.w; }
float transmittance(Material m) { return m.transmission.x; }
float refractiveIndex(Material m) { return m.transmission.y; }
uint textureRefPlusOne(Material m) { return floatBitsToUint(m.transmission.z); } // 0: untextured
float alphaCutoff(Material m) { return m.transmission.w; } // 0: not masked
float baseAlpha(Material m) { return m.absorption.a; }
vec3 absorptionPerUnit(Material m) { return m.absorption.rgb; }

vec3 lightPosition(Light l) { return l.position.xyz; }
bool castsShadows(Light l) { return l.position.w > 0.0; }
vec3 lightColor(Light l) { return l.color.rgb; }

vec3 sphereCenter(Sphere s) { return s.centerRadius.xyz; }
// centre = sphereCenter + sphereCenterLow to ~2^-48 relative: a ground of radius 1e6 sits where the
// scene put it, not half an ulp of 1e6 (0.03) above or below (docs/numerics.md).
vec3 sphereCenterLow(Sphere s) { return uintBitsToFloat(s.meta.yzw); }
float sphereRadius(Sphere s) { return s.centerRadius.w; }
uint sphereMaterial(Sphere s) { return s.meta.x; }

vec3 planeNormal(Plane p) { return p.normalOffset.xyz; }
float planeOffset(Plane p) { return p.normalOffset.w; }
uint planeMaterial(Plane p) { return p.meta.x; }

uint triangleMaterial(Triangle t) { return floatBitsToUint(t.v0.w); }
uint triangleNormalBase(Triangle t) { return floatBitsToUint(t.v1.w); } // kNoNormals: flat
uint triangleUvBasePlusOne(Triangle t) { return floatBitsToUint(t.v2.w); } // 0: no texture coordinates

vec3 polygonNormal(Polygon q) { return q.plane.xyz; }
uint polygonFirstVertex(Polygon q) { return q.meta.x; }
uint polygonVertexCount(Polygon q) { return q.meta.y; }
uint polygonMaterial(Polygon q) { return q.meta.z; }
// Every vertex lies within this distance of the first one (a bounding sphere about it, rounded up).
float polygonBoundRadius(Polygon q) { return uintBitsToFloat(q.meta.w); }

uint textureFirstLevel(TextureRef t) { return t.levels.x; } // index of a TextureLevel in TextureInfo[]
uint textureLevelCount(TextureRef t) { return t.levels.y; }
uint wrapModeS(TextureRef t) { return t.levels.z & kSamplerWrapMask; } // kWrap*
uint wrapModeT(TextureRef t) { return (t.levels.z >> kSamplerWrapTShift) & kSamplerWrapMask; } // kWrap*
bool magnifiesNearest(TextureRef t) { return (t.levels.z & kSamplerMagNearest) != 0u; }
uint minifiedLevels(TextureRef t) { return (t.levels.z >> kSamplerMinLevelsShift) & 3u; } // kMinLevels*
bool minifiesNearest(TextureRef t) { return (t.levels.z & kSamplerMinNearest) != 0u; }
bool readsUvSet1(TextureRef t) { return t.levels.w != 0u; } // else uv set 0
vec3 uvTransformRow0(TextureRef t) { return uintBitsToFloat(t.row0.xyz); }
vec3 uvTransformRow1(TextureRef t) { return uintBitsToFloat(t.row1.xyz); }
float textureLodOffset(TextureRef t) { return uintBitsToFloat(t.row0.w); } // log2 texels per uv unit

uint levelFirstTexel(TextureLevel l) { return l.extent.x; } // in Texels[]
uint levelWidth(TextureLevel l) { return l.extent.y; } // texels
uint levelHeight(TextureLevel l) { return l.extent.z; } // texels

vec2 triangleLodBias(UvInfo i) { return i.lodAndFlags.xy; } // x: uv set 0, y: set 1; log2 uv units per world unit
bool hasVertexColors(UvInfo i) { return i.lodAndFlags.z != 0.0; } // kUvRecordColorTexels follow
bool hasTexCoords(UvInfo i) { return i.lodAndFlags.w != 0.0; } // else the corners' uvs are zero

// Word k < kEntryStackSlots of the walk's stack, bottom first.
uint entryStackWord(TileEntryPoints e, uint k) { return k < 4u ? e.stack[k] : e.stackTop[k - 4u]; }
uint entryStart(TileEntryPoints e) { return e.stackTop.z; } // kBvhNoRef: the tile's frustum meets nothing
uint entryStackHeight(TileEntryPoints e) { return e.stackTop.w; }

// A pixel of Image[] and PrevImage[]: vec4(sum of its samples' linear RGB radiance, sample count).
vec3 pixelRadianceSum(vec4 p) { return p.rgb; }
float pixelSampleCount(vec4 p) { return p.w; }
// clang-format on
#endif

#ifdef __cplusplus
// The host's reads and writes of the words it moves or checks after packing, named as in the shaders.
// clang-format off
inline uint triangleMaterial(const Triangle& t) { return std::bit_cast<uint>(t.v0.w); }
inline uint triangleNormalBase(const Triangle& t) { return std::bit_cast<uint>(t.v1.w); } // kNoNormals: flat
inline uint triangleUvBasePlusOne(const Triangle& t) { return std::bit_cast<uint>(t.v2.w); } // 0: none
inline void setTriangleMaterial(Triangle& t, uint material) { t.v0.w = std::bit_cast<float>(material); }
inline void setTriangleNormalBase(Triangle& t, uint first) { t.v1.w = std::bit_cast<float>(first); }
inline void setTriangleUvBasePlusOne(Triangle& t, uint firstPlusOne) { t.v2.w = std::bit_cast<float>(firstPlusOne); }
inline uint polygonFirstVertex(const Polygon& q) { return q.meta.x; }
inline uint polygonVertexCount(const Polygon& q) { return q.meta.y; }
inline float polygonBoundRadius(const Polygon& q) { return std::bit_cast<float>(q.meta.w); }
inline void setPolygonBoundRadius(Polygon& q, float r) { q.meta.w = std::bit_cast<uint>(r); }
inline bool hasVertexColors(const UvInfo& i) { return i.lodAndFlags.z != 0.0f; }
// clang-format on
#endif

struct SceneUbo {
  Material materials[kUboMaterials];
  Light lights[kUboLights];
  Sphere spheres[kUboSpheres];
  Plane planes[kUboPlanes];
  Triangle triangles[kUboTriangles];
  Polygon polygons[kUboPolygons];
  vec4 polyVertices[kUboPolyVertices];
};

struct FrameParams {
  vec4 cameraForward;      // xyz: unit view direction
  vec4 cameraRight;        // xyz: right * tan(fov_y / 2) * aspect
  vec4 cameraUp;           // xyz: up * tan(fov_y / 2)
  vec4 cameraOrigin;       // xyz: eye position (camera-relative frame: 0); w: lens radius (0: pinhole)
  vec4 worldOffset;        // xyz: world position of the frame's origin (checker patterns use world space)
  vec4 background;         // rgb: colour of rays that miss
  vec4 ambientLight;       // rgb: global ambient light
  float bailout;           // branches with a smaller weight are not traced
  float adaptiveThreshold; // adaptive AA: neighbour difference that triggers refinement
  float coneSpread;        // textures: the eye rays' cone spread angle, radians per unit distance
  float focusDistance;     // thin lens: distance of the plane in focus along cameraForward
  uvec2 imageSize;         // width, height in pixels
  uint shadowEntryBase;    // shadow entry points' first texel in BvhNodes[] (SHADOW_ENTRIES; 0: none)
  uint maxDepth;           // bounces after the eye ray
  uint sphereCount;
  uint planeCount;
  uint triangleCount;
  uint polygonCount;
  uint lightCount;
  uint shadowEntryLights;  // lights per triangle in the shadow entry points' table
  uint occluderPlaneCount; // planes that can cast shadows (first in Planes[])
  uint bvhRoot;            // the BVH root's reference (BvhWideNode)
  // Without a BVH: boxes around all triangles and around all polygons (xyz; exact, from the float
  // vertices, as the BVH's leaf boxes). A ray that misses one skips that kind's whole loop.
  vec4 triangleBoundsMin;
  vec4 triangleBoundsMax;
  vec4 polygonBoundsMin;
  vec4 polygonBoundsMax;
  // render.seed: mixed into each pixel's key for its sample sequences (0: the key is the pixel's
  // index, as it always was), and into the forward tracer's photon streams.
  uint sampleSeed;
  uint framePad0, framePad1, framePad2;
};

// ---- Ray counters --------------------------------------------------------------------------------
// The one list of the kernel's counters. X(host field, GPU field, name printed by --stats, how
// counts from several dispatches combine: Sum or Max). It generates the GPU struct below and, on the
// host (render/ray_stats.h), the statistics struct, its copy from the GPU, its sums and its
// printing. A new counter is a line here, an increment in the kernel and its flush (trace.comp).
#define VKRAY_RAY_COUNTERS(X)                                                                                          \
  X(eye, eyeRays, "eye rays", Sum)                                                                                     \
  X(shadow, shadowRays, "shadow rays", Sum)                                                                            \
  X(reflection, reflectionRays, "reflection rays", Sum)                                                                \
  X(refraction, refractionRays, "refraction rays", Sum)                                                                \
  X(bailoutSaved, bailoutSaved, "bailout saved", Sum)          /* branches below the bailout weight */                 \
  X(faintHighlights, faintHighlights, "faint highlights", Sum) /* lights not sampled (kNegligibleHighlight) */         \
  X(stackOverflow, stackOverflow, "stack overflow", Sum)       /* branches dropped: explicit stack full */             \
  X(truncated, truncated, "truncated samples", Sum)            /* cut short by the driver's loop limit */              \
  X(refinedPixels, refinedPixels, "refined pixels", Sum)       /* adaptive AA: pixels supersampled */                  \
  X(nonFinite, nonFinite, "non-finite samples", Sum)           /* NaN/Inf replaced by black; expected 0 */             \
  X(maxDepth, maxDepth, "deepest bounce", Max)

#define VKRAY_GPU_COUNTER_FIELD(host, gpu, label, combine) uint gpu;
struct RayStats {
  VKRAY_RAY_COUNTERS(VKRAY_GPU_COUNTER_FIELD)
  // Always 0. The kernels read it at run time into gDynamicZero (common.glsl), a zero the compiler
  // cannot see through.
  uint zero;
};
#undef VKRAY_GPU_COUNTER_FIELD

// The image buffers hold a window of whole rows: Image[] starts at row imageRow0 and PrevImage[] at
// row prevRow0, so images larger than one storage buffer can be traced band by band.
struct PushConstants {
  uvec2 tileOrigin; // first pixel of this dispatch
  uvec2 tileSize;   // pixels covered by this dispatch
  uint pass;        // kPassSample / kPassRefine / kPassList
  uint sampleBase;  // index of the first sample in the per-pixel sequence
  uint sampleCount; // samples per pixel in this dispatch
  uint flags;       // kFlagCenterSample | kFlagAccumulate | kFlagNoHalf0 << pass
  uint imageRow0;   // image row held by Image[0]
  uint prevRow0;    // image row held by PrevImage[0]
  uint prevRows;    // rows held by PrevImage[]
  // Per kernel: trace.comp's tile-row stride (the sample pass, see Renderer::recordDispatch; 0 or 1:
  // rows in order); forward.comp's contribution scale (float bits).
  uint param;
  // The list pass: the sequence index where the pass's second half starts; the samples below it
  // also go into the first half's sum (host/render/adaptive.h).
  uint splitBase;
  // A list pass may take up to three of the schedule's passes at once, each reported on its own
  // (the passes before the first decision; Renderer::renderProgressive): the samples from
  // segmentEnd0 on belong to the second, from segmentEnd1 on to the third (0: no such pass; a pass
  // never starts at sample 0), and the second's and third's first halves end at splitBase1 and
  // splitBase2.
  uint segmentEnd0;
  uint segmentEnd1;
  uint splitBase1;
  uint splitBase2;
};

// ---- The ray-tree recorder (kSpecRecordTree, shaders/lib/tree_record.glsl) ----------------------
// One TreeRay per ray the inspected pixel's samples trace, in the order the kernel traces them:
// each eye ray, the shadow rays of the surface it meets, then its children depth first. Positions
// are in the packed, camera-relative frame (GpuScene::origin); the host adds the origin back.
VKRAY_CONST(uint, kTreeEye, 0u); // kinds: the trace kernel's kRay* and one for shadows
VKRAY_CONST(uint, kTreeReflection, 1u);
VKRAY_CONST(uint, kTreeRefraction, 2u);
VKRAY_CONST(uint, kTreeShadow, 3u);
// What a ray met: a surface, nothing (the background); for a shadow ray, its light (through
// transmissive surfaces, attenuated, or freely), a blocker, or no shadow ray at all (the light casts
// no shadows, or nothing in the scene can cast one) with the light's full share.
VKRAY_CONST(uint, kTreeMiss, 0u);
VKRAY_CONST(uint, kTreeSurface, 1u);
VKRAY_CONST(uint, kTreeLightReached, 2u);
VKRAY_CONST(uint, kTreeBlocked, 3u);
VKRAY_CONST(uint, kTreeUnshadowed, 4u);
// Why a surface's branches were not traced (bits of TreeRay.what.z).
VKRAY_CONST(uint, kTreeCutDepth, 1u);             // at the depth cap with reflectance or transmission
VKRAY_CONST(uint, kTreeCutReflectionBailout, 2u); // the reflected branch's weight was below the bailout
VKRAY_CONST(uint, kTreeCutRefractionBailout, 4u); // the refracted branch's weight was below the bailout
VKRAY_CONST(uint, kTreeCutStack, 8u);             // the reflected branch found the stack full
VKRAY_CONST(uint, kTreeNoParent, 0xFFFFFFFFu);

struct TreeRay {
  vec4 origin;       // xyz: where the ray starts; w: distance to what it met (0 for a miss)
  vec4 direction;    // xyz: unit direction
  vec4 weight;       // rgb: what the ray's radiance is multiplied by on its way to the pixel
  vec4 contribution; // rgb: radiance this ray's shading added to the sample (weight included)
  vec4 point;        // xyz: the surface point, the light's position or the blocker's point
  uvec4 what;        // x: kind; y: outcome; z: kTreeCut* bits; w: parent record (kTreeNoParent)
  uvec4 where;       // x: primitive kind met (kPrim*; kNoHit); y: its index; z: light (shadow
                     // rays) or material (surfaces); w: sample index
};

// The buffer: a header, then the records. header.x: records written; y: capacity; z: rays not
// recorded for want of room; w: 1 when a tree stopped at kMaxTreeRays.
struct TreeRayHeader {
  uvec4 counts;
};

// ---- Probe kernel (shaders/probe.comp): the shaders/lib functions on arrays of test rays ---------
VKRAY_CONST(uint, kProbeBindingQueries, 0u);
VKRAY_CONST(uint, kProbeBindingResults, 1u);
VKRAY_CONST(uint, kProbeBindingVertices, 2u);

VKRAY_CONST(uint, kProbeSphere, 0u);     // a: centre, radius; b: centre low part; op.z: 1 = a = 1 (unit dir)
VKRAY_CONST(uint, kProbePlane, 1u);      // a: normal, D
VKRAY_CONST(uint, kProbeTriangle, 2u);   // a, b, c: vertices
VKRAY_CONST(uint, kProbePolygon, 3u);    // a: normal; op.z/op.w: first vertex, count in Vertices[]
VKRAY_CONST(uint, kProbeSpawn, 4u);      // origin: p; dir: side normal; a.x: error bound
VKRAY_CONST(uint, kProbeDielectric, 5u); // dir: incident; a: shading normal (facing); b: geometric
                                         // normal (facing); c.x, c.y: n1, n2; op.z: 1 = Schlick

struct ProbeQuery {
  vec4 origin; // xyz: ray origin; w: tMax (0: unbounded)
  vec4 dir;    // xyz: ray direction
  vec4 a;
  vec4 b;
  vec4 c;
  uvec4 op; // x: kProbe* operation; y: kNumerics*; z, w: per operation
};

struct ProbeResult {
  vec4 hit;      // x: t (-1: miss); yzw: barycentrics (triangles). Dielectric: x: Fresnel
  vec4 point;    // xyz: surface point; w: error bound. Dielectric: xyz: refracted direction
  vec4 normal;   // xyz: geometric normal as stored. Dielectric: xyz: mirror direction
  vec4 spawnOut; // xyz: origin for a ray leaving on the incoming side (shadow, reflection)
  vec4 spawnIn;  // xyz: origin for a ray continuing through the surface (refraction)
};

#ifdef __cplusplus
} // namespace vkray::gpu
#endif
// VKRAY_CONST stays defined for the other shared headers (resolve_types.h).
#endif
