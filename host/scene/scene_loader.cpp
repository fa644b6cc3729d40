// Scene file -> Scene. One function per JSON section; each validates what it reads.
#include "scene/scene_loader.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>

#include "scene/animation.h"
#include "scene/json_reader.h"
#include "scene/mesh_import.h"
#include "scene/model_scene.h"
#include "scene/scene_limits.h"
#include "util/error.h"
#include "util/file_extension.h"

namespace vkray {

namespace {

using glm::dvec3;

struct LoadContext {
  Scene& scene;
  std::map<std::string, std::uint32_t> materialIds;
  std::filesystem::path baseDir;
  std::optional<Camera> importedCamera; // from a mesh object with import_camera
  std::string importedCameraFrom;       // that object's JSON path
};

// Why a length beyond kMaxCoordinate is refused (scene_limits.h).
std::string squaredPastFloat(double v, const char* squared) {
  return "the kernel squares " + std::string(squared) + " in float32, and " + formatNumber(v) +
         " squared is past float32's 3.4e+38";
}

// A position the kernel sees: every coordinate within kMaxCoordinate.
dvec3 readPoint(const JsonNode& node) {
  dvec3 p = node.vec3();
  for (std::size_t i = 0; i < 3; ++i) {
    if (std::abs(p[static_cast<int>(i)]) > kMaxCoordinate) {
      node[i].fail("must be within +-" + formatNumber(kMaxCoordinate) + ", got " +
                   formatNumber(p[static_cast<int>(i)]) + ": " + squaredPastFloat(p[static_cast<int>(i)], "distances"));
    }
  }
  return p;
}

// A camera placed by hand, or `"fit": true` (optionally `"from"`: the direction it looks from),
// placed after the objects are read (model_scene.h: fitCamera). Returns whether it is to be fitted.
bool readCamera(const JsonNode& node, Camera& camera, glm::dvec3& fitFrom) {
  node.allowKeys({"position", "look_at", "up", "fov_y", "fit", "from", "aperture", "focus_distance"});
  bool fit = false;
  if (auto f = node.find("fit")) fit = f->boolean();
  if (fit) {
    for (const char* key : {"position", "look_at"}) {
      if (auto k = node.find(key)) k->fail("give either camera.fit or camera." + std::string(key) + ", not both");
    }
    if (auto from = node.find("from")) fitFrom = from->nonZeroVec3();
  } else {
    if (auto from = node.find("from")) from->fail("only with \"fit\": true");
    camera.position = readPoint(node.at("position"));
    camera.lookAt = readPoint(node.at("look_at"));
  }
  if (auto up = node.find("up")) camera.up = up->nonZeroVec3();
  if (auto fov = node.find("fov_y")) {
    camera.fovY = fov->number();
    if (!(camera.fovY > 0.0 && camera.fovY < 180.0)) {
      fov->fail("must be in (0, 180) degrees, got " + formatNumber(camera.fovY));
    }
  }
  if (auto a = node.find("aperture")) {
    camera.aperture = a->number();
    if (!(std::isfinite(camera.aperture) && camera.aperture >= 0.0)) {
      a->fail("must be a finite lens radius >= 0 (0: pinhole), got " + formatNumber(camera.aperture));
    }
  }
  if (auto d = node.find("focus_distance")) {
    double focus = d->number();
    if (!(std::isfinite(focus) && focus > 0.0)) d->fail("must be > 0, got " + formatNumber(focus));
    camera.focusDistance = focus;
  }
  if (fit) {
    if (glm::length(glm::cross(glm::normalize(fitFrom), glm::normalize(camera.up))) < 1e-9) {
      node.fail("camera.from must not be parallel to camera.up");
    }
    return true;
  }
  if (glm::length(camera.lookAt - camera.position) == 0.0) {
    node.at("look_at").fail("must differ from camera.position");
  }
  return false;
}

void readImage(const JsonNode& node, Scene& scene, bool& sawBackground, bool& sawAmbient) {
  node.allowKeys({"width", "height", "background", "ambient"});
  if (auto w = node.find("width")) scene.render.width = static_cast<std::uint32_t>(w->integer(1, kMaxImageSide));
  if (auto h = node.find("height")) scene.render.height = static_cast<std::uint32_t>(h->integer(1, kMaxImageSide));
  if (auto bg = node.find("background")) {
    scene.background = bg->color();
    sawBackground = true;
  }
  if (auto amb = node.find("ambient")) {
    scene.ambientLight = amb->color();
    sawAmbient = true;
  }
}

void readRender(const JsonNode& node, RenderSettings& r) {
  node.allowKeys({"max_depth", "spp", "bailout", "antialiasing", "adaptive_threshold", "numerics", "fresnel",
                  "transmissive_shadows", "precision", "bvh", "texture_filter", "noise_threshold", "time_limit",
                  "min_spp", "max_spp", "method", "photons", "seed"});
  if (auto v = node.find("max_depth")) r.maxDepth = static_cast<int>(v->integer(0, kMaxDepthLimit));
  if (auto v = node.find("spp")) r.spp = static_cast<int>(v->integer(1, kMaxSpp));
  if (auto v = node.find("bailout")) r.bailout = v->number(0.0, 1.0);
  if (auto v = node.find("antialiasing")) r.antialiasing = v->enumValue<Antialiasing>();
  if (auto v = node.find("adaptive_threshold")) r.adaptiveThreshold = v->number(0.0, 1.0);
  if (auto v = node.find("numerics")) r.numerics = v->enumValue<Numerics>();
  if (auto v = node.find("fresnel")) r.fresnel = v->enumValue<FresnelMode>();
  if (auto v = node.find("transmissive_shadows")) r.transmissiveShadows = v->enumValue<TransmissiveShadows>();
  if (auto v = node.find("precision")) r.precision = v->enumValue<Precision>();
  if (auto v = node.find("texture_filter")) r.textureFilter = v->enumValue<TextureFilter>();
  if (auto v = node.find("bvh")) r.bvh = v->enumValue<BvhMode>();
  if (auto v = node.find("noise_threshold")) {
    r.noiseThreshold = v->number(0.0, 1e6);
    if (!(r.noiseThreshold > 0.0)) v->fail("must be > 0 (a standard error in linear RGB), got 0");
  }
  if (auto v = node.find("time_limit")) {
    r.timeLimit = v->number(0.0, kMaxTimeLimitSeconds);
    if (!(r.timeLimit > 0.0)) v->fail("must be > 0 seconds, got 0");
  }
  if (auto v = node.find("method")) r.method = v->enumValue<Method>();
  if (auto v = node.find("photons")) r.photons = static_cast<std::uint64_t>(v->integer(1, kMaxPhotons));
  if (auto v = node.find("min_spp")) r.minSpp = static_cast<int>(v->integer(1, kMaxSpp));
  if (auto v = node.find("max_spp")) r.maxSpp = static_cast<int>(v->integer(1, kMaxSpp));
  if (auto v = node.find("seed")) r.seed = static_cast<std::uint32_t>(v->integer(0, 0xFFFFFFFFll));
}

Material readMaterial(const JsonNode& node, const std::string& name) {
  node.allowKeys({"color", "ambient", "diffuse", "specular", "shininess", "reflection", "transmission", "ior",
                  "absorption", "checker"});
  Material m;
  m.name = name;
  if (auto v = node.find("color")) m.color = v->color();
  if (auto v = node.find("ambient")) m.ambient = v->number(0.0, 1e6);
  if (auto v = node.find("diffuse")) m.diffuse = v->number(0.0, 1e6);
  if (auto v = node.find("specular")) m.specular = v->number(0.0, 1e6);
  if (auto v = node.find("shininess")) m.shininess = v->number(0.0, 1e6);
  if (auto v = node.find("reflection")) m.reflection = v->number(0.0, 1.0);
  if (auto v = node.find("transmission")) m.transmission = v->number(0.0, 1.0);
  if (auto v = node.find("ior")) {
    m.ior = v->number();
    if (!(m.ior >= 0.01 && m.ior <= 100.0)) v->fail("must be in [0.01, 100], got " + formatNumber(m.ior));
  }
  if (auto v = node.find("absorption")) m.absorption = v->color();
  if (m.reflection + m.transmission > 1.0 + 1e-12) {
    node.at("transmission")
        .fail("reflection + transmission must be <= 1 (energy), got " + formatNumber(m.reflection + m.transmission));
  }
  if (auto c = node.find("checker")) {
    c->allowKeys({"color2", "scale"});
    Checker checker;
    checker.color2 = c->at("color2").color();
    if (auto s = c->find("scale")) checker.scale = s->positive();
    m.checker = checker;
  }
  return m;
}

void readMaterials(const JsonNode& node, LoadContext& ctx) {
  for (auto& [name, value] : node.members()) {
    if (name.empty()) value.fail("material names must not be empty");
    ctx.materialIds[name] = static_cast<std::uint32_t>(ctx.scene.materials.size());
    ctx.scene.materials.push_back(readMaterial(value, name));
  }
}

std::uint32_t defaultMaterial(LoadContext& ctx) {
  auto it = ctx.materialIds.find("");
  if (it != ctx.materialIds.end()) return it->second;
  Material m;
  m.name = "(default)";
  auto id = static_cast<std::uint32_t>(ctx.scene.materials.size());
  ctx.scene.materials.push_back(m);
  ctx.materialIds[""] = id;
  return id;
}

// An object's material: a name from "materials", an inline material object, or the default grey.
std::uint32_t readObjectMaterial(const JsonNode& object, LoadContext& ctx) {
  auto node = object.find("material");
  if (!node) return defaultMaterial(ctx);
  if (node->isObject()) {
    auto id = static_cast<std::uint32_t>(ctx.scene.materials.size());
    ctx.scene.materials.push_back(readMaterial(*node, object.path() + ".material"));
    return id;
  }
  std::string name = node->string();
  auto it = ctx.materialIds.find(name);
  if (it == ctx.materialIds.end() || name.empty()) {
    std::string known;
    for (auto& [k, v] : ctx.materialIds) {
      if (!k.empty()) known += (known.empty() ? "" : ", ") + k;
    }
    node->fail("unknown material '" + name + "'" +
               (known.empty() ? " (no materials defined)" : " (known: " + known + ")"));
  }
  return it->second;
}

void readLights(const JsonNode& node, Scene& scene) {
  for (std::size_t i = 0; i < node.size(); ++i) {
    JsonNode l = node[i];
    l.allowKeys({"type", "name", "position", "color", "shadows"});
    if (auto t = l.find("type")) t->choice({"point"});
    PointLight light;
    light.position = readPoint(l.at("position"));
    if (auto c = l.find("color")) light.color = c->color();
    if (auto s = l.find("shadows")) light.shadows = s->boolean();
    if (auto n = l.find("name")) {
      std::string name = n->string();
      if (name.empty()) n->fail("must not be empty");
      for (const NamedLight& other : scene.namedLights) {
        if (other.name == name) n->fail("'" + name + "' names lights[" + std::to_string(other.index) + "] already");
      }
      scene.namedLights.push_back({name, scene.lights.size()});
    }
    scene.lights.push_back(light);
  }
}

// Newell's method: a robust normal for a (nearly) planar polygon, length = twice its area.
dvec3 newellNormal(const std::vector<dvec3>& v) {
  dvec3 n(0.0);
  for (std::size_t i = 0; i < v.size(); ++i) {
    const dvec3& a = v[i];
    const dvec3& b = v[(i + 1) % v.size()];
    n.x += (a.y - b.y) * (a.z + b.z);
    n.y += (a.z - b.z) * (a.x + b.x);
    n.z += (a.x - b.x) * (a.y + b.y);
  }
  return n;
}

void readPolygon(const JsonNode& obj, LoadContext& ctx) {
  obj.allowKeys({"type", "name", "vertices", "material"});
  JsonNode verts = obj.at("vertices");
  verts.expectArray();
  if (verts.size() < 3) verts.fail("a polygon needs at least 3 vertices, got " + std::to_string(verts.size()));
  if (verts.size() > kMaxPolygonVertices) {
    verts.fail("at most " + std::to_string(kMaxPolygonVertices) + " vertices, got " + std::to_string(verts.size()));
  }
  Polygon poly;
  for (std::size_t i = 0; i < verts.size(); ++i) poly.vertices.push_back(readPoint(verts[i]));
  const auto& v = poly.vertices;
  double extent = 0.0;
  for (std::size_t i = 0; i < v.size(); ++i) {
    double edge = glm::length(v[(i + 1) % v.size()] - v[i]);
    if (edge == 0.0) {
      verts[(i + 1) % v.size()].fail("repeats the previous vertex (zero-length edge)");
    }
    extent = std::max(extent, edge);
  }
  dvec3 n = newellNormal(v);
  double len = glm::length(n);
  if (!(len > 1e-12 * extent * extent)) verts.fail("is degenerate: its vertices are collinear");
  n /= len;
  // Planarity: every vertex within a relative 1e-6 of the plane through their centroid.
  dvec3 centroid(0.0);
  for (auto& p : v) centroid += p;
  centroid /= static_cast<double>(v.size());
  bool planar = true;
  for (std::size_t i = 0; i < v.size(); ++i) planar = planar && std::abs(glm::dot(n, v[i] - centroid)) <= 1e-6 * extent;
  if (!planar) {
    // Off the plane through all of them, every vertex of a twisted quad is equally far: the one to
    // name is the vertex furthest from the plane of the others, where the others lie flattest.
    std::size_t worst = 0;
    double worstScore = -1.0, worstDistance = 0.0;
    for (std::size_t i = 0; i < v.size(); ++i) {
      std::vector<dvec3> others;
      for (std::size_t j = 0; j < v.size(); ++j) {
        if (j != i) others.push_back(v[j]);
      }
      dvec3 on = newellNormal(others);
      if (!(glm::length(on) > 0.0)) continue; // the others are collinear: no plane
      on = glm::normalize(on);
      dvec3 oc(0.0);
      for (auto& p : others) oc += p;
      oc /= static_cast<double>(others.size());
      double residual = 0.0;
      for (auto& p : others) residual = std::max(residual, std::abs(glm::dot(on, p - oc)));
      double d = std::abs(glm::dot(on, v[i] - oc));
      if (d - residual > worstScore) {
        worst = i;
        worstScore = d - residual;
        worstDistance = d;
      }
    }
    verts.fail("is not planar: vertex " + std::to_string(worst) + " is " + formatNumber(worstDistance) +
               " off the plane of the others");
  }
  // Convexity: every turn the same way round the normal, and one full turn in total (a star
  // pentagram turns the same way everywhere but twice around).
  double turning = 0.0;
  for (std::size_t i = 0; i < v.size(); ++i) {
    dvec3 e0 = v[(i + 1) % v.size()] - v[i];
    dvec3 e1 = v[(i + 2) % v.size()] - v[(i + 1) % v.size()];
    double cross = glm::dot(glm::cross(e0, e1), n);
    if (cross < -1e-9 * glm::length(e0) * glm::length(e1)) {
      verts.fail("is not convex: it turns the other way at vertex " + std::to_string((i + 1) % v.size()));
    }
    turning += std::atan2(cross, glm::dot(e0, e1));
  }
  if (std::abs(turning - 2.0 * M_PI) > 1e-3) verts.fail("is not convex: its edges cross each other");
  poly.normal = n;
  poly.material = readObjectMaterial(obj, ctx);
  ctx.scene.polygons.push_back(std::move(poly));
}

void readTriangle(const JsonNode& obj, LoadContext& ctx) {
  obj.allowKeys({"type", "name", "vertices", "normals", "material"});
  JsonNode verts = obj.at("vertices");
  verts.expectArray();
  if (verts.size() != 3) verts.fail("a triangle needs exactly 3 vertices, got " + std::to_string(verts.size()));
  Triangle tri;
  for (std::size_t i = 0; i < 3; ++i) tri.v[i] = readPoint(verts[i]);
  dvec3 n = glm::cross(tri.v[1] - tri.v[0], tri.v[2] - tri.v[0]);
  if (glm::length(n) == 0.0) verts.fail("is degenerate (zero area)");
  if (auto normals = obj.find("normals")) {
    normals->expectArray();
    if (normals->size() != 3) normals->fail("needs exactly 3 normals, got " + std::to_string(normals->size()));
    std::array<dvec3, 3> ns;
    for (std::size_t i = 0; i < 3; ++i) ns[i] = glm::normalize((*normals)[i].nonZeroVec3());
    tri.normals = ns;
  }
  tri.material = readObjectMaterial(obj, ctx);
  ctx.scene.triangles.push_back(tri);
}

// A mesh's placement: translate / rotate / scale, or a row-major 4x4 affine `matrix`.
glm::dmat4 readTransform(const JsonNode& node) {
  node.expectObject();
  node.allowKeys({"translate", "rotate", "scale", "matrix"});
  glm::dmat4 m(1.0);
  if (auto mat = node.find("matrix")) {
    if (node.find("translate") || node.find("rotate") || node.find("scale")) {
      mat->fail("give either 'matrix' or translate/rotate/scale, not both");
    }
    mat->expectArray();
    if (mat->size() != 16) mat->fail("needs 16 numbers (4 rows of 4), got " + std::to_string(mat->size()));
    for (std::size_t i = 0; i < 16; ++i) m[static_cast<int>(i % 4)][static_cast<int>(i / 4)] = (*mat)[i].number();
    if (m[0][3] != 0.0 || m[1][3] != 0.0 || m[2][3] != 0.0 || m[3][3] != 1.0) {
      mat->fail("must be affine: its last row must be 0, 0, 0, 1");
    }
  } else {
    dvec3 translate(0.0);
    dvec3 rotate(0.0);
    dvec3 scale(1.0);
    if (auto t = node.find("translate")) translate = t->vec3();
    if (auto r = node.find("rotate")) rotate = r->vec3();
    if (auto sc = node.find("scale")) {
      if (sc->isArray()) {
        scale = sc->vec3();
      } else {
        double k = sc->number();
        scale = dvec3(k);
      }
    }
    m = composeTransform(translate, rotate, scale);
  }
  double det = glm::determinant(glm::dmat3(m));
  if (!(std::abs(det) > 0.0) || !std::isfinite(det)) node.fail("is singular (it flattens the mesh: determinant 0)");
  return m;
}

void readMesh(const JsonNode& obj, LoadContext& ctx) {
  obj.allowKeys(
      {"type", "name", "file", "transform", "material", "normals", "import_camera", "import_lights", "light_scale"});
  JsonNode fileNode = obj.at("file");
  std::string file = fileNode.string();
  if (file.empty()) fileNode.fail("must name a mesh file");
  MeshRequest request;
  request.file = ctx.baseDir / file;
  request.shownAs = request.file.lexically_normal().string();
  if (auto t = obj.find("transform")) request.worldFromMesh = readTransform(*t);
  if (obj.find("material")) request.material = readObjectMaterial(obj, ctx);
  if (auto n = obj.find("normals")) request.normals = n->enumValue<MeshNormals>();
  const std::string ext = lowerExtension(request.file);
  bool gltf = ext == ".gltf" || ext == ".glb";
  if (auto c = obj.find("import_camera")) {
    request.importCamera = c->boolean();
    if (request.importCamera && !gltf) c->fail("only glTF files (.gltf, .glb) carry cameras");
    if (request.importCamera && ctx.importedCamera) {
      c->fail("a camera is already imported by " + ctx.importedCameraFrom);
    }
  }
  if (auto l = obj.find("import_lights")) {
    request.importLights = l->boolean();
    if (request.importLights && !gltf) l->fail("only glTF files (.gltf, .glb) carry lights");
  }
  if (auto k = obj.find("light_scale")) request.lightScale = k->number(0.0, 1e6);
  request.defaultMaterial = [&ctx] { return defaultMaterial(ctx); };
  std::optional<Camera> camera;
  try {
    camera = importMesh(request, ctx.scene);
  } catch (const InputError& e) {
    fileNode.fail(e.what());
  }
  if (camera) {
    ctx.importedCamera = camera;
    ctx.importedCameraFrom = obj.path();
  }
}

void readObjects(const JsonNode& node, LoadContext& ctx) {
  std::map<std::string, std::string> names; // object name -> JSON path of the object that took it
  for (std::size_t i = 0; i < node.size(); ++i) {
    JsonNode obj = node[i];
    obj.expectObject();
    std::string type = obj.at("type").choice({"sphere", "plane", "polygon", "triangle", "mesh"});
    // A "name" lets the animation refer to the object: remember which primitives it made.
    std::optional<std::string> name;
    if (auto n = obj.find("name")) {
      name = n->string();
      if (name->empty()) n->fail("must not be empty");
      if (auto it = names.find(*name); it != names.end()) n->fail("'" + *name + "' names " + it->second + " already");
      names[*name] = obj.path();
    }
    const Scene& s = ctx.scene;
    const std::size_t before[] = {s.spheres.size(), s.planes.size(), s.polygons.size(), s.triangles.size()};
    if (type == "sphere") {
      obj.allowKeys({"type", "name", "center", "radius", "material"});
      Sphere s;
      s.center = readPoint(obj.at("center"));
      JsonNode radius = obj.at("radius");
      s.radius = radius.positive();
      if (s.radius > kMaxCoordinate) {
        radius.fail("must be at most " + formatNumber(kMaxCoordinate) + ", got " + formatNumber(s.radius) + ": " +
                    squaredPastFloat(s.radius, "the radius (radius^2 in the sphere test)"));
      }
      s.material = readObjectMaterial(obj, ctx);
      ctx.scene.spheres.push_back(s);
    } else if (type == "plane") {
      obj.allowKeys({"type", "name", "normal", "offset", "point", "material"});
      Plane p;
      dvec3 n = obj.at("normal").nonZeroVec3();
      double len = glm::length(n);
      p.normal = n / len;
      if (obj.find("offset") && obj.find("point")) obj.fail("give either 'offset' or 'point', not both");
      if (auto d = obj.find("offset")) {
        p.offset = d->number() / len;
        if (std::abs(p.offset) > kMaxCoordinate) {
          d->fail("puts the plane " + formatNumber(std::abs(p.offset)) + " from the origin, past " +
                  formatNumber(kMaxCoordinate) + ": " + squaredPastFloat(p.offset, "distances"));
        }
      }
      if (auto pt = obj.find("point")) p.offset = -glm::dot(p.normal, readPoint(*pt));
      p.material = readObjectMaterial(obj, ctx);
      ctx.scene.planes.push_back(p);
    } else if (type == "polygon") {
      readPolygon(obj, ctx);
    } else if (type == "triangle") {
      readTriangle(obj, ctx);
    } else if (type == "mesh") {
      readMesh(obj, ctx);
    }
    if (name) {
      NamedObject named;
      named.name = *name;
      if (type == "sphere") named = {*name, ObjectKind::Sphere, before[0], 1};
      if (type == "plane") named = {*name, ObjectKind::Plane, before[1], 1};
      if (type == "polygon") named = {*name, ObjectKind::Polygon, before[2], 1};
      if (type == "triangle") named = {*name, ObjectKind::Triangle, before[3], 1};
      if (type == "mesh") named = {*name, ObjectKind::Mesh, before[3], s.triangles.size() - before[3]};
      ctx.scene.namedObjects.push_back(named);
    }
    if (ctx.scene.objectCount() > kMaxPrimitives) {
      obj.fail("too many primitives: more than " + std::to_string(kMaxPrimitives));
    }
  }
}

Scene buildScene(const nlohmann::json& doc, const std::string& name, const std::filesystem::path& baseDir) {
  Scene scene;
  LoadContext ctx{scene, {}, baseDir, std::nullopt, {}};
  JsonNode root(doc, "", name);
  root.expectObject();
  root.allowKeys({"description", "base", "camera", "image", "background", "ambient", "render", "materials", "lights",
                  "objects", "animation"});
  if (auto d = root.find("description")) d->string();
  // The camera may instead come from a glTF file (a mesh object with import_camera).
  auto cameraNode = root.find("camera");
  glm::dvec3 fitFrom = kThreeQuarterView;
  bool fit = cameraNode && readCamera(*cameraNode, scene.camera, fitFrom);
  bool sawBackground = false;
  bool sawAmbient = false;
  if (auto img = root.find("image")) readImage(*img, scene, sawBackground, sawAmbient);
  if (auto bg = root.find("background")) {
    if (sawBackground) bg->fail("given twice (also as image.background)");
    scene.background = bg->color();
  }
  if (auto amb = root.find("ambient")) {
    if (sawAmbient) amb->fail("given twice (also as image.ambient)");
    scene.ambientLight = amb->color();
  }
  if (auto r = root.find("render")) readRender(*r, scene.render);
  if (auto m = root.find("materials")) readMaterials(*m, ctx);
  if (auto l = root.find("lights")) readLights(*l, scene);
  if (auto o = root.find("objects")) readObjects(*o, ctx);
  if (ctx.importedCamera) {
    if (cameraNode) cameraNode->fail("given twice (" + ctx.importedCameraFrom + " imports one: import_camera)");
    scene.camera = *ctx.importedCamera;
  } else if (!cameraNode) {
    root.at("camera"); // throws: missing required key
  } else if (fit) {
    double aspect = static_cast<double>(scene.render.width) / scene.render.height;
    Camera fitted = fitCamera(sceneBounds(scene), fitFrom, scene.camera.fovY, aspect, name + ": camera.fit");
    fitted.up = scene.camera.up;
    fitted.aperture = scene.camera.aperture;
    fitted.focusDistance = scene.camera.focusDistance;
    scene.camera = fitted;
    scene.fitFrom = fitFrom;
  }
  if (scene.materials.size() > kMaxMaterialCount) {
    root.at("materials")
        .fail("too many materials: " + std::to_string(scene.materials.size()) + " (at most " +
              std::to_string(kMaxMaterialCount) + ")");
  }
  if (auto a = root.find("animation")) {
    scene.path = name; // for the animation's messages
    scene.animation = std::make_shared<const Animation>(readAnimation(*a, scene));
  }
  return scene;
}

} // namespace

namespace {

std::string readSceneFile(const std::filesystem::path& path, const std::string& shownAs) {
  std::error_code ec;
  auto status = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(status)) throw InputError(shownAs, "no such file");
  if (std::filesystem::is_directory(status)) throw InputError(shownAs, "is a directory, not a scene file");
  auto size = std::filesystem::file_size(path, ec);
  if (!ec && size > kMaxSceneFileBytes) {
    throw InputError(shownAs, "file too large to be a scene (" + std::to_string(size) + " bytes; at most " +
                                  std::to_string(kMaxSceneFileBytes) + ")");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(shownAs, "cannot open for reading");
  // Read no further than the cap: a device or a pipe (/dev/zero, a FIFO) has no size to check first.
  std::string text;
  std::vector<char> chunk(1 << 16);
  while (in.read(chunk.data(), static_cast<std::streamsize>(chunk.size())) || in.gcount() > 0) {
    text.append(chunk.data(), static_cast<std::size_t>(in.gcount()));
    if (text.size() > kMaxSceneFileBytes) {
      throw InputError(shownAs,
                       "file too large to be a scene (more than " + std::to_string(kMaxSceneFileBytes) + " bytes)");
    }
  }
  if (in.bad()) throw InputError(shownAs, "cannot read");
  return text;
}

// Whether a file's text opens a JSON object: its first character after white space, a UTF-8
// byte-order mark and comments (which the parser skips) is '{'.
bool opensAnObject(const std::string& text) {
  std::size_t i = text.rfind("\xEF\xBB\xBF", 0) == 0 ? 3 : 0;
  while (i < text.size()) {
    if (std::isspace(static_cast<unsigned char>(text[i]))) {
      ++i;
    } else if (text.compare(i, 2, "//") == 0) {
      i = text.find('\n', i);
    } else if (text.compare(i, 2, "/*") == 0) {
      i = text.find("*/", i + 2);
      if (i != std::string::npos) i += 2;
    } else {
      return text[i] == '{';
    }
  }
  return false;
}

// "base": "other.json" makes a scene a patch of another (RFC 7386 JSON merge patch): objects merge
// key by key, anything else (arrays included) replaces. Chains are followed up to a depth of 8.
nlohmann::json resolveBase(nlohmann::json doc, const std::string& name, const std::filesystem::path& baseDir,
                           int depth) {
  if (!doc.is_object() || !doc.contains("base")) return doc;
  JsonNode node(doc["base"], "base", name);
  std::string baseName = node.string();
  if (depth >= 8) node.fail("too many nested base scenes (a cycle?)");
  std::filesystem::path basePath = baseDir / baseName;
  nlohmann::json base;
  try {
    base = parseJsonText(readSceneFile(basePath, basePath.string()), basePath.string());
  } catch (const InputError& e) {
    node.fail(e.what()); // names the key that brought the file in
  }
  base = resolveBase(std::move(base), basePath.string(), basePath.parent_path(), depth + 1);
  doc.erase("base");
  base.merge_patch(doc);
  return base;
}

} // namespace

Scene loadSceneFromString(const std::string& text, const std::string& name, const std::filesystem::path& baseDir) {
  if (text.size() > kMaxSceneFileBytes) {
    throw InputError(name, "file too large to be a scene (" + std::to_string(text.size()) + " bytes; at most " +
                               std::to_string(kMaxSceneFileBytes) + ")");
  }
  nlohmann::json doc = resolveBase(parseJsonText(text, name), name, baseDir, 0);
  Scene scene = buildScene(doc, name, baseDir);
  scene.path = name;
  return scene;
}

Scene loadScene(const std::filesystem::path& path, const ModelSceneOptions& model) {
  if (isModelFile(path)) return loadModelScene(path, model);
  std::string text = readSceneFile(path, path.string());
  // A file that is not JSON and not named .json is most likely a model in a format vkray does not
  // read (STL, FBX, 3DS, ...): say so, instead of the JSON parser's complaint about its first byte.
  const std::string ext = lowerExtension(path);
  if (ext != ".json" && !opensAnObject(text)) {
    throw InputError(path.string(), "neither a JSON scene (it does not begin with '{') nor a model vkray reads "
                                    "(.obj, .gltf, .glb, .ply); convert other model formats, e.g. with assimp "
                                    "export (Debian's assimp-utils)");
  }
  Scene scene = loadSceneFromString(text, path.string(), path.parent_path());
  scene.path = path;
  return scene;
}

} // namespace vkray
