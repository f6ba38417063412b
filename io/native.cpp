#include <atelier/io/native.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cstring>
#include <limits>
#include <tuple>
#include <type_traits>

#include <atelier/io/atomic_file.h>
#include <atelier/io/checksum.h>
#include <atelier/io/mesh_arrays.h>
#include <atelier/storage/validate.h>

namespace atelier {

using namespace io_detail;

namespace {

constexpr char kMagic[8] = {'A', 'T', 'E', 'L', 'I', 'E', 'R', '\x1a'};
constexpr std::uint32_t kVersion = 2;  // 1: no halfedge properties (still read)
constexpr std::uint32_t kInvalid = std::numeric_limits<std::uint32_t>::max();

constexpr std::uint32_t tag(const char (&s)[5]) {
  return std::uint32_t(std::uint8_t(s[0])) | std::uint32_t(std::uint8_t(s[1])) << 8 |
         std::uint32_t(std::uint8_t(s[2])) << 16 | std::uint32_t(std::uint8_t(s[3])) << 24;
}
constexpr std::array<std::uint32_t, 11> kSections = {tag("HEAD"), tag("NODE"), tag("EDGE"), tag("FACE"),
                                                     tag("SURF"), tag("MEDG"), tag("LOOP"), tag("JOIN"),
                                                     tag("ATND"), tag("ATED"), tag("PROP")};
std::string tag_name(std::uint32_t t) {
  std::string s(4, ' ');
  for (int k = 0; k < 4; ++k) {
    const char c = static_cast<char>((t >> (8 * k)) & 0xff);
    s[static_cast<std::size_t>(k)] = (c >= 32 && c < 127) ? c : '?';
  }
  return s;
}

// ------------------------------------------------------------------ writing

class Out {
 public:
  template <class T>
  void put(T v) {
    static_assert(std::is_trivially_copyable_v<T> && std::is_arithmetic_v<T>);
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    if constexpr (std::endian::native == std::endian::big) std::reverse(b, b + sizeof(T));
    s_.append(b, sizeof(T));
  }
  template <class Tag>
  void put(Idx<Tag> i) {
    put<std::uint32_t>(i.value);
  }
  void put(const Vec3d& v) { put(v.x()), put(v.y()), put(v.z()); }
  void put(const Vec2d& v) { put(v.x()), put(v.y()); }
  void put(const std::string& s) {
    put<std::uint32_t>(static_cast<std::uint32_t>(s.size()));
    s_.append(s);
  }
  template <class T>
  void column(const std::vector<T>& c) {
    for (const T& v : c) put(v);
  }
  template <class T, class F>
  void ragged(const RaggedColumn<T>& r, F&& put_value) {
    for (std::size_t i = 0; i < r.rows(); ++i) put<std::uint32_t>(static_cast<std::uint32_t>(r.size(i)));
    for (std::size_t i = 0; i < r.rows(); ++i)
      for (const T& v : r.row(i)) put_value(*this, v);
  }
  std::string& str() { return s_; }

