// Large scene buffers in vkray's own huge pages (host/vk/host_pages.h): the mapping itself, and
// that a device importing it (VK_EXT_external_memory_host) reads exactly what it would read from
// its own memory.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>
#include <vector>

#include <unistd.h>

#include <gtest/gtest.h>

#include "render/renderer.h"
#include "scene/mesh_import.h"
#include "test_support.h"
#include "vk/buffer.h"
#include "vk/host_pages.h"

namespace vkray {
namespace {

using vulkan::HostPages;
using vulkan::kHugePageBytes;

TEST(HostPages, WholeAlignedHugePagesThatCanBeWrittenAndMoved) {
  HostPages pages(5u << 20);
  ASSERT_NE(pages.data(), nullptr);
  EXPECT_EQ(pages.size(), 6u << 20) << "rounded up to whole 2 MiB pages";
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(pages.data()) % kHugePageBytes, 0u);
  auto* bytes = static_cast<unsigned char*>(pages.data());
  std::memset(bytes, 0xA5, pages.size());
  EXPECT_EQ(bytes[0], 0xA5);
  EXPECT_EQ(bytes[pages.size() - 1], 0xA5);
  // What the kernel backs with huge pages depends on the machine (its setting and free memory),
  // never more than the range.
  EXPECT_LE(pages.hugeBytes(), pages.size());

