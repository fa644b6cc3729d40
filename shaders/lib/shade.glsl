// Local shading (the Phong model of the seed and POV-Ray's finish), shadow rays, Fresnel and the
// per-ray stack of transmissive media. Needs scene.glsl and the kernel's ray counters.
#ifndef VKRAY_SHADE_GLSL
#define VKRAY_SHADE_GLSL

#include "optics.glsl"
#include "scene.glsl"
#include "texture.glsl"
#include "tree_record.glsl"

// This invocation's ray counters (the list in shared/gpu_types.h), summed per subgroup and added to
// the statistics buffer at the end of the kernel (trace.comp, flushStats). `truncated` is counted
// even without COUNT_STATS: a cut-short tree is a wrong pixel.
#define VKRAY_COUNTER_FIELD(host, gpu, label, combine) uint gpu;
struct RayCounts {
  VKRAY_RAY_COUNTERS(VKRAY_COUNTER_FIELD)
  uint listEnd; // unused: takes the constructor's last argument (a macro list cannot drop its last comma)
};
#undef VKRAY_COUNTER_FIELD
#define VKRAY_COUNTER_ZERO(host, gpu, label, combine) 0u,
RayCounts gCount = RayCounts(VKRAY_RAY_COUNTERS(VKRAY_COUNTER_ZERO) 0u);
#undef VKRAY_COUNTER_ZERO

const int kMaxShadowCrossings = 8; // transmissive surfaces a shadow ray passes before giving up

// ---- Media stack: up to kMaxMediaDepth material ids, 16 bits each, packed into a uvec2 ----------
const uvec2 kEmptyMedia = uvec2(0xFFFFFFFFu);

uint mediaSlot(uvec2 m, uint i) { return (m[i >> 1u] >> ((i & 1u) * 16u)) & 0xFFFFu; }

uvec2 mediaSetSlot(uvec2 m, uint i, uint id) {
  uint shift = (i & 1u) * 16u;
  m[i >> 1u] = (m[i >> 1u] & ~(0xFFFFu << shift)) | (id << shift);
  return m;
}

// The media helpers run a fixed number of turns with selects: on CPU drivers a loop whose trip count
// the compiler cannot see (an early return, a data-dependent bound) stays a loop, and a loop costs
// one more whole turn, masked off, than its lanes need (traverseBvh in bvh.glsl).

// The innermost medium, or kNoMedium outside everything.
uint mediaTop(uvec2 m) {
  uint top = kNoMedium;
  for (uint i = 0u; i < kMaxMediaDepth; ++i) {
    uint id = mediaSlot(m, i);
    top = id != kNoMedium ? id : top;
  }
  return top;
}

// Entering a medium; a full stack keeps its outer media (documented limit of kMaxMediaDepth).
uvec2 mediaPush(uvec2 m, uint id) {
  bool placed = false;
  for (uint i = 0u; i < kMaxMediaDepth; ++i) {
    bool here = !placed && mediaSlot(m, i) == kNoMedium;
    m = here ? mediaSetSlot(m, i, id) : m;
    placed = placed || here;
  }
  return m;
}

// Leaving a medium: remove its innermost entry and close the gap.
uvec2 mediaRemove(uvec2 m, uint id) {
  int found = -1;
  for (uint i = 0u; i < kMaxMediaDepth; ++i) found = mediaSlot(m, i) == id ? int(i) : found;
  uvec2 closed = m;
  for (uint i = 0u; i + 1u < kMaxMediaDepth; ++i) {
    closed = int(i) >= found ? mediaSetSlot(closed, i, mediaSlot(m, i + 1u)) : closed;
  }
  closed = mediaSetSlot(closed, kMaxMediaDepth - 1u, kNoMedium);
  return found < 0 ? m : closed;
}

float mediumIor(uint id) { return id == kNoMedium ? 1.0 : refractiveIndex(loadMaterial(id)); }

// Beer-Lambert attenuation over a distance; a zero coefficient never meets an infinite distance.
vec3 beerLambert(vec3 sigma, float dist) {
  return vec3(sigma.x > 0.0 ? exp(-sigma.x * dist) : 1.0, sigma.y > 0.0 ? exp(-sigma.y * dist) : 1.0,
              sigma.z > 0.0 ? exp(-sigma.z * dist) : 1.0);
}

