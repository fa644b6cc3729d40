// The command line as users script it: exit codes, one-line errors, `name: value` statistics, and no
// output file (or an untouched old one) whenever a render fails.
#include <sys/wait.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <Imath/half.h>
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>

#include "image/exr_io.h"
#include "image/image_io.h"

#include "test_support.h"

namespace vkray::test {
namespace {

namespace fs = std::filesystem;

using RunResult = CliRun;

// Runs build/vkray with args (a shell-quoted string) on lavapipe.
RunResult vkray(const std::string& args) {
  return runVkray(args, test::scratchDir("cli"));
}

class Cli : public ::testing::Test {
protected:
  void SetUp() override { dir_ = test::freshScratchDir("cli-test"); }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path write(const std::string& name, const std::string& text) {
    fs::path p = dir_ / name;
    std::ofstream(p) << text;
    return p;
  }
  std::string scene(const std::string& name) const { return std::string(VKRAY_SOURCE_DIR "/scenes/") + name; }
  fs::path dir_;
};

TEST_F(Cli, RendersAPngWithStatistics) {
  fs::path out = dir_ / "a.png";
  RunResult r = vkray("render '" + scene("showcase.json") + "' -o '" + out.string() +
                      "' --width 64 --height 48 --stats --validate --no-pipeline-cache");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_TRUE(fs::exists(out));
  EXPECT_EQ(r.err, "");
  // Every statistic is one "name: value" line.
  std::map<std::string, std::string> stats;
  std::istringstream lines(r.out);
  for (std::string line; std::getline(lines, line);) {
    auto colon = line.find(": ");
    ASSERT_NE(colon, std::string::npos) << "not a name: value line: " << line;
    stats[line.substr(0, colon)] = line.substr(colon + 2);
  }
  for (const char* key : {"load", "upload", "pipeline", "trace", "readback", "write", "rays per second", "eye rays",
                          "shadow rays", "reflection rays"}) {
    EXPECT_TRUE(stats.count(key)) << "missing statistic " << key;
  }
  EXPECT_EQ(stats["eye rays"], "3072");
  EXPECT_FALSE(stats.count("decisions")) << "a uniform render has no progressive passes";
  // The sky above the showcase is filled, not traced (row culling): whole workgroup rows of it.
  int culled = std::stoi(stats["culled rows"]);
  EXPECT_GT(culled, 0);
  EXPECT_LT(culled, 48);
  EXPECT_EQ(culled % 8, 0);
  EXPECT_NE(stats["culled rows"].find(" of 48"), std::string::npos);
  EXPECT_NE(stats["trace"].find(" ms"), std::string::npos);
  // Each pipeline built says what its creation and its first (empty) dispatch took.
  EXPECT_NE(stats["pipeline trace"].find(", first dispatch "), std::string::npos) << r.out;
  EXPECT_GT(std::stod(stats["rays per second"]), 0.0);
}

// Progressive rendering through the command line: --stats says what the noise threshold reached,
// and the same command writes the same bytes again (the passes are deterministic).
TEST_F(Cli, NoiseThresholdPrintsWhatItReachedAndIsDeterministic) {
  fs::path a = dir_ / "a.pfm", b = dir_ / "b.pfm";
  const std::string flags = "' --width 48 --height 36 --noise-threshold 0.01 --min-spp 8 --max-spp 64 --stats";
  RunResult r = vkray("render '" + scene("showcase.json") + "' -o '" + a.string() + flags + " --validate");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_EQ(r.err, "");
  std::map<std::string, std::string> stats;
  std::istringstream lines(r.out);
  for (std::string line; std::getline(lines, line);) {
    auto colon = line.find(": ");
    if (colon != std::string::npos) stats[line.substr(0, colon)] = line.substr(colon + 2);
  }
  EXPECT_EQ(stats["noise threshold"], "0.01");
  EXPECT_EQ(stats["spp"].rfind("mean ", 0), 0u) << stats["spp"];
  EXPECT_NE(stats["spp"].find("(min 8, cap 64)"), std::string::npos) << stats["spp"];
  EXPECT_GE(std::stoi(stats["passes"]), 2);
  EXPECT_EQ(stats["error estimate"].rfind("mean ", 0), 0u);
  EXPECT_NE(stats["converged pixels"].find(" %"), std::string::npos);
  EXPECT_NE(stats["trace"].find(" ms"), std::string::npos);
  // The host's time between passes (deciding who stays open) has a line of its own.
  EXPECT_NE(stats["decisions"].find(" ms"), std::string::npos) << r.out;
  ASSERT_EQ(vkray("render '" + scene("showcase.json") + "' -o '" + b.string() + flags).exitCode, 0);
  EXPECT_EQ(slurp(a), slurp(b));
}

TEST_F(Cli, TimeLimitPrintsItsBudget) {
  fs::path out = dir_ / "t.png";
  RunResult r = vkray("render '" + scene("showcase.json") + "' -o '" + out.string() +
                      "' --width 48 --height 36 --time-limit 0.2 --stats");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_NE(r.out.find("time limit: 0.2 s\n"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("passes: "), std::string::npos);
  EXPECT_TRUE(fs::exists(out));
}

// --shadow-entry-points: auto builds the table only when the render's samples pay for it, and
// looks for the pairs with nothing between only when more samples pay for that; on builds both
// always, entries the entry points alone, off nothing; --stats says which, and the picture is the
// same bytes every way.
TEST_F(Cli, ShadowEntryPointsSayWhetherTheyWereBuiltAndChangeNothing) {
  auto run = [&](const std::string& mode, const std::string& extra = "") {
    fs::path out = dir_ / ("s-" + mode + ".pfm");
    RunResult r = vkray("render '" + scene("meshes.json") + "' -o '" + out.string() +
                        "' --width 64 --height 48 --stats --shadow-entry-points " + mode + extra);
    EXPECT_EQ(r.exitCode, 0) << r.err;
    auto at = r.out.find("shadow entry points: ");
    EXPECT_NE(at, std::string::npos) << r.out;
    std::string line = at == std::string::npos ? "" : r.out.substr(at, r.out.find('\n', at) - at);
    return std::make_pair(line, slurp(out));
  };
  auto [onLine, on] = run("on");
  auto [offLine, off] = run("off");
  auto [autoLine, automatic] = run("auto");
  auto [manyLine, many] = run("auto", " --spp 16");
  auto [mostLine, most] = run("auto", " --spp 64");
  auto [entriesLine, entries] = run("entries");
  EXPECT_EQ(onLine.rfind("shadow entry points: built in ", 0), 0u) << onLine;
  EXPECT_NE(onLine.find("(5392 triangles x 2 lights), nothing between in "), std::string::npos) << onLine;
  EXPECT_NE(entriesLine.find("(5392 triangles x 2 lights), nothing between: not looked for (--shadow-entry-points "
                             "entries)"),
            std::string::npos)
      << entriesLine;
  EXPECT_EQ(offLine, "shadow entry points: off (--shadow-entry-points off)");
  // 64 x 48 pixels, one sample each, for 5392 triangles: under 4 pixel samples per triangle.
  EXPECT_NE(autoLine.find("not built (too few pixel samples per triangle"), std::string::npos) << autoLine;
  // 16 samples: 49152 pixel samples, over 4 per triangle but under 32.
  EXPECT_EQ(manyLine.rfind("shadow entry points: built in ", 0), 0u) << manyLine;
  EXPECT_NE(manyLine.find("nothing between: not looked for (too few pixel samples per triangle"), std::string::npos)
      << manyLine;
  // 64 samples: 196608, over 32 per triangle.
  EXPECT_NE(mostLine.find(", nothing between in "), std::string::npos) << mostLine;
  EXPECT_FALSE(on.empty());
  EXPECT_EQ(on, off);
  EXPECT_EQ(on, automatic);
  EXPECT_EQ(on, entries);
  auto [mostEntriesLine, mostEntries] = run("entries", " --spp 64");
  EXPECT_EQ(most, mostEntries) << "64 samples, with and without the pairs marked nothing-between";

  RunResult bad = vkray("render '" + scene("meshes.json") + "' -o '" + (dir_ / "bad.png").string() +
                        "' --shadow-entry-points sometimes");
  EXPECT_NE(bad.exitCode, 0);
  EXPECT_NE(bad.err.find("--shadow-entry-points"), std::string::npos) << bad.err;
  EXPECT_EQ(std::count(bad.err.begin(), bad.err.end(), '\n'), 1) << bad.err;
  EXPECT_FALSE(fs::exists(dir_ / "bad.png"));
}

TEST_F(Cli, WritesLinearPfm) {
  fs::path out = dir_ / "a.pfm";
  RunResult r = vkray("render '" + scene("showcase.json") + "' -o '" + out.string() + "' --width 16 --height 8 -q");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  std::string data = slurp(out);
  EXPECT_EQ(data.rfind("PF\n16 8\n-1.0\n", 0), 0u);
  EXPECT_EQ(data.size(), std::string("PF\n16 8\n-1.0\n").size() + 16 * 8 * 12);
}

// An EXR holds the render's linear values: read back with OpenEXR, its R, G and B channels (named
// so in the file) equal the PFM's bit for bit; with --exr-half each is the value rounded to half.
TEST_F(Cli, WritesExrWithTheSameValuesAsThePfm) {
  fs::path pfm = dir_ / "a.pfm", exr = dir_ / "a.exr", half = dir_ / "h.exr";
  const std::string common = " --width 40 --height 30 -q";
  ASSERT_EQ(vkray("render '" + scene("glass.json") + "' -o '" + pfm.string() + "'" + common).exitCode, 0);
  RunResult r = vkray("render '" + scene("glass.json") + "' -o '" + exr.string() + "'" + common);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  ASSERT_EQ(vkray("render '" + scene("glass.json") + "' -o '" + half.string() + "' --exr-half" + common).exitCode, 0);
  Imf::InputFile file(exr.c_str());
  std::vector<std::string> names;
  for (auto it = file.header().channels().begin(); it != file.header().channels().end(); ++it) {
    names.push_back(it.name());
    EXPECT_EQ(it.channel().type, Imf::FLOAT) << it.name();
  }
  EXPECT_EQ(names, (std::vector<std::string>{"B", "G", "R"})); // OpenEXR lists channels by name
  Image linear = readImage(pfm);
  Image fromExr = readExr(exr);
  EXPECT_EQ(fromExr.pixels, linear.pixels);
  Imf::InputFile halfFile(half.c_str());
  EXPECT_EQ(halfFile.header().channels().findChannel("R")->type, Imf::HALF);
  Image fromHalf = readExr(half);
  ASSERT_EQ(fromHalf.pixels.size(), linear.pixels.size());
  for (std::size_t i = 0; i < linear.pixels.size(); ++i) {
    for (int c = 0; c < 3; ++c) EXPECT_EQ(fromHalf.pixels[i][c], float(Imath::half(linear.pixels[i][c])));
  }
  // --exr-half with another format is refused before any work, and nothing is written.
  fs::path png = dir_ / "b.png";
  r = vkray("render '" + scene("glass.json") + "' -o '" + png.string() + "' --exr-half" + common);
  EXPECT_EQ(r.exitCode, 1);
  EXPECT_EQ(r.err, "vkray: error: --exr-half: the output '" + png.string() + "' is not an .exr file\n");
  EXPECT_FALSE(fs::exists(png));
}

TEST_F(Cli, BrokenSceneFailsWithOneLineAndWritesNothing) {
  fs::path bad = write("bad.json", R"({ "camera": { "position": [0,0,5], "look_at": [0,0,0] },
      "objects": [ { "type": "sphere", "center": [0,0,0], "radius": -1 } ] })");
  fs::path out = dir_ / "out.png";
  RunResult r = vkray("render '" + bad.string() + "' -o '" + out.string() + "'");
  EXPECT_EQ(r.exitCode, 1);
  EXPECT_EQ(r.err, "vkray: error: " + bad.string() + ": objects[0].radius: must be > 0, got -1\n");
  EXPECT_FALSE(fs::exists(out));
  for (const auto& e : fs::directory_iterator(dir_)) EXPECT_NE(e.path().filename(), "out.png");
}

TEST_F(Cli, FailedRenderLeavesTheOldFileIntact) {
  fs::path out = write("keep.png", "previous contents");
  fs::path bad = write("bad.json", "{ not json");
  RunResult r = vkray("render '" + bad.string() + "' -o '" + out.string() + "'");
  EXPECT_EQ(r.exitCode, 1);
  EXPECT_EQ(slurp(out), "previous contents");
  std::size_t files = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir_)) ++files;
  EXPECT_EQ(files, 2u) << "a temporary file was left behind";
}

