// Prepared operands of the net Booleans (PreparedNet): step 1 of
// boolean.h (the split into triangles and the checks), the box hierarchy,
// the volume and area, done once per net (geometry-central's reusable
// solver beside the one-call function; OpenVDB's and Embree's explicit
// commit of derived data). Also the nets' measures (soup_volume,
// soup_area), which prepare and the Booleans share.
#include <atelier/engine/parallel.h>
#include <atelier/systems/net/boolean.h>

#include "boolean_detail.h"

namespace atelier {

namespace net_detail {

namespace {

double prep_tri_volume(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  return a.dot(b.cross(c)) / 6.0;
}

double prep_mesh_volume(const TriMesh& m) {
  double v = 0;
  for (const auto& t : m.tri) v += prep_tri_volume(m.p[t[0]], m.p[t[1]], m.p[t[2]]);
  return v;
}

/// Below ctx.sequential_threshold polygons the start-up of parallel tasks
/// costs more than the work (as in net_boolean).
ExecContext sized(const ExecContext& ctx, std::size_t faces) {
  ExecContext c = ctx;
  if (faces < c.sequential_threshold) c.threads = 1;
  return c;
}

}  // namespace

void prepare_data(PreparedData& d, std::string name, bool check_self_intersection, const ExecContext& ctx,
                  PrepareSteps& steps) {
  steps.built = build_tri_mesh(d.soup, std::move(name), d.mesh, ctx);
  if (!steps.built) return;
  build_bvh(d.mesh, d.bvh, ctx);
  d.volume = soup_volume(d.soup);
  d.area = soup_area(d.soup);
  if (!(prep_mesh_volume(d.mesh) > 0)) {
    steps.volume = fail(ErrorCode::kTopology, "net ", d.mesh.name,
                        " encloses no volume or is oriented inwards (signed volume <= 0): reverse its faces");
    return;
  }
  d.self_checked = check_self_intersection;
  if (!check_self_intersection) return;
  const auto bad = first_self_crossing(d.mesh, d.bvh, ctx);
  if (bad[0] != kNil)
    steps.crossing = fail(ErrorCode::kTopology, "net ", d.mesh.name, " intersects itself: faces ",
                          d.mesh.face_of[bad[0]], " and ", d.mesh.face_of[bad[1]], " cross");
}

const PreparedData* PreparedAccess::get(const PreparedNet& p) noexcept {
  return p.data_.get();
}

PreparedNet PreparedAccess::make(std::shared_ptr<const PreparedData> d) noexcept {
  return PreparedNet(std::move(d));
}

namespace {

/// d's soup is d.owned; the checks of `opt`, errors in prepare_data's order.
Status prepare_owned(PreparedData& d, std::string name, bool check, const ExecContext& ctx) {
  d.soup = d.owned;
  PrepareSteps st;
  prepare_data(d, std::move(name), check, sized(ctx, d.owned.face_count()), st);
  for (const Status* s : {&st.built, &st.volume, &st.crossing})
    if (!*s) return *s;
  return {};
}

Expected<PreparedNet> finish_prepare(std::shared_ptr<PreparedData> d, const PrepareOptions& opt,
                                     const ExecContext& ctx) {
  if (Status s = prepare_owned(*d, opt.name, opt.check_self_intersection, ctx); !s) return s;
  if (Status s = stage_done(ctx, "prepare: net", 1, 1); !s) return s;
  return PreparedAccess::make(std::move(d));
}

}  // namespace

PreparedNet prepare_result(const PolygonSoup& result, std::string name, const ExecContext& ctx, Status& why) {
  auto d = std::make_shared<PreparedData>();
  d->owned.positions = result.positions;
  d->owned.face_offsets = result.face_offsets;
  d->owned.face_nodes = result.face_nodes;
  // The self-intersection test runs on results too: the exact cut is not
  // self-intersecting, but its rounding to doubles can fold a near-flat
  // piece over its neighbour (a 12-gon prism and its copy shifted by 1/8
  // along the axis: the union's cap leaves a sliver crossing a side
  // triangle). A prepared net marked self_checked that crosses itself sends
  // cut_nets into a constrained triangulation of crossing segments (a
  // segfault in CGAL); the soup path refuses the same net with this test.
  why = prepare_owned(*d, std::move(name), true, ctx);
  if (!why) return {};
  return PreparedAccess::make(std::move(d));
}

}  // namespace net_detail

using namespace net_detail;

Expected<PreparedNet> PreparedNet::prepare(const PolygonSoupView& soup, const PrepareOptions& opt,
                                           const ExecContext& ctx) {
  auto d = std::make_shared<PreparedData>();
  d->owned.positions.assign(soup.positions.begin(), soup.positions.end());
  if (!soup.face_offsets.empty()) d->owned.face_offsets.assign(soup.face_offsets.begin(), soup.face_offsets.end());
  d->owned.face_nodes.assign(soup.face_nodes.begin(), soup.face_nodes.end());
  return finish_prepare(std::move(d), opt, ctx);
}

Expected<PreparedNet> PreparedNet::prepare(PolygonSoup&& soup, const PrepareOptions& opt, const ExecContext& ctx) {
  auto d = std::make_shared<PreparedData>();
  d->owned = std::move(soup);
  d->owned.corner_uv.clear();
  return finish_prepare(std::move(d), opt, ctx);
}

const PolygonSoup& PreparedNet::soup() const noexcept {
  static const PolygonSoup kEmpty;
  return data_ ? data_->owned : kEmpty;
}
const std::string& PreparedNet::name() const noexcept {
  static const std::string kNone;
  return data_ ? data_->mesh.name : kNone;
}
double PreparedNet::volume() const noexcept {
  return data_ ? data_->volume : 0.0;
}
double PreparedNet::area() const noexcept {
  return data_ ? data_->area : 0.0;
}
std::size_t PreparedNet::triangle_count() const noexcept {
  return data_ ? data_->mesh.tri.size() : 0;
}
bool PreparedNet::self_checked() const noexcept {
  return data_ && data_->self_checked;
}

double soup_volume(const PolygonSoupView& s) {
  double v = 0;
  for (std::size_t f = 0; f < s.face_count(); ++f) {
    const std::uint32_t b = s.face_offsets[f], e = s.face_offsets[f + 1];
    if (e - b == 3) {
      v += prep_tri_volume(s.positions[s.face_nodes[b]], s.positions[s.face_nodes[b + 1]],
                           s.positions[s.face_nodes[b + 2]]);
      continue;
    }
    Vec3d c = Vec3d::Zero();
    for (std::uint32_t i = b; i < e; ++i) c += s.positions[s.face_nodes[i]];
    c /= static_cast<double>(e - b);
    for (std::uint32_t i = b; i < e; ++i)
      v += prep_tri_volume(c, s.positions[s.face_nodes[i]], s.positions[s.face_nodes[i + 1 < e ? i + 1 : b]]);
  }
  return v;
}

double soup_area(const PolygonSoupView& s) {
  double a = 0;
  for (std::size_t f = 0; f < s.face_count(); ++f) {
    const std::uint32_t b = s.face_offsets[f], e = s.face_offsets[f + 1];
    if (e - b == 3) {
      // The fan below about the first corner: its two other terms are
      // exact zeros, so this one term is the same sum, bit for bit.
      const Vec3d& p = s.positions[s.face_nodes[b]];
      a += 0.5 * (s.positions[s.face_nodes[b + 1]] - p).cross(s.positions[s.face_nodes[b + 2]] - p).norm();
      continue;
    }
    Vec3d c = Vec3d::Zero();
    for (std::uint32_t i = b; i < e; ++i) c += s.positions[s.face_nodes[i]];
    c /= static_cast<double>(e - b);
    for (std::uint32_t i = b; i < e; ++i) {
      const Vec3d& p = s.positions[s.face_nodes[i]];
      const Vec3d& q = s.positions[s.face_nodes[i + 1 < e ? i + 1 : b]];
      a += 0.5 * (p - c).cross(q - c).norm();
    }
  }
  return a;
}

}  // namespace atelier
