#include <atelier/io/ply.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <string>

#include <atelier/io/atomic_file.h>
#include <atelier/io/mesh_arrays.h>

namespace atelier {

using namespace io_detail;

namespace {

enum class PlyType : std::uint8_t { kInt8, kUInt8, kInt16, kUInt16, kInt32, kUInt32, kFloat32, kFloat64 };
enum class PlyFormat : std::uint8_t { kAscii, kLittle, kBig };

std::size_t type_size(PlyType t) noexcept {
  switch (t) {
    case PlyType::kInt8: case PlyType::kUInt8: return 1;
    case PlyType::kInt16: case PlyType::kUInt16: return 2;
    case PlyType::kInt32: case PlyType::kUInt32: case PlyType::kFloat32: return 4;
    case PlyType::kFloat64: return 8;
  }
  return 0;
}
bool is_float(PlyType t) noexcept { return t == PlyType::kFloat32 || t == PlyType::kFloat64; }

bool parse_type(std::string_view s, PlyType& t) noexcept {
  struct Name { std::string_view a, b; PlyType t; };
  static constexpr Name kNames[] = {
      {"char", "int8", PlyType::kInt8},       {"uchar", "uint8", PlyType::kUInt8},
      {"short", "int16", PlyType::kInt16},    {"ushort", "uint16", PlyType::kUInt16},
      {"int", "int32", PlyType::kInt32},      {"uint", "uint32", PlyType::kUInt32},
      {"float", "float32", PlyType::kFloat32}, {"double", "float64", PlyType::kFloat64}};
  for (const Name& n : kNames)
    if (s == n.a || s == n.b) {
      t = n.t;
      return true;
    }
  return false;
}

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::kFloat32;
  bool is_list = false;
  PlyType count_type = PlyType::kUInt8;
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> props;
};

struct PlyHeader {
  PlyFormat format = PlyFormat::kAscii;
  std::map<std::int64_t, std::string> surface_names;  // "comment surface <id> <name>"
  std::vector<PlyElement> elements;
  std::size_t data_begin = 0;  // byte offset of the first data byte
  std::size_t data_line = 0;   // line number of the first data line (ascii)
};

PlyHeader parse_header(std::string_view bytes, std::string_view file) {
  PlyHeader h;
  std::size_t pos = 0, line_no = 0;
  bool have_format = false, ended = false;
  std::vector<std::string_view> tok;
  auto fail = [&](const std::string& what) { throw parse_error_at_line(file, line_no, what); };
  while (pos < bytes.size() && !ended) {
    const std::size_t nl = bytes.find('\n', pos);
    if (nl == std::string_view::npos) {
      ++line_no;
      fail("wrong header: it does not end with an 'end_header' line");
    }
    std::string_view l = bytes.substr(pos, nl - pos);
    pos = nl + 1;
    ++line_no;
    if (!l.empty() && l.back() == '\r') l.remove_suffix(1);
    split_blanks(l, tok);
    if (line_no == 1) {
      if (tok.size() != 1 || tok[0] != "ply") fail("wrong header: the file does not start with 'ply'");
      continue;
    }
    if (tok.empty()) continue;
    const std::string_view kw = tok[0];
    if (kw == "comment" && tok.size() >= 3 && tok[1] == "surface") {
      // Our own comment naming a surface id: the rest of the line is the name.
      if (const auto id = parse_int(tok[2])) {
        const std::size_t at = static_cast<std::size_t>(tok[2].data() + tok[2].size() - l.data());
        std::string_view name = l.substr(at);
        while (!name.empty() && (name.front() == ' ' || name.front() == '\t')) name.remove_prefix(1);
        h.surface_names[*id] = std::string(name);
      }
      continue;
    }
    if (kw == "comment" || kw == "obj_info") continue;
    if (kw == "format") {
      if (tok.size() != 3) fail("wrong header: 'format' needs a format name and a version");
      if (tok[1] == "ascii") h.format = PlyFormat::kAscii;
      else if (tok[1] == "binary_little_endian") h.format = PlyFormat::kLittle;
      else if (tok[1] == "binary_big_endian") h.format = PlyFormat::kBig;
      else fail("unknown PLY format '" + std::string(tok[1]) + "'");
      if (tok[2] != "1.0") fail("unsupported PLY version '" + std::string(tok[2]) + "'");
      have_format = true;
    } else if (kw == "element") {
      if (tok.size() != 3) fail("wrong header: 'element' needs a name and a count");
      const auto n = parse_int(tok[2]);
      if (!n || *n < 0) fail("wrong header: element count '" + std::string(tok[2]) + "' is not a non-negative integer");
      h.elements.push_back({std::string(tok[1]), static_cast<std::uint64_t>(*n), {}});
    } else if (kw == "property") {
      if (h.elements.empty()) fail("wrong header: 'property' before any 'element'");
      PlyProperty p;
      if (tok.size() == 5 && tok[1] == "list") {
        p.is_list = true;
        if (!parse_type(tok[2], p.count_type) || !parse_type(tok[3], p.type))
          fail("wrong header: unknown property type in '" + std::string(l) + "'");
        if (is_float(p.count_type)) fail("wrong header: list count type must be an integer type");
        p.name = std::string(tok[4]);
      } else if (tok.size() == 3) {
        if (!parse_type(tok[1], p.type)) fail("wrong header: unknown property type '" + std::string(tok[1]) + "'");
        p.name = std::string(tok[2]);
      } else {
        fail("wrong header: malformed property line '" + std::string(l) + "'");
      }
      h.elements.back().props.push_back(std::move(p));
    } else if (kw == "end_header") {
      ended = true;
    } else {
      fail("wrong header: unknown keyword '" + std::string(kw) + "'");
    }
  }
  if (!ended) {
    ++line_no;
    fail("wrong header: it does not end with an 'end_header' line");
  }
  if (!have_format) fail("wrong header: no 'format' line");
  h.data_begin = pos;
  h.data_line = line_no + 1;
  return h;
}

/// Reads the values of the data section, ascii tokens or binary scalars,
/// and knows where it is for error messages.
class DataReader {
 public:
  DataReader(std::string_view bytes, const PlyHeader& h, std::string_view file)
      : bytes_(bytes), pos_(h.data_begin), line_(h.data_line), format_(h.format), file_(file) {}

