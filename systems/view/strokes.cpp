#include <atelier/io/atomic_file.h>
#include <atelier/systems/view/strokes.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

namespace atelier {

namespace {

using Json = nlohmann::json;

constexpr const char* kToolNames[] = {"paint", "paint-through", "cut", "partition", "pick", "extrude"};

/// Thrown inside the reader only; turned into a Status at the entry point.
struct Refusal {
  std::string message;
};

/// line:column (1-based) of a byte offset.
std::string line_column(std::string_view text, std::size_t byte) {
  byte = std::min(byte, text.size());
  std::size_t line = 1, col = 1;
  for (std::size_t i = 0; i < byte; ++i) {
    if (text[i] == '\n') {
      ++line;
      col = 1;
    } else {
      ++col;
    }
  }
  return std::to_string(line) + ":" + std::to_string(col);
}

/// Nesting depth check before parsing (a deeply nested file is refused
/// without building it). Strings are skipped, escapes included.
std::size_t too_deep_at(std::string_view text, std::size_t max_depth) {
  std::size_t depth = 0;
  bool in_string = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (c == '\\')
        ++i;
      else if (c == '"')
        in_string = false;
      continue;
    }
    if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > max_depth) return i;
    } else if ((c == ']' || c == '}') && depth > 0) {
      --depth;
    }
  }
  return std::string_view::npos;
}

/// The literal starting at or just before `byte` when it is one of the
/// non-finite spellings other JSON writers produce (Python's json: NaN,
/// Infinity, -Infinity).
std::string non_finite_literal(std::string_view text, std::size_t byte) {
  byte = std::min(byte, text.size());
  std::size_t b = byte;
  while (b > 0 && (std::isalpha(static_cast<unsigned char>(text[b - 1])) || text[b - 1] == '-' || text[b - 1] == '+'))
    --b;
  std::size_t e = b;
  while (e < text.size() && (std::isalpha(static_cast<unsigned char>(text[e])) || text[e] == '-' || text[e] == '+'))
    ++e;
  std::string tok(text.substr(b, e - b));
  std::string low = tok;
  for (char& c : low) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  for (const char* bad : {"nan", "-nan", "+nan", "infinity", "-infinity", "+infinity", "inf", "-inf", "+inf"})
    if (low == bad) return tok;
  return {};
}

class Reader {
 public:
  Reader(std::string_view file, const StrokeLimits& limits) : file_(file), limits_(limits) {}

  [[noreturn]] void fail(const std::string& ptr, const std::string& what) const {
    throw Refusal{file_ + ": at " + (ptr.empty() ? std::string("/") : ptr) + ": " + what};
  }

  static const char* type_of(const Json& v) noexcept {
    if (v.is_number_integer() || v.is_number_unsigned()) return "an integer";
    if (v.is_number()) return "a number";
    if (v.is_string()) return "a string";
    if (v.is_boolean()) return "a boolean";
    if (v.is_null()) return "null";
    if (v.is_array()) return "an array";
    return "an object";
  }

  void expect_object(const Json& v, const std::string& ptr, std::initializer_list<const char*> required,
                     std::initializer_list<const char*> optional) const {
    if (!v.is_object()) fail(ptr, std::string("expected an object, found ") + type_of(v));
    for (const char* k : required)
      if (!v.contains(k)) fail(ptr, std::string("missing key \"") + k + "\"");
    for (auto it = v.begin(); it != v.end(); ++it) {
      bool known = false;
      for (const char* k : required) known |= it.key() == k;
      for (const char* k : optional) known |= it.key() == k;
      if (!known) {
        std::string allowed;
        for (const char* k : required) allowed += std::string(allowed.empty() ? "" : ", ") + k;
        for (const char* k : optional) allowed += std::string(allowed.empty() ? "" : ", ") + k;
        fail(ptr + "/" + escape(it.key()), "unknown key (expected one of: " + allowed + ")");
      }
    }
  }

  double number(const Json& v, const std::string& ptr) const {
    if (!v.is_number()) fail(ptr, std::string("expected a number, found ") + type_of(v));
    const double x = v.get<double>();
    if (!std::isfinite(x)) fail(ptr, "non-finite number");
    return x;
  }

