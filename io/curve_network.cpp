#include <atelier/io/curve_network.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>

#include <atelier/io/atomic_file.h>
#include <atelier/io/mesh_arrays.h>
#include <atelier/io/obj.h>

namespace atelier {

using namespace io_detail;

void PolylineSet::add(std::int64_t id, std::span<const Vec3d> pts, std::uint64_t line) {
  points.insert(points.end(), pts.begin(), pts.end());
  offsets.push_back(static_cast<std::uint32_t>(points.size()));
  ids.push_back(id);
  lines.push_back(line);
}

std::string PolylineSet::describe(std::size_t c) const {
  std::string s = "CURVE " + std::to_string(c < ids.size() ? ids[c] : static_cast<std::int64_t>(c));
  const std::uint64_t line = c < lines.size() ? lines[c] : 0;
  if (!source.empty() && line > 0)
    s += " (" + source + ": line " + std::to_string(line) + ")";
  else if (!source.empty())
    s += " (" + source + ")";
  else if (line > 0)
    s += " (line " + std::to_string(line) + ")";
  return s;
}

namespace {

Status fail(std::string_view file, std::size_t line, const std::string& what) {
  return Status(ErrorCode::kParse, std::string(file) + ": line " + std::to_string(line) + ": " + what);
}

}  // namespace

Expected<PolylineSet> parse_curve_network(std::string_view text, std::string_view display_name) {
  PolylineSet out;
  out.source = std::string(display_name);
  std::unordered_map<std::int64_t, std::uint64_t> seen;  // id -> header line
  std::vector<std::string_view> tok;
  std::size_t pos = 0, line_no = 0;
  bool open = false;  // a header was read
  auto close_curve = [&]() -> Status {
    if (!open) return {};
    const std::size_t c = out.size() - 1;
    if (out.curve(c).size() < 2)
      return Status(ErrorCode::kParse, out.describe(c) + " has " + std::to_string(out.curve(c).size()) + " point" +
                                           (out.curve(c).size() == 1 ? "" : "s") + " (at least 2 needed)");
    return {};
  };
  while (pos < text.size()) {
    const std::size_t nl = text.find('\n', pos);
    std::string_view l = text.substr(pos, nl == std::string_view::npos ? std::string_view::npos : nl - pos);
    pos = nl == std::string_view::npos ? text.size() : nl + 1;
    ++line_no;
    if (const auto hash = l.find('#'); hash != std::string_view::npos) l = l.substr(0, hash);
    split_blanks(l, tok);
    if (tok.empty()) continue;
    if (tok[0] == "CURVE") {
      if (Status s = close_curve(); !s) return s;
      if (tok.size() != 2) return fail(display_name, line_no, "a curve header is `CURVE <integer id>`");
      const auto id = parse_int(tok[1]);
      if (!id) return fail(display_name, line_no, "curve id '" + std::string(tok[1]) + "' is not an integer");
      if (const auto [it, fresh] = seen.emplace(*id, line_no); !fresh)
        return fail(display_name, line_no,
                    "CURVE " + std::to_string(*id) + " repeats the id of line " + std::to_string(it->second));
      out.offsets.push_back(out.offsets.back());
      out.ids.push_back(*id);
      out.lines.push_back(line_no);
      open = true;
      continue;
    }
    if (!open) return fail(display_name, line_no, "a point before the first `CURVE <id>` header");
    const std::string curve = "CURVE " + std::to_string(out.ids.back());
    if (tok.size() != 3)
      return fail(display_name, line_no,
                  curve + ": a point has " + std::to_string(tok.size()) + " values (x y z needed)");
    Vec3d p;
    for (int k = 0; k < 3; ++k) {
      const auto v = parse_double(tok[static_cast<std::size_t>(k)]);
      if (!v)
        return fail(display_name, line_no,
                    curve + ": non-numeric token '" + std::string(tok[static_cast<std::size_t>(k)]) + "'");
      if (!std::isfinite(*v))
        return fail(display_name, line_no,
                    curve + ": NaN/inf coordinate '" + std::string(tok[static_cast<std::size_t>(k)]) + "'");
      p[k] = *v;
    }
    if (out.points.size() >= std::numeric_limits<std::uint32_t>::max() - 1)
      return fail(display_name, line_no, "more than 2^32 - 2 points");
    out.points.push_back(p);
    out.offsets.back() = static_cast<std::uint32_t>(out.points.size());
  }
  if (Status s = close_curve(); !s) return s;
  if (out.size() == 0)
    return Status(ErrorCode::kParse, std::string(display_name) + ": no curve (`CURVE <id>` header) in the file");
  return out;
}

PolylineSet read_curve_network(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext == ".obj") return read_obj_polylines(path);
  const std::string bytes = read_file_bytes(path);
  auto r = parse_curve_network(bytes, path.string());
  if (!r) throw Error(r.status());
  return std::move(r).value();
}

void write_curve_network(const PolylineSet& curves, const std::filesystem::path& path) {
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
    std::string s;
    for (std::size_t c = 0; c < curves.size(); ++c) {
      s += "CURVE ";
      s += std::to_string(c < curves.ids.size() ? curves.ids[c] : static_cast<std::int64_t>(c));
      s += '\n';
      for (const Vec3d& p : curves.curve(c)) {
        append_double(s, p.x());
        s += ' ';
        append_double(s, p.y());
        s += ' ';
        append_double(s, p.z());
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
