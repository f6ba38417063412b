#include <atelier/io/makehuman/mhclo.h>

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
}  // namespace

GarmentBinding read_mhclo(const std::filesystem::path& file, std::uint32_t n) {
  std::ifstream in(file);
  if (!in) throw Error(Status(ErrorCode::kIo, file.string() + ": cannot open"));
  GarmentBinding b;
  std::string line;
  std::size_t ln = 0;
  enum { kHeader, kVerts, kDelete } mode = kHeader;
  auto check_index = [&](long long v) {
    if (v < 0 || v >= n) {
      std::ostringstream s;
      s << "vertex index " << v << " out of range (the base mesh has " << n << " vertices)";
      fail(file, ln, s.str());
    }
    return static_cast<std::uint32_t>(v);
  };
  while (std::getline(in, line)) {
    ++ln;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line[0] == '#') continue;
    std::istringstream s(line);
    std::string key;
    s >> key;
    if (mode == kDelete && (std::isdigit(static_cast<unsigned char>(key[0])) || key == "-")) {
      // Indices and ranges "a - b".
      std::istringstream t(line);
      std::string tok;
      bool range = false;
      while (t >> tok) {
        if (tok == "-") {
          if (b.delete_verts.empty() || range) fail(file, ln, "a range needs a start index");
          range = true;
          continue;
        }
        char* end = nullptr;
        const long long v = std::strtoll(tok.c_str(), &end, 10);
        if (*end != '\0') fail(file, ln, "'" + tok + "' is not a vertex index");
        const std::uint32_t hi = check_index(v);
        if (range) {
          for (std::uint32_t x = b.delete_verts.back() + 1; x <= hi; ++x) b.delete_verts.push_back(x);
          range = false;
        } else {
          b.delete_verts.push_back(hi);
        }
      }
      if (range) fail(file, ln, "a range needs an end index");
      continue;
    }
    if (std::isdigit(static_cast<unsigned char>(key[0])) || key[0] == '-') {
      std::istringstream t(line);
      std::vector<double> x;
      double d;
      while (t >> d) x.push_back(d);
      if (!t.eof()) fail(file, ln, "non-numeric token in a binding line");
      if (mode == kVerts) {
        GarmentBinding::Ref r;
        if (x.size() == 1) {
          r.v = {check_index(static_cast<long long>(x[0])), 0, 0};
          r.w = {1, 0, 0};
        } else if (x.size() == 9) {
          for (int k = 0; k < 3; ++k) {
            if (x[k] != std::floor(x[k])) fail(file, ln, "vertex index is not an integer");
            r.v[k] = check_index(static_cast<long long>(x[k]));
            r.w[k] = x[3 + k];
          }
          r.offset = Vec3d(x[6], x[7], x[8]);
          if (!r.offset.allFinite() || !std::isfinite(r.w[0] + r.w[1] + r.w[2])) fail(file, ln, "non-finite value");
        } else {
          std::ostringstream m;
          m << "a binding line needs 1 or 9 numbers, found " << x.size();
          fail(file, ln, m.str());
        }
        b.refs.push_back(r);
      } else {
        fail(file, ln, "numbers before a 'verts' section");
      }
      continue;
    }
    if (key == "verts") {
      mode = kVerts;
    } else if (key == "delete_verts") {
      mode = kDelete;
    } else if (key == "name") {
      s >> b.name;
    } else if (key == "obj_file") {
      s >> b.obj_file;
    } else if (key == "z_depth") {
      if (!(s >> b.z_depth)) fail(file, ln, "z_depth needs an integer");
    } else if (key == "x_scale" || key == "y_scale" || key == "z_scale") {
      const int axis = key[0] - 'x';
      long long a, c;
      double d;
      if (!(s >> a >> c >> d) || !(d > 0)) fail(file, ln, key + " needs two vertex indices and a positive distance");
      b.scale_a[axis] = check_index(a);
      b.scale_b[axis] = check_index(c);
      b.scale_d[axis] = d;
      b.has_scale[axis] = true;
    } else {
      mode = kHeader;  // other header keys (uuid, tag, material, ...) are skipped
    }
  }
  if (b.refs.empty()) fail(file, ln, "no 'verts' section");
  return b;
}

}  // namespace atelier::makehuman
