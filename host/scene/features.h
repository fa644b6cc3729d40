// Scene analysis: which effects and primitive kinds a scene actually calls for, so the renderer can
// specialize its kernel to them and trace nothing the image cannot show.
#pragma once

#include <string>
#include <vector>

#include "scene/scene.h"

namespace vkray {

struct Features {
  // Primitive kinds present.
  bool spheres = false;
  bool planes = false;
  int planeCount = 0;
  bool triangles = false;
  bool polygons = false;
  bool smoothNormals = false; // some triangle carries shading normals
  bool checker = false;       // some material has a checker
  bool textures = false;      // some material has a base-colour texture and some triangle uvs for it
  bool vertexColors = false;  // some triangle has vertex colours (glTF COLOR_0)
  bool alphaMask = false;     // some triangle's material cuts out by alpha (glTF alphaMode MASK)
  // The camera has a thin lens (camera.aperture > 0): depth of field. Its eye rays do not all pass
  // through the eye, so the pinhole-only shortcuts (entry points, row culling) are off.
  bool thinLens = false;
  double aperture = 0.0;      // lens radius
  double focusDistance = 0.0; // of the plane in focus
  // render.method forward: photons from the lights into the lens (settings, applySettings).
  bool forward = false;

  // Shadows: lights that ask for them, and whether anything could block them at all (a single
  // convex object cannot shadow itself: lights behind a surface are skipped before any ray).
  int lights = 0;
  int shadowLights = 0;
  bool occluderPossible = false;
  bool shadows = false;
  int occluderPlanes = 0; // planes that can stand between a surface and a light

  // Secondary rays: reflection covers mirrors and the reflected half of dielectrics.
  bool reflection = false;
  bool refraction = false;
  int requestedDepth = 0;       // max_depth asked for
  int usableDepth = 0;          // deepest bounce whose weight can reach the bailout (<= requestedDepth)
  double maxBranchWeight = 0.0; // largest per-bounce weight factor (reflection + transmission)
  int stackSize = 1;            // pending branches the kernel must hold (refraction only)
  bool stackTruncated = false;  // usableDepth > kMaxStackSize: extra branches will be dropped

  bool useBvh = false;
  std::size_t boundedPrimitives = 0;

  // Facts about the scene alone, kept so settings can be re-applied (the viewer changes them live).
  bool anyReflectiveMaterial = false;
  bool anyTransmissiveMaterial = false;
  // Some material has a highlight but no diffuse term: its lights are sampled only where the
  // highlight can show (gpu::kNegligibleHighlight).
  bool specularOnlyMaterial = false;

  // One line per aspect, in words: "shadows: on (2 lights)".
  std::vector<std::string> explain() const;

  // Recomputes everything that depends on the settings (depth, bailout, BVH mode).
  void applySettings(const RenderSettings& settings);
};

// Bounded primitives at which BvhMode::Auto switches from brute force to the BVH.
inline constexpr std::size_t kBvhAutoThreshold = 12;

Features analyzeScene(const Scene& scene, const RenderSettings& settings);

// For each plane: can it ever stand between a shaded point and a shadow-casting light? A plane
// cannot when every light is strictly on one side and every other surface lies (weakly) on that
// same side: e.g. a floor with all objects and lights above it. Exact, in double precision.
std::vector<bool> planesThatCanOcclude(const Scene& scene);

} // namespace vkray
