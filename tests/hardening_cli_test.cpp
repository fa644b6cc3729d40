// Hardening, through the command line as users run it: malformed input ends in one line and exit 1
// with no file written; Ctrl-C, SIGTERM and SIGKILL never leave a partial or corrupt output; the
// progress bar shows on a terminal only; no Vulkan driver is one line saying how to get lavapipe;
// the same scene and flags give the same bytes in every process; a validated render leaves no
// message and no Vulkan object behind; the widest image streams through the band window.
#include <fcntl.h>
#include <poll.h>
#include <pty.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "render/adaptive.h"
#include "test_support.h"
#include "util/host_memory.h"

extern char** environ;

namespace vkray::test {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

const fs::path kMalformedDir = VKRAY_SOURCE_DIR "/tests/data/malformed";

std::string scene(const std::string& name) {
  return std::string(VKRAY_SOURCE_DIR "/scenes/") + name;
}

std::size_t lineCount(const std::string& s) {
  return static_cast<std::size_t>(std::count(s.begin(), s.end(), '\n'));
}

// How a child ended.
struct Outcome {
  int exitCode = -1; // when it exited
  int signal = 0;    // when a signal ended it
  std::string out;   // stdout (with a terminal: everything it wrote there)
  std::string err;   // stderr (empty with a terminal)
  long maxRssKb = 0;
};

// build/vkray started with args: output to files, or to a pseudo-terminal (then stdout and stderr
// are that terminal, as in an interactive shell, and ^C can be typed into it). The environment is
// this process's plus `env` ("NAME=value"), with VKRAY_DEVICE=llvmpipe.
class Vkray {
public:
  // maxFileBytes > 0 limits the size of any file the child writes (RLIMIT_FSIZE, SIGXFSZ ignored):
  // a write past it fails with EFBIG, as a write to a full disk fails with ENOSPC.
  Vkray(const std::vector<std::string>& args, const fs::path& dir, bool terminal = false,
        const std::vector<std::string>& env = {}, rlim_t maxFileBytes = 0)
      : dir_(dir) {
    // Everything the child needs is prepared before fork: it only calls async-signal-safe functions.
    std::vector<std::string> argStrings{VKRAY_BINARY};
    argStrings.insert(argStrings.end(), args.begin(), args.end());
    std::vector<std::string> envStrings{"VKRAY_DEVICE=llvmpipe"};
    envStrings.insert(envStrings.end(), env.begin(), env.end());
    for (char** e = environ; *e; ++e) {
      std::string entry = *e;
      std::string name = entry.substr(0, entry.find('='));
      bool overridden = std::any_of(envStrings.begin(), envStrings.end(),
                                    [&](const std::string& s) { return s.rfind(name + "=", 0) == 0; });
      if (!overridden) envStrings.push_back(entry);
    }
    std::vector<char*> argv;
    for (auto& s : argStrings) argv.push_back(s.data());
    argv.push_back(nullptr);
    std::vector<char*> envp;
    for (auto& s : envStrings) envp.push_back(s.data());
    envp.push_back(nullptr);

    if (terminal) {
      winsize size{};
      size.ws_col = 160;
      size.ws_row = 40;
      pid_ = ::forkpty(&master_, nullptr, nullptr, &size);
      if (pid_ == 0) {
        ::execve(argv[0], argv.data(), envp.data());
        ::_exit(127);
      }
      if (master_ >= 0) ::fcntl(master_, F_SETFL, O_NONBLOCK);
    } else {
      int devNull = ::open("/dev/null", O_RDONLY);
      int out = ::open((dir_ / "stdout").c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      int err = ::open((dir_ / "stderr").c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      pid_ = ::fork();
      if (pid_ == 0) {
        if (maxFileBytes > 0) {
          rlimit limit{maxFileBytes, maxFileBytes};
          ::setrlimit(RLIMIT_FSIZE, &limit);
          ::signal(SIGXFSZ, SIG_IGN);
        }
        ::dup2(devNull, 0);
        ::dup2(out, 1);
        ::dup2(err, 2);
        ::execve(argv[0], argv.data(), envp.data());
        ::_exit(127);
      }
      ::close(devNull);
      ::close(out);
      ::close(err);
    }
    EXPECT_GT(pid_, 0) << "cannot start " << VKRAY_BINARY;
  }

  ~Vkray() {
    if (pid_ > 0 && !done_) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
    if (master_ >= 0) ::close(master_);
    std::error_code ec;
    fs::remove(dir_ / "stdout", ec);
    fs::remove(dir_ / "stderr", ec);
  }

  pid_t pid() const { return pid_; }

  // Terminal only: waits until the child has written `text` (true), or for at most `seconds`.
  bool waitForOutput(const std::string& text, double seconds) {
    auto until = Clock::now() + std::chrono::duration<double>(seconds);
    while (Clock::now() < until) {
      drain(50);
      if (terminal_.find(text) != std::string::npos) return true;
      if (exited()) return false;
    }
    return false;
  }

  // Types characters into the terminal, as a user at the keyboard would ("\x03" is Ctrl-C).
  void type(const std::string& keys) { ASSERT_EQ(::write(master_, keys.data(), keys.size()), (ssize_t)keys.size()); }

  void signal(int sig) { ::kill(pid_, sig); }

  // True once the child has ended (reaped here; its status in `status`), without waiting.
  bool ended(int& status) {
    bool e = exited();
    status = status_;
    return e;
  }

  // Waits for the child to end; kills it (and fails) after `seconds`.
  Outcome wait(double seconds = 300) {
    auto until = Clock::now() + std::chrono::duration<double>(seconds);
    while (!exited()) {
      drain(20);
      if (Clock::now() > until) {
        ADD_FAILURE() << "vkray did not finish in " << seconds << " s; killed";
        ::kill(pid_, SIGKILL);
        ::wait4(pid_, &status_, 0, &usage_);
        done_ = true;
      }
    }
    drain(0);
    const int status = status_;
    const rusage& usage = usage_;
    Outcome o;
    if (WIFEXITED(status)) o.exitCode = WEXITSTATUS(status);
    if (WIFSIGNALED(status)) o.signal = WTERMSIG(status);
    o.maxRssKb = usage.ru_maxrss;
    if (master_ >= 0) {
      o.out = terminal_;
    } else {
      o.out = slurp(dir_ / "stdout");
      o.err = slurp(dir_ / "stderr");
    }
    return o;
  }

private:
  // Reaps the child if it has ended, keeping its status and resource usage.
  bool exited() {
    if (!done_ && pid_ > 0 && ::wait4(pid_, &status_, WNOHANG, &usage_) == pid_) done_ = true;
    return done_;
  }
  void drain(int waitMs) {
    if (master_ < 0) {
      if (waitMs > 0) std::this_thread::sleep_for(std::chrono::milliseconds(waitMs));
      return;
    }
    pollfd p{master_, POLLIN, 0};
    if (::poll(&p, 1, waitMs) <= 0) return;
    char buf[4096];
    for (ssize_t n; (n = ::read(master_, buf, sizeof buf)) > 0;) terminal_.append(buf, static_cast<std::size_t>(n));
  }

  fs::path dir_;
  pid_t pid_ = -1;
  int master_ = -1;
  bool done_ = false;
  int status_ = 0;
  rusage usage_{};
  std::string terminal_;
};

// Runs vkray to completion with output to files.
Outcome run(const std::vector<std::string>& args, const fs::path& dir, const std::vector<std::string>& env = {}) {
  return Vkray(args, dir, false, env).wait();
}

class CliHardening : public ::testing::Test {
protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("vkray-hardening-cli-" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "out");
    // A pipeline cache of this test's own, so that "first run" really is one.
    cacheEnv_ = "VKRAY_CACHE_DIR=" + (dir_ / "cache").string();
  }
  void TearDown() override { fs::remove_all(dir_); }

  fs::path write(const std::string& name, const std::string& text) {
    fs::path p = dir_ / name;
    std::ofstream(p, std::ios::binary) << text;
    return p;
  }

  // Names in the output directory (hidden files included).
  std::vector<std::string> outputs() const {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir_ / "out")) names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
  }

