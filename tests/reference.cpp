// Double-precision reference tracer (see reference.h).
#include "reference.h"

#include <algorithm>
#include <cmath>

#include "render/gpu_scene.h"

namespace vkray::test {

using glm::dvec3;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

bool hitSphere(const Sphere& s, const dvec3& o, const dvec3& d, double tMin, double tMax, double& t) {
  dvec3 f = o - s.center;
  double a = glm::dot(d, d);
  double b = glm::dot(f, d);
  double c = glm::dot(f, f) - s.radius * s.radius;
  double disc = b * b - a * c;
  if (disc < 0) return false;
  double sq = std::sqrt(disc);
  double t0 = (-b - sq) / a;
  double t1 = (-b + sq) / a;
  if (t0 > tMin && t0 < tMax) {
    t = t0;
    return true;
  }
  if (t1 > tMin && t1 < tMax) {
    t = t1;
    return true;
  }
  return false;
}

bool hitPlaneOf(const dvec3& n, double dOffset, const dvec3& o, const dvec3& d, double tMin, double tMax, double& t) {
  double denom = glm::dot(n, d);
  if (denom == 0) return false;
  double tt = -(glm::dot(n, o) + dOffset) / denom;
  if (tt > tMin && tt < tMax) {
    t = tt;
    return true;
  }
  return false;
}

// Inside test for a convex planar polygon: the point is on the inner side of every edge.
bool insideConvex(const std::vector<dvec3>& v, const dvec3& n, const dvec3& p) {
  for (std::size_t i = 0; i < v.size(); ++i) {
    const dvec3& a = v[i];
    const dvec3& b = v[(i + 1) % v.size()];
    if (glm::dot(glm::cross(b - a, p - a), n) < 0) return false;
  }
  return true;
}

double fresnel(double cosI, double n1, double n2) {
  double eta = n1 / n2;
  double sin2T = eta * eta * std::max(0.0, 1 - cosI * cosI);
  if (sin2T >= 1) return 1;
  double cosT = std::sqrt(1 - sin2T);
  double rs = (n1 * cosI - n2 * cosT) / (n1 * cosI + n2 * cosT);
  double rp = (n1 * cosT - n2 * cosI) / (n1 * cosT + n2 * cosI);
  return 0.5 * (rs * rs + rp * rp);
}

} // namespace

ReferenceTracer::ReferenceTracer(const Scene& scene) : scene_(scene) {}

RefHit ReferenceTracer::closestHit(const dvec3& o, const dvec3& d, double tMin, double tMax) const {
  RefHit h;
  h.t = tMax;
  double t = 0;
  for (std::size_t i = 0; i < scene_.spheres.size(); ++i) {
    if (hitSphere(scene_.spheres[i], o, d, tMin, h.t, t)) {
      h.t = t;
      h.kind = 0;
      h.index = i;
    }
  }
  for (std::size_t i = 0; i < scene_.planes.size(); ++i) {
    const Plane& p = scene_.planes[i];
    if (hitPlaneOf(p.normal, p.offset, o, d, tMin, h.t, t)) {
      h.t = t;
      h.kind = 1;
      h.index = i;
    }
  }
  for (std::size_t i = 0; i < scene_.polygons.size(); ++i) {
    const Polygon& poly = scene_.polygons[i];
    double off = -glm::dot(poly.normal, poly.vertices[0]);
    if (hitPlaneOf(poly.normal, off, o, d, tMin, h.t, t) && insideConvex(poly.vertices, poly.normal, o + t * d)) {
      h.t = t;
      h.kind = 2;
      h.index = i;
    }
  }
  for (std::size_t i = 0; i < scene_.triangles.size(); ++i) {
    const Triangle& tri = scene_.triangles[i];
    dvec3 n = glm::normalize(glm::cross(tri.v[1] - tri.v[0], tri.v[2] - tri.v[0]));
    std::vector<dvec3> v{tri.v[0], tri.v[1], tri.v[2]};
    if (hitPlaneOf(n, -glm::dot(n, tri.v[0]), o, d, tMin, h.t, t) && insideConvex(v, n, o + t * d)) {
      h.t = t;
      h.kind = 3;
      h.index = i;
    }
  }
  if (!h.hit()) {
    h.t = kInf;
    return h;
  }
  h.p = o + h.t * d;
  switch (h.kind) {
  case 0:
    h.n = glm::normalize(h.p - scene_.spheres[h.index].center);
    h.material = scene_.spheres[h.index].material;
    break;
  case 1:
    h.n = scene_.planes[h.index].normal;
    h.material = scene_.planes[h.index].material;
    break;
  case 2:
    h.n = scene_.polygons[h.index].normal;
    h.material = scene_.polygons[h.index].material;
    break;
  default: {
    const Triangle& tri = scene_.triangles[h.index];
    h.n = glm::normalize(glm::cross(tri.v[1] - tri.v[0], tri.v[2] - tri.v[0]));
    h.material = tri.material;
  }
  }
  return h;
}

