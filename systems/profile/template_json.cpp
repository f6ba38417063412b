#include <atelier/systems/profile/template_json.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include <atelier/io/atomic_file.h>
#include <atelier/io/mesh_arrays.h>
#include <atelier/storage/validate.h>

namespace atelier {

namespace {

using Json = nlohmann::ordered_json;

// ------------------------------------------------------------------ names

const char* kind_name(ProfileCurve::Kind k) noexcept { return k == ProfileCurve::Kind::kBezier ? "bezier" : "points"; }
const char* shift_name(ShiftMode m) noexcept { return m == ShiftMode::kScale ? "scale" : "scale_rotate"; }
const char* attrib_kind_name(AttribNodeKind k) noexcept {
  switch (k) {
    case AttribNodeKind::kVertex: return "vertex";
    case AttribNodeKind::kEdge: return "edge";
    case AttribNodeKind::kFace: return "face";
  }
  return "?";
}

constexpr int kMaxLevels = kMaxTemplateLevels;

constexpr NodeEncodingMode kModes[] = {NodeEncodingMode::kFeaturePoint, NodeEncodingMode::kFeatureOffset,
                                       NodeEncodingMode::kVertex,       NodeEncodingMode::kEdge,
                                       NodeEncodingMode::kFace,         NodeEncodingMode::kOneToOne,
                                       NodeEncodingMode::kNToOne};

// ------------------------------------------------------------------ writing

[[noreturn]] void refuse(const std::string& name, const std::string& what) {
  throw Error(Status(ErrorCode::kInvalidArgument, "template '" + name + "': cannot write: " + what));
}

Json num(double x, const std::string& tname, const char* what) {
  // JSON has no NaN or infinity; refusing here keeps files readable back.
  if (!std::isfinite(x)) refuse(tname, std::string("non-finite number in ") + what);
  return Json(x);
}
Json vec(const Vec3d& p, const std::string& tname, const char* what) {
  return Json::array({num(p.x(), tname, what), num(p.y(), tname, what), num(p.z(), tname, what)});
}

bool has_tombstones_in_any_table(const Model& m) {
  return m.nodes.slots.size() != m.nodes.slots.capacity() || m.edges.slots.size() != m.edges.slots.capacity() ||
         m.faces.slots.size() != m.faces.slots.capacity() || m.surfaces.slots.size() != m.surfaces.slots.capacity() ||
         m.mesh_edges.slots.size() != m.mesh_edges.slots.capacity() ||
         m.mesh_loops.slots.size() != m.mesh_loops.slots.capacity() ||
         m.joints.slots.size() != m.joints.slots.capacity() ||
         m.attrib_nodes.slots.size() != m.attrib_nodes.slots.capacity() ||
         m.attrib_edges.slots.size() != m.attrib_edges.slots.capacity();
}

/// compact() on a copy, with the per-node arrays, node references of the
/// encodings and profile halfedges moved along.
ProfileTemplate compacted(const ProfileTemplate& t) {
  ProfileTemplate c = t;
  const CompactRemap r = c.model.compact();
  const std::size_t n = c.model.nodes.slots.capacity();
  std::vector<std::string> names(n);
  std::vector<NodeEncoding> enc(n);
  std::vector<double> clr(t.encoded_clearance.empty() ? 0 : n);
  for (std::size_t i = 0; i < r.nodes.size(); ++i) {
    if (!r.nodes[i].valid()) continue;
    const std::uint32_t k = r.nodes[i].value;
    names[k] = t.node_names[i];
    enc[k] = t.encodings.nodes[i];
    if (!clr.empty()) clr[k] = t.encoded_clearance[i];
  }
  auto node = [&](std::uint32_t old) {
    if (old >= r.nodes.size() || !r.nodes[old].valid())
      refuse(t.name, "an encoding refers to dead node " + std::to_string(old));
    return r.nodes[old].value;
  };
  for (NodeEncoding& e : enc)
    if (e.mode == NodeEncodingMode::kOneToOne) e.element = node(e.element);
  for (NodeRef& ref : c.encodings.refs) ref.node = node(ref.node);
  c.node_names = std::move(names);
  c.encodings.nodes = std::move(enc);
  c.encoded_clearance = std::move(clr);
  for (TemplateProfile& p : c.profiles) p.halfedge = r.halfedge(p.halfedge);
  return c;
}

Json pair_of(const Model& m, HalfedgeIdx h) { return Json::array({m.tail(h).value, m.head(h).value}); }

Json to_json(const ProfileTemplate& t) {
  if (Status s = validate_template(t); !s) refuse(t.name, "it does not validate: " + s.message());
  const Model& m = t.model;
  const std::string& tn = t.name;
  // The reader's ranges: a file this writes must read back.
  if (t.levels < 0 || t.levels > kMaxLevels) refuse(tn, "levels " + std::to_string(t.levels) + " outside [0, " + std::to_string(kMaxLevels) + "]");
  if (m.complex_holes < 0) refuse(tn, "negative complex hole count");
  const std::size_t nn = m.nodes.slots.capacity(), ne = m.edges.slots.capacity(), nf = m.faces.slots.capacity();

  Json doc = Json::object();
  doc["format"] = std::string(kTemplateFormat);
  doc["version"] = kTemplateFormatVersion;
  doc["name"] = t.name;
  doc["reference"] = t.reference;
  doc["clearance"] = num(t.clearance, tn, "clearance");
  doc["levels"] = t.levels;
  doc["complex_holes"] = m.complex_holes;

  // Faces are numbered in file order, surface after surface: their indices
  // survive only if the model groups them that way (the builders do).
  for (std::size_t f = 1; f < nf; ++f)
    if (m.faces.surface[f].value < m.faces.surface[f - 1].value)
      refuse(tn, "face " + std::to_string(f) + " of surface " + std::to_string(m.faces.surface[f].value) +
                     " follows a face of surface " + std::to_string(m.faces.surface[f - 1].value) +
                     " (faces must be grouped by surface)");
  Json surfaces = Json::array();
  std::vector<NodeIdx> cyc;
  for (std::size_t s = 0; s < m.surfaces.slots.capacity(); ++s) {
    Json js = Json::object();
    js["name"] = m.surfaces.name[s];
    if (m.surfaces.flags[s] != 0) js["flags"] = m.surfaces.flags[s];
    Json faces = Json::array();
    Json fflags = Json::array();
    bool any_flag = false;
    for (std::size_t f = 0; f < nf; ++f) {
      if (m.faces.surface[f].value != s) continue;
      m.face_nodes(FaceIdx{static_cast<std::uint32_t>(f)}, cyc);
      Json jf = Json::array();
      for (NodeIdx v : cyc) jf.push_back(v.value);
      faces.push_back(std::move(jf));
      fflags.push_back(m.faces.flags[f]);
      any_flag |= m.faces.flags[f] != 0;
    }
    js["faces"] = std::move(faces);
    if (any_flag) js["face_flags"] = std::move(fflags);
    surfaces.push_back(std::move(js));
  }
  doc["surfaces"] = std::move(surfaces);

  Json nodes = Json::array();
  for (std::size_t v = 0; v < nn; ++v) {
    Json jn = Json::object();
    jn["name"] = t.node_names[v];
    jn["surface"] = m.nodes.surface[v].value;
    jn["position"] = vec(m.nodes.position[v], tn, "a node position");
    // Columns the builders leave at their defaults are only written when set.
    if (m.nodes.position_backup[v] != Vec3d::Zero())
      jn["position_backup"] = vec(m.nodes.position_backup[v], tn, "a backup position");
    if (m.nodes.uv[v] != Vec2d::Zero())
      jn["uv"] = Json::array({num(m.nodes.uv[v].x(), tn, "a uv"), num(m.nodes.uv[v].y(), tn, "a uv")});
    if (m.nodes.in_face[v].valid()) jn["in_face"] = m.nodes.in_face[v].value;
    const NodeEncoding& e = t.encodings.nodes[v];
    Json je = Json::object();
    je["mode"] = to_string(e.mode);
    je["feature_point"] = e.feature_point;
    je["element"] = e.element;
    je["t"] = num(e.t, tn, "an encoding parameter");
    je["coords"] = vec(e.coords, tn, "encoding coordinates");
    if (e.mode == NodeEncodingMode::kNToOne) {
      if (std::size_t{e.first_ref} + e.ref_count > t.encodings.refs.size())
        refuse(tn, "node " + std::to_string(v) + " refers past the reference pool");
      Json refs = Json::array();
      for (std::uint32_t k = 0; k < e.ref_count; ++k) {
        const NodeRef& r = t.encodings.refs[e.first_ref + k];
        Json jr = Json::object();
        jr["node"] = r.node;
        jr["delta"] = vec(r.delta, tn, "a reference delta");
        jr["weight"] = num(r.weight, tn, "a reference weight");
        refs.push_back(std::move(jr));
      }
      je["refs"] = std::move(refs);
    }
    jn["encoding"] = std::move(je);
    if (!t.encoded_clearance.empty()) jn["encoded_clearance"] = num(t.encoded_clearance[v], tn, "a clearance");
    nodes.push_back(std::move(jn));
  }
  doc["nodes"] = std::move(nodes);

  Json edges = Json::array();
  Json eflags = Json::array();
  bool any_eflag = false;
  for (std::size_t e = 0; e < ne; ++e) {
    edges.push_back(pair_of(m, halfedge_of(EdgeIdx{static_cast<std::uint32_t>(e)}, 0)));
    eflags.push_back(m.edges.flags[e]);
    any_eflag |= m.edges.flags[e] != 0;
  }
  doc["edges"] = std::move(edges);
  if (any_eflag) doc["edge_flags"] = std::move(eflags);

  Json mes = Json::array();
  for (std::size_t i = 0; i < m.mesh_edges.slots.capacity(); ++i) {
    const auto chain = m.mesh_edges.halfedges.row(i);
    Json jm = Json::object();
    jm["surface"] = m.mesh_edges.surface[i].value;
    Json jn = Json::array();
    for (std::size_t k = 0; k < chain.size(); ++k) {
      if (k == 0) jn.push_back(m.tail(chain[0]).value);
      else if (m.tail(chain[k]) != m.head(chain[k - 1]))
        refuse(tn, "mesh edge " + std::to_string(i) + " is not a connected chain");
      jn.push_back(m.head(chain[k]).value);
    }
    jm["nodes"] = std::move(jn);
    mes.push_back(std::move(jm));
  }
  doc["mesh_edges"] = std::move(mes);

  Json loops = Json::array();
  for (std::size_t i = 0; i < m.mesh_loops.slots.capacity(); ++i) {
    Json jl = Json::object();
    jl["surface"] = m.mesh_loops.surface[i].value;
    Json list = Json::array();
    for (MeshEdgeIdx me : m.mesh_loops.mesh_edges.row(i)) list.push_back(me.value);
    jl["mesh_edges"] = std::move(list);
    loops.push_back(std::move(jl));
  }
  doc["mesh_loops"] = std::move(loops);

  Json joints = Json::array();
  for (std::size_t i = 0; i < m.joints.slots.capacity(); ++i) {
    Json members = Json::array();
    for (const JointMember& jm : m.joints.members.row(i)) {
      Json x = Json::object();
      x["mesh_edge"] = jm.mesh_edge.value;
      x["positive"] = jm.positive;
      members.push_back(std::move(x));
    }
    Json jj = Json::object();
    jj["members"] = std::move(members);
    joints.push_back(std::move(jj));
  }
  doc["joints"] = std::move(joints);

  Json anodes = Json::array();
  for (std::size_t i = 0; i < m.attrib_nodes.slots.capacity(); ++i) {
    const auto& a = m.attrib_nodes;
    Json ja = Json::object();
    ja["kind"] = attrib_kind_name(a.kind[i]);
    ja["surface"] = a.surface[i].value;
    switch (a.kind[i]) {
      case AttribNodeKind::kVertex: ja["node"] = a.element[i]; break;
      case AttribNodeKind::kEdge: ja["halfedge"] = pair_of(m, HalfedgeIdx{a.element[i]}); break;
      case AttribNodeKind::kFace:
        ja["face"] = a.element[i];
        ja["corner"] = a.corner[i];
        break;
    }
    ja["param"] = vec(a.param[i], tn, "an attribute parameter");
    ja["position"] = vec(a.position[i], tn, "an attribute position");
    anodes.push_back(std::move(ja));
  }
  doc["attribute_nodes"] = std::move(anodes);

  Json aedges = Json::array();
  for (std::size_t i = 0; i < m.attrib_edges.slots.capacity(); ++i) {
    Json ja = Json::object();
    ja["surface"] = m.attrib_edges.surface[i].value;
    ja["feature_id"] = m.attrib_edges.feature_id[i];
    Json list = Json::array();
    for (AttribNodeIdx a : m.attrib_edges.nodes.row(i)) list.push_back(a.value);
    ja["nodes"] = std::move(list);
    aedges.push_back(std::move(ja));
  }
  doc["attribute_edges"] = std::move(aedges);

  Json profiles = Json::array();
  for (const TemplateProfile& p : t.profiles) {
    Json jp = Json::object();
    jp["halfedge"] = pair_of(m, p.halfedge);
    jp["kind"] = kind_name(p.kind);
    jp["shift"] = shift_name(p.shift);
    if (p.kind == ProfileCurve::Kind::kBezier) {
      Json off = Json::array();
      for (const Vec3d& o : p.bezier.offsets) off.push_back(vec(o, tn, "a Bezier offset"));
      jp["offsets"] = std::move(off);
    } else {
      jp["a"] = vec(p.points.a, tn, "a profile end");
      jp["b"] = vec(p.points.b, tn, "a profile end");
      Json u = Json::array();
      for (double x : p.points.u) u.push_back(num(x, tn, "a profile parameter"));
      jp["u"] = std::move(u);
      Json pts = Json::array();
      for (const Vec3d& q : p.points.points) pts.push_back(vec(q, tn, "a profile point"));
      jp["points"] = std::move(pts);
    }
    profiles.push_back(std::move(jp));
  }
  doc["profiles"] = std::move(profiles);
  return doc;
}

/// Pretty printer: objects one member per line, arrays of scalars on one
/// line (positions, face cycles), arrays of containers one element per line.
/// Numbers go through nlohmann's dump, which writes the shortest decimal
/// that reads back to the same double.
void emit(const Json& j, int indent, std::string& out) {
  if (j.is_object()) {
    if (j.empty()) {
      out += "{}";
      return;
    }
    out += "{\n";
    bool first = true;
    for (auto it = j.begin(); it != j.end(); ++it) {
      if (!first) out += ",\n";
      first = false;
      out.append(static_cast<std::size_t>(indent + 2), ' ');
      out += Json(it.key()).dump();
      out += ": ";
      emit(it.value(), indent + 2, out);
    }
    out += '\n';
    out.append(static_cast<std::size_t>(indent), ' ');
    out += '}';
  } else if (j.is_array()) {
    const bool flat = std::none_of(j.begin(), j.end(), [](const Json& x) { return x.is_structured(); });
    if (flat) {
      out += '[';
      for (std::size_t i = 0; i < j.size(); ++i) {
        if (i) out += ", ";
        out += j[i].dump();
      }
      out += ']';
      return;
    }
    out += "[\n";
    for (std::size_t i = 0; i < j.size(); ++i) {
      if (i) out += ",\n";
      out.append(static_cast<std::size_t>(indent + 2), ' ');
      emit(j[i], indent + 2, out);
    }
    out += '\n';
    out.append(static_cast<std::size_t>(indent), ' ');
    out += ']';
  } else {
    out += j.dump();
  }
}

// ------------------------------------------------------------------ reading

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
    if (arr.size() != 2) fail(a.ptr, "expected a node pair [tail, head], found " + std::to_string(arr.size()) + " values");
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

ProfileTemplate from_json(const Json& root, const Reader& R) {
  const At doc{root, ""};
  if (!root.is_object()) R.wrong(doc, "an object");
  {
    const At f = R.field(doc, "format");
    if (!f.v.is_string() || f.v.get<std::string>() != kTemplateFormat)
      R.fail(f.ptr, "not an atelier template (format is " + f.v.dump() + ", expected \"" +
                        std::string(kTemplateFormat) + "\")");
    const At v = R.field(doc, "version");
    if (!v.v.is_number_integer() || v.v.get<std::int64_t>() != kTemplateFormatVersion)
      R.fail(v.ptr, "unsupported version " + v.v.dump() + " (this reader knows version " +
                        std::to_string(kTemplateFormatVersion) + ")");
  }
  ProfileTemplate t;
  t.name = R.string(R.field(doc, "name"));
  t.reference = R.string(R.field(doc, "reference"));
  t.clearance = R.number(R.field(doc, "clearance"));
  t.levels = static_cast<int>(R.integer(R.field(doc, "levels"), 0, kMaxLevels, "levels"));
  Model& m = t.model;
  m.complex_holes = R.integer(R.field(doc, "complex_holes"), 0, std::numeric_limits<std::int32_t>::max(),
                              "complex hole count");

  // Every list is read fully before the primitives run, so a bad index never
  // reaches a table.
  const At jsurf = R.field(doc, "surfaces");
  const At jnodes = R.field(doc, "nodes");
  const At jedges = R.field(doc, "edges");
  const At jmes = R.field(doc, "mesh_edges");
  const At jloops = R.field(doc, "mesh_loops");
  const At jjoints = R.field(doc, "joints");
  const At janodes = R.field(doc, "attribute_nodes");
  const At jaedges = R.field(doc, "attribute_edges");
  const At jprof = R.field(doc, "profiles");
  const std::size_t ns = R.array(jsurf).size(), nn = R.array(jnodes).size(), ne = R.array(jedges).size();
  const std::size_t nme = R.array(jmes).size(), nl = R.array(jloops).size(), nj = R.array(jjoints).size();
  const std::size_t nan_ = R.array(janodes).size(), nae = R.array(jaedges).size();
  (void)R.array(jprof);
  constexpr std::size_t kMaxRows = std::size_t{1} << 30;  // halfedge indices must fit 32 bits
  if (nn > kMaxRows || ne > kMaxRows) R.fail("", "too many nodes or edges");

  // Surfaces (names first: nodes refer to them).
  for (std::size_t s = 0; s < ns; ++s) {
    const At js = R.item(jsurf, s);
    const Surface h = m.add_surface(R.string(R.field(js, "name")));
    if (Reader::has(js, "flags")) m.surfaces.flags[h.idx.value] = R.byte(R.field(js, "flags"), "surface flags");
  }

  // Nodes.
  t.node_names.resize(nn);
  t.encodings.nodes.resize(nn);
  bool any_clearance = false;
  for (std::size_t v = 0; v < nn; ++v) {
    const At jn = R.item(jnodes, v);
    t.node_names[v] = R.string(R.field(jn, "name"));
    const SurfaceIdx s{R.index(R.field(jn, "surface"), ns, "surface")};
    const NodeIdx id = m.new_node(s, R.vec3(R.field(jn, "position")));
    if (Reader::has(jn, "position_backup")) m.nodes.position_backup[id.value] = R.vec3(R.field(jn, "position_backup"));
    if (Reader::has(jn, "uv")) m.nodes.uv[id.value] = R.vec2(R.field(jn, "uv"));
    const bool c = Reader::has(jn, "encoded_clearance");
    if (v == 0) any_clearance = c;
    if (c != any_clearance)
      R.fail(jn.ptr, "encoded_clearance must be given for every node or for none (node 0 " +
                         std::string(any_clearance ? "has" : "has none") + ")");
    if (c) {
      if (t.encoded_clearance.empty()) t.encoded_clearance.resize(nn);
      t.encoded_clearance[v] = R.number(R.field(jn, "encoded_clearance"));
    }
    // Encoding.
    const At je = R.field(jn, "encoding");
    NodeEncoding e;
    const At jm = R.field(je, "mode");
    const std::string mode = R.string(jm);
    const auto* it = std::find_if(std::begin(kModes), std::end(kModes),
                                  [&](NodeEncodingMode x) { return mode == to_string(x); });
    if (it == std::end(kModes))
      R.fail(jm.ptr, "unknown encoding mode '" + mode +
                         "' (feature_point, feature_offset, vertex, edge, face, one_to_one or n_to_one)");
    e.mode = *it;
    e.feature_point = static_cast<std::int32_t>(R.integer(R.field(je, "feature_point"),
                                                          std::numeric_limits<std::int32_t>::min(),
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
      e.first_ref = static_cast<std::uint32_t>(t.encodings.refs.size());
      e.ref_count = static_cast<std::uint32_t>(refs.size());
      for (std::size_t k = 0; k < refs.size(); ++k) {
        const At x = R.item(jr, k);
        NodeRef r;
        r.node = R.index(R.field(x, "node"), nn, "node");
        if (r.node == v) R.fail(x.ptr + "/node", "node " + std::to_string(v) + " refers to itself");
        r.delta = R.vec3(R.field(x, "delta"));
        r.weight = R.number(R.field(x, "weight"));
        t.encodings.refs.push_back(r);
      }
    } else if (has_refs) {
      R.fail(je.ptr + "/refs", std::string("references are only allowed for mode n_to_one, not ") + to_string(e.mode));
    }
    t.encodings.nodes[v] = e;
  }

  // Edges: halfedge 2e runs from the first node to the second.
  for (std::size_t e = 0; e < ne; ++e) {
    const At je = R.item(jedges, e);
    const Json& arr = R.array(je);
    if (arr.size() != 2) R.fail(je.ptr, "an edge is a node pair [tail, head], found " + std::to_string(arr.size()) + " values");
    const NodeIdx a{R.index(R.item(je, 0), nn, "node")}, b{R.index(R.item(je, 1), nn, "node")};
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
    if (R.array(jf).size() != ne) R.fail(jf.ptr, "needs one value per edge (" + std::to_string(ne) + ")");
    for (std::size_t e = 0; e < ne; ++e) m.edges.flags[e] = R.byte(R.item(jf, e), "edge flags");
  }

  // Faces, surface after surface.
  std::vector<HalfedgeIdx> cycle;
  for (std::size_t s = 0; s < ns; ++s) {
    const At js = R.item(jsurf, s);
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
        ids[k] = NodeIdx{R.index(x, nn, "node")};
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
                             std::to_string(m.face(h).value) + " (a third face on an edge, or faces oriented inconsistently)");
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
  for (std::size_t v = 0; v < nn; ++v) {
    const At jn = R.item(jnodes, v);
    if (Reader::has(jn, "in_face"))
      m.nodes.in_face[v] = FaceIdx{R.index(R.field(jn, "in_face"), m.faces.slots.capacity(), "face")};
  }

  // Mesh edges: node chains; the halfedges carry the direction.
  std::vector<HalfedgeIdx> chain;
  for (std::size_t i = 0; i < nme; ++i) {
    const At jm = R.item(jmes, i);
    const SurfaceIdx s{R.index(R.field(jm, "surface"), ns, "surface")};
    const At jn = R.field(jm, "nodes");
    const Json& list = R.array(jn, 2, "nodes");
    chain.clear();
    for (std::size_t k = 0; k + 1 < list.size(); ++k) {
      const NodeIdx a{R.index(R.item(jn, k), nn, "node")}, b{R.index(R.item(jn, k + 1), nn, "node")};
      const HalfedgeIdx h = m.find_halfedge(a, b);
      const std::string where = jn.ptr + "/" + std::to_string(k);
      if (!h.valid())
        R.fail(where, "no edge joins node " + std::to_string(a.value) + " to node " + std::to_string(b.value));
      if (m.surface_of(edge_of(h)) != s)
        R.fail(where, "edge " + std::to_string(edge_of(h).value) + " is not in surface " + std::to_string(s.value));
      if (const MeshEdgeIdx o = m.edges.mesh_edge[edge_of(h).value]; o.valid())
        R.fail(where, "edge " + std::to_string(edge_of(h).value) + " already belongs to mesh edge " + std::to_string(o.value));
      if (std::find_if(chain.begin(), chain.end(), [&](HalfedgeIdx x) { return edge_of(x) == edge_of(h); }) != chain.end())
        R.fail(where, "the chain runs along edge " + std::to_string(edge_of(h).value) + " twice");
      chain.push_back(h);
    }
    (void)m.new_mesh_edge(s, chain);
  }

  std::vector<MeshEdgeIdx> list_me;
  for (std::size_t i = 0; i < nl; ++i) {
    const At jl = R.item(jloops, i);
    const SurfaceIdx s{R.index(R.field(jl, "surface"), ns, "surface")};
    const At jm = R.field(jl, "mesh_edges");
    const Json& list = R.array(jm, 1, "mesh edges");
    list_me.clear();
    for (std::size_t k = 0; k < list.size(); ++k) {
      const At x = R.item(jm, k);
      const MeshEdgeIdx me{R.index(x, nme, "mesh edge")};
      if (const MeshLoopIdx o = m.mesh_edges.loop[me.value]; o.valid() || std::count(list_me.begin(), list_me.end(), me))
        R.fail(x.ptr, "mesh edge " + std::to_string(me.value) + " is already in a loop");
      list_me.push_back(me);
    }
    (void)m.new_mesh_loop(s, list_me);
  }

  std::vector<JointMember> members;
  for (std::size_t i = 0; i < nj; ++i) {
    const At jj = R.item(jjoints, i);
    const At jm = R.field(jj, "members");
    const Json& list = R.array(jm, 2, "members");
    members.clear();
    for (std::size_t k = 0; k < list.size(); ++k) {
      const At x = R.item(jm, k);
      JointMember mm;
      mm.mesh_edge = MeshEdgeIdx{R.index(R.field(x, "mesh_edge"), nme, "mesh edge")};
      mm.positive = R.boolean(R.field(x, "positive"));
      if (m.mesh_edges.joint[mm.mesh_edge.value].valid() ||
          std::any_of(members.begin(), members.end(), [&](const JointMember& o) { return o.mesh_edge == mm.mesh_edge; }))
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

  for (std::size_t i = 0; i < nan_; ++i) {
    const At ja = R.item(janodes, i);
    const SurfaceIdx s{R.index(R.field(ja, "surface"), ns, "surface")};
    const At jk = R.field(ja, "kind");
    const std::string kind = R.string(jk);
    AttribNodeKind k{};
    std::uint32_t element = 0;
    std::uint8_t corner = 0;
    if (kind == "vertex") {
      k = AttribNodeKind::kVertex;
      element = R.index(R.field(ja, "node"), nn, "node");
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

  std::vector<AttribNodeIdx> list_an;
  for (std::size_t i = 0; i < nae; ++i) {
    const At ja = R.item(jaedges, i);
    const SurfaceIdx s{R.index(R.field(ja, "surface"), ns, "surface")};
    const auto fid = static_cast<std::int32_t>(R.integer(R.field(ja, "feature_id"), std::numeric_limits<std::int32_t>::min(),
                                                         std::numeric_limits<std::int32_t>::max(), "feature id"));
    const At jn = R.field(ja, "nodes");
    const Json& list = R.array(jn);
    list_an.clear();
    for (std::size_t k = 0; k < list.size(); ++k) {
      const At x = R.item(jn, k);
      const AttribNodeIdx a{R.index(x, nan_, "attribute node")};
      if (m.attrib_nodes.owner[a.value].valid() || std::count(list_an.begin(), list_an.end(), a))
        R.fail(x.ptr, "attribute node " + std::to_string(a.value) + " already belongs to an attribute edge");
      list_an.push_back(a);
    }
    (void)m.new_attrib_edge(s, fid, list_an);
  }

  // Profiles.
  const Json& profiles = R.array(jprof);
  std::vector<std::uint32_t> profile_of_edge(ne, std::numeric_limits<std::uint32_t>::max());
  for (std::size_t i = 0; i < profiles.size(); ++i) {
    const At jp = R.item(jprof, i);
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
    if (shift == "scale") p.shift = ShiftMode::kScale;
    else if (shift == "scale_rotate") p.shift = ShiftMode::kScaleRotate;
    else R.fail(js.ptr, "unknown shift mode '" + shift + "' (scale or scale_rotate)");
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
    throw Error(Status(ErrorCode::kParse, std::string(source) + ": " + where + "non-finite number or invalid JSON: " + what));
  }
  try {
    return from_json(root, R);
  } catch (const Json::exception& e) {
    // Every access is type-checked first; this is a last line of defence.
    throw Error(Status(ErrorCode::kParse, std::string(source) + ": invalid template: " + e.what()));
  }
}

}  // namespace

std::string template_to_json_string(const ProfileTemplate& t) {
  const Json doc = has_tombstones_in_any_table(t.model) ? to_json(compacted(t)) : to_json(t);
  std::string out;
  emit(doc, 0, out);
  out += '\n';
  return out;
}

ProfileTemplate template_from_json_string(std::string_view text, std::string_view source_name) {
  return parse(text, source_name);
}

void write_template_json(const ProfileTemplate& t, const std::filesystem::path& path) {
  std::string text;
  try {
    text = template_to_json_string(t);
  } catch (const Error& e) {
    throw Error(Status(e.status().code(), path.string() + ": " + e.status().message()));
  }
  write_atomically(path, [&](AtomicFile& out) { out.write(text); });
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
