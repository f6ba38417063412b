// validate_template and check_template_references: the checks of a template
// on its own and against its reference body (apart from the builder, so
// that a reader of template files needs nothing of the builder's machinery).
#include <algorithm>
#include <cmath>
#include <string>

#include <atelier/storage/validate.h>
#include <atelier/systems/profile/profile_template.h>

namespace atelier {

namespace {

Status invalid_reference(const std::string& what) { return {ErrorCode::kInvalidArgument, what}; }

}  // namespace

Status validate_template(const ProfileTemplate& t) {
  if (Status s = validate(t.model); !s) return Status(s.code(), "template '" + t.name + "': " + s.message());
  const std::size_t n = t.model.nodes.slots.capacity();
  if (t.encodings.nodes.size() != n)
    return Status(ErrorCode::kMismatch, "template '" + t.name + "': " + std::to_string(t.encodings.nodes.size()) +
                                            " node encodings for " + std::to_string(n) + " node slots");
  if (!t.encoded_clearance.empty() && t.encoded_clearance.size() != n)
    return Status(ErrorCode::kMismatch, "template '" + t.name + "': encoded clearances do not match the node slots");
  if (t.node_names.size() != n)
    return Status(ErrorCode::kMismatch, "template '" + t.name + "': " + std::to_string(t.node_names.size()) +
                                            " node names for " + std::to_string(n) + " node slots");
  if (t.levels < 0 || t.levels > kMaxTemplateLevels)
    return invalid_reference("template '" + t.name + "': levels " + std::to_string(t.levels) + " outside [0, " +
                   std::to_string(kMaxTemplateLevels) + "] (what regeneration supports)");
  if (!std::isfinite(t.clearance) || t.clearance < 0)
    return invalid_reference("template '" + t.name + "': the clearance must be a finite non-negative distance");
  for (std::size_t i = 0; i < t.profiles.size(); ++i) {
    const TemplateProfile& p = t.profiles[i];
    const std::string where = "template '" + t.name + "', profile " + std::to_string(i);
    if (!p.halfedge.valid() || edge_of(p.halfedge).value >= t.model.edges.slots.capacity() ||
        !t.model.alive(p.halfedge))
      return invalid_reference(where + ": dead or out-of-range halfedge");
    if (p.kind == ProfileCurve::Kind::kBezier) {
      if (p.bezier.offsets.size() < 2) return invalid_reference(where + ": a Bezier profile needs at least 2 control points");
    } else {
      if (p.points.u.size() != p.points.points.size()) return invalid_reference(where + ": point list u/points sizes differ");
      for (double u : p.points.u)
        if (!(u > 0.0 && u < 1.0)) return invalid_reference(where + ": point parameter outside (0, 1)");
      if (!std::is_sorted(p.points.u.begin(), p.points.u.end())) return invalid_reference(where + ": parameters not increasing");
    }
    for (std::size_t k = 0; k < i; ++k)
      if (edge_of(t.profiles[k].halfedge) == edge_of(p.halfedge))
        return invalid_reference(where + ": edge " + std::to_string(edge_of(p.halfedge).value) + " already has profile " +
                       std::to_string(k));
  }
  return {};
}

Status check_template_references(const ProfileTemplate& t, const ReferenceBody& reference) {
  const Model& body = reference.model;
  const std::size_t n = std::min(t.encodings.nodes.size(), t.model.nodes.slots.capacity());
  for (std::size_t i = 0; i < n; ++i) {
    if (!t.model.alive(NodeIdx{static_cast<std::uint32_t>(i)})) continue;
    const NodeEncoding& e = t.encodings.nodes[i];
    const std::string where = "template '" + t.name + "', node " + std::to_string(i) +
                              (i < t.node_names.size() && !t.node_names[i].empty() ? " ('" + t.node_names[i] + "')" : "");
    switch (e.mode) {
      case NodeEncodingMode::kFeaturePoint:
      case NodeEncodingMode::kFeatureOffset: {
        const bool found = std::any_of(reference.points.begin(), reference.points.end(),
                                       [&](const FeaturePoint& p) { return p.id == e.feature_point; });
        if (!found)
          return invalid_reference(where + ": feature point " + std::to_string(e.feature_point) +
                         " does not exist on the reference body (" + std::to_string(reference.points.size()) +
                         " feature points)");
        break;
      }
      case NodeEncodingMode::kVertex:
        if (e.element >= body.nodes.slots.capacity() || !body.alive(NodeIdx{e.element}))
          return invalid_reference(where + ": body vertex " + std::to_string(e.element) + " out of range or dead (the reference has " +
                         std::to_string(body.nodes.slots.capacity()) + " node slots)");
        break;
      case NodeEncodingMode::kEdge:
        if (e.element >= 2 * body.edges.slots.capacity() || !body.alive(HalfedgeIdx{e.element}))
          return invalid_reference(where + ": body halfedge " + std::to_string(e.element) + " out of range or dead (the reference has " +
                         std::to_string(2 * body.edges.slots.capacity()) + " halfedges)");
        if (!std::isfinite(e.t)) return invalid_reference(where + ": edge parameter t is not finite");
        break;
      case NodeEncodingMode::kFace:
        if (e.element >= body.faces.slots.capacity() || !body.alive(FaceIdx{e.element}))
          return invalid_reference(where + ": body face " + std::to_string(e.element) + " out of range or dead (the reference has " +
                         std::to_string(body.faces.slots.capacity()) + " face slots)");
        break;
      case NodeEncodingMode::kOneToOne:
      case NodeEncodingMode::kNToOne:
        break;  // template nodes: checked by the reader against the template
    }
    if (!e.coords.allFinite()) return invalid_reference(where + ": encoded coordinates are not finite");
  }
  return {};
}

}  // namespace atelier
