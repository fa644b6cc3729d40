// Canonical hash of a resolved Scene (see scene_fingerprint.h).
#include "scene/scene_fingerprint.h"

#include <cstdio>
#include <cstring>

#include "util/fnv_hash.h"

namespace vkray {

namespace {

// The scene's values into FNV-1a (util/fnv_hash.h), doubles as their bits.
class Hasher : public Fnv1a {
public:
  void f64(double v) {
    if (v == 0.0) v = 0.0; // -0 and +0 render alike
    std::uint64_t bits;
    std::memcpy(&bits, &v, sizeof bits);
    u64(bits);
  }
  void vec(const glm::dvec2& v) {
    f64(v.x);
    f64(v.y);
  }
  void vec(const glm::dvec3& v) {
    f64(v.x);
    f64(v.y);
    f64(v.z);
  }
  void vec(const glm::dvec4& v) {
    vec(glm::dvec3(v));
    f64(v.w);
  }
};

// A decoded texture: its sampling and its image. The mip levels below level 0 are built from it
// (buildMipChain), so their sizes stand for them.
void hashTexture(Hasher& h, const Texture& t) {
  h.u64(static_cast<std::uint64_t>(t.wrapS));
  h.u64(static_cast<std::uint64_t>(t.wrapT));
  h.u64(t.nearest ? 1 : 0);
  h.u64(static_cast<std::uint64_t>(t.minFilter));
  h.u64(t.levels.size());
  for (const TextureLevel& level : t.levels) {
    h.u64(level.width);
    h.u64(level.height);
  }
  if (!t.levels.empty()) {
    const auto& texels = t.levels[0].texels;
    h.u64(texels.size());
    h.words(texels.data(), texels.size() * sizeof(glm::vec4));
  }
}

} // namespace

std::string sceneFingerprint(const Scene& s, int frame) {
  Hasher h;
  h.u64(3); // encoding version (3: the progressive, forward and seed settings)
  h.u64(static_cast<std::uint64_t>(frame));
  const RenderSettings& r = s.render;
  h.u64(r.width);
  h.u64(r.height);
  h.u64(static_cast<std::uint64_t>(r.maxDepth));
  h.u64(static_cast<std::uint64_t>(r.spp));
  h.f64(r.bailout);
  h.u64(static_cast<std::uint64_t>(r.antialiasing));
  h.f64(r.adaptiveThreshold);
  h.u64(static_cast<std::uint64_t>(r.numerics));
  h.u64(static_cast<std::uint64_t>(r.fresnel));
  h.u64(static_cast<std::uint64_t>(r.transmissiveShadows));
  h.u64(static_cast<std::uint64_t>(r.bvh));
  h.u64(static_cast<std::uint64_t>(r.precision));
  h.u64(static_cast<std::uint64_t>(r.textureFilter));
  // What else decides the pixels: a noise threshold's or time limit's passes, a forward render's
  // photons, the sample sequences' scrambling.
  h.f64(r.noiseThreshold);
  h.f64(r.timeLimit);
  h.u64(static_cast<std::uint64_t>(r.minSpp));
  h.u64(static_cast<std::uint64_t>(r.maxSpp));
  h.u64(static_cast<std::uint64_t>(r.method));
  h.u64(r.photons);
  h.u64(r.seed);
  h.vec(s.camera.position);
  h.vec(s.camera.lookAt);
  h.vec(s.camera.up);
  h.f64(s.camera.fovY);
  h.vec(s.background);
  h.vec(s.ambientLight);
  h.u64(s.materials.size());
  for (const Material& m : s.materials) {
    h.vec(m.color);
    for (double v : {m.ambient, m.diffuse, m.specular, m.shininess, m.reflection, m.transmission, m.ior}) h.f64(v);
    h.vec(m.absorption);
    h.u64(m.checker ? 1 : 0);
    if (m.checker) {
      h.vec(m.checker->color2);
      h.f64(m.checker->scale);
    }
    h.u64(m.baseColorTexture ? 1 : 0);
    if (const auto& t = m.baseColorTexture) {
      h.u64(t->texture);
      h.u64(t->texCoord);
      h.vec(t->transform.offset);
      h.f64(t->transform.rotation);
      h.vec(t->transform.scale);
    }
    h.f64(m.alphaCutoff);
    h.f64(m.alpha);
  }
  h.u64(s.lights.size());
  for (const PointLight& l : s.lights) {
    h.vec(l.position);
    h.vec(l.color);
    h.u64(l.shadows ? 1 : 0);
  }
  h.u64(s.spheres.size());
  for (const Sphere& sp : s.spheres) {
    h.vec(sp.center);
    h.f64(sp.radius);
    h.u64(sp.material);
  }
  h.u64(s.planes.size());
  for (const Plane& p : s.planes) {
    h.vec(p.normal);
    h.f64(p.offset);
    h.u64(p.material);
  }
  h.u64(s.polygons.size());
  for (const Polygon& p : s.polygons) {
    h.u64(p.vertices.size());
    for (const auto& v : p.vertices) h.vec(v);
    h.vec(p.normal);
    h.u64(p.material);
  }
  h.u64(s.triangles.size());
  for (const Triangle& t : s.triangles) {
    for (const auto& v : t.v) h.vec(v);
    h.u64(t.normals ? 1 : 0);
    if (t.normals) {
      for (const auto& n : *t.normals) h.vec(n);
    }
    h.u64(t.uvs ? 1 : 0);
    if (t.uvs) {
      for (const auto& uv : *t.uvs) h.vec(uv);
    }
    h.u64(t.colors ? 1 : 0);
    if (t.colors) {
      for (const auto& c : *t.colors) h.vec(c);
    }
    h.u64(t.material);
  }
  h.u64(s.textures.size());
  for (const auto& t : s.textures) {
    h.u64(t ? 1 : 0);
    if (t) hashTexture(h, *t);
  }
  char text[17];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(h.value()));
  return text;
}

} // namespace vkray
