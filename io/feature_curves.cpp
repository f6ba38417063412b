#include <atelier/io/atomic_file.h>
#include <atelier/io/feature_curves.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <memory>
#include <sstream>
#include <utility>

namespace atelier {

namespace {

constexpr std::size_t kMaxDepth = 16;
constexpr std::size_t kMaxPoints = 1'000'000;
constexpr double kMaxCoordinate = 1e6;
constexpr std::uintmax_t kMaxFileBytes = 64u << 20;

constexpr auto kNames = std::to_array<std::string_view>(
    {// The mannequin's names (systems/body/mannequin_topology.cpp) ...
     "neck_base", "shoulder_left", "shoulder_right", "armhole_left", "armhole_right", "bust", "underbust", "waist",
     "hip", "thigh_left", "thigh_right", "knee_left", "knee_right", "ankle_left", "ankle_right", "centre_front",
     "centre_back", "side_left", "side_right", "upper_arm_left", "upper_arm_right",
     // ... and MakeHuman's (systems/body/makehuman_body.cpp).
     "neck", "left_thigh", "right_thigh", "left_knee", "right_knee", "left_calf", "right_calf", "left_ankle",
     "right_ankle", "left_upperarm", "right_upperarm", "left_wrist", "right_wrist", "left_side", "right_side"});

// A minimal JSON tree that remembers the line of every value: nlohmann's
// parser reports a byte offset for syntax errors only, and an error about a
// value ("point 12 is not finite") must name its line too.
struct Value {
  enum Kind : std::uint8_t { kNull, kBool, kNumber, kString, kArray, kObject } kind = kNull;
  std::uint32_t line = 0;
  bool boolean = false;
  double number = 0;
  bool number_finite = true;  // false for a literal that overflows a double
  std::string text;
  std::vector<Value> items;
  // An object's members, in order (two vectors: a pair of an incomplete
  // type cannot be a vector's element).
  std::vector<std::string> keys;
  std::vector<Value> values;
};

const char* kind_name(Value::Kind k) {
  switch (k) {
    case Value::kNull:
      return "null";
    case Value::kBool:
      return "a boolean";
    case Value::kNumber:
      return "a number";
    case Value::kString:
      return "a string";
    case Value::kArray:
      return "an array";
    case Value::kObject:
      return "an object";
  }
  return "?";
}

class Parser {
 public:
  Parser(std::string_view s, std::string_view name) : s_(s), name_(name) {}

  Expected<Value> document() {
    if (s_.size() >= 3 && static_cast<unsigned char>(s_[0]) == 0xEF && static_cast<unsigned char>(s_[1]) == 0xBB &&
        static_cast<unsigned char>(s_[2]) == 0xBF)
      i_ = 3;  // a UTF-8 byte-order mark
    skip();
    if (i_ >= s_.size()) return error("the file is empty (expected a JSON object)");
    Value v;
    if (Status st = value(v, 0); !st) return st;
    skip();
    if (i_ < s_.size()) return error("unexpected text after the JSON document");
    return v;
  }

 private:
  Status error(const std::string& what) const {
    return {ErrorCode::kParse, std::string(name_) + ":" + std::to_string(line_) + ": " + what};
  }

  void skip() {
    while (i_ < s_.size()) {
      const char c = s_[i_];
      if (c == '\n') {
        ++line_;
      } else if (c != ' ' && c != '\t' && c != '\r') {
        return;
      }
      ++i_;
    }
  }

  bool literal(std::string_view word) {
    if (s_.substr(i_, word.size()) != word) return false;
    i_ += word.size();
    return true;
  }

  Status value(Value& v, std::size_t depth) {
    if (depth > kMaxDepth) return error("nesting deeper than " + std::to_string(kMaxDepth));
    skip();
    if (i_ >= s_.size()) return error("unexpected end of file (a value is missing)");
    v.line = line_;
    const char c = s_[i_];
    if (c == '{') return object(v, depth);
    if (c == '[') return array(v, depth);
    if (c == '"') {
      v.kind = Value::kString;
      return string(v.text);
    }
    if (c == 't' || c == 'f' || c == 'n') {
      if (literal("true")) {
        v.kind = Value::kBool;
        v.boolean = true;
      } else if (literal("false")) {
        v.kind = Value::kBool;
      } else if (literal("null")) {
        v.kind = Value::kNull;
      } else {
        return error("unexpected text (JSON has true, false and null; NaN and Infinity are not JSON)");
      }
      return {};
    }
    if (c == '-' || (c >= '0' && c <= '9')) return number(v);
    return error(std::string("unexpected character '") + (c >= 32 && c < 127 ? std::string(1, c) : "?") +
                 "' (NaN and Infinity are not JSON numbers)");
  }