// ---- Surface colour ------------------------------------------------------------------------------
// 3-D checker (cubes of side `scale` in world space), evaluated at a point pushed just behind the
// surface by more than the hit point's error: a floor at y = 0 would otherwise flicker between two
// cells as rounding puts its hit points on either side of the cell boundary.
vec3 untexturedBaseColor(Material mat, Surface s) {
  if (!CHECKER) return baseColor(mat);
  float scale = checkerSize(mat);
  vec3 offset = frame.worldOffset.xyz;
  float margin = 2.0 * s.errorBound + 4.0 * 1.2e-7 * (maxComponent(abs(offset)) + maxComponent(abs(s.p)));
  vec3 q = (s.p + offset - s.ng * margin) / max(scale, 1e-30);
  float cells = floor(q.x) + floor(q.y) + floor(q.z);
  bool odd = cells - 2.0 * floor(0.5 * cells) != 0.0;
  return (scale > 0.0 && odd) ? checkerColor(mat) : baseColor(mat);
}

// The material's colour times its base-colour texture's texel (glTF baseColorFactor x texture).
vec3 baseColor(Material mat, Surface s) {
  vec3 c = untexturedBaseColor(mat, s);
  if (TEXTURES) c *= baseColorTexel(mat, s).rgb;
  if (VERTEX_COLORS) c *= s.vertexColor;
  return c;
}

// Fraction of light `light`'s colour that reaches `origin` (already offset off the surface, a
// primitive of kind `kind` and index `index`, whose shadow entry points start the walk where it is
// a triangle): 0 or 1 for opaque shadows; through transmissive surfaces, the product of their
// transmissions and the Beer-Lambert absorption between entering and leaving (POV-Ray's default
// behaviour).
vec3 shadowTransmittance(vec3 origin, vec3 lightPos, uint light, uint kind, uint index) {
  vec3 toLight = lightPos - origin;
  float dist = length(toLight);
  vec3 dir = toLight / dist;
  // SHADOW_MODE is attenuated only when some material transmits (host/render/kernel_variants.cpp), and
  // independently of max_depth: glass casts a light shadow even when no refracted ray is traced.
  if (SHADOW_MODE == kShadowsOpaque) {
    // An origin at the light (dist 0) is lit; its NaN direction meets nothing. Selects, not an
    // early return: on CPU drivers a return masks all the code after it.
    if (COUNT_RAYS) gCount.shadowRays += uint(dist > 0.0);
    Hit h = traceScene(makeTraceRay(origin, dir), dist, true, true, false, shadowEntryPoints(kind, index, light));
    if (RECORD_TREE) treeNoteShadowHit(h, origin, dir, dist);
    return (dist <= 0.0 || h.kind == kNoHit) ? vec3(1.0) : vec3(0.0);
  }
  if (dist <= 0.0) return vec3(1.0);
  vec3 transmit = vec3(1.0);
  vec3 o = origin;
  float travelled = 0.0; // along the shadow ray from the first origin
  float enteredAt = 0.0;
  int crossing = 0;
  uint fromKind = kind, fromIndex = index; // the surface the segment leaves
  while (true) { // tested at the bottom (see traverseBvh in bvh.glsl)
    if (COUNT_RAYS) gCount.shadowRays++;
    TraceRay r = makeTraceRay(o, dir);
    float remaining = length(lightPos - o);
    Hit h = traceScene(r, remaining, false, true, false, shadowEntryPoints(fromKind, fromIndex, light));
    if (h.kind == kNoHit) return transmit;
    Surface s = surfaceAt(r, h);
    Material m = loadMaterial(s.material);
    if (RECORD_TREE) treeNoteBlocker(h, s.p); // kept only if it stops the ray
    if (transmittance(m) <= 0.0) return vec3(0.0);
    transmit *= transmittance(m);
    float here = travelled + h.t;
    bool entering = dot(s.ng, dir) < 0.0;
    if (entering) {
      enteredAt = here;
    } else {
      transmit *= beerLambert(absorptionPerUnit(m), here - enteredAt);
    }
    if (maxComponent(transmit) <= 0.0) return vec3(0.0);
    vec3 side = entering ? -s.ng : s.ng; // continue on the far side of the surface
    vec3 next = ROBUST ? spawnOrigin(s.p, side, s.errorBound) : s.p;
    travelled += length(next - o);
    o = next;
    fromKind = h.kind;
    fromIndex = h.index;
    if (++crossing >= kMaxShadowCrossings) break;
  }
  return transmit;
}