  void* where = pages.data();
  HostPages moved(std::move(pages));
  EXPECT_EQ(moved.data(), where);
  EXPECT_EQ(pages.data(), nullptr);
  EXPECT_EQ(pages.hugeBytes(), 0u);
  HostPages other(1);
  EXPECT_EQ(other.size(), kHugePageBytes);
  other = std::move(moved); // releases its own page
  EXPECT_EQ(other.data(), where);
  EXPECT_EQ(static_cast<unsigned char*>(other.data())[12345], 0xA5);
}

TEST(HostPages, ModeIsReadable) {
  std::string mode = vulkan::transparentHugePages();
  EXPECT_TRUE(mode == "always" || mode == "madvise" || mode == "never" || mode == "unknown") << mode;
}

// A bumpy torus of 2 u v triangles, big enough that its triangles pass the 4 MiB from which
// buffers import host pages.
Scene bigMeshScene() {
  const int u = 320, v = 200; // 128 000 triangles of 48 bytes: 5.9 MiB
  MeshData mesh;
  for (int i = 0; i < u; ++i) {
    double a = 2.0 * M_PI * i / u;
    for (int j = 0; j < v; ++j) {
      double b = 2.0 * M_PI * j / v;
      double r = 0.35 * (1.0 + 0.1 * std::sin(7.0 * a) * std::sin(5.0 * b));
      mesh.positions.emplace_back((1.0 + r * std::cos(b)) * std::cos(a), r * std::sin(b),
                                  (1.0 + r * std::cos(b)) * std::sin(a));
    }
  }
  auto id = [&](int i, int j) { return static_cast<std::uint32_t>((i % u) * v + (j % v)); };
  for (int i = 0; i < u; ++i) {
    for (int j = 0; j < v; ++j) {
      mesh.faces.push_back({id(i, j), id(i, j + 1), id(i + 1, j + 1)});
      mesh.faces.push_back({id(i, j), id(i + 1, j + 1), id(i + 1, j)});
    }
  }
  Scene scene;
  scene.camera.position = {0.0, 1.9, 2.6};
  scene.camera.lookAt = {0.0, -0.1, 0.0};
  scene.camera.fovY = 45.0;
  scene.render.width = 64;
  scene.render.height = 48;
  scene.render.maxDepth = 0;
  scene.render.bvh = BvhMode::On;
  scene.ambientLight = glm::dvec3(0.2);
  scene.lights.push_back(PointLight{glm::dvec3(2.0, 4.0, 1.0), glm::dvec3(1.0), true});
  MeshRequest request;
  request.shownAs = "test torus";
  request.normals = MeshNormals::Flat;
  appendMesh(mesh, request, scene);
  return scene;
}

// The same scene rendered from imported huge pages and from the driver's memory: the same image,
// bit for bit, and the same hits. Skipped on a device that cannot import host memory.
TEST(GpuHostPages, ImportedBuffersRenderWhatTheDriversMemoryRenders) {
  if (test::gpu().info().hostImportAlignment == 0) GTEST_SKIP() << "the device imports no host memory";
  Scene scene = bigMeshScene();
  RenderOptions query;
  query.kernel = Kernel::Hits;

  Renderer& imported = test::renderer();
  imported.setScene(scene);
  RenderResult a = imported.render(scene.camera, scene.render, {});
  RenderResult aHits = imported.render(scene.camera, scene.render, query);
  HostPageUse use = imported.sceneHostPages();
  EXPECT_GE(use.bytes, 6u << 20) << "the triangles, 4 MiB or more, live in imported host pages";
  EXPECT_LE(use.hugeBytes, use.bytes);
  test::expectNoValidationMessages();

  vulkan::ContextOptions options = test::testContextOptions(test::syncValidationRequested(), true);
  options.hostPages = false;
  vulkan::Context context(options);
  auto own = std::make_unique<Renderer>(context, nullptr);
  own->setScene(scene);
  RenderResult b = own->render(scene.camera, scene.render, {});
  RenderResult bHits = own->render(scene.camera, scene.render, query);
  EXPECT_EQ(own->sceneHostPages().bytes, 0u);
  own.reset();
  EXPECT_EQ(context.validationMessageCount(), 0u);

  ASSERT_EQ(a.image.pixels.size(), b.image.pixels.size());
  ASSERT_EQ(aHits.hits.size(), bHits.hits.size());
  std::size_t hits = 0;
  for (std::size_t i = 0; i < a.image.pixels.size(); ++i) {
    ASSERT_EQ(std::memcmp(&a.image.pixels[i], &b.image.pixels[i], sizeof(glm::vec3)), 0) << "pixel " << i;
    ASSERT_EQ(std::memcmp(&aHits.hits[i], &bHits.hits[i], sizeof(glm::vec4)), 0) << "pixel " << i;
    hits += aHits.hits[i].x > 0.0f;
  }
  EXPECT_GT(hits, a.image.pixels.size() / 4) << "the view must show the mesh";
}

// What the host writes into imported pages is what the device copies out of them, and what the
// device writes there the host reads.
TEST(GpuHostPages, DeviceAndHostSeeTheSameBytes) {
  if (test::gpu().info().hostImportAlignment == 0) GTEST_SKIP() << "the device imports no host memory";
  const vulkan::Context& context = test::gpu();
  const std::size_t count = (5u << 20) / sizeof(std::uint32_t);
  std::vector<std::uint32_t> pattern(count);
  for (std::size_t i = 0; i < count; ++i) pattern[i] = static_cast<std::uint32_t>(i * 2654435761u);
  const vk::DeviceSize bytes = count * sizeof(std::uint32_t);
  vulkan::Buffer source(context, bytes, vk::BufferUsageFlagBits::eStorageBuffer, vulkan::MemoryUse::DeviceLocal,
                        "imported source");
  vulkan::Buffer target(context, bytes, vk::BufferUsageFlagBits::eStorageBuffer, vulkan::MemoryUse::DeviceLocal,
                        "imported target");
  ASSERT_NE(source.hostPages(), nullptr);
  ASSERT_NE(target.hostPages(), nullptr);
  source.write(pattern.data(), bytes);
  context.submitAndWait("copying between imported buffers", [&](const vk::raii::CommandBuffer& cmd) {
    cmd.copyBuffer(source.handle(), target.handle(), vk::BufferCopy(0, 0, bytes));
  });
  std::vector<std::uint32_t> back(count);
  target.read(back.data(), bytes);
  EXPECT_EQ(back, pattern);
  // Small buffers stay in the driver's memory.
  vulkan::Buffer small(context, 4096, vk::BufferUsageFlagBits::eStorageBuffer, vulkan::MemoryUse::DeviceLocal, "small");
  EXPECT_EQ(small.hostPages(), nullptr);
  test::expectNoValidationMessages();
}

// The command line: `render --stats` says how much of the scene is in vkray's pages, and
// `--no-huge-pages` keeps it in the driver's memory with the same image, byte for byte.
TEST(CliHostPages, StatsReportThePagesAndTheFlagTurnsThemOff) {
  bool imports = false;
  for (const vulkan::DeviceInfo& d : vulkan::Context::listDevices()) {
    imports = imports || (d.name.find("llvmpipe") != std::string::npos && d.hostImportAlignment != 0);
  }
  if (!imports) GTEST_SKIP() << "lavapipe imports no host memory here";
  namespace fs = std::filesystem;
  fs::path dir = test::scratchDir("cli-pages");
  // A 320 x 200 grid of quads: 128 000 triangles, 5.9 MiB of them in the kernel's layout.
  {
    std::ofstream obj(dir / "grid.obj");
    const int nx = 320, ny = 200;
    for (int j = 0; j <= ny; ++j) {
      for (int i = 0; i <= nx; ++i)
        obj << "v " << i * 0.01 << ' ' << j * 0.01 << ' ' << 0.02 * std::sin(i * 0.3) << '\n';
    }
    for (int j = 0; j < ny; ++j) {
      for (int i = 0; i < nx; ++i) {
        int a = j * (nx + 1) + i + 1, b = a + 1, c = a + nx + 2, d = a + nx + 1;
        obj << "f " << a << ' ' << b << ' ' << c << "\nf " << a << ' ' << c << ' ' << d << '\n';
      }
    }
  }
  std::ofstream(dir / "grid.json") << R"({ "camera": { "position": [1.6, 1, 3], "look_at": [1.6, 1, 0] },
    "lights": [ { "type": "point", "position": [1, 2, 3], "color": [1, 1, 1] } ],
    "objects": [ { "type": "mesh", "file": "grid.obj" } ] })";
  auto run = [&](const std::string& flags, const std::string& out) {
    std::string cmd = std::string("VKRAY_DEVICE=llvmpipe '") + VKRAY_BINARY + "' render '" +
                      (dir / "grid.json").string() + "' -o '" + (dir / out).string() +
                      "' --width 32 --height 24 --stats -q " + flags + " >'" + (dir / "log.txt").string() + "' 2>&1";
    int status = std::system(cmd.c_str());
    std::ifstream in(dir / "log.txt");
    std::string log((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_EQ(status, 0) << log;
    return log;
  };
  std::string on = run("", "on.png");
  std::string off = run("--no-huge-pages", "off.png");
  EXPECT_NE(on.find("scene buffers in vkray's pages: 6.0 MiB"), std::string::npos) << on;
  EXPECT_EQ(off.find("scene buffers in vkray's pages"), std::string::npos) << off;
  auto bytes = [&](const char* name) {
    std::ifstream in(dir / name, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  };
  EXPECT_FALSE(bytes("on.png").empty());
  EXPECT_EQ(bytes("on.png"), bytes("off.png"));
  fs::remove_all(dir);
}

} // namespace
} // namespace vkray
