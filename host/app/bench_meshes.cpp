// `vkray bench meshes`: for procedural meshes from 1k to 1M triangles, the BVH's build time,
// size and depth and the GPU's primary- and shadow-ray throughput at 800x600; and, when built
// with Embree 3, the same triangles and the same rays through rtcIntersect1 / rtcOccluded1.
// Figures only, never pass/fail (docs/performance.md, "Meshes").
#include "app/bench_meshes.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <string>
#include <thread>

#include <sys/resource.h>

#include "app/bench.h"
#include "render/gpu_scene.h"
#include "render/renderer.h"
#include "util/clock.h"
#include "util/error.h"
#include "vk/context.h"

#ifdef VKRAY_HAVE_EMBREE
#include <embree3/rtcore.h>
#endif

namespace vkray {

MeshData proceduralTorus(std::size_t triangles) {
  // u around the ring, v around the tube; 2 u v triangles, u = 2 v.
  auto v = static_cast<std::size_t>(std::max(2.0, std::round(std::sqrt(static_cast<double>(triangles) / 4.0))));
  std::size_t u = 2 * v;
  const double ringRadius = 1.0;
  const double tubeRadius = 0.35;
  MeshData mesh;
  mesh.positions.reserve(u * v);
  for (std::size_t i = 0; i < u; ++i) {
    double a = 2.0 * M_PI * static_cast<double>(i) / static_cast<double>(u);
    for (std::size_t j = 0; j < v; ++j) {
      double b = 2.0 * M_PI * static_cast<double>(j) / static_cast<double>(v);
      // Bumps at two scales, so that small triangles still see curvature.
      double r =
          tubeRadius * (1.0 + 0.12 * std::sin(7.0 * a) * std::sin(5.0 * b) + 0.03 * std::sin(41.0 * a + 3.0 * b));
      mesh.positions.emplace_back((ringRadius + r * std::cos(b)) * std::cos(a), r * std::sin(b),
                                  (ringRadius + r * std::cos(b)) * std::sin(a));
    }
  }
  auto id = [&](std::size_t i, std::size_t j) { return static_cast<std::uint32_t>((i % u) * v + (j % v)); };
  mesh.faces.reserve(2 * u * v);
  for (std::size_t i = 0; i < u; ++i) {
    for (std::size_t j = 0; j < v; ++j) {
      // Counter-clockwise seen from outside the tube.
      mesh.faces.push_back({id(i, j), id(i, j + 1), id(i + 1, j + 1)});
      mesh.faces.push_back({id(i, j), id(i + 1, j + 1), id(i + 1, j)});
    }
  }
  return mesh;
}

namespace {

// CPU time of the whole process (every lavapipe worker thread included), in ms. On a shared,
// noisy machine it varies far less than wall or GPU-timestamp time.
double processCpuMs() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return (u.ru_utime.tv_sec + u.ru_stime.tv_sec) * 1e3 + (u.ru_utime.tv_usec + u.ru_stime.tv_usec) * 1e-3;
}

// Median GPU time and mean process CPU time of `runs` renders with an already built pipeline.
std::pair<double, double> timeRenders(Renderer& renderer, const Scene& scene, const RenderOptions& options, int runs) {
  std::vector<double> gpu;
  double cpu0 = processCpuMs();
  for (int i = 0; i < runs; ++i) gpu.push_back(renderer.render(scene.camera, scene.render, options).timings.traceMs);
  return {median(gpu), (processCpuMs() - cpu0) / runs};
}

Scene benchScene(const MeshData& mesh, const BenchMeshesArgs& args, bool shadows) {
  Scene scene;
  scene.camera.position = {0.0, 1.9, 2.6};
  scene.camera.lookAt = {0.0, -0.1, 0.0};
  scene.camera.fovY = 45.0;
  scene.render.width = args.width;
  scene.render.height = args.height;
  scene.render.maxDepth = 0;
  scene.render.bvh = BvhMode::On;
  scene.ambientLight = glm::dvec3(0.2);
  scene.background = glm::dvec3(0.1, 0.1, 0.15);
  PointLight light;
  light.position = {2.0, 4.0, 1.0};
  light.shadows = shadows;
  scene.lights.push_back(light);
  MeshRequest request;
  request.shownAs = "procedural torus";
  request.normals = MeshNormals::Flat;
  appendMesh(mesh, request, scene);
  return scene;
}

struct Row {
  std::size_t triangles = 0;
  double buildMs = 0.0;
  double shadowTableMs = 0.0;   // the shadow entry points' table (0: not built)
  std::size_t nothingPairs = 0; // its (triangle, light) pairs marked "nothing between"
  std::size_t nodes = 0;
  int depth = 0;
  double bytesPerTriangle = 0.0;
  // The ray queries alone (shaders/hits.comp), the work Embree is asked for.
  double primaryMs = 0.0;    // GPU time of the eye rays' closest hits
  double shadowMs = 0.0;     // GPU time the shadow rays add (any-hit)
  double primaryCpuMs = 0.0; // process CPU time of the same (lavapipe: all worker threads)
  double shadowCpuMs = 0.0;
  std::uint64_t eyeRays = 0;
  std::uint64_t shadowRays = 0;
  std::uint64_t occluded = 0;
  // The renderer's kernel on the same eye rays: closest hit plus shading and the image.
  double renderMs = 0.0;
  double renderCpuMs = 0.0;
  // Agreement with Embree on the same rays.
  std::uint64_t hitsDiffer = 0;    // pixels one hits and the other misses
  double maxRelativeTDiff = 0.0;   // over pixels both hit
  std::uint64_t farApart = 0;      // pixels both hit more than 1e-3 (relative) apart: different surfaces
  std::uint64_t shadowsDiffer = 0; // pixels lit by one and shadowed by the other
  std::uint64_t embreeOccluded = 0;
  // Embree (0 when not measured)
  double embreeBuildMs = 0.0;
  double embreeBytesPerTriangle = 0.0;
  double embreePrimaryMs = 0.0;
  double embreeShadowMs = 0.0;
  std::uint64_t embreeShadowRays = 0;

