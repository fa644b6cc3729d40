// Eye-ray culling by rows: which bands of workgroup rows provably see nothing but the background.
//
// On CPU drivers a SIMD group of 8 pixels pays for the whole Whitted loop body even when every one
// of its eye rays misses (docs/performance.md, "Why lavapipe needs this"), so the sky above a
// scene costs as much per pixel as a lit floor. The Renderer fills rows of workgroups whose every
// eye ray misses everything with a kernel that writes the background (shaders/fill.comp) and
// traces only the others. The test is conservative: a row is empty only when the pyramid from the
// eye through the row, one pixel wider on every side than its pixels, misses the box of every
// bounded primitive and every plane with margins far above float rounding, so every eye ray the
// kernel would trace there (any sample position inside a pixel) meets nothing; the image is the
// same bit for bit.
#pragma once

#include <cstdint>
#include <vector>

#include "accel/bvh.h"
#include "render/gpu_scene.h"

namespace vkray {

// What the test needs, in the packed scene's frame (positions relative to GpuScene::origin).
struct CullScene {
  CameraFrame camera;             // position relative to the packed frame
  Aabb bounds;                    // every sphere, triangle and polygon (GpuScene::bounds)
  std::vector<glm::dvec4> planes; // xyz: unit normal, w: D (n.x + D = 0)
};

CullScene makeCullScene(const GpuScene& g, const CameraFrame& camera);

// Whether every eye ray through image rows [row0, row0 + rows) of a width x height image, at any
// position inside their pixels, provably misses every primitive.
bool rowsSeeNothing(const CullScene& scene, std::uint32_t width, std::uint32_t height, std::uint32_t row0,
                    std::uint32_t rows);

// A run of consecutive rows that are all empty or all not.
struct RowRun {
  std::uint32_t row0 = 0;
  std::uint32_t rows = 0;
  bool empty = false;
};

// Splits rows [row0, row0 + rows) into runs of `step` rows (the workgroup height; the last one may
// be shorter), merged while their verdict is the same.
std::vector<RowRun> splitRows(const CullScene& scene, std::uint32_t width, std::uint32_t height, std::uint32_t row0,
                              std::uint32_t rows, std::uint32_t step);

} // namespace vkray
