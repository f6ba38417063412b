#include <atelier/io/png.h>

#include <zlib.h>

#include <algorithm>
#include <array>
#include <cstdlib>
#include <cstring>
#include <limits>

#include <atelier/engine/status.h>
#include <atelier/io/atomic_file.h>
#include <atelier/io/crc32.h>
#include <atelier/io/mesh_arrays.h>

namespace atelier {

namespace {

constexpr std::array<std::uint8_t, 8> kSignature = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};

std::uint32_t crc_update(std::uint32_t crc, const std::uint8_t* p, std::size_t n) noexcept {
  return io_detail::crc32_update(crc, p, n);
}

void put_u32(std::string& out, std::uint32_t v) {
  out.push_back(static_cast<char>(v >> 24));
  out.push_back(static_cast<char>(v >> 16));
  out.push_back(static_cast<char>(v >> 8));
  out.push_back(static_cast<char>(v));
}

std::uint32_t get_u32(const std::uint8_t* p) noexcept {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) | p[3];
}

void put_chunk(std::string& out, const char type[4], std::string_view data) {
  put_u32(out, static_cast<std::uint32_t>(data.size()));
  const std::size_t start = out.size();
  out.append(type, 4);
  out.append(data);
  const auto* bytes = reinterpret_cast<const std::uint8_t*>(out.data() + start);
  put_u32(out, crc_update(0xffffffffu, bytes, out.size() - start) ^ 0xffffffffu);
}

// Paeth predictor (PNG specification 9.4).
std::uint8_t paeth(int a, int b, int c) noexcept {
  const int p = a + b - c;
  const int pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
  if (pa <= pb && pa <= pc) return static_cast<std::uint8_t>(a);
  if (pb <= pc) return static_cast<std::uint8_t>(b);
  return static_cast<std::uint8_t>(c);
}

// The prediction of filter type f (0 none, 1 sub, 2 up, 3 average, 4 Paeth)
// from the left (a), upper (b) and upper-left (c) bytes: filtering subtracts
// it, decoding adds it back.
int predictor(int f, int a, int b, int c) noexcept {
  switch (f) {
    case 1:
      return a;
    case 2:
      return b;
    case 3:
      return (a + b) / 2;
    case 4:
      return paeth(a, b, c);
    default:
      return 0;
  }
}

// Filters one row with filter `f`; bpp bytes per pixel, prev = previous raw
// row (zeros for the first).
void filter_row(int f, const std::uint8_t* row, const std::uint8_t* prev, std::size_t n, std::size_t bpp,
                std::uint8_t* out) noexcept {
  for (std::size_t i = 0; i < n; ++i) {
    const int a = i >= bpp ? row[i - bpp] : 0;
    const int b = prev[i];
    const int c = i >= bpp ? prev[i - bpp] : 0;
    const int pred = predictor(f, a, b, c);
    out[i] = static_cast<std::uint8_t>(row[i] - pred);
  }
}

Error png_error(std::string_view name, std::string_view what) {
  return Error(Status(ErrorCode::kParse, std::string(name) + ": " + std::string(what)));
}

}  // namespace

std::uint32_t png_crc32(std::span<const std::uint8_t> bytes) noexcept {
  return crc_update(0xffffffffu, bytes.data(), bytes.size()) ^ 0xffffffffu;
}

std::string encode_png(const RgbImage& image, int level) {
  if (image.width == 0 || image.height == 0)
    throw Error(Status(ErrorCode::kInvalidArgument, "encode_png: empty image"));
  const std::size_t stride = std::size_t{3} * image.width;
  if (image.pixels.size() != stride * image.height)
    throw Error(Status(ErrorCode::kInvalidArgument, "encode_png: pixel array of the wrong size"));
  if (image.width > 0x7fffffffu || image.height > 0x7fffffffu)
    throw Error(Status(ErrorCode::kInvalidArgument, "encode_png: image too large"));

  // Filtered scanlines: one filter byte then the row (PNG specification 7.3).
  std::vector<std::uint8_t> raw((stride + 1) * image.height);
  std::vector<std::uint8_t> zero(stride, 0), candidate(stride);
  for (std::uint32_t y = 0; y < image.height; ++y) {
    const std::uint8_t* row = image.pixels.data() + y * stride;
    const std::uint8_t* prev = y ? row - stride : zero.data();
    std::uint8_t* dst = raw.data() + y * (stride + 1);
    std::uint64_t best = std::numeric_limits<std::uint64_t>::max();
    for (int f = 0; f < 5; ++f) {
      filter_row(f, row, prev, stride, 3, candidate.data());
      // Minimum sum of absolute differences, bytes read as signed (12.8).
      std::uint64_t sum = 0;
      for (std::uint8_t v : candidate) sum += static_cast<std::uint64_t>(std::abs(static_cast<std::int8_t>(v)));
      if (sum < best) {
        best = sum;
        dst[0] = static_cast<std::uint8_t>(f);
        std::memcpy(dst + 1, candidate.data(), stride);
      }
    }
  }
  uLongf zsize = compressBound(static_cast<uLong>(raw.size()));
  std::string z(zsize, '\0');
  if (compress2(reinterpret_cast<Bytef*>(z.data()), &zsize, raw.data(), static_cast<uLong>(raw.size()),
                std::clamp(level, 0, 9)) != Z_OK)
    throw Error(Status(ErrorCode::kInternal, "encode_png: zlib compress2 failed"));
  z.resize(zsize);

  std::string out(reinterpret_cast<const char*>(kSignature.data()), kSignature.size());
  std::string ihdr;
  put_u32(ihdr, image.width);
  put_u32(ihdr, image.height);
  ihdr += std::string{'\x08', '\x02', '\x00', '\x00', '\x00'};  // depth 8, RGB, deflate, adaptive, no interlace
  put_chunk(out, "IHDR", ihdr);
  put_chunk(out, "IDAT", z);
  put_chunk(out, "IEND", {});
  return out;
}

