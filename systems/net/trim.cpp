// Trimming (seed 004 section 6): the band, the cut (cut.cpp), the choice of
// the enclosed part.
#include <atelier/io/mesh_arrays.h>
#include <atelier/systems/net/boolean.h>
#include <atelier/systems/net/trim.h>
#include <atelier/systems/spatial/body_bvh.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numeric>
#include <sstream>

#include "boolean_detail.h"

namespace atelier {

using namespace net_detail;

namespace {

}  // namespace

std::vector<Vec3d> parse_curve(std::string_view text, std::string_view name) {
  std::vector<Vec3d> out;
  std::vector<std::string_view> tok;
  std::size_t line_no = 0;
  while (!text.empty()) {
    const std::size_t nl = text.find('\n');
    std::string_view line = text.substr(0, nl);
    text = nl == std::string_view::npos ? std::string_view() : text.substr(nl + 1);
    ++line_no;
    io_detail::split_blanks(line, tok);
    if (tok.empty() || tok[0][0] == '#') continue;
    if (tok.size() != 3)
      throw io_detail::parse_error_at_line(name, line_no,
                                           "expected 3 numbers (x y z), found " + std::to_string(tok.size()));
    Vec3d p;
    for (int k = 0; k < 3; ++k) {
      const auto v = io_detail::parse_double(tok[static_cast<std::size_t>(k)]);
      if (!v || !std::isfinite(*v))
        throw io_detail::parse_error_at_line(
            name, line_no, "not a finite number: '" + std::string(tok[static_cast<std::size_t>(k)]) + "'");
      p[k] = *v;
    }
    out.push_back(p);
  }
  return out;
}

std::vector<Vec3d> read_curve(const std::filesystem::path& path) {
  return parse_curve(io_detail::read_file_bytes(path), path.string());
}

Expected<TrimReport> trim_net(const PolygonSoupView& net, std::span<const Vec3d> curve_in, const TrimOptions& opt,
                              const ExecContext& ctx) {
  std::vector<Vec3d> curve(curve_in.begin(), curve_in.end());
  if (curve.size() >= 2 && curve.front() == curve.back()) curve.pop_back();
  if (curve.size() < 3) return fail(ErrorCode::kInvalidArgument, "trim: the curve needs at least 3 points");
  for (std::size_t k = 0; k < curve.size(); ++k)
    if (!is_finite(curve[k])) return fail(ErrorCode::kInvalidArgument, "trim: curve point ", k, " is not finite");
  if (!std::isfinite(opt.height) || opt.height < 0)
    return fail(ErrorCode::kInvalidArgument, "trim: the band height must be finite and >= 0");
  TriMesh A;
  if (Status s = build_tri_mesh(net, "net", A, ctx, true); !s) return s;
  TrimReport rep;
  rep.area_before = soup_area(net);

  // The band: each curve point pushed both ways along the net's normal there.
  double h = opt.height;
  if (h == 0) {
    double sum = 0;
    for (const auto& e : A.edge) sum += (A.p[e[0]] - A.p[e[1]]).norm();
    h = 2.0 * sum / static_cast<double>(std::max<std::size_t>(1, A.edge.size()));
  }
  BodyBvh bvh;
  std::vector<Triangle> tris(A.tri.begin(), A.tri.end());
  if (Status s = bvh.build(std::span<const Vec3d>(A.p), tris, {}, ctx); !s) return s;
  PolygonSoup& band = rep.band;
  const std::size_t n = curve.size();
  for (std::size_t k = 0; k < n; ++k) {
    const ClosestHit hit = bvh.closest_point(curve[k]);
    const auto& t = A.tri[hit.triangle];
    const Vec3d normal = (A.p[t[1]] - A.p[t[0]]).cross(A.p[t[2]] - A.p[t[0]]).normalized();
    band.positions.push_back(curve[k] - h * normal);
    band.positions.push_back(curve[k] + h * normal);
  }
  for (std::size_t k = 0; k < n; ++k) {
    const auto a = static_cast<std::uint32_t>(2 * k), b = static_cast<std::uint32_t>(2 * ((k + 1) % n));
    band.add_face(std::array<std::uint32_t, 4>{a, b, b + 1, a + 1});
  }
  TriMesh S;
  if (Status s = build_tri_mesh(band, "band", S, ctx, true); !s)
    return fail(ErrorCode::kInvalidArgument, "trim: the extruded curve is not a valid band (", s.message(),
                "): a curve crossing itself or with repeated points?");
  Bvh bvh_a, bvh_s;
  build_bvh(A, bvh_a, ctx);
  build_bvh(S, bvh_s, ctx);
  if (Status s = stage_done(ctx, "trim: band", 1, 3); !s) return s;
  Cut cut;
  if (Status s = cut_nets(A, bvh_a, S, bvh_s, ctx, cut); !s) return s;
  if (Status s = stage_done(ctx, "trim: cut", 2, 3); !s) return s;
  rep.cut_points = cut.new_keys.size();

  // Parts: components of pieces; does a part reach the net's boundary? its area?
  CutSide& side = cut.sides[0];
  const std::size_t count = side.piece.size();
  std::vector<std::uint32_t> roots;
  std::vector<std::uint8_t> border(count, 0);
  std::vector<double> area(count, 0.0);
  std::vector<std::uint32_t> tri_of(count);
  for (std::uint32_t t = 0; t < A.tri.size(); ++t)
    for (std::uint32_t p = side.piece_begin[t]; p < side.piece_begin[t + 1]; ++p) tri_of[p] = t;
  for (std::uint32_t p = 0; p < count; ++p) {
    const std::uint32_t r = side.component[p];
    if (r == p) roots.push_back(r);
    const auto& q = side.piece[p];
    const Vec3d a = cut.position(A, S, q[0]), b = cut.position(A, S, q[1]), c = cut.position(A, S, q[2]);
    area[r] += 0.5 * (b - a).cross(c - a).norm();
    for (std::uint32_t e : A.tri_edge[tri_of[p]])
      if (A.edge_tri[e][1] == kNil) border[r] = 1;
  }
  rep.parts = roots.size();
  if (roots.size() < 2)
    return fail(ErrorCode::kInvalidArgument,
                "trim: the curve does not cut the net into parts (does it lie on the net, "
                "and is it closed?)");
  bool any_border = false;
  for (std::uint32_t r : roots) any_border |= border[r] != 0;
  std::vector<std::uint8_t> enclosed(count, 0);
  if (any_border) {
    for (std::uint32_t r : roots) enclosed[r] = !border[r];
  } else {
    const std::uint32_t smallest = *std::min_element(
        roots.begin(), roots.end(), [&](std::uint32_t x, std::uint32_t y) { return area[x] < area[y]; });
    enclosed[smallest] = 1;
  }
  side.keep.assign(count, 0);
  for (std::uint32_t p = 0; p < count; ++p) side.keep[p] = enclosed[side.component[p]] == opt.keep_enclosed ? 1 : 0;
  std::vector<std::uint32_t> out_index(cut.canon.size(), kNil);
  std::vector<std::uint8_t> face_side;
  emit_side(cut, A, S, 0, net, false, rep.result, out_index, face_side);
  rep.area_after = soup_area(rep.result);
  if (Status s = stage_done(ctx, "trim: result", 3, 3); !s) return s;
  return rep;
}

}  // namespace atelier