  Mat4d matrix(const Json& v, const std::string& ptr) const {
    if (!v.is_array()) fail(ptr, std::string("expected an array of 16 numbers, found ") + type_of(v));
    if (v.size() != 16) fail(ptr, "expected 16 numbers (a row-major 4x4 matrix), found " + std::to_string(v.size()));
    Mat4d m;
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) {
        const std::size_t k = static_cast<std::size_t>(4 * r + c);
        m(r, c) = number(v[k], ptr + "/" + std::to_string(k));
      }
    return m;
  }

  int pixels(const Json& v, const std::string& ptr) const {
    const double x = number(v, ptr);
    if (!(x >= 1) || x != std::floor(x) || x > 1e6)
      fail(ptr, "the viewport size must be a positive whole number of pixels (at most 1000000)");
    return static_cast<int>(x);
  }

  Camera camera(const Json& v, const std::string& ptr) const {
    expect_object(v, ptr, {"view", "projection", "viewport"}, {});
    Camera c;
    c.view = matrix(v["view"], ptr + "/view");
    c.projection = matrix(v["projection"], ptr + "/projection");
    const Json& vp = v["viewport"];
    if (!vp.is_array() || vp.size() != 2)
      fail(ptr + "/viewport", std::string("expected [width, height], found ") +
                                  (vp.is_array() ? "an array of " + std::to_string(vp.size()) : type_of(vp)));
    c.width = pixels(vp[0], ptr + "/viewport/0");
    c.height = pixels(vp[1], ptr + "/viewport/1");
    if (Status s = c.check(); !s) {
      std::string msg = s.message();
      if (msg.rfind("camera: ", 0) == 0) msg = msg.substr(8);
      fail(ptr, msg);
    }
    return c;
  }

  Stroke stroke(const Json& v, const std::string& ptr, std::size_t& total_points) const {
    expect_object(v, ptr, {"points", "tool"}, {"through", "name", "comment", "camera"});
    Stroke s;
    const Json& tool = v["tool"];
    if (!tool.is_string()) fail(ptr + "/tool", std::string("expected a string, found ") + type_of(tool));
    const std::string t = tool.get<std::string>();
    bool found = false;
    for (std::size_t k = 0; k < std::size(kToolNames); ++k)
      if (t == kToolNames[k]) {
        s.tool = static_cast<StrokeTool>(k);
        found = true;
      }
    if (!found)
      fail(ptr + "/tool",
           "unknown tool \"" + t + "\" (expected paint, paint-through, cut, partition, pick or extrude)");
    s.through = s.tool == StrokeTool::kPaintThrough;
    if (v.contains("through")) {
      const Json& th = v["through"];
      if (!th.is_boolean()) fail(ptr + "/through", std::string("expected true or false, found ") + type_of(th));
      const bool b = th.get<bool>();
      if (s.tool == StrokeTool::kPick && b) fail(ptr + "/through", "a pick stroke cannot be \"through\"");
      if (s.tool == StrokeTool::kPaintThrough && !b)
        fail(ptr + "/through", "\"paint-through\" with \"through\": false is contradictory");
      if (s.tool == StrokeTool::kPaint && b) s.tool = StrokeTool::kPaintThrough;
      s.through = s.through || b;
    }
    if (v.contains("name")) {
      if (!v["name"].is_string()) fail(ptr + "/name", std::string("expected a string, found ") + type_of(v["name"]));
      s.name = v["name"].get<std::string>();
    }
    if (v.contains("camera")) s.camera = camera(v["camera"], ptr + "/camera");
    if (v.contains("comment") && !v["comment"].is_string())
      fail(ptr + "/comment", std::string("expected a string, found ") + type_of(v["comment"]));
    const Json& pts = v["points"];
    const std::string pp = ptr + "/points";
    if (!pts.is_array()) fail(pp, std::string("expected an array of [x, y] points, found ") + type_of(pts));
    total_points += pts.size();
    if (total_points > limits_.max_points)
      fail(pp, "more than " + std::to_string(limits_.max_points) + " points in the file");
    s.points.reserve(pts.size());
    for (std::size_t i = 0; i < pts.size(); ++i) {
      const std::string ip = pp + "/" + std::to_string(i);
      const Json& p = pts[i];
      if (!p.is_array() || p.size() != 2)
        fail(ip, std::string("expected a point [x, y], found ") +
                     (p.is_array() ? "an array of " + std::to_string(p.size()) : type_of(p)));
      const Vec2d q(number(p[0], ip + "/0"), number(p[1], ip + "/1"));
      for (int k = 0; k < 2; ++k)
        if (!(std::abs(q[k]) <= limits_.max_coordinate))
          fail(ip + "/" + std::to_string(k),
               "coordinate beyond +-" + std::to_string(limits_.max_coordinate) + " pixels");
      s.points.push_back(q);
    }
    if (s.tool == StrokeTool::kPick) {
      if (s.points.size() != 1)
        fail(pp, "a pick stroke has exactly one point (found " + std::to_string(s.points.size()) + ")");
    } else {
      std::size_t distinct = s.points.empty() ? 0 : 1;
      for (std::size_t i = 1; i < s.points.size(); ++i) distinct += s.points[i] != s.points[i - 1];
      if (distinct < 2)
        fail(pp, std::string("a ") + kToolNames[static_cast<int>(s.tool)] +
                     " stroke needs at least 2 distinct points (found " + std::to_string(s.points.size()) + " point" +
                     (s.points.size() == 1 ? "" : "s") + (s.points.size() > 1 ? ", all equal" : "") + ")");
    }
    return s;
  }

  StrokeFile file(const Json& root) const {
    expect_object(root, "", {"camera", "strokes"}, {"comment"});
    StrokeFile f;
    f.camera = camera(root["camera"], "/camera");
    const Json& st = root["strokes"];
    if (!st.is_array()) fail("/strokes", std::string("expected an array of strokes, found ") + type_of(st));
    std::size_t total = 0;
    for (std::size_t i = 0; i < st.size(); ++i) {
      f.strokes.push_back(stroke(st[i], "/strokes/" + std::to_string(i), total));
      if (f.strokes.back().tool == StrokeTool::kPick && (i == 0 || f.strokes[i - 1].tool != StrokeTool::kCut))
        fail("/strokes/" + std::to_string(i), "a pick stroke must follow a cut stroke");
    }
    // A run of consecutive extrude strokes is one extrusion: the base stroke
    // and one (closed extrusion) or two (open extrusion) extruding strokes.
    for (std::size_t i = 0; i < f.strokes.size();) {
      std::size_t j = i;
      while (j < f.strokes.size() && f.strokes[j].tool == StrokeTool::kExtrude) ++j;
      if (j > i && (j - i < 2 || j - i > 3))
        fail("/strokes/" + std::to_string(i),
             "an extrusion is a run of 2 or 3 extrude strokes (a base stroke, then "
             "one or two extruding strokes); found " +
                 std::to_string(j - i));
      i = j > i ? j : i + 1;
    }
    return f;
  }

  /// JSON pointer escaping of a key (RFC 6901: ~ -> ~0, / -> ~1).
  static std::string escape(const std::string& k) {
    std::string o;
    for (char c : k) {
      if (c == '~')
        o += "~0";
      else if (c == '/')
        o += "~1";
      else
        o += c;
    }
    return o;
  }

 private:
  std::string file_;
  StrokeLimits limits_;
};

}  // namespace

