// Reading a profile template from its JSON file (systems/profile/template_json.h):
// from_json builds the template table after table, in the order the
// primitives need them (surfaces, nodes, edges, faces, mesh edges, loops,
// joints, attribute nodes and edges, profiles). Every list is located and
// sized first, so a bad index never reaches a table, and every error names
// the file and the JSON pointer of the value.
#include <atelier/systems/profile/template_json.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include <atelier/io/mesh_arrays.h>
#include <atelier/storage/validate.h>

#include "template_json_detail.h"

namespace atelier {

namespace {

using Json = nlohmann::ordered_json;
using template_json_detail::kMaxLevels;

constexpr NodeEncodingMode kModes[] = {NodeEncodingMode::kFeaturePoint, NodeEncodingMode::kFeatureOffset,
                                       NodeEncodingMode::kVertex,       NodeEncodingMode::kEdge,
                                       NodeEncodingMode::kFace,         NodeEncodingMode::kOneToOne,
                                       NodeEncodingMode::kNToOne};

/// A JSON value with its location (JSON pointer) for error messages.
struct At {
  const Json& v;
  std::string ptr;
};

class Reader {
 public:
  explicit Reader(std::string_view file) : file_(file) {}

  [[noreturn]] void fail(const std::string& ptr, const std::string& what) const {
    throw Error(Status(ErrorCode::kParse, file_ + ": at " + (ptr.empty() ? std::string("/") : ptr) + ": " + what));
  }

  static const char* type_of(const Json& v) noexcept {
    if (v.is_number_integer()) return "an integer";
    if (v.is_number()) return "a number";
    if (v.is_string()) return "a string";
    if (v.is_boolean()) return "a boolean";
    if (v.is_null()) return "null";
    if (v.is_array()) return "an array";
    return "an object";
  }
  [[noreturn]] void wrong(const At& a, const char* expected) const {
    fail(a.ptr, std::string("wrong type: expected ") + expected + ", found " + type_of(a.v));
  }

  At field(const At& obj, const char* key) const {
    if (!obj.v.is_object()) wrong(obj, "an object");
    const auto it = obj.v.find(key);
    if (it == obj.v.end()) fail(obj.ptr, std::string("missing field '") + key + "'");
    return {*it, obj.ptr + "/" + key};
  }
  [[nodiscard]] static bool has(const At& obj, const char* key) { return obj.v.is_object() && obj.v.contains(key); }
  At item(const At& arr, std::size_t i) const { return {arr.v[i], arr.ptr + "/" + std::to_string(i)}; }

