// The renderer's kernel: one invocation per pixel generates its eye rays, follows each one's Whitted
// ray tree (mirror reflection and dielectric reflection + refraction) with an explicit stack, and
// writes the sum of its samples' radiance. Effects the scene lacks are specialized away.
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_shuffle : require

#include "shared/gpu_types.h"

layout(local_size_x = kWorkgroupSizeX, local_size_y = kWorkgroupSizeY, local_size_z = 1) in;

#define VKRAY_TREE_RECORDER 1 // the real recorder (lib/tree_record.glsl), behind RECORD_TREE
#include "lib/sampling.glsl"
#include "lib/shade.glsl"

// The sums (rgb, samples) per pixel, and the refine pass's copy of the base image: storage texel
// buffers, which llvmpipe reads one 16-byte texel per lane, where a storage buffer's vec4 is four
// per-lane loops of scalar loads (10-15 % of an accumulated sample's time). The sums are written
// through the same memory as a storage buffer (imageOut), whose stores llvmpipe compiles inline at
// half the cost of imageStore's helper function (gpu_types.h, kBindingImageOut); so neither
// declaration is `restrict`.
layout(binding = kBindingImage, rgba32f) uniform readonly imageBuffer imageTexels;
layout(std430, binding = kBindingImageOut) writeonly buffer ImageOut { vec4 imageOut[]; };
layout(binding = kBindingPrevImage, rgba32f) uniform readonly restrict imageBuffer prevTexels;
layout(std430, binding = kBindingStats) buffer StatsBuffer { RayStats stats; };
// Rays per pixel, summed over its samples (PIXEL_RAYS: the viewer's cost map).
layout(std430, binding = kBindingPixelRays) restrict buffer PixelRaysBuffer { uint pixelRays[]; };
layout(push_constant) uniform Push { PushConstants pc; };
layout(constant_id = kSpecRefinePass) const bool REFINE_PASS = false;
layout(constant_id = kSpecListPass) const bool LIST_PASS = false;

const uint kRayEye = 0u;
const uint kRayReflection = 1u;
const uint kRayRefraction = 2u;

// A branch of the ray tree waiting to be traced.
struct PendingRay {
  vec3 origin;
  uint depthKind; // bits 0..15: depth (bounces so far); bits 16..17: kRay* kind
  vec3 dir;
  vec3 weight;    // product of reflection/transmission factors and absorption along the path
  uvec2 media;    // media stack (shade.glsl)
};

// Branch-free: on CPU drivers every branch costs as much as its body.
void countRay(uint kind, uint depth) {
  if (!COUNT_RAYS) return;
  gCount.eyeRays += uint(kind == kRayEye);
  gCount.reflectionRays += uint(kind == kRayReflection);
  gCount.refractionRays += uint(kind == kRayRefraction);
  gCount.maxDepth = max(gCount.maxDepth, depth);
}

// A branch is worth tracing when its weight is positive and not below the bailout (POV-Ray's
// adc_bailout). A zero weight is never traced, even with bailout 0, so an all-features pipeline
// and a specialized one follow exactly the same branches.
bool worthTracing(vec3 weight) {
  float w = maxComponent(weight);
  return w > 0.0 && w >= frame.bailout;
}