  // A render that fails on bad input: exit 1, one line "vkray: error: ...", no output file.
  void expectRefused(const fs::path& sceneFile, const std::string& problem) {
    SCOPED_TRACE(sceneFile.string());
    fs::path out = dir_ / "out" / "image.png";
    Outcome r = run({"render", sceneFile.string(), "-o", out.string()}, dir_);
    EXPECT_EQ(r.exitCode, 1) << "signal " << r.signal << "\n" << r.err;
    EXPECT_EQ(lineCount(r.err), 1u) << r.err;
    EXPECT_EQ(r.err.rfind("vkray: error: ", 0), 0u) << r.err;
    EXPECT_NE(r.err.find(problem), std::string::npos) << r.err << "expected: " << problem;
    EXPECT_TRUE(outputs().empty()) << "wrote " << outputs().front();
  }

  fs::path dir_;
  std::string cacheEnv_;
};

// ---- Malformed input -----------------------------------------------------------------------------

struct MalformedScene {
  const char* file; // in tests/data/malformed
  const char* problem;
};

const MalformedScene kMalformedScenes[] = {
    {"truncated.json", "truncated.json:1:54: invalid JSON: syntax error while parsing"},
    {"wrong-type.json", "wrong-type.json: objects[0].radius: must be a number, got a boolean"},
    {"wrong-type-top.json", "wrong-type-top.json: objects: must be an array, got an object"},
    {"empty-center.json", "empty-center.json: objects[0].center: must be an array of 3 numbers, got 0 elements"},
    {"empty-vertices.json", "empty-vertices.json: objects[0].vertices: a polygon needs at least 3 vertices, got 0"},
    {"nan-literal.json", "nan-literal.json:2:50: invalid JSON: syntax error while parsing value - invalid literal"},
    {"nan-string.json", "nan-string.json: lights[0].position[2]: must be a finite number, got NaN"},
    {"inf-overflow.json", "inf-overflow.json:1:69: invalid JSON: number overflow parsing '1e999'"},
    {"inf-string.json", "inf-string.json: render.bailout: must be a finite number, got -Infinity"},
    {"huge-integer.json", "huge-integer.json: image.width: must be in [1, 16384], got 1e+20"},
    {"absurd-spp.json", "absurd-spp.json: render.spp: must be in [1, 4096], got 1000000"},
    {"absurd-depth.json", "absurd-depth.json: render.max_depth: must be in [0, 64], got 100000"},
    {"noise-threshold-zero.json", "noise-threshold-zero.json: render.noise_threshold: must be > 0 (a standard error in "
                                  "linear RGB), got 0"},
    {"time-limit-negative.json", "time-limit-negative.json: render.time_limit: must be in [0, 604800], got -1"},
    {"empty.json", "empty.json:1:1: invalid JSON: syntax error while parsing value - unexpected end of input"},
    {"null.json", "null.json: (top level): must be an object, got null"},
    // Not named .json and not opening an object: no JSON error at its first byte, but what it is not.
    {"garbage.bin", "garbage.bin: neither a JSON scene (it does not begin with '{') nor a model vkray reads"},
    {"invalid-utf8.json", "invalid-utf8.json:1:82: invalid JSON: syntax error while parsing value - invalid string: "
                          "ill-formed UTF-8 byte; last read: '\"caf\\xe9 '"},
    {"control-chars-key.json", "control-chars-key.json: (top level): unknown key 'objects\\n\\r\\x1b[31m'"},
};

