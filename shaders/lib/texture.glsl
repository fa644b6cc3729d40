// Base-colour textures, sampled by hand from one texel buffer (layout in shared/gpu_types.h):
// nearest, bilinear, or trilinear between the two mip levels a ray cone's footprint falls between
// (Akenine-Moller et al., "Texture Level of Detail Strategies for Real-Time Ray Tracing", Ray
// Tracing Gems ch. 20, sec. 20.3.4). Compiled in only when TEXTURES; host/scene/texture.cpp has the
// same samplers for the tests.
#ifndef VKRAY_TEXTURE_GLSL
#define VKRAY_TEXTURE_GLSL

#include "bindings.glsl"
#include "ray_records.glsl"

// The ray cone's footprint at the hit being shaded: width / |n.d| (trace.comp sets it).
float gConeFootprint = 0.0;

// The cones of the rays a surface sends on: (width at their origin, spread angle). `width` is the
// incoming cone's where it met the surface, `spread` its spread angle, `curvature` the surface's as
// the ray sees it (1 / radius where it bulges towards the ray, negative where it is hollow, 0 when
// flat). Paraxially: the cone's edge ray, w/2 off its axis, meets a normal tilted by curvature * w/2.
// - A mirror turns that tilt twice: spread + 2 curvature width. (At incidence angle theta the
//   footprint is w / cos(theta) long in the plane of incidence, where the reflection turns by
//   2 curvature w / cos(theta), and w across it, where it turns by 2 curvature w cos(theta); their
//   geometric mean, used here, keeps the footprint's area, which is what the level of detail reads.)
// - Snell's law for small angles, with eta = n1 / n2: eta spread + (eta - 1) curvature width; a
//   glass ball (convex going in, hollow coming out, eta < 1 then > 1) makes it converge.
// RenderTexture.ConesWidenAtConvexMirrorsAndNarrowInGlass checks both against a double-precision model.
// The spread is kept within a half-turn either way: a wider cone already picks the coarsest level
// from its first unit of travel, and a finite bound keeps the sums finite where a sliver triangle's
// vertex normals give an enormous curvature (an infinite spread would meet an opposite one as NaN).
const float kMaxConeSpread = 3.14159265;

vec2 coneAfterReflection(float spread, float width, float curvature) {
  return vec2(width, clamp(spread + 2.0 * curvature * width, -kMaxConeSpread, kMaxConeSpread));
}

vec2 coneAfterRefraction(float spread, float width, float curvature, float eta) {
  return vec2(width, clamp(eta * spread + (eta - 1.0) * curvature * width, -kMaxConeSpread, kMaxConeSpread));
}

// uv into [0, 1] by the wrap mode (the repeat and mirror periods taken in float, before any integer
// conversion, so huge uv cannot overflow).
float wrapAxis(float u, uint mode) {
  if (mode == kWrapRepeat) return u - floor(u);
  if (mode == kWrapMirror) {
    float m = u - 2.0 * floor(0.5 * u);
    return m <= 1.0 ? m : 2.0 - m;
  }
  return clamp(u, 0.0, 1.0);
}

// A bilinear neighbour's index, i in [-1, n]: repeat wraps round, clamp and mirror stay at the edge.
uint edgeTexel(int i, uint n, uint mode) {
  if (mode == kWrapRepeat) return i < 0 ? n - 1u : (uint(i) >= n ? 0u : uint(i));
  return uint(clamp(i, 0, int(n) - 1));
}

vec4 levelTexel(TextureLevel level, uint x, uint y) {
  return texelFetch(textureTexels, int(levelFirstTexel(level) + y * levelWidth(level) + x));
}

vec4 sampleLevelNearest(TextureLevel level, vec2 uv) {
  uint x = min(uint(uv.x * float(levelWidth(level))), levelWidth(level) - 1u);
  uint y = min(uint(uv.y * float(levelHeight(level))), levelHeight(level) - 1u);
  return levelTexel(level, x, y);
}

vec4 sampleLevelBilinear(TextureLevel level, vec2 uv, uint wrapS, uint wrapT) {
  vec2 p = uv * vec2(levelWidth(level), levelHeight(level)) - 0.5;
  vec2 p0 = floor(p);
  vec2 f = p - p0;
  ivec2 i = ivec2(p0);
  uint x0 = edgeTexel(i.x, levelWidth(level), wrapS), x1 = edgeTexel(i.x + 1, levelWidth(level), wrapS);
  uint y0 = edgeTexel(i.y, levelHeight(level), wrapT), y1 = edgeTexel(i.y + 1, levelHeight(level), wrapT);
  vec4 top = mix(levelTexel(level, x0, y0), levelTexel(level, x1, y0), f.x);
  vec4 bottom = mix(levelTexel(level, x0, y1), levelTexel(level, x1, y1), f.x);
  return mix(top, bottom, f.y);
}

