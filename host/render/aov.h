// The AOV layers `render --aov` writes beside RGB in an EXR: their names, what each needs from the
// renderer, and their channels built from what the renders returned.
//
// Channels follow OpenEXR's `layer.channel` convention (one layer per AOV, 32-bit float):
//   depth.Z                          distance from the eye along the pixel-centre ray; +inf: no hit
//   normal.X, normal.Y, normal.Z     world-space unit shading normal facing the eye; 0: no hit
//   albedo.R, albedo.G, albedo.B     base colour at the first hit (linear); 0: no hit
//   spp.Y, error.Y, rays.Y           samples, estimated standard error, rays traced (PixelStats)
// depth, normal and albedo come from the pixel-centre eye ray (Kernel::Aov, shaders/aov.comp); spp,
// error and rays from the render's own per-pixel statistics (RenderOptions::pixelStats).
#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include "image/exr_io.h"
#include "render/render_options.h"
#include "util/enum_names.h"

namespace vkray {

enum class Aov { Depth, Normal, Albedo, Spp, Error, Rays };
template <> struct EnumNames<Aov> {
  static constexpr std::array<EnumName<Aov>, 6> values{{{Aov::Depth, "depth"},
                                                        {Aov::Normal, "normal"},
                                                        {Aov::Albedo, "albedo"},
                                                        {Aov::Spp, "spp"},
                                                        {Aov::Error, "error"},
                                                        {Aov::Rays, "rays"}}};
};

// "depth,normal" or "all" (names may repeat and mix with `all`): the AOVs in the table's order,
// each once. InputError at `--aov` for an empty list, an empty name or an unknown one.
std::vector<Aov> parseAovList(const std::string& list);

// depth, normal or albedo: a Kernel::Aov pass after the render.
bool needsFirstHits(const std::vector<Aov>& aovs);
// spp, error or rays: RenderOptions::pixelStats on the render.
bool needsPixelStats(const std::vector<Aov>& aovs);

// Error when the render was asked for per-pixel statistics the AOVs need and returned none, rather
// than layers of zeros.
void checkPixelStats(const std::vector<Aov>& aovs, const PixelStats& pixels);

// The EXR channels of `aovs`, in order, for an image of `pixelCount` pixels. firstHits: the
// Kernel::Aov pass's records (read only when needsFirstHits); pixels: the render's statistics
// (only when needsPixelStats). Error when one the AOVs need is missing or of another size.
std::vector<ExrChannel> aovChannels(const std::vector<Aov>& aovs, const std::vector<FirstHit>& firstHits,
                                    const PixelStats& pixels, std::size_t pixelCount);

} // namespace vkray
