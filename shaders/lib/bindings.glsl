// The scene's descriptor bindings as the tracing kernels declare them (numbers in shared/gpu_types.h),
// and the loop bounds of the brute-force arrays.
#ifndef VKRAY_BINDINGS_GLSL
#define VKRAY_BINDINGS_GLSL

// Read-only texel buffers are samplerless (textureBuffer, read with texelFetch): a sampled image of
// Dim Buffer is not valid SPIR-V for Vulkan, and Mesa 25 reports it through the validation messenger.
#extension GL_EXT_samplerless_texture_functions : require

#include "../shared/gpu_types.h"
#include "common.glsl"
#include "specialization.glsl"

layout(std140, binding = kBindingFrame) uniform FrameBlock { FrameParams frameUbo; };
FrameParams frame; // frameUbo, copied by loadSceneRegisters() (scene_access.glsl)
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
layout(binding = kBindingNormals) uniform textureBuffer normalTexels;    // 1 per vertex normal
layout(binding = kBindingBvhNodes, rgba32ui) uniform readonly restrict uimageBuffer nodeTexels; // 4 per BvhWideNode
layout(binding = kBindingPrimRefs) uniform utextureBuffer primRefTexels; // 1 per reference

layout(std140, binding = kBindingSceneUbo) uniform SceneBlock { SceneUbo small; };
// Written by shaders/entry.comp as a storage buffer, read here as texels once per invocation.
layout(binding = kBindingEntryTexels) uniform utextureBuffer entryTexels;
// Textures (TEXTURES only; layout in shared/gpu_types.h).
layout(binding = kBindingTexCoords) uniform textureBuffer texCoordTexels;
layout(binding = kBindingTextureInfo) uniform utextureBuffer textureInfoTexels;
layout(binding = kBindingTexels) uniform textureBuffer textureTexels;

// Loop bounds: a specialization constant where the host baked the count in (the loop unrolls).
uint sphereCount() { return SPHERE_COUNT != kRuntimeCount ? SPHERE_COUNT : opaqueUniform(frame.sphereCount); }
uint planeCount() { return PLANE_COUNT != kRuntimeCount ? PLANE_COUNT : opaqueUniform(frame.planeCount); }
uint triangleCount() { return TRIANGLE_COUNT != kRuntimeCount ? TRIANGLE_COUNT : opaqueUniform(frame.triangleCount); }
uint polygonCount() { return POLYGON_COUNT != kRuntimeCount ? POLYGON_COUNT : opaqueUniform(frame.polygonCount); }
uint occluderPlaneCount() {
  return OCCLUDER_PLANE_COUNT != kRuntimeCount ? OCCLUDER_PLANE_COUNT : opaqueUniform(frame.occluderPlaneCount);
}
uint lightCount() { return LIGHT_COUNT != kRuntimeCount ? LIGHT_COUNT : opaqueUniform(frame.lightCount); }

#endif
