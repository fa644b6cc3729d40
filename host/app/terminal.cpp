// Ctrl-C handling and the progress bar (see terminal.h).
#include "app/terminal.h"

#include <algorithm>
#include <csignal>
#include <cstdio>
#include <string>

#include <unistd.h>

namespace vkray {

namespace {

std::atomic<bool> gInterrupted{false};

// The first SIGINT/SIGTERM asks the render to stop between bands; a second one of either kind
// ends the process at once, by the signal it received (so the parent sees the right cause).
extern "C" void onInterrupt(int signal) {
  if (gInterrupted.exchange(true)) {
    std::signal(signal, SIG_DFL);
    std::raise(signal);
  }
}

std::string formatMs(double ms) {
  char buf[32];
  if (ms < 1000.0)
    std::snprintf(buf, sizeof buf, "%.0f ms", ms);
  else if (ms < 120000.0)
    std::snprintf(buf, sizeof buf, "%.1f s", ms / 1000.0);
  else
    std::snprintf(buf, sizeof buf, "%.1f min", ms / 60000.0);
  return buf;
}

} // namespace

const std::atomic<bool>& installInterruptFlag() {
  struct sigaction sa {};
  sa.sa_handler = onInterrupt;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  return gInterrupted;
}

ProgressBar::ProgressBar(bool enabled) : enabled_(enabled && ::isatty(STDERR_FILENO)) {}

ProgressBar::~ProgressBar() {
  finish();
}

void ProgressBar::update(const RenderProgress& p) {
  if (!enabled_) return;
  constexpr int kWidth = 30;
  int filled = std::clamp(static_cast<int>(p.fraction * kWidth + 0.5), 0, kWidth);
  char percent[16];
  std::snprintf(percent, sizeof percent, "%3.0f%%", p.fraction * 100.0);
  std::string line = "[";
  line.append(static_cast<std::size_t>(filled), '#');
  line.append(static_cast<std::size_t>(kWidth - filled), '.');
  line += "] ";
  line += percent;
  // Rays per second only when the renderer counts rays (--stats): counting is compiled out otherwise.
  if (p.raysPerSecond > 0) {
    char rate[32];
    std::snprintf(rate, sizeof rate, "  %.1f Mrays/s", p.raysPerSecond * 1e-6);
    line += rate;
  }
  line += "  " + formatMs(p.remainingMs) + " left";
  // Pad over the rest of a longer previous line; finish() clears exactly what was drawn.
  int n = static_cast<int>(line.size());
  std::fprintf(stderr, "\r%s%*s", line.c_str(), std::max(0, width_ - n), "");
  std::fflush(stderr);
  width_ = std::max(width_, n);
  drawn_ = true;
}

void ProgressBar::finish() {
  if (drawn_) {
    std::fprintf(stderr, "\r%*s\r", width_, "");
    std::fflush(stderr);
    drawn_ = false;
    width_ = 0;
  }
}

} // namespace vkray
