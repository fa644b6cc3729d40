// The ray-tree inspector's host side (see ray_tree.h).
#include "render/ray_tree.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include <nlohmann/json.hpp>

#include "util/error.h"

namespace vkray {

namespace {

// Keys in the order they are written: what a ray is first, then where it goes and what it adds.
using json = nlohmann::ordered_json;

// The Scene's index of packed primitive `index` of GPU kind `kind`.
std::optional<TreeObject> sceneObject(const GpuScene& g, std::uint32_t kind, std::uint32_t index) {
  auto from = [&](const std::vector<std::uint32_t>& source, ObjectKind k) -> std::optional<TreeObject> {
    if (index >= source.size()) return std::nullopt;
    return TreeObject{k, source[index]};
  };
  switch (kind) {
  case gpu::kPrimSphere:
    return from(g.sphereSource, ObjectKind::Sphere);
  case gpu::kPrimPlane:
    return from(g.planeSource, ObjectKind::Plane);
  case gpu::kPrimPolygon:
    return from(g.polygonSource, ObjectKind::Polygon);
  case gpu::kPrimTriangle:
    return from(g.triangleSource, ObjectKind::Triangle);
  default:
    return std::nullopt;
  }
}

TreeOutcome outcomeOf(std::uint32_t o) {
  switch (o) {
  case gpu::kTreeSurface:
    return TreeOutcome::Surface;
  case gpu::kTreeLightReached:
    return TreeOutcome::Light;
  case gpu::kTreeBlocked:
    return TreeOutcome::Blocked;
  case gpu::kTreeUnshadowed:
    return TreeOutcome::Unshadowed;
  default:
    return TreeOutcome::Background;
  }
}

glm::dvec3 d3(const glm::vec4& v) {
  return glm::dvec3(v.x, v.y, v.z);
}

// A float's value to 9 significant digits (enough to round-trip it), so 0.3f prints as 0.300000012
// rather than with the 17 digits of its double.
double floatDigits(double x) {
  if (!std::isfinite(x)) return x;
  char text[32];
  std::snprintf(text, sizeof text, "%.9g", x);
  return std::strtod(text, nullptr);
}

json vec(const glm::dvec3& v) {
  return json::array({floatDigits(v.x), floatDigits(v.y), floatDigits(v.z)});
}

const char* objectKindName(ObjectKind k) {
  switch (k) {
  case ObjectKind::Sphere:
    return "sphere";
  case ObjectKind::Plane:
    return "plane";
  case ObjectKind::Polygon:
    return "polygon";
  case ObjectKind::Triangle:
    return "triangle";
  case ObjectKind::Mesh:
    return "mesh";
  }
  return "object";
}

// {"kind", "index"} and, where the scene file named it or a mesh made it, "name" and "mesh".
json objectJson(const TreeObject& o, const Scene& scene) {
  json j{{"kind", objectKindName(o.kind)}, {"index", o.index}};
  for (const NamedObject& named : scene.namedObjects) {
    ObjectKind kind = named.kind == ObjectKind::Mesh ? ObjectKind::Triangle : named.kind;
    if (kind == o.kind && o.index >= named.first && o.index < named.first + named.count) j["name"] = named.name;
  }
  if (o.kind == ObjectKind::Triangle) {
    for (const MeshInfo& mesh : scene.meshes) {
      if (o.index >= mesh.firstTriangle && o.index < mesh.firstTriangle + mesh.triangleCount) {
        j["mesh"] = mesh.file;
        j["mesh_triangle"] = o.index - mesh.firstTriangle;
      }
    }
  }
  return j;
}

json cutsJson(std::uint32_t cuts, std::uint32_t depth, std::uint32_t maxDepth) {
  json list = json::array();
  if (cuts & gpu::kTreeCutDepth) {
    // Below max_depth the kernel stops where the weights provably fall under the bailout at every
    // deeper level (Features::usableDepth): a bailout, not the cap.
    const char* by = depth >= maxDepth ? "depth" : "bailout";
    list.push_back({{"branch", "reflection and refraction"}, {"by", by}});
  }
  if (cuts & gpu::kTreeCutReflectionBailout) list.push_back({{"branch", "reflection"}, {"by", "bailout"}});
  if (cuts & gpu::kTreeCutRefractionBailout) list.push_back({{"branch", "refraction"}, {"by", "bailout"}});
  if (cuts & gpu::kTreeCutStack) list.push_back({{"branch", "reflection"}, {"by", "stack"}});
  return list;
}

} // namespace

glm::dvec3 RayTree::contributionSum() const {
  glm::dvec3 sum(0.0);
  for (const InspectedRay& r : rays) sum += r.contribution;
  return sum;
}

RayTree rayTreeFromRecords(const gpu::TreeRayHeader& header, const std::vector<gpu::TreeRay>& records,
                           const GpuScene& packed, glm::uvec2 pixel, const glm::vec4& sums, std::uint32_t maxDepth) {
  RayTree tree;
  tree.pixel = pixel;
  tree.samples = static_cast<std::uint32_t>(sums.w);
  const double perSample = sums.w > 0.0f ? 1.0 / sums.w : 0.0;
  tree.value = d3(sums) * perSample;
  tree.notRecorded = header.counts.z;
  tree.stoppedAtRayBudget = header.counts.w != 0;
  tree.maxDepth = maxDepth;
  const std::size_t count = std::min<std::size_t>(header.counts.x, records.size());
  for (std::size_t i = 0; i < count; ++i) {
    const gpu::TreeRay& g = records[i];
    InspectedRay r;
    r.kind = static_cast<TreeRayKind>(std::min<std::uint32_t>(g.what.x, gpu::kTreeShadow));
    r.outcome = outcomeOf(g.what.y);
    r.cuts = g.what.z;
    if (g.what.w != gpu::kTreeNoParent && g.what.w < i) r.parent = g.what.w;
    r.sample = g.where.w;
    if (r.kind == TreeRayKind::Eye) {
      r.depth = 0;
    } else if (r.parent) {
      r.depth = tree.rays[*r.parent].depth + (r.kind == TreeRayKind::Shadow ? 0u : 1u);
    }
    r.origin = d3(g.origin) + packed.origin;
    r.direction = d3(g.direction);
    r.weight = d3(g.weight);
    r.contribution = d3(g.contribution) * perSample;
    r.distance = g.origin.w;
    const bool located = r.outcome != TreeOutcome::Background;
    r.point = located ? d3(g.point) + packed.origin : glm::dvec3(0.0);
    if (r.outcome == TreeOutcome::Surface || r.outcome == TreeOutcome::Blocked)
      r.object = sceneObject(packed, g.where.x, g.where.y);
    if (r.kind == TreeRayKind::Shadow) {
      r.light = g.where.z;
    } else {
      r.material = g.where.z;
    }
    tree.rays.push_back(r);
  }
  return tree;
}

std::string rayTreeJson(const RayTree& tree, const Scene& scene) {
  json rays = json::array();
  for (std::size_t i = 0; i < tree.rays.size(); ++i) {
    const InspectedRay& r = tree.rays[i];
    json j;
    j["index"] = i;
    j["kind"] = enumName(r.kind);
    j["parent"] = r.parent ? json(*r.parent) : json(nullptr);
    j["sample"] = r.sample;
    j["depth"] = r.depth;
    j["origin"] = vec(r.origin);
    j["direction"] = vec(r.direction);
    json hit;
    switch (r.outcome) {
    case TreeOutcome::Background:
      hit["background"] = vec(scene.background);
      break;
    case TreeOutcome::Surface:
      if (r.object) hit["object"] = objectJson(*r.object, scene);
      hit["point"] = vec(r.point);
      hit["distance"] = floatDigits(r.distance);
      hit["material"] = r.material;
      break;
    case TreeOutcome::Light:
    case TreeOutcome::Unshadowed:
      hit["light"] = r.light.value_or(0);
      hit["point"] = vec(r.point);
      hit["distance"] = floatDigits(r.distance);
      if (r.outcome == TreeOutcome::Unshadowed) hit["traced"] = false;
      break;
    case TreeOutcome::Blocked:
      hit["light"] = r.light.value_or(0);
      if (r.object) hit["blocked_by"] = objectJson(*r.object, scene);
      hit["point"] = vec(r.point);
      hit["distance"] = floatDigits(r.distance);
      break;
    }
    j["hit"] = hit;
    j["weight"] = vec(r.weight);
    j["contribution"] = vec(r.contribution);
    if (r.cuts != 0) j["cut"] = cutsJson(r.cuts, r.depth, tree.maxDepth);
    rays.push_back(j);
  }
  // One ray per line: a tree of a few dozen rays stays readable, and line-oriented tools (grep,
  // diff) see one ray at a time.
  json head;
  head["pixel"] = {tree.pixel.x, tree.pixel.y};
  head["samples"] = tree.samples;
  head["value"] = vec(tree.value);
  head["contribution_sum"] = vec(tree.contributionSum());
  if (tree.notRecorded != 0) head["rays_not_recorded"] = tree.notRecorded;
  if (tree.stoppedAtRayBudget) head["stopped_at_ray_budget"] = true;
  std::string out = "{\n";
  for (const auto& [key, value] : head.items()) out += "  \"" + key + "\": " + value.dump() + ",\n";
  out += "  \"rays\": [";
  for (std::size_t i = 0; i < rays.size(); ++i) out += (i == 0 ? "\n    " : ",\n    ") + rays[i].dump();
  out += rays.empty() ? "]\n}" : "\n  ]\n}";
  return out;
}

glm::uvec2 parsePixel(const std::string& text, std::uint32_t width, std::uint32_t height, const std::string& flag) {
  const auto comma = text.find(',');
  auto number = [&](const std::string& part, std::uint32_t& out) {
    const char* end = part.data() + part.size();
    auto [ptr, ec] = std::from_chars(part.data(), end, out);
    return !part.empty() && ec == std::errc() && ptr == end;
  };
  glm::uvec2 p{0};
  if (comma == std::string::npos || !number(text.substr(0, comma), p.x) || !number(text.substr(comma + 1), p.y)) {
    throw InputError(flag, "expected a pixel as X,Y (two integers >= 0), got '" + text + "'");
  }
  if (p.x >= width || p.y >= height) {
    throw InputError(flag, "pixel " + text + " is outside the " + std::to_string(width) + " x " +
                               std::to_string(height) + " image");
  }
  return p;
}

} // namespace vkray