TEST_F(CliHardening, MalformedScenesFailWithOneLineAndWriteNothing) {
  for (const auto& bad : kMalformedScenes) expectRefused(kMalformedDir / bad.file, bad.problem);
  // Every scene-like file in the corpus has a row above.
  for (const auto& e : fs::directory_iterator(kMalformedDir)) {
    std::string ext = e.path().extension().string();
    if (ext != ".json" && ext != ".bin") continue;
    std::string name = e.path().filename().string();
    EXPECT_TRUE(std::any_of(std::begin(kMalformedScenes), std::end(kMalformedScenes),
                            [&](const MalformedScene& m) { return name == m.file; }))
        << name << " has no row in kMalformedScenes";
  }
}

// Meshes with out-of-range indices and other damage (their exact messages: hardening_test.cpp).
TEST_F(CliHardening, MalformedMeshesFailWithOneLineAndWriteNothing) {
  int meshes = 0;
  for (const auto& e : fs::directory_iterator(kMalformedDir)) {
    std::string ext = e.path().extension().string();
    if (ext != ".obj" && ext != ".gltf" && ext != ".glb") continue;
    fs::path sceneFile = write("mesh.json", R"({ "camera": { "position": [0, 0, 5], "look_at": [0, 0, 0] },
        "objects": [ { "type": "mesh", "file": ")" +
                                                e.path().string() + R"(" } ] })");
    expectRefused(sceneFile, "mesh.json: objects[0].file: " + e.path().string() + ": ");
    ++meshes;
  }
  EXPECT_GE(meshes, 10);
}

TEST_F(CliHardening, DeepNestingFailsWithOneLine) {
  fs::path deep = write("deep.json", R"({ "camera": { "position": [0, 0, 5], "look_at": [0, 0, 0] }, "description": )" +
                                         std::string(1'000'000, '[') + std::string(1'000'000, ']') + "}");
  expectRefused(deep, "deep.json:1:140: invalid JSON: nested more than 64 levels deep");
}

