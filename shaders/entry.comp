// Entry points for eye rays: for each tile of 8 x 8 pixels of the band (one workgroup of the trace
// kernels), the BVH subtrees that the tile's eye rays can reach, found once for the tile instead of
// by each of its 64 rays walking down from the root (the entry-point search of Reshetov, Soupikov
// and Hurley, "Multi-Level Ray Tracing Algorithm", SIGGRAPH 2005, with a budget instead of their
// split heuristics).
//
// Every eye ray of the tile leaves the eye through the tile's pixel rectangle (widened by a margin
// for rounding), so it lies in the frustum of four planes through the eye and the rectangle's corners; a
// primitive the ray hits lies in the frustum, and so does some point of every box that contains
// the primitive. The search walks the tree from the root, nearest box first, and drops subtrees
// whose box lies wholly outside a plane (tested with the box's corner farthest along the plane's
// normal, conservatively for rounding). It keeps expanding while the subtrees kept so far, those
// waiting on its stack and the children just found fit kEntryPointsMax, and keeps a node whole
// where they would not. The result, nearest first, is written as the walk's starting state
// (gpu_types.h): an eye ray then finds exactly the hit it would find from the root, having
// skipped the levels above the entry points and every subtree outside its tile. Pinhole rays only:
// with a thin lens (THIN_LENS) eye rays start off the eye, and the host does not run this pass.
#version 460
#extension GL_GOOGLE_include_directive : require

#include "shared/gpu_types.h"

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

#include "lib/scene.glsl"

layout(std430, binding = kBindingEntryPoints) writeonly restrict buffer EntryPoints { uvec4 entryPoints[]; };
layout(std430, binding = kBindingStats) readonly buffer StatsBuffer { RayStats stats; };
layout(push_constant) uniform Push { PushConstants pc; };

vec3 gEye;
vec3 gFrustum[5]; // inward normals: four sides through the eye, and the plane facing the tile's centre

// False only if the box lies wholly on the outer side of some plane. The box corner farthest along
// a plane's normal decides; its distance counts as outside only beyond the rounding error bound of
// its computation (a few ulps of the sum of the terms' magnitudes).
bool boxInFrustum(vec3 bmin, vec3 bmax) {
  bool inside = true;
  for (int k = 0; k < 5; ++k) {
    vec3 n = gFrustum[k];
    vec3 d = mix(bmin, bmax, greaterThan(n, vec3(0.0))) - gEye;
    inside = inside && dot(n, d) >= -1e-6 * dot(abs(n), abs(d));
  }
  return inside;
}

// The search's two short lists live in registers: each is read and written only through these,
// whose loops unroll into constant indices, so every slot is a register of its own and a write is
// a select per slot. Indexed by the lane's own count they would be private arrays, which llvmpipe
// writes and reads lane by lane with a branch per lane: the pass took a tenth of the eye rays' time
// at 1 k triangles (docs/performance.md, "Entry points").
#define ENTRY_LIST uint[kEntryPointsMax]

void listPut(inout ENTRY_LIST list, int i, uint value) {
  for (int k = 0; k < int(kEntryPointsMax); ++k) list[k] = k == i ? value : list[k];
}

uint listGet(ENTRY_LIST list, int i) {
  uint value = kBvhNoRef;
  for (int k = 0; k < int(kEntryPointsMax); ++k) value = k == i ? list[k] : value;
  return value;
}

float boxDistance2(vec3 bmin, vec3 bmax) {
  vec3 d = clamp(gEye, bmin, bmax) - gEye;
  return dot(d, d);
}

