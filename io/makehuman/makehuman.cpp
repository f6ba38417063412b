#include <atelier/io/makehuman/makehuman.h>

#include <charconv>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include <atelier/engine/status.h>

namespace atelier::makehuman {

namespace {

[[noreturn]] void parse_error(const std::filesystem::path& f, std::size_t line, const std::string& what) {
  std::ostringstream s;
  s << f.string();
  if (line) s << ":" << line;
  s << ": " << what;
  throw Error(Status(ErrorCode::kParse, s.str()));
}

std::string slurp(const std::filesystem::path& f) {
  std::ifstream in(f, std::ios::binary);
  if (!in) throw Error(Status(ErrorCode::kIo, f.string() + ": cannot open"));
  // Read straight into the string when the size is known (a start-up reads
  // some 30 MB of targets: a string stream copied every byte twice).
  std::error_code ec;
  const auto size = std::filesystem::file_size(f, ec);
  if (!ec) {
    std::string text(static_cast<std::size_t>(size), '\0');
    in.read(text.data(), static_cast<std::streamsize>(size));
    if (in.gcount() == static_cast<std::streamsize>(size) && in.peek() == std::char_traits<char>::eof()) return text;
    in.clear();
    in.seekg(0);
  }
  std::ostringstream ss;
  ss << in.rdbuf();
  return std::move(ss).str();
}

/// Short decimals ("-.166", "0.0265", "12"): the value exactly as
/// std::from_chars gives it, faster (MakeHuman's targets are 13 million
/// such numbers, which from_chars parsed in a third of regen's start-up).
/// Exact because the digits as an integer m <= 2^24 and 10^k for k <= 10
/// are floats exactly, so m / 10^k is one correctly rounded float division
/// (Clinger's fast path), the correctly rounded value from_chars returns;
/// anything else (more digits, exponents, inf, nan) returns false, and the
/// caller uses from_chars.
bool read_short_float(const char*& p, const char* end, float& v) noexcept {
  static constexpr float kPow10[] = {1e0f, 1e1f, 1e2f, 1e3f, 1e4f, 1e5f, 1e6f, 1e7f, 1e8f, 1e9f, 1e10f};
  const char* q = p;
  const bool negative = q < end && *q == '-';
  if (negative) ++q;
  std::uint32_t m = 0;
  int digits = 0, fraction = 0;
  for (; q < end && *q >= '0' && *q <= '9'; ++q, ++digits) {
    if (m > (1u << 24) / 10) return false;
    m = m * 10 + static_cast<std::uint32_t>(*q - '0');
  }
  if (q < end && *q == '.') {
    for (++q; q < end && *q >= '0' && *q <= '9'; ++q, ++digits, ++fraction) {
      if (m > (1u << 24) / 10 || fraction >= 10) return false;
      m = m * 10 + static_cast<std::uint32_t>(*q - '0');
    }
  }
  if (digits == 0 || m > (1u << 24)) return false;
  if (q < end && *q != ' ' && *q != '\t' && *q != '\r' && *q != '/') return false;
  const float x = static_cast<float>(m) / kPow10[fraction];
  v = negative ? -x : x;
  p = q;
  return true;
}


/// A UTF-8 byte-order mark is not part of the first line.
std::string_view without_bom(std::string_view text) {
  if (text.starts_with("\xEF\xBB\xBF")) text.remove_prefix(3);
  return text;
}

// Minimal tokeniser over a line.
struct Cursor {
  const char* p;
  const char* end;
  void skip_ws() {
    while (p < end && (*p == ' ' || *p == '\t' || *p == '\r')) ++p;
  }
  bool done() {
    skip_ws();
    return p >= end;
  }
  /// Why the last read() failed: the token is a number out of the type's
  /// range (std::from_chars leaves the value untouched then).
  bool read(float& v) {
    skip_ws();
    out_of_range = false;
    if (read_short_float(p, end, v)) return true;
    return read<float>(v);
  }
  bool out_of_range = false;
  template <class T>
  bool read(T& v) {
    skip_ws();
    auto [q, ec] = std::from_chars(p, end, v);
    out_of_range = ec == std::errc::result_out_of_range;
    if (ec != std::errc{} || (q < end && *q != ' ' && *q != '\t' && *q != '\r' && *q != '/')) return false;
    p = q;
    return true;
  }
};

template <class F>
void for_each_line(std::string_view text, F&& f) {
  std::size_t line = 0, pos = 0;
  while (pos < text.size()) {
    std::size_t nl = text.find('\n', pos);
    if (nl == std::string::npos) nl = text.size();
    ++line;
    f(line, text.data() + pos, text.data() + nl);
    pos = nl + 1;
  }
}

}  // namespace

Target read_target(const std::filesystem::path& file, std::uint32_t vertex_count) {
  return parse_target(slurp(file), file, vertex_count);
}

Target parse_target(std::string_view text, const std::filesystem::path& file, std::uint32_t vertex_count) {
  Target t;
  t.name = file.stem().string();
  for_each_line(without_bom(text), [&](std::size_t line, const char* b, const char* e) {
    Cursor c{b, e};
    if (c.done() || *c.p == '#') return;
    std::uint32_t idx = 0;
    float d[3];
    if (!c.read(idx))
      parse_error(file, line,
                  c.out_of_range ? "vertex index out of range (above 2^32 - 1)"
                                 : "expected 'INDEX DX DY DZ', got a non-integer index");
    for (float& x : d)
      if (!c.read(x))
        parse_error(file, line,
                    c.out_of_range ? "displacement out of the range of a float"
                                   : "expected 'INDEX DX DY DZ', a displacement is missing or not a number");
    if (!c.done()) parse_error(file, line, "extra tokens after 'INDEX DX DY DZ'");
    if (idx >= vertex_count) {
      std::ostringstream s;
      s << "vertex index " << idx << " out of range (the base mesh has " << vertex_count << " vertices)";
      parse_error(file, line, s.str());
    }
    if (!std::isfinite(d[0]) || !std::isfinite(d[1]) || !std::isfinite(d[2]))
      parse_error(file, line, "non-finite displacement");
    t.index.push_back(idx);
    t.delta.emplace_back(d[0], d[1], d[2]);
  });
  // A target with no displacement line is valid: MakeHuman ships such files
  // (macrodetails/universal-female-child-averagemuscle-averageweight.target
  // is its licence header only: the neutral blend). Text that is not a
  // target fails on its first line above.
  return t;
}

const BaseMesh::Group* BaseMesh::group(std::string_view name) const noexcept {
  for (const auto& g : groups)
    if (g.name == name) return &g;
  return nullptr;
}

BaseMesh read_base_mesh(const std::filesystem::path& file) { return parse_base_mesh(slurp(file), file); }

BaseMesh parse_base_mesh(std::string_view text, const std::filesystem::path& file) {
  BaseMesh m;
  BaseMesh::Group* cur = nullptr;
  std::vector<std::uint32_t> face;
  std::vector<Vec2d> texcoords;
  std::vector<std::int64_t> corner_vt;  // per corner over all groups in file order, -1 none
  std::vector<long long> face_vt;
  std::vector<std::vector<long long>> cur_vt;  // per group: the texcoord of each corner, -1 none
  for_each_line(without_bom(text), [&](std::size_t line, const char* b, const char* e) {
    Cursor c{b, e};
    if (c.done() || *c.p == '#') return;
    const char* kw = c.p;
    while (c.p < e && *c.p != ' ' && *c.p != '\t' && *c.p != '\r') ++c.p;
    const std::string_view key(kw, static_cast<std::size_t>(c.p - kw));
    if (key == "v") {
      float x, y, z;
      if (!c.read(x) || !c.read(y) || !c.read(z))
        parse_error(file, line, c.out_of_range ? "vertex coordinate out of the range of a float" : "vertex needs three numbers");
      if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) parse_error(file, line, "non-finite vertex");
      m.positions.emplace_back(x, y, z);
    } else if (key == "vt") {
      float u = 0, v = 0;
      if (!c.read(u)) parse_error(file, line, c.out_of_range ? "texture coordinate out of the range of a float" : "vt needs a number");
      if (!c.done() && !c.read(v))
        parse_error(file, line, c.out_of_range ? "texture coordinate out of the range of a float" : "vt needs numbers");
      if (!std::isfinite(u) || !std::isfinite(v)) parse_error(file, line, "non-finite texture coordinate");
      texcoords.emplace_back(static_cast<double>(u), static_cast<double>(v));
    } else if (key == "g" || key == "o") {
      c.skip_ws();
      std::string name(c.p, static_cast<std::size_t>(e - c.p));
      while (!name.empty() && (name.back() == '\r' || name.back() == ' ')) name.pop_back();
      m.groups.emplace_back().name = name;
      cur_vt.emplace_back();
      cur = &m.groups.back();
    } else if (key == "f") {
      if (!cur) {
        m.groups.emplace_back().name = "default";
        cur_vt.emplace_back();
        cur = &m.groups.back();
      }
      face.clear();
      face_vt.clear();
      while (!c.done()) {
        long long v = 0;
        if (!c.read(v)) parse_error(file, line, c.out_of_range ? "face index out of range" : "face index is not an integer");
        long long t = 0;
        if (c.p < e && *c.p == '/' && c.p + 1 < e && c.p[1] != '/') {
          ++c.p;
          if (!c.read(t)) parse_error(file, line, "texture index is not an integer");
          const long long nt = static_cast<long long>(texcoords.size());
          const long long ti = t > 0 ? t - 1 : nt + t;
          if (t == 0 || ti < 0 || ti >= nt) {
            std::ostringstream s;
            s << "texture index " << t << " out of range (" << nt << " texture coordinates so far)";
            parse_error(file, line, s.str());
          }
          face_vt.push_back(ti);
        } else {
          face_vt.push_back(-1);
        }
        while (c.p < e && *c.p != ' ' && *c.p != '\t' && *c.p != '\r') ++c.p;  // skip the rest (/vn)
        const long long n = static_cast<long long>(m.positions.size());
        const long long i = v > 0 ? v - 1 : n + v;
        if (v == 0 || i < 0 || i >= n) {
          std::ostringstream s;
          s << "face index " << v << " out of range (" << n << " vertices so far)";
          parse_error(file, line, s.str());
        }
        face.push_back(static_cast<std::uint32_t>(i));
      }
      if (face.size() < 3) parse_error(file, line, "face with fewer than 3 vertices");
      cur->face_nodes.insert(cur->face_nodes.end(), face.begin(), face.end());
      cur->face_offsets.push_back(static_cast<std::uint32_t>(cur->face_nodes.size()));
      for (const long long t : face_vt) cur_vt[static_cast<std::size_t>(cur - m.groups.data())].push_back(t);
    }
  });
  // Texture coordinates per corner, kept only when every corner has one
  // (a garment's uv map; a mesh with some corners unmapped keeps none).
  bool all_mapped = !texcoords.empty();
  for (const auto& g : cur_vt)
    for (const long long t : g) all_mapped &= t >= 0;
  if (all_mapped)
    for (std::size_t g = 0; g < m.groups.size(); ++g)
      for (const long long t : cur_vt[g]) m.groups[g].corner_uv.push_back(texcoords[static_cast<std::size_t>(t)]);
  // Text or bytes with no geometry are not an empty mesh: refuse them.
  if (m.positions.empty()) parse_error(file, 0, "no vertex ('v' line): not an OBJ mesh");
  bool any_face = false;
  for (const auto& g : m.groups) any_face |= g.face_count() > 0;
  if (!any_face) parse_error(file, 0, "no face ('f' line)");
  return m;
}

