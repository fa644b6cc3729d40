// Forward ray tracing (`render --method forward`): the lecture's first, rejected algorithm. Each
// invocation is one photon of one point light, emitted in a direction of a deterministic sequence
// uniform over the sphere. It follows the light paths the backward (Whitted) model describes, in
// the other direction (docs/forward.md derives the correspondence):
//
//   light --straight, through transmissive surfaces (their shadow attenuation)--> a surface X, where
//   the Phong model's diffuse and specular terms act as a reflection distribution: the photon
//   leaves in a sampled direction --specular chain (mirror reflection, dielectric reflection or
//   refraction, at most max_depth events)--> the camera's lens, then the plane in focus: a pixel.
//
// A photon adds to a pixel only when it passes through the lens: with a pinhole (aperture 0) it
// never does, which is the lecture's point. Contributions are summed as 64-bit fixed point with
// 32-bit atomics, so the image does not depend on the order the photons arrive in.
//
// Buffer kBindingPhotonImage (uint[]): the header (kPhotonHeaderWords: photons struck lo/hi, rays
// traced lo/hi, non-finite contributions), then per pixel and channel a 64-bit sum (lo, hi) of the
// contribution times 2^kPhotonFixedBits. The host (renderer_forward.cpp) divides by the photons
// emitted per light.
//
// Push constants: tileOrigin.x the light, sampleBase the first photon index, sampleCount photons in
// this dispatch, param a float scale the host applies to every contribution (keeps sums in range).
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_basic : require

#include "shared/gpu_types.h"

layout(local_size_x = kWorkgroupSizeX, local_size_y = kWorkgroupSizeY, local_size_z = 1) in;

#include "lib/sampling.glsl"
#include "lib/shade.glsl"

layout(std430, binding = kBindingStats) readonly buffer StatsBuffer { RayStats stats; };
layout(std430, binding = kBindingPhotonImage) restrict buffer PhotonImage { uint photonImage[]; };
layout(push_constant) uniform Push { PushConstants pc; };

uint gRays = 0u;   // rays this photon traced
uint gStruck = 0u; // its branches that reached the image

// Adds a non-negative 64-bit value (lo, hi) at word `at`: the low words' carry goes to the high word,
// so the sum is exact whatever the order of the additions.
void add64(uint at, uint lo, uint hi) {
  uint before = atomicAdd(photonImage[at], lo);
  uint carry = (before + lo < before) ? 1u : 0u;
  if (hi + carry != 0u) atomicAdd(photonImage[at + 1u], hi + carry);
}

// A contribution in fixed point: value * 2^kPhotonFixedBits as (lo, hi); values at or above
// 2^(64 - kPhotonFixedBits - 1) are clamped (none occur at the scales the host picks).
void addFixed(uint at, float value) {
  const float kHiUnit = float(1u << (32u - kPhotonFixedBits)); // one unit of the high word
  float v = clamp(value, 0.0, kHiUnit * 2147483648.0);
  float hi = floor(v / kHiUnit);
  float lo = (v - hi * kHiUnit) * float(1u << kPhotonFixedBits);
  add64(at, uint(min(lo + 0.5, 4294967040.0)), uint(hi)); // the largest float below 2^32
}

// An orthonormal frame around the unit vector n (Duff et al., "Building an Orthonormal Basis,
// Revisited", JCGT 6(1), 2017).
void frameAround(vec3 n, out vec3 t, out vec3 b) {
  float s = signNonZero(n.z);
  float a = -1.0 / (s + n.z);
  float c = n.x * n.y * a;
  t = vec3(1.0 + s * n.x * n.x * a, s * c, -s * n.x);
  b = vec3(c, s + n.y * n.y * a, -n.y);
}

vec3 aroundAxis(vec3 axis, float cosTheta, float phi) {
  vec3 t, b;
  frameAround(axis, t, b);
  float sinTheta = sqrt(max(0.0, 1.0 - cosTheta * cosTheta));
  return normalize(sinTheta * cos(phi) * t + sinTheta * sin(phi) * b + cosTheta * axis);
}

