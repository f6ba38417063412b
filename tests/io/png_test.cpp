// PNG writer and reader (io/png.h): round trips of random and structured
// pictures, chunk CRCs recomputed independently with zlib's crc32, the image
// data inflated independently with zlib, and refusal of damaged files.
#include <gtest/gtest.h>
#include <zlib.h>

#include <random>
#include <string>
#include <vector>

#include "io/io_test_support.h"
#include <atelier/io/png.h>

namespace atelier {
namespace {

RgbImage random_image(std::uint32_t w, std::uint32_t h, std::uint32_t seed) {
  RgbImage img(w, h);
  std::mt19937 rng(seed);
  for (auto& b : img.pixels) b = static_cast<std::uint8_t>(rng());
  return img;
}

// Smooth gradients with flat areas: every PNG filter gets chosen somewhere.
RgbImage gradient_image(std::uint32_t w, std::uint32_t h) {
  RgbImage img(w, h);
  for (std::uint32_t y = 0; y < h; ++y)
    for (std::uint32_t x = 0; x < w; ++x) {
      std::uint8_t* p = img.at(x, y);
      p[0] = static_cast<std::uint8_t>(x * 3);
      p[1] = static_cast<std::uint8_t>(y * 5);
      p[2] = (x / 8 + y / 8) % 2 ? 200 : static_cast<std::uint8_t>((x * y) & 0xff);
    }
  return img;
}

std::uint32_t be32(const std::string& s, std::size_t at) {
  const auto* p = reinterpret_cast<const unsigned char*>(s.data() + at);
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) | p[3];
}

struct Chunk {
  std::string type;
  std::size_t offset;  // of the length field
  std::uint32_t length;
};

std::vector<Chunk> chunks(const std::string& png) {
  std::vector<Chunk> out;
  for (std::size_t pos = 8; pos + 12 <= png.size();) {
    const std::uint32_t len = be32(png, pos);
    out.push_back({png.substr(pos + 4, 4), pos, len});
    pos += 12 + len;
  }
  return out;
}

TEST(Png, RoundTripsAndSizes) {
  for (const auto& [w, h] : std::vector<std::pair<std::uint32_t, std::uint32_t>>{{1, 1}, {7, 3}, {64, 48}, {255, 1}}) {
    const RgbImage a = random_image(w, h, w * 131 + h);
    EXPECT_EQ(decode_png(encode_png(a)), a) << w << "x" << h;
  }
  const RgbImage g = gradient_image(120, 90);
  EXPECT_EQ(decode_png(encode_png(g, 9)), g);
  EXPECT_EQ(decode_png(encode_png(g, 0)), g);
  // Structured pictures compress; a flat one to almost nothing.
  EXPECT_LT(encode_png(RgbImage(200, 200, 255)).size(), 1000u);
  EXPECT_LT(encode_png(g).size(), g.pixels.size() / 2);
}

TEST(Png, ChunksHaveValidCrcsAndTheDataInflatesIndependently) {
  const RgbImage g = gradient_image(50, 40);
  const std::string png = encode_png(g);
  ASSERT_EQ(png.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  const auto cs = chunks(png);
  ASSERT_EQ(cs.size(), 3u);
  EXPECT_EQ(cs[0].type, "IHDR");
  EXPECT_EQ(cs[1].type, "IDAT");
  EXPECT_EQ(cs[2].type, "IEND");
  EXPECT_EQ(cs[2].offset + 12 + cs[2].length, png.size());
  for (const Chunk& c : cs) {
    const auto* p = reinterpret_cast<const Bytef*>(png.data() + c.offset + 4);
    const auto zcrc = static_cast<std::uint32_t>(crc32(0L, p, c.length + 4));
    EXPECT_EQ(be32(png, c.offset + 8 + c.length), zcrc) << c.type;
  }
  EXPECT_EQ(be32(png, cs[0].offset + 8), 50u);
  EXPECT_EQ(be32(png, cs[0].offset + 12), 40u);
  // Inflate with zlib and undo the filters by hand (row filter bytes 0..4).
  std::vector<unsigned char> raw((50 * 3 + 1) * 40);
  uLongf n = raw.size();
  ASSERT_EQ(uncompress(raw.data(), &n, reinterpret_cast<const Bytef*>(png.data() + cs[1].offset + 8), cs[1].length),
            Z_OK);
  ASSERT_EQ(n, raw.size());
  std::vector<int> prev(150, 0), cur(150);
  std::vector<int> filters_used(5, 0);
  for (int y = 0; y < 40; ++y) {
    const unsigned char* row = raw.data() + y * 151;
    ASSERT_LE(row[0], 4);
    ++filters_used[row[0]];
    for (int i = 0; i < 150; ++i) {
      const int a = i >= 3 ? cur[i - 3] : 0, b = prev[i], c = i >= 3 ? prev[i - 3] : 0;
      int pred = 0;
      if (row[0] == 1) pred = a;
      if (row[0] == 2) pred = b;
      if (row[0] == 3) pred = (a + b) / 2;
      if (row[0] == 4) {
        const int p = a + b - c, pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
        pred = pa <= pb && pa <= pc ? a : (pb <= pc ? b : c);
      }
      cur[i] = (row[1 + i] + pred) & 0xff;
      ASSERT_EQ(cur[i], g.at(static_cast<std::uint32_t>(i / 3), static_cast<std::uint32_t>(y))[i % 3]);
    }
    std::swap(prev, cur);
  }
  EXPECT_GE(std::count_if(filters_used.begin(), filters_used.end(), [](int k) { return k > 0; }), 2);
}

TEST(Png, WritesAtomicallyAndReadsBack) {
  test::TempDir dir;
  const RgbImage a = random_image(33, 17, 5);
  write_png(a, dir / "a.png");
  EXPECT_EQ(read_png(dir / "a.png"), a);
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"a.png"});  // no temporary left behind
  EXPECT_THROW(write_png(a, dir / "missing" / "a.png"), Error);
  EXPECT_THROW((void)read_png(dir / "nope.png"), Error);
  EXPECT_THROW((void)encode_png(RgbImage{}), Error);
  RgbImage bad(4, 4);
  bad.pixels.pop_back();
  EXPECT_THROW((void)encode_png(bad), Error);
}

