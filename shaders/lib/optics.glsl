// Dielectric interfaces: Fresnel reflectance (exact or Schlick) and the refracted direction, with
// total internal reflection handled explicitly. No buffer access: the probe tests these directly.
#ifndef VKRAY_OPTICS_GLSL
#define VKRAY_OPTICS_GLSL

// Reflectance of an interface n1 -> n2 for incident cosine cosI (>= 0); 1 beyond the critical angle.
float fresnelDielectric(float cosI, float n1, float n2, bool schlick) {
  float eta = n1 / n2;
  float sin2T = eta * eta * max(0.0, 1.0 - cosI * cosI);
  if (sin2T >= 1.0) return 1.0; // total internal reflection
  float cosT = sqrt(max(0.0, 1.0 - sin2T));
  if (schlick) {
    // Schlick (1994), with the cosine taken on the optically thinner side so that the
    // approximation reaches 1 exactly where total internal reflection begins.
    float r0 = (n1 - n2) / (n1 + n2);
    r0 *= r0;
    float c = n1 <= n2 ? cosI : cosT;
    float m = 1.0 - c;
    return r0 + (1.0 - r0) * (m * m) * (m * m) * m;
  }
  float rs = (n1 * cosI - n2 * cosT) / (n1 * cosI + n2 * cosT);
  float rp = (n1 * cosT - n2 * cosI) / (n1 * cosT + n2 * cosI);
  return clamp(0.5 * (rs * rs + rp * rp), 0.0, 1.0);
}

// The two branches at a dielectric hit. dir: unit incident direction; nsf/ngf: shading and
// geometric normals facing the incoming ray. fresnel = 1 and refracted = 0 on total internal
// reflection (including the grazing cases where refract() would return a zero vector).
struct DielectricSplit {
  float fresnel;
  vec3 refracted; // unit, or zero
};

DielectricSplit dielectricSplit(vec3 dir, vec3 nsf, vec3 ngf, float n1, float n2, bool schlick) {
  DielectricSplit s;
  float cosI = clamp(-dot(dir, nsf), 0.0, 1.0);
  s.fresnel = fresnelDielectric(cosI, n1, n2, schlick);
  s.refracted = vec3(0.0);
  if (s.fresnel < 1.0) {
    float eta = n1 / n2;
    vec3 t = refract(dir, nsf, eta);
    // A smooth normal can bend the refracted ray back out: refract about the true face instead.
    if (dot(t, ngf) >= 0.0) t = refract(dir, ngf, eta);
    float len2 = dot(t, t);
    if (len2 > 0.0 && dot(t, ngf) < 0.0) {
      s.refracted = t * inversesqrt(len2);
    } else {
      s.fresnel = 1.0;
    }
  }
  return s;
}

// Mirror direction about the shading normal, falling back to the geometric one when a smooth
// normal would send the ray below the surface.
vec3 mirrorDirection(vec3 dir, vec3 nsf, vec3 ngf) {
  vec3 r = reflect(dir, nsf);
  if (dot(r, ngf) <= 0.0) r = reflect(dir, ngf);
  return normalize(r);
}

#endif