std::map<std::string, std::vector<std::uint32_t>> read_measures(const std::filesystem::path& file,
                                                                std::uint32_t vertex_count) {
  return parse_measures(slurp(file), file, vertex_count);
}

std::map<std::string, std::vector<std::uint32_t>> parse_measures(std::string_view text, const std::filesystem::path& file,
                                                                 std::uint32_t vertex_count) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(without_bom(text));
  } catch (const nlohmann::json::exception& e) {  // parse errors, and numbers beyond a double (out_of_range 406)
    parse_error(file, 0, e.what());
  }
  std::map<std::string, std::vector<std::uint32_t>> out;
  if (!j.contains("measures") || !j["measures"].is_object()) parse_error(file, 0, "no \"measures\" object");
  for (auto& [name, list] : j["measures"].items()) {
    if (!list.is_array()) parse_error(file, 0, "measure '" + name + "' is not an array");
    std::vector<std::uint32_t> v;
    for (auto& x : list) {
      if (!x.is_number_unsigned() || x.get<std::uint64_t>() >= vertex_count)
        parse_error(file, 0, "measure '" + name + "' has an invalid vertex index " + x.dump());
      v.push_back(x.get<std::uint32_t>());
    }
    out[name] = std::move(v);
  }
  return out;
}

std::vector<MeasureModifier> read_measure_modifiers(const std::filesystem::path& file) {
  return parse_measure_modifiers(slurp(file), file);
}

