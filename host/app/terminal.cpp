// Ctrl-C handling and the progress bar (see terminal.h).
#include "app/terminal.h"

#include <csignal>
#include <cstdio>

#include <unistd.h>

namespace vkray {

namespace {

std::atomic<bool> gInterrupted{false};

extern "C" void onInterrupt(int) {
  if (gInterrupted.exchange(true)) {
    std::signal(SIGINT, SIG_DFL);
    std::raise(SIGINT);
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
  int filled = static_cast<int>(p.fraction * kWidth + 0.5);
  char bar[kWidth + 1];
  for (int i = 0; i < kWidth; ++i) bar[i] = i < filled ? '#' : '.';
  bar[kWidth] = '\0';
  std::fprintf(stderr, "\r[%s] %3.0f%%", bar, p.fraction * 100.0);
  if (p.raysPerSecond > 0) std::fprintf(stderr, "  %.1f Mrays/s", p.raysPerSecond * 1e-6);
  std::fprintf(stderr, "  %s left   ", formatMs(p.remainingMs).c_str());
  std::fflush(stderr);
  drawn_ = true;
}

void ProgressBar::finish() {
  if (drawn_) {
    std::fprintf(stderr, "\r%60s\r", "");
    std::fflush(stderr);
    drawn_ = false;
  }
}

} // namespace vkray