  double primaryMrays() const { return primaryMs > 0 ? eyeRays / (primaryMs * 1e3) : 0.0; }
  double shadowMrays() const { return shadowMs > 0 ? shadowRays / (shadowMs * 1e3) : 0.0; }
  double renderMrays() const { return renderMs > 0 ? eyeRays / (renderMs * 1e3) : 0.0; }
  double embreePrimaryMrays() const { return embreePrimaryMs > 0 ? eyeRays / (embreePrimaryMs * 1e3) : 0.0; }
  double embreeShadowMrays() const { return embreeShadowMs > 0 ? embreeShadowRays / (embreeShadowMs * 1e3) : 0.0; }
};

#ifdef VKRAY_HAVE_EMBREE

std::atomic<long long> gEmbreeBytes{0};

bool embreeMemoryMonitor(void*, ssize_t bytes, bool) {
  gEmbreeBytes += bytes;
  return true;
}

// The same float triangles (camera-relative, as packed for the GPU) and the same rays: eye rays
// through pixel centres, then a shadow ray from every hit that faces the light. Both phases run on
// all cores (as lavapipe does), one rtcIntersect1 / rtcOccluded1 per ray.
// Traces the kernel's rays with Embree and compares the hits with `vkHits` (the query kernel's
// records, shaders/hits.comp).
void runEmbree(const GpuScene& g, const Scene& scene, const BenchMeshesArgs& args, const std::vector<glm::vec4>& vkHits,
               Row& row) {
  RTCDevice device = rtcNewDevice(nullptr);
  if (!device) throw Error("embree: rtcNewDevice failed");
  rtcSetDeviceMemoryMonitorFunction(device, embreeMemoryMonitor, nullptr);
  const std::size_t n = g.triangles.size();
  // Embree reads vertices with 16-byte loads: one float of padding after the last.
  std::vector<float> vertices(9 * n + 1, 0.0f);
  std::vector<std::uint32_t> indices(3 * n);
  for (std::size_t i = 0; i < n; ++i) {
    const glm::vec4* v[3] = {&g.triangles[i].v0, &g.triangles[i].v1, &g.triangles[i].v2};
    for (int k = 0; k < 3; ++k) {
      vertices[9 * i + 3 * k + 0] = v[k]->x;
      vertices[9 * i + 3 * k + 1] = v[k]->y;
      vertices[9 * i + 3 * k + 2] = v[k]->z;
      indices[3 * i + k] = static_cast<std::uint32_t>(3 * i + k);
    }
  }
  RTCScene rtcScene = nullptr;
  double best = 1e30;
  for (int attempt = 0; attempt < 2; ++attempt) {
    if (rtcScene) rtcReleaseScene(rtcScene);
    gEmbreeBytes = 0;
    auto t0 = Clock::now();
    rtcScene = rtcNewScene(device);
    RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, vertices.data(), 0,
                               3 * sizeof(float), 3 * n);
    rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, indices.data(), 0,
                               3 * sizeof(std::uint32_t), n);
    rtcCommitGeometry(geom);
    rtcAttachGeometry(rtcScene, geom);
    rtcReleaseGeometry(geom);
    rtcCommitScene(rtcScene);
    best = std::min(best, msSince(t0));
  }
  row.embreeBuildMs = best;
  row.embreeBytesPerTriangle = static_cast<double>(gEmbreeBytes.load()) / static_cast<double>(n);

  const std::uint32_t w = args.width;
  const std::uint32_t h = args.height;
  CameraFrame cam = makeCameraFrame(scene.camera, w, h);
  const glm::vec3 light = glm::vec3(scene.lights[0].position - g.origin);
  const unsigned threads = std::max(1u, std::thread::hardware_concurrency());
  std::vector<float> hitT(static_cast<std::size_t>(w) * h);
  std::vector<glm::vec3> hitN(hitT.size());
  std::vector<glm::vec3> dirs(hitT.size());
  for (std::uint32_t y = 0; y < h; ++y) {
    for (std::uint32_t x = 0; x < w; ++x) {
      dirs[static_cast<std::size_t>(y) * w + x] = glm::vec3(glm::normalize(cam.rayDirection(x + 0.5, y + 0.5, w, h)));
    }
  }
  auto parallelRows = [&](auto&& body) {
    std::atomic<std::uint32_t> nextRow{0};
    std::vector<std::thread> pool;
    for (unsigned t = 0; t < threads; ++t) {
      pool.emplace_back([&] {
        RTCIntersectContext context;
        rtcInitIntersectContext(&context);
        for (std::uint32_t y0 = nextRow.fetch_add(8); y0 < h; y0 = nextRow.fetch_add(8)) {
          for (std::uint32_t y = y0; y < std::min(h, y0 + 8); ++y) body(context, y);
        }
      });
    }
    for (auto& t : pool) t.join();
  };
  std::vector<double> primaryTimes;
  std::vector<double> shadowTimes;
  std::atomic<std::uint64_t> shadowRays{0};
  std::atomic<std::uint64_t> occluded{0};
  std::vector<signed char> shadowed(hitT.size(), -1); // -1 no shadow ray, 0 lit, 1 occluded
  for (int run = 0; run < std::max(1, args.runs); ++run) {
    auto t0 = Clock::now();
    parallelRows([&](RTCIntersectContext& context, std::uint32_t y) {
      for (std::uint32_t x = 0; x < w; ++x) {
        std::size_t i = static_cast<std::size_t>(y) * w + x;
        RTCRayHit rh{};
        rh.ray.org_x = rh.ray.org_y = rh.ray.org_z = 0.0f;
        rh.ray.dir_x = dirs[i].x;
        rh.ray.dir_y = dirs[i].y;
        rh.ray.dir_z = dirs[i].z;
        rh.ray.tnear = 0.0f;
        rh.ray.tfar = INFINITY;
        rh.ray.mask = 0xFFFFFFFFu;
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(rtcScene, &context, &rh);
        bool hit = rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
        hitT[i] = hit ? rh.ray.tfar : -1.0f;
        hitN[i] = glm::vec3(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z);
      }
    });
    primaryTimes.push_back(msSince(t0));
    shadowRays = 0;
    occluded = 0;
    t0 = Clock::now();
    parallelRows([&](RTCIntersectContext& context, std::uint32_t y) {
      std::uint64_t localRays = 0;
      std::uint64_t localOccluded = 0;
      for (std::uint32_t x = 0; x < w; ++x) {
        std::size_t i = static_cast<std::size_t>(y) * w + x;
        if (hitT[i] < 0.0f) continue;
        glm::vec3 p = hitT[i] * dirs[i];
        glm::vec3 n = glm::normalize(hitN[i]);
        if (glm::dot(n, dirs[i]) > 0.0f) n = -n;
        glm::vec3 l = light - p;
        if (glm::dot(n, l) <= 0.0f) continue; // light behind the surface: no ray (as the kernel)
        ++localRays;
        glm::vec3 o = p + n * (1e-4f * (1.0f + glm::length(p)));
        RTCRay ray{};
        ray.org_x = o.x;
        ray.org_y = o.y;
        ray.org_z = o.z;
        ray.dir_x = l.x;
        ray.dir_y = l.y;
        ray.dir_z = l.z;
        ray.tnear = 0.0f;
        ray.tfar = 1.0f;
        ray.mask = 0xFFFFFFFFu;
        rtcOccluded1(rtcScene, &context, &ray);
        shadowed[i] = ray.tfar < 0.0f ? 1 : 0; // Embree sets tfar to -inf on a hit
        localOccluded += shadowed[i];
      }
      shadowRays += localRays;
      occluded += localOccluded;
    });
    shadowTimes.push_back(msSince(t0));
  }
  row.embreePrimaryMs = median(primaryTimes);
  row.embreeShadowMs = median(shadowTimes);
  row.embreeShadowRays = shadowRays.load();
  row.embreeOccluded = occluded.load();
  for (std::size_t i = 0; i < hitT.size() && i < vkHits.size(); ++i) {
    int vkShadow = vkHits[i].w < 0.0f ? -1 : vkHits[i].w > 0.0f ? 1 : 0;
    row.shadowsDiffer += vkShadow != shadowed[i];
    bool vkHit = vkHits[i].x > 0.0f;
    bool embreeHit = hitT[i] >= 0.0f;
    if (vkHit != embreeHit) {
      ++row.hitsDiffer;
    } else if (vkHit) {
      double rel = std::abs(static_cast<double>(vkHits[i].x) - hitT[i]) / static_cast<double>(hitT[i]);
      row.maxRelativeTDiff = std::max(row.maxRelativeTDiff, rel);
      row.farApart += rel > 1e-3;
    }
  }
  rtcReleaseScene(rtcScene);
  rtcReleaseDevice(device);
}