// Radiance along one eye ray: the whole Whitted tree, depth first. At a dielectric both children
// are live; the refracted one is followed at once and the reflected one waits on the stack, so at
// most one branch per level waits: STACK_SIZE = max_depth never overflows (the host caps it at
// kMaxStackSize; deeper trees drop and count the extra branches).
vec3 traceRadiance(vec3 origin, vec3 dir) {
  vec3 radiance = vec3(0.0);
  PendingRay stack[STACK_SIZE];
  int sp = 0;
  PendingRay cur = PendingRay(origin, kRayEye << 16u, dir, vec3(1.0), kEmptyMedia);
  // TEXTURES: the current ray's cone (Ray Tracing Gems ch. 20) as x, its width at the ray's origin,
  // and y, its spread angle (radians: width gained per unit distance; negative while it converges).
  // The eye ray's starts at the pinhole with the pixel's angle; each surface passes its width on and
  // bends the spread by its curvature (coneAfterReflection, coneAfterRefraction). Outside
  // PendingRay, so without TEXTURES nothing of it is compiled.
  vec2 cone = vec2(0.0, frame.coneSpread);
  vec2 coneStack[STACK_SIZE];
  uint maxDepth = opaqueUniform(frame.maxDepth);
  // The loop's own exit leaves nothing pending. A tree cut short, by the ray budget below or by a
  // driver's loop limit (Mesa 22's llvmpipe ends every loop of an invocation once its SIMD group has
  // run 65535 loop iterations in all), still has its current ray or stacked branches, and the sample
  // is counted as truncated instead of passing silently as a darker pixel. (A flag set before the
  // break would be folded away by the compiler, which cannot know of a driver's limit.)
  bool haveNext = true;
  // Rays of this tree so far: a glass tree stops at kMaxTreeRays (counted as truncated below), on
  // every driver alike, rather than running 2^depth rays where no driver cuts the loop.
  uint treeRays = 0u;
  // RECORD_TREE: the record of the current ray's parent, and of each waiting branch's.
  uint parent = kTreeNoParent;
  uint parentStack[STACK_SIZE];
  while (true) {
    if (REFRACTION && treeRays == kMaxTreeRays) {
      if (RECORD_TREE) treeStopped();
      break;
    }
    treeRays++;
    uint depth = cur.depthKind & 0xFFFFu;
    countRay(cur.depthKind >> 16u, depth);
    TraceRay r = makeTraceRay(cur.origin, cur.dir);
    Hit hit = traceScene(r, kInfinity, false, false, depth == 0u); // depth 0: the eye ray
    vec3 w = cur.weight;
    uint medium = REFRACTION ? mediaTop(cur.media) : kNoMedium;
    if (REFRACTION && medium != kNoMedium) w *= beerLambert(absorptionPerUnit(loadMaterial(medium)), hit.t);
    uint record = kTreeNoParent;
    if (RECORD_TREE) {
      record = treeAppend(cur.depthKind >> 16u, parent, cur.origin, cur.dir, w);
      gTreeCurrent = record;
      gTreeWeight = w;
    }

    haveNext = false;
    if (hit.kind == kNoHit) {
      radiance += w * frame.background.rgb;
      if (RECORD_TREE) {
        treeSetHit(record, hit, vec3(0.0), 0u);
        treeAddContribution(record, w * frame.background.rgb);
      }
    } else {
      Surface s = surfaceAt(r, hit);
      Material mat = loadMaterial(s.material);
      if (RECORD_TREE) treeSetHit(record, hit, s.p, s.material);
      bool front = dot(s.ng, cur.dir) < 0.0;
      vec3 ngf = front ? s.ng : -s.ng;
      vec3 nsf = front ? s.ns : -s.ns;
      // The cone's width where it meets the surface (through a focus, a converging cone widens again),
      // and the surface's curvature as the ray sees it: positive where the surface bulges towards it.
      float coneWidth = 0.0;
      float curvature = 0.0;
      if (TEXTURES) {
        coneWidth = abs(cone.x + cone.y * hit.t);
        curvature = front ? s.curvature : -s.curvature;
        gConeFootprint = coneWidth / max(abs(dot(s.ng, cur.dir)), 1e-6);
      }
      radiance += w * localShade(mat, s, ngf, nsf, cur.dir, w);

      if ((REFLECTION || REFRACTION) && depth < maxDepth) {
        float kr = reflectance(mat);
        float kt = 0.0;
        float eta = 1.0; // n1 / n2 at a dielectric
        vec3 tdir = vec3(0.0);
        uvec2 tmedia = cur.media;
        if (REFRACTION && transmittance(mat) > 0.0) {
          float trans = transmittance(mat);
          float n1, n2;
          if (front) {
            n1 = mediumIor(medium);
            n2 = refractiveIndex(mat);
            tmedia = mediaPush(cur.media, s.material);
          } else {
            n1 = refractiveIndex(mat);
            tmedia = mediaRemove(cur.media, s.material);
            n2 = mediumIor(mediaTop(tmedia));
          }
          DielectricSplit split = dielectricSplit(cur.dir, nsf, ngf, n1, n2, FRESNEL == kFresnelSchlick);
          // Total internal reflection gives all of the transmitted share to the reflected branch.
          kr += trans * split.fresnel;
          kt = trans * (1.0 - split.fresnel);
          tdir = split.refracted;
          eta = n1 / n2;
        }
        vec3 wr = w * kr;
        bool doR = worthTracing(wr);
        if (COUNT_STATS && !doR && maxComponent(wr) > 0.0) gCount.bailoutSaved++;
        if (RECORD_TREE) treeAddCuts(record, !doR && maxComponent(wr) > 0.0 ? kTreeCutReflectionBailout : 0u);
        vec3 wt = vec3(0.0);
        bool doT = false;
        if (REFRACTION) {
          wt = w * kt;
          doT = worthTracing(wt);
          if (COUNT_STATS && !doT && maxComponent(wt) > 0.0) gCount.bailoutSaved++;
          if (RECORD_TREE) treeAddCuts(record, !doT && maxComponent(wt) > 0.0 ? kTreeCutRefractionBailout : 0u);
        }
        uint nextDepth = depth + 1u;
        vec2 reflectedCone = vec2(0.0);
        if (TEXTURES) reflectedCone = coneAfterReflection(cone.y, coneWidth, curvature);
        PendingRay reflected;
        if (doR) {
          vec3 ro = ROBUST ? spawnOrigin(s.p, ngf, s.errorBound) : s.p;
          reflected = PendingRay(ro, nextDepth | (kRayReflection << 16u), mirrorDirection(cur.dir, nsf, ngf), wr,
                                 cur.media);
        }
        if (REFRACTION && doT) {
          vec3 to = ROBUST ? spawnOrigin(s.p, -ngf, s.errorBound) : s.p;
          if (doR) {
            if (sp < STACK_SIZE) {
              if (TEXTURES) coneStack[sp] = reflectedCone;
              if (RECORD_TREE) parentStack[sp] = record;
              stack[sp++] = reflected;
            } else {
              if (COUNT_STATS) gCount.stackOverflow++;
              if (RECORD_TREE) treeAddCuts(record, kTreeCutStack);
            }
          }
          cur = PendingRay(to, nextDepth | (kRayRefraction << 16u), tdir, wt, tmedia);
          if (TEXTURES) cone = coneAfterRefraction(cone.y, coneWidth, curvature, eta);
          haveNext = true;
        } else if (doR) {
          cur = reflected;
          if (TEXTURES) cone = reflectedCone;
          haveNext = true;
        }
        if (RECORD_TREE) parent = record;
      } else if (RECORD_TREE) {
        // At the depth cap: the branches this surface would have had.
        bool branches = (REFLECTION || REFRACTION) && (reflectance(mat) > 0.0 || transmittance(mat) > 0.0);
        treeAddCuts(record, branches ? kTreeCutDepth : 0u);
      }
    }
    if (!haveNext) {
      // Without refraction nothing is ever pushed: the stack code compiles out.
      if (!REFRACTION || sp == 0) break;
      if (TEXTURES) cone = coneStack[sp - 1];
      if (RECORD_TREE) parent = parentStack[sp - 1];
      cur = stack[--sp];
      haveNext = true;
    }
  }
  // Only trees with glass grow exponentially; without REFRACTION a tree is at most max_depth + 1
  // rays, and keeping the check out keeps `haveNext` out of the loop's state (~10 % on the showcase).
  if (REFRACTION) gCount.truncated += uint(haveNext || sp != 0);
  return radiance;
}