 private:
  std::string s_;
};

// Property columns of these types are written; each has a one-byte tag.
using PropTypes = std::tuple<std::int8_t, std::uint8_t, std::int16_t, std::uint16_t, std::int32_t, std::uint32_t,
                             std::int64_t, std::uint64_t, float, double, Vec2d, Vec3d>;

template <class Tag, std::size_t K = 0>
bool write_prop(Out& o, const PropertyRegistry<Tag>& reg, const std::string& name) {
  if constexpr (K == std::tuple_size_v<PropTypes>) {
    return false;
  } else {
    using T = std::tuple_element_t<K, PropTypes>;
    const auto p = reg.template find<T>(name);
    if (!p.valid()) return write_prop<Tag, K + 1>(o, reg, name);
    o.put(name);
    o.put<std::uint8_t>(static_cast<std::uint8_t>(K));
    o.put<std::uint64_t>(p.vector().size());
    o.column(p.vector());
    return true;
  }
}

template <class Tag>
void write_props(Out& o, const PropertyRegistry<Tag>& reg) {
  Out body;
  std::uint32_t n = 0;
  for (const std::string& name : reg.names()) n += write_prop(body, reg, name) ? 1 : 0;
  o.put<std::uint32_t>(n);
  o.str() += body.str();
}

void add_section(Out& file, std::uint32_t t, Out& payload) {
  file.put<std::uint32_t>(t);
  file.put<std::uint64_t>(payload.str().size());
  file.put<std::uint32_t>(crc32(payload.str()));
  file.str() += payload.str();
}

bool has_tombstones(const Model& m) {
  return m.nodes.slots.capacity() != m.nodes.slots.size() || m.edges.slots.capacity() != m.edges.slots.size() ||
         m.faces.slots.capacity() != m.faces.slots.size() || m.surfaces.slots.capacity() != m.surfaces.slots.size() ||
         m.mesh_edges.slots.capacity() != m.mesh_edges.slots.size() ||
         m.mesh_loops.slots.capacity() != m.mesh_loops.slots.size() ||
         m.joints.slots.capacity() != m.joints.slots.size() ||
         m.attrib_nodes.slots.capacity() != m.attrib_nodes.slots.size() ||
         m.attrib_edges.slots.capacity() != m.attrib_edges.slots.size();
}

std::string serialize_compact(const Model& m) {
  Out file;
  file.str().append(kMagic, 8);
  file.put<std::uint32_t>(kVersion);
  file.put<std::uint32_t>(static_cast<std::uint32_t>(kSections.size()));
  const std::size_t nn = m.nodes.slots.capacity(), ne = m.edges.slots.capacity(), nf = m.faces.slots.capacity();
  {
    Out o;
    o.put<std::int64_t>(m.complex_holes);
    for (std::size_t n :
         {nn, ne, nf, m.surfaces.slots.capacity(), m.mesh_edges.slots.capacity(), m.mesh_loops.slots.capacity(),
          m.joints.slots.capacity(), m.attrib_nodes.slots.capacity(), m.attrib_edges.slots.capacity()})
      o.put<std::uint64_t>(n);
    add_section(file, kSections[0], o);
  }
  {
    Out o;
    o.column(m.nodes.position);
    o.column(m.nodes.position_backup);
    o.column(m.nodes.uv);
    o.column(m.nodes.out);
    o.column(m.nodes.surface);
    o.column(m.nodes.in_face);
    add_section(file, kSections[1], o);
  }
  {
    Out o;
    o.column(m.edges.flags);
    o.column(m.edges.mesh_edge);
    o.column(m.halfedges.tail);
    o.column(m.halfedges.face);
    o.column(m.halfedges.next);
    o.column(m.halfedges.prev);
    o.column(m.halfedges.vnext);
    o.column(m.halfedges.vprev);
    add_section(file, kSections[2], o);
  }
  {
    Out o;
    o.column(m.faces.halfedge);
    o.column(m.faces.surface);
    o.column(m.faces.flags);
    add_section(file, kSections[3], o);
  }
  {
    Out o;
    o.column(m.surfaces.flags);
    for (const std::string& s : m.surfaces.name) o.put(s);
    add_section(file, kSections[4], o);
  }
  {
    Out o;
    o.column(m.mesh_edges.surface);
    o.column(m.mesh_edges.loop);
    o.column(m.mesh_edges.joint);
    o.ragged(m.mesh_edges.halfedges, [](Out& x, HalfedgeIdx h) { x.put(h); });
    add_section(file, kSections[5], o);
  }
  {
    Out o;
    o.column(m.mesh_loops.surface);
    o.ragged(m.mesh_loops.mesh_edges, [](Out& x, MeshEdgeIdx e) { x.put(e); });
    add_section(file, kSections[6], o);
  }
  {
    Out o;
    o.ragged(m.joints.members, [](Out& x, const JointMember& j) {
      x.put(j.mesh_edge);
      x.put<std::uint8_t>(j.positive ? 1 : 0);
    });
    add_section(file, kSections[7], o);
  }
  {
    Out o;
    const auto& a = m.attrib_nodes;
    for (AttribNodeKind k : a.kind) o.put<std::uint8_t>(static_cast<std::uint8_t>(k));
    o.column(a.element);
    o.column(a.corner);
    o.column(a.param);
    o.column(a.position);
    o.column(a.owner);
    o.column(a.surface);
    add_section(file, kSections[8], o);
  }
  {
    Out o;
    o.column(m.attrib_edges.surface);
    o.column(m.attrib_edges.feature_id);
    o.ragged(m.attrib_edges.nodes, [](Out& x, AttribNodeIdx n) { x.put(n); });
    add_section(file, kSections[9], o);
  }
  {
    Out o;
    write_props(o, m.nodes.props);
    write_props(o, m.edges.props);
    write_props(o, m.faces.props);
    write_props(o, m.surfaces.props);
    write_props(o, m.attrib_edges.props);
    write_props(o, m.halfedges.props);  // version 2
    add_section(file, kSections[10], o);
  }
  return std::move(file.str());
}

// ------------------------------------------------------------------ reading

class In {
 public:
  In(std::string_view bytes, std::size_t base, std::string_view file, std::string section)
      : b_(bytes), base_(base), file_(file), section_(std::move(section)) {}