TEST(Png, RefusesDamagedFiles) {
  const std::string good = encode_png(gradient_image(20, 10));
  auto code = [](const std::string& bytes) {
    try {
      (void)decode_png(bytes, "x.png");
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("x.png"), std::string::npos) << e.what();
      return e.status().code();
    }
    return ErrorCode::kOk;
  };
  EXPECT_EQ(code(good), ErrorCode::kOk);
  EXPECT_EQ(code("GIF89a"), ErrorCode::kParse);
  EXPECT_EQ(code(good.substr(0, good.size() - 5)), ErrorCode::kParse);  // truncated IEND
  for (std::size_t at : {std::size_t{20}, good.size() / 2, good.size() - 20}) {
    std::string flipped = good;
    flipped[at] = static_cast<char>(flipped[at] ^ 0x10);
    EXPECT_EQ(code(flipped), ErrorCode::kParse) << "byte " << at;  // some CRC no longer matches
  }
}

TEST(Png, EveryFlippedByteAndEveryTruncationIsRefused) {
  // Signature, lengths, types, data and CRCs are all covered: any single
  // damaged byte or cut must be a parse error, never a crash or a silent read.
  const std::string good = encode_png(gradient_image(9, 5));
  for (std::size_t at = 0; at < good.size(); ++at) {
    std::string bad = good;
    bad[at] = static_cast<char>(bad[at] ^ 0x01);
    try {
      (void)decode_png(bad);
      ADD_FAILURE() << "flipped byte " << at << " was accepted";
    } catch (const Error& e) {
      EXPECT_EQ(e.status().code(), ErrorCode::kParse) << at;
    }
  }
  for (std::size_t n = 0; n < good.size(); ++n) {
    try {
      (void)decode_png(good.substr(0, n));
      ADD_FAILURE() << "truncation to " << n << " bytes was accepted";
    } catch (const Error& e) {
      EXPECT_EQ(e.status().code(), ErrorCode::kParse) << n;
    }
  }
}

}  // namespace
}  // namespace atelier
