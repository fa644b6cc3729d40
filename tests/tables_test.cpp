// The house's single tables: every enum's names, the ray-counter list, and the places that read
// them (the scene loader, the CLI, the --stats lines).
#include <set>
#include <string>

#include <gtest/gtest.h>

#include "render/ray_stats.h"
#include "render/render_options.h"
#include "scene/scene.h"
#include "scene/scene_loader.h"
#include "util/error.h"

namespace vkray {
namespace {

template <typename E> void expectTableRoundTrips() {
  std::set<std::string> seen;
  for (const auto& entry : EnumNames<E>::values) {
    EXPECT_TRUE(seen.insert(std::string(entry.name)).second) << "duplicate name " << entry.name;
    EXPECT_EQ(enumName(entry.value), entry.name);
    ASSERT_TRUE(parseEnum<E>(entry.name).has_value()) << entry.name;
    EXPECT_EQ(*parseEnum<E>(entry.name), entry.value);
  }
  EXPECT_FALSE(parseEnum<E>("no-such-value").has_value());
  EXPECT_EQ(enumNameList<E>().size(), EnumNames<E>::values.size());
}

TEST(EnumTables, EveryTableRoundTrips) {
  expectTableRoundTrips<Numerics>();
  expectTableRoundTrips<FresnelMode>();
  expectTableRoundTrips<TransmissiveShadows>();
  expectTableRoundTrips<Antialiasing>();
  expectTableRoundTrips<BvhMode>();
  expectTableRoundTrips<Precision>();
  expectTableRoundTrips<SceneMemory>();
}

TEST(EnumTables, ChoicesReadAsAList) {
  EXPECT_EQ(enumChoices<BvhMode>(), "'auto', 'on' or 'off'");
  EXPECT_EQ(enumChoices<Numerics>(), "'robust' or 'naive'");
}

constexpr const char* kCamera = R"("camera": { "position": [0, 0, 5], "look_at": [0, 0, 0] })";

Scene withRender(const std::string& render) {
  std::string text = "{ "; // appended: GCC 12 -Warray-bounds misfires on a + chain here
  text += kCamera;
  text += R"(, "render": )";
  text += render;
  text += " }";
  return loadSceneFromString(text, "t.json");
}

// Every enum-valued key of "render" reads every name of its table.
TEST(EnumTables, TheLoaderReadsEveryName) {
  for (const auto& e : EnumNames<Numerics>::values) {
    EXPECT_EQ(withRender(R"({ "numerics": ")" + std::string(e.name) + "\" }").render.numerics, e.value);
  }
  for (const auto& e : EnumNames<FresnelMode>::values) {
    EXPECT_EQ(withRender(R"({ "fresnel": ")" + std::string(e.name) + "\" }").render.fresnel, e.value);
  }
  for (const auto& e : EnumNames<TransmissiveShadows>::values) {
    EXPECT_EQ(withRender(R"({ "transmissive_shadows": ")" + std::string(e.name) + "\" }").render.transmissiveShadows,
              e.value);
  }
  for (const auto& e : EnumNames<Antialiasing>::values) {
    EXPECT_EQ(withRender(R"({ "antialiasing": ")" + std::string(e.name) + "\" }").render.antialiasing, e.value);
  }
  for (const auto& e : EnumNames<BvhMode>::values) {
    EXPECT_EQ(withRender(R"({ "bvh": ")" + std::string(e.name) + "\" }").render.bvh, e.value);
  }
  // render.precision is public, as --precision is (it was parsed but refused as an unknown key).
  for (const auto& e : EnumNames<Precision>::values) {
    EXPECT_EQ(withRender(R"({ "precision": ")" + std::string(e.name) + "\" }").render.precision, e.value);
  }
}

TEST(EnumTables, AnUnknownNameListsTheTable) {
  try {
    withRender(R"({ "precision": "float16" })");
    FAIL() << "float16 accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("render.precision: must be one of 'float32', 'float64', got 'float16'"),
              std::string::npos)
        << e.what();
  }
}

// The host's counters follow the one list: each GPU field lands in its host field, sums add, the
// deepest bounce takes the maximum, and every counter has its --stats name, in the list's order.
TEST(RayCounters, HostStatisticsFollowTheList) {
  gpu::RayStats raw{};
  raw.eyeRays = 1;
  raw.shadowRays = 2;
  raw.reflectionRays = 3;
  raw.refractionRays = 4;
  raw.bailoutSaved = 5;
  raw.stackOverflow = 6;
  raw.truncated = 7;
  raw.refinedPixels = 8;
  raw.nonFinite = 9;
  raw.maxDepth = 10;
  raw.faintHighlights = 11;
  RayStats s = RayStats::fromGpu(raw);
  EXPECT_EQ(s.eye, 1u);
  EXPECT_EQ(s.shadow, 2u);
  EXPECT_EQ(s.reflection, 3u);
  EXPECT_EQ(s.refraction, 4u);
  EXPECT_EQ(s.bailoutSaved, 5u);
  EXPECT_EQ(s.stackOverflow, 6u);
  EXPECT_EQ(s.truncated, 7u);
  EXPECT_EQ(s.refinedPixels, 8u);
  EXPECT_EQ(s.nonFinite, 9u);
  EXPECT_EQ(s.maxDepth, 10u);
  EXPECT_EQ(s.faintHighlights, 11u);
  EXPECT_EQ(s.total(), 10u);

  RayStats t = s;
  t.maxDepth = 4;
  t += s;
  EXPECT_EQ(t.eye, 2u);
  EXPECT_EQ(t.nonFinite, 18u);
  EXPECT_EQ(t.maxDepth, 10u); // a maximum, not a sum

  RayStats avg = t.perFrame(2);
  EXPECT_EQ(avg.eye, 1u);
  EXPECT_EQ(avg.refinedPixels, 8u);
  EXPECT_EQ(avg.maxDepth, 10u);

  auto named = s.named();
  ASSERT_EQ(named.size(), 11u);
  EXPECT_EQ(named.front().first, "eye rays");
  EXPECT_EQ(named.front().second, 1u);
  EXPECT_EQ(named.back().first, "deepest bounce");
  EXPECT_EQ(named.back().second, 10u);
  std::set<std::string> names;
  for (const auto& [name, value] : named) EXPECT_TRUE(names.insert(std::string(name)).second) << name;
}

} // namespace
} // namespace vkray