  void set_context(const PlyElement* e, std::uint64_t i, const PlyProperty* p) noexcept {
    element_ = e;
    index_ = i;
    prop_ = p;
  }

  [[noreturn]] void fail(const std::string& what) const {
    std::string where = format_ == PlyFormat::kAscii ? "line " + std::to_string(token_line_)
                                                     : "byte offset " + std::to_string(value_pos_);
    if (element_) {
      where += ", element '" + element_->name + "' " + std::to_string(index_);
      if (prop_) where += ", property '" + prop_->name + "'";
    }
    throw parse_error(file_, where, what);
  }

  /// The value of one scalar as a double (integers are exact below 2^53).
  double scalar(PlyType t) {
    if (format_ == PlyFormat::kAscii) {
      const std::string_view tok = next_token(t);
      if (is_float(t)) {
        const auto v = parse_double(tok);
        if (!v) fail(number_problem(tok));
        // A float property holds what a float can: 1e300 would become inf.
        if (t == PlyType::kFloat32 && std::isfinite(*v) && std::abs(*v) > std::numeric_limits<float>::max())
          fail("value " + std::string(tok) + " does not fit the property type (float)");
        return *v;
      }
      const auto v = parse_int(tok);
      if (!v) fail(number_problem(tok, true) + " (an integer is expected)");
      if (!fits(t, *v)) fail("value " + std::string(tok) + " does not fit the property type");
      return static_cast<double>(*v);
    }
    const std::size_t n = type_size(t);
    value_pos_ = pos_;
    if (bytes_.size() - pos_ < n)
      fail("truncated binary file: " + std::to_string(n) + " bytes needed but " + std::to_string(bytes_.size() - pos_) +
           " remain");
    unsigned char b[8];
    std::memcpy(b, bytes_.data() + pos_, n);
    pos_ += n;
    const bool swap = (format_ == PlyFormat::kBig) != (std::endian::native == std::endian::big);
    if (swap) std::reverse(b, b + n);
    switch (t) {
      case PlyType::kInt8: { std::int8_t v; std::memcpy(&v, b, 1); return v; }
      case PlyType::kUInt8: return b[0];
      case PlyType::kInt16: { std::int16_t v; std::memcpy(&v, b, 2); return v; }
      case PlyType::kUInt16: { std::uint16_t v; std::memcpy(&v, b, 2); return v; }
      case PlyType::kInt32: { std::int32_t v; std::memcpy(&v, b, 4); return v; }
      case PlyType::kUInt32: { std::uint32_t v; std::memcpy(&v, b, 4); return v; }
      case PlyType::kFloat32: { float v; std::memcpy(&v, b, 4); return v; }
      case PlyType::kFloat64: { double v; std::memcpy(&v, b, 8); return v; }
    }
    return 0;
  }