  [[noreturn]] void fail(const std::string& what) const {
    throw parse_error(file_, "section '" + section_ + "' at byte offset " + std::to_string(base_ + pos_), what);
  }
  void need(std::uint64_t n, const char* what) const {
    if (b_.size() - pos_ < n)
      fail(std::string("truncated ") + what + ": " + std::to_string(n) + " bytes needed, " +
           std::to_string(b_.size() - pos_) + " left in the section");
  }
  /// A count of items of at least `each` bytes must fit in what is left:
  /// checked before allocating so a corrupt count cannot exhaust memory.
  void need_items(std::uint64_t count, std::uint64_t each, const char* what) const {
    if (count > (b_.size() - pos_) / std::max<std::uint64_t>(each, 1))
      fail(std::string("element count mismatch: ") + std::to_string(count) + " " + what + " do not fit in the " +
           std::to_string(b_.size() - pos_) + " bytes left in the section");
  }

  template <class T>
  T get(const char* what = "value") {
    need(sizeof(T), what);
    char b[sizeof(T)];
    std::memcpy(b, b_.data() + pos_, sizeof(T));
    if constexpr (std::endian::native == std::endian::big) std::reverse(b, b + sizeof(T));
    pos_ += sizeof(T);
    T v;
    std::memcpy(&v, b, sizeof(T));
    return v;
  }
  template <class T>
  void get_into(T& v) {
    if constexpr (std::is_same_v<T, Vec3d>) {
      // Sequenced reads: argument evaluation order is unspecified.
      const double x = get<double>();
      const double y = get<double>();
      v = Vec3d(x, y, get<double>());
    } else if constexpr (std::is_same_v<T, Vec2d>) {
      const double x = get<double>();
      v = Vec2d(x, get<double>());
    } else if constexpr (requires { v.value; }) {
      v = T{get<std::uint32_t>()};
    } else {
      v = get<T>();
    }
  }
  template <class T>
  void column(std::vector<T>& c, std::size_t n) {
    need_items(n, wire_size<T>(), "values");
    c.resize(n);
    for (auto& v : c) get_into(v);
  }
  std::string string() {
    const auto n = get<std::uint32_t>("string length");
    need(n, "string");
    std::string s(b_.substr(pos_, n));
    pos_ += n;
    return s;
  }
  /// Ragged column: sizes then values.
  template <class T, class F>
  void ragged(RaggedColumn<T>& r, std::size_t rows, std::size_t value_bytes, F&& get_value) {
    need_items(rows, 4, "rows");
    std::vector<std::uint32_t> sizes(rows);
    std::uint64_t total = 0;
    for (auto& s : sizes) total += (s = get<std::uint32_t>("row size"));
    need_items(total, value_bytes, "list values");
    r.clear();
    r.resize_rows(rows);
    std::vector<T> row;
    for (std::size_t i = 0; i < rows; ++i) {
      row.clear();
      for (std::uint32_t k = 0; k < sizes[i]; ++k) row.push_back(get_value(*this));
      r.assign(i, row);
    }
  }
  void expect_end() const {
    if (pos_ != b_.size()) fail("section has " + std::to_string(b_.size() - pos_) + " unexpected trailing bytes");
  }
  [[nodiscard]] std::size_t left() const noexcept { return b_.size() - pos_; }

  template <class T>
  static constexpr std::size_t wire_size() {
    if constexpr (std::is_same_v<T, Vec3d>)
      return 24;
    else if constexpr (std::is_same_v<T, Vec2d>)
      return 16;
    else if constexpr (requires(T t) { t.value; })
      return 4;
    else
      return sizeof(T);
  }

