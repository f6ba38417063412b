// Seam-length constraints of a piece (FlattenOptions::seam_lengths,
// flatten_detail.h): the joints' members on the piece and their targets.
#include <atelier/engine/status_format.h>

#include <algorithm>
#include <cmath>

#include "flatten_detail.h"

namespace atelier::pattern_detail {

PieceSeams collect_seams(const Model& m, SurfaceIdx s, const PieceTopology& t) {
  PieceSeams ps;
  auto local = [&](NodeIdx v) {
    const auto it =
        std::lower_bound(t.node.begin(), t.node.end(), v, [](NodeIdx a, NodeIdx b) { return a.value < b.value; });
    return it != t.node.end() && *it == v ? static_cast<std::uint32_t>(it - t.node.begin()) : kNone;
  };
  // Sides on the piece's boundary (either direction).
  std::vector<std::uint64_t> boundary;
  for (const auto& lp : t.loops)
    for (std::size_t i = 0; i < lp.size(); ++i) {
      const std::uint32_t a = lp[i], b = lp[(i + 1) % lp.size()];
      boundary.push_back((std::uint64_t{std::min(a, b)} << 32) | std::max(a, b));
    }
  std::sort(boundary.begin(), boundary.end());
  auto on_boundary = [&](const std::array<std::uint32_t, 2>& x) {
    if (x[0] == kNone || x[1] == kNone) return false;
    const std::uint64_t key = (std::uint64_t{std::min(x[0], x[1])} << 32) | std::max(x[0], x[1]);
    return std::binary_search(boundary.begin(), boundary.end(), key);
  };
  for (std::uint32_t j = 0; j < m.joints.slots.capacity(); ++j) {
    if (!m.alive(JointIdx{j})) continue;
    const auto row = m.joints.members.row(j);
    std::vector<std::vector<std::array<NodeIdx, 2>>> members;
    std::vector<std::vector<std::array<std::uint32_t, 2>>> mine;
    for (const JointMember& mem : row) {
      std::vector<std::array<NodeIdx, 2>> sides;
      for (HalfedgeIdx h : m.mesh_edges.halfedges.row(mem.mesh_edge.value)) sides.push_back({m.tail(h), m.head(h)});
      if (sides.empty()) continue;
      if (m.mesh_edges.surface[mem.mesh_edge.value] == s) {
        std::vector<std::array<std::uint32_t, 2>> loc;
        for (const auto& sd : sides) loc.push_back({local(sd[0]), local(sd[1])});
        if (std::all_of(loc.begin(), loc.end(), on_boundary)) mine.push_back(std::move(loc));
      }
      members.push_back(std::move(sides));
    }
    if (mine.empty() || members.size() < 2) continue;
    const auto ji = static_cast<std::uint32_t>(ps.members.size());
    for (auto& loc : mine) {
      ps.lengths.sides.push_back(std::move(loc));
      ps.joint.push_back(ji);
    }
    ps.joint_id.push_back(JointIdx{j});
    ps.members.push_back(std::move(members));
  }
  ps.lengths.target.assign(ps.lengths.sides.size(), 0.0);
  ps.lengths.lambda.assign(ps.lengths.sides.size(), 0.0);
  return ps;
}

Status set_seam_targets(PieceSeams& ps, std::span<const Vec3d> positions, const std::string& label) {
  std::vector<double> mean(ps.members.size(), 0.0);
  for (std::size_t j = 0; j < ps.members.size(); ++j) {
    for (const auto& sides : ps.members[j])
      for (const auto& sd : sides) mean[j] += (positions[sd[1].value] - positions[sd[0].value]).norm();
    mean[j] /= static_cast<double>(ps.members[j].size());
    if (!std::isfinite(mean[j]) || !(mean[j] > 0))
      return status_of(ErrorCode::kDegenerate, "flatten: ", label, ": joint ", ps.joint_id[j].value,
                       " (a seam) has length ", mean[j]);
  }
  for (std::size_t i = 0; i < ps.lengths.size(); ++i) ps.lengths.target[i] = mean[ps.joint[i]];
  return {};
}

}  // namespace atelier::pattern_detail