// The Phong highlight specular * (r.v)^shininess, r the mirror of the light direction l about n.
float phongHighlight(vec3 l, vec3 n, vec3 v, float ks, float shininess) {
  float rv = dot(reflect(-l, n), v);
  // pow(x, 0) is 1 but GLSL leaves pow(0, y <= 0) undefined: only evaluate it for rv > 0.
  return (ks > 0.0 && rv > 0.0) ? ks * pow(rv, shininess) : 0.0;
}

// Ambient + for each light: visibility * colour * (diffuse * base * n.l + specular * (r.v)^shininess).
// ngf/nsf: geometric and shading normals turned towards the incoming ray.
vec3 localShade(Material mat, Surface s, vec3 ngf, vec3 nsf, vec3 rayDir, vec3 weight) {
  vec3 base = baseColor(mat, s);
  vec3 color = ambientFactor(mat) * base * frame.ambientLight.rgb;
  if (RECORD_TREE) treeAddContribution(gTreeCurrent, gTreeWeight * color);
  float kd = diffuseFactor(mat);
  float ks = specularFactor(mat);
  float shininess = phongExponent(mat);
  bool lightable = kd > 0.0 || ks > 0.0; // else nothing to light: no shadow rays either
  vec3 v = -rayDir;
  vec3 origin = ROBUST ? spawnOrigin(s.p, ngf, s.errorBound) : s.p;
  for (uint i = 0u; i < lightCount(); ++i) {
    Light light = loadLight(i);
    vec3 toLight = lightPosition(light) - s.p;
    float dist = length(toLight);
    vec3 l = toLight / dist;
    float ndotl = dot(nsf, l);
    // A light behind the surface (geometrically, or for the shading normal) does not light it.
    // One condition instead of a `continue` per test: on CPU drivers each masks the rest.
    // Without a diffuse term a light adds only its highlight, which a sharp one (glass: shininess
    // 300) confines to a few degrees around the mirror direction; elsewhere what it would add to the
    // pixel (the branch's weight times the light's colour times the highlight) is below
    // kNegligibleHighlight, or exactly zero, and its shadow ray is not traced: nearly half of the
    // glass scene's shadow rays (docs/performance.md, "Highlights too faint to see"). Scenes whose
    // materials all have a diffuse term compile the test out (SPECULAR_ONLY) and compute the
    // highlight only where the light is used, as before.
    float spec = SPECULAR_ONLY ? phongHighlight(l, nsf, v, ks, shininess) : 0.0;
    bool showsHighlight = maxComponent(weight * lightColor(light)) * spec >= kNegligibleHighlight;
    bool faces = lightable && dist > 0.0 && dot(ngf, l) > 0.0 && ndotl > 0.0;
    bool lit = faces && (!SPECULAR_ONLY || kd > 0.0 || showsHighlight);
    // --stats' "faint highlights": the lights the rule above left unsampled, each a shadow ray (or
    // more, through glass) not traced.
    if (SPECULAR_ONLY && COUNT_STATS) gCount.faintHighlights += uint(faces && !lit && SHADOWS && castsShadows(light));
    if (lit) {
      vec3 visible = vec3(1.0);
      if (RECORD_TREE) treeShadowStart();
      if (SHADOWS && castsShadows(light)) visible = shadowTransmittance(origin, lightPosition(light), i, s.kind, s.index);
      if (!SPECULAR_ONLY) spec = phongHighlight(l, nsf, v, ks, shininess);
      if (maxComponent(visible) > 0.0) color += visible * lightColor(light) * (kd * ndotl * base + spec);
      if (RECORD_TREE) {
        vec3 share = maxComponent(visible) > 0.0 ? visible * lightColor(light) * (kd * ndotl * base + spec) : vec3(0.0);
        treeRecordShadow(i, origin, lightPosition(light), SHADOWS && castsShadows(light), visible, gTreeWeight * share);
      }
    }
  }
  return color;
}

#endif