// One sample: the eye ray through `offset` in the pixel, from the eye (the pinhole) or, THIN_LENS,
// from the lens point `lensUv` (lensSample: the sample's own point, decorrelated from the offset).
vec3 traceSample(uvec2 pixel, vec2 offset, vec2 lensUv) {
  vec3 origin = frame.cameraOrigin.xyz;
  vec3 dir;
  if (THIN_LENS) {
    thinLensRay(vec2(pixel) + offset, lensUv, origin, dir);
  } else {
    dir = eyeRayDir(vec2(pixel) + offset);
  }
  vec3 radiance = traceRadiance(origin, dir);
  if (!isFiniteVec(radiance)) {
    if (COUNT_STATS) gCount.nonFinite++;
    radiance = vec3(0.0);
  }
  return radiance;
}

// What seeds a pixel's sample sequences: its index in the image, moved by render.seed times an odd
// constant (the golden ratio's 32-bit fraction), so that every seed gives every pixel another key
// and seed 0 the key it always had.
uint pixelSequenceKey(uvec2 pixel) {
  return pixel.y * frame.imageSize.x + pixel.x + frame.sampleSeed * 0x9e3779b9u;
}

// Sum of `count` samples starting at `base` in the pixel's sequence.
vec3 sampleSum(uvec2 pixel, uint pixelIndex, uint base, uint count, bool center) {
  vec3 sum = vec3(0.0);
  if (count == 0u) return sum;
  // Tested at the bottom (a `for` would run one more whole sample, masked off, on llvmpipe).
  uint k = 0u;
  while (true) {
    vec2 offset = (CENTER_SAMPLE || center) ? vec2(0.5) : sobolOwenSample(base + k, hashPcg(pixelIndex));
    vec2 lensUv = THIN_LENS ? lensSample(base + k, hashPcg(pixelIndex)) : vec2(0.0);
    if (RECORD_TREE) gTreeSample = base + k;
    sum += traceSample(pixel, offset, lensUv);
    ++k;
    if (k >= count) break;
  }
  return sum;
}