  Status number(Value& v) {
    // The JSON grammar: -?(0|[1-9][0-9]*)(\.[0-9]+)?([eE][+-]?[0-9]+)?
    const std::size_t start = i_;
    auto digits = [&] {
      const std::size_t b = i_;
      while (i_ < s_.size() && s_[i_] >= '0' && s_[i_] <= '9') ++i_;
      return i_ - b;
    };
    if (s_[i_] == '-') ++i_;
    if (i_ < s_.size() && s_[i_] == '0') {
      ++i_;
    } else if (digits() == 0) {
      return error("malformed number");
    }
    if (i_ < s_.size() && s_[i_] == '.') {
      ++i_;
      if (digits() == 0) return error("malformed number (digits must follow the '.')");
    }
    if (i_ < s_.size() && (s_[i_] == 'e' || s_[i_] == 'E')) {
      ++i_;
      if (i_ < s_.size() && (s_[i_] == '+' || s_[i_] == '-')) ++i_;
      if (digits() == 0) return error("malformed number (digits must follow the exponent)");
    }
    v.kind = Value::kNumber;
    const auto r = std::from_chars(s_.data() + start, s_.data() + i_, v.number);
    if (r.ec == std::errc::result_out_of_range) {
      v.number_finite = false;  // named by the caller with its curve and point
    } else if (r.ec != std::errc() || r.ptr != s_.data() + i_) {
      return error("malformed number");
    }
    return {};
  }

  Status string(std::string& out) {
    ++i_;  // the opening quote
    while (i_ < s_.size()) {
      const char c = s_[i_++];
      if (c == '"') return {};
      if (static_cast<unsigned char>(c) < 0x20) return error("a control character or line break inside a string");
      if (c != '\\') {
        out += c;
        continue;
      }
      if (i_ >= s_.size()) break;
      const char e = s_[i_++];
      switch (e) {
        case '"':
        case '\\':
        case '/':
          out += e;
          break;
        case 'b':
          out += '\b';
          break;
        case 'f':
          out += '\f';
          break;
        case 'n':
          out += '\n';
          break;
        case 'r':
          out += '\r';
          break;
        case 't':
          out += '\t';
          break;
        case 'u': {
          // Kept as '?': names are ASCII, a name with an escape is unknown anyway.
          for (int k = 0; k < 4; ++k, ++i_)
            if (i_ >= s_.size() || !std::isxdigit(static_cast<unsigned char>(s_[i_])))
              return error("malformed \\u escape in a string");
          out += '?';
          break;
        }
        default:
          return error("unknown escape in a string");
      }
    }
    return error("unterminated string");
  }

  Status array(Value& v, std::size_t depth) {
    v.kind = Value::kArray;
    ++i_;
    skip();
    if (i_ < s_.size() && s_[i_] == ']') {
      ++i_;
      return {};
    }
    for (;;) {
      v.items.emplace_back();
      if (Status st = value(v.items.back(), depth + 1); !st) return st;
      if (++values_ > 4 * kMaxPoints)
        return error("too many values (at most " + std::to_string(kMaxPoints) + " points)");
      skip();
      if (i_ >= s_.size()) return error("unexpected end of file inside an array (missing ']')");
      if (s_[i_] == ',') {
        ++i_;
        continue;
      }
      if (s_[i_] == ']') {
        ++i_;
        return {};
      }
      return error("expected ',' or ']' in an array");
    }
  }

  Status object(Value& v, std::size_t depth) {
    v.kind = Value::kObject;
    ++i_;
    skip();
    if (i_ < s_.size() && s_[i_] == '}') {
      ++i_;
      return {};
    }
    for (;;) {
      skip();
      if (i_ >= s_.size() || s_[i_] != '"') return error("expected a key in double quotes");
      std::string key;
      if (Status st = string(key); !st) return st;
      for (const auto& k : v.keys)
        if (k == key) return error("key \"" + key + "\" appears twice in one object");
      skip();
      if (i_ >= s_.size() || s_[i_] != ':') return error("expected ':' after key \"" + key + "\"");
      ++i_;
      v.keys.push_back(std::move(key));
      v.values.emplace_back();
      if (Status st = value(v.values.back(), depth + 1); !st) return st;
      skip();
      if (i_ >= s_.size()) return error("unexpected end of file inside an object (missing '}')");
      if (s_[i_] == ',') {
        ++i_;
        continue;
      }
      if (s_[i_] == '}') {
        ++i_;
        return {};
      }
      return error("expected ',' or '}' in an object");
    }
  }