#endif

// One round of one mesh: the renderer's kernel and the ray queries on vkray's side, then (when
// `embree`) the same rays through Embree. `eye` holds the mesh under a light that casts no shadows,
// `shadow` the same mesh under one that does; the query kernel's runs alternate between the two,
// and the shadow rays' time is the median of each pair's difference, so that a slow spell of the
// machine falls on both sides of a difference instead of on one.
Row measureMesh(Renderer& eye, Renderer& shadow, const MeshData& mesh, const BenchMeshesArgs& args,
                const RenderOptions& options, bool embree) {
  (void)embree; // read only where Embree is built in
  Row row;
  Scene eyeScene = benchScene(mesh, args, false);
  Scene shadowScene = benchScene(mesh, args, true);
  row.triangles = eyeScene.triangles.size();
  eye.setScene(eyeScene);
  shadow.setScene(shadowScene);
  const GpuScene& g = shadow.gpuScene();
  row.buildMs = std::min(eye.gpuScene().bvh.stats.buildMs, g.bvh.stats.buildMs);
  row.nodes = g.bvh.stats.nodes;
  row.depth = g.bvh.stats.depth;
  row.bytesPerTriangle = static_cast<double>(g.meshBytes()) / static_cast<double>(row.triangles);

  // The renderer's own kernel on the eye rays: one counted render (builds the pipeline), one
  // warm-up, then the timed runs.
  TimedRender t = timeRender(eye, eyeScene, eyeScene.render, options, 1, 1);
  auto [renderMs, renderCpuMs] = timeRenders(eye, eyeScene, options, args.runs);
  row.renderMs = renderMs;
  row.renderCpuMs = renderCpuMs;
  row.eyeRays = t.stats.eye;

  // The ray queries alone: one render of each builds its pipeline (and the shadow entry points'
  // table) and gives the hits, then the timed runs in pairs.
  RenderOptions query = options;
  query.kernel = Kernel::Hits;
  eye.render(eyeScene.camera, eyeScene.render, query);
  RenderResult hits = shadow.render(shadowScene.camera, shadowScene.render, query);
  row.shadowTableMs = g.shadowEntryMs;
  row.nothingPairs = g.shadowNothingPairs;
  std::vector<double> eyeMs, pairMs;
  double eyeCpu = 0.0, shadowCpu = 0.0;
  for (int i = 0; i < args.runs; ++i) {
    double cpu0 = processCpuMs();
    double a = eye.render(eyeScene.camera, eyeScene.render, query).timings.traceMs;
    double cpu1 = processCpuMs();
    double b = shadow.render(shadowScene.camera, shadowScene.render, query).timings.traceMs;
    double cpu2 = processCpuMs();
    eyeMs.push_back(a);
    pairMs.push_back(b - a);
    eyeCpu += cpu1 - cpu0;
    shadowCpu += (cpu2 - cpu1) - (cpu1 - cpu0);
  }
  row.primaryMs = median(eyeMs);
  row.primaryCpuMs = eyeCpu / args.runs;
  row.shadowMs = resolvedShadowMs(eyeMs, pairMs); // 0, and the line says so, where it is noise
  row.shadowCpuMs = std::max(1e-3, shadowCpu / args.runs);
  for (const glm::vec4& h : hits.hits) {
    row.shadowRays += h.w >= 0.0f;
    row.occluded += h.w > 0.0f;
  }
#ifdef VKRAY_HAVE_EMBREE
  if (embree) runEmbree(g, shadowScene, args, hits.hits, row);
#endif
  return row;
}