TEST_F(Cli, UnwritableOutputFailsBeforeRendering) {
  RunResult r = vkray("render '" + scene("showcase.json") + "' -o /nonexistent-dir/x.png");
  EXPECT_EQ(r.exitCode, 1);
  EXPECT_NE(r.err.find("directory '/nonexistent-dir' does not exist"), std::string::npos) << r.err;
  RunResult ext = vkray("render '" + scene("showcase.json") + "' -o '" + (dir_ / "x.jpg").string() + "'");
  EXPECT_EQ(ext.exitCode, 1);
  EXPECT_NE(ext.err.find("unknown image format '.jpg'"), std::string::npos) << ext.err;
}

TEST_F(Cli, MissingSceneFile) {
  RunResult r = vkray("render /nonexistent/scene.json -o '" + (dir_ / "x.png").string() + "'");
  EXPECT_EQ(r.exitCode, 1);
  EXPECT_EQ(r.err, "vkray: error: /nonexistent/scene.json: no such file\n");
}

// VKRAY_LOG_STEPS=1: each step says on standard error when it starts and how long it took
// (docs/reliability.md), so a run that hangs names the step it hangs in; tools/device-check reads
// it to tell a compiling driver from a running kernel.
TEST_F(Cli, StepLogNamesEveryStepAndHowLongItTook) {
  ::setenv("VKRAY_LOG_STEPS", "1", 1);
  RunResult r = vkray("render '" + scene("seed.json") + "' --width 16 --height 12 --inspect 8,6 --inspect-out '" +
                      (dir_ / "tree.json").string() + "' --no-pipeline-cache");
  ::unsetenv("VKRAY_LOG_STEPS");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const std::regex started(R"(vkray \[ *[0-9]+\.[0-9]{3} s\] (.+) \.\.\.)");
  const std::regex ended(R"(vkray \[ *[0-9]+\.[0-9]{3} s\] (.+) \.\.\. done in [0-9]+\.[0-9] ms)");
  // A wait of a second or more (a cold compile at a pipeline's first dispatch) says so each second.
  const std::regex waiting(R"(vkray \[ *[0-9]+\.[0-9]{3} s\] (.+): still waiting for the device after [0-9]+ s)");
  std::map<std::string, int> running; // step -> starts not yet ended
  int steps = 0;
  std::istringstream lines(r.err);
  for (std::string line; std::getline(lines, line);) {
    std::smatch m;
    if (std::regex_match(line, m, ended)) {
      EXPECT_GT(running[m[1]]--, 0) << "ended before it started: " << line;
    } else if (std::regex_match(line, m, started)) {
      ++running[m[1]];
      ++steps;
    } else if (std::regex_match(line, m, waiting)) {
      EXPECT_GT(running[m[1]], 0) << "waiting in a step not started: " << line;
    } else {
      ADD_FAILURE() << "not a step line: " << line;
    }
  }
  for (const auto& [step, n] : running) EXPECT_EQ(n, 0) << "never ended: " << step;
  EXPECT_TRUE(running.count("creating pipeline 'trace'")) << r.err;
  EXPECT_TRUE(running.count("inspecting rows 6..6")) << r.err;
  // A new pipeline is dispatched once, empty, before any work (lavapipe generates its code then).
  const auto created = r.err.find("creating pipeline 'trace' ... done");
  const auto first = r.err.find("first dispatch of pipeline 'trace' ... done");
  const auto traced = r.err.find("inspecting rows 6..6 ...");
  ASSERT_NE(first, std::string::npos) << r.err;
  EXPECT_LT(created, first);
  EXPECT_LT(first, traced);
  EXPECT_GT(steps, 10);
  // Off (the default), a run prints nothing on standard error (Cli.RendersAPngWithStatistics).
}

