#include <atelier/io/off.h>

#include <cmath>
#include <limits>

#include <atelier/io/atomic_file.h>
#include <atelier/io/mesh_arrays.h>

namespace atelier {

using namespace io_detail;

namespace {

/// Non-blank, comment-free lines with their numbers.
class LineSource {
 public:
  explicit LineSource(std::string_view text) : text_(skip_utf8_bom(text)) {}
  bool next(std::vector<std::string_view>& tok) {
    while (pos_ < text_.size()) {
      const std::size_t nl = text_.find('\n', pos_);
      std::string_view l = text_.substr(pos_, nl == std::string_view::npos ? std::string_view::npos : nl - pos_);
      pos_ = nl == std::string_view::npos ? text_.size() : nl + 1;
      ++line_;
      if (const auto h = l.find('#'); h != std::string_view::npos) l = l.substr(0, h);
      split_blanks(l, tok);
      if (!tok.empty()) return true;
    }
    return false;
  }
  [[nodiscard]] std::size_t line() const noexcept { return line_; }

 private:
  std::string_view text_;
  std::size_t pos_ = 0;
  std::size_t line_ = 0;
};

Model read_off_impl(std::string_view text, std::string_view file, std::string surface_name) {
  LineSource src(text);
  std::vector<std::string_view> tok;
  auto fail = [&](const std::string& what) -> Error { return parse_error_at_line(file, src.line(), what); };
  if (!src.next(tok)) throw parse_error_at_line(file, 1, "wrong header: empty file (expected 'OFF')");
  {
    const std::string_view kw = tok[0];
    const bool known = kw == "OFF" || kw == "COFF" || kw == "NOFF" || kw == "CNOFF" || kw == "NCOFF" ||
                       kw == "STOFF" || kw == "STCOFF" || kw == "STNOFF" || kw == "STCNOFF";
    if (!known) {
      if (kw.size() >= 3 && kw.substr(kw.size() - 3) == "OFF")
        throw fail("wrong header: unsupported OFF variant '" + std::string(kw) + "' (4D and nOFF are not read)");
      throw fail("wrong header: expected 'OFF', found '" + std::string(kw) + "'");
    }
  }
  // Counts: on the header line or the next line.
  if (tok.size() == 1 && !src.next(tok)) throw fail("wrong header: missing the vertex/face/edge counts");
  const std::size_t first = tok[0].ends_with("OFF") ? 1 : 0;
  if (tok.size() < first + 2) throw fail("wrong header: expected 'vertex_count face_count edge_count'");
  std::int64_t counts[2];
  for (int k = 0; k < 2; ++k) {
    const auto v = parse_int(tok[first + k]);
    if (!v) throw fail(number_problem(tok[first + k], true) + " in the counts line");
    if (*v < 0) throw fail("negative count " + std::to_string(*v));
    counts[k] = *v;
  }
  const std::int64_t nv = counts[0], nf = counts[1];
  if (nv == 0) throw fail("the header declares no vertex: nothing to read");
  // Every vertex and face needs at least one line of at least two bytes.
  if (static_cast<std::uint64_t>(nv) + static_cast<std::uint64_t>(nf) > text.size() / 2 + 1)
    throw fail("element count mismatch: " + std::to_string(nv) + " vertices and " + std::to_string(nf) +
               " faces cannot fit in the file");

  SurfaceSoup soup;
  soup.name = std::move(surface_name);
  soup.positions.reserve(static_cast<std::size_t>(nv));
  for (std::int64_t i = 0; i < nv; ++i) {
    if (!src.next(tok))
      throw fail("element count mismatch: the file ends after " + std::to_string(i) + " of " + std::to_string(nv) +
                 " vertices");
    if (tok.size() < 3) throw fail("vertex " + std::to_string(i) + " has " + std::to_string(tok.size()) + " coordinates (3 needed)");
    Vec3d p;
    for (int c = 0; c < 3; ++c) {
      const auto v = parse_double(tok[c]);
      if (!v) throw fail(number_problem(tok[c]) + " in vertex " + std::to_string(i));
      if (!std::isfinite(*v)) throw fail("NaN/inf coordinate '" + std::string(tok[c]) + "' in vertex " + std::to_string(i));
      p[c] = *v;
    }
    soup.positions.push_back(p);
  }
  for (std::int64_t i = 0; i < nf; ++i) {
    if (!src.next(tok))
      throw fail("element count mismatch: the file ends after " + std::to_string(i) + " of " + std::to_string(nf) +
                 " faces");
    const auto n = parse_int(tok[0]);
    if (!n) throw fail(number_problem(tok[0], true) + " as the vertex count of face " + std::to_string(i));
    if (*n < 3) throw fail("face " + std::to_string(i) + " has " + std::to_string(*n) + " vertices (at least 3 needed)");
    if (static_cast<std::int64_t>(tok.size()) - 1 < *n)
      throw fail("face " + std::to_string(i) + " declares " + std::to_string(*n) + " vertices but lists " +
                 std::to_string(tok.size() - 1));
    for (std::int64_t c = 1; c <= *n; ++c) {
      const auto idx = parse_int(tok[static_cast<std::size_t>(c)]);
      if (!idx) throw fail(number_problem(tok[static_cast<std::size_t>(c)], true) + " in face " + std::to_string(i));
      if (*idx < 0 || *idx >= nv)
        throw fail("bad index: vertex index " + std::to_string(*idx) + " out of range in face " + std::to_string(i) +
                   " (" + std::to_string(nv) + " vertices)");
      soup.face_nodes.push_back(static_cast<std::uint32_t>(*idx));
    }
    soup.face_offsets.push_back(static_cast<std::uint32_t>(soup.face_nodes.size()));
    soup.face_where.push_back(src.line());
  }
  if (src.next(tok)) throw fail("element count mismatch: more data than the header declares");
  Model m;
  add_soup_surface(m, soup, file, "line");
  return m;
}

}  // namespace

Model read_off_from_string(std::string_view text, std::string_view display_name) {
  return read_off_impl(text, display_name, "off");
}

Model read_off(const std::filesystem::path& path) {
  const std::string bytes = read_file_bytes(path);
  return read_off_impl(bytes, path.string(), path.stem().string());
}

std::size_t write_off(const Model& m, const std::filesystem::path& path) {
  const FlatMesh flat = flatten(m);
  write_atomically(path, [&](AtomicFile& out) {
    std::string s = "OFF\n# written by Atelier\n";
    append_uint(s, flat.nodes.size());
    s += ' ';
    append_uint(s, flat.faces.size());
    s += ' ';
    append_uint(s, m.num_edges());
    s += '\n';
    for (NodeIdx v : flat.nodes) {
      const Vec3d& p = m.nodes.position[v.value];
      require_finite(p, v, path);
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
    for (std::size_t f = 0; f + 1 < flat.face_offsets.size(); ++f) {
      append_uint(s, flat.face_offsets[f + 1] - flat.face_offsets[f]);
      for (std::uint32_t k = flat.face_offsets[f]; k < flat.face_offsets[f + 1]; ++k) {
        s += ' ';
        append_uint(s, flat.face_nodes[k]);
      }
      s += '\n';
      if (s.size() > 1u << 15) {
        out.write(s);
        s.clear();
      }
    }
    out.write(s);
  });
  return m.num_surfaces();
}

}  // namespace atelier