  const Json& array(const At& a, std::size_t min_size = 0, const char* what = "elements") const {
    if (!a.v.is_array()) wrong(a, "an array");
    if (a.v.size() < min_size)
      fail(a.ptr, "needs at least " + std::to_string(min_size) + " " + what + ", has " + std::to_string(a.v.size()));
    return a.v;
  }
  double number(const At& a) const {
    if (!a.v.is_number()) wrong(a, "a number");
    const double x = a.v.get<double>();
    if (!std::isfinite(x)) fail(a.ptr, "non-finite number");
    // Every number of a template is a length in metres, a parameter or a
    // weight: beyond kTemplateMaxMagnitude it is a typo or an attack (1e300
    // becomes inf as a float inside the BVH queries and a body takes minutes).
    if (std::abs(x) > kTemplateMaxMagnitude)
      fail(a.ptr, "number " + a.v.dump() + " out of range (|x| <= " + Json(kTemplateMaxMagnitude).dump() +
                      "; lengths are in metres)");
    return x;
  }
  std::int64_t integer(const At& a, std::int64_t lo, std::int64_t hi, const char* what) const {
    if (!a.v.is_number_integer()) wrong(a, "an integer");
    std::int64_t x = 0;
    if (a.v.is_number_unsigned()) {
      const auto u = a.v.get<std::uint64_t>();
      if (u > static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max()))
        fail(a.ptr, std::string(what) + " " + std::to_string(u) + " out of range");
      x = static_cast<std::int64_t>(u);
    } else {
      x = a.v.get<std::int64_t>();
    }
    if (x < lo || x > hi)
      fail(a.ptr, std::string(what) + " " + std::to_string(x) + " out of range [" + std::to_string(lo) + ", " +
                      std::to_string(hi) + "]");
    return x;
  }
  /// An index into a table of `count` rows.
  std::uint32_t index(const At& a, std::size_t count, const char* what) const {
    if (!a.v.is_number_integer()) wrong(a, "an integer");
    if (a.v.is_number_integer() && !a.v.is_number_unsigned() && a.v.get<std::int64_t>() < 0)
      fail(a.ptr, std::string(what) + " index " + std::to_string(a.v.get<std::int64_t>()) + " is negative");
    const auto u = a.v.get<std::uint64_t>();
    if (u >= count)
      fail(a.ptr, std::string(what) + " index " + std::to_string(u) + " out of range (" + std::to_string(count) + " " +
                      what + "s)");
    return static_cast<std::uint32_t>(u);
  }
  std::string string(const At& a) const {
    if (!a.v.is_string()) wrong(a, "a string");
    return a.v.get<std::string>();
  }
  bool boolean(const At& a) const {
    if (!a.v.is_boolean()) wrong(a, "a boolean");
    return a.v.get<bool>();
  }
  Vec3d vec3(const At& a) const {
    const Json& arr = array(a);
    if (arr.size() != 3) fail(a.ptr, "expected 3 numbers [x, y, z], found " + std::to_string(arr.size()));
    return {number(item(a, 0)), number(item(a, 1)), number(item(a, 2))};
  }
  Vec2d vec2(const At& a) const {
    const Json& arr = array(a);
    if (arr.size() != 2) fail(a.ptr, "expected 2 numbers [u, v], found " + std::to_string(arr.size()));
    return {number(item(a, 0)), number(item(a, 1))};
  }
  /// The halfedge tail -> head given as a node pair; it must exist.
  HalfedgeIdx halfedge(const At& a, const Model& m) const {
    const Json& arr = array(a);
    if (arr.size() != 2)
      fail(a.ptr, "expected a node pair [tail, head], found " + std::to_string(arr.size()) + " values");
    const std::size_t nn = m.nodes.slots.capacity();
    const NodeIdx t{index(item(a, 0), nn, "node")}, h{index(item(a, 1), nn, "node")};
    const HalfedgeIdx he = m.find_halfedge(t, h);
    if (!he.valid())
      fail(a.ptr, "no edge joins node " + std::to_string(t.value) + " to node " + std::to_string(h.value));
    return he;
  }
  std::uint8_t byte(const At& a, const char* what) const { return static_cast<std::uint8_t>(integer(a, 0, 255, what)); }