TEST_F(Cli, SeedFlagPicksAnotherNoisePatternAndSaysSo) {
  auto renderWith = [&](const std::string& flags, const fs::path& out) {
    return vkray("render '" + scene("showcase.json") + "' -o '" + out.string() +
                 "' --width 32 --height 24 --spp 4 --stats " + flags);
  };
  RunResult a = renderWith("", dir_ / "a.pfm");
  RunResult b = renderWith("--seed 7", dir_ / "b.pfm");
  ASSERT_EQ(a.exitCode, 0) << a.err;
  ASSERT_EQ(b.exitCode, 0) << b.err;
  EXPECT_EQ(a.out.find("seed: "), std::string::npos) << "seed 0 prints nothing";
  EXPECT_NE(b.out.find("\nseed: 7\n"), std::string::npos) << b.out;
  EXPECT_NE(readImage(dir_ / "a.pfm").pixels, readImage(dir_ / "b.pfm").pixels);
  RunResult bad = renderWith("--seed 4294967296", dir_ / "c.pfm");
  EXPECT_NE(bad.exitCode, 0);
  EXPECT_NE(bad.err.find("--seed"), std::string::npos) << bad.err;
  EXPECT_FALSE(fs::exists(dir_ / "c.pfm"));
}

TEST_F(Cli, ExplainSaysWhatTheSceneCallsFor) {
  RunResult r = vkray("render '" + scene("seed.json") + "' -o '" + (dir_ / "x.png").string() +
                      "' --width 8 --height 8 --explain -q");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_NE(r.out.find("shadows: on (1 light)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("reflection: on, up to depth 2"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("refraction: off — no transmissive material"), std::string::npos) << r.out;
}

TEST_F(Cli, FlagsOverrideTheScene) {
  fs::path out = dir_ / "x.pfm";
  RunResult r = vkray("render '" + scene("seed.json") + "' -o '" + out.string() +
                      "' --width 12 --height 10 --max-depth 0 --stats -q");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_NE(r.out.find("image: 12x10"), std::string::npos);
  EXPECT_NE(r.out.find("reflection rays: 0"), std::string::npos);
  RunResult bad = vkray("render '" + scene("seed.json") + "' -o '" + out.string() + "' --width 0");
  EXPECT_NE(bad.exitCode, 0);
  EXPECT_NE(bad.err.find("--width"), std::string::npos) << bad.err;
}

TEST_F(Cli, InfoListsLavapipe) {
  RunResult r = vkray("info");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_NE(r.out.find("llvmpipe"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("maxStorageBufferRange"), std::string::npos);
  EXPECT_NE(r.out.find("maxTexelBufferElements: 134217728"), std::string::npos) << r.out;
}

TEST_F(Cli, UnknownDeviceIsOneLine) {
  RunResult r = vkray("render '" + scene("seed.json") + "' -o '" + (dir_ / "x.png").string() + "' --device nosuchgpu");
  EXPECT_EQ(r.exitCode, 1);
  EXPECT_NE(r.err.find("--device 'nosuchgpu' matches no device"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
}

// Adaptive antialiasing refines from neighbour rows: a tile traces the row beyond each edge in its
// base pass, so its pixels are still the whole image's. Tiles and frame ranges combine.
TEST_F(Cli, AdaptiveTilesOfAFrameRangeMergeExactly) {
  std::string scene = this->scene("showcase-turntable.json");
  std::string flags = " --width 40 --height 30 --spp 4 --aa adaptive -q";
  auto r = vkray("render " + scene + " --frames 6-7" + flags + " -o '" + (dir_ / "w_%d.pfm").string() + "'");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  for (int i = 1; i <= 3; ++i) {
    r = vkray("render " + scene + " --frames 6-7 --tile " + std::to_string(i) + "/3" + flags + " -o '" +
              (dir_ / ("t_%d_" + std::to_string(i) + ".pfm")).string() + "'");
    ASSERT_EQ(r.exitCode, 0) << r.err;
  }
  for (int f : {6, 7}) {
    std::string tiles;
    for (int i = 3; i >= 1; --i)
      tiles += " " + (dir_ / ("t_" + std::to_string(f) + "_" + std::to_string(i) + ".pfm")).string();
    fs::path merged = dir_ / ("m_" + std::to_string(f) + ".pfm");
    r = vkray("merge -o " + merged.string() + tiles);
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_TRUE(slurp(merged) == slurp(dir_ / ("w_" + std::to_string(f) + ".pfm"))) << "frame " << f;
  }
}

TEST_F(Cli, TilesOfAnotherThresholdOrSeedDoNotMerge) {
  // Two bands of one scene, the second at another noise threshold (or seed): not one image.
  std::string scene = this->scene("showcase.json");
  std::string flags = " --width 40 --height 30 -q";
  auto tile = [&](int i, const std::string& extra, const std::string& name) {
    return vkray("render " + scene + " --tile " + std::to_string(i) + "/2" + flags + extra + " -o '" +
                 (dir_ / name).string() + "'");
  };
  ASSERT_EQ(tile(1, " --noise-threshold 0.02", "a1.pfm").exitCode, 0);
  ASSERT_EQ(tile(2, " --noise-threshold 0.02", "a2.pfm").exitCode, 0);
  ASSERT_EQ(tile(2, " --noise-threshold 0.01", "b2.pfm").exitCode, 0);
  ASSERT_EQ(tile(2, " --noise-threshold 0.02 --seed 3", "c2.pfm").exitCode, 0);
  auto merge = [&](const std::string& second, const std::string& out) {
    return vkray("merge -o '" + (dir_ / out).string() + "' '" + (dir_ / "a1.pfm").string() + "' '" +
                 (dir_ / second).string() + "'");
  };
  EXPECT_EQ(merge("a2.pfm", "ok.pfm").exitCode, 0);
  for (const char* second : {"b2.pfm", "c2.pfm"}) {
    RunResult r = merge(second, "bad.pfm");
    EXPECT_NE(r.exitCode, 0) << second;
    EXPECT_NE(r.err.find(second), std::string::npos) << r.err; // the line names the tile at fault
    EXPECT_FALSE(fs::exists(dir_ / "bad.pfm"));
  }
}

// Frames and tiles: a frame of the animated scene is the static scene with its values written in,
// a range writes one file per frame, tiles merge into the whole image byte for byte, and bad
// frame, tile and pattern flags fail with one line and write nothing.
TEST_F(Cli, FrameOfAnAnimationEqualsTheStaticSceneWithItsValues) {
  std::string animated = R"({ "camera": { "position": [0, 1.5, 5], "look_at": [0, 0.5, 0], "fov_y": 40 },
    "lights": [ { "name": "key", "position": [2, 5, 3] } ],
    "objects": [ { "type": "plane", "normal": [0, 1, 0], "offset": 0 },
                 { "type": "sphere", "name": "ball", "center": [0, 0.5, 0], "radius": 0.5 } ],
    "animation": { "frames": 5,
      "camera": [ { "frame": 0, "fov_y": 40 }, { "frame": 4, "fov_y": 30 } ],
      "objects": { "ball": [ { "frame": 0, "translate": [0, 0, 0] }, { "frame": 4, "translate": [1, 0, 0] } ] },
      "lights": { "key": [ { "frame": 0, "position": [2, 5, 3] }, { "frame": 4, "position": [-2, 5, 3] } ] } } })";
  std::string written = R"({ "camera": { "position": [0, 1.5, 5], "look_at": [0, 0.5, 0], "fov_y": 35 },
    "lights": [ { "position": [0, 5, 3] } ],
    "objects": [ { "type": "plane", "normal": [0, 1, 0], "offset": 0 },
                 { "type": "sphere", "center": [0.5, 0.5, 0], "radius": 0.5 } ] })";
  fs::path a = write("anim.json", animated);
  fs::path b = write("static.json", written);
  auto r = vkray("render " + a.string() + " --frame 2 --width 48 --height 32 -q -o " + (dir_ / "f2.png").string());
  ASSERT_EQ(r.exitCode, 0) << r.err;
  r = vkray("render " + b.string() + " --width 48 --height 32 -q -o " + (dir_ / "s.png").string());
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_TRUE(slurp(dir_ / "f2.png") == slurp(dir_ / "s.png"));
  r = vkray("render " + a.string() + " --frame 0 --width 48 --height 32 -q -o " + (dir_ / "f0.png").string());
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_TRUE(slurp(dir_ / "f0.png") != slurp(dir_ / "s.png"));
}

TEST_F(Cli, FrameRangeWritesOneFilePerFrameAndTilesMergeExactly) {
  std::string scene = this->scene("showcase-turntable.json");
  std::string size = " --width 40 --height 30 -q";
  auto r = vkray("render " + scene + " --frames 3-5" + size + " -o '" + (dir_ / "f_%04d.png").string() + "'");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  for (const char* f : {"f_0003.png", "f_0004.png", "f_0005.png"}) EXPECT_TRUE(fs::exists(dir_ / f)) << f;
  EXPECT_FALSE(fs::exists(dir_ / "f_0002.png"));
  EXPECT_TRUE(slurp(dir_ / "f_0003.png") != slurp(dir_ / "f_0005.png"));
  std::string tiles;
  for (int i = 1; i <= 4; ++i) {
    fs::path t = dir_ / ("t" + std::to_string(i) + ".pfm");
    r = vkray("render " + scene + " --frame 4 --tile " + std::to_string(i) + "/4" + size + " -o " + t.string());
    ASSERT_EQ(r.exitCode, 0) << r.err;
    tiles += " " + t.string();
  }
  r = vkray("merge -o " + (dir_ / "m.png").string() + tiles);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_TRUE(slurp(dir_ / "m.png") == slurp(dir_ / "f_0004.png"));
  // Tiles of another frame do not merge with these.
  r = vkray("render " + scene + " --frame 5 --tile 2/4" + size + " -o " + (dir_ / "other.pfm").string());
  ASSERT_EQ(r.exitCode, 0) << r.err;
  r = vkray("merge -o " + (dir_ / "bad.png").string() + " " + (dir_ / "t1.pfm").string() + " " +
            (dir_ / "other.pfm").string() + " " + (dir_ / "t3.pfm").string() + " " + (dir_ / "t4.pfm").string());
  EXPECT_EQ(r.exitCode, 1);
  EXPECT_NE(r.err.find("other.pfm: is of frame 5"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "bad.png"));
}

TEST_F(Cli, BadFramesAndTilesFailWithOneLineAndWriteNothing) {
  std::string scene = this->scene("showcase-turntable.json");
  struct Case {
    std::string args;
    std::string expect;
  };
  const std::vector<Case> cases = {
      {"--tile 0/3 -o x.pfm", "--tile 0/3: the band must be 1 to 3, got 0"},
      {"--tile 4/3 -o x.pfm", "--tile 4/3: the band must be 1 to 3, got 4"},
      {"--tile 1/3 -o x.png", "a tile is written as .pfm"},
      {"--frames 5-2 -o 'x_%d.png'", "--frames 5-2: the range runs backwards"},
      {"--frames 40-48 -o 'x_%d.png'", "--frames 40-48: the animation has frames 0-47"},
      {"--frame 48 -o x.png", "--frame 48: the animation has frames 0-47"},
      {"--frames 1-3 -o x.png", "name them with a frame number pattern such as out_%04d.png"},
  };
  for (const Case& c : cases) {
    auto r = vkray("render " + scene + " --width 16 --height 16 -q " + c.args.substr(0, c.args.find(" -o ")) + " -o " +
                   (dir_ / "").string() + c.args.substr(c.args.find(" -o ") + 4));
    EXPECT_EQ(r.exitCode, 1) << c.args;
    EXPECT_NE(r.err.find(c.expect), std::string::npos) << c.args << ": " << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
  EXPECT_TRUE(fs::is_empty(dir_)) << "a failed run wrote a file";
}

} // namespace
} // namespace vkray::test