  /// An integer value (list counts and indices): floats must be integral.
  std::int64_t integer(PlyType t) {
    const double v = scalar(t);
    if (!(v == std::floor(v)) || std::abs(v) > 9e15) fail("value is not an integer");
    return static_cast<std::int64_t>(v);
  }

  /// Skips one property value (scalar or list).
  void skip(const PlyProperty& p) {
    if (!p.is_list) {
      (void)scalar(p.type);
      return;
    }
    const std::int64_t n = integer(p.count_type);
    if (n < 0) fail("negative list length " + std::to_string(n));
    if (format_ != PlyFormat::kAscii) {
      const std::uint64_t need = static_cast<std::uint64_t>(n) * type_size(p.type);
      value_pos_ = pos_;
      if (bytes_.size() - pos_ < need)
        fail("truncated binary file: list of " + std::to_string(n) + " values needs " + std::to_string(need) +
             " bytes but " + std::to_string(bytes_.size() - pos_) + " remain");
      pos_ += need;
      return;
    }
    for (std::int64_t k = 0; k < n; ++k) (void)scalar(p.type);
  }

  /// After the last element: nothing but blanks may follow (ascii), nothing
  /// at all (binary).
  void expect_end() {
    set_context(nullptr, 0, nullptr);
    if (format_ == PlyFormat::kAscii) {
      skip_blanks();
      if (pos_ < bytes_.size()) {
        token_line_ = line_;
        fail("element count mismatch: more data than the header declares");
      }
    } else if (pos_ < bytes_.size()) {
      value_pos_ = pos_;
      fail("element count mismatch: " + std::to_string(bytes_.size() - pos_) +
           " bytes follow the last element the header declares");
    }
  }

  /// Line (ascii) or byte offset (binary) of the next value.
  [[nodiscard]] std::size_t where() {
    if (format_ == PlyFormat::kAscii) skip_blanks();
    return format_ == PlyFormat::kAscii ? line_ : pos_;
  }

 private:
  static bool fits(PlyType t, std::int64_t v) noexcept {
    switch (t) {
      case PlyType::kInt8: return v >= -128 && v <= 127;
      case PlyType::kUInt8: return v >= 0 && v <= 255;
      case PlyType::kInt16: return v >= -32768 && v <= 32767;
      case PlyType::kUInt16: return v >= 0 && v <= 65535;
      case PlyType::kInt32: return v >= std::numeric_limits<std::int32_t>::min() && v <= std::numeric_limits<std::int32_t>::max();
      case PlyType::kUInt32: return v >= 0 && v <= std::numeric_limits<std::uint32_t>::max();
      default: return true;
    }
  }
  void skip_blanks() {
    while (pos_ < bytes_.size()) {
      const char c = bytes_[pos_];
      if (c == '\n') ++line_;
      else if (c != ' ' && c != '\t' && c != '\r') break;
      ++pos_;
    }
  }
  std::string_view next_token(PlyType) {
    skip_blanks();
    token_line_ = line_;
    if (pos_ >= bytes_.size()) fail("unexpected end of file: the header declares more data (element count mismatch)");
    const std::size_t b = pos_;
    while (pos_ < bytes_.size() && bytes_[pos_] != ' ' && bytes_[pos_] != '\t' && bytes_[pos_] != '\r' &&
           bytes_[pos_] != '\n')
      ++pos_;
    return bytes_.substr(b, pos_ - b);
  }

