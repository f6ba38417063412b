#include <atelier/io/obj.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <unordered_map>

#include <atelier/engine/math.h>
#include <atelier/io/atomic_file.h>
#include <atelier/io/mesh_arrays.h>

namespace atelier {

using namespace io_detail;

namespace {


struct ObjFace {
  std::uint32_t group;
  std::uint32_t begin, end;  // into corner arrays
  std::size_t line;
};

struct ObjData {
  std::vector<Vec3d> positions;
  std::vector<Vec2d> texcoords;
  std::vector<std::int64_t> corner_v;   // 0-based once resolved
  std::vector<std::int64_t> corner_vt;  // 0-based, -1 when absent
  std::vector<ObjFace> faces;
  std::vector<std::string> group_names;
  std::unordered_map<std::string, std::uint32_t> group_of;
  // `l` statements, only when the parser is asked for them (read_obj_polylines).
  std::vector<std::int64_t> line_v;  // 0-based once resolved
  std::vector<ObjFace> polylines;    // group unused
};

class ObjParser {
 public:
  ObjParser(std::string_view text, std::string_view file, bool polylines = false)
      : text_(skip_utf8_bom(text)), file_(file), polylines_(polylines) {}

  ObjData run() {
    std::size_t pos = 0, line_no = 0;
    std::string logical;
    while (pos < text_.size()) {
      // Assemble one logical line (a trailing backslash continues it).
      logical.clear();
      const std::size_t first_line = line_no + 1;
      for (;;) {
        const std::size_t nl = text_.find('\n', pos);
        std::string_view phys = text_.substr(pos, nl == std::string_view::npos ? std::string_view::npos : nl - pos);
        pos = nl == std::string_view::npos ? text_.size() : nl + 1;
        ++line_no;
        while (!phys.empty() && (phys.back() == '\r' || phys.back() == ' ' || phys.back() == '\t')) phys.remove_suffix(1);
        if (!phys.empty() && phys.back() == '\\' && pos < text_.size()) {
          phys.remove_suffix(1);
          logical.append(phys).push_back(' ');
          continue;
        }
        if (!phys.empty() && phys.back() == '\\') phys.remove_suffix(1);
        logical.append(phys);
        break;
      }
      line(logical, first_line);
    }
    check_ranges();
    // Text or bytes with no `v` statement are not a mesh (an empty model
    // would be written back by convert as if something had been read).
    if (d_.positions.empty()) fail(line_no, "no vertex ('v' statement) in the file: not an OBJ mesh");
    return std::move(d_);
  }

 private:
  [[noreturn]] void fail(std::size_t line, const std::string& what) const { throw parse_error_at_line(file_, line, what); }

  double number(std::string_view tok, std::size_t line, const char* what) const {
    const auto v = parse_double(tok);
    if (!v) fail(line, number_problem(tok) + " in " + what);
    if (!std::isfinite(*v)) fail(line, "NaN/inf coordinate '" + std::string(tok) + "' in " + what);
    return *v;
  }

  void line(std::string_view l, std::size_t line_no) {
    if (const auto hash = l.find('#'); hash != std::string_view::npos) l = l.substr(0, hash);
    split_blanks(l, tok_);
    if (tok_.empty()) return;
    const std::string_view kw = tok_[0];
    if (kw == "v") {
      if (tok_.size() < 4) fail(line_no, "vertex has " + std::to_string(tok_.size() - 1) + " coordinates (3 needed)");
      // Extra values (w, or r g b vertex colours) are allowed but must be numbers.
      Vec3d p;
      for (int k = 0; k < 3; ++k) p[k] = number(tok_[k + 1], line_no, "vertex");
      for (std::size_t k = 4; k < tok_.size(); ++k) (void)number(tok_[k], line_no, "vertex");
      d_.positions.push_back(p);
    } else if (kw == "vt") {
      if (tok_.size() < 2) fail(line_no, "texture coordinate has no values");
      Vec2d t(number(tok_[1], line_no, "texture coordinate"), 0.0);
      if (tok_.size() > 2) t.y() = number(tok_[2], line_no, "texture coordinate");
      d_.texcoords.push_back(t);
    } else if (kw == "f") {
      if (!polylines_) face(line_no);
    } else if (kw == "l" && polylines_) {
      polyline(line_no);
    } else if (kw == "g" || kw == "o") {
      std::string name;
      for (std::size_t k = 1; k < tok_.size(); ++k) {
        if (k > 1) name.push_back(' ');
        name.append(tok_[k]);
      }
      current_ = name.empty() ? std::string("default") : std::move(name);
      group_ = kNone;
    }
    // Everything else (vn, vp, s, mtllib, usemtl, ..., and `l` outside
    // read_obj_polylines) does not describe the surfaces' topology and is skipped.
  }