namespace vkray::test {
namespace {

// The accuracy harness end to end in quick mode: a CSV row per point with no NaN, then the plots and
// the report from tools/plot_accuracy.py.
// Splits one CSV line into fields (quoted fields may hold commas).
std::vector<std::string> csvFields(const std::string& line) {
  std::vector<std::string> fields(1);
  bool quoted = false;
  for (char c : line) {
    if (c == '"')
      quoted = !quoted;
    else if (c == ',' && !quoted)
      fields.emplace_back();
    else
      fields.back() += c;
  }
  return fields;
}

TEST_F(Cli, AccuracyBenchQuickWritesACsvAndPlots) {
  fs::path out = dir_ / "acc";
  RunResult r = vkray("bench accuracy --quick --out '" + out.string() + "'");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  std::istringstream csv(slurp(out / "accuracy.csv"));
  std::string header;
  std::getline(csv, header);
  const std::vector<std::string> names = csvFields(header);
  std::map<std::string, std::size_t> column;
  for (std::size_t i = 0; i < names.size(); ++i) column[names[i]] = i;
  for (const char* c : {"trace_ms", "trace_ms_min", "trace_ms_max", "runs", "rmse", "rmse_min", "rmse_max", "spp_mean",
                        "noise_threshold", "time_limit"})
    ASSERT_TRUE(column.count(c)) << c << " missing from " << header;
  int rows = 0;
  std::map<std::string, int> knobs;
  for (std::string line; std::getline(csv, line);) {
    ++rows;
    const std::vector<std::string> f = csvFields(line);
    ASSERT_EQ(f.size(), names.size()) << line;
    EXPECT_EQ(line.find("nan"), std::string::npos) << line;
    const std::string knob = f[column["knob"]];
    knobs[knob]++;
    auto num = [&](const char* c) { return std::stod(f[column[c]]); };
    // The spread: min <= median <= max over the timed runs (quick mode times each point twice,
    // interleaved; the reference is not timed again).
    EXPECT_EQ(num("runs"), knob == "reference" ? 0 : 2) << line;
    EXPECT_LE(num("trace_ms_min"), num("trace_ms")) << line;
    EXPECT_LE(num("trace_ms"), num("trace_ms_max")) << line;
    EXPECT_GT(num("trace_ms_min"), 0.0) << line;
    EXPECT_LE(num("rmse_min"), num("rmse")) << line;
    EXPECT_LE(num("rmse"), num("rmse_max")) << line;
    if (knob == "noise_threshold") {
      EXPECT_EQ(num("noise_threshold"), 0.02) << line;
      EXPECT_GE(num("spp_mean"), 4.0) << line; // the points' min_spp and max_spp
      EXPECT_LE(num("spp_mean"), 64.0) << line;
    } else if (knob == "time_limit") {
      EXPECT_EQ(num("time_limit"), 0.05) << line;
      EXPECT_GE(num("spp_mean"), 1.0) << line;
    } else {
      EXPECT_EQ(num("noise_threshold"), 0.0) << line;
      EXPECT_EQ(num("time_limit"), 0.0) << line;
      EXPECT_EQ(num("spp_mean"), num("spp")) << line;
      if (knob != "reference") {
        EXPECT_EQ(num("rmse_min"), num("rmse_max")) << line; // deterministic images
      }
    }
  }
  EXPECT_EQ(rows, 8); // reference + baseline + depth, bailout, spp, numerics, noise_threshold, time_limit
  for (const char* k :
       {"reference", "baseline", "depth", "bailout", "spp", "numerics", "noise_threshold", "time_limit"})
    EXPECT_EQ(knobs[k], 1) << k;

  std::string cmd = std::string("/usr/bin/python3 '") + VKRAY_SOURCE_DIR + "/tools/plot_accuracy.py' '" + out.string() +
                    "' '" + (out / "report.md").string() + "' '" + (out / "img").string() + "' >/dev/null 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  EXPECT_TRUE(fs::exists(out / "img" / "accuracy.png"));
  EXPECT_TRUE(fs::exists(out / "img" / "accuracy-showcase.png"));
  std::string report = slurp(out / "report.md");
  EXPECT_NE(report.find("| numerics | naive |"), std::string::npos);
  EXPECT_NE(report.find("| noise_threshold | 0.02 |"), std::string::npos);
  EXPECT_NE(report.find("| time_limit | 0.05 |"), std::string::npos);
  EXPECT_NE(report.find("min–max ms"), std::string::npos); // the spread beside each time
  EXPECT_NE(report.find("Within noise"), std::string::npos);
  EXPECT_NE(report.find("Pareto front"), std::string::npos);
}

// bench adaptive prints, per threshold, the uniform spp and time at the same 95th-percentile error,
// the time ratio, and that ratio as the product of its three factors: samples, rays per sample and
// time per ray (each the threshold's over uniform sampling's).
TEST_F(Cli, AdaptiveBenchSplitsTheRatioIntoItsFactors) {
  RunResult r = vkray("bench adaptive '" + std::string(VKRAY_SOURCE_DIR) +
                      "/scenes/showcase.json' --height 48 --runs 1 --thresholds 0.016 --max-uniform-spp 64 "
                      "--reference-spp 256");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  std::istringstream lines(r.out);
  std::string line;
  bool header = false;
  int rows = 0;
  while (std::getline(lines, line)) {
    if (line.rfind("threshold ", 0) == 0) {
      header = true;
      EXPECT_NE(line.find("ratio  samples   rays/spp   ms/ray"), std::string::npos) << line;
      continue;
    }
    if (!header || line.rfind("E ", 0) != 0) continue;
    ++rows;
    // E 0.016  spp  p95  rays  ms [min, max]  uniform-spp  uniform-ms  ratio  samples  rays/spp  ms/ray
    std::istringstream f(line.substr(2));
    double e, spp, p95, rays, ms, uSpp, uMs, ratio, samples, perSample, perRay;
    std::string lo, hi;
    ASSERT_TRUE(f >> e >> spp >> p95 >> rays >> ms >> lo >> hi >> uSpp >> uMs >> ratio >> samples >> perSample >>
                perRay)
        << line;
    EXPECT_NEAR(samples, spp / uSpp, 0.006) << line;
    EXPECT_NEAR(ratio, samples * perSample * perRay, 0.02 + 0.01 * ratio) << line; // printed to 2 decimals
  }
  EXPECT_EQ(rows, 1) << r.out;
}

// bench adaptive --max-spp takes a list: each threshold is measured at each cap, and the last two
// columns say which cap and what share of the pixels met the threshold before it. A cap below what
// the threshold needs leaves pixels open (a mean at most the cap), a higher one fewer.
TEST_F(Cli, AdaptiveBenchMeasuresEachThresholdAtEachCap) {
  RunResult r = vkray("bench adaptive '" + std::string(VKRAY_SOURCE_DIR) +
                      "/scenes/showcase.json' --height 48 --runs 1 --thresholds 0.004 --max-spp 8,1024 "
                      "--max-uniform-spp 64 --reference-spp 256");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_NE(r.out.find("max_spp  converged"), std::string::npos) << r.out;
  std::istringstream lines(r.out);
  std::string line;
  std::vector<std::pair<double, double>> rows; // (spp mean, converged %) in the order printed
  std::vector<int> caps;
  while (std::getline(lines, line)) {
    if (line.rfind("E ", 0) != 0) continue;
    std::istringstream f(line.substr(2));
    double e, spp, p95, rays, ms, converged;
    std::string lo, hi, uSpp, uMs, ratio, samples, perSample, perRay; // "nan" outside the uniform points
    int cap = 0;
    ASSERT_TRUE(f >> e >> spp >> p95 >> rays >> ms >> lo >> hi >> uSpp >> uMs >> ratio >> samples >> perSample >>
                perRay >> cap >> converged)
        << line;
    rows.emplace_back(spp, converged);
    caps.push_back(cap);
  }
  ASSERT_EQ(caps, (std::vector<int>{8, 1024})) << r.out;
  EXPECT_LE(rows[0].first, 8.0) << r.out;
  EXPECT_LT(rows[0].second, 100.0) << r.out;
  EXPECT_GT(rows[1].first, rows[0].first) << r.out;
  EXPECT_GT(rows[1].second, rows[0].second) << r.out;
}

// bench adaptive --scene-size renders each scene at its own image size, not at --height rows; the
// two do not go together.
TEST_F(Cli, AdaptiveBenchAtTheScenesOwnSize) {
  const auto scene = std::filesystem::path(::testing::TempDir()) / "adaptive-size.json";
  {
    std::ofstream f(scene);
    f << R"({ "base": ")" << VKRAY_SOURCE_DIR << R"(/scenes/showcase.json", "image": { "width": 40, "height": 30 } })";
  }
  const std::string common = " --runs 1 --thresholds 0.016 --max-uniform-spp 8 --reference-spp 32";
  RunResult own = vkray("bench adaptive '" + scene.string() + "' --scene-size" + common);
  ASSERT_EQ(own.exitCode, 0) << own.err;
  EXPECT_NE(own.out.find("adaptive-size.json, 40x30,"), std::string::npos) << own.out;
  RunResult scaled = vkray("bench adaptive '" + scene.string() + "' --height 24" + common);
  ASSERT_EQ(scaled.exitCode, 0) << scaled.err;
  EXPECT_NE(scaled.out.find("adaptive-size.json, 32x24,"), std::string::npos) << scaled.out;
  RunResult both = vkray("bench adaptive '" + scene.string() + "' --scene-size --height 24" + common);
  EXPECT_NE(both.exitCode, 0);
  EXPECT_NE(both.err.find("--height excludes --scene-size"), std::string::npos) << both.err;
}
} // namespace
} // namespace vkray::test