  std::string_view s_, name_;
  std::size_t i_ = 0;
  std::uint32_t line_ = 1;
  std::size_t values_ = 0;
};

Status bad(std::string_view file, std::uint32_t line, const std::string& what) {
  return {ErrorCode::kParse, std::string(file) + ":" + std::to_string(line) + ": " + what};
}

const Value* member(const Value& o, std::string_view key) {
  for (std::size_t i = 0; i < o.keys.size(); ++i)
    if (o.keys[i] == key) return &o.values[i];
  return nullptr;
}

Status check_keys(std::string_view file, const Value& o, std::initializer_list<std::string_view> allowed,
                  const std::string& where) {
  for (std::size_t i = 0; i < o.keys.size(); ++i)
    if (std::find(allowed.begin(), allowed.end(), o.keys[i]) == allowed.end()) {
      std::string list;
      for (auto a : allowed) list += (list.empty() ? "\"" : ", \"") + std::string(a) + "\"";
      return bad(file, o.values[i].line, where + ": unknown key \"" + o.keys[i] + "\" (the keys are " + list + ")");
    }
  return {};
}

Status read_curve(std::string_view file, const Value& c, std::size_t index, FeatureCurveSpec& out) {
  std::string where = "curve " + std::to_string(index);
  if (c.kind != Value::kObject) return bad(file, c.line, where + " is " + kind_name(c.kind) + ", not an object");
  out.line = c.line;
  const Value* name = member(c, "name");
  if (!name) return bad(file, c.line, where + " has no \"name\"");
  if (name->kind != Value::kString)
    return bad(file, name->line, where + ": \"name\" is " + kind_name(name->kind) + ", not a string");
  out.name = name->text;
  const auto names = feature_curve_names();
  if (std::find(names.begin(), names.end(), out.name) == names.end()) {
    std::string list;
    for (auto n : names) list += (list.empty() ? "" : ", ") + std::string(n);
    return bad(file, name->line, where + ": unknown curve name \"" + out.name + "\" (the names are: " + list + ")");
  }
  where = "curve '" + out.name + "'";
  if (Status s = check_keys(file, c, {"name", "closed", "points"}, where); !s) return s;
  const Value* closed = member(c, "closed");
  if (!closed) return bad(file, c.line, where + " has no \"closed\" (true for a loop such as a girth)");
  if (closed->kind != Value::kBool)
    return bad(file, closed->line, where + ": \"closed\" is " + kind_name(closed->kind) + ", not true or false");
  out.closed = closed->boolean;
  const Value* pts = member(c, "points");
  if (!pts) return bad(file, c.line, where + " has no \"points\"");
  if (pts->kind != Value::kArray)
    return bad(file, pts->line, where + ": \"points\" is " + kind_name(pts->kind) + ", not an array of [x, y, z]");
  for (std::size_t k = 0; k < pts->items.size(); ++k) {
    const Value& p = pts->items[k];
    const std::string pw = where + ", point " + std::to_string(k);
    if (p.kind != Value::kArray || p.items.size() != 3)
      return bad(file, p.line, pw + ": expected [x, y, z], three numbers");
    Vec3d q;
    for (int d = 0; d < 3; ++d) {
      const Value& x = p.items[d];
      if (x.kind != Value::kNumber)
        return bad(file, x.line,
                   pw + ": coordinate " + std::to_string(d) + " is " + kind_name(x.kind) + ", not a number");
      if (!x.number_finite || !std::isfinite(x.number) || std::abs(x.number) > kMaxCoordinate)
        return bad(file, x.line,
                   pw + ": coordinate " + std::to_string(d) + " is out of range (at most 1e6 in magnitude)");
      q[d] = x.number;
    }
    out.points.push_back(q);
    out.point_lines.push_back(p.line);
  }
  // A closed curve written with its first point repeated at the end.
  if (out.closed && out.points.size() >= 2 && out.points.front() == out.points.back()) {
    out.points.pop_back();
    out.point_lines.pop_back();
  }
  const std::size_t need = out.closed ? 3 : 2;
  if (out.points.size() < need)
    return bad(file, pts->line,
               where + " has " + std::to_string(out.points.size()) + " distinct points; a" +
                   (out.closed ? " closed curve needs at least 3" : "n open curve needs at least 2"));
  for (std::size_t k = 0; k + 1 < out.points.size(); ++k)
    if (out.points[k] == out.points[k + 1])
      return bad(file, out.point_lines[k + 1],
                 where + ", point " + std::to_string(k + 1) + " repeats the point before it");
  return {};
}

}  // namespace

std::span<const std::string_view> feature_curve_names() noexcept {
  return kNames;
}

Expected<FeatureCurveFile> parse_feature_curves(std::string_view bytes, std::string_view display_name) {
  try {
    Parser parser(bytes, display_name);
    auto doc = parser.document();
    if (!doc) return doc.status();
    const Value& root = *doc;
    FeatureCurveFile f;
    f.source = std::string(display_name);
    if (root.kind != Value::kObject)
      return bad(display_name, root.line,
                 std::string("the document is ") + kind_name(root.kind) + ", not an object with \"curves\"");
    if (Status s = check_keys(display_name, root, {"units", "up", "curves"}, "the document"); !s) return s;
    if (const Value* u = member(root, "units")) {
      if (u->kind != Value::kString || (u->text != "m" && u->text != "cm" && u->text != "mm"))
        return bad(display_name, u->line, "\"units\" must be \"m\", \"cm\" or \"mm\"");
      f.has_units = true;
      f.scale = u->text == "m" ? 1.0 : u->text == "cm" ? 0.01 : 0.001;
    }
    if (const Value* up = member(root, "up")) {
      if (up->kind != Value::kString || (up->text != "y" && up->text != "z"))
        return bad(display_name, up->line, "\"up\" must be \"y\" or \"z\"");
      f.has_up = true;
      f.up_z = up->text == "z";
    }
    const Value* curves = member(root, "curves");
    if (!curves) return bad(display_name, root.line, "the document has no \"curves\"");
    if (curves->kind != Value::kArray)
      return bad(display_name, curves->line,
                 std::string("\"curves\" is ") + kind_name(curves->kind) + ", not an array");
    if (curves->items.empty()) return bad(display_name, curves->line, "\"curves\" is empty");
    std::size_t total = 0;
    for (std::size_t c = 0; c < curves->items.size(); ++c) {
      FeatureCurveSpec spec;
      if (Status s = read_curve(display_name, curves->items[c], c, spec); !s) return s;
      for (const auto& prev : f.curves)
        if (prev.name == spec.name)
          return bad(display_name, spec.line,
                     "curve '" + spec.name + "' is given twice (first at line " + std::to_string(prev.line) + ")");
      total += spec.points.size();
      if (total > kMaxPoints)
        return bad(display_name, spec.line, "more than " + std::to_string(kMaxPoints) + " points in the file");
      f.curves.push_back(std::move(spec));
    }
    return f;
  } catch (const std::bad_alloc&) {
    return Status(ErrorCode::kParse, std::string(display_name) + ": out of memory while reading");
  }
}

Expected<FeatureCurveFile> read_feature_curves(const std::filesystem::path& path) {
  const std::string name = path.string();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return Status(ErrorCode::kIo, name + ": no such file");
  const auto size = std::filesystem::file_size(path, ec);
  if (ec) return Status(ErrorCode::kIo, name + ": " + ec.message());
  if (size > kMaxFileBytes) return Status(ErrorCode::kParse, name + ": larger than 64 MB; not a feature-curve file");
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status(ErrorCode::kIo, name + ": cannot be opened");
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) return Status(ErrorCode::kIo, name + ": read error");
  return parse_feature_curves(ss.str(), name);
}

