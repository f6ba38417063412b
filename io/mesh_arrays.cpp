#include <atelier/io/mesh_arrays.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <regex>
#include <sstream>

#include <atelier/storage/builder.h>

namespace atelier::io_detail {

std::string read_file_bytes(const std::filesystem::path& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw Error(Status(ErrorCode::kIo, path.string() + ": is a directory, not a file"));
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(Status(ErrorCode::kIo, path.string() + ": cannot open for reading: " + std::strerror(errno)));
  std::string bytes;
  in.seekg(0, std::ios::end);
  const auto size = in.tellg();
  if (size > 0) {
    bytes.resize(static_cast<std::size_t>(size));
    in.seekg(0, std::ios::beg);
    in.read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  }
  if (in.bad() || (size > 0 && in.gcount() != static_cast<std::streamsize>(bytes.size())))
    throw Error(Status(ErrorCode::kIo, path.string() + ": read failed"));
  return bytes;
}

Error parse_error(std::string_view file, std::string_view where, std::string_view what) {
  std::string msg(file);
  if (!where.empty()) msg.append(": ").append(where);
  msg.append(": ").append(what);
  return Error(Status(ErrorCode::kParse, std::move(msg)));
}

Error parse_error_at_line(std::string_view file, std::size_t line, std::string_view what) {
  return parse_error(file, "line " + std::to_string(line), what);
}

void append_double(std::string& out, double v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  out.append(buf, r.ptr);
}

void append_uint(std::string& out, std::uint64_t v) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  out.append(buf, r.ptr);
}

std::optional<double> parse_double(std::string_view t) noexcept {
  if (!t.empty() && t.front() == '+') t.remove_prefix(1);
  if (t.empty() || t.front() == '+') return std::nullopt;
  double v = 0;
  const auto r = std::from_chars(t.data(), t.data() + t.size(), v);
  if (r.ec == std::errc::result_out_of_range) {
    // from_chars leaves v untouched on "out of range" (it was read as 0
    // before): tell overflow (refused) from underflow (a real number, read
    // as strtod rounds it) with strtod on a copy of the token.
    if (r.ptr != t.data() + t.size()) return std::nullopt;
    const std::string copy(t);
    errno = 0;
    const double s = std::strtod(copy.c_str(), nullptr);
    if (std::isinf(s)) return std::nullopt;
    return s;
  }
  if (r.ec != std::errc() || r.ptr != t.data() + t.size()) return std::nullopt;
  return v;
}

std::optional<std::int64_t> parse_int(std::string_view t) noexcept {
  if (!t.empty() && t.front() == '+') t.remove_prefix(1);
  if (t.empty() || t.front() == '+') return std::nullopt;
  std::int64_t v = 0;
  const auto r = std::from_chars(t.data(), t.data() + t.size(), v);
  if (r.ec != std::errc() || r.ptr != t.data() + t.size()) return std::nullopt;
  return v;
}

std::string number_problem(std::string_view t, bool integer) {
  std::string_view u = t;
  if (!u.empty() && u.front() == '+') u.remove_prefix(1);
  bool out_of_range = false;
  if (integer) {
    std::int64_t v = 0;
    const auto r = std::from_chars(u.data(), u.data() + u.size(), v);
    out_of_range = r.ec == std::errc::result_out_of_range;
  } else {
    double v = 0;
    const auto r = std::from_chars(u.data(), u.data() + u.size(), v);
    out_of_range = r.ec == std::errc::result_out_of_range && r.ptr == u.data() + u.size();
  }
  if (out_of_range)
    return "number '" + std::string(t) + "' is out of range (beyond " + (integer ? "a 64-bit integer" : "a double") + ")";
  return "non-numeric token '" + std::string(t) + "'";
}

std::string_view skip_utf8_bom(std::string_view text) noexcept {
  if (text.size() >= 3 && static_cast<unsigned char>(text[0]) == 0xEF && static_cast<unsigned char>(text[1]) == 0xBB &&
      static_cast<unsigned char>(text[2]) == 0xBF)
    text.remove_prefix(3);
  return text;
}

void split_blanks(std::string_view line, std::vector<std::string_view>& out) {
  out.clear();
  auto blank = [](char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; };
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && blank(line[i])) ++i;
    const std::size_t b = i;
    while (i < line.size() && !blank(line[i])) ++i;
    if (i > b) out.push_back(line.substr(b, i - b));
  }
}