  std::string_view bytes_;
  std::size_t pos_;
  std::size_t line_;
  std::size_t token_line_ = 0;
  std::size_t value_pos_ = 0;
  PlyFormat format_;
  std::string_view file_;
  const PlyElement* element_ = nullptr;
  std::uint64_t index_ = 0;
  const PlyProperty* prop_ = nullptr;
};

/// A `surface` face property splits the faces into surfaces (ascending
/// ids; names from "comment surface <id> <name>" lines, else
/// "<stem>_<id>"): each surface gets the vertices its faces use, in file
/// order; vertices no face uses go to the first surface.
void split_surfaces(Model& m, const SurfaceSoup& all, const std::vector<std::int64_t>& face_surface,
                    const std::map<std::int64_t, std::string>& names, const std::string& stem, std::string_view file,
                    std::string_view where_label) {
  std::vector<std::int64_t> ids(face_surface);
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  const std::size_t nv = all.positions.size();
  std::vector<std::uint8_t> used(nv, 0);
  for (std::uint32_t v : all.face_nodes) used[v] = 1;
  if (ids.empty()) ids.push_back(0);  // no face: one surface for the vertices
  // Faces bucketed by surface (file order kept): linear in the corners.
  std::vector<std::vector<std::uint32_t>> faces_of(ids.size());
  for (std::size_t f = 0; f < all.face_count(); ++f)
    faces_of[static_cast<std::size_t>(std::lower_bound(ids.begin(), ids.end(), face_surface[f]) - ids.begin())]
        .push_back(static_cast<std::uint32_t>(f));
  std::vector<std::uint32_t> local(nv, std::numeric_limits<std::uint32_t>::max());
  std::vector<std::uint32_t> verts;
  for (std::size_t si = 0; si < ids.size(); ++si) {
    SurfaceSoup s;
    const auto named = names.find(ids[si]);
    s.name = named != names.end() ? named->second : stem + "_" + std::to_string(ids[si]);
    verts.clear();
    for (std::uint32_t f : faces_of[si])
      for (std::uint32_t v : all.face(f)) verts.push_back(v);
    if (si == 0)
      for (std::uint32_t v = 0; v < nv; ++v)
        if (!used[v]) verts.push_back(v);
    std::sort(verts.begin(), verts.end());
    verts.erase(std::unique(verts.begin(), verts.end()), verts.end());
    for (std::uint32_t v : verts) {
      local[v] = static_cast<std::uint32_t>(s.positions.size());
      s.positions.push_back(all.positions[v]);
      if (!all.uv.empty()) s.uv.push_back(all.uv[v]);
    }
    for (std::uint32_t f : faces_of[si]) {
      for (std::uint32_t v : all.face(f)) s.face_nodes.push_back(local[v]);
      s.face_offsets.push_back(static_cast<std::uint32_t>(s.face_nodes.size()));
      s.face_where.push_back(all.face_where[f]);
    }
    add_soup_surface(m, s, file, where_label);
  }
}

Model read_ply_impl(std::string_view bytes, std::string_view file, std::string surface_name) {
  const PlyHeader h = parse_header(bytes, file);
  const PlyElement* vert = nullptr;
  const PlyElement* face = nullptr;
  for (const PlyElement& e : h.elements) {
    if (e.name == "vertex" && !vert) vert = &e;
    if (e.name == "face" && !face) face = &e;
  }
  if (!vert) throw parse_error(file, "header", "wrong header: no 'vertex' element");
  int xyz[3] = {-1, -1, -1}, uvp[2] = {-1, -1};
  for (std::size_t k = 0; k < vert->props.size(); ++k) {
    const PlyProperty& p = vert->props[k];
    const std::string& n = p.name;
    int* slot = n == "x" ? &xyz[0] : n == "y" ? &xyz[1] : n == "z" ? &xyz[2]
              : (n == "u" || n == "s" || n == "texture_u" || n == "texture_s") ? &uvp[0]
              : (n == "v" || n == "t" || n == "texture_v" || n == "texture_t") ? &uvp[1] : nullptr;
    if (slot && *slot < 0 && !p.is_list) *slot = static_cast<int>(k);
  }
  if (vert->count == 0) throw parse_error(file, "header", "element 'vertex' has no vertex: nothing to read");
  if (xyz[0] < 0 || xyz[1] < 0 || xyz[2] < 0)
    throw parse_error(file, "header", "wrong header: element 'vertex' lacks scalar x, y and z properties");
  const bool has_uv = uvp[0] >= 0 && uvp[1] >= 0;
  int list = -1, surface_prop = -1;
  if (face) {
    for (std::size_t k = 0; k < face->props.size(); ++k)
      if (face->props[k].is_list && (face->props[k].name == "vertex_indices" || face->props[k].name == "vertex_index")) {
        list = static_cast<int>(k);
        break;
      }
    if (list < 0) throw parse_error(file, "header", "wrong header: element 'face' has no 'vertex_indices' list");
    for (std::size_t k = 0; k < face->props.size(); ++k)
      if (!face->props[k].is_list && face->props[k].name == "surface" && !is_float(face->props[k].type)) {
        surface_prop = static_cast<int>(k);
        break;
      }
  }

  // Counts come from the file: do not trust them for allocation beyond what
  // the bytes could hold (a corrupt count must not exhaust memory).
  const std::uint64_t max_items = bytes.size() - h.data_begin + 1;
  if (vert->count > max_items || vert->count >= std::numeric_limits<std::uint32_t>::max())
    throw parse_error(file, "header", "element count mismatch: " + std::to_string(vert->count) +
                                          " vertices cannot fit in the " + std::to_string(bytes.size()) + "-byte file");

  SurfaceSoup soup;
  soup.name = surface_name;
  std::vector<std::int64_t> face_surface;  // the `surface` face property, when present
  soup.positions.reserve(vert->count);
  if (has_uv) soup.uv.reserve(vert->count);
  DataReader r(bytes, h, file);
  const std::string_view where_label = h.format == PlyFormat::kAscii ? "line" : "byte offset";
  for (const PlyElement& e : h.elements) {
    const bool is_vert = &e == vert, is_face = &e == face;
    // An element without properties holds no bytes whatever its count: a
    // count of 3.5e15 looped that many times over nothing (found by the ply
    // fuzz harness). Every other element consumes at least a byte per item,
    // so its loop ends at the end of the data.
    if (e.props.empty()) continue;
    for (std::uint64_t i = 0; i < e.count; ++i) {
      Vec3d p = Vec3d::Zero();
      Vec2d t = Vec2d::Zero();
      const std::size_t face_where = r.where();
      for (std::size_t k = 0; k < e.props.size(); ++k) {
        const PlyProperty& prop = e.props[k];
        r.set_context(&e, i, &prop);
        if (is_vert && !prop.is_list) {
          const double v = r.scalar(prop.type);
          const int ki = static_cast<int>(k);
          for (int c = 0; c < 3; ++c)
            if (ki == xyz[c]) {
              if (!std::isfinite(v)) r.fail("NaN/inf coordinate");
              p[c] = v;
            }
          for (int c = 0; c < 2; ++c)
            if (ki == uvp[c]) {
              if (!std::isfinite(v)) r.fail("NaN/inf texture coordinate");
              t[c] = v;
            }
        } else if (is_face && static_cast<int>(k) == list) {
          const std::int64_t n = r.integer(prop.count_type);
          if (n < 0) r.fail("negative list length " + std::to_string(n));
          if (n < 3) r.fail("face has " + std::to_string(n) + " vertices (at least 3 needed)");
          if (static_cast<std::uint64_t>(n) > max_items) r.fail("truncated file: list length " + std::to_string(n) + " exceeds the data");
          for (std::int64_t c = 0; c < n; ++c) {
            const std::int64_t idx = r.integer(prop.type);
            if (idx < 0 || static_cast<std::uint64_t>(idx) >= vert->count)
              r.fail("bad index: vertex index " + std::to_string(idx) + " out of range (" + std::to_string(vert->count) +
                     " vertices)");
            soup.face_nodes.push_back(static_cast<std::uint32_t>(idx));
          }
          if (soup.face_nodes.size() >= std::numeric_limits<std::uint32_t>::max())
            r.fail("too many face corners for 32-bit indices");
          soup.face_offsets.push_back(static_cast<std::uint32_t>(soup.face_nodes.size()));
          soup.face_where.push_back(face_where);
        } else if (is_face && static_cast<int>(k) == surface_prop) {
          face_surface.push_back(r.integer(prop.type));
        } else {
          r.skip(prop);
        }
      }
      if (is_vert) {
        soup.positions.push_back(p);
        if (has_uv) soup.uv.push_back(t);
      }
    }
  }
  r.expect_end();
  Model m;
  if (surface_prop < 0) {
    add_soup_surface(m, soup, file, where_label);
    return m;
  }
  split_surfaces(m, soup, face_surface, h.surface_names, surface_name, file, where_label);
  return m;
}

void put_scalar(std::string& s, const void* v, std::size_t n) {
  const auto* b = static_cast<const char*>(v);
  if constexpr (std::endian::native == std::endian::little) {
    s.append(b, n);
  } else {
    for (std::size_t k = n; k-- > 0;) s.push_back(b[k]);
  }
}

}  // namespace

