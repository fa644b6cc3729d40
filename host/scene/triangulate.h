// Polygons to triangles for the mesh readers (OBJ faces of more than three vertices, PLY faces):
// ear clipping in the polygon's best-fit plane, so concave faces keep their shape. Strictly convex
// polygons become the fan from their first corner, the split vkray made before (docs/meshes.md,
// "Polygons").
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

namespace vkray {

using Corners = std::array<std::uint32_t, 3>; // a triangle as three corner numbers of its polygon

// Appends the triangles of the polygon whose corners, in order, lie at `corners` to `out`, as corner
// numbers (0 .. corners.size() - 1), wound as the polygon is. A triangle is passed through as it is;
// a larger polygon gives no zero-area triangle (repeated and collinear corners cover nothing), so it
// may give fewer than corners.size() - 2. Never loops forever, whatever the input (self-intersecting
// and non-planar polygons get some triangles, not necessarily a sensible set).
void triangulatePolygon(std::span<const glm::dvec3> corners, std::vector<Corners>& out);

} // namespace vkray