// The photon has reached the lens at `lensPoint` travelling along `dir`: the backward eye ray from
// that lens point along -dir meets the plane in focus in one point, which names the pixel. Its
// contribution is flux / (A_lens A_pixel cos^4 theta): the inverse of the throughput between the
// lens and the pixel's patch of the image plane at unit distance, since a backward pixel averages
// radiance uniformly over both (docs/forward.md, "The camera").
void deposit(vec3 lensPoint, vec3 dir, vec3 flux) {
  vec3 back = -dir;
  float cosTheta = dot(back, frame.cameraForward.xyz);
  vec3 q = lensPoint + back * (frame.focusDistance / cosTheta) - frame.cameraOrigin.xyz;
  vec3 right = frame.cameraRight.xyz;
  vec3 up = frame.cameraUp.xyz;
  float x = dot(q, right) / (frame.focusDistance * dot(right, right));
  float y = dot(q, up) / (frame.focusDistance * dot(up, up));
  vec2 size = vec2(frame.imageSize);
  vec2 pos = vec2(0.5 * (x + 1.0) * size.x, 0.5 * (1.0 - y) * size.y);
  if (!(pos.x >= 0.0 && pos.y >= 0.0 && pos.x < size.x && pos.y < size.y)) return;
  uvec2 pixel = min(uvec2(pos), frame.imageSize - 1u);
  float pixelArea = (2.0 * length(right) / size.x) * (2.0 * length(up) / size.y);
  float lensArea = kPi * frame.cameraOrigin.w * frame.cameraOrigin.w;
  float c2 = cosTheta * cosTheta;
  vec3 value = flux * (uintBitsToFloat(pc.param) / (lensArea * pixelArea * c2 * c2));
  if (!isFiniteVec(value)) {
    atomicAdd(photonImage[4], 1u);
    return;
  }
  uint at = kPhotonHeaderWords + 6u * (pixel.y * frame.imageSize.x + pixel.x);
  addFixed(at, value.r);
  addFixed(at + 2u, value.g);
  addFixed(at + 4u, value.b);
  gStruck++;
}

// From a surface towards the camera: the specular chain a backward eye ray would have followed the
// other way. At each surface the photon takes the mirror or the refracted branch with probability
// in proportion to their weights (the sum of both is kept in its flux); `chain` is the weight the
// backward tree would give this branch, cut at the bailout and at max_depth events as it is.
void towardsTheLens(vec3 origin, vec3 dir, vec3 flux, uvec2 media, uint index, uint stream) {
  vec3 o = origin;
  vec3 d = dir;
  vec3 chain = vec3(1.0);
  uint maxDepth = opaqueUniform(frame.maxDepth);
  uint events = 0u;
  while (true) { // tested at the bottom (see traverseBvh in bvh.glsl)
    gRays++;
    TraceRay r = makeTraceRay(o, d);
    Hit hit = traceScene(r, kInfinity, false, false, false);
    uint medium = REFRACTION ? mediaTop(media) : kNoMedium;
    // The lens: a disk of radius cameraOrigin.w around the eye, facing cameraForward.
    float towards = dot(d, frame.cameraForward.xyz);
    float tLens = towards < 0.0 ? dot(frame.cameraOrigin.xyz - o, frame.cameraForward.xyz) / towards : -1.0;
    vec3 lensPoint = o + tLens * d;
    bool onLens = tLens > 0.0 && tLens < hit.t &&
                  length(lensPoint - frame.cameraOrigin.xyz) <= frame.cameraOrigin.w;
    vec3 absorbed = (REFRACTION && medium != kNoMedium)
                        ? beerLambert(absorptionPerUnit(loadMaterial(medium)), onLens ? tLens : hit.t)
                        : vec3(1.0);
    if (onLens) {
      // The backward tree's last branch (this one, from the eye) carries every factor but the
      // absorption before X: traced only at or above the bailout.
      vec3 eyeBranch = chain * absorbed;
      if (events == 0u || maxComponent(eyeBranch) >= frame.bailout) deposit(lensPoint, d, flux * absorbed);
      break;
    }
    if (hit.kind == kNoHit || !(REFLECTION || REFRACTION) || events >= maxDepth) break;
    flux *= absorbed;
    if (events > 0u) chain *= absorbed; // (the segment from X is not in any backward branch's weight)
    Surface s = surfaceAt(r, hit);
    Material mat = loadMaterial(s.material);
    bool front = dot(s.ng, d) < 0.0;
    vec3 ngf = front ? s.ng : -s.ng;
    vec3 nsf = front ? s.ns : -s.ns;
    float kr = reflectance(mat);
    float kt = 0.0;
    vec3 tdir = vec3(0.0);
    uvec2 tmedia = media;
    if (REFRACTION && transmittance(mat) > 0.0) {
      float trans = transmittance(mat);
      float n1, n2;
      if (front) {
        n1 = mediumIor(medium);
        n2 = refractiveIndex(mat);
        tmedia = mediaPush(media, s.material);
      } else {
        n1 = refractiveIndex(mat);
        tmedia = mediaRemove(media, s.material);
        n2 = mediumIor(mediaTop(tmedia));
      }
      DielectricSplit split = dielectricSplit(d, nsf, ngf, n1, n2, FRESNEL == kFresnelSchlick);
      kr += trans * split.fresnel;
      kt = trans * (1.0 - split.fresnel);
      tdir = split.refracted;
    }
    float total = kr + kt;
    if (!(total > 0.0)) break; // a surface with no specular branch: backward sees it only lit directly
    bool refracted = REFRACTION && hashToUnit(hashPcg(index ^ hashPcg(stream + 977u * events))) * total >= kr;
    float factor = refracted ? kt : kr;
    chain *= factor;
    if (!(maxComponent(chain) > 0.0 && maxComponent(chain) >= frame.bailout)) break;
    flux *= total; // the branch's factor over its probability (factor / total)
    if (refracted) {
      o = ROBUST ? spawnOrigin(s.p, -ngf, s.errorBound) : s.p;
      d = tdir;
      media = tmedia;
    } else {
      o = ROBUST ? spawnOrigin(s.p, ngf, s.errorBound) : s.p;
      d = mirrorDirection(d, nsf, ngf);
    }
    ++events;
  }
}

