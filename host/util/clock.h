// Wall-clock intervals for the timings vkray prints (load, pipeline, write, total, ...).
#pragma once

#include <chrono>

namespace vkray {

using Clock = std::chrono::steady_clock;

// Milliseconds since `t`.
inline double msSince(Clock::time_point t) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

} // namespace vkray
