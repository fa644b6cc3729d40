// parallelFor: a host loop of independent iterations spread over the machine's hardware threads.
#pragma once

#include <algorithm>
#include <cstddef>
#include <exception>
#include <thread>
#include <vector>

namespace vkray {

// The threads parallelFor uses at most: the hardware's (1 where the library cannot tell).
inline unsigned hostThreads() {
  return std::max(1u, std::thread::hardware_concurrency());
}

// Calls body(begin, end) on contiguous ranges that cover [0, n) exactly once, one range per thread,
// each of at least `minPerThread` iterations (so a short loop runs on the caller alone, with no
// thread started), at most `threads` ranges (0: hostThreads()). The caller runs the first range and
// waits for the others. Iterations must not depend on one another; where each writes only its own
// elements the result is the same whatever the split. An exception from any range is rethrown
// here, after every range has finished.
template <class Body> void parallelFor(std::size_t n, std::size_t minPerThread, Body body, unsigned threads = 0) {
  if (n == 0) return;
  const std::size_t most = threads > 0 ? threads : hostThreads();
  const std::size_t ranges = std::clamp<std::size_t>(n / std::max<std::size_t>(minPerThread, 1), 1, most);
  if (ranges == 1) {
    body(std::size_t{0}, n);
    return;
  }
  std::vector<std::exception_ptr> failures(ranges);
  auto run = [&](std::size_t r) {
    try {
      body(n * r / ranges, n * (r + 1) / ranges);
    } catch (...) {
      failures[r] = std::current_exception();
    }
  };
  std::vector<std::thread> workers;
  workers.reserve(ranges - 1);
  for (std::size_t r = 1; r < ranges; ++r) workers.emplace_back(run, r);
  run(0);
  for (std::thread& t : workers) t.join();
  for (const std::exception_ptr& f : failures)
    if (f) std::rethrow_exception(f);
}

} // namespace vkray
