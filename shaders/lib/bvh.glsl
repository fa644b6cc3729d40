// The BVH walk: each tile's entry points, leaf decoding, the robust slab test and the lockstep
// while-while traversal.
#ifndef VKRAY_BVH_GLSL
#define VKRAY_BVH_GLSL

#extension GL_KHR_shader_subgroup_ballot : require // traverseBvh's lockstep

#include "primitives.glsl"

// The invocation's tile's entry points (gpu_types.h), loaded by loadEntryPoints(); with them an eye
// ray's walk starts from the subtrees its tile's frustum reaches instead of the root.
TileEntryPoints gEntryPoints = TileEntryPoints(uvec4(kBvhNoRef), uvec4(kBvhNoRef, kBvhNoRef, kBvhNoRef, 0u));

// Call in main() with the invocation's pixel, when ENTRY_POINTS; `row0` is the band's first row.
void loadEntryPoints(uvec2 pixel, uint row0) {
  if (!ENTRY_POINTS) return;
  uint tilesX = (frame.imageSize.x + kEntryTileSize - 1u) / kEntryTileSize;
  uint tile = ((pixel.y - row0) / kEntryTileSize) * tilesX + pixel.x / kEntryTileSize;
  gEntryPoints = TileEntryPoints(texelFetch(entryTexels, int(2u * tile)), texelFetch(entryTexels, int(2u * tile + 1u)));
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

// A walk that starts at the root (traverseBvh's shadowStart for every other ray).
ShadowStart fromTheRoot() {
  return ShadowStart(uvec4(kBvhNoRef), uvec4(kBvhNoRef, kBvhNoRef, kBvhNoRef, 0u));
}

// A shadow ray's entry points (host/accel/shadow_entries.h) when it leaves triangle `triangle` for
// light `light`: the two texels of gpu_types.h's layout. From the root (x kBvhNoRef) where the
// scene has no table or the ray leaves another kind of surface.
ShadowStart shadowEntryPoints(uint kind, uint triangle, uint light) {
  if (!SHADOW_ENTRIES || kind != kPrimTriangle || frame.shadowEntryBase == 0u) return fromTheRoot();
  int texel = int(frame.shadowEntryBase + 2u * (triangle * frame.shadowEntryLights + light));
  return ShadowStart(imageLoad(nodeTexels, texel), imageLoad(nodeTexels, texel + 1));
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
//
// `shadowStart` (SHADOW_ENTRIES): a shadow ray's entry points, as shadowEntryPoints() gives them;
// a.x kBvhNoRef walks from the root.
void traverseBvh(TraceRay r, inout Hit hit, bool anyHit, bool fromEntryPoints, ShadowStart shadowStart) {
  // The builder caps the depth at kBvhStackSize; a walk from entry points starts with up to
  // kEntryStackSlots of them stacked.
  uint stack[kBvhStackSize + kEntryStackSlots];
  int sp = 0;
  uint ref = opaqueUniform(frame.bvhRoot); // the root
  if (ENTRY_POINTS) {
    // Constant slots: plain vector stores, written whether or not this ray starts from them.
    stack[0] = entryStackWord(gEntryPoints, 0u);
    stack[1] = entryStackWord(gEntryPoints, 1u);
    stack[2] = entryStackWord(gEntryPoints, 2u);
    stack[3] = entryStackWord(gEntryPoints, 3u);
    stack[4] = entryStackWord(gEntryPoints, 4u);
    stack[5] = entryStackWord(gEntryPoints, 5u);
    if (fromEntryPoints) {
      ref = entryStart(gEntryPoints);
      sp = int(entryStackHeight(gEntryPoints));
    }
  }
  if (SHADOW_ENTRIES && !fromEntryPoints) {
    // Constant slots again (after the eye rays' words, which they replace): the shadow ray's start
    // and up to six subtrees stacked under it.
    stack[0] = shadowStart.a.y;
    stack[1] = shadowStart.a.z;
    stack[2] = shadowStart.a.w;
    stack[3] = shadowStart.b.x;
    stack[4] = shadowStart.b.y;
    stack[5] = shadowStart.b.z;
    if (shadowStart.a.x != kBvhNoRef) {
      ref = shadowStart.a.x;
      sp = int(shadowStart.b.w);
    } else if (ROBUST && shadowStart.b.w == kShadowNothingBetween) {
      // Nothing in the tree can stop a ray from this triangle to this light: no walk. Only for
      // robust origins, which leave the surface on the light's side; naive ones sit on it and
      // show the acne that numerics mode exists to show.
      ref = kBvhNoRef;
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
  // leaves the closest distance the same. In a shallow tree (BVH_STEPS_PER_VOTE 1) only the
  // descent loop keeps its ballot: a lane enters it and leaves the walk on its own condition, so
  // the mask is fixed within each run of the descent loop but not for the whole walk (`descend`).
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
    // Whether to descend. In a shallow tree (one step per vote) each lane branches on its own
    // condition, and llvmpipe skips the loop when no lane takes the branch: one ballot fewer per
    // turn, and another where a finished lane leaves the walk below (4.3 % fewer instructions at
    // 1 k triangles). In a deep tree every lane enters while any must: lanes left out would change
    // the masked stack writes' per-lane branches from turn to turn, which cost more time there than
    // the ballots (docs/performance.md, "Two steps per vote in deep trees").
    bool descend = BVH_STEPS_PER_VOTE == 1u ? ref < kBvhLeafFlag : anyLane(ref < kBvhLeafFlag);
    if (descend) {
      while (true) {
        // BVH_STEPS_PER_VOTE steps before each vote (one, or two in a deep tree). A second step
        // changes nothing of a lane that already holds a leaf or has finished (`descending`), and
        // takes a lane with a leaf set aside one step on towards its second, as a vote that found
        // other lanes still descending would: the same closest hit.
        for (uint step = 0u; step < BVH_STEPS_PER_VOTE; ++step) {
          bool descending = ref < kBvhLeafFlag; // else the step changes nothing of this lane's
          BvhWideNode node = loadBvhNode(descending ? ref : 0u);
          float enter0 = boxEntry(r, node.min0, node.max0, hit.t);
          float enter1 = boxEntry(r, node.min1, node.max1, hit.t);
          uint ref0 = node.ref0;
          uint ref1 = node.ref1;
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
        }
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
    // A finished lane leaves; in a deep tree it stays (masked by its own steps) until every lane is
    // done, for the reason given for `descend` above.
    if (BVH_STEPS_PER_VOTE == 1u ? ref == kBvhNoRef : !anyLane(ref != kBvhNoRef)) break;
  }
}

#endif
