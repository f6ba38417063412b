// Scalar -> colour maps for pictures of per-vertex figures (issue 26: the
// garment coloured by clearance change and by strain) and their colour bar.
//
//  * kViridis: perceptually uniform, for magnitudes (strain). The 10 stops
//    of matplotlib's viridis sampled at t = i/9 (van der Walt and Smith's
//    map, the stops R's viridis(10) prints), interpolated linearly in sRGB;
//    within 3/255 of matplotlib's 256-entry table.
//  * kDiverging: for signed figures centred on 0 (clearance change): the
//    7 stops of ColorBrewer's RdBu (Brewer, reversed: blue negative, near
//    white at the middle, red positive), interpolated linearly in sRGB.
//
// t is clamped to [0, 1]; NaN maps to the lowest colour (callers reject
// non-finite figures before colouring). Values are sRGB in [0, 1]; the
// renderer wants linear RGB (srgb_to_linear).
//
// Reads and writes nothing but its arguments.
#pragma once

#include <atelier/engine/math.h>
#include <atelier/engine/status.h>
#include <atelier/io/png.h>

#include <array>
#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

namespace atelier {

enum class ColourMap : std::uint8_t { kViridis, kDiverging };

/// The map's name ("viridis", "diverging") and back (nullopt-like: kInvalidArgument).
[[nodiscard]] std::string_view colour_map_name(ColourMap map) noexcept;
[[nodiscard]] Expected<ColourMap> colour_map_from_name(std::string_view name);

/// sRGB colour in [0, 1]^3 of t in [0, 1] (clamped).
[[nodiscard]] Vec3d colour_map_srgb(ColourMap map, double t) noexcept;
/// The same as 8-bit sRGB (rounded).
[[nodiscard]] std::array<std::uint8_t, 3> colour_map_bytes(ColourMap map, double t) noexcept;
/// sRGB component -> linear (IEC 61966-2-1), for the renderer's colours.
[[nodiscard]] double srgb_to_linear(double c) noexcept;
/// Linear RGB of t: what RenderMesh::vertex_colours takes.
[[nodiscard]] Vec3d colour_map_linear(ColourMap map, double t) noexcept;

/// Per-vertex linear colours of `values` mapped from [lo, hi] to [0, 1]
/// (lo == hi maps everything to the middle). kInvalidArgument for a
/// non-finite value (naming its index) or bound, or lo > hi.
[[nodiscard]] Expected<std::vector<Vec3d>> map_values(std::span<const double> values, double lo, double hi,
                                                      ColourMap map);

/// A horizontal colour bar: column x has the colour of t = x / (width - 1),
/// every row the same, framed by a 1-pixel dark border when `border`.
/// kInvalidArgument for width < 2 or height < 1 or a size over 4096.
[[nodiscard]] Expected<RgbImage> colour_bar(ColourMap map, std::uint32_t width, std::uint32_t height,
                                            bool border = false);

}  // namespace atelier
