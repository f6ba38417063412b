#include <atelier/io/makehuman/mhclo.h>

#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>

#include <atelier/engine/status.h>

namespace atelier::makehuman {

namespace {

[[noreturn]] void fail(const std::filesystem::path& f, std::size_t line, const std::string& what) {
  std::ostringstream s;
  s << f.string() << ":" << line << ": " << what;
  throw Error(Status(ErrorCode::kParse, s.str()));
}

std::vector<std::string_view> words(std::string_view l) {
  std::vector<std::string_view> out;
  auto blank = [](char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; };
  std::size_t i = 0;
  while (i < l.size()) {
    while (i < l.size() && blank(l[i])) ++i;
    const std::size_t b = i;
    while (i < l.size() && !blank(l[i])) ++i;
    if (i > b) out.push_back(l.substr(b, i - b));
  }
  return out;
}

bool starts_numeric(std::string_view w) {
  return !w.empty() && (std::isdigit(static_cast<unsigned char>(w[0])) || w[0] == '-' || w[0] == '+' || w[0] == '.');
}

/// Reads one .mhclo line after another; numbers are parsed strictly (the
/// whole word, in range) so that no value is silently truncated.
class MhcloParser {
 public:
  MhcloParser(const std::filesystem::path& file, std::uint32_t n) : file_(file), n_(n) {}

  GarmentBinding run(std::string_view text) {
    if (text.starts_with("\xEF\xBB\xBF")) text.remove_prefix(3);
    std::size_t pos = 0;
    while (pos < text.size()) {
      std::size_t nl = text.find('\n', pos);
      if (nl == std::string_view::npos) nl = text.size();
      ++ln_;
      line(text.substr(pos, nl - pos));
      pos = nl + 1;
    }
    if (b_.refs.empty()) fail(file_, ln_, "no 'verts' section (not a MakeHuman garment binding)");
    return std::move(b_);
  }

 private:
  double real(std::string_view w) const {
    double v = 0;
    if (!w.empty() && w[0] == '+') w.remove_prefix(1);
    const auto r = std::from_chars(w.data(), w.data() + w.size(), v);
    if (r.ec == std::errc::result_out_of_range) fail(file_, ln_, "number '" + std::string(w) + "' out of the range of a double");
    if (r.ec != std::errc{} || r.ptr != w.data() + w.size()) fail(file_, ln_, "'" + std::string(w) + "' is not a number");
    if (!std::isfinite(v)) fail(file_, ln_, "non-finite value '" + std::string(w) + "'");
    return v;
  }
  std::uint32_t index(std::string_view w) const {
    long long v = 0;
    const auto r = std::from_chars(w.data(), w.data() + w.size(), v);
    if (r.ec != std::errc{} || r.ptr != w.data() + w.size()) {
      if (r.ec == std::errc::result_out_of_range || (r.ptr != w.data() && r.ptr == w.data() + w.size()))
        fail(file_, ln_, "vertex index " + std::string(w) + " out of range (the base mesh has " + std::to_string(n_) +
                             " vertices)");
      fail(file_, ln_, "'" + std::string(w) + "' is not a vertex index (an integer)");
    }
    if (v < 0 || v >= static_cast<long long>(n_))
      fail(file_, ln_, "vertex index " + std::to_string(v) + " out of range (the base mesh has " + std::to_string(n_) +
                           " vertices)");
    return static_cast<std::uint32_t>(v);
  }

  void line(std::string_view l) {
    const std::vector<std::string_view> w = words(l);
    // Blank or whitespace-only lines carry no word: MakeHuman skips them and
    // so do we, in every section (they do not end a `verts` section).
    if (w.empty() || w[0][0] == '#') return;
    if (mode_ == kDelete && (std::isdigit(static_cast<unsigned char>(w[0][0])) || w[0] == "-")) {
      delete_line(w);
      return;
    }
    if (starts_numeric(w[0])) {
      if (mode_ != kVerts) fail(file_, ln_, "numbers before a 'verts' section");
      binding_line(w);
      return;
    }
    const std::string_view key = w[0];
    if (key == "verts") {
      mode_ = kVerts;
    } else if (key == "delete_verts") {
      mode_ = kDelete;
    } else if (key == "name") {
      if (w.size() > 1) b_.name = std::string(w[1]);
    } else if (key == "obj_file") {
      if (w.size() > 1) b_.obj_file = std::string(w[1]);
    } else if (key == "z_depth") {
      int z = 0;
      const auto r = w.size() == 2 ? std::from_chars(w[1].data(), w[1].data() + w[1].size(), z) : std::from_chars_result{};
      if (w.size() != 2 || r.ec != std::errc{} || r.ptr != w[1].data() + w[1].size())
        fail(file_, ln_, "z_depth needs one integer");
      b_.z_depth = z;
      b_.has_z_depth = true;
    } else if (key == "x_scale" || key == "y_scale" || key == "z_scale") {
      const int axis = key[0] - 'x';
      if (w.size() != 4) fail(file_, ln_, std::string(key) + " needs two vertex indices and a positive distance");
      b_.scale_a[axis] = index(w[1]);
      b_.scale_b[axis] = index(w[2]);
      const double d = real(w[3]);
      if (!(d > 0)) fail(file_, ln_, std::string(key) + " needs two vertex indices and a positive distance");
      b_.scale_d[axis] = d;
      b_.has_scale[axis] = true;
    } else {
      mode_ = kHeader;  // other header keys (uuid, tag, material, ...) are skipped
    }
  }

  void delete_line(const std::vector<std::string_view>& w) {
    // Indices and ranges "a - b".
    bool range = false;
    for (std::string_view tok : w) {
      if (tok == "-") {
        if (b_.delete_verts.empty() || range) fail(file_, ln_, "a range needs a start index");
        range = true;
        continue;
      }
      const std::uint32_t hi = index(tok);
      if (range) {
        for (std::uint32_t x = b_.delete_verts.back() + 1; x <= hi; ++x) b_.delete_verts.push_back(x);
        range = false;
      } else {
        b_.delete_verts.push_back(hi);
      }
    }
    if (range) fail(file_, ln_, "a range needs an end index");
  }

  void binding_line(const std::vector<std::string_view>& w) {
    GarmentBinding::Ref r;
    if (w.size() == 1) {
      r.v = {index(w[0]), 0, 0};
      r.w = {1, 0, 0};
    } else if (w.size() == 9) {
      for (int k = 0; k < 3; ++k) {
        r.v[k] = index(w[k]);
        r.w[k] = real(w[3 + k]);
      }
      r.offset = Vec3d(real(w[6]), real(w[7]), real(w[8]));
    } else {
      fail(file_, ln_, "a binding line needs 1 or 9 numbers, found " + std::to_string(w.size()));
    }
    b_.refs.push_back(r);
  }

  const std::filesystem::path& file_;
  std::uint32_t n_;
  std::size_t ln_ = 0;
  enum { kHeader, kVerts, kDelete } mode_ = kHeader;
  GarmentBinding b_;
};

}  // namespace

GarmentBinding parse_mhclo(std::string_view text, const std::filesystem::path& file, std::uint32_t n) {
  return MhcloParser(file, n).run(text);
}

GarmentBinding read_mhclo(const std::filesystem::path& file, std::uint32_t n) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw Error(Status(ErrorCode::kIo, file.string() + ": cannot open"));
  std::ostringstream ss;
  ss << in.rdbuf();
  return parse_mhclo(ss.str(), file, n);
}

}  // namespace atelier::makehuman