  std::int64_t index(std::string_view tok, std::size_t count, std::size_t line_no, const char* what) const {
    const auto v = parse_int(tok);
    if (!v) fail(line_no, number_problem(tok, true) + " as " + what + " index in face");
    if (*v == 0) fail(line_no, std::string("bad index: ") + what + " index 0 (OBJ indices start at 1)");
    if (*v < 0) {
      // Relative: -1 is the last one defined so far.
      const std::int64_t r = static_cast<std::int64_t>(count) + *v;
      if (r < 0)
        fail(line_no, std::string("bad index: relative ") + what + " index " + std::string(tok) + " refers before the first " +
                          what + " (" + std::to_string(count) + " defined so far)");
      return r;
    }
    return *v - 1;  // range checked once the whole file is read (forward references)
  }

  void face(std::size_t line_no) {
    const std::size_t n = tok_.size() - 1;
    if (n < 3) fail(line_no, "face has " + std::to_string(n) + " vertices (at least 3 needed)");
    if (group_ == kNone) {
      auto [it, inserted] = d_.group_of.try_emplace(current_, static_cast<std::uint32_t>(d_.group_names.size()));
      if (inserted) d_.group_names.push_back(current_);
      group_ = it->second;
    }
    const auto begin = static_cast<std::uint32_t>(d_.corner_v.size());
    for (std::size_t k = 1; k <= n; ++k) {
      const std::string_view t = tok_[k];
      const std::size_t s1 = t.find('/');
      d_.corner_v.push_back(index(t.substr(0, s1), d_.positions.size(), line_no, "vertex"));
      std::int64_t vt = -1;
      if (s1 != std::string_view::npos) {
        const std::size_t s2 = t.find('/', s1 + 1);
        const std::string_view tt = t.substr(s1 + 1, s2 == std::string_view::npos ? std::string_view::npos : s2 - s1 - 1);
        if (!tt.empty()) vt = index(tt, d_.texcoords.size(), line_no, "texture");
        if (s2 != std::string_view::npos) {
          const std::string_view tn = t.substr(s2 + 1);
          if (tn.empty() || tn.find('/') != std::string_view::npos || !parse_int(tn))
            fail(line_no, "non-numeric token '" + std::string(t) + "' in face (expected v, v/vt, v/vt/vn or v//vn)");
        }
      }
      d_.corner_vt.push_back(vt);
    }
    d_.faces.push_back({group_, begin, static_cast<std::uint32_t>(d_.corner_v.size()), line_no});
  }

  void polyline(std::size_t line_no) {
    const std::size_t n = tok_.size() - 1;
    if (n < 2) fail(line_no, "polyline has " + std::to_string(n) + " vertices (at least 2 needed)");
    const auto begin = static_cast<std::uint32_t>(d_.line_v.size());
    for (std::size_t k = 1; k <= n; ++k) {
      const std::string_view t = tok_[k];
      const std::size_t s1 = t.find('/');
      const std::string_view tt = s1 == std::string_view::npos ? std::string_view{} : t.substr(s1 + 1);
      if (!parse_int(t.substr(0, s1)) || (!tt.empty() && !parse_int(tt)))
        fail(line_no, "non-numeric token '" + std::string(t) + "' in polyline (expected v or v/vt)");
      d_.line_v.push_back(index(t.substr(0, s1), d_.positions.size(), line_no, "vertex"));
      if (s1 != std::string_view::npos) {
        if (!tt.empty()) (void)index(tt, d_.texcoords.size(), line_no, "texture");
      }
    }
    d_.polylines.push_back({0, begin, static_cast<std::uint32_t>(d_.line_v.size()), line_no});
  }

