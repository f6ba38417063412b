// MakeHuman's own way of fitting a garment on a body, its binding (.mhclo,
// read by io/makehuman/mhclo.h): the peer that garment regeneration is
// compared with, and how a MakeHuman garment is placed on the reference
// body before it is encoded as a detail template.
//   fitted = w0 H[i0] + w1 H[i1] + w2 H[i2] + (sx dx, sy dy, sz dz),
//   s_axis = |H[a].axis - H[b].axis| / d   from the x_scale/y_scale/z_scale lines.
//
// Reads: a binding and a body's vertex array. Writes: the fitted positions.
#pragma once

#include <filesystem>
#include <span>
#include <vector>

#include <atelier/engine/math.h>
#include <atelier/engine/status.h>
#include <atelier/io/makehuman/mhclo.h>
#include <atelier/storage/polygon_soup.h>
#include <atelier/systems/body/makehuman_body.h>

namespace atelier::makehuman {

/// The binding's fit on a body with vertex array H (base.obj units).
[[nodiscard]] std::vector<Vec3d> fit_binding(const GarmentBinding& b, std::span<const Vec3f> H);

/// The garment of a .mhclo file (its OBJ's faces, beside it) fitted by its
/// binding on the library's default body, in metres: the garment on the
/// MakeHuman reference body. Errors name the file.
[[nodiscard]] Expected<PolygonSoup> fitted_garment(const HumanLibrary& lib, const std::filesystem::path& mhclo);

}  // namespace atelier::makehuman
