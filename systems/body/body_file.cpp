#include <atelier/io/feature_curves.h>
#include <atelier/io/obj.h>
#include <atelier/systems/body/body_file.h>
#include <atelier/systems/body/makehuman_body.h>
#include <atelier/systems/body/mannequin.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <sstream>
#include <string>
#include <unordered_map>

namespace atelier {

namespace fs = std::filesystem;

Expected<UpAxis> parse_up_axis(std::string_view text) {
  std::string t(text);
  std::transform(t.begin(), t.end(), t.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (t == "y") return UpAxis::kY;
  if (t == "z") return UpAxis::kZ;
  return Status(ErrorCode::kInvalidArgument, "up axis '" + std::string(text) + "': use y or z");
}

namespace {

/// n when scale is 1/n for a whole n (centimetres: 100, millimetres: 1000),
/// else 0. Dividing by n rounds once, so a coordinate that is n times a
/// double x exactly becomes x again, bit for bit; multiplying by the
/// rounded 0.01 would round twice.
double whole_inverse(double scale) noexcept {
  if (!(scale > 0) || scale >= 1) return 0;
  const double n = std::round(1 / scale);
  return std::abs(n * scale - 1) <= 1e-12 ? n : 0;
}

}  // namespace

// Z-up: file (x, y, z) -> engine (x, z, -y), a rotation (det +1); its
// inverse takes engine (X, Y, Z) to file (X, -Z, Y). Only sign changes and
// swaps: exact in floating point, the scale is the only rounding.
Vec3d BodyFrame::to_engine(const Vec3d& p) const noexcept {
  const Vec3d r = up == UpAxis::kZ ? Vec3d(p.x(), p.z(), -p.y()) : p;
  const double n = whole_inverse(scale);
  return n > 0 ? Vec3d(r / n) : Vec3d(scale * r);
}

Vec3d BodyFrame::to_file(const Vec3d& p) const noexcept {
  const double n = whole_inverse(scale);
  const Vec3d q = n > 0 ? Vec3d(n * p) : Vec3d(p / scale);
  return up == UpAxis::kZ ? Vec3d(q.x(), -q.z(), q.y()) : q;
}

void BodyFrame::to_engine(std::span<Vec3d> points) const noexcept {
  for (Vec3d& p : points) p = to_engine(p);
}

void BodyFrame::to_file(std::span<Vec3d> points) const noexcept {
  for (Vec3d& p : points) p = to_file(p);
}

Status BodyFrame::check() const {
  if (!std::isfinite(scale) || scale < 1e-3 || scale > 1e3) {
    std::ostringstream s;
    s << "scale " << scale << ": file units to metres must be a number from 0.001 to 1000 (0.01 for centimetres)";
    return {ErrorCode::kInvalidArgument, s.str()};
  }
  return {};
}

Status check_closed_oriented(const Model& m, std::string_view what) {
  // Directed edge uses: a closed, consistently oriented shell uses every
  // edge exactly once in each direction.
  struct Uses {
    std::uint32_t forward = 0, backward = 0;  // a->b with a < b, and b->a
  };
  std::unordered_map<std::uint64_t, Uses> uses;
  uses.reserve(2 * m.num_faces() + 16);
  std::vector<NodeIdx> f;
  double volume6 = 0;  // six times the signed volume (divergence theorem over fan triangles)
  for (std::uint32_t fi = 0; fi < m.faces.slots.capacity(); ++fi) {
    if (!m.alive(FaceIdx{fi})) continue;
    m.face_nodes(FaceIdx{fi}, f);
    for (std::size_t k = 0; k < f.size(); ++k) {
      const std::uint32_t a = f[k].value, b = f[(k + 1) % f.size()].value;
      const std::uint64_t key = (static_cast<std::uint64_t>(std::min(a, b)) << 32) | std::max(a, b);
      Uses& u = uses[key];
      (a < b ? u.forward : u.backward) += 1;
    }
    const Vec3d& p0 = m.position(f[0]);
    for (std::size_t k = 1; k + 1 < f.size(); ++k) volume6 += p0.dot(m.position(f[k]).cross(m.position(f[k + 1])));
  }
  if (uses.empty()) return {ErrorCode::kDegenerate, std::string(what) + ": the body has no faces"};
  std::size_t open = 0, flipped = 0;
  std::uint64_t first_open = ~0ull, first_flipped = ~0ull;
  for (const auto& [key, u] : uses) {
    if (u.forward + u.backward != 2) {
      ++open;
      first_open = std::min(first_open, key);
    } else if (u.forward != 1) {
      ++flipped;
      first_flipped = std::min(first_flipped, key);
    }
  }
  auto edge_text = [](std::uint64_t key) {
    return "vertices " + std::to_string((key >> 32) + 1) + " and " + std::to_string((key & 0xffffffffu) + 1);
  };
  if (open > 0)
    return {ErrorCode::kDegenerate,
            std::string(what) + ": the body is not closed: " + std::to_string(open) +
                " edges are used by one face or by more than two (the first: the edge between " +
                edge_text(first_open) + "); a reference body must be a closed surface (fill its holes)"};
  if (flipped > 0)
    return {ErrorCode::kDegenerate, std::string(what) +
                                        ": the body is not consistently oriented: " + std::to_string(flipped) +
                                        " edges are used twice in the same direction (the first: the edge between " +
                                        edge_text(first_flipped) + "); its faces' corners must all turn the same way"};
  if (!(volume6 > 0))
    return {ErrorCode::kDegenerate, std::string(what) +
                                        ": the body's faces point inward (its signed volume is not positive); "
                                        "reverse the order of every face's corners"};
  return {};
}

namespace {

/// Same node slots and the same faces, corner for corner.
bool same_topology(const Model& a, const Model& b) {
  if (a.nodes.slots.capacity() != b.nodes.slots.capacity() || a.num_faces() != b.num_faces() ||
      a.faces.slots.capacity() != b.faces.slots.capacity())
    return false;
  std::vector<NodeIdx> fa, fb;
  for (std::uint32_t f = 0; f < a.faces.slots.capacity(); ++f) {
    if (a.alive(FaceIdx{f}) != b.alive(FaceIdx{f})) return false;
    if (!a.alive(FaceIdx{f})) continue;
    a.face_nodes(FaceIdx{f}, fa);
    b.face_nodes(FaceIdx{f}, fb);
    if (fa != fb) return false;
  }
  return true;
}

}  // namespace

Expected<ReferenceBody> read_reference_body(const fs::path& file, const BodyFileOptions& options,
                                            const ExecContext& ctx) {
  const std::string name = file.string();
  if (Status s = options.frame.check(); !s) return Status(s.code(), name + ": " + s.message());
  std::error_code ec;
  if (!fs::is_regular_file(file, ec)) return Status(ErrorCode::kIo, name + ": no such file");
  ReferenceBody rb;
  try {
    rb.model = read_obj(file);
  } catch (const Error& e) {
    return e.status();  // names the file and line
  }
  if (rb.model.num_surfaces() != 1)
    return Status(ErrorCode::kInvalidArgument,
                  name + ": the body has " + std::to_string(rb.model.num_surfaces()) +
                      " surfaces (OBJ groups or separate pieces); a reference body is one closed skin");
  for (std::uint32_t s = 0; s < rb.model.surfaces.slots.capacity(); ++s)
    if (rb.model.alive(SurfaceIdx{s})) rb.skin = SurfaceIdx{s};
  for (Vec3d& p : rb.model.nodes.position) p = options.frame.to_engine(p);
  for (std::uint32_t v = 0; v < rb.model.nodes.slots.capacity(); ++v)
    if (rb.model.alive(NodeIdx{v}) && !rb.model.position(NodeIdx{v}).allFinite())
      return Status(ErrorCode::kDegenerate, name + ": vertex " + std::to_string(v + 1) + " is not finite");
  // After the transform: a rotation and a positive scale keep orientation,
  // and the sign of the volume is that of the engine's body.
  if (Status s = check_closed_oriented(rb.model, name); !s) return s;

  if (!options.features.empty()) {
    // The user's own curves (see the header); a known topology's are not adopted.
    auto file = read_feature_curves(options.features);
    if (!file) return file.status();
    BodyFrame curve_frame = options.frame;
    if (file->has_units) curve_frame.scale = file->scale;
    if (file->has_up) curve_frame.up = file->up_z ? UpAxis::kZ : UpAxis::kY;
    std::vector<std::vector<Vec3d>> points(file->curves.size());
    std::vector<FeaturePolyline> lines;
    for (std::size_t c = 0; c < file->curves.size(); ++c) {
      const FeatureCurveSpec& spec = file->curves[c];
      points[c] = spec.points;
      curve_frame.to_engine(points[c]);
      lines.push_back({spec.name, spec.closed, points[c], spec.point_lines});
    }
    FeatureSnapOptions snap = options.snap;
    snap.source = file->source;
    auto added = add_snapped_feature_curves(rb, lines, snap);
    if (!added) return added.status();
    return rb;
  }
  // Features of a known topology (see the header).
  const std::vector<Vec3d> positions = rb.model.nodes.position;
  auto adopt = [&](const ReferenceBody& known) -> Expected<bool> {
    if (!same_topology(known.model, rb.model)) return false;
    auto moved = with_positions(known, positions);
    if (!moved) return Status(moved.status().code(), name + ": " + moved.status().message());
    rb = std::move(*moved);
    return true;
  };
  if (auto topo = make_mannequin_topology(); topo) {
    if (auto ref = make_mannequin(MannequinParams{}, *topo); ref) {
      auto a = adopt(*ref);
      if (!a) return a.status();
      if (*a) return rb;
    }
  }
  if (!options.makehuman_data.empty() && positions.size() > 10000 &&
      fs::exists(options.makehuman_data / "makehuman", ec)) {
    try {
      const auto lib = makehuman::HumanLibrary::load(options.makehuman_data / "makehuman", ctx);
      auto a = adopt(makehuman::make_reference_body(lib));
      if (!a) return a.status();
    } catch (const Error&) {
      // MakeHuman's data unreadable: the body is still a body, without features.
    }
  }
  return rb;
}

}  // namespace atelier