// The Phong model at X as a reflection distribution, for a photon arriving along `dir` with flux
// `flux` per unit of (geometric) irradiance. Backward, X seen from direction v is
//   L = I (kd base (ns.l) + ks (r.v)^n),   r = reflect(-l, ns),
// for a light of colour I in direction l; the photons deliver E = I (ng.l) per unit area, so the
// distribution is f(v) = (kd base (ns.l) + ks (r.v)^n) / (ng.l). The leaving direction is drawn from
// a mix of a cosine lobe (the diffuse term) and a Phong lobe around r (the highlight), weighted by
// f cos / pdf of the mix (one-sample balance heuristic).
void scatterAtSurface(Surface s, Material mat, vec3 dir, vec3 flux, uvec2 media, uint index, uint stream) {
  vec3 l = -dir;
  vec3 ngl = dot(s.ng, l) > 0.0 ? s.ng : -s.ng; // the light's side: the camera must be on it too
  vec3 nsl = dot(s.ng, l) > 0.0 ? s.ns : -s.ns;
  float cosShading = dot(nsl, l);
  float cosGeometric = dot(ngl, l);
  float kd = diffuseFactor(mat);
  float ks = specularFactor(mat);
  if (!(cosShading > 0.0 && cosGeometric > 0.0 && (kd > 0.0 || ks > 0.0))) return;
  vec3 base = baseColor(mat, s);
  float shininess = phongExponent(mat);
  vec3 r = reflect(-l, nsl);
  float diffuseWeight = kd * maxComponent(base) * cosShading;
  float lobe = ks > 0.0 ? ks / (diffuseWeight + ks) : 0.0; // probability of sampling the Phong lobe
  vec2 u = sobolOwenSample(index, hashPcg(stream ^ 0x7f4a7c15u));
  float choose = hashToUnit(hashPcg(index ^ hashPcg(stream ^ 0x2c1b3c6du)));
  vec3 v = choose < lobe ? aroundAxis(r, pow(u.x, 1.0 / (shininess + 1.0)), 2.0 * kPi * u.y)
                         : aroundAxis(ngl, sqrt(u.x), 2.0 * kPi * u.y);
  float cosOut = dot(ngl, v);
  if (!(cosOut > 0.0)) return;
  float rv = max(dot(r, v), 0.0);
  float phong = (ks > 0.0 && rv > 0.0) ? pow(rv, shininess) : 0.0;
  vec3 f = (kd * cosShading * base + ks * phong) / cosGeometric;
  float pdf = (1.0 - lobe) * cosOut / kPi + lobe * (shininess + 1.0) / (2.0 * kPi) * phong;
  if (!(pdf > 0.0)) return;
  vec3 leaving = flux * f * (cosOut / pdf);
  if (maxComponent(leaving) <= 0.0) return;
  vec3 origin = ROBUST ? spawnOrigin(s.p, ngl, s.errorBound) : s.p;
  towardsTheLens(origin, v, leaving, media, index, stream ^ 0x51ed270bu);
}

