// What this scene calls for: the kernels' specialization constants (ids in shared/gpu_types.h). Each
// switches code on or off at pipeline creation, so the driver compiles out absent effects.
#ifndef VKRAY_SPECIALIZATION_GLSL
#define VKRAY_SPECIALIZATION_GLSL

#include "../shared/gpu_types.h"

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
layout(constant_id = kSpecShadowEntries) const bool SHADOW_ENTRIES = false;
layout(constant_id = kSpecBvhStepsPerVote) const uint BVH_STEPS_PER_VOTE = 1u;
layout(constant_id = kSpecTextures) const bool TEXTURES = false;
layout(constant_id = kSpecTextureFilter) const uint TEXTURE_FILTER = kTextureCone;
layout(constant_id = kSpecAlphaMask) const bool ALPHA_MASK = false;
layout(constant_id = kSpecVertexColors) const bool VERTEX_COLORS = false;
layout(constant_id = kSpecPixelRays) const bool PIXEL_RAYS = false;
layout(constant_id = kSpecThinLens) const bool THIN_LENS = false;
layout(constant_id = kSpecSpecularOnly) const bool SPECULAR_ONLY = true;

const bool ROBUST = NUMERICS == kNumericsRobust;
// The invocation counts its rays (gCount) for the statistics buffer, or for its pixel's cost alone.
const bool COUNT_RAYS = COUNT_STATS || PIXEL_RAYS;

#endif
