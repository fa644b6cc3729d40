// The ray-tree recorder (`render --inspect`): with kSpecRecordTree on, the trace kernel appends a
// TreeRay (shared/gpu_types.h) for every ray it traces, so the host can print the pixel's whole
// Whitted tree. Off, every call site sits behind `if (RECORD_TREE)` and folds away.
//
// trace.comp defines VKRAY_TREE_RECORDER; the other kernels that include shade.glsl get the empty
// stand-ins below, with no buffer binding. Built with VKRAY_NO_TREE_RECORDER, trace.comp gets the
// stand-ins too: tests/ray_tree_test.cpp checks that the real recorder, specialized off, folds to
// the same code as that build.
#ifndef VKRAY_TREE_RECORD_GLSL
#define VKRAY_TREE_RECORD_GLSL

#if defined(VKRAY_TREE_RECORDER) && !defined(VKRAY_NO_TREE_RECORDER)

layout(constant_id = kSpecRecordTree) const bool RECORD_TREE = false;

// Only the one invocation of the inspected pixel records (the host dispatches a 1 x 1 tile), so
// plain reads and writes suffice.
layout(std430, binding = kBindingRayTree) restrict buffer TreeRayBuffer {
  TreeRayHeader treeHeader;
  TreeRay treeRays[];
};

// The record of the ray being shaded (its shadow rays' parent), its weight, and the sample.
uint gTreeCurrent;
vec3 gTreeWeight;
uint gTreeSample;
// What the last shadow ray stopped at (shadowTransmittance): a primitive and a point.
uint gShadowBlockKind;
uint gShadowBlockIndex;
vec3 gShadowBlockPoint;

// Appends a record; returns its index, or kTreeNoParent when the buffer is full (counted).
uint treeAppend(uint kind, uint parent, vec3 origin, vec3 dir, vec3 weight) {
  uint i = treeHeader.counts.x;
  if (i >= treeHeader.counts.y) {
    treeHeader.counts.z++;
    return kTreeNoParent;
  }
  treeHeader.counts.x = i + 1u;
  TreeRay r;
  r.origin = vec4(origin, 0.0);
  r.direction = vec4(dir, 0.0);
  r.weight = vec4(weight, 0.0);
  r.contribution = vec4(0.0);
  r.point = vec4(0.0);
  r.what = uvec4(kind, kTreeMiss, 0u, parent);
  r.where = uvec4(kNoHit, 0u, 0u, gTreeSample);
  treeRays[i] = r;
  return i;
}

// What a traced ray met: the surface at `p` (distance t), or nothing.
void treeSetHit(uint i, Hit hit, vec3 p, uint material) {
  if (i == kTreeNoParent) return;
  treeRays[i].origin.w = hit.kind == kNoHit ? 0.0 : hit.t;
  treeRays[i].point = vec4(p, 0.0);
  treeRays[i].what.y = hit.kind == kNoHit ? kTreeMiss : kTreeSurface;
  treeRays[i].where.xyz = uvec3(hit.kind, hit.index, material);
}

void treeAddContribution(uint i, vec3 c) {
  if (i != kTreeNoParent) treeRays[i].contribution.rgb += c;
}

void treeAddCuts(uint i, uint cuts) {
  if (i != kTreeNoParent) treeRays[i].what.z |= cuts;
}

void treeStopped() { treeHeader.counts.w = 1u; }

// Before a shadow ray: nothing blocks it yet.
void treeShadowStart() { gShadowBlockKind = kNoHit; }

void treeNoteBlocker(Hit h, vec3 p) {
  gShadowBlockKind = h.kind;
  gShadowBlockIndex = h.index;
  gShadowBlockPoint = p;
}

// An any-hit shadow query's result (opaque shadows): the blocker it found, if any.
void treeNoteShadowHit(Hit h, vec3 origin, vec3 dir, float dist) {
  if (dist > 0.0 && h.kind != kNoHit) treeNoteBlocker(h, origin + h.t * dir);
}

// The shadow ray from `origin` to light `light` of the ray being shaded, after it was traced
// (traced: false when the light casts no shadow and no ray was sent), and the light's share.
void treeRecordShadow(uint light, vec3 origin, vec3 lightPos, bool traced, vec3 visible, vec3 contribution) {
  vec3 toLight = lightPos - origin;
  float dist = length(toLight);
  uint i = treeAppend(kTreeShadow, gTreeCurrent, origin, toLight / dist, gTreeWeight * visible);
  if (i == kTreeNoParent) return;
  bool blocked = traced && gShadowBlockKind != kNoHit && maxComponent(visible) <= 0.0;
  treeRays[i].origin.w = blocked ? length(gShadowBlockPoint - origin) : dist;
  treeRays[i].point = vec4(blocked ? gShadowBlockPoint : lightPos, 0.0);
  treeRays[i].what.y = !traced ? kTreeUnshadowed : blocked ? kTreeBlocked : kTreeLightReached;
  treeRays[i].where = uvec4(blocked ? gShadowBlockKind : kNoHit, blocked ? gShadowBlockIndex : 0u, light, gTreeSample);
  treeRays[i].contribution = vec4(contribution, 0.0);
}

#else

const bool RECORD_TREE = false;
uint gTreeCurrent;
vec3 gTreeWeight;
uint gTreeSample;
uint treeAppend(uint kind, uint parent, vec3 origin, vec3 dir, vec3 weight) { return kTreeNoParent; }
void treeSetHit(uint i, Hit hit, vec3 p, uint material) {}
void treeAddContribution(uint i, vec3 c) {}
void treeAddCuts(uint i, uint cuts) {}
void treeStopped() {}
void treeShadowStart() {}
void treeNoteBlocker(Hit h, vec3 p) {}
void treeNoteShadowHit(Hit h, vec3 origin, vec3 dir, float dist) {}
void treeRecordShadow(uint light, vec3 origin, vec3 lightPos, bool traced, vec3 visible, vec3 contribution) {}

#endif

#endif