Model read_ply_from_string(std::string_view bytes, std::string_view display_name) {
  return read_ply_impl(bytes, display_name, "ply");
}

Model read_ply(const std::filesystem::path& path) {
  const std::string bytes = read_file_bytes(path);
  return read_ply_impl(bytes, path.string(), path.stem().string());
}

void write_ply(const Model& m, const std::filesystem::path& path, bool binary) {
  const FlatMesh flat = flatten(m);
  std::uint32_t max_degree = 0;
  for (std::size_t f = 0; f + 1 < flat.face_offsets.size(); ++f)
    max_degree = std::max(max_degree, flat.face_offsets[f + 1] - flat.face_offsets[f]);
  const bool small = max_degree <= 255;
  // Several surfaces: a `surface` face property (the surface's ordinal among
  // the live ones) and one "comment surface <ordinal> <name>" line each, so
  // the reader splits them again instead of merging them into one.
  std::vector<std::int32_t> ordinal(m.surfaces.slots.capacity(), -1);
  std::string surface_comments;
  std::int32_t n_surfaces = 0;
  for (std::uint32_t si = 0; si < m.surfaces.slots.capacity(); ++si) {
    if (!m.alive(SurfaceIdx{si})) continue;
    ordinal[si] = n_surfaces++;
    std::string name = m.surfaces.name[si];
    for (char& ch : name)
      if (ch == '\n' || ch == '\r') ch = ' ';
    surface_comments += "comment surface " + std::to_string(ordinal[si]) + " " + name + "\n";
  }
  const bool multi = n_surfaces > 1;
  write_atomically(path, [&](AtomicFile& out) {
    std::string s = "ply\nformat ";
    s += binary ? "binary_little_endian" : "ascii";
    s += " 1.0\ncomment written by Atelier\n";
    if (multi) s += surface_comments;
    s += "element vertex ";
    append_uint(s, flat.nodes.size());
    s += "\nproperty double x\nproperty double y\nproperty double z\nelement face ";
    append_uint(s, flat.faces.size());
    s += small ? "\nproperty list uchar int vertex_indices\n" : "\nproperty list int int vertex_indices\n";
    if (multi) s += "property int surface\n";
    s += "end_header\n";
    for (NodeIdx v : flat.nodes) {
      const Vec3d& p = m.nodes.position[v.value];
      require_finite(p, v, path);
      for (int c = 0; c < 3; ++c) {
        if (binary) {
          put_scalar(s, &p[c], 8);
        } else {
          if (c) s += ' ';
          append_double(s, p[c]);
        }
      }
      if (!binary) s += '\n';
      if (s.size() > 1u << 15) {
        out.write(s);
        s.clear();
      }
    }
    for (std::size_t f = 0; f + 1 < flat.face_offsets.size(); ++f) {
      const std::uint32_t b = flat.face_offsets[f], e = flat.face_offsets[f + 1];
      if (binary) {
        if (small) {
          s.push_back(static_cast<char>(e - b));
        } else {
          const std::int32_t n = static_cast<std::int32_t>(e - b);
          put_scalar(s, &n, 4);
        }
        for (std::uint32_t k = b; k < e; ++k) {
          const std::int32_t i = static_cast<std::int32_t>(flat.face_nodes[k]);
          put_scalar(s, &i, 4);
        }
        if (multi) put_scalar(s, &ordinal[m.faces.surface[flat.faces[f].value].value], 4);
      } else {
        append_uint(s, e - b);
        for (std::uint32_t k = b; k < e; ++k) {
          s += ' ';
          append_uint(s, flat.face_nodes[k]);
        }
        if (multi) {
          s += ' ';
          s += std::to_string(ordinal[m.faces.surface[flat.faces[f].value].value]);
        }
        s += '\n';
      }
      if (s.size() > 1u << 15) {
        out.write(s);
        s.clear();
      }
    }
    out.write(s);
  });
}

}  // namespace atelier