 private:
  std::string_view b_;
  std::size_t pos_ = 0;
  std::size_t base_;
  std::string_view file_;
  std::string section_;
};

template <class Tag, std::size_t K = 0>
void read_prop_column(In& in, PropertyRegistry<Tag>& reg, const std::string& name, std::uint8_t type,
                      std::size_t rows) {
  if constexpr (K == std::tuple_size_v<PropTypes>) {
    in.fail("unknown property type tag " + std::to_string(type) + " for property '" + name + "'");
  } else {
    if (type != K) return read_prop_column<Tag, K + 1>(in, reg, name, type, rows);
    using T = std::tuple_element_t<K, PropTypes>;
    if (reg.contains(name)) in.fail("property '" + name + "' appears twice");
    auto p = reg.template add<T>(name);
    in.column(p.vector(), rows);
  }
}

template <class Tag>
void read_props(In& in, PropertyRegistry<Tag>& reg, std::size_t rows, const char* table) {
  const auto n = in.get<std::uint32_t>("property count");
  for (std::uint32_t k = 0; k < n; ++k) {
    const std::string name = in.string();
    const auto type = in.get<std::uint8_t>("property type");
    const auto size = in.get<std::uint64_t>("property size");
    if (size != rows)
      in.fail(std::string("element count mismatch: ") + table + " property '" + name + "' has " + std::to_string(size) +
              " values for " + std::to_string(rows) + " rows");
    read_prop_column(in, reg, name, type, rows);
  }
}

/// Every stored index must be invalid (when allowed) or address a row.
template <class T>
void check_refs(const In& in, const std::vector<T>& col, std::size_t limit, bool may_be_invalid, const char* what) {
  for (std::size_t i = 0; i < col.size(); ++i) {
    const std::uint32_t v = col[i].value;
    if (v == kInvalid ? !may_be_invalid : v >= limit)
      in.fail("bad index: " + std::string(what) + " " + std::to_string(i) + " refers to " +
              (v == kInvalid ? std::string("nothing") : std::to_string(v)) + " (" + std::to_string(limit) + " rows)");
  }
}
template <class T>
void check_ragged_refs(const In& in, const RaggedColumn<T>& r, std::size_t limit, const char* what) {
  for (std::size_t i = 0; i < r.rows(); ++i)
    for (const T& v : r.row(i))
      if (v.value >= limit)
        in.fail("bad index: " + std::string(what) + " list " + std::to_string(i) + " refers to " +
                std::to_string(v.value) + " (" + std::to_string(limit) + " rows)");
}

Model deserialize_impl(std::string_view bytes, std::string_view file) {
  if (bytes.size() < 16 || std::memcmp(bytes.data(), kMagic, 8) != 0)
    throw parse_error(file, "byte offset 0", "wrong header: not an Atelier model file (bad magic)");
  In head(bytes.substr(8, 8), 8, file, "file header");
  const auto version = head.get<std::uint32_t>();
  const auto nsec = head.get<std::uint32_t>();
  if (version != 1 && version != kVersion)
    throw parse_error(file, "byte offset 8",
                      "unsupported version " + std::to_string(version) + " (this reader knows 1 and " +
                          std::to_string(kVersion) + ")");
  if (nsec != kSections.size())
    throw parse_error(
        file, "byte offset 12",
        "wrong header: " + std::to_string(nsec) + " sections, expected " + std::to_string(kSections.size()));
  // Split and checksum every section first: nothing is built from bytes
  // that fail their CRC.
  std::vector<In> sec;
  std::size_t pos = 16;
  for (std::uint32_t want : kSections) {
    if (bytes.size() - pos < 16)
      throw parse_error(file, "byte offset " + std::to_string(pos),
                        "truncated file: section '" + tag_name(want) + "' header is missing");
    In h(bytes.substr(pos, 16), pos, file, "header of " + tag_name(want));
    const auto t = h.get<std::uint32_t>();
    const auto size = h.get<std::uint64_t>();
    const auto crc = h.get<std::uint32_t>();
    if (t != want)
      throw parse_error(file, "byte offset " + std::to_string(pos),
                        "wrong section: found '" + tag_name(t) + "' where '" + tag_name(want) + "' belongs");
    pos += 16;
    if (size > bytes.size() - pos)
      throw parse_error(file, "byte offset " + std::to_string(pos),
                        "truncated file: section '" + tag_name(want) + "' declares " + std::to_string(size) +
                            " bytes but only " + std::to_string(bytes.size() - pos) + " remain");
    const std::string_view payload = bytes.substr(pos, size);
    if (crc32(payload) != crc)
      throw parse_error(file, "byte offset " + std::to_string(pos),
                        "checksum mismatch in section '" + tag_name(want) + "' (the file is corrupted)");
    sec.emplace_back(payload, pos, file, tag_name(want));
    pos += size;
  }
  if (pos != bytes.size())
    throw parse_error(file, "byte offset " + std::to_string(pos),
                      std::to_string(bytes.size() - pos) + " unexpected bytes after the last section");

  Model m;
  In& hd = sec[0];
  m.complex_holes = hd.get<std::int64_t>();
  std::uint64_t n[9];
  for (auto& x : n) {
    x = hd.get<std::uint64_t>("table size");
    if (x >= kInvalid / 2) hd.fail("table size " + std::to_string(x) + " is too large");
  }
  hd.expect_end();
  const std::size_t nn = n[0], ne = n[1], nf = n[2], ns = n[3], nme = n[4], nl = n[5], nj = n[6], nan = n[7],
                    nae = n[8];
  const std::size_t nh = 2 * ne;

  // Columns are read into the model's own vectors; slots come last, once
  // every size is known to be right.
  {
    In& s = sec[1];
    s.need_items(nn, 76, "nodes");
    s.column(m.nodes.position, nn);
    s.column(m.nodes.position_backup, nn);
    s.column(m.nodes.uv, nn);
    s.column(m.nodes.out, nn);
    s.column(m.nodes.surface, nn);
    s.column(m.nodes.in_face, nn);
    s.expect_end();
    check_refs(s, m.nodes.out, nh, true, "node outgoing halfedge of node");
    check_refs(s, m.nodes.surface, ns, false, "surface of node");
    check_refs(s, m.nodes.in_face, nf, true, "in_face of node");
  }
  {
    In& s = sec[2];
    s.need_items(ne, 5 + 2 * 24, "edges");  // 53 bytes per edge
    s.column(m.edges.flags, ne);
    s.column(m.edges.mesh_edge, ne);
    s.column(m.halfedges.tail, nh);
    s.column(m.halfedges.face, nh);
    s.column(m.halfedges.next, nh);
    s.column(m.halfedges.prev, nh);
    s.column(m.halfedges.vnext, nh);
    s.column(m.halfedges.vprev, nh);
    s.expect_end();
    check_refs(s, m.edges.mesh_edge, nme, true, "mesh edge of edge");
    check_refs(s, m.halfedges.tail, nn, false, "tail of halfedge");
    check_refs(s, m.halfedges.face, nf, true, "face of halfedge");
    check_refs(s, m.halfedges.next, nh, true, "next of halfedge");
    check_refs(s, m.halfedges.prev, nh, true, "prev of halfedge");
    check_refs(s, m.halfedges.vnext, nh, false, "vnext of halfedge");
    check_refs(s, m.halfedges.vprev, nh, false, "vprev of halfedge");
  }
  {
    In& s = sec[3];
    s.need_items(nf, 9, "faces");
    s.column(m.faces.halfedge, nf);
    s.column(m.faces.surface, nf);
    s.column(m.faces.flags, nf);
    s.expect_end();
    check_refs(s, m.faces.halfedge, nh, false, "halfedge of face");
    check_refs(s, m.faces.surface, ns, false, "surface of face");
  }
  {
    In& s = sec[4];
    s.need_items(ns, 5, "surfaces");
    s.column(m.surfaces.flags, ns);
    m.surfaces.name.resize(ns);
    for (auto& name : m.surfaces.name) name = s.string();
    s.expect_end();
  }
  {
    In& s = sec[5];
    auto& t = m.mesh_edges;
    s.need_items(nme, 16, "mesh edges");
    s.column(t.surface, nme);
    s.column(t.loop, nme);
    s.column(t.joint, nme);
    s.ragged(t.halfedges, nme, 4, [](In& x) { return HalfedgeIdx{x.get<std::uint32_t>()}; });
    s.expect_end();
    check_refs(s, t.surface, ns, false, "surface of mesh edge");
    check_refs(s, t.loop, nl, true, "loop of mesh edge");
    check_refs(s, t.joint, nj, true, "joint of mesh edge");
    check_ragged_refs(s, t.halfedges, nh, "mesh edge halfedge");
  }
  {
    In& s = sec[6];
    s.need_items(nl, 8, "mesh loops");
    s.column(m.mesh_loops.surface, nl);
    s.ragged(m.mesh_loops.mesh_edges, nl, 4, [](In& x) { return MeshEdgeIdx{x.get<std::uint32_t>()}; });
    s.expect_end();
    check_refs(s, m.mesh_loops.surface, ns, false, "surface of mesh loop");
    check_ragged_refs(s, m.mesh_loops.mesh_edges, nme, "mesh loop");
  }
  {
    In& s = sec[7];
    s.ragged(m.joints.members, nj, 5, [](In& x) {
      JointMember j;
      j.mesh_edge = MeshEdgeIdx{x.get<std::uint32_t>()};
      const auto flag = x.get<std::uint8_t>("direction flag");
      if (flag > 1) x.fail("joint direction flag " + std::to_string(flag) + " is not 0 or 1");
      j.positive = flag == 1;
      return j;
    });
    s.expect_end();
    for (std::size_t i = 0; i < nj; ++i)
      for (const JointMember& j : m.joints.members.row(i))
        if (j.mesh_edge.value >= nme)
          s.fail("bad index: joint " + std::to_string(i) + " refers to mesh edge " + std::to_string(j.mesh_edge.value) +
                 " (" + std::to_string(nme) + " rows)");
  }
  {
    In& s = sec[8];
    auto& a = m.attrib_nodes;
    s.need_items(nan, 62, "attribute nodes");
    std::vector<std::uint8_t> kinds;
    s.column(kinds, nan);
    a.kind.resize(nan);
    for (std::size_t i = 0; i < nan; ++i) {
      if (kinds[i] > 2) s.fail("attribute node " + std::to_string(i) + " has unknown kind " + std::to_string(kinds[i]));
      a.kind[i] = static_cast<AttribNodeKind>(kinds[i]);
    }
    s.column(a.element, nan);
    s.column(a.corner, nan);
    s.column(a.param, nan);
    s.column(a.position, nan);
    s.column(a.owner, nan);
    s.column(a.surface, nan);
    s.expect_end();
    check_refs(s, a.owner, nae, true, "owner of attribute node");
    check_refs(s, a.surface, ns, false, "surface of attribute node");
    // element is checked against its kind's table by validate(), which
    // bounds-checks before it dereferences.
  }
  {
    In& s = sec[9];
    auto& t = m.attrib_edges;
    s.need_items(nae, 12, "attribute edges");
    s.column(t.surface, nae);
    s.column(t.feature_id, nae);
    s.ragged(t.nodes, nae, 4, [](In& x) { return AttribNodeIdx{x.get<std::uint32_t>()}; });
    s.expect_end();
    check_refs(s, t.surface, ns, false, "surface of attribute edge");
    check_ragged_refs(s, t.nodes, nan, "attribute edge");
  }

  // Slots: all alive, generation 0, as after compact().
  (void)m.nodes.slots.append_bulk(nn);
  (void)m.edges.slots.append_bulk(ne);
  (void)m.faces.slots.append_bulk(nf);
  (void)m.surfaces.slots.append_bulk(ns);
  (void)m.mesh_edges.slots.append_bulk(nme);
  (void)m.mesh_loops.slots.append_bulk(nl);
  (void)m.joints.slots.append_bulk(nj);
  (void)m.attrib_nodes.slots.append_bulk(nan);
  (void)m.attrib_edges.slots.append_bulk(nae);
  m.nodes.props.resize(nn);
  m.edges.props.resize(ne);
  m.faces.props.resize(nf);
  m.surfaces.props.resize(ns);
  m.attrib_edges.props.resize(nae);
  m.halfedges.props.resize(2 * ne);
  {
    In& s = sec[10];
    read_props(s, m.nodes.props, nn, "node");
    read_props(s, m.edges.props, ne, "edge");
    read_props(s, m.faces.props, nf, "face");
    read_props(s, m.surfaces.props, ns, "surface");
    read_props(s, m.attrib_edges.props, nae, "attribute edge");
    if (version >= 2) read_props(s, m.halfedges.props, 2 * ne, "halfedge");
    s.expect_end();
  }
  ++m.topology_version;
  if (Status st = validate(m); !st) throw parse_error(file, "", "the model read is not valid: " + st.message());
  return m;
}

}  // namespace

std::string serialize_model(const Model& m) {
  if (!has_tombstones(m)) return serialize_compact(m);
  Model c = m;
  (void)c.compact();
  return serialize_compact(c);
}

Model deserialize_model(std::string_view bytes, std::string_view display_name) {
  return deserialize_impl(bytes, display_name);
}

void write_model(const Model& m, const std::filesystem::path& path) {
  const std::string bytes = serialize_model(m);
  write_atomically(path, [&](AtomicFile& out) { out.write(bytes); });
}

Model read_model(const std::filesystem::path& path) {
  const std::string bytes = read_file_bytes(path);
  return deserialize_impl(bytes, path.string());
}

}  // namespace atelier
