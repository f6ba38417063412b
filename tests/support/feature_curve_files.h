// Test helpers for feature-curve files (issue 26): a reference body written
// as OBJ in another frame, and its own feature curves written as the JSON
// of io/feature_curves.h in that frame, so that a test can read both back
// through read_reference_body and compare with the engine's curves.
#pragma once

#include <atelier/io/feature_curves.h>
#include <atelier/systems/body/reference_body.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

namespace atelier::testing {

/// Engine (X, Y, Z) in metres is file (X, -Z, Y) in centimetres, Z up.
inline Vec3d to_cm_z_up(const Vec3d& p) {
  return Vec3d(100 * p.x(), -100 * p.z(), 100 * p.y());
}
inline Vec3d same_frame(const Vec3d& p) {
  return p;
}

/// The skin as OBJ, every vertex mapped and written with 17 digits.
inline void write_body_obj(const ReferenceBody& b, const std::filesystem::path& file,
                           const std::function<Vec3d(const Vec3d&)>& map) {
  std::ofstream o(file);
  char buf[160];
  const Model& m = b.model;
  for (std::uint32_t v = 0; v < m.nodes.slots.capacity(); ++v) {
    const Vec3d q = map(m.nodes.position[v]);
    std::snprintf(buf, sizeof buf, "v %.17g %.17g %.17g\n", q.x(), q.y(), q.z());
    o << buf;
  }
  std::vector<NodeIdx> f;
  for (std::uint32_t i = 0; i < m.faces.slots.capacity(); ++i) {
    if (!m.alive(FaceIdx{i})) continue;
    m.face_nodes(FaceIdx{i}, f);
    o << "f";
    for (NodeIdx n : f) o << ' ' << n.value + 1;
    o << '\n';
  }
}

/// The JSON of docs/body-files.md written here with 17 digits (not with
/// write_feature_curves: an independent writer, and no fsync per file).
inline void write_curves_json(const FeatureCurveFile& f, const std::filesystem::path& file) {
  std::ofstream o(file);
  char buf[200];
  o << "{";
  if (f.has_units) o << "\"units\": \"" << (f.scale == 1.0 ? "m" : f.scale == 0.01 ? "cm" : "mm") << "\",\n";
  if (f.has_up) o << "\"up\": \"" << (f.up_z ? "z" : "y") << "\",\n";
  o << "\"curves\": [\n";
  for (std::size_t c = 0; c < f.curves.size(); ++c) {
    const auto& k = f.curves[c];
    o << "  {\"name\": \"" << k.name << "\", \"closed\": " << (k.closed ? "true" : "false") << ", \"points\": [";
    for (std::size_t i = 0; i < k.points.size(); ++i) {
      std::snprintf(buf, sizeof buf, "%s\n    [%.17g, %.17g, %.17g]", i ? "," : "", k.points[i].x(), k.points[i].y(),
                    k.points[i].z());
      o << buf;
    }
    o << "]}" << (c + 1 < f.curves.size() ? ",\n" : "\n");
  }
  o << "]}\n";
}

/// The body's own curves (feature_curve_polyline), named ones only, mapped;
/// `units` / `up` are written when not empty. The curve named `first` (if
/// any) is written first.
inline void write_body_curves(const ReferenceBody& b, const std::filesystem::path& file,
                              const std::function<Vec3d(const Vec3d&)>& map, const std::string& units,
                              const std::string& up, const std::string& first = "waist") {
  FeatureCurveFile f;
  f.has_units = !units.empty();
  f.scale = units == "cm" ? 0.01 : units == "mm" ? 0.001 : 1.0;
  f.has_up = !up.empty();
  f.up_z = up == "z";
  std::vector<const FeatureCurve*> order;
  for (const auto& c : b.curves)
    if (c.name == first)
      order.insert(order.begin(), &c);
    else
      order.push_back(&c);
  for (const FeatureCurve* c : order) {
    auto pl = feature_curve_polyline(b, c->id);
    if (!pl) throw Error(pl.status());
    FeatureCurveSpec s;
    s.name = c->name;
    s.closed = c->closed;
    for (const Vec3d& p : *pl) s.points.push_back(map(p));
    f.curves.push_back(std::move(s));
  }
  write_curves_json(f, file);
}

}  // namespace atelier::testing