dvec3 ReferenceTracer::eyeDirection(double px, double py) const {
  CameraFrame cam = makeCameraFrame(scene_.camera, scene_.render.width, scene_.render.height);
  return glm::normalize(cam.rayDirection(px, py, scene_.render.width, scene_.render.height));
}

dvec3 ReferenceTracer::baseColor(const RefHit& h) const {
  const Material& m = scene_.materials[h.material];
  if (!m.checker) return m.color;
  // 3-D checker evaluated just behind the surface (see shaders/lib/shade.glsl).
  dvec3 q = (h.p - h.n * 1e-7) / m.checker->scale;
  double cells = std::floor(q.x) + std::floor(q.y) + std::floor(q.z);
  bool odd = std::fmod(std::abs(cells), 2.0) == 1.0;
  return odd ? m.checker->color2 : m.color;
}

dvec3 ReferenceTracer::shadowTransmittance(const dvec3& p, const dvec3& light, RefHit* blocker) const {
  dvec3 o = p;
  dvec3 transmit(1.0);
  double enteredAt = 0.0;
  double travelled = 0.0;
  for (int crossing = 0; crossing < 8; ++crossing) {
    dvec3 toL = light - o;
    double dist = glm::length(toL);
    dvec3 d = toL / dist;
    RefHit h = closestHit(o, d, 1e-9 * (1.0 + glm::length(o)), dist);
    if (!h.hit()) return transmit;
    const Material& m = scene_.materials[h.material];
    bool opaque = m.transmission <= 0 || scene_.render.transmissiveShadows == TransmissiveShadows::Opaque;
    if (opaque) {
      if (blocker) *blocker = h;
      return dvec3(0.0);
    }
    transmit *= m.transmission;
    double here = travelled + h.t;
    if (glm::dot(h.n, d) < 0) {
      enteredAt = here;
    } else {
      for (int c = 0; c < 3; ++c) {
        if (m.absorption[c] > 0) transmit[c] *= std::exp(-m.absorption[c] * (here - enteredAt));
      }
    }
    travelled = here;
    o = h.p;
  }
  return transmit;
}

dvec3 ReferenceTracer::localShade(const RefHit& h, const dvec3& d) const {
  return shade(h, d, dvec3(1.0), nullptr, "");
}

dvec3 ReferenceTracer::shade(const RefHit& h, const dvec3& d, const dvec3& weight, std::vector<RefTreeRay>* tree,
                             const std::string& path) const {
  const Material& m = scene_.materials[h.material];
  dvec3 base = baseColor(h);
  dvec3 color = m.ambient * base * scene_.ambientLight;
  if (tree) tree->back().contribution += weight * color; // the ray being shaded was recorded last
  if (m.diffuse <= 0 && m.specular <= 0) return color;
  dvec3 n = glm::dot(h.n, d) < 0 ? h.n : -h.n;
  dvec3 v = -d;
  for (std::size_t li = 0; li < scene_.lights.size(); ++li) {
    const PointLight& light = scene_.lights[li];
    dvec3 toL = light.position - h.p;
    double dist = glm::length(toL);
    if (dist <= 0) continue;
    dvec3 l = toL / dist;
    double ndotl = glm::dot(n, l);
    if (ndotl <= 0) continue;
    dvec3 r = 2.0 * ndotl * n - l;
    double rv = glm::dot(r, v);
    double spec = (m.specular > 0 && rv > 0) ? m.specular * std::pow(rv, m.shininess) : 0.0;
    // As the kernel: a light that could add only a negligible highlight to the pixel is not sampled.
    const dvec3 reach = weight * light.color;
    if (m.diffuse <= 0 && std::max({reach.x, reach.y, reach.z}) * spec < gpu::kNegligibleHighlight) continue;
    dvec3 visible(1.0);
    RefHit blocker;
    if (light.shadows) visible = shadowTransmittance(h.p, light.position, &blocker);
    color += visible * light.color * (m.diffuse * ndotl * base + spec);
    if (tree) {
      RefTreeRay s;
      s.path = path + "/L" + std::to_string(li);
      s.kind = 3;
      s.outcome = !light.shadows ? 4 : blocker.hit() ? 3 : 2;
      s.objectKind = blocker.kind;
      s.objectIndex = blocker.index;
      s.contribution = weight * visible * light.color * (m.diffuse * ndotl * base + spec);
      tree->push_back(s);
    }
  }
  return color;
}