vec3 averaged(vec4 p) { return pixelSampleCount(p) > 0.0 ? pixelRadianceSum(p) / pixelSampleCount(p) : vec3(0.0); }

// Adaptive antialiasing (POV-Ray's +A): resample a pixel when its colour differs from a neighbour's
// by more than the threshold in some channel (colours clamped to [0, 1], as they will be displayed).
vec4 prevPixel(uvec2 p) { return imageLoad(prevTexels, int((p.y - pc.prevRow0) * frame.imageSize.x + p.x)); }

bool needsRefinement(uvec2 pixel) {
  uvec2 size = frame.imageSize;
  vec3 c = clamp(averaged(prevPixel(pixel)), 0.0, 1.0);
  ivec2 offsets[4] = ivec2[4](ivec2(-1, 0), ivec2(1, 0), ivec2(0, -1), ivec2(0, 1));
  // Selects, not `continue` or `return`: a loop the compiler cannot unroll costs one more whole
  // turn, masked off, on CPU drivers. A neighbour outside the image, or outside the uploaded rows
  // (never the case for the host's bands), is read clamped and does not count.
  ivec2 lo = ivec2(0, int(pc.prevRow0));
  ivec2 hi = max(ivec2(int(size.x), int(pc.prevRow0 + pc.prevRows)) - 1, lo);
  bool refine = false;
  for (int i = 0; i < 4; ++i) {
    ivec2 q = ivec2(pixel) + offsets[i];
    bool counts = q.x >= 0 && q.y >= 0 && q.x < int(size.x) && q.y < int(size.y) &&
                  uint(q.y) >= pc.prevRow0 && uint(q.y) < pc.prevRow0 + pc.prevRows;
    vec3 n = clamp(averaged(prevPixel(uvec2(clamp(q, lo, hi)))), 0.0, 1.0);
    refine = refine || (counts && maxComponent(abs(n - c)) > frame.adaptiveThreshold);
  }
  return refine;
}