std::vector<MeasureModifier> parse_measure_modifiers(std::string_view text, const std::filesystem::path& file) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(without_bom(text));
  } catch (const nlohmann::json::exception& e) {  // parse errors, and numbers beyond a double (out_of_range 406)
    parse_error(file, 0, e.what());
  }
  // Every access is checked first: nlohmann's type errors would otherwise
  // escape as exceptions that name neither the file nor the place.
  if (!j.is_array()) parse_error(file, 0, "expected an array of modifier groups");
  std::vector<MeasureModifier> out;
  for (std::size_t g = 0; g < j.size(); ++g) {
    const auto& group = j[g];
    const std::string at = "/" + std::to_string(g);
    if (!group.is_object()) parse_error(file, 0, at + ": a modifier group must be an object");
    const auto mods = group.find("modifiers");
    if (mods == group.end()) continue;
    if (!mods->is_array()) parse_error(file, 0, at + "/modifiers: must be an array");
    for (std::size_t k = 0; k < mods->size(); ++k) {
      const auto& m = (*mods)[k];
      const std::string mat = at + "/modifiers/" + std::to_string(k);
      if (!m.is_object()) parse_error(file, 0, mat + ": a modifier must be an object");
      MeasureModifier mm;
      for (auto [key, dst] : {std::pair<const char*, std::string*>{"target", &mm.target}, {"min", &mm.min}, {"max", &mm.max}}) {
        const auto it = m.find(key);
        if (it == m.end()) continue;
        if (!it->is_string()) parse_error(file, 0, mat + "/" + key + ": must be a string");
        *dst = it->get<std::string>();
      }
      if (mm.target.empty()) continue;
      out.push_back(std::move(mm));
    }
  }
  return out;
}

}  // namespace atelier::makehuman
