// Reading the scene's records: from registers (small scenes on CPU devices), the uniform block, or
// the storage and texel buffers; the specialization constants leave one way of each.
#ifndef VKRAY_SCENE_ACCESS_GLSL
#define VKRAY_SCENE_ACCESS_GLSL

#include "bindings.glsl"

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
BvhWideNode loadBvhNode(uint i) {
  // Three texels (host/accel/bvh_records.h): min0.xyz max0.x | max0.yz min1.xy | min1.z max1.xyz, the
  // references in the low bytes of the first eight words; each bound was rounded outwards before its
  // byte went in, so the boxes are used as they are. A fourth texel read is a call of the texel-fetch
  // function on llvmpipe, dearer than the eighteen vector operations that take the bytes out.
  int n = int(kBvhRecordTexels * i);
  uvec4 a = imageLoad(nodeTexels, n);
  uvec4 b = imageLoad(nodeTexels, n + 1);
  uvec4 c = imageLoad(nodeTexels, n + 2);
  uint ref0 = (a.x & 0xFFu) | ((a.y & 0xFFu) << 8u) | ((a.z & 0xFFu) << 16u) | (a.w << 24u);
  uint ref1 = (b.x & 0xFFu) | ((b.y & 0xFFu) << 8u) | ((b.z & 0xFFu) << 16u) | (b.w << 24u);
  return BvhWideNode(uintBitsToFloat(a.xyz), ref0, uintBitsToFloat(uvec3(a.w, b.xy)), ref1, uintBitsToFloat(uvec3(b.zw, c.x)),
                     0u, uintBitsToFloat(c.yzw), 0u);
}

// Textures (TEXTURES, VERTEX_COLORS). `record` is a uv record's first texel in TexCoords[].
UvInfo loadUvInfo(int record) { return UvInfo(texelFetch(texCoordTexels, record + int(kUvRecordInfo))); }
vec4 loadUvCorner(int record, int k) { return texelFetch(texCoordTexels, record + int(kUvRecordCorners) + k); }
vec3 loadCornerColor(int record, int k) { return texelFetch(texCoordTexels, record + int(kUvRecordColors) + k).rgb; }
// `ref` is Material's texture reference + 1.
TextureRef loadTextureRef(uint ref) {
  int r = int((ref - 1u) * kTextureRefTexels);
  return TextureRef(texelFetch(textureInfoTexels, r), texelFetch(textureInfoTexels, r + 1),
                    texelFetch(textureInfoTexels, r + 2));
}
TextureLevel loadTextureLevel(uint i) { return TextureLevel(texelFetch(textureInfoTexels, int(i))); }


#endif
