// Packing the scene into GPU arrays (see gpu_scene.h).
#include "render/gpu_scene.h"

#include <algorithm>
#include <array>
#include <bit>
#include <chrono>
#include <cmath>

#include "scene/features.h"

namespace vkray {

namespace {

glm::vec3 rel(const glm::dvec3& p, const glm::dvec3& origin) {
  return glm::vec3(p - origin);
}

// float(x) may round towards the inside of a box; step one ulp outwards so bounds stay conservative.
float down(double x) {
  float f = static_cast<float>(x);
  return static_cast<double>(f) > x ? std::nextafter(f, -INFINITY) : f;
}
float up(double x) {
  float f = static_cast<float>(x);
  return static_cast<double>(f) < x ? std::nextafter(f, INFINITY) : f;
}

// TextureRef's sampler word: wrap modes, magnification and the glTF minFilter (the levels a
// minified sample reads, and nearest or bilinear texels in them), as texture.glsl reads it.
std::uint32_t samplerWord(const Texture& tex) {
  const TextureMinFilter mf = tex.minFilter;
  const std::uint32_t minLevels =
      mf == TextureMinFilter::NearestLevel || mf == TextureMinFilter::NearestLevelNearest ? gpu::kMinLevelsNearest
      : mf == TextureMinFilter::Linear || mf == TextureMinFilter::Nearest                 ? gpu::kMinLevelsBase
                                                                                          : gpu::kMinLevelsBlend;
  const bool minNearest = mf == TextureMinFilter::NearestBetweenLevels || mf == TextureMinFilter::NearestLevelNearest ||
                          mf == TextureMinFilter::Nearest;
  return static_cast<std::uint32_t>(tex.wrapS) | static_cast<std::uint32_t>(tex.wrapT) << gpu::kSamplerWrapTShift |
         (tex.nearest ? gpu::kSamplerMagNearest : 0u) | minLevels << gpu::kSamplerMinLevelsShift |
         (minNearest ? gpu::kSamplerMinNearest : 0u);
}

} // namespace

std::vector<BvhPrimitive> bvhPrimitives(const Scene& scene, const GpuScene& g) {
  std::vector<BvhPrimitive> prims;
  prims.reserve(g.spheres.size() + g.triangles.size() + g.polygons.size());
  for (std::size_t i = 0; i < g.spheres.size(); ++i) {
    // Bounds from the double centre and radius, rounded outwards: they contain the float sphere.
    const Sphere& s = scene.spheres[i];
    glm::dvec3 c = s.center - g.origin;
    double r = s.radius * (1.0 + 1e-6);
    Aabb b;
    b.min = glm::vec3(down(c.x - r), down(c.y - r), down(c.z - r));
    b.max = glm::vec3(up(c.x + r), up(c.y + r), up(c.z + r));
    prims.push_back({b, gpu::kPrimSphere << gpu::kPrimKindShift | static_cast<std::uint32_t>(i)});
  }
  for (std::size_t i = 0; i < g.triangles.size(); ++i) {
    // The float vertices themselves: the box is exact.
    Aabb b;
    b.grow(glm::vec3(g.triangles[i].v0));
    b.grow(glm::vec3(g.triangles[i].v1));
    b.grow(glm::vec3(g.triangles[i].v2));
    prims.push_back({b, gpu::kPrimTriangle << gpu::kPrimKindShift | static_cast<std::uint32_t>(i)});
  }
  for (std::size_t i = 0; i < g.polygons.size(); ++i) {
    Aabb b;
    for (std::uint32_t k = 0; k < gpu::polygonVertexCount(g.polygons[i]); ++k)
      b.grow(glm::vec3(g.polyVertices[gpu::polygonFirstVertex(g.polygons[i]) + k]));
    prims.push_back({b, gpu::kPrimPolygon << gpu::kPrimKindShift | static_cast<std::uint32_t>(i)});
  }
  return prims;
}

void orderByLeaves(GpuScene& g) {
  const std::size_t kinds = 3;
  std::array<std::uint32_t, kinds> next{};
  std::vector<gpu::Sphere> spheres(g.spheres.size());
  std::vector<gpu::Triangle> triangles(g.triangles.size());
  std::vector<gpu::Polygon> polygons(g.polygons.size());
  std::vector<std::uint32_t> sphereSource(g.sphereSource.size()), triangleSource(g.triangleSource.size()),
      polygonSource(g.polygonSource.size());
  std::vector<glm::vec4> normals;
  normals.reserve(g.normals.size());
  std::vector<glm::vec4> texCoords;
  texCoords.reserve(g.texCoords.size());
  for (std::uint32_t& ref : g.bvh.primRefs) {
    std::uint32_t kind = ref >> gpu::kPrimKindShift;
    std::uint32_t index = ref & gpu::kPrimIndexMask;
    std::uint32_t slot = next[kind]++;
    if (kind == gpu::kPrimSphere) {
      spheres[slot] = g.spheres[index];
      sphereSource[slot] = g.sphereSource[index];
    } else if (kind == gpu::kPrimTriangle) {
      gpu::Triangle t = g.triangles[index];
      std::uint32_t uvBase = gpu::triangleUvBasePlusOne(t);
      if (uvBase != 0) {
        gpu::setTriangleUvBasePlusOne(t, static_cast<std::uint32_t>(texCoords.size()) + 1);
        bool colors = gpu::hasVertexColors(gpu::UvInfo{g.texCoords[uvBase - 1 + gpu::kUvRecordInfo]});
        std::uint32_t n = gpu::kUvRecordTexels + (colors ? gpu::kUvRecordColorTexels : 0);
        for (std::uint32_t k = 0; k < n; ++k) texCoords.push_back(g.texCoords[uvBase - 1 + k]);
      }
      std::uint32_t normalBase = gpu::triangleNormalBase(t);
      if (normalBase != gpu::kNoNormals) {
        // The shading normals move with their triangle, so a leaf's data stays together.
        gpu::setTriangleNormalBase(t, static_cast<std::uint32_t>(normals.size()));
        for (std::uint32_t k = 0; k < 3; ++k) normals.push_back(g.normals[normalBase + k]);
      }
      triangles[slot] = t;
      triangleSource[slot] = g.triangleSource[index];
    } else {
      polygons[slot] = g.polygons[index];
      polygonSource[slot] = g.polygonSource[index];
    }
    ref = kind << gpu::kPrimKindShift | slot;
  }
  g.spheres = std::move(spheres);
  g.triangles = std::move(triangles);
  g.polygons = std::move(polygons);
  g.sphereSource = std::move(sphereSource);
  g.triangleSource = std::move(triangleSource);
  g.polygonSource = std::move(polygonSource);
  g.normals = std::move(normals);
  g.texCoords = std::move(texCoords);
}

void buildShadowEntries(GpuScene& g, const ShadowEntryOptions& options) {
  if (g.bvhRoot == gpu::kBvhNoRef || g.bvh.nodes.empty() || g.triangles.empty() || g.lights.empty() ||
      g.lights.size() > gpu::kShadowEntryLightsMax)
    return;
  const auto start = std::chrono::steady_clock::now();
  std::vector<glm::dvec3> lights;
  std::vector<bool> casts;
  for (const gpu::Light& l : g.lights) {
    lights.emplace_back(glm::vec3(l.position));
    casts.push_back(l.position.w != 0.0f);
  }
  if (std::find(casts.begin(), casts.end(), true) == casts.end()) return; // no shadow rays at all
  g.shadowEntries = shadowEntryTable(
      {g.bvhNodes, g.bvhRoot, nodeBounds(g.bvh.nodes[0]), g.bvh.primRefs, g.triangles, lights, casts}, options);
  g.shadowEntryMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  g.shadowNothingBetween = options.nothingBetween;
  g.shadowNothingPairs = 0;
  for (std::size_t i = 1; i < g.shadowEntries.size(); i += 2)
    g.shadowNothingPairs += g.shadowEntries[i].w == gpu::kShadowNothingBetween;
}

std::size_t GpuScene::bvhBytes() const {
  return bvhNodes.size() * gpu::kBvhRecordTexels * sizeof(glm::uvec4) + bvh.primRefs.size() * sizeof(std::uint32_t);
}

std::size_t GpuScene::meshBytes() const {
  return triangles.size() * sizeof(gpu::Triangle) + (normals.size() + texCoords.size()) * sizeof(glm::vec4) +
         bvhBytes();
}

std::size_t GpuScene::bytes() const {
  return materials.size() * sizeof(gpu::Material) + lights.size() * sizeof(gpu::Light) +
         spheres.size() * sizeof(gpu::Sphere) + planes.size() * sizeof(gpu::Plane) +
         triangles.size() * sizeof(gpu::Triangle) + polygons.size() * sizeof(gpu::Polygon) +
         (polyVertices.size() + normals.size() + texCoords.size() + texels.size()) * sizeof(glm::vec4) +
         textureInfo.size() * sizeof(glm::uvec4) + bvhBytes();
}

GpuScene packScene(const Scene& scene, const glm::dvec3& origin, bool withBvh, const BvhOptions& bvhOptions) {
  GpuScene g;
  g.origin = origin;
  g.background = scene.background;
  g.ambientLight = scene.ambientLight;
  // Textures: each level's texels; TextureInfo[] holds one TextureRef per textured material, then
  // the TextureLevels the references point at.
  const auto texturedMaterials = static_cast<std::uint32_t>(
      std::ranges::count_if(scene.materials, [](const Material& m) { return m.baseColorTexture.has_value(); }));
  const std::uint32_t levelBase = texturedMaterials * gpu::kTextureRefTexels; // the first TextureLevel
  std::vector<std::uint32_t> firstLevel; // each texture's first TextureLevel in TextureInfo[]
  std::vector<gpu::TextureLevel> levels;
  for (const auto& tex : scene.textures) {
    firstLevel.push_back(levelBase + static_cast<std::uint32_t>(levels.size()));
    for (const TextureLevel& l : tex->levels) {
      levels.push_back(
          gpu::TextureLevel{glm::uvec4(static_cast<std::uint32_t>(g.texels.size()), l.width, l.height, 0u)});
      g.texels.insert(g.texels.end(), l.texels.begin(), l.texels.end());
    }
  }
  std::vector<std::uint32_t> textureRef(scene.materials.size(), 0); // + 1; 0: untextured
  for (std::size_t i = 0; i < scene.materials.size(); ++i) {
    const auto& bt = scene.materials[i].baseColorTexture;
    if (!bt) continue;
    const Texture& tex = *scene.textures[bt->texture];
    textureRef[i] = static_cast<std::uint32_t>(g.textureInfo.size() / gpu::kTextureRefTexels) + 1;
    const TextureTransform& x = bt->transform;
    double c = std::cos(x.rotation), s = std::sin(x.rotation);
    // uv' = T R S uv as rows (a b e; c d f), as texture.h's TextureTransform::apply.
    glm::dvec3 row0(c * x.scale.x, s * x.scale.y, x.offset.x);
    glm::dvec3 row1(-s * x.scale.x, c * x.scale.y, x.offset.y);
    double det = std::abs(row0.x * row1.y - row0.y * row1.x);
    double texels = double(tex.levels[0].width) * tex.levels[0].height * std::max(det, 1e-30);
    auto bits = [](double v) { return std::bit_cast<std::uint32_t>(static_cast<float>(v)); };
    const double lodOffset = 0.5 * std::log2(texels);
    gpu::TextureRef ref;
    ref.levels = glm::uvec4(firstLevel[bt->texture], static_cast<std::uint32_t>(tex.levels.size()), samplerWord(tex),
                            bt->texCoord);
    ref.row0 = glm::uvec4(bits(row0.x), bits(row0.y), bits(row0.z), bits(lodOffset));
    ref.row1 = glm::uvec4(bits(row1.x), bits(row1.y), bits(row1.z), 0u);
    g.textureInfo.insert(g.textureInfo.end(), {ref.levels, ref.row0, ref.row1});
  }
  if (texturedMaterials > 0) {
    for (const gpu::TextureLevel& level : levels) g.textureInfo.push_back(level.extent);
  } else {
    g.texels.clear();
  }
  for (std::size_t mi = 0; mi < scene.materials.size(); ++mi) {
    const Material& m = scene.materials[mi];
    gpu::Material gm{};
    gm.color = glm::vec4(glm::vec3(m.color), static_cast<float>(m.ambient));
    gm.color2 =
        m.checker ? glm::vec4(glm::vec3(m.checker->color2), static_cast<float>(m.checker->scale)) : glm::vec4(0.0f);
    gm.phong = glm::vec4(static_cast<float>(m.diffuse), static_cast<float>(m.specular), static_cast<float>(m.shininess),
                         static_cast<float>(m.reflection));
    gm.transmission = glm::vec4(static_cast<float>(m.transmission), static_cast<float>(m.ior),
                                std::bit_cast<float>(textureRef[mi]), static_cast<float>(m.alphaCutoff));
    gm.absorption = glm::vec4(glm::vec3(m.absorption), m.alphaCutoff > 0.0 ? static_cast<float>(m.alpha) : 0.0f);
    g.materials.push_back(gm);
  }
  for (const PointLight& l : scene.lights) {
    g.lights.push_back(
        gpu::Light{glm::vec4(rel(l.position, origin), l.shadows ? 1.0f : 0.0f), glm::vec4(glm::vec3(l.color), 0.0f)});
  }
  for (const Sphere& s : scene.spheres) {
    g.sphereSource.push_back(static_cast<std::uint32_t>(g.spheres.size()));
    // The centre as float plus its rounding error, so robust numerics see it to ~2^-48 (gpu_types.h).
    glm::dvec3 center = s.center - origin;
    glm::vec3 high(center);
    glm::vec3 low(center - glm::dvec3(high));
    g.spheres.push_back(
        gpu::Sphere{glm::vec4(high, static_cast<float>(s.radius)),
                    glm::uvec4(s.material, std::bit_cast<std::uint32_t>(low.x), std::bit_cast<std::uint32_t>(low.y),
                               std::bit_cast<std::uint32_t>(low.z))});
  }
  // Planes that can cast shadows go first: shadow rays test only those (features.h).
  std::vector<bool> occluding = planesThatCanOcclude(scene);
  for (int pass = 0; pass < 2; ++pass) {
    for (std::size_t i = 0; i < scene.planes.size(); ++i) {
      if (occluding[i] != (pass == 0)) continue;
      const Plane& p = scene.planes[i];
      // n.(x_rel + origin) + D = 0  =>  n.x_rel + (D + n.origin) = 0
      double d = p.offset + glm::dot(p.normal, origin);
      g.planeSource.push_back(static_cast<std::uint32_t>(i));
      g.planes.push_back(
          gpu::Plane{glm::vec4(glm::vec3(p.normal), static_cast<float>(d)), glm::uvec4(p.material, 0, 0, 0)});
      if (pass == 0) ++g.occluderPlanes;
    }
  }
  for (const Polygon& poly : scene.polygons) {
    g.polygonSource.push_back(static_cast<std::uint32_t>(g.polygons.size()));
    auto first = static_cast<std::uint32_t>(g.polyVertices.size());
    for (const auto& v : poly.vertices) g.polyVertices.emplace_back(rel(v, origin), 0.0f);
    double d = -glm::dot(poly.normal, poly.vertices[0] - origin);
    gpu::Polygon gp{glm::vec4(glm::vec3(poly.normal), static_cast<float>(d)),
                    glm::uvec4(first, static_cast<std::uint32_t>(poly.vertices.size()), poly.material, 0)};
    // The bounding sphere about the first vertex, over the float vertices the kernel reads, in
    // double and rounded up: the kernel's cheap reject must never drop a hit.
    glm::dvec3 v0(glm::vec3(g.polyVertices[first]));
    double radius = 0.0;
    for (std::size_t i = first; i < g.polyVertices.size(); ++i) {
      radius = std::max(radius, glm::length(glm::dvec3(glm::vec3(g.polyVertices[i])) - v0));
    }
    gpu::setPolygonBoundRadius(gp, std::nextafter(static_cast<float>(radius), std::numeric_limits<float>::infinity()));
    g.polygons.push_back(gp);
  }
  for (const Triangle& t : scene.triangles) {
    g.triangleSource.push_back(static_cast<std::uint32_t>(g.triangles.size()));
    std::uint32_t normalBase = gpu::kNoNormals;
    if (t.normals) {
      normalBase = static_cast<std::uint32_t>(g.normals.size());
      for (const auto& n : *t.normals) g.normals.emplace_back(glm::vec3(n), 0.0f);
    }
    std::uint32_t uvBase = 0; // + 1; 0: none
    const bool textured = t.uvs && textureRef[t.material] != 0;
    if (textured || t.colors) {
      uvBase = static_cast<std::uint32_t>(g.texCoords.size()) + 1;
      for (int k = 0; k < 3; ++k) g.texCoords.emplace_back(textured ? glm::vec4((*t.uvs)[k]) : glm::vec4(0.0f));
      // 0.5 log2(uv area / world area) per set: the triangle's part of the ray-cone LOD (RTG eq. 20.4).
      double world = glm::length(glm::cross(t.v[1] - t.v[0], t.v[2] - t.v[0]));
      auto uvArea = [&](int a) {
        glm::dvec2 p0((*t.uvs)[0][a], (*t.uvs)[0][a + 1]), p1((*t.uvs)[1][a], (*t.uvs)[1][a + 1]),
            p2((*t.uvs)[2][a], (*t.uvs)[2][a + 1]);
        glm::dvec2 e1 = p1 - p0, e2 = p2 - p0;
        return std::abs(e1.x * e2.y - e1.y * e2.x);
      };
      auto bias = [&](int a) {
        return textured ? static_cast<float>(0.5 * std::log2(std::max(uvArea(a), 1e-30) / world)) : 0.0f;
      };
      gpu::UvInfo info;
      info.lodAndFlags = glm::vec4(bias(0), bias(2), t.colors ? 1.0f : 0.0f, textured ? 1.0f : 0.0f);
      g.texCoords.push_back(info.lodAndFlags);
      if (t.colors)
        for (const auto& c : *t.colors) g.texCoords.emplace_back(c);
    }
    gpu::Triangle gt{glm::vec4(rel(t.v[0], origin), 0.0f), glm::vec4(rel(t.v[1], origin), 0.0f),
                     glm::vec4(rel(t.v[2], origin), 0.0f)};
    gpu::setTriangleMaterial(gt, t.material);
    gpu::setTriangleNormalBase(gt, normalBase);
    gpu::setTriangleUvBasePlusOne(gt, uvBase);
    g.triangles.push_back(gt);
  }

  const std::vector<BvhPrimitive> prims = bvhPrimitives(scene, g);
  for (const BvhPrimitive& p : prims) {
    g.bounds.grow(p.bounds);
    const std::uint32_t kind = p.ref >> gpu::kPrimKindShift;
    if (kind == gpu::kPrimTriangle) g.triangleBounds.grow(p.bounds);
    if (kind == gpu::kPrimPolygon) g.polygonBounds.grow(p.bounds);
  }
  if (withBvh) {
    auto start = std::chrono::steady_clock::now();
    g.bvh = buildBvh(prims, bvhOptions);
    orderByLeaves(g);
    g.bvhRoot = wideBvh(g.bvh, g.bvhNodes);
    // Build time as --stats reports it: from packed primitives to the final arrays.
    g.bvh.stats.buildMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  }
  return g;
}

CameraFrame makeCameraFrame(const Camera& camera, std::uint32_t width, std::uint32_t height) {
  CameraFrame f;
  f.position = camera.position;
  f.forward = glm::normalize(camera.lookAt - camera.position);
  // A degenerate `up` (parallel to the view) would make right = 0/0: try the world axes instead.
  const glm::dvec3 candidates[] = {camera.up, {0, 1, 0}, {0, 0, 1}, {1, 0, 0}};
  glm::dvec3 right(1, 0, 0);
  for (const auto& u : candidates) {
    glm::dvec3 c = glm::cross(f.forward, u);
    double len = glm::length(c);
    if (len > 1e-9 * glm::length(u)) {
      right = c / len;
      break;
    }
  }
  f.right = right;
  f.up = glm::cross(f.right, f.forward);
  f.tanHalfFovY = std::tan(glm::radians(camera.fovY) * 0.5);
  f.aspect = static_cast<double>(width) / static_cast<double>(height);
  return f;
}

glm::dvec3 CameraFrame::rayDirection(double px, double py, std::uint32_t width, std::uint32_t height) const {
  double x = 2.0 * px / width - 1.0;
  double y = 1.0 - 2.0 * py / height;
  return forward + x * (right * tanHalfFovY * aspect) + y * (up * tanHalfFovY);
}

} // namespace vkray