// Ratio of the round's primary-ray throughput: against Embree's where it ran, else vkray's own.
double primaryScore(const Row& r, bool embree) {
  return embree && r.embreePrimaryMrays() > 0 ? r.primaryMrays() / r.embreePrimaryMrays() : r.primaryMrays();
}

// The round whose primary score is the median (the lower middle one of an even count).
Row medianRound(std::vector<Row> rounds, bool embree) {
  std::sort(rounds.begin(), rounds.end(),
            [&](const Row& a, const Row& b) { return primaryScore(a, embree) < primaryScore(b, embree); });
  return rounds[(rounds.size() - 1) / 2];
}

// Median, least and largest of one figure over the rounds, as "median [min-max]".
std::string spread(const std::vector<Row>& rounds, const std::function<double(const Row&)>& figure) {
  std::vector<double> v;
  for (const Row& r : rounds) v.push_back(figure(r));
  auto [lo, hi] = std::minmax_element(v.begin(), v.end());
  char text[64];
  std::snprintf(text, sizeof text, "%.2f [%.2f-%.2f]", median(v), *lo, *hi);
  return text;
}

} // namespace

int runBenchMeshes(const BenchMeshesArgs& args) {
  vulkan::Context context(contextOptions(args.device));
  bool embree = false;
#ifdef VKRAY_HAVE_EMBREE
  embree = !args.noEmbree;
#endif
  std::printf("device: %s (%s), %ux%u, median of %d runs", context.info().name.c_str(), context.info().driver.c_str(),
              args.width, args.height, args.runs);
  if (args.rounds > 1) std::printf(", %d interleaved rounds", args.rounds);
  std::printf("; %u CPU threads\n", std::thread::hardware_concurrency());
#ifdef VKRAY_HAVE_EMBREE
  if (embree) std::printf("embree: %s, rtcIntersect1 / rtcOccluded1 on every CPU thread\n", RTC_VERSION_STRING);
#endif
  if (!embree) std::printf("embree: not measured (vkray built without Embree 3, or --no-embree)\n");
  std::fflush(stdout);
  // Two renderers on one device: the mesh without and with shadow rays (measureMesh).
  Renderer renderer(context, nullptr);
  Renderer shadowRenderer(context, nullptr);
  RenderOptions options;
  options.countStats = false;
  // Embree traces every eye ray, the background's too: so does the renderer's column here.
  options.cullRows = false;
  options.entryPoints = !args.noEntryPoints;
  // The table is built once per mesh, as the BVH is, and timed beside it.
  options.shadowEntryPoints = args.noShadowEntryPoints ? ShadowEntries::Off
                              : args.noNothingBetween  ? ShadowEntries::Entries
                                                       : ShadowEntries::On;
  // Rounds are interleaved: round r of every size before round r + 1 of any, so that a slow spell
  // of a shared machine spreads over the sizes instead of landing on one.
  std::vector<MeshData> meshes;
  for (std::size_t size : args.sizes) meshes.push_back(proceduralTorus(size));
  std::vector<std::vector<Row>> bySize(meshes.size());
  for (int round = 1; round <= args.rounds; ++round) {
    for (std::size_t i = 0; i < meshes.size(); ++i) {
      Row row = measureMesh(renderer, shadowRenderer, meshes[i], args, options, embree);
      bySize[i].push_back(row);
      if (args.rounds > 1) std::printf("round %d of %d, ", round, args.rounds);
      std::printf("%zu triangles: build %.1f ms, primary %.2f Mrays/s, ", row.triangles, row.buildMs,
                  row.primaryMrays());
      if (row.shadowMs > 0)
        std::printf("shadow %.2f Mrays/s", row.shadowMrays());
      else
        std::printf("shadow below the runs' noise (0 in the tables)");
      if (row.shadowTableMs > 0)
        std::printf(" (shadow entry table built in %.1f ms, nothing between in %zu pairs)", row.shadowTableMs,
                    row.nothingPairs);
      HostPageUse pages = shadowRenderer.sceneHostPages();
      if (pages.bytes > 0) std::printf(", huge pages %zu of %zu MiB", pages.hugeBytes >> 20, pages.bytes >> 20);
      if (embree) {
        std::printf(" | embree: build %.1f ms, primary %.2f Mrays/s, shadow %.2f Mrays/s", row.embreeBuildMs,
                    row.embreePrimaryMrays(), row.embreeShadowMrays());
      }
      std::printf("\n");
      std::fflush(stdout);
    }
  }
  // The table (and the CSV) shows, for each size, its median round: the one whose primary rays
  // came out in the middle, against Embree's where Embree ran.
  std::vector<Row> rows;
  for (const std::vector<Row>& rounds : bySize) rows.push_back(medianRound(rounds, embree));

  std::printf("\n%10s %9s %9s %6s %8s %9s %9s %9s %9s %9s %9s", "triangles", "build ms", "nodes", "depth", "B/tri",
              "eye ms", "eye cpu", "eye Mr/s", "shd Mr/s", "rays", "rend Mr/s");
  if (embree)
    std::printf(" | %9s %8s %9s %9s %8s %8s %8s", "emb build", "emb B/t", "emb eye", "emb shd", "eye x", "rend x",
                "build x");
  std::printf("\n");
  for (const Row& r : rows) {
    std::printf("%10zu %9.1f %9zu %6d %8.1f %9.2f %9.1f %9.2f %9.2f %9llu %9.2f", r.triangles, r.buildMs, r.nodes,
                r.depth, r.bytesPerTriangle, r.primaryMs, r.primaryCpuMs, r.primaryMrays(), r.shadowMrays(),
                static_cast<unsigned long long>(r.eyeRays + r.shadowRays), r.renderMrays());
    if (embree) {
      double e = r.embreePrimaryMrays();
      std::printf(" | %9.1f %8.1f %9.2f %9.2f %8.2f %8.2f %8.2f", r.embreeBuildMs, r.embreeBytesPerTriangle, e,
                  r.embreeShadowMrays(), e > 0 ? r.primaryMrays() / e : 0.0, e > 0 ? r.renderMrays() / e : 0.0,
                  r.embreeBuildMs > 0 ? r.buildMs / r.embreeBuildMs : 0.0);
    }
    std::printf("\n");
  }
  std::printf("eye/shd: the ray queries alone (shaders/hits.comp), as Embree is asked; rend: the renderer's kernel\n"
              "(closest hit + shading + image) on the same eye rays\n");
  if (rows.size() >= 2 && rows.front().primaryMs > 0) {
    const Row& a = rows.front();
    const Row& b = rows.back();
    std::printf("eye-ray time %zu -> %zu triangles: x%.2f (%.0fx the triangles)\n", a.triangles, b.triangles,
                b.primaryMs / a.primaryMs, static_cast<double>(b.triangles) / a.triangles);
  }
  if (embree) {
    std::printf("columns 'eye x', 'rend x' and 'build x': vkray eye-ray throughput / Embree's (queries alone, and\n"
                "the renderer's kernel), vkray build time / Embree's\n");
    for (const Row& r : rows) {
      auto u = [](std::uint64_t v) { return static_cast<unsigned long long>(v); };
      std::printf("  %zu triangles: of %llu eye rays, %llu hit where Embree's miss or the reverse, %llu hit another "
                  "surface (t > 1e-3 apart; largest relative difference %.1e); shadow rays vkray %llu, Embree %llu; "
                  "occluded vkray %llu, Embree %llu; %llu pixels shadowed differently\n",
                  r.triangles, u(r.eyeRays), u(r.hitsDiffer), u(r.farApart), r.maxRelativeTDiff, u(r.shadowRays),
                  u(r.embreeShadowRays), u(r.occluded), u(r.embreeOccluded), u(r.shadowsDiffer));
    }
  }

  if (args.rounds > 1) {
    std::printf("\nover %d rounds, median [least-largest]%s:\n", args.rounds,
                embree ? " of each round's ratio to Embree's" : ", Mrays/s");
    std::printf("%10s  %-20s  %-20s  %-20s", "triangles", "primary", "shadow", "renderer");
    if (embree) std::printf("  %-20s", "build");
    std::printf("\n");
    for (const std::vector<Row>& rounds : bySize) {
      auto ratio = [](double a, double b) { return b > 0 ? a / b : 0.0; };
      std::string primary, shadow, render, build;
      if (embree) {
        primary = spread(rounds, [&](const Row& r) { return ratio(r.primaryMrays(), r.embreePrimaryMrays()); });
        shadow = spread(rounds, [&](const Row& r) { return ratio(r.shadowMrays(), r.embreeShadowMrays()); });
        render = spread(rounds, [&](const Row& r) { return ratio(r.renderMrays(), r.embreePrimaryMrays()); });
        build = spread(rounds, [&](const Row& r) { return ratio(r.buildMs, r.embreeBuildMs); });
      } else {
        primary = spread(rounds, [](const Row& r) { return r.primaryMrays(); });
        shadow = spread(rounds, [](const Row& r) { return r.shadowMrays(); });
        render = spread(rounds, [](const Row& r) { return r.renderMrays(); });
      }
      std::printf("%10zu  %-20s  %-20s  %-20s", rounds.front().triangles, primary.c_str(), shadow.c_str(),
                  render.c_str());
      if (embree) std::printf("  %-20s", build.c_str());
      std::printf("\n");
    }
    std::printf("the table above and the CSV show each size's median round (by primary rays%s)\n",
                embree ? " against Embree" : "");
  }

  if (!args.csv.empty()) {
    std::ofstream out(args.csv);
    if (!out) throw InputError(args.csv.string(), "cannot open for writing");
    out << "triangles,build_ms,nodes,depth,bytes_per_triangle,eye_ms,eye_cpu_ms,shadow_cpu_ms,eye_mrays,shadow_mrays,"
           "embree_build_ms,"
           "embree_bytes_per_triangle,embree_eye_mrays,embree_shadow_mrays,render_eye_ms,render_eye_mrays,"
           "shadow_table_ms\n";
    for (const Row& r : rows) {
      out << r.triangles << ',' << r.buildMs << ',' << r.nodes << ',' << r.depth << ',' << r.bytesPerTriangle << ','
          << r.primaryMs << ',' << r.primaryCpuMs << ',' << r.shadowCpuMs << ',' << r.primaryMrays() << ','
          << r.shadowMrays() << ',' << r.embreeBuildMs << ',' << r.embreeBytesPerTriangle << ','
          << r.embreePrimaryMrays() << ',' << r.embreeShadowMrays() << ',' << r.renderMs << ',' << r.renderMrays()
          << ',' << r.shadowTableMs << '\n';
    }
    std::printf("wrote %s\n", args.csv.string().c_str());
  }
  return 0;
}

} // namespace vkray