// One atomic per counter per subgroup: subgroupAdd sums the invocations' counters, one invocation
// adds the totals. No barrier, so CPU drivers need no coroutine to run the workgroup.
// (A macro: GLSL cannot pass a buffer member by reference to an atomic.)
#define ADD_COUNTER(value, member)                                                                   \
  {                                                                                                  \
    uint total = subgroupAdd(value);                                                                 \
    if (subgroupElect() && total != 0u) atomicAdd(stats.member, total);                              \
  }

// On CPU drivers every subgroup sum, every atomic and every branch around one is a loop over the
// lanes. Flushed one by one, the nine counters were 5.2 M of the showcase's 23.6 M instructions
// (160 x 120, depth 3, callgrind); summed four at a time, with every atomic in one elected branch
// and only the counters the pipeline can count, 2.5 M.
void flushStats() {
  if (REFRACTION) ADD_COUNTER(gCount.truncated, truncated);
  if (!COUNT_STATS) return;
  const bool BOUNCES = REFLECTION || REFRACTION; // a dielectric reflects too
  uvec4 rays = subgroupAdd(uvec4(gCount.eyeRays, gCount.shadowRays, gCount.reflectionRays, gCount.bailoutSaved));
  uvec4 rest = (REFRACTION || REFINE_PASS)
                   ? subgroupAdd(uvec4(gCount.refractionRays, gCount.stackOverflow, gCount.refinedPixels, gCount.nonFinite))
                   : uvec4(0u, 0u, 0u, subgroupAdd(gCount.nonFinite));
  uint deepest = BOUNCES ? subgroupMax(gCount.maxDepth) : 0u;
  uint faint = SPECULAR_ONLY ? subgroupAdd(gCount.faintHighlights) : 0u;
  if (subgroupElect()) {
    atomicAdd(stats.eyeRays, rays.x);
    if (SHADOWS) atomicAdd(stats.shadowRays, rays.y);
    if (BOUNCES) {
      atomicAdd(stats.reflectionRays, rays.z);
      if (rays.w != 0u) atomicAdd(stats.bailoutSaved, rays.w);
      atomicMax(stats.maxDepth, deepest);
    }
    if (REFRACTION) {
      atomicAdd(stats.refractionRays, rest.x);
      if (rest.y != 0u) atomicAdd(stats.stackOverflow, rest.y);
    }
    if (REFINE_PASS) atomicAdd(stats.refinedPixels, rest.z);
    if (rest.w != 0u) atomicAdd(stats.nonFinite, rest.w);
    if (faint != 0u) atomicAdd(stats.faintHighlights, faint);
  }
}

// A progressive pass (host/render/adaptive.h): the host lists the pixels still open, (x, y) as
// floats, so SIMD lanes stay full however few remain. Two texels per entry: (sum rgb, samples) and
// (sum rgb of the pass's first half, rays traced): the samples whose sequence index is below
// pc.splitBase. From the halves of its passes the host estimates each pixel's standard error. The
// passes before the first decision run as one, with two texels per entry for each of them.
//
// `pc.param` lanes (a power of two; 1 when the dispatch takes one sample per pixel) share one entry
// and trace its samples side by side, lane j sample j of each round: late passes list scattered
// pixels, and lanes of eight different pixels walk different nodes, materials and textures, where a
// pixel's own samples, a fraction of a pixel apart, take nearly the same path. Work is assigned by
// subgroup, so a pixel's lanes are one subgroup's whatever the driver's mapping of invocations.
// Whether the list pass writes (and reads) pass `pass`'s first-half texel: not where the host's
// kFlagNoHalf0 bit says the half is empty.
bool hasHalfTexel(uint flags, uint pass) { return (flags & (kFlagNoHalf0 << pass)) == 0u; }