void main() {
  gDynamicZero = stats.zero;
  loadSceneRegisters(); // before any branch (scene_access.glsl)
  uint tilesX = (frame.imageSize.x + kEntryTileSize - 1u) / kEntryTileSize;
  uint tileRows = (pc.tileSize.y + kEntryTileSize - 1u) / kEntryTileSize;
  uint tile = gl_GlobalInvocationID.x;
  if (tile >= tilesX * tileRows) return;

  // The tile's pixel rectangle in image coordinates, widened on every side by a margin that
  // covers the rounding of the ray directions (the trace kernels' and these): sample positions
  // lie within their pixel. A direction's components carry errors of a few ulps of |F| + |R| + |U|
  // (the camera vectors), which the margin bounds generously in pixels: 1/16 of a pixel at
  // ordinary sizes, about one pixel for a 0.05 degree view 16384 pixels tall.
  vec3 F = frame.cameraForward.xyz;
  vec3 R = frame.cameraRight.xyz;
  vec3 U = frame.cameraUp.xyz;
  vec2 size = vec2(frame.imageSize);
  float pixel = min(2.0 * length(R) / size.x, 2.0 * length(U) / size.y); // in direction units
  float margin = 0.0625 + 1e-6 * (length(F) + length(R) + length(U)) / pixel;
  vec2 lo = vec2(float((tile % tilesX) * kEntryTileSize), float(pc.imageRow0 + (tile / tilesX) * kEntryTileSize)) - margin;
  vec2 hi = lo + float(kEntryTileSize) + 2.0 * margin;
  vec3 c00 = imagePlaneDir(lo);
  vec3 c10 = imagePlaneDir(vec2(hi.x, lo.y));
  vec3 c11 = imagePlaneDir(hi);
  vec3 c01 = imagePlaneDir(vec2(lo.x, hi.y));
  vec3 centre = imagePlaneDir(0.5 * (lo + hi));
  gEye = frame.cameraOrigin.xyz;
  // Each side's plane holds the eye, a corner ray and the side's direction in the image plane. The
  // same plane as the cross product of the side's two corner rays, but without its cancellation:
  // those rays are nearly parallel when pixels are small, their cross product then mostly rounding.
  vec3 alongRow = R * (2.0 * (hi.x - lo.x) / size.x);
  vec3 alongColumn = U * (-2.0 * (hi.y - lo.y) / size.y);
  gFrustum[0] = cross(c00, alongRow);
  gFrustum[1] = cross(c10, alongColumn);
  gFrustum[2] = cross(c11, alongRow);
  gFrustum[3] = cross(c01, alongColumn);
  for (int k = 0; k < 4; ++k) gFrustum[k] = dot(gFrustum[k], centre) < 0.0 ? -gFrustum[k] : gFrustum[k];
  gFrustum[4] = centre;
  // A frustum that is not a narrow cone (a tile spanning a very wide field of view) is not
  // culled against: its planes may not bound it. The walk then starts at the root.
  float cosMin = 0.25;
  bool narrow = true;
  vec3 cn = normalize(centre);
  narrow = narrow && dot(normalize(c00), cn) > cosMin && dot(normalize(c10), cn) > cosMin;
  narrow = narrow && dot(normalize(c11), cn) > cosMin && dot(normalize(c01), cn) > cosMin;
  if (!narrow) {
    for (int k = 0; k < 5; ++k) gFrustum[k] = vec3(0.0);
  }

  uint found[kEntryPointsMax];
  uint pending[kEntryPointsMax];
  for (int k = 0; k < int(kEntryPointsMax); ++k) {
    found[k] = kBvhNoRef;
    pending[k] = kBvhNoRef;
  }
  int count = 0;
  int top = 0;
  uint root = opaqueUniform(frame.bvhRoot);
  if (root != kBvhNoRef) listPut(pending, top++, root);
  // Invariant: count + top <= kEntryPointsMax. The loop is tested at the bottom (bvh.glsl).
  if (top > 0) {
    while (true) {
      uint ref = listGet(pending, --top);
      bool expanded = false;
      if (ref < kBvhLeafFlag) {
        BvhWideNode node = loadBvhNode(ref);
        bool in0 = boxInFrustum(node.min0, node.max0);
        bool in1 = boxInFrustum(node.min1, node.max1);
        int children = int(in0) + int(in1);
        // A leaf is never an entry point: the ray would test its primitives without testing its
        // box, which only the record above holds. A record with a leaf child stays whole.
        bool leafChild = (in0 && node.ref0 >= kBvhLeafFlag) || (in1 && node.ref1 >= kBvhLeafFlag);
        if (!leafChild && count + top + children <= int(kEntryPointsMax)) {
          expanded = true;
          // The farther child waits below the nearer; a lone child is the nearer.
          bool firstNearer = !in1 || (in0 && boxDistance2(node.min0, node.max0) <= boxDistance2(node.min1, node.max1));
          if (in0 && in1) listPut(pending, top++, firstNearer ? node.ref1 : node.ref0);
          if (children > 0) listPut(pending, top++, firstNearer ? node.ref0 : node.ref1);
        }
      }
      if (!expanded) listPut(found, count++, ref);
      if (top == 0) break;
    }
  }

  // found[0] is where an eye ray starts; the rest wait on its stack, the farthest at the bottom.
  uint words[8];
  for (int k = 0; k < 6; ++k) words[k] = k < count - 1 ? listGet(found, count - 1 - k) : kBvhNoRef;
  words[6] = count > 0 ? found[0] : kBvhNoRef;
  words[7] = uint(max(count - 1, 0));
  entryPoints[2u * tile] = uvec4(words[0], words[1], words[2], words[3]);
  entryPoints[2u * tile + 1u] = uvec4(words[4], words[5], words[6], words[7]);
}