void write_feature_curves(const FeatureCurveFile& f, const std::filesystem::path& path) {
  for (const auto& c : f.curves) {
    if (c.points.size() < (c.closed ? 3u : 2u))
      throw Error(Status(ErrorCode::kInvalidArgument, path.string() + ": curve '" + c.name + "' has too few points"));
    for (const Vec3d& p : c.points)
      if (!p.allFinite() || p.cwiseAbs().maxCoeff() > kMaxCoordinate)
        throw Error(Status(ErrorCode::kInvalidArgument,
                           path.string() + ": curve '" + c.name + "' has a non-finite or out-of-range point"));
  }
  std::string s = "{";
  if (f.has_units) s += "\"units\": \"" + std::string(f.scale == 1.0 ? "m" : f.scale == 0.01 ? "cm" : "mm") + "\", ";
  if (f.has_up) s += "\"up\": \"" + std::string(f.up_z ? "z" : "y") + "\", ";
  s += "\"curves\": [\n";
  for (std::size_t c = 0; c < f.curves.size(); ++c) {
    const auto& k = f.curves[c];
    s += "  {\"name\": \"" + k.name + "\", \"closed\": " + (k.closed ? "true" : "false") + ", \"points\": [";
    for (std::size_t i = 0; i < k.points.size(); ++i) {
      s += i ? ",\n    [" : "\n    [";
      for (int d = 0; d < 3; ++d) {
        if (d) s += ", ";
        // Shortest text that reads back to the same double (std::to_chars).
        char buf[32];
        const auto r = std::to_chars(buf, buf + sizeof buf, k.points[i][d]);
        s.append(buf, r.ptr);
      }
      s += "]";
    }
    s += "]}";
    s += c + 1 < f.curves.size() ? ",\n" : "\n";
  }
  s += "]}\n";
  write_atomically(path, [&](AtomicFile& out) { out.write(s); });
}

}  // namespace atelier