void listPass() {
  uint lanes = min(max(opaqueUniform(pc.param), 1u), gl_SubgroupSize);
  uint item = gl_WorkGroupID.x * (kWorkgroupSizeX * kWorkgroupSizeY) + gl_SubgroupID * gl_SubgroupSize +
              gl_SubgroupInvocationID;
  uint entry = item / lanes;
  uint lane = gl_SubgroupInvocationID & (lanes - 1u);
  uint firstLane = gl_SubgroupInvocationID - lane; // of this entry's lanes
  // Past the list's end a lane traces nothing but still takes part in its subgroup's shuffles.
  bool listed = entry < pc.tileSize.x;
  entry = min(entry, pc.tileSize.x - 1u);
  uvec2 pixel = uvec2(imageLoad(prevTexels, int(entry)).xy);
  loadEntryPoints(pixel, 0u); // the host found them for the whole image, per lane's own tile
  uint index = pixelSequenceKey(pixel);
  uint count = opaqueUniform(pc.sampleCount);
  // Up to three of the schedule's passes in this one (pc.segmentEnd0/1), each summed on its own, in
  // two texels per entry and pass: (sum rgb, samples) and (sum rgb of the pass's first half, rays).
  uint end0 = opaqueUniform(pc.segmentEnd0), end1 = opaqueUniform(pc.segmentEnd1);
  uint passes = end0 == 0u ? 1u : (end1 == 0u ? 2u : 3u);
  if (end0 == 0u) end0 = 0xFFFFFFFFu;
  if (end1 == 0u) end1 = 0xFFFFFFFFu;
  uint out0 = 2u * entry * passes; // the entry's first texel
  bool writes = listed && lane == 0u;
  uint base = opaqueUniform(pc.sampleBase);
  uint current = base < end0 ? 0u : (base < end1 ? 1u : 2u); // the pass of the dispatch's first sample
  // The sums of that pass start from the entry's earlier dispatches where it began in one of them:
  // each sample is added to its pass's running sum one at a time, in the sequence's order, whether
  // the host gave a dispatch one sample or several and however many lanes traced them, so the float
  // rounding (and the image) does not depend on how the host split the pass.
  uint began = current == 0u ? 0u : (current == 1u ? end0 : end1); // pass 0: the host's flag says
  // A pass of one sample has an empty first half: where one dispatch takes the whole list pass, the
  // host leaves its texel out (kFlagNoHalf0), which spares two of the six stores of the passes before
  // the first decision at min_spp 4.
  uint flags = opaqueUniform(pc.flags);
  bool resume = (flags & kFlagAccumulate) != 0u && (current == 0u || began < base);
  vec4 sum = vec4(0.0);
  vec4 firstHalf = vec4(0.0);
  if (resume) {
    sum = imageLoad(imageTexels, int(out0 + 2u * current));
    if (hasHalfTexel(flags, current)) firstHalf = imageLoad(imageTexels, int(out0 + 2u * current + 1u));
  }
  // One turn per pass, each with its own loop over its samples, so that the common case, one pass,
  // runs the loop it always did.
  uint round0 = 0u; // this round's first sample
  while (true) {
    uint passEnd = min(count, (current == 0u ? end0 : (current == 1u ? end1 : 0xFFFFFFFFu)) - base);
    uint split = current == 0u ? opaqueUniform(pc.splitBase)
                               : (current == 1u ? opaqueUniform(pc.splitBase1) : opaqueUniform(pc.splitBase2));
    uint passFirst = round0;
    while (true) { // tested at the bottom, as in sampleSum
      uint k = round0 + lane;
      vec3 radiance = vec3(0.0);
      if (listed && k < passEnd) {
        vec2 lensUv = THIN_LENS ? lensSample(base + k, hashPcg(index)) : vec2(0.0);
        radiance = traceSample(pixel, sobolOwenSample(base + k, hashPcg(index)), lensUv);
      }
      if (lanes == 1u) {
        sum.rgb += radiance;
        if (base + k < split) firstHalf.rgb += radiance;
      } else {
        for (uint j = 0u; j < lanes; ++j) {
          vec3 r = subgroupShuffle(radiance, firstLane + j);
          if (round0 + j < passEnd) {
            sum.rgb += r;
            if (base + round0 + j < split) firstHalf.rgb += r;
          }
        }
      }
      round0 += lanes;
      if (round0 >= passEnd) break;
    }
    sum.w += float(passEnd - passFirst);
    round0 = passEnd; // a pass's samples need not fill its last round
    if (round0 >= count) break;
    if (writes) {
      imageOut[out0 + 2u * current] = sum;
      if (hasHalfTexel(flags, current)) imageOut[out0 + 2u * current + 1u] = firstHalf;
    }
    sum = vec4(0.0);
    firstHalf = vec4(0.0);
    current++;
  }
  uint rays = COUNT_STATS ? gCount.eyeRays + gCount.shadowRays + gCount.reflectionRays + gCount.refractionRays : 0u;
  if (COUNT_STATS && lanes > 1u) {
    uint own = rays;
    rays = 0u;
    for (uint j = 0u; j < lanes; ++j) rays += subgroupShuffle(own, firstLane + j);
  }
  if (writes) {
    firstHalf.w += float(rays); // all of the dispatch's, with its last pass's sums (the host adds them up)
    imageOut[out0 + 2u * current] = sum;
    imageOut[out0 + 2u * current + 1u] = firstHalf;
  }
}

