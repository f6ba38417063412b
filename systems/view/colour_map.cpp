#include <atelier/systems/view/colour_map.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace atelier {

namespace {

struct Stops {
  const std::uint8_t (*rgb)[3];
  std::size_t n;
};

// matplotlib viridis at t = i / 9 (#440154 ... #FDE725).
constexpr std::uint8_t kViridis[][3] = {{0x44, 0x01, 0x54}, {0x48, 0x28, 0x78}, {0x3E, 0x4A, 0x89}, {0x31, 0x68, 0x8E},
                                        {0x26, 0x82, 0x8E}, {0x1F, 0x9E, 0x89}, {0x35, 0xB7, 0x79}, {0x6D, 0xCD, 0x59},
                                        {0xB4, 0xDE, 0x2C}, {0xFD, 0xE7, 0x25}};
// ColorBrewer RdBu, 7 classes, blue (negative) to red (positive).
constexpr std::uint8_t kDiverging[][3] = {{0x21, 0x66, 0xAC}, {0x67, 0xA9, 0xCF}, {0xD1, 0xE5, 0xF0},
                                          {0xF7, 0xF7, 0xF7}, {0xFD, 0xDB, 0xC7}, {0xEF, 0x8A, 0x62},
                                          {0xB2, 0x18, 0x2B}};

Stops stops_of(ColourMap map) noexcept {
  if (map == ColourMap::kDiverging) return {kDiverging, std::size(kDiverging)};
  return {kViridis, std::size(kViridis)};
}

}  // namespace

std::string_view colour_map_name(ColourMap map) noexcept {
  return map == ColourMap::kDiverging ? "diverging" : "viridis";
}

Expected<ColourMap> colour_map_from_name(std::string_view name) {
  if (name == "viridis") return ColourMap::kViridis;
  if (name == "diverging") return ColourMap::kDiverging;
  return Status(ErrorCode::kInvalidArgument, "colour map: unknown map '" + std::string(name) + "'");
}

Vec3d colour_map_srgb(ColourMap map, double t) noexcept {
  const Stops s = stops_of(map);
  if (!(t > 0.0)) t = 0.0;  // also NaN
  if (t > 1.0) t = 1.0;
  const double pos = t * static_cast<double>(s.n - 1);
  const auto i = std::min(static_cast<std::size_t>(pos), s.n - 2);
  const double f = pos - static_cast<double>(i);
  Vec3d c;
  for (int k = 0; k < 3; ++k) c[k] = ((1.0 - f) * s.rgb[i][k] + f * s.rgb[i + 1][k]) / 255.0;
  return c;
}

std::array<std::uint8_t, 3> colour_map_bytes(ColourMap map, double t) noexcept {
  const Vec3d c = colour_map_srgb(map, t);
  std::array<std::uint8_t, 3> b{};
  for (int k = 0; k < 3; ++k) b[k] = static_cast<std::uint8_t>(std::lround(std::clamp(c[k], 0.0, 1.0) * 255.0));
  return b;
}

double srgb_to_linear(double c) noexcept {
  c = std::clamp(c, 0.0, 1.0);
  return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
}

Vec3d colour_map_linear(ColourMap map, double t) noexcept {
  const Vec3d c = colour_map_srgb(map, t);
  return {srgb_to_linear(c[0]), srgb_to_linear(c[1]), srgb_to_linear(c[2])};
}

Expected<std::vector<Vec3d>> map_values(std::span<const double> values, double lo, double hi, ColourMap map) {
  if (!std::isfinite(lo) || !std::isfinite(hi) || lo > hi)
    return Status(ErrorCode::kInvalidArgument,
                  "colour map: bad range [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  std::vector<Vec3d> out(values.size());
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (!std::isfinite(values[i]))
      return Status(ErrorCode::kInvalidArgument, "colour map: value " + std::to_string(i) + " is not finite");
    const double t = hi > lo ? (values[i] - lo) / (hi - lo) : 0.5;
    out[i] = colour_map_linear(map, t);
  }
  return out;
}

Expected<RgbImage> colour_bar(ColourMap map, std::uint32_t width, std::uint32_t height, bool border) {
  if (width < 2 || height < 1 || width > 4096 || height > 4096)
    return Status(ErrorCode::kInvalidArgument,
                  "colour bar: bad size " + std::to_string(width) + " x " + std::to_string(height));
  RgbImage img(width, height);
  for (std::uint32_t x = 0; x < width; ++x) {
    const auto c = colour_map_bytes(map, static_cast<double>(x) / static_cast<double>(width - 1));
    for (std::uint32_t y = 0; y < height; ++y) std::copy(c.begin(), c.end(), img.at(x, y));
  }
  if (border)
    for (std::uint32_t y = 0; y < height; ++y)
      for (std::uint32_t x = 0; x < width; ++x)
        if (x == 0 || y == 0 || x + 1 == width || y + 1 == height) std::fill(img.at(x, y), img.at(x, y) + 3, 60);
  return img;
}

}  // namespace atelier
