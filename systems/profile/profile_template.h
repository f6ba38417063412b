// Profile templates (seed 000 section 4.1, seed 001 section 4): a coarse,
// possibly non-manifold Model whose nodes are feature nodes encoded on a
// reference body, with profile curves on some of its edges. Regeneration
// (systems/regenerate.h) decodes it on another body and refines it.
//
// A ProfileTemplate holds
//   - model: surfaces (PMESH), faces, mesh edges and joints (MESHJOINT),
//     with node positions as on the reference body it was encoded on;
//   - encodings: one NodeEncoding per node slot (systems/feature_encoding.h).
//     A feature node used by several surfaces has one node per surface (the
//     model is non-manifold only through joints); the copies after the first
//     are encoded one-to-one on it with delta 0, so they decode bit-identical;
//   - profiles: curves on template halfedges, either Bezier curves encoded by
//     eq. (6) of seed 001, or attached point lists (seed 000 section 4.1.4)
//     mirrored in the model as ATTRIB_EDGENODEs.
//
// TemplateBuilder is the authoring API: name feature nodes, place them
// (encoded on feature points, vertices, edges, faces or other nodes), list
// faces per surface by node names, join surfaces along node chains, and add
// profiles (Bezier control points, point lists, or a 2D stroke and a camera).
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <atelier/engine/math.h>
#include <atelier/engine/status.h>
#include <atelier/storage/model.h>
#include <atelier/systems/profile/feature_encoding.h>
#include <atelier/systems/profile/profile_curve.h>
#include <atelier/systems/body/reference_body.h>

namespace atelier {

/// A profile on one template halfedge: the curve runs from tail(halfedge)
/// (u = 0) to head(halfedge) (u = 1).
struct TemplateProfile {
  HalfedgeIdx halfedge;
  ProfileCurve::Kind kind = ProfileCurve::Kind::kBezier;
  BezierProfileEncoding bezier;  // kBezier: seed 001 eq. (6)
  PointListProfile points;       // kPolyline: seed 000 attached points, shifted by eq. (3)
  ShiftMode shift = ShiftMode::kScaleRotate;
};

struct ProfileTemplate {
  std::string name;
  std::string reference;  // the reference body it is encoded on (informative)
  Model model;
  std::vector<std::string> node_names;  // per node slot; copies share their feature node's name
  NodeEncodings encodings;              // per node slot
  std::vector<TemplateProfile> profiles;
  /// Per node slot: signed distance to the reference body when encoded (the
  /// "encoded offset" the regenerated nodes are compared with).
  std::vector<double> encoded_clearance;
  double clearance = 0.004;  // distance kept from the body by regeneration (m)
  int levels = 3;            // default refinement levels

  /// Curves of the profiles on given node positions (indexed by node): eq. (7)
  /// for Bezier profiles, eq. (3) for point lists.
  [[nodiscard]] std::vector<ProfileCurve> decode_profiles(std::span<const Vec3d> node_positions) const;
};

/// Most refinement levels regeneration runs (systems/profile/regenerate.h):
/// each level multiplies the face count by about 4.
inline constexpr int kMaxTemplateLevels = 8;

/// Checks a template: the model validates, one encoding and one name per node
/// slot, profiles on live halfedges with consistent data, `levels` in
/// [0, kMaxTemplateLevels] and a finite, non-negative clearance.
[[nodiscard]] Status validate_template(const ProfileTemplate& t);

/// Checks what a template refers to on its reference body, so that a template
/// that cannot regenerate is refused when it is read rather than once per
/// body: every live node's feature point exists on `reference`, its body
/// vertex, halfedge or face is a live element of the reference model, and its
/// edge parameter is finite. Returns kInvalidArgument naming the template and
/// the node. (Implemented beside validate_template, systems/profile/template_check.cpp.)
[[nodiscard]] Status check_template_references(const ProfileTemplate& t, const ReferenceBody& reference);

class TemplateBuilder {
 public:
  /// Nodes are encoded on `body` as it is (its model's node positions). The
  /// builder keeps a reference: the body must outlive it.
  TemplateBuilder(const ReferenceBody& body, std::string name);
  ~TemplateBuilder();
  TemplateBuilder(const TemplateBuilder&) = delete;
  TemplateBuilder& operator=(const TemplateBuilder&) = delete;

  // ------------------------------------------------------------ feature nodes
  /// Seed 000 eq. (1): p = q_j + a n + b t1 + g t2 at the feature point `point`.
  Status node_on_feature_point(const std::string& name, std::string_view point, const Vec3d& abg);
  /// A node at position p encoded in `mode` on the nearest element: nearest
  /// feature point (kFeaturePoint / kFeatureOffset), body vertex (kVertex),
  /// edge (kEdge) or face (kFace).
  Status node_at(const std::string& name, const Vec3d& p, NodeEncodingMode mode);
  /// A node at p encoded on other feature nodes: one-to-one for one name,
  /// n-to-one (seed 001 eqs. (4)-(5)) for several.
  Status node_relative(const std::string& name, std::span<const std::string> others, const Vec3d& p);
  [[nodiscard]] Expected<Vec3d> position(std::string_view name) const;
  [[nodiscard]] bool has_node(std::string_view name) const;

  // ------------------------------------------------------------ topology
  /// A surface of polygon faces given by feature-node names, counter-clockwise
  /// seen from outside (away from the body).
  Status surface(const std::string& name, std::span<const std::vector<std::string>> faces);
  /// Joins surfaces along node chains of equal length (a MESHJOINT): each
  /// member is a surface name and the chain of feature-node names along one
  /// of its edge paths (boundary or inner edges). The chains must name the
  /// same feature nodes in the same order. Members are ordered clockwise
  /// about the chain direction (right-hand rule) automatically.
  struct JointChain {
    std::string surface;
    std::vector<std::string> nodes;
  };
  Status joint(std::span<const JointChain> members);

  /// Marks the edges of `surface` along a node chain as a seam (the
  /// kEdgeSeam bit of their flags, storage/edge_flags.h): regeneration
  /// carries the mark to every refined edge, and the pattern cuts there
  /// (systems/pattern/seams.h). Errors: kInvalidArgument (no such surface,
  /// node or edge; fewer than two nodes), with nothing marked.
  Status seam(std::string_view surface, std::span<const std::string> nodes);

  // ------------------------------------------------------------ profiles
  /// A Bezier profile from node `from` to node `to` of `surface`: the
  /// interior control points (the end points are the nodes).
  Status bezier_profile(std::string_view surface, std::string_view from, std::string_view to,
                        std::span<const Vec3d> interior_control_points);
  /// An attached point list (interior points, parameters in (0, 1)).
  Status point_list_profile(std::string_view surface, std::string_view from, std::string_view to,
                            std::span<const double> u, std::span<const Vec3d> points);
  /// Seed 000 4.1.4: edges of `surface` selected by a 2D stroke under a
  /// camera get the stroke's cut pieces as attached point lists. Returns the
  /// number of edges that received a profile.
  Expected<std::size_t> stroke_profile(std::string_view surface, const Camera& camera, std::span<const Vec2d> stroke,
                                       double tol_px);

  void set_clearance(double c) noexcept;
  void set_levels(int levels) noexcept;

  /// The template (validated). The builder is left empty.
  [[nodiscard]] Expected<ProfileTemplate> build();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace atelier
