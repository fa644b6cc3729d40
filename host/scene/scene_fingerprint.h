// A fingerprint of what a render's pixels depend on: the resolved scene (after loading, flags and
// animation), its settings, the frame and the image size. Tiles carry it so that a merge can tell
// whether they belong to the same image.
#pragma once

#include <string>

#include "scene/scene.h"

namespace vkray {

// 16 hex digits (FNV-1a, 64 bits, over a canonical encoding: every double by its bit pattern, every
// array with its length). Equal scenes give equal fingerprints; the file's path and the names of
// things do not enter.
std::string sceneFingerprint(const Scene& scene, int frame);

} // namespace vkray
