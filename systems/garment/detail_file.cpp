// The detail-template file (.atd): magic, version, sizes and topology hash,
// the CSR matrix, then a checksum of everything before it. Version 3 (what
// is written) has, after the matrix, the garment's layer order (one byte:
// 1 if it has one, then its z_depth as an int32) and ends in the CRC-32 of
// the native formats (io/checksum.h); it is written through an AtomicFile.
// Version 2 files (no layer order) and version 1 files (no layer order, an
// FNV-1a sum) are still read. Version 4 adds one byte of frame flags after
// the layer order (bit 0: scaled frames, DetailParams::scaled_frames); it is
// written only for an encoding with scaled frames, so files of encodings
// without them stay version 3, readable by older builds.
#include <atelier/systems/garment/detail_template.h>

#include <array>
#include <cmath>
#include <cstring>
#include <string>

#include <atelier/io/atomic_file.h>
#include <atelier/io/checksum.h>
#include <atelier/io/mesh_arrays.h>
#include "detail_template_detail.h"

namespace atelier {

using namespace detail_internal;

namespace {

constexpr char kMagic[8] = {'A', 'T', 'L', 'D', 'E', 'T', 'L', '1'};
constexpr std::uint32_t kVersion = 4;  // 3: no frame flags, 2: no z_depth, 1: also an FNV-1a checksum

template <class T>
void put(std::string& s, const T& v) {
  s.append(reinterpret_cast<const char*>(&v), sizeof v);
}
template <class T>
void put_vec(std::string& s, const std::vector<T>& v) {
  s.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
}

}  // namespace

void write_detail(const DetailEncoding& enc, const std::filesystem::path& path) {
  std::string s(kMagic, 8);
  put(s, enc.scaled_frames ? kVersion : std::uint32_t{3});
  put(s, enc.polygon_count);
  put(s, enc.body_node_count);
  put(s, enc.topology_hash);
  put(s, static_cast<std::uint64_t>(enc.vertex_count()));
  put(s, static_cast<std::uint64_t>(enc.entries()));
  put(s, static_cast<std::uint64_t>(enc.reference_corners.size()));
  put_vec(s, enc.row);
  put_vec(s, enc.polygon);
  put_vec(s, enc.a);
  put_vec(s, enc.b);
  put_vec(s, enc.c);
  put_vec(s, enc.d);
  put_vec(s, enc.reference_corners);
  put(s, static_cast<std::uint8_t>(enc.z_depth.has_value()));
  put(s, enc.z_depth.value_or(0));
  if (enc.scaled_frames) put(s, std::uint8_t{1});
  put(s, crc32(s));
  write_atomically(path, [&](AtomicFile& f) { f.write(s); });
}

DetailEncoding read_detail(const std::filesystem::path& path) {
  const std::string bytes = io_detail::read_file_bytes(path);
  return read_detail_from_bytes(bytes, path.string());
}

DetailEncoding read_detail_from_bytes(std::string_view s, std::string_view display_name) {
  std::size_t pos = 0;
  auto fail = [&](const std::string& what) {
    throw Error(Status(ErrorCode::kParse, std::string(display_name) + ": byte offset " + std::to_string(pos) + ": " + what));
  };
  auto get = [&](void* dst, std::size_t n, const char* what) {
    if (n > s.size() - pos) fail(std::string("truncated file (while reading ") + what + ")");
    if (n == 0) return;  // an empty array's data() may be null: memcpy(nullptr, ., 0) is undefined
    std::memcpy(dst, s.data() + pos, n);
    pos += n;
  };
  char magic[8];
  get(magic, 8, "magic");
  if (std::memcmp(magic, kMagic, 8) != 0) {
    pos = 0;
    fail("not an Atelier detail template (bad magic)");
  }
  std::uint32_t version;
  get(&version, 4, "version");
  if (version < 1 || version > kVersion) {
    pos -= 4;
    fail("unsupported version " + std::to_string(version) + " (this atelier reads versions 1 to 4)");
  }
  DetailEncoding e;
  std::uint64_t nv, ne, nc;
  get(&e.polygon_count, 4, "header");
  get(&e.body_node_count, 4, "header");
  get(&e.topology_hash, 8, "header");
  get(&nv, 8, "header");
  get(&ne, 8, "header");
  get(&nc, 8, "header");
  // With the layer order and the frame flags.
  const std::size_t sum_bytes = (version == 1 ? 8 : 4) + (version >= 3 ? 5 : 0) + (version >= 4 ? 1 : 0);
  // Sizes are checked against the file before anything is allocated.
  if (nv >= s.size() || ne > s.size() || nc > s.size() || s.size() - pos < (nv + 1) * 4 + ne * 20 + nc * 8 + sum_bytes)
    fail("truncated file (the sizes in the header exceed the file)");
  // Where each array starts, to name the byte offset of a bad value.
  const std::size_t row_at = pos, polygon_at = row_at + (nv + 1) * 4, coeff_at = polygon_at + ne * 4,
                    corners_at = coeff_at + ne * 16;
  e.row.resize(nv + 1);
  e.polygon.resize(ne);
  for (auto* v : {&e.a, &e.b, &e.c, &e.d}) v->resize(ne);
  get(e.row.data(), e.row.size() * 4, "rows");
  get(e.polygon.data(), ne * 4, "polygons");
  for (auto* v : {&e.a, &e.b, &e.c, &e.d}) get(v->data(), ne * 4, "coefficients");
  e.reference_corners.resize(nc);
  get(e.reference_corners.data(), nc * 8, "reference corners");
  std::size_t z_at = pos;
  std::uint8_t has_z = 0;
  std::int32_t z = 0;
  if (version >= 3) {
    get(&has_z, 1, "layer order");
    get(&z, 4, "layer order");
  }
  const std::size_t flags_at = pos;
  std::uint8_t flags = 0;
  if (version >= 4) get(&flags, 1, "frame flags");
  const std::size_t body_end = pos;
  bool ok = false;
  if (version == 1) {
    std::uint64_t sum;
    get(&sum, 8, "checksum");
    ok = sum == fnv1a(0xcbf29ce484222325ull, s.data(), body_end);
  } else {
    std::uint32_t sum;
    get(&sum, 4, "checksum");
    ok = sum == crc32(s.data(), body_end);
  }
  if (!ok) {
    pos = body_end;
    fail("checksum mismatch (corrupted file)");
  }
  if (pos != s.size()) fail(std::to_string(s.size() - pos) + " bytes after the checksum");
  if (has_z > 1) {
    pos = z_at;
    fail("bad layer-order flag " + std::to_string(has_z) + " (0 or 1)");
  }
  if (has_z) e.z_depth = z;
  if (flags > 1) {
    pos = flags_at;
    fail("bad frame flags " + std::to_string(flags) + " (0 or 1)");
  }
  e.scaled_frames = flags == 1;
  if (e.scaled_frames && nc == 0) {
    pos = flags_at;
    fail("scaled frames without reference corners");
  }
  pos = row_at;
  if (e.row.front() != 0) fail("row offsets do not start at 0");
  pos = row_at + nv * 4;
  if (e.row.back() != ne) fail("row offsets do not cover the entries");
  for (std::size_t v = 0; v < nv; ++v) {
    pos = row_at + (v + 1) * 4;
    if (e.row[v] > e.row[v + 1]) fail("row offsets decrease at vertex " + std::to_string(v));
  }
  for (std::size_t i = 0; i < ne; ++i) {
    pos = polygon_at + i * 4;
    if (e.polygon[i] >= e.polygon_count) fail("entry " + std::to_string(i) + " names a polygon out of range");
  }
  for (std::size_t k = 0; k < 4; ++k) {
    const std::vector<float>& v = *std::array{&e.a, &e.b, &e.c, &e.d}[k];
    for (std::size_t i = 0; i < ne; ++i) {
      pos = coeff_at + (k * ne + i) * 4;
      if (!std::isfinite(v[i])) fail("entry " + std::to_string(i) + " has a non-finite coefficient");
    }
  }
  for (std::size_t i = 0; i < nc; ++i) {
    pos = corners_at + i * 8;
    if (!e.reference_corners[i].allFinite()) fail("reference corner " + std::to_string(i) + " is not finite");
  }
  return e;
}

}  // namespace atelier