const char* to_string(StrokeTool t) noexcept {
  const auto k = static_cast<std::size_t>(t);
  return k < std::size(kToolNames) ? kToolNames[k] : "?";
}

Expected<StrokeFile> parse_strokes(std::string_view bytes, std::string_view file_name, const StrokeLimits& limits) {
  const std::string name(file_name);
  if (bytes.size() > limits.max_bytes)
    return Status(ErrorCode::kParse, name + ": " + std::to_string(bytes.size()) + " bytes, more than the limit of " +
                                         std::to_string(limits.max_bytes));
  if (const std::size_t at = too_deep_at(bytes, limits.max_depth); at != std::string_view::npos)
    return Status(ErrorCode::kParse, name + ":" + line_column(bytes, at) + ": JSON nested deeper than " +
                                         std::to_string(limits.max_depth) + " levels");
  Json root;
  try {
    root = Json::parse(bytes.begin(), bytes.end());
  } catch (const Json::parse_error& e) {
    // e.byte is one past the offending character (1-based), or the end for a truncated file.
    const std::size_t at = e.byte > 0 ? e.byte - 1 : 0;
    const std::string lit = non_finite_literal(bytes, at);
    if (!lit.empty())
      return Status(ErrorCode::kParse, name + ":" + line_column(bytes, at) + ": non-finite number '" + lit +
                                           "' (JSON has no NaN or Infinity)");
    const bool truncated = e.byte > bytes.size();
    std::string what = e.what();
    if (const auto p = what.find("syntax error"); p != std::string::npos) what = what.substr(p);
    return Status(ErrorCode::kParse, name + ":" + line_column(bytes, at) + ": " +
                                         (truncated ? "truncated file or " : "") + "invalid JSON: " + what);
  } catch (const Json::exception& e) {
    // Out-of-range numbers (1e999) are refused by the parser itself, which
    // names the token but not its place: find it in the text.
    std::string where;
    const std::string what = e.what();
    const auto q1 = what.find('\''), q2 = what.rfind('\'');
    if (q1 != std::string::npos && q2 > q1 + 1)
      if (const auto at = bytes.find(what.substr(q1 + 1, q2 - q1 - 1)); at != std::string_view::npos)
        where = ":" + line_column(bytes, at);
    return Status(ErrorCode::kParse, name + where + ": number out of range or invalid JSON: " + what);
  }
  try {
    return Reader(name, limits).file(root);
  } catch (const Refusal& r) {
    return Status(ErrorCode::kParse, r.message);
  } catch (const Json::exception& e) {
    // Every access is type-checked first; this is a last line of defence.
    return Status(ErrorCode::kParse, name + ": invalid stroke file: " + e.what());
  }
}