namespace {

/// The faces a builder message names ("face 3", "faces 3 and 5",
/// "faces (3, 5, 8)"), to point the user at their lines in the file.
std::vector<std::uint64_t> faces_named_in(const std::string& msg) {
  std::vector<std::uint64_t> out;
  static const std::regex kFace(R"(faces? \(?([0-9]+)((?:(?:, | and )[0-9]+)*))");
  static const std::regex kNum(R"([0-9]+)");
  for (auto it = std::sregex_iterator(msg.begin(), msg.end(), kFace); it != std::sregex_iterator(); ++it) {
    const std::string all = (*it)[1].str() + (*it)[2].str();
    for (auto n = std::sregex_iterator(all.begin(), all.end(), kNum); n != std::sregex_iterator(); ++n)
      out.push_back(std::stoull(n->str()));
  }
  return out;
}

}  // namespace

void add_soup_surface(Model& m, SurfaceSoup& soup, std::string_view file, std::string_view where_label) {
  const std::uint32_t first = static_cast<std::uint32_t>(m.nodes.slots.capacity());
  const std::uint32_t first_face = static_cast<std::uint32_t>(m.faces.slots.capacity());
  auto made = add_polygon_surface(m, soup.name, soup, ExecContext::sequential());
  if (!made) {
    std::string msg = made.status().message();
    const auto named = faces_named_in(msg);
    std::string where;
    for (std::uint64_t f : named) {
      if (f >= soup.face_where.size()) continue;
      where += where.empty() ? " (" : ", ";
      where += "face " + std::to_string(f) + " is at " + std::string(where_label) + " " +
               std::to_string(soup.face_where[f]);
    }
    if (!where.empty()) msg += where + ")";
    throw parse_error(file, "", msg);
  }
  if (!soup.uv.empty())
    for (std::size_t i = 0; i < soup.uv.size(); ++i) m.nodes.uv[first + i] = soup.uv[i];
  if (!soup.source.empty()) {
    auto prop = m.nodes.props.add<std::int32_t>("source_vertex", -1);
    for (std::size_t i = 0; i < soup.source.size(); ++i) prop[NodeIdx{first + static_cast<std::uint32_t>(i)}] = soup.source[i];
  }
  // Face corners: the builder makes soup face k as face first_face + k, its
  // first halfedge leaving the face's first corner, in corner order.
  if (!soup.corner_uv.empty() || !soup.corner_texcoord.empty()) {
    auto uv = m.halfedges.props.add<Vec2d>("corner_uv", Vec2d::Zero());
    auto src = m.halfedges.props.add<std::int32_t>("source_texcoord", -1);
    for (std::size_t f = 0; f < soup.face_count(); ++f) {
      std::uint32_t k = soup.face_offsets[f];
      m.for_each_face_halfedge(FaceIdx{first_face + static_cast<std::uint32_t>(f)}, [&](HalfedgeIdx h) {
        if (!soup.corner_uv.empty()) uv[h] = soup.corner_uv[k];
        if (!soup.corner_texcoord.empty()) src[h] = soup.corner_texcoord[k];
        ++k;
      });
    }
  }
}

FlatMesh flatten(const Model& m) {
  FlatMesh f;
  const std::size_t nn = m.nodes.slots.capacity();
  f.dense.assign(nn, NodeIdx::kInvalid);
  for (std::uint32_t v = 0; v < nn; ++v)
    if (m.alive(NodeIdx{v})) {
      f.dense[v] = static_cast<std::uint32_t>(f.nodes.size());
      f.nodes.push_back(NodeIdx{v});
    }
  std::vector<NodeIdx> corners;
  for (std::uint32_t i = 0; i < m.faces.slots.capacity(); ++i) {
    const FaceIdx fi{i};
    if (!m.alive(fi)) continue;
    f.faces.push_back(fi);
    m.face_nodes(fi, corners);
    for (NodeIdx v : corners) f.face_nodes.push_back(f.dense[v.value]);
    f.face_offsets.push_back(static_cast<std::uint32_t>(f.face_nodes.size()));
  }
  return f;
}

void require_finite(const Vec3d& p, NodeIdx v, const std::filesystem::path& path) {
  if (p.allFinite()) return;
  std::ostringstream s;
  s << path.string() << ": node " << v.value << " has a non-finite position; refusing to write a file that cannot be read back";
  throw Error(Status(ErrorCode::kInvalidArgument, s.str()));
}

}  // namespace atelier::io_detail