void main() {
  gDynamicZero = stats.zero;
  loadSceneRegisters(); // before any branch (scene_access.glsl)
  if (LIST_PASS) {
    listPass();
    flushStats();
    return;
  }
  // llvmpipe hands each of its threads one contiguous block of a dispatch's workgroups, which in
  // order is a band of tile rows: one thread would trace the sky while the other traced the scene.
  // Workgroup row r takes tile row r * stride mod rows (the host's stride is coprime to the rows and
  // near 0.618 of them), so every block holds rows from all over the dispatch. The pixels are the
  // same, only which workgroup traces which (Renderer::recordDispatch, spreadStride).
  uint tileRow = (gl_WorkGroupID.y * max(opaqueUniform(pc.param), 1u)) % gl_NumWorkGroups.y;
  uvec2 local = invocationPixelIn(uvec2(gl_WorkGroupID.x, tileRow)); // 4 x 2 blocks per SIMD batch
  uvec2 pixel = pc.tileOrigin + local;
  // The dispatch is rounded up to whole workgroups: invocations past the tile or image do nothing,
  // but still take part in flushStats' subgroup sums.
  bool inside = all(lessThan(local, pc.tileSize)) && all(lessThan(pixel, frame.imageSize));
  if (inside) {
    loadEntryPoints(pixel, pc.imageRow0);
    uint index = pixelSequenceKey(pixel);
    uint slot = (pixel.y - pc.imageRow0) * frame.imageSize.x + pixel.x;
    if (REFINE_PASS) {
      // Refined pixels get spp fresh samples; the others keep their base sample. The host may
      // split the samples over several dispatches; the later ones accumulate (refined pixels only).
      bool accumulate = (opaqueUniform(pc.flags) & kFlagAccumulate) != 0u;
      if (needsRefinement(pixel)) {
        if (COUNT_STATS && !accumulate) gCount.refinedPixels++;
        vec4 result = vec4(sampleSum(pixel, index, pc.sampleBase, opaqueUniform(pc.sampleCount), false),
                           float(pc.sampleCount));
        if (accumulate) result += imageLoad(imageTexels, int(slot));
        imageOut[slot] = result;
      } else if (!accumulate) {
        imageOut[slot] = prevPixel(pixel);
      }
    } else {
      bool center = (opaqueUniform(pc.flags) & kFlagCenterSample) != 0u;
      vec4 result = vec4(sampleSum(pixel, index, pc.sampleBase, opaqueUniform(pc.sampleCount), center),
                         float(pc.sampleCount));
      bool accumulate = (opaqueUniform(pc.flags) & kFlagAccumulate) != 0u;
      if (accumulate) result += imageLoad(imageTexels, int(slot));
      imageOut[slot] = result;
      if (PIXEL_RAYS) {
        uint rays = gCount.eyeRays + gCount.shadowRays + gCount.reflectionRays + gCount.refractionRays;
        pixelRays[slot] = accumulate ? pixelRays[slot] + rays : rays;
      }
    }
  }
  flushStats();
}