// A scene whose base is a device that never ends is read no further than the size cap.
TEST_F(CliHardening, EndlessBaseFileFailsOnSize) {
  fs::path endless = write("endless.json", R"({ "base": "/dev/zero" })");
  expectRefused(endless, "endless.json: base: /dev/zero: file too large to be a scene");
}

// Ten million objects that fit the 64 MiB cap (as "{}") are parsed, then refused at the first; the
// parse takes memory in proportion to the file, bounded by the cap, not by what the file claims.
TEST_F(CliHardening, TenMillionObjectsFailWithoutExhaustingMemory) {
  std::string text = R"({ "camera": { "position": [0, 0, 5], "look_at": [0, 0, 0] }, "objects": [)";
  text.reserve(text.size() + 30'000'010);
  for (int i = 0; i < 10'000'000; ++i) text += "{},";
  text.back() = ']';
  text += '}';
  fs::path many = write("many.json", text);
  text.clear();
  text.shrink_to_fit();
  fs::path out = dir_ / "out" / "image.png";
  Outcome r = run({"render", many.string(), "-o", out.string()}, dir_);
  EXPECT_EQ(r.exitCode, 1) << r.err;
  EXPECT_EQ(r.err, "vkray: error: " + many.string() + ": objects[0]: missing required key 'type'\n");
  EXPECT_TRUE(outputs().empty());
  // About 36 bytes of parsed JSON per byte of "{}," (1.1 GB); AddressSanitizer's allocator doubles it.
#if defined(__SANITIZE_ADDRESS__)
  const long limitKb = 4l << 20;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
  const long limitKb = 4l << 20;
#else
  const long limitKb = 2l << 20;
#endif
#else
  const long limitKb = 2l << 20;
#endif
  EXPECT_LT(r.maxRssKb, limitKb) << "peak memory " << r.maxRssKb / 1024 << " MiB";
}

// ---- Limits --------------------------------------------------------------------------------------

TEST_F(CliHardening, FlagsBeyondTheCapsAreRefused) {
  struct Case {
    std::vector<std::string> flags;
    const char* says;
  };
  const Case cases[] = {
      {{"--spp", "4097"}, "vkray: error: --spp: Value 4097 not in range 1 to 4096\n"},
      {{"--max-depth", "65"}, "vkray: error: --max-depth: Value 65 not in range 0 to 64\n"},
      {{"--width", "16385"}, "vkray: error: --width: Value 16385 not in range 1 to 16384\n"},
      {{"--height", "0"}, "vkray: error: --height: Value 0 not in range 1 to 16384\n"},
      {{"--band-ms", "0"}, "vkray: error: --band-ms: Value 0 not in range 1 to 10000\n"},
      {{"--band-ms", "1e9"}, "vkray: error: --band-ms: Value 1e9 not in range 1 to 10000\n"},
      {{"--bailout", "1.5"}, "vkray: error: --bailout: Value 1.5 not in range 0 to 1\n"},
      {{"--bailout", "nan"}, "vkray: error: --bailout: Value nan not in range 0 to 1\n"},
      {{"--adaptive-threshold", "-0.1"}, "vkray: error: --adaptive-threshold: Value -0.1 not in range 0 to 1\n"},
      {{"--bailout", "half"}, "vkray: error: --bailout: Value half is not a number\n"},
      {{"--spp", "many"}, "vkray: error: --spp: Value many is not a whole number\n"},
      {{"--spp", "1.5"}, "vkray: error: --spp: Value 1.5 is not a whole number\n"},
      {{"--width", "1e3"}, "vkray: error: --width: Value 1e3 is not a whole number\n"},
      {{"--max-spp", "x"}, "vkray: error: --max-spp: Value x is not a whole number\n"},
      {{"--seed", "-1"}, "vkray: error: --seed: Value -1 not in range 0 to 4294967295\n"},
      {{"--spp", "99999999999999999999999"},
       "vkray: error: --spp: Value 99999999999999999999999 not in range 1 to 4096\n"},
      {{"--noise-threshold", "0"}, "vkray: error: --noise-threshold: Value 0 must be > 0 and at most 1e+06\n"},
      {{"--noise-threshold", "-0.01"}, "vkray: error: --noise-threshold: Value -0.01 must be > 0 and at most 1e+06\n"},
      {{"--noise-threshold", "nan"}, "vkray: error: --noise-threshold: Value nan must be > 0 and at most 1e+06\n"},
      {{"--time-limit", "0"}, "vkray: error: --time-limit: Value 0 must be > 0 and at most 604800\n"},
      {{"--time-limit", "-5"}, "vkray: error: --time-limit: Value -5 must be > 0 and at most 604800\n"},
      {{"--max-spp", "0"}, "vkray: error: --max-spp: Value 0 not in range 1 to 4096\n"},
      {{"--noise-threshold", "0.01", "--min-spp", "64", "--max-spp", "32"},
       "vkray: error: render.min_spp: must not exceed max_spp (32), got 64\n"},
      {{"--noise-threshold", "0.01", "--spp", "4", "--aa", "adaptive"},
       "vkray: error: render.antialiasing: \"adaptive\" cannot be combined with a noise threshold, a time limit or "
       "the spp, error and rays AOVs (they sample progressively): use one\n"},
  };
  fs::path out = dir_ / "out" / "image.png";
  for (const auto& c : cases) {
    std::vector<std::string> args{"render", scene("seed.json"), "-o", out.string()};
    args.insert(args.end(), c.flags.begin(), c.flags.end());
    Outcome r = run(args, dir_);
    EXPECT_EQ(r.exitCode, 1) << c.says;
    EXPECT_EQ(r.err, c.says);
    EXPECT_TRUE(outputs().empty());
  }
}

