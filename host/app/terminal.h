// Terminal concerns of the command line: the Ctrl-C flag checked between bands, and the progress
// bar drawn on stderr when it is a terminal.
#pragma once

#include <atomic>

#include "render/renderer.h"

namespace vkray {

// Installs a SIGINT and SIGTERM handler that sets the returned flag; a second signal kills at once.
const std::atomic<bool>& installInterruptFlag();

class ProgressBar {
public:
  explicit ProgressBar(bool enabled);
  ~ProgressBar();
  void update(const RenderProgress& p);
  void finish();

private:
  bool enabled_;
  bool drawn_ = false;
  int width_ = 0; // columns the widest line drawn so far takes
};

} // namespace vkray