// Texture reference `ref` (+ 1) at texture coordinates `uvs` (both sets), with the triangle's lod
// biases and the ray cone's footprint (0: the full-size image).
vec4 baseColorTexelAt(uint ref, vec4 uvs, vec2 uvLodBias, float footprint) {
  TextureRef tex = loadTextureRef(ref);
  bool set1 = readsUvSet1(tex);
  vec3 uv1 = vec3(set1 ? uvs.zw : uvs.xy, 1.0);
  vec2 uv = vec2(dot(uvTransformRow0(tex), uv1), dot(uvTransformRow1(tex), uv1));
  uint wrapS = wrapModeS(tex);
  uint wrapT = wrapModeT(tex);
  bool nearest = magnifiesNearest(tex);
  vec2 w = vec2(wrapAxis(uv.x, wrapS), wrapAxis(uv.y, wrapT));
  TextureLevel base = loadTextureLevel(textureFirstLevel(tex));
  if (TEXTURE_FILTER == kTextureNearest) return sampleLevelNearest(base, w);
  if (TEXTURE_FILTER == kTextureBilinear) return nearest ? sampleLevelNearest(base, w) : sampleLevelBilinear(base, w, wrapS, wrapT);
  // Ray cones: lambda = 0.5 log2(texel area / world area) + log2(width / |n.d|) (RTG eq. 20.7).
  float lod = (set1 ? uvLodBias.y : uvLodBias.x) + textureLodOffset(tex) + log2(max(footprint, 1e-30));
  if (nearest && lod <= 0.0) return sampleLevelNearest(base, w); // magnified: the sampler's filter
  lod = clamp(lod, 0.0, float(textureLevelCount(tex) - 1u));
  // Minified, the sampler's minFilter (gpu_scene.cpp packs it): which levels, and which texels in them.
  uint minLevels = minifiedLevels(tex);
  bool minNearest = lod > 0.0 && minifiesNearest(tex);
  if (lod > 0.0 && minLevels != kMinLevelsBlend) {
    TextureLevel level =
        minLevels == kMinLevelsBase ? base : loadTextureLevel(textureFirstLevel(tex) + uint(lod + 0.5));
    return minNearest ? sampleLevelNearest(level, w) : sampleLevelBilinear(level, w, wrapS, wrapT);
  }
  uint l0 = uint(lod);
  uint l1 = min(l0 + 1u, textureLevelCount(tex) - 1u);
  TextureLevel level0 = loadTextureLevel(textureFirstLevel(tex) + l0);
  TextureLevel level1 = loadTextureLevel(textureFirstLevel(tex) + l1);
  vec4 a = minNearest ? sampleLevelNearest(level0, w) : sampleLevelBilinear(level0, w, wrapS, wrapT);
  vec4 b = minNearest ? sampleLevelNearest(level1, w) : sampleLevelBilinear(level1, w, wrapS, wrapT);
  return mix(a, b, lod - float(l0));
}

// The material's base-colour texel at the surface; 1 for untextured materials and surfaces
// without texture coordinates.
vec4 baseColorTexel(Material mat, Surface s) {
  uint ref = textureRefPlusOne(mat);
  if (ref == 0u || !s.hasUv) return vec4(1.0);
  return baseColorTexelAt(ref, s.uv, s.uvLodBias, gConeFootprint);
}

// glTF alphaMode MASK (ALPHA_MASK only): a candidate hit on triangle `index` at `bary` does not
// count where the base colour's alpha (factor x texel, the full-size image: the intersection test
// has no ray cone) is below the material's cutoff. Used by every query, so shadow rays pass
// through the cut-out parts too.
bool alphaCutOut(uint index, vec3 bary) {
  Triangle tri = loadTriangle(index);
  Material m = loadMaterial(triangleMaterial(tri));
  float cutoff = alphaCutoff(m);
  float alpha = baseAlpha(m);
  uint ref = textureRefPlusOne(m);
  uint uvBase = triangleUvBasePlusOne(tri);
  if (TEXTURES && cutoff > 0.0 && ref != 0u && uvBase != 0u && hasTexCoords(loadUvInfo(int(uvBase - 1u)))) {
    int b = int(uvBase - 1u);
    vec4 uvs = bary.x * loadUvCorner(b, 0) + bary.y * loadUvCorner(b, 1) + bary.z * loadUvCorner(b, 2);
    alpha *= baseColorTexelAt(ref, uvs, vec2(0.0), 0.0).a;
  }
  return alpha < cutoff;
}

#endif