// The widest image the format allows is traced in bands of rows through a window of at most 64 MiB
// (16384 pixels: 256 rows), however tall the image is.
TEST_F(CliHardening, TheWidestImageStreamsThroughTheBandWindow) {
  fs::path out = dir_ / "out" / "wide.pfm";
  Outcome r = run({"render", scene("seed.json"), "-o", out.string(), "--width", "16384", "--height", "40",
                   "--max-depth", "0", "--stats", "-q"},
                  dir_, {cacheEnv_});
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_EQ(fs::file_size(out), std::string("PF\n16384 40\n-1.0\n").size() + 16384ull * 40 * 12);
}

// A progressive render keeps per-pixel sums on the host: at the largest size they need more memory
// than most machines have, and the render is refused before it traces, in one line that says how
// much, instead of ending in std::bad_alloc or the kernel's OOM killer. (Where the machine has the
// 27 GiB, there is nothing to refuse and the test is skipped.)
TEST_F(CliHardening, AProgressiveRenderTooLargeForHostMemoryIsRefused) {
  const std::uint64_t needed = progressiveHostBytes(16384, 16384, 16384);
  auto available = hostMemoryAvailable();
  if (!available || *available >= needed) GTEST_SKIP() << "this machine has the memory";
  fs::path out = dir_ / "out" / "huge.exr";
  Outcome r = run({"render", scene("seed.json"), "-o", out.string(), "--width", "16384", "--height", "16384",
                   "--noise-threshold", "0.01"},
                  dir_, {cacheEnv_});
  EXPECT_EQ(r.exitCode, 1) << "signal " << r.signal << "\n" << r.err;
  EXPECT_EQ(lineCount(r.err), 1u) << r.err;
  EXPECT_EQ(r.err.rfind("vkray: error: sampling progressively (a noise threshold, a time limit, or the spp, error or "
                        "rays AOVs) at 16384x16384 keeps 27.0 GiB of per-pixel sums in host memory, and ",
                        0),
            0u)
      << r.err;
  EXPECT_TRUE(outputs().empty());
  EXPECT_LT(r.maxRssKb, 2 * 1024 * 1024) << "refused after allocating";
}

// ---- Interrupts, kills and atomic output ---------------------------------------------------------

// The output path is checked before anything else is opened: with no Vulkan driver at all, the
// error is still the output's, so no time is spent tracing an image that could not be written.
TEST_F(CliHardening, AnUnwritableOutputFailsBeforeAnyTracing) {
  const std::vector<std::string> noDriver{"VK_ICD_FILENAMES=/nonexistent/icd.json",
                                          "VK_DRIVER_FILES=/nonexistent/icd.json"};
  fs::path missingDir = dir_ / "no-such-dir" / "image.png";
  Outcome r = run({"render", scene("seed.json"), "-o", missingDir.string()}, dir_, noDriver);
  EXPECT_EQ(r.exitCode, 1);
  EXPECT_EQ(r.err, "vkray: error: " + missingDir.string() + ": directory '" + missingDir.parent_path().string() +
                       "' does not exist\n");
  fs::create_directories(dir_ / "out" / "dir.png");
  r = run({"render", scene("seed.json"), "-o", (dir_ / "out" / "dir.png").string()}, dir_, noDriver);
  EXPECT_EQ(r.exitCode, 1);
  EXPECT_EQ(r.err, "vkray: error: " + (dir_ / "out" / "dir.png").string() + ": is a directory\n");
  r = run({"render", scene("seed.json"), "-o", (dir_ / "out" / "image.jpg").string()}, dir_, noDriver);
  EXPECT_EQ(r.exitCode, 1);
  EXPECT_EQ(lineCount(r.err), 1u) << r.err;
  EXPECT_EQ(r.err.find("Vulkan"), std::string::npos) << r.err;
}