  void check_ranges() const {
    for (const ObjFace& l : d_.polylines)
      for (std::uint32_t k = l.begin; k < l.end; ++k)
        if (d_.line_v[k] >= static_cast<std::int64_t>(d_.positions.size()))
          fail(l.line, "bad index: vertex index " + std::to_string(d_.line_v[k] + 1) + " out of range (the file has " +
                           std::to_string(d_.positions.size()) + " vertices)");
    for (const ObjFace& f : d_.faces)
      for (std::uint32_t k = f.begin; k < f.end; ++k) {
        if (d_.corner_v[k] >= static_cast<std::int64_t>(d_.positions.size()))
          fail(f.line, "bad index: vertex index " + std::to_string(d_.corner_v[k] + 1) + " out of range (the file has " +
                           std::to_string(d_.positions.size()) + " vertices)");
        if (d_.corner_vt[k] >= static_cast<std::int64_t>(d_.texcoords.size()))
          fail(f.line, "bad index: texture index " + std::to_string(d_.corner_vt[k] + 1) +
                           " out of range (the file has " + std::to_string(d_.texcoords.size()) +
                           " texture coordinates)");
      }
  }

  std::string_view text_;
  std::string_view file_;
  bool polylines_ = false;
  ObjData d_;
  std::vector<std::string_view> tok_;
  std::string current_ = "default";
  std::uint32_t group_ = kNone;
};

/// Issue 27: where three or more faces of different groups share an OBJ
/// edge, the surfaces are joined there by a MESHJOINT (the papers' way of
/// assembling non-manifold bodies) instead of being left unconnected: one
/// single-edge MESHEDGE per surface, running along that surface's face
/// (negative flag when that is against the joint direction, which runs from
/// the lower OBJ vertex index to the higher), members clockwise about the
/// joint direction by the right-hand rule, as TemplateBuilder::joint orders
/// them. Two faces of two groups meeting at an edge (a material seam, the
/// common case) stay unjoined, as before. Returns the number of joints made.
std::size_t join_shared_edges(Model& m) {
  const auto src = m.nodes.props.find<std::int32_t>("source_vertex");
  if (!src.valid()) return 0;
  struct Side {
    std::uint64_t key;
    std::uint32_t edge;
    bool operator<(const Side& o) const { return key != o.key ? key < o.key : edge < o.edge; }
  };
  std::vector<Side> sides;
  for (std::uint32_t e = 0; e < m.edges.slots.capacity(); ++e) {
    if (!m.alive(EdgeIdx{e})) continue;
    const auto a = static_cast<std::uint32_t>(src[m.tail(halfedge_of(EdgeIdx{e}, 0))]);
    const auto b = static_cast<std::uint32_t>(src[m.tail(halfedge_of(EdgeIdx{e}, 1))]);
    sides.push_back({std::uint64_t{std::min(a, b)} << 32 | std::max(a, b), e});
  }
  std::sort(sides.begin(), sides.end());
  std::size_t made = 0;
  struct Member {
    MeshEdgeIdx mesh_edge;
    bool positive;
    double angle;
  };
  std::vector<Member> members;
  for (std::size_t i = 0; i < sides.size();) {
    std::size_t j = i;
    int faces = 0;
    while (j < sides.size() && sides[j].key == sides[i].key) {
      const EdgeIdx e{sides[j].edge};
      faces += m.face(halfedge_of(e, 0)).valid() + m.face(halfedge_of(e, 1)).valid();
      ++j;
    }
    // One surface holds one node per OBJ vertex, so a run of several edges
    // is several surfaces.
    if (j - i >= 2 && faces >= 3) {
      const auto lo = static_cast<std::int32_t>(sides[i].key >> 32);
      members.clear();
      Vec3d dir = Vec3d::Zero(), e1 = Vec3d::Zero(), e2 = Vec3d::Zero();
      for (std::size_t k = i; k < j; ++k) {
        const EdgeIdx e{sides[k].edge};
        HalfedgeIdx h = halfedge_of(e, src[m.tail(halfedge_of(e, 0))] == lo ? 0u : 1u);  // lo -> hi
        if (k == i) {
          dir = m.position(m.head(h)) - m.position(m.tail(h));
          if (dir.norm() > 0) {
            dir.normalize();
            e1 = dir.unitOrthogonal();
            e2 = dir.cross(e1);
          }
        }
        bool positive = true;
        if (!m.face(h).valid()) {
          h = twin(h);
          positive = false;
        }
        const std::array<HalfedgeIdx, 1> chain{h};
        const MeshEdgeIdx me = m.new_mesh_edge(m.nodes.surface[m.tail(h).value], chain);
        Vec3d c = Vec3d::Zero();
        int n = 0;
        m.for_each_face_halfedge(m.face(h), [&](HalfedgeIdx x) {
          c += m.position(m.tail(x));
          ++n;
        });
        const Vec3d w = c / n - 0.5 * (m.position(m.tail(h)) + m.position(m.head(h)));
        members.push_back({me, positive, std::atan2(w.dot(e2), w.dot(e1))});
      }
      // Clockwise about dir by the right-hand rule: decreasing angle.
      std::stable_sort(members.begin(), members.end(), [](const Member& x, const Member& y) { return x.angle > y.angle; });
      std::vector<JointMember> jm;
      for (const Member& mm : members) jm.push_back({mm.mesh_edge, mm.positive});
      (void)m.new_joint(jm);
      ++made;
    }
    i = j;
  }
  return made;
}


Model build(ObjData& d, std::string_view file) {
  const std::size_t nv = d.positions.size();
  std::vector<std::uint8_t> used(nv, 0);
  for (std::int64_t v : d.corner_v) used[static_cast<std::size_t>(v)] = 1;
  const bool has_isolated = std::find(used.begin(), used.end(), 0) != used.end();
  if (has_isolated && !d.group_of.count("default")) {
    d.group_of.emplace("default", static_cast<std::uint32_t>(d.group_names.size()));
    d.group_names.push_back("default");
  }
  const std::uint32_t default_group = has_isolated ? d.group_of.at("default") : kNone;

  // Faces bucketed by group, file order kept inside each group.
  const std::size_t ng = d.group_names.size();
  std::vector<std::uint32_t> start(ng + 1, 0);
  for (const ObjFace& f : d.faces) ++start[f.group + 1];
  for (std::size_t g = 0; g < ng; ++g) start[g + 1] += start[g];
  std::vector<std::uint32_t> order(d.faces.size());
  {
    std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
    for (std::uint32_t i = 0; i < d.faces.size(); ++i) order[fill[d.faces[i].group]++] = i;
  }

  Model m;
  std::vector<std::uint32_t> local(nv, kNone);
  std::vector<std::uint32_t> verts;
  const bool has_uv = !d.texcoords.empty();
  for (std::uint32_t g = 0; g < ng; ++g) {
    verts.clear();
    for (std::uint32_t k = start[g]; k < start[g + 1]; ++k) {
      const ObjFace& f = d.faces[order[k]];
      for (std::uint32_t c = f.begin; c < f.end; ++c) verts.push_back(static_cast<std::uint32_t>(d.corner_v[c]));
    }
    if (g == default_group)
      for (std::uint32_t v = 0; v < nv; ++v)
        if (!used[v]) verts.push_back(v);
    std::sort(verts.begin(), verts.end());
    verts.erase(std::unique(verts.begin(), verts.end()), verts.end());

    SurfaceSoup soup;
    soup.name = d.group_names[g];
    soup.positions.reserve(verts.size());
    soup.source.reserve(verts.size());
    for (std::uint32_t i = 0; i < verts.size(); ++i) {
      local[verts[i]] = i;
      soup.positions.push_back(d.positions[verts[i]]);
      soup.source.push_back(static_cast<std::int32_t>(verts[i]));
    }
    std::vector<std::uint8_t> uv_set;
    if (has_uv) {
      soup.uv.assign(verts.size(), Vec2d::Zero());
      uv_set.assign(verts.size(), 0);
    }
    for (std::uint32_t k = start[g]; k < start[g + 1]; ++k) {
      const ObjFace& f = d.faces[order[k]];
      for (std::uint32_t c = f.begin; c < f.end; ++c) {
        const std::uint32_t l = local[static_cast<std::size_t>(d.corner_v[c])];
        soup.face_nodes.push_back(l);
        if (has_uv) {
          const std::int64_t vt = d.corner_vt[c];
          soup.corner_uv.push_back(vt >= 0 ? d.texcoords[static_cast<std::size_t>(vt)] : Vec2d::Zero());
          soup.corner_texcoord.push_back(static_cast<std::int32_t>(vt));
        }
        if (has_uv && d.corner_vt[c] >= 0 && !uv_set[l]) {
          soup.uv[l] = d.texcoords[static_cast<std::size_t>(d.corner_vt[c])];
          uv_set[l] = 1;
        }
      }
      soup.face_offsets.push_back(static_cast<std::uint32_t>(soup.face_nodes.size()));
      soup.face_where.push_back(f.line);
    }
    for (std::uint32_t v : verts) local[v] = kNone;
    add_soup_surface(m, soup, file, "line");
  }
  (void)join_shared_edges(m);
  return m;
}



/// The `vt` list of a model with per-corner texture coordinates: one entry
/// per distinct (source texcoord index, value) over the live face corners,
/// in source order (so a file read and written again lists its `vt` as it
/// did), then corners with no source index by value in first-use order.
/// Corners read without a `vt` (source index -1 beside others) get none.
struct CornerTexcoords {
  std::vector<Vec2d> values;
  std::vector<std::uint32_t> index;  // per halfedge: into values, or kNone
};

CornerTexcoords corner_texcoords(const Model& m) {
  const auto uv = m.halfedges.props.find<Vec2d>("corner_uv");
  const auto src = m.halfedges.props.find<std::int32_t>("source_texcoord");
  CornerTexcoords out;
  out.index.assign(2 * std::size_t{m.edges.slots.capacity()}, kNone);
  struct Key {
    std::int64_t source;
    std::uint64_t u, v;  // bits: equal values are the same texcoord
    auto operator<=>(const Key&) const = default;
  };
  std::vector<std::pair<Key, std::uint32_t>> keys;  // key, halfedge
  std::uint64_t fresh = 0;
  std::map<std::pair<std::uint64_t, std::uint64_t>, std::uint64_t> unsourced;
  for (std::uint32_t h = 0; h < out.index.size(); ++h) {
    const HalfedgeIdx hi{h};
    if (!m.alive(hi) || !m.face(hi).valid()) continue;
    const Vec2d t = uv[hi];
    std::uint64_t ub, vb;
    std::memcpy(&ub, &t.x(), 8);
    std::memcpy(&vb, &t.y(), 8);
    std::int64_t s = src.valid() ? src[hi] : -2;
    if (s == -1) continue;  // read without a vt
    if (s < 0) {            // no source index: by value, first use first
      auto [it, inserted] = unsourced.try_emplace({ub, vb}, fresh);
      if (inserted) ++fresh;
      s = std::int64_t{1} << 40 | static_cast<std::int64_t>(it->second);
    }
    keys.push_back({{s, ub, vb}, h});
  }
  std::sort(keys.begin(), keys.end());
  for (std::size_t i = 0; i < keys.size(); ++i) {
    if (i == 0 || keys[i].first != keys[i - 1].first) out.values.push_back(uv[HalfedgeIdx{keys[i].second}]);
    out.index[keys[i].second] = static_cast<std::uint32_t>(out.values.size() - 1);
  }
  return out;
}
}  // namespace

Model read_obj_from_string(std::string_view text, std::string_view display_name) {
  ObjData d = ObjParser(text, display_name).run();
  return build(d, display_name);
}

Model read_obj(const std::filesystem::path& path) {
  const std::string bytes = read_file_bytes(path);
  return read_obj_from_string(bytes, path.string());
}

PolylineSet read_obj_polylines_from_string(std::string_view text, std::string_view display_name) {
  const ObjData d = ObjParser(text, display_name, true).run();
  if (d.polylines.empty()) throw parse_error(display_name, "", "no polyline (`l` statement) in the file");
  PolylineSet out;
  out.source = std::string(display_name);
  std::vector<Vec3d> pts;
  for (std::size_t i = 0; i < d.polylines.size(); ++i) {
    const ObjFace& l = d.polylines[i];
    pts.clear();
    for (std::uint32_t k = l.begin; k < l.end; ++k) pts.push_back(d.positions[static_cast<std::size_t>(d.line_v[k])]);
    out.add(static_cast<std::int64_t>(i), pts, l.line);
  }
  return out;
}

PolylineSet read_obj_polylines(const std::filesystem::path& path) {
  const std::string bytes = read_file_bytes(path);
  return read_obj_polylines_from_string(bytes, path.string());
}

void write_obj_polylines(const PolylineSet& curves, const std::filesystem::path& path) {
  for (std::size_t c = 0; c < curves.size(); ++c) {
    if (curves.curve(c).size() < 2)
      throw Error(
          Status(ErrorCode::kInvalidArgument, path.string() + ": " + curves.describe(c) + " has fewer than 2 points"));
    for (const Vec3d& p : curves.curve(c))
      if (!p.allFinite())
        throw Error(
            Status(ErrorCode::kInvalidArgument, path.string() + ": " + curves.describe(c) + " has a non-finite point"));
  }
  write_atomically(path, [&](AtomicFile& out) {
    std::string s = "# written by Atelier\n";
    for (const Vec3d& p : curves.points) {
      s += "v ";
      append_double(s, p.x());
      s += ' ';
      append_double(s, p.y());
      s += ' ';
      append_double(s, p.z());
      s += '\n';
      if (s.size() > 1u << 15) {
        out.write(s);
        s.clear();
      }
    }
    for (std::size_t c = 0; c < curves.size(); ++c) {
      s += 'l';
      for (std::uint32_t k = curves.offsets[c]; k < curves.offsets[c + 1]; ++k) {
        s += ' ';
        append_uint(s, k + 1u);
      }
      s += '\n';
      if (s.size() > 1u << 15) {
        out.write(s);
        s.clear();
      }
    }
    out.write(s);
  });
}

void write_obj(const Model& m, const std::filesystem::path& path) {
  // Vertex order: by source_vertex (the reader's OBJ index) so a file read
  // and written again lists its vertices in the original order; nodes that
  // came from the same OBJ vertex are written once if they still coincide.
  const auto source = m.nodes.props.find<std::int32_t>("source_vertex");
  std::vector<NodeIdx> live;
  for (std::uint32_t v = 0; v < m.nodes.slots.capacity(); ++v)
    if (m.alive(NodeIdx{v})) live.push_back(NodeIdx{v});
  auto key = [&](NodeIdx v) -> std::int64_t {
    if (source.valid() && source[v] >= 0) return source[v];
    return std::int64_t{std::numeric_limits<std::int32_t>::max()} + 1 + v.value;
  };
  std::stable_sort(live.begin(), live.end(), [&](NodeIdx a, NodeIdx b) { return key(a) < key(b); });
  // Texture coordinates: per face corner when the model has them (the
  // halfedge property "corner_uv", seams kept), else per node (nodes.uv).
  const auto corner_uv = m.halfedges.props.find<Vec2d>("corner_uv");
  const CornerTexcoords vt = corner_uv.valid() ? corner_texcoords(m) : CornerTexcoords{};
  bool has_uv = false;
  if (!corner_uv.valid())
    for (NodeIdx v : live) has_uv |= !m.nodes.uv[v.value].isZero(0.0);

  std::vector<std::uint32_t> obj_index(m.nodes.slots.capacity(), kNone);
  std::vector<NodeIdx> written;  // obj index -> first node written there
  std::size_t run_begin = 0;
  for (std::size_t i = 0; i < live.size(); ++i) {
    const NodeIdx v = live[i];
    if (i > 0 && key(live[i - 1]) != key(v)) run_begin = written.size();
    std::uint32_t same = kNone;
    for (std::size_t w = run_begin; w < written.size() && same == kNone; ++w) {
      const NodeIdx o = written[w];
      if (key(o) == key(v) && std::memcmp(m.nodes.position[o.value].data(), m.nodes.position[v.value].data(), 24) == 0 &&
          std::memcmp(m.nodes.uv[o.value].data(), m.nodes.uv[v.value].data(), 16) == 0)
        same = static_cast<std::uint32_t>(w);
    }
    if (same == kNone) {
      same = static_cast<std::uint32_t>(written.size());
      written.push_back(v);
    }
    obj_index[v.value] = same;
  }

  write_atomically(path, [&](AtomicFile& out) {
    std::string s = "# written by Atelier\n";
    for (NodeIdx v : written) {
      const Vec3d& p = m.nodes.position[v.value];
      require_finite(p, v, path);
      s += "v ";
      append_double(s, p.x());
      s += ' ';
      append_double(s, p.y());
      s += ' ';
      append_double(s, p.z());
      s += '\n';
      if (s.size() > 1u << 15) {
        out.write(s);
        s.clear();
      }
    }
    for (const Vec2d& t : vt.values) {
      s += "vt ";
      append_double(s, t.x());
      s += ' ';
      append_double(s, t.y());
      s += '\n';
      if (s.size() > 1u << 15) {
        out.write(s);
        s.clear();
      }
    }
    if (has_uv)
      for (NodeIdx v : written) {
        s += "vt ";
        append_double(s, m.nodes.uv[v.value].x());
        s += ' ';
        append_double(s, m.nodes.uv[v.value].y());
        s += '\n';
        if (s.size() > 1u << 15) {
          out.write(s);
          s.clear();
        }
      }
    // Faces surface by surface.
    std::vector<std::vector<FaceIdx>> by_surface(m.surfaces.slots.capacity());
    for (std::uint32_t f = 0; f < m.faces.slots.capacity(); ++f)
      if (m.alive(FaceIdx{f})) by_surface[m.faces.surface[f].value].push_back(FaceIdx{f});
    std::vector<HalfedgeIdx> corner_h;
    for (std::uint32_t si = 0; si < m.surfaces.slots.capacity(); ++si) {
      if (!m.alive(SurfaceIdx{si})) continue;
      // A name is one line of text in OBJ: line breaks would start new
      // statements, so they become blanks.
      std::string name = m.surfaces.name[si];
      for (char& ch : name)
        if (ch == '\n' || ch == '\r') ch = ' ';
      s += "g ";
      s += name;
      s += '\n';
      for (FaceIdx f : by_surface[si]) {
        m.face_halfedges(f, corner_h);
        s += 'f';
        for (HalfedgeIdx h : corner_h) {
          const NodeIdx v = m.tail(h);
          s += ' ';
          append_uint(s, obj_index[v.value] + 1u);
          if (has_uv) {
            s += '/';
            append_uint(s, obj_index[v.value] + 1u);
          } else if (!vt.index.empty() && vt.index[h.value] != kNone) {
            s += '/';
            append_uint(s, vt.index[h.value] + 1u);
          }
        }
        s += '\n';
        if (s.size() > 1u << 15) {
          out.write(s);
          s.clear();
        }
      }
    }
    out.write(s);
  });
}

}  // namespace atelier
