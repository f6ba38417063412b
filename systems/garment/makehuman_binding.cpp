#include <atelier/systems/garment/makehuman_binding.h>

#include <cmath>
#include <string>

#include <atelier/systems/garment/regenerate_garment.h>

namespace atelier::makehuman {

std::vector<Vec3d> fit_binding(const GarmentBinding& b, std::span<const Vec3f> H) {
  Vec3d scale(1, 1, 1);
  for (int k = 0; k < 3; ++k)
    if (b.has_scale[k])
      scale[k] = std::abs(static_cast<double>(H[b.scale_a[k]][k]) - static_cast<double>(H[b.scale_b[k]][k])) /
                 b.scale_d[k];
  std::vector<Vec3d> out(b.refs.size());
  for (std::size_t i = 0; i < b.refs.size(); ++i) {
    const auto& r = b.refs[i];
    Vec3d p = Vec3d::Zero();
    for (int k = 0; k < 3; ++k) p += r.w[k] * H[r.v[k]].cast<double>();
    out[i] = p + r.offset.cwiseProduct(scale);
  }
  return out;
}

Expected<PolygonSoup> fitted_garment(const HumanLibrary& lib, const std::filesystem::path& mhclo) {
  GarmentBinding binding;
  try {
    binding = read_mhclo(mhclo, lib.vertex_count());
  } catch (const Error& e) {
    return e.status();
  }
  auto g = read_garment_mesh(mhclo.parent_path() / binding.obj_file);
  if (!g) return g.status();
  if (g->positions.size() != binding.refs.size())
    return Status(ErrorCode::kMismatch, mhclo.string() + ": " + std::to_string(binding.refs.size()) +
                                            " bound vertices but " + binding.obj_file + " has " +
                                            std::to_string(g->positions.size()));
  // The binding's fit on the default body, the reference body's shape.
  std::vector<Vec3f> H(lib.vertex_count());
  lib.build(MacroParams{}, H);
  g->positions = fit_binding(binding, H);
  for (Vec3d& p : g->positions) p *= kMakeHumanToMetres;
  return g;
}

}  // namespace atelier::makehuman