void write_png(const RgbImage& image, const std::filesystem::path& path, int level) {
  const std::string bytes = encode_png(image, level);
  write_atomically(path, [&](AtomicFile& f) { f.write(bytes); });
}

RgbImage decode_png(std::string_view bytes, std::string_view name) {
  const auto* p = reinterpret_cast<const std::uint8_t*>(bytes.data());
  const std::size_t n = bytes.size();
  if (n < kSignature.size() || std::memcmp(p, kSignature.data(), kSignature.size()) != 0)
    throw png_error(name, "not a PNG file (bad signature)");
  std::size_t pos = kSignature.size();
  std::uint32_t width = 0, height = 0;
  int channels = 0;
  bool have_header = false, have_end = false;
  std::string idat;
  while (pos < n && !have_end) {
    if (n - pos < 12) throw png_error(name, "truncated chunk at byte offset " + std::to_string(pos));
    const std::uint32_t len = get_u32(p + pos);
    if (len > n - pos - 12) throw png_error(name, "chunk length past the end at byte offset " + std::to_string(pos));
    const std::uint8_t* type = p + pos + 4;
    const std::uint8_t* data = type + 4;
    const std::string tname(reinterpret_cast<const char*>(type), 4);
    if (get_u32(data + len) != (crc_update(0xffffffffu, type, len + 4) ^ 0xffffffffu))
      throw png_error(name, "CRC mismatch in chunk " + tname + " at byte offset " + std::to_string(pos));
    if (tname == "IHDR") {
      if (len != 13) throw png_error(name, "IHDR of the wrong length");
      width = get_u32(data);
      height = get_u32(data + 4);
      const int depth = data[8], colour = data[9];
      if (width == 0 || height == 0 || width > (1u << 24) || height > (1u << 24))
        throw png_error(name, "unsupported image size");
      if (depth != 8) throw png_error(name, "unsupported bit depth " + std::to_string(depth) + " (8 only)");
      switch (colour) {
        case 0:
          channels = 1;
          break;
        case 2:
          channels = 3;
          break;
        case 4:
          channels = 2;
          break;
        case 6:
          channels = 4;
          break;
        default:
          throw png_error(name, "unsupported colour type " + std::to_string(colour));
      }
      if (data[10] != 0 || data[11] != 0) throw png_error(name, "unknown compression or filter method");
      if (data[12] != 0) throw png_error(name, "interlaced images are not supported");
      have_header = true;
    } else if (tname == "IDAT") {
      if (!have_header) throw png_error(name, "IDAT before IHDR");
      idat.append(reinterpret_cast<const char*>(data), len);
    } else if (tname == "IEND") {
      have_end = true;
    } else if (!(type[0] & 0x20)) {
      throw png_error(name, "unknown critical chunk " + tname);
    }
    pos += std::size_t{len} + 12;
  }
  if (!have_header) throw png_error(name, "no IHDR chunk");
  if (!have_end) throw png_error(name, "no IEND chunk");

  const std::size_t bpp = static_cast<std::size_t>(channels);
  const std::size_t stride = bpp * width;
  std::vector<std::uint8_t> raw((stride + 1) * height);
  z_stream zs{};
  if (inflateInit(&zs) != Z_OK) throw Error(Status(ErrorCode::kInternal, "decode_png: inflateInit failed"));
  zs.next_in = reinterpret_cast<Bytef*>(idat.data());
  zs.avail_in = static_cast<uInt>(idat.size());
  zs.next_out = raw.data();
  zs.avail_out = static_cast<uInt>(raw.size());
  const int rc = inflate(&zs, Z_FINISH);
  const std::size_t produced = raw.size() - zs.avail_out;
  inflateEnd(&zs);
  if (rc != Z_STREAM_END || produced != raw.size())
    throw png_error(name, "image data does not inflate to " + std::to_string(raw.size()) + " bytes");

  std::vector<std::uint8_t> cur(stride), prev(stride, 0);
  RgbImage img(width, height);
  for (std::uint32_t y = 0; y < height; ++y) {
    const std::uint8_t* src = raw.data() + y * (stride + 1);
    const int f = src[0];
    if (f > 4) throw png_error(name, "bad filter type " + std::to_string(f) + " on row " + std::to_string(y));
    for (std::size_t i = 0; i < stride; ++i) {
      const int a = i >= bpp ? cur[i - bpp] : 0;
      const int b = prev[i];
      const int c = i >= bpp ? prev[i - bpp] : 0;
      const int pred = predictor(f, a, b, c);
      cur[i] = static_cast<std::uint8_t>(src[1 + i] + pred);
    }
    for (std::uint32_t x = 0; x < width; ++x) {
      const std::uint8_t* s = cur.data() + x * bpp;
      std::uint8_t* d = img.at(x, y);
      if (channels <= 2) {
        d[0] = d[1] = d[2] = s[0];
      } else {
        d[0] = s[0];
        d[1] = s[1];
        d[2] = s[2];
      }
    }
    std::swap(cur, prev);
  }
  return img;
}

RgbImage read_png(const std::filesystem::path& path) {
  const std::string bytes = io_detail::read_file_bytes(path);
  return decode_png(bytes, path.string());
}

}  // namespace atelier