// A write that fails part way (here the file-size limit; on a full disk, ENOSPC) is one line, and
// leaves the old file as it was and no temporary file behind. The limit is 4 MiB against a 12 MiB
// image: Mesa 25's lavapipe backs small device allocations with memory files that the limit
// applies to as well (a tighter one is a SIGBUS inside the driver before anything is written),
// while vkray's larger buffers come from its own anonymous pages.
TEST_F(CliHardening, AFailedWriteKeepsTheOldFileAndLeavesNothingElse) {
  fs::path out = dir_ / "out" / "image.pfm";
  std::ofstream(out) << "previous contents";
  Outcome r = Vkray({"render", scene("seed.json"), "-o", out.string(), "--width", "1024", "--height", "1024", "-q",
                     "--no-pipeline-cache"},
                    dir_, false, {cacheEnv_}, /*maxFileBytes=*/4 << 20)
                  .wait();
  EXPECT_EQ(r.exitCode, 1) << "signal " << r.signal;
  EXPECT_EQ(r.err, "vkray: error: " + out.string() + ": cannot write: File too large\n");
  EXPECT_EQ(slurp(out), "previous contents");
  EXPECT_EQ(outputs(), std::vector<std::string>{"image.pfm"});
}

// Long enough on lavapipe that signals arrive mid-render (it is stopped long before the end).
std::vector<std::string> slowRender(const fs::path& out) {
  return {"render", scene("showcase.json"), "-o", out.string(), "--width", "800", "--height", "600", "--spp", "256"};
}

TEST_F(CliHardening, CtrlCStopsBetweenBandsAndKeepsTheOldFile) {
  for (bool oldFile : {false, true}) {
    SCOPED_TRACE(oldFile ? "replacing a file" : "new file");
    fs::path out = dir_ / "out" / "image.png";
    if (oldFile) std::ofstream(out) << "previous contents";
    Vkray vkray(slowRender(out), dir_, /*terminal=*/true, {cacheEnv_});
    ASSERT_TRUE(vkray.waitForOutput("% ", 240)) << "no progress bar";
    vkray.type("\x03"); // Ctrl-C at the terminal: SIGINT to the foreground process
    Outcome r = vkray.wait(60);
    EXPECT_EQ(r.exitCode, 130) << "signal " << r.signal << "\n" << r.out;
    EXPECT_NE(r.out.find("vkray: interrupted; no output written"), std::string::npos) << r.out;
    if (oldFile) {
      EXPECT_EQ(slurp(out), "previous contents");
      EXPECT_EQ(outputs(), std::vector<std::string>{"image.png"});
      fs::remove(out);
    } else {
      EXPECT_TRUE(outputs().empty());
    }
  }
}

TEST_F(CliHardening, SigtermStopsLikeCtrlC) {
  fs::path out = dir_ / "out" / "image.png";
  Vkray vkray(slowRender(out), dir_, /*terminal=*/true, {cacheEnv_});
  ASSERT_TRUE(vkray.waitForOutput("% ", 240)) << "no progress bar";
  vkray.signal(SIGTERM);
  Outcome r = vkray.wait(60);
  EXPECT_EQ(r.exitCode, 130) << "signal " << r.signal;
  EXPECT_TRUE(outputs().empty());
}

TEST_F(CliHardening, SigkillMidRenderKeepsTheOldFile) {
  fs::path out = dir_ / "out" / "image.png";
  std::ofstream(out) << "previous contents";
  Vkray vkray(slowRender(out), dir_, /*terminal=*/true, {cacheEnv_});
  ASSERT_TRUE(vkray.waitForOutput("% ", 240)) << "no progress bar";
  vkray.signal(SIGKILL);
  Outcome r = vkray.wait(60);
  EXPECT_EQ(r.signal, SIGKILL);
  EXPECT_EQ(slurp(out), "previous contents");
  EXPECT_EQ(outputs(), std::vector<std::string>{"image.png"});
}