Expected<StrokeFile> read_strokes(const std::filesystem::path& path, const StrokeLimits& limits) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (ec) return Status(ErrorCode::kIo, path.string() + ": cannot read: " + ec.message());
  if (size > limits.max_bytes)
    return Status(ErrorCode::kParse, path.string() + ": " + std::to_string(size) + " bytes, more than the limit of " +
                                         std::to_string(limits.max_bytes));
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status(ErrorCode::kIo, path.string() + ": cannot open");
  std::ostringstream s;
  s << in.rdbuf();
  if (in.bad()) return Status(ErrorCode::kIo, path.string() + ": read error");
  return parse_strokes(s.str(), path.string(), limits);
}

Expected<std::string> strokes_to_json(const StrokeFile& f) {
  auto finite = [](double x) { return std::isfinite(x); };
  auto camera_json = [&](const Camera& c, Json& cam) -> Status {
    cam = Json::object();
    for (const auto& [key, m] : {std::pair<const char*, const Mat4d*>{"view", &c.view},
                                 std::pair<const char*, const Mat4d*>{"projection", &c.projection}}) {
      Json a = Json::array();
      for (int r = 0; r < 4; ++r)
        for (int k = 0; k < 4; ++k) {
          if (!finite((*m)(r, k)))
            return Status(ErrorCode::kInvalidArgument, std::string("strokes_to_json: non-finite ") + key + " matrix");
          a.push_back((*m)(r, k));
        }
      cam[key] = std::move(a);
    }
    cam["viewport"] = Json::array({c.width, c.height});
    return {};
  };
  Json root = Json::object();
  Json cam;
  if (Status st = camera_json(f.camera, cam); !st) return st;
  root["camera"] = std::move(cam);
  Json strokes = Json::array();
  for (std::size_t i = 0; i < f.strokes.size(); ++i) {
    const Stroke& s = f.strokes[i];
    Json js = Json::object();
    Json pts = Json::array();
    for (const Vec2d& p : s.points) {
      if (!p.allFinite())
        return Status(ErrorCode::kInvalidArgument,
                      "strokes_to_json: stroke " + std::to_string(i) + " has a non-finite point");
      pts.push_back(Json::array({p.x(), p.y()}));
    }
    js["points"] = std::move(pts);
    js["tool"] = to_string(s.tool);
    if (s.tool == StrokeTool::kCut || s.tool == StrokeTool::kPartition) js["through"] = s.through;
    if (!s.name.empty()) js["name"] = s.name;
    if (s.camera) {
      Json sc;
      if (Status st = camera_json(*s.camera, sc); !st) return st;
      js["camera"] = std::move(sc);
    }
    strokes.push_back(std::move(js));
  }
  root["strokes"] = std::move(strokes);
  std::string text = root.dump(1) + "\n";
  // What is written must read back: the same checks as the reader.
  if (auto back = parse_strokes(text, "strokes_to_json"); !back)
    return Status(ErrorCode::kInvalidArgument, back.status().message());
  return text;
}

Status write_strokes(const StrokeFile& f, const std::filesystem::path& path) {
  auto text = strokes_to_json(f);
  if (!text) return text.status();
  try {
    write_atomically(path, [&](AtomicFile& out) { out.write(*text); });
  } catch (const Error& e) {
    return e.status();
  }
  return {};
}

}  // namespace atelier
