// Helpers shared by the io tests: fresh temporary directories, small models
// built through the public builders, and parse-error expectations.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <atelier/engine/status.h>
#include <atelier/storage/builder.h>
#include <atelier/storage/model.h>
#include <atelier/storage/validate.h>

namespace atelier::test {

/// A fresh directory under $ATELIER_TMP (or the system temp dir), removed
/// with everything in it at the end of the test.
class TempDir {
 public:
  TempDir() {
    const char* env = std::getenv("ATELIER_TMP");
    const std::filesystem::path root = env && *env ? std::filesystem::path(env) : std::filesystem::temp_directory_path();
    std::filesystem::create_directories(root);
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::random_device rd;
    for (int attempt = 0;; ++attempt) {
      path_ = root / ("io-" + std::string(info ? info->name() : "test") + "-" + std::to_string(::getpid()) + "-" +
                      std::to_string(rd()));
      if (std::filesystem::create_directory(path_)) break;
      if (attempt > 100) throw std::runtime_error("cannot make a temporary directory");
    }
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  [[nodiscard]] const std::filesystem::path& path() const noexcept { return path_; }
  [[nodiscard]] std::filesystem::path operator/(const std::string& name) const { return path_ / name; }
  /// Names of the entries in the directory, sorted.
  [[nodiscard]] std::vector<std::string> entries() const {
    std::vector<std::string> out;
    for (const auto& e : std::filesystem::directory_iterator(path_)) out.push_back(e.path().filename().string());
    std::sort(out.begin(), out.end());
    return out;
  }

 private:
  std::filesystem::path path_;
};

inline std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

inline void spit(const std::filesystem::path& p, const std::string& bytes) {
  std::ofstream out(p, std::ios::binary);
  out << bytes;
}

/// Polygon soup with owning storage (PolygonSoupView only views).
struct Soup {
  std::vector<Vec3d> positions;
  std::vector<std::uint32_t> offsets{0};
  std::vector<std::uint32_t> nodes;
  void face(std::initializer_list<std::uint32_t> f) {
    nodes.insert(nodes.end(), f.begin(), f.end());
    offsets.push_back(static_cast<std::uint32_t>(nodes.size()));
  }
  [[nodiscard]] PolygonSoupView arrays() const { return {positions, offsets, nodes}; }
};

/// A grid of nx*ny quads with jittered positions of full double precision
/// (so text round trips are tested on digits that need all 17).
inline Soup jittered_grid(int nx, int ny, std::uint32_t seed) {
  Soup s;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> jit(-0.3, 0.3);
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) s.positions.emplace_back(i + jit(rng), j + jit(rng), jit(rng) * 1e-7 + jit(rng) * 1e5);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const auto v = static_cast<std::uint32_t>(j * (nx + 1) + i);
      s.face({v, v + 1, v + static_cast<std::uint32_t>(nx) + 2, v + static_cast<std::uint32_t>(nx) + 1});
    }
  return s;
}

/// Closed cube of 6 quads (outward orientation).
inline Soup cube() {
  Soup s;
  for (int k = 0; k < 8; ++k) s.positions.emplace_back(k & 1, (k >> 1) & 1, (k >> 2) & 1);
  s.face({0, 2, 3, 1});
  s.face({4, 5, 7, 6});
  s.face({0, 1, 5, 4});
  s.face({2, 6, 7, 3});
  s.face({0, 4, 6, 2});
  s.face({1, 3, 7, 5});
  return s;
}

inline Model model_of(const Soup& s, const std::string& name) {
  Model m;
  auto r = add_polygon_surface(m, name, s.arrays());
  if (!r) throw Error(r.status());
  return m;
}

/// Runs `fn`, requires an atelier::Error with `code` whose message holds
/// every fragment. Returns the message.
inline std::string expect_error(const std::function<void()>& fn, ErrorCode code,
                                const std::vector<std::string>& fragments) {
  try {
    fn();
  } catch (const Error& e) {
    EXPECT_EQ(e.status().code(), code) << e.what();
    for (const auto& f : fragments) EXPECT_NE(std::string(e.what()).find(f), std::string::npos)
        << "message '" << e.what() << "' lacks '" << f << "'";
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected atelier::Error, got std::exception: " << e.what();
    return {};
  }
  ADD_FAILURE() << "expected an atelier::Error, nothing was thrown";
  return {};
}

/// Face corner positions of every live face, in face order.
inline std::vector<std::vector<Vec3d>> face_positions(const Model& m) {
  std::vector<std::vector<Vec3d>> out;
  std::vector<NodeIdx> c;
  for (std::uint32_t f = 0; f < m.faces.slots.capacity(); ++f) {
    if (!m.alive(FaceIdx{f})) continue;
    m.face_nodes(FaceIdx{f}, c);
    auto& v = out.emplace_back();
    for (NodeIdx n : c) v.push_back(m.position(n));
  }
  return out;
}

}  // namespace atelier::test