// One photon: from the light in its direction, a straight line through every surface a shadow ray
// would pass (transmissive ones attenuate it as they attenuate shadow rays; an opaque one stops it),
// scattering towards the camera at each. The flux of a photon is 4 pi I r^2 per photon emitted
// (times the host's scale): the backward model's lights do not fall off with distance, so the
// photons that reach a surface at distance r carry r^2 more to deliver irradiance I cos, as a shadow
// ray finds it.
void tracePhoton(uint light, uint index) {
  Light L = loadLight(light);
  vec3 lightPos = lightPosition(L);
  bool blocks = SHADOWS && castsShadows(L);
  // render.seed moves every light's stream (seed 0: the stream it always had).
  uint seed = hashPcg(light * 0x9e3779b9u + 0x632be5abu + frame.sampleSeed * 0x85ebca6bu);
  vec2 u = sobolOwenSample(index, seed);
  float z = 1.0 - 2.0 * u.x;
  float ring = sqrt(max(0.0, 1.0 - z * z));
  vec3 dir = vec3(ring * cos(2.0 * kPi * u.y), ring * sin(2.0 * kPi * u.y), z);
  vec3 transmit = lightColor(L);
  vec3 o = lightPos;
  uvec2 media = kEmptyMedia;
  float enteredAt = 0.0;
  int crossing = 0;
  while (true) { // tested at the bottom
    gRays++;
    TraceRay r = makeTraceRay(o, dir);
    Hit hit = traceScene(r, kInfinity, false, false, false);
    if (hit.kind == kNoHit) break;
    Surface s = surfaceAt(r, hit);
    Material mat = loadMaterial(s.material);
    float fromLight = length(s.p - lightPos);
    bool entering = dot(s.ng, dir) < 0.0;
    vec3 here = transmit;
    if (blocks && SHADOW_MODE == kShadowsAttenuated && !entering) {
      here *= beerLambert(absorptionPerUnit(mat), fromLight - enteredAt);
    }
    uint stream = hashPcg(seed ^ (uint(crossing) * 0x85ebca6bu));
    scatterAtSurface(s, mat, dir, here * (4.0 * kPi * fromLight * fromLight), media, index, stream);
    if (blocks) {
      // A shadow ray stops at an opaque surface, and at any surface when shadows are opaque.
      float passes = SHADOW_MODE == kShadowsAttenuated ? transmittance(mat) : 0.0;
      if (!(passes > 0.0)) break;
      transmit = here * passes;
      if (entering) enteredAt = fromLight;
      if (maxComponent(transmit) <= 0.0) break;
    }
    if (REFRACTION) media = entering ? mediaPush(media, s.material) : mediaRemove(media, s.material);
    vec3 side = entering ? -s.ng : s.ng;
    o = ROBUST ? spawnOrigin(s.p, side, s.errorBound) : s.p;
    if (++crossing > kMaxShadowCrossings) break;
  }
}

void main() {
  gDynamicZero = stats.zero;
  loadSceneRegisters(); // before any branch (scene_access.glsl)
  uint offset = gl_WorkGroupID.x * (kWorkgroupSizeX * kWorkgroupSizeY) + gl_LocalInvocationIndex;
  if (offset < opaqueUniform(pc.sampleCount)) tracePhoton(opaqueUniform(pc.tileOrigin.x), pc.sampleBase + offset);
  // Every invocation takes part in the subgroup sums (no early return above).
  uint rays = subgroupAdd(gRays);
  uint struck = subgroupAdd(gStruck);
  if (subgroupElect()) {
    if (struck != 0u) add64(0u, struck, 0u);
    add64(2u, rays, 0u);
  }
}