// SIGKILL while the new file is being written (between creating the temporary file and renaming it)
// leaves the old file intact and a hidden ".image.pfm.tmp-PID-XXXXXX"; the next write to the same
// output removes it. The window is a few tens of milliseconds: the test watches for the temporary
// file and kills on sight, and tries again if the write won the race.
TEST_F(CliHardening, SigkillWhileWritingLeavesTheOldFileAndTheNextRunCleansUp) {
  fs::path out = dir_ / "out" / "image.pfm";
  bool caught = false;
  for (int attempt = 0; attempt < 4 && !caught; ++attempt) {
    std::ofstream(out) << "previous contents";
    Vkray vkray({"render", scene("seed.json"), "-o", out.string(), "--width", "3072", "--height", "3072", "--max-depth",
                 "0", "-q"},
                dir_, false, {cacheEnv_});
    for (bool done = false; !done && !caught;) {
      for (const auto& name : outputs()) {
        if (name.rfind(".image.pfm.tmp-", 0) == 0) {
          vkray.signal(SIGKILL);
          caught = true;
        }
      }
      int status = 0;
      if (!caught && vkray.ended(status)) {
        done = true; // the write finished before it was seen: the old file was replaced whole
        EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
        EXPECT_EQ(outputs(), std::vector<std::string>{"image.pfm"});
        EXPECT_EQ(fs::file_size(out), std::string("PF\n3072 3072\n-1.0\n").size() + 3072ull * 3072 * 12);
      }
      std::this_thread::sleep_for(std::chrono::microseconds(500));
    }
    if (caught) {
      Outcome r = vkray.wait(60);
      EXPECT_EQ(r.signal, SIGKILL);
    }
  }
  if (!caught) GTEST_SKIP() << "the write always finished before the temporary file was seen";
  EXPECT_EQ(slurp(out), "previous contents");
  auto names = outputs();
  ASSERT_EQ(names.size(), 2u);
  EXPECT_EQ(names[1], "image.pfm");
  EXPECT_EQ(names[0].rfind(".image.pfm.tmp-", 0), 0u) << names[0];

  Outcome next =
      run({"render", scene("seed.json"), "-o", out.string(), "--width", "8", "--height", "8", "-q"}, dir_, {cacheEnv_});
  ASSERT_EQ(next.exitCode, 0) << next.err;
  EXPECT_EQ(outputs(), std::vector<std::string>{"image.pfm"}) << "the stale temporary file was left";
}

// ---- Terminal ------------------------------------------------------------------------------------

TEST_F(CliHardening, ProgressBarOnATerminalOnly) {
  fs::path out = dir_ / "out" / "image.png";
  std::vector<std::string> args{
      "render", scene("showcase.json"), "-o", out.string(), "--width", "400", "--height", "300", "--spp", "16",
      "--stats"};
  Outcome tty = Vkray(args, dir_, /*terminal=*/true, {cacheEnv_}).wait();
  ASSERT_EQ(tty.exitCode, 0) << tty.out;
  // Percentage, rays per second (counted with --stats) and time left, redrawn in place.
  EXPECT_NE(tty.out.find("\r[#"), std::string::npos) << tty.out;
  EXPECT_NE(tty.out.find("% "), std::string::npos);
  EXPECT_NE(tty.out.find(" Mrays/s"), std::string::npos);
  EXPECT_NE(tty.out.find(" left"), std::string::npos);
  // The bar is wiped before the statistics are printed.
  // (The statistics have " left" of their own: "is left out of shadow rays".)
  auto stats = tty.out.find("scene: ");
  ASSERT_NE(stats, std::string::npos) << tty.out;
  auto lastBar = tty.out.rfind(" left", stats);
  ASSERT_NE(lastBar, std::string::npos) << tty.out;
  EXPECT_NE(tty.out.substr(lastBar, stats - lastBar).find("\r"), std::string::npos);

  std::vector<std::string> quietArgs(args.begin(), args.end() - 1); // without --stats
  quietArgs.push_back("-q");
  Outcome quiet = Vkray(quietArgs, dir_, true, {cacheEnv_}).wait();
  ASSERT_EQ(quiet.exitCode, 0);
  EXPECT_EQ(quiet.out.find('%'), std::string::npos) << quiet.out;

  Outcome piped = run(args, dir_, {cacheEnv_});
  ASSERT_EQ(piped.exitCode, 0) << piped.err;
  EXPECT_EQ(piped.err, "") << "stderr is not a terminal: no progress bar";
}

// ---- No device -----------------------------------------------------------------------------------