 private:
  std::string file_;
};

// ------------------------------------------------------------------ stages

/// The format and version fields: refused before anything else is read.
void check_format(const Reader& R, const At& doc) {
  const At f = R.field(doc, "format");
  if (!f.v.is_string() || f.v.get<std::string>() != kTemplateFormat)
    R.fail(f.ptr,
           "not an atelier template (format is " + f.v.dump() + ", expected \"" + std::string(kTemplateFormat) + "\")");
  const At v = R.field(doc, "version");
  if (!v.v.is_number_integer() || v.v.get<std::int64_t>() != kTemplateFormatVersion)
    R.fail(v.ptr, "unsupported version " + v.v.dump() + " (this reader knows version " +
                      std::to_string(kTemplateFormatVersion) + ")");
}

/// The scalar fields: name, reference, clearance, levels, complex holes.
void read_header(const Reader& R, const At& doc, ProfileTemplate& t) {
  t.name = R.string(R.field(doc, "name"));
  t.reference = R.string(R.field(doc, "reference"));
  t.clearance = R.number(R.field(doc, "clearance"));
  t.levels = static_cast<int>(R.integer(R.field(doc, "levels"), 0, kMaxLevels, "levels"));
  t.model.complex_holes =
      R.integer(R.field(doc, "complex_holes"), 0, std::numeric_limits<std::int32_t>::max(), "complex hole count");
}

/// The document's lists and their sizes, all located before the primitives
/// run.
struct Lists {
  At surfaces, nodes, edges, mesh_edges, loops, joints, attrib_nodes, attrib_edges, profiles;
  std::size_t ns = 0, nn = 0, ne = 0, nme = 0, nl = 0, nj = 0, nan = 0, nae = 0;
};

Lists locate_lists(const Reader& R, const At& doc) {
  Lists L{R.field(doc, "surfaces"),        R.field(doc, "nodes"),           R.field(doc, "edges"),
          R.field(doc, "mesh_edges"),      R.field(doc, "mesh_loops"),      R.field(doc, "joints"),
          R.field(doc, "attribute_nodes"), R.field(doc, "attribute_edges"), R.field(doc, "profiles")};
  L.ns = R.array(L.surfaces).size();
  L.nn = R.array(L.nodes).size();
  L.ne = R.array(L.edges).size();
  L.nme = R.array(L.mesh_edges).size();
  L.nl = R.array(L.loops).size();
  L.nj = R.array(L.joints).size();
  L.nan = R.array(L.attrib_nodes).size();
  L.nae = R.array(L.attrib_edges).size();
  (void)R.array(L.profiles);
  constexpr std::size_t kMaxRows = std::size_t{1} << 30;  // halfedge indices must fit 32 bits
  if (L.nn > kMaxRows || L.ne > kMaxRows) R.fail("", "too many nodes or edges");
  return L;
}

/// Surfaces: names and flags (first: nodes refer to them). Writes the
/// surface table.
void read_surfaces(const Reader& R, const Lists& L, Model& m) {
  for (std::size_t s = 0; s < L.ns; ++s) {
    const At js = R.item(L.surfaces, s);
    const Surface h = m.add_surface(R.string(R.field(js, "name")));
    if (Reader::has(js, "flags")) m.surfaces.flags[h.idx.value] = R.byte(R.field(js, "flags"), "surface flags");
  }
}

/// A node's encoding (systems/profile/feature_encoding.h); an n-to-one
/// node's references are appended to the pool `enc.refs`.
NodeEncoding read_encoding(const Reader& R, const At& je, std::size_t v, std::size_t nn, NodeEncodings& enc) {
  NodeEncoding e;
  const At jm = R.field(je, "mode");
  const std::string mode = R.string(jm);
  const auto* it =
      std::find_if(std::begin(kModes), std::end(kModes), [&](NodeEncodingMode x) { return mode == to_string(x); });
  if (it == std::end(kModes))
    R.fail(jm.ptr, "unknown encoding mode '" + mode +
                       "' (feature_point, feature_offset, vertex, edge, face, one_to_one or n_to_one)");
  e.mode = *it;
  e.feature_point =
      static_cast<std::int32_t>(R.integer(R.field(je, "feature_point"), std::numeric_limits<std::int32_t>::min(),
                                          std::numeric_limits<std::int32_t>::max(), "feature point"));
  const At jel = R.field(je, "element");
  if (e.mode == NodeEncodingMode::kOneToOne) {
    e.element = R.index(jel, nn, "node");
    if (e.element == v) R.fail(jel.ptr, "node " + std::to_string(v) + " is encoded on itself");
  } else {
    e.element = static_cast<std::uint32_t>(R.integer(jel, 0, std::numeric_limits<std::uint32_t>::max(), "element"));
  }
  e.t = R.number(R.field(je, "t"));
  e.coords = R.vec3(R.field(je, "coords"));
  const bool has_refs = Reader::has(je, "refs");
  if (e.mode == NodeEncodingMode::kNToOne) {
    const At jr = R.field(je, "refs");
    const Json& refs = R.array(jr, 1, "references");
    e.first_ref = static_cast<std::uint32_t>(enc.refs.size());
    e.ref_count = static_cast<std::uint32_t>(refs.size());
    for (std::size_t k = 0; k < refs.size(); ++k) {
      const At x = R.item(jr, k);
      NodeRef r;
      r.node = R.index(R.field(x, "node"), nn, "node");
      if (r.node == v) R.fail(x.ptr + "/node", "node " + std::to_string(v) + " refers to itself");
      r.delta = R.vec3(R.field(x, "delta"));
      r.weight = R.number(R.field(x, "weight"));
      enc.refs.push_back(r);
    }
  } else if (has_refs) {
    R.fail(je.ptr + "/refs", std::string("references are only allowed for mode n_to_one, not ") + to_string(e.mode));
  }
  return e;
}

/// Nodes: names, surfaces, positions and the optional columns, encodings
/// and encoded clearances. Writes the node table, node_names, encodings,
/// encoded_clearance.
void read_nodes(const Reader& R, const Lists& L, ProfileTemplate& t) {
  Model& m = t.model;
  t.node_names.resize(L.nn);
  t.encodings.nodes.resize(L.nn);
  bool any_clearance = false;
  for (std::size_t v = 0; v < L.nn; ++v) {
    const At jn = R.item(L.nodes, v);
    t.node_names[v] = R.string(R.field(jn, "name"));
    const SurfaceIdx s{R.index(R.field(jn, "surface"), L.ns, "surface")};
    const NodeIdx id = m.new_node(s, R.vec3(R.field(jn, "position")));
    if (Reader::has(jn, "position_backup")) m.nodes.position_backup[id.value] = R.vec3(R.field(jn, "position_backup"));
    if (Reader::has(jn, "uv")) m.nodes.uv[id.value] = R.vec2(R.field(jn, "uv"));
    const bool c = Reader::has(jn, "encoded_clearance");
    if (v == 0) any_clearance = c;
    if (c != any_clearance)
      R.fail(jn.ptr, "encoded_clearance must be given for every node or for none (node 0 " +
                         std::string(any_clearance ? "has" : "has none") + ")");
    if (c) {
      if (t.encoded_clearance.empty()) t.encoded_clearance.resize(L.nn);
      t.encoded_clearance[v] = R.number(R.field(jn, "encoded_clearance"));
    }
    t.encodings.nodes[v] = read_encoding(R, R.field(jn, "encoding"), v, L.nn, t.encodings);
  }
}

/// Edges: halfedge 2e runs from the first node to the second; the optional
/// edge flags. Writes the edge table.
void read_edges(const Reader& R, const At& doc, const Lists& L, Model& m) {
  for (std::size_t e = 0; e < L.ne; ++e) {
    const At je = R.item(L.edges, e);
    const Json& arr = R.array(je);
    if (arr.size() != 2)
      R.fail(je.ptr, "an edge is a node pair [tail, head], found " + std::to_string(arr.size()) + " values");
    const NodeIdx a{R.index(R.item(je, 0), L.nn, "node")}, b{R.index(R.item(je, 1), L.nn, "node")};
    if (a == b) R.fail(je.ptr, "edge joins node " + std::to_string(a.value) + " to itself");
    if (m.nodes.surface[a.value] != m.nodes.surface[b.value])
      R.fail(je.ptr, "edge joins nodes of different surfaces (" + std::to_string(m.nodes.surface[a.value].value) +
                         " and " + std::to_string(m.nodes.surface[b.value].value) + ")");
    if (const HalfedgeIdx h = m.find_halfedge(a, b); h.valid())
      R.fail(je.ptr, "duplicate edge: nodes " + std::to_string(a.value) + " and " + std::to_string(b.value) +
                         " are already joined by edge " + std::to_string(edge_of(h).value));
    (void)m.new_edge(a, b);
  }
  if (Reader::has(doc, "edge_flags")) {
    const At jf = R.field(doc, "edge_flags");
    if (R.array(jf).size() != L.ne) R.fail(jf.ptr, "needs one value per edge (" + std::to_string(L.ne) + ")");
    for (std::size_t e = 0; e < L.ne; ++e) m.edges.flags[e] = R.byte(R.item(jf, e), "edge flags");
  }
}

/// Faces, surface after surface, as node cycles over existing edges; the
/// optional face flags. Writes the face table and the halfedges' faces.
void read_faces(const Reader& R, const Lists& L, Model& m) {
  std::vector<HalfedgeIdx> cycle;
  for (std::size_t s = 0; s < L.ns; ++s) {
    const At js = R.item(L.surfaces, s);
    const At jfs = R.field(js, "faces");
    const Json& faces = R.array(jfs);
    std::vector<FaceIdx> made;
    for (std::size_t f = 0; f < faces.size(); ++f) {
      const At jf = R.item(jfs, f);
      const Json& list = R.array(jf, 3, "nodes");
      cycle.clear();
      std::vector<NodeIdx> ids(list.size());
      for (std::size_t k = 0; k < list.size(); ++k) {
        const At x = R.item(jf, k);
        ids[k] = NodeIdx{R.index(x, L.nn, "node")};
        if (m.nodes.surface[ids[k].value].value != s)
          R.fail(x.ptr, "node " + std::to_string(ids[k].value) + " belongs to surface " +
                            std::to_string(m.nodes.surface[ids[k].value].value) + ", not to this one");
      }
      for (std::size_t k = 0; k < ids.size(); ++k) {
        const NodeIdx a = ids[k], b = ids[(k + 1) % ids.size()];
        const HalfedgeIdx h = m.find_halfedge(a, b);
        const std::string side = std::to_string(a.value) + " -> " + std::to_string(b.value);
        if (!h.valid()) R.fail(jf.ptr, "no edge " + side + " in /edges");
        if (m.face(h).valid())
          R.fail(jf.ptr, "non-manifold face list: halfedge " + side + " already bounds face " +
                             std::to_string(m.face(h).value) +
                             " (a third face on an edge, or faces oriented inconsistently)");
        if (std::find(cycle.begin(), cycle.end(), h) != cycle.end())
          R.fail(jf.ptr, "non-manifold face list: the face runs along halfedge " + side + " twice");
        cycle.push_back(h);
      }
      made.push_back(m.new_face(SurfaceIdx{static_cast<std::uint32_t>(s)}, cycle));
    }
    if (Reader::has(js, "face_flags")) {
      const At jff = R.field(js, "face_flags");
      if (R.array(jff).size() != made.size())
        R.fail(jff.ptr, "needs one value per face (" + std::to_string(made.size()) + ")");
      for (std::size_t f = 0; f < made.size(); ++f) m.faces.flags[made[f].value] = R.byte(R.item(jff, f), "face flags");
    }
  }
}

/// The nodes' in_face column (once the faces exist).
void read_nodes_in_faces(const Reader& R, const Lists& L, Model& m) {
  for (std::size_t v = 0; v < L.nn; ++v) {
    const At jn = R.item(L.nodes, v);
    if (Reader::has(jn, "in_face"))
      m.nodes.in_face[v] = FaceIdx{R.index(R.field(jn, "in_face"), m.faces.slots.capacity(), "face")};
  }
}

/// Mesh edges: node chains; the halfedges carry the direction.
void read_mesh_edges(const Reader& R, const Lists& L, Model& m) {
  std::vector<HalfedgeIdx> chain;
  for (std::size_t i = 0; i < L.nme; ++i) {
    const At jm = R.item(L.mesh_edges, i);
    const SurfaceIdx s{R.index(R.field(jm, "surface"), L.ns, "surface")};
    const At jn = R.field(jm, "nodes");
    const Json& list = R.array(jn, 2, "nodes");
    chain.clear();
    for (std::size_t k = 0; k + 1 < list.size(); ++k) {
      const NodeIdx a{R.index(R.item(jn, k), L.nn, "node")}, b{R.index(R.item(jn, k + 1), L.nn, "node")};
      const HalfedgeIdx h = m.find_halfedge(a, b);
      const std::string where = jn.ptr + "/" + std::to_string(k);
      if (!h.valid())
        R.fail(where, "no edge joins node " + std::to_string(a.value) + " to node " + std::to_string(b.value));
      if (m.surface_of(edge_of(h)) != s)
        R.fail(where, "edge " + std::to_string(edge_of(h).value) + " is not in surface " + std::to_string(s.value));
      if (const MeshEdgeIdx o = m.edges.mesh_edge[edge_of(h).value]; o.valid())
        R.fail(where,
               "edge " + std::to_string(edge_of(h).value) + " already belongs to mesh edge " + std::to_string(o.value));
      if (std::find_if(chain.begin(), chain.end(), [&](HalfedgeIdx x) { return edge_of(x) == edge_of(h); }) !=
          chain.end())
        R.fail(where, "the chain runs along edge " + std::to_string(edge_of(h).value) + " twice");
      chain.push_back(h);
    }
    (void)m.new_mesh_edge(s, chain);
  }
}

/// Mesh loops: lists of mesh edges, each in one loop at most.
void read_mesh_loops(const Reader& R, const Lists& L, Model& m) {
  std::vector<MeshEdgeIdx> list_me;
  for (std::size_t i = 0; i < L.nl; ++i) {
    const At jl = R.item(L.loops, i);
    const SurfaceIdx s{R.index(R.field(jl, "surface"), L.ns, "surface")};
    const At jm = R.field(jl, "mesh_edges");
    const Json& list = R.array(jm, 1, "mesh edges");
    list_me.clear();
    for (std::size_t k = 0; k < list.size(); ++k) {
      const At x = R.item(jm, k);
      const MeshEdgeIdx me{R.index(x, L.nme, "mesh edge")};
      if (const MeshLoopIdx o = m.mesh_edges.loop[me.value];
          o.valid() || std::count(list_me.begin(), list_me.end(), me))
        R.fail(x.ptr, "mesh edge " + std::to_string(me.value) + " is already in a loop");
      list_me.push_back(me);
    }
    (void)m.new_mesh_loop(s, list_me);
  }
}

/// Joints: members (mesh edge and direction) of equal length, each mesh
/// edge in one joint at most.
void read_joints(const Reader& R, const Lists& L, Model& m) {
  std::vector<JointMember> members;
  for (std::size_t i = 0; i < L.nj; ++i) {
    const At jj = R.item(L.joints, i);
    const At jm = R.field(jj, "members");
    const Json& list = R.array(jm, 2, "members");
    members.clear();
    for (std::size_t k = 0; k < list.size(); ++k) {
      const At x = R.item(jm, k);
      JointMember mm;
      mm.mesh_edge = MeshEdgeIdx{R.index(R.field(x, "mesh_edge"), L.nme, "mesh edge")};
      mm.positive = R.boolean(R.field(x, "positive"));
      if (m.mesh_edges.joint[mm.mesh_edge.value].valid() ||
          std::any_of(members.begin(), members.end(),
                      [&](const JointMember& o) { return o.mesh_edge == mm.mesh_edge; }))
        R.fail(x.ptr, "mesh edge " + std::to_string(mm.mesh_edge.value) + " is already in a joint");
      const std::size_t len = m.mesh_edges.halfedges.size(mm.mesh_edge.value);
      const std::size_t len0 = members.empty() ? len : m.mesh_edges.halfedges.size(members[0].mesh_edge.value);
      if (len != len0)
        R.fail(x.ptr, "joint members of different length: mesh edge " + std::to_string(mm.mesh_edge.value) + " has " +
                          std::to_string(len) + " edges, mesh edge " + std::to_string(members[0].mesh_edge.value) +
                          " has " + std::to_string(len0));
      members.push_back(mm);
    }
    (void)m.new_joint(members);
  }
}

/// Attribute nodes on a vertex, an edge (halfedge as a node pair) or a face.
void read_attribute_nodes(const Reader& R, const Lists& L, Model& m) {
  for (std::size_t i = 0; i < L.nan; ++i) {
    const At ja = R.item(L.attrib_nodes, i);
    const SurfaceIdx s{R.index(R.field(ja, "surface"), L.ns, "surface")};
    const At jk = R.field(ja, "kind");
    const std::string kind = R.string(jk);
    AttribNodeKind k{};
    std::uint32_t element = 0;
    std::uint8_t corner = 0;
    if (kind == "vertex") {
      k = AttribNodeKind::kVertex;
      element = R.index(R.field(ja, "node"), L.nn, "node");
    } else if (kind == "edge") {
      k = AttribNodeKind::kEdge;
      element = R.halfedge(R.field(ja, "halfedge"), m).value;
    } else if (kind == "face") {
      k = AttribNodeKind::kFace;
      element = R.index(R.field(ja, "face"), m.faces.slots.capacity(), "face");
      corner = R.byte(R.field(ja, "corner"), "corner");
    } else {
      R.fail(jk.ptr, "unknown attribute node kind '" + kind + "' (vertex, edge or face)");
    }
    (void)m.new_attrib_node(s, k, element, R.vec3(R.field(ja, "param")), R.vec3(R.field(ja, "position")), corner);
  }
}

/// Attribute edges: lists of attribute nodes, each in one edge at most.
void read_attribute_edges(const Reader& R, const Lists& L, Model& m) {
  std::vector<AttribNodeIdx> list_an;
  for (std::size_t i = 0; i < L.nae; ++i) {
    const At ja = R.item(L.attrib_edges, i);
    const SurfaceIdx s{R.index(R.field(ja, "surface"), L.ns, "surface")};
    const auto fid =
        static_cast<std::int32_t>(R.integer(R.field(ja, "feature_id"), std::numeric_limits<std::int32_t>::min(),
                                            std::numeric_limits<std::int32_t>::max(), "feature id"));
    const At jn = R.field(ja, "nodes");
    const Json& list = R.array(jn);
    list_an.clear();
    for (std::size_t k = 0; k < list.size(); ++k) {
      const At x = R.item(jn, k);
      const AttribNodeIdx a{R.index(x, L.nan, "attribute node")};
      if (m.attrib_nodes.owner[a.value].valid() || std::count(list_an.begin(), list_an.end(), a))
        R.fail(x.ptr, "attribute node " + std::to_string(a.value) + " already belongs to an attribute edge");
      list_an.push_back(a);
    }
    (void)m.new_attrib_edge(s, fid, list_an);
  }
}

/// Profiles: a halfedge (at most one profile per edge), a shift mode and a
/// Bezier offset list or a point list. Writes t.profiles.
void read_profiles(const Reader& R, const Lists& L, ProfileTemplate& t) {
  const Model& m = t.model;
  const Json& profiles = R.array(L.profiles);
  std::vector<std::uint32_t> profile_of_edge(L.ne, std::numeric_limits<std::uint32_t>::max());
  for (std::size_t i = 0; i < profiles.size(); ++i) {
    const At jp = R.item(L.profiles, i);
    TemplateProfile p;
    const At jh = R.field(jp, "halfedge");
    p.halfedge = R.halfedge(jh, m);
    const std::uint32_t e = edge_of(p.halfedge).value;
    if (profile_of_edge[e] != std::numeric_limits<std::uint32_t>::max())
      R.fail(jh.ptr, "duplicated profile edge: edge " + std::to_string(e) + " already has profile " +
                         std::to_string(profile_of_edge[e]));
    profile_of_edge[e] = static_cast<std::uint32_t>(i);
    const At jk = R.field(jp, "kind");
    const std::string kind = R.string(jk);
    const At js = R.field(jp, "shift");
    const std::string shift = R.string(js);
    if (shift == "scale")
      p.shift = ShiftMode::kScale;
    else if (shift == "scale_rotate")
      p.shift = ShiftMode::kScaleRotate;
    else
      R.fail(js.ptr, "unknown shift mode '" + shift + "' (scale or scale_rotate)");
    if (kind == "bezier") {
      p.kind = ProfileCurve::Kind::kBezier;
      const At jo = R.field(jp, "offsets");
      const Json& off = R.array(jo, 2, "control point offsets");
      for (std::size_t k = 0; k < off.size(); ++k) p.bezier.offsets.push_back(R.vec3(R.item(jo, k)));
    } else if (kind == "points") {
      p.kind = ProfileCurve::Kind::kPolyline;
      p.points.a = R.vec3(R.field(jp, "a"));
      p.points.b = R.vec3(R.field(jp, "b"));
      const At ju = R.field(jp, "u"), jq = R.field(jp, "points");
      const Json& u = R.array(ju);
      const Json& q = R.array(jq);
      if (u.size() != q.size())
        R.fail(jp.ptr, std::to_string(u.size()) + " parameters for " + std::to_string(q.size()) + " points");
      for (std::size_t k = 0; k < u.size(); ++k) {
        const At x = R.item(ju, k);
        const double uk = R.number(x);
        if (!(uk > 0.0 && uk < 1.0)) R.fail(x.ptr, "profile parameter " + std::to_string(uk) + " outside (0, 1)");
        if (k > 0 && uk < p.points.u.back()) R.fail(x.ptr, "profile parameters must not decrease");
        p.points.u.push_back(uk);
        p.points.points.push_back(R.vec3(R.item(jq, k)));
      }
    } else {
      R.fail(jk.ptr, "unknown profile kind '" + kind + "' (bezier or points)");
    }
    t.profiles.push_back(std::move(p));
  }
}

ProfileTemplate from_json(const Json& root, const Reader& R) {
  const At doc{root, ""};
  if (!root.is_object()) R.wrong(doc, "an object");
  check_format(R, doc);
  ProfileTemplate t;
  read_header(R, doc, t);
  const Lists L = locate_lists(R, doc);
  Model& m = t.model;
  read_surfaces(R, L, m);
  read_nodes(R, L, t);
  read_edges(R, doc, L, m);
  read_faces(R, L, m);
  read_nodes_in_faces(R, L, m);
  read_mesh_edges(R, L, m);
  read_mesh_loops(R, L, m);
  read_joints(R, L, m);
  read_attribute_nodes(R, L, m);
  read_attribute_edges(R, L, m);
  read_profiles(R, L, t);
  ++m.topology_version;
  if (Status s = validate_template(t); !s) R.fail("", "the template read is not valid: " + s.message());
  return t;
}

ProfileTemplate parse(std::string_view text, std::string_view source) {
  const Reader R(source);
  Json root;
  try {
    text = io_detail::skip_utf8_bom(text);
    root = Json::parse(text.begin(), text.end());
  } catch (const Json::parse_error& e) {
    // e.byte is the position of the error; a truncated file fails at its end.
    const bool at_end = e.byte >= text.size();
    throw Error(Status(ErrorCode::kParse, std::string(source) + ": at byte " + std::to_string(e.byte) + ": " +
                                              (at_end ? "truncated file or " : "") + "invalid JSON: " + e.what()));
  } catch (const Json::exception& e) {
    // Out-of-range numbers (1e999) are refused by the parser itself, which
    // names the token but not its place: find it in the text.
    std::string where;
    const std::string what = e.what();
    const auto q1 = what.find('\''), q2 = what.rfind('\'');
    if (q1 != std::string::npos && q2 > q1 + 1)
      if (const auto at = text.find(what.substr(q1 + 1, q2 - q1 - 1)); at != std::string_view::npos)
        where = "at byte " + std::to_string(at) + ": ";
    throw Error(
        Status(ErrorCode::kParse, std::string(source) + ": " + where + "non-finite number or invalid JSON: " + what));
  }
  try {
    return from_json(root, R);
  } catch (const Json::exception& e) {
    // Every access is type-checked first; this is a last line of defence.
    throw Error(Status(ErrorCode::kParse, std::string(source) + ": invalid template: " + e.what()));
  }
}

}  // namespace

ProfileTemplate template_from_json_string(std::string_view text, std::string_view source_name) {
  return parse(text, source_name);
}

ProfileTemplate read_template_json(const std::filesystem::path& path) {
  const std::string text = io_detail::read_file_bytes(path);
  return parse(text, path.string());
}

ProfileTemplate read_template_json(const std::filesystem::path& path, const ReferenceBody& reference) {
  ProfileTemplate t = read_template_json(path);
  if (Status s = check_template_references(t, reference); !s)
    throw Error(Status(ErrorCode::kParse, path.string() + ": " + s.message()));
  return t;
}

}  // namespace atelier