dvec3 ReferenceTracer::trace(const dvec3& o, const dvec3& d, int depth, dvec3 weight, std::vector<std::uint32_t> media,
                             std::vector<RefTreeRay>* tree, const std::string& path, int kind) const {
  RefHit h = closestHit(o, d, 1e-9 * (1.0 + glm::length(o)));
  dvec3 w = weight;
  if (!media.empty()) {
    const dvec3& sigma = scene_.materials[media.back()].absorption;
    for (int c = 0; c < 3; ++c) {
      if (sigma[c] > 0) w[c] *= std::exp(-sigma[c] * h.t);
    }
  }
  if (tree) {
    RefTreeRay r;
    r.path = path;
    r.kind = kind;
    r.outcome = h.hit() ? 1 : 0;
    r.objectKind = h.kind;
    r.objectIndex = h.index;
    r.contribution = h.hit() ? dvec3(0.0) : w * scene_.background;
    tree->push_back(r);
  }
  if (!h.hit()) return w * scene_.background;
  const Material& m = scene_.materials[h.material];
  dvec3 color = w * shade(h, d, w, tree, path);
  if (depth >= scene_.render.maxDepth) return color;
  bool front = glm::dot(h.n, d) < 0;
  dvec3 n = front ? h.n : -h.n;
  double kr = m.reflection;
  double kt = 0;
  dvec3 tdir(0.0);
  std::vector<std::uint32_t> tmedia = media;
  if (m.transmission > 0) {
    double n1, n2;
    if (front) {
      n1 = media.empty() ? 1.0 : scene_.materials[media.back()].ior;
      n2 = m.ior;
      tmedia.push_back(h.material);
    } else {
      n1 = m.ior;
      auto it = std::find(tmedia.rbegin(), tmedia.rend(), h.material);
      if (it != tmedia.rend()) tmedia.erase(std::next(it).base());
      n2 = tmedia.empty() ? 1.0 : scene_.materials[tmedia.back()].ior;
    }
    double cosI = std::clamp(-glm::dot(d, n), 0.0, 1.0);
    double F = fresnel(cosI, n1, n2);
    kr += m.transmission * F;
    kt = m.transmission * (1 - F);
    if (kt > 0) {
      double eta = n1 / n2;
      double k = 1 - eta * eta * (1 - cosI * cosI);
      tdir = glm::normalize(eta * d + (eta * cosI - std::sqrt(k)) * n);
    }
  }
  double bail = scene_.render.bailout;
  auto worth = [&](const dvec3& ww) {
    double mx = std::max({ww.x, ww.y, ww.z});
    return mx > 0 && mx >= bail;
  };
  if (worth(w * kr)) {
    dvec3 rdir = glm::normalize(d - 2.0 * glm::dot(d, n) * n);
    color += trace(h.p, rdir, depth + 1, w * kr, media, tree, path + "/R", 1);
  }
  if (worth(w * kt)) color += trace(h.p, tdir, depth + 1, w * kt, tmedia, tree, path + "/T", 2);
  return color;
}

dvec3 ReferenceTracer::radiance(const dvec3& o, const dvec3& d) const {
  return trace(o, d, 0, dvec3(1.0), {});
}

dvec3 ReferenceTracer::radiance(const dvec3& o, const dvec3& d, std::vector<RefTreeRay>& tree) const {
  return trace(o, d, 0, dvec3(1.0), {}, &tree);
}

Image ReferenceTracer::render() const {
  Image img(scene_.render.width, scene_.render.height);
  for (std::uint32_t y = 0; y < img.height; ++y) {
    for (std::uint32_t x = 0; x < img.width; ++x) {
      img.at(x, y) = glm::vec3(radiance(eyeOrigin(), eyeDirection(x + 0.5, y + 0.5)));
    }
  }
  return img;
}

} // namespace vkray::test