TEST_F(CliHardening, NoVulkanDriverIsOneLineThatSaysHowToGetLavapipe) {
  const std::vector<std::string> noDriver{"VK_ICD_FILENAMES=/nonexistent/icd.json",
                                          "VK_DRIVER_FILES=/nonexistent/icd.json"};
  fs::path out = dir_ / "out" / "image.png";
  for (const auto& args :
       {std::vector<std::string>{"render", scene("seed.json"), "-o", out.string()}, std::vector<std::string>{"info"}}) {
    Outcome r = run(args, dir_, noDriver);
    EXPECT_EQ(r.exitCode, 1) << r.err;
    EXPECT_EQ(r.err, "vkray: error: no Vulkan driver found: install a Vulkan driver; for the CPU driver lavapipe: "
                     "apt-get install mesa-vulkan-drivers\n");
  }
  EXPECT_TRUE(outputs().empty());
}

// A driver that is installed but finds no hardware (Mesa's Radeon driver without a Radeon) fails to
// enumerate devices; that is "no device", said the same way.
TEST_F(CliHardening, DriverWithoutHardwareIsOneLineThatSaysHowToGetLavapipe) {
  const fs::path radeon = "/usr/share/vulkan/icd.d/radeon_icd.x86_64.json";
  if (!fs::exists(radeon) || fs::exists("/dev/dri")) GTEST_SKIP() << "needs Mesa's Radeon ICD and no /dev/dri";
  fs::path out = dir_ / "out" / "image.png";
  for (const auto& args :
       {std::vector<std::string>{"render", scene("seed.json"), "-o", out.string()}, std::vector<std::string>{"info"}}) {
    Outcome r = run(args, dir_, {"VK_ICD_FILENAMES=" + radeon.string(), "VK_DRIVER_FILES=" + radeon.string()});
    EXPECT_EQ(r.exitCode, 1) << r.err;
    EXPECT_EQ(r.err, "vkray: error: no Vulkan device found: install a Vulkan driver; for the CPU driver lavapipe: "
                     "apt-get install mesa-vulkan-drivers\n");
  }
}

// ---- Determinism ---------------------------------------------------------------------------------

// The same scene and flags give byte-identical files in separate processes: with the pipeline
// cache cold and warm, and with bands of different heights (--band-ms 1 cuts the image into the
// smallest bands), so no pixel depends on how the work was split.
TEST_F(CliHardening, SameSceneAndFlagsGiveTheSameBytes) {
  struct Case {
    const char* scene;
    const char* file;
    std::vector<std::string> flags;
  };
  const Case cases[] = {
      {"showcase.json", "stratified.png", {"--width", "96", "--height", "64", "--spp", "4"}},
      {"showcase.json", "adaptive.pfm", {"--width", "96", "--height", "64", "--spp", "8", "--aa", "adaptive"}},
      {"glass.json", "glass.pfm", {"--width", "80", "--height", "60", "--spp", "2", "--aa", "adaptive"}},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.file);
    std::vector<std::string> bytes;
    for (int run = 0; run < 3; ++run) {
      fs::path out = dir_ / "out" / (std::to_string(run) + c.file);
      std::vector<std::string> args{"render", scene(c.scene), "-o", out.string(), "-q"};
      args.insert(args.end(), c.flags.begin(), c.flags.end());
      if (run == 2) args.insert(args.end(), {"--band-ms", "1"});
      Outcome r = vkray::test::run(args, dir_, {cacheEnv_});
      ASSERT_EQ(r.exitCode, 0) << r.err;
      bytes.push_back(slurp(out));
    }
    EXPECT_GT(bytes[0].size(), 1000u);
    EXPECT_TRUE(bytes[0] == bytes[1]) << "two runs differ";
    EXPECT_TRUE(bytes[0] == bytes[2]) << "a different band split changes the image";
  }
}

// ---- Validation ----------------------------------------------------------------------------------

// With the validation layer and its synchronization checks on, a render prints nothing: no message
// during the work and no "has not been destroyed" report when the device and instance close.
TEST_F(CliHardening, ValidatedRenderLeavesNoMessageAndNoObjectBehind) {
  fs::path out = dir_ / "out" / "image.pfm";
  Outcome r = run({"render", scene("showcase.json"), "-o", out.string(), "--width", "64", "--height", "48", "--spp",
                   "4", "--aa", "adaptive", "--validate", "--sync-validation", "--band-ms", "1", "-q"},
                  dir_, {cacheEnv_});
  EXPECT_EQ(r.exitCode, 0) << r.err;
  EXPECT_EQ(r.err, "");
}

} // namespace
} // namespace vkray::test
