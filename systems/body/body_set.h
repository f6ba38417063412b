// BodySet: many bodies sharing one topology and one feature definition (a
// ReferenceBody), with their positions in structure-of-arrays float columns.
// Sources generate or load bodies in chunks, so 10,000 bodies never need to
// be in memory at once.
//
// Layout: body b's coordinates are data_[b*3N .. b*3N+N) = x, then y, then z
// (N = node capacity of the reference model; dead node slots hold 0).
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <atelier/engine/exec_context.h>
#include <atelier/engine/math.h>
#include <atelier/engine/status.h>
#include <atelier/systems/body/body_file.h>
#include <atelier/systems/body/reference_body.h>

namespace atelier {

class BodySet {
 public:
  BodySet() = default;
  explicit BodySet(std::shared_ptr<const ReferenceBody> reference);

  [[nodiscard]] const std::shared_ptr<const ReferenceBody>& reference() const noexcept { return reference_; }
  [[nodiscard]] std::size_t size() const noexcept { return names_.size(); }
  [[nodiscard]] bool empty() const noexcept { return names_.empty(); }
  /// Nodes per body (the reference model's node capacity).
  [[nodiscard]] std::size_t node_count() const noexcept { return n_; }
  [[nodiscard]] std::size_t bytes_per_body() const noexcept { return 3 * n_ * sizeof(float); }

  /// Appends a body; positions indexed by node index. Errors on a size
  /// mismatch or a non-finite coordinate (naming the body and node).
  [[nodiscard]] Status add(std::string name, std::span<const Vec3d> positions);
  [[nodiscard]] Status add(std::string name, std::span<const Vec3f> positions);
  /// Drops the bodies, keeps the reference and the allocation (chunk reuse).
  void clear() noexcept;
  void reserve(std::size_t bodies) { data_.reserve(bodies * 3 * n_); }

  [[nodiscard]] const std::string& name(std::size_t b) const { return names_[b]; }
  [[nodiscard]] std::span<const float> x(std::size_t b) const noexcept { return {data_.data() + b * 3 * n_, n_}; }
  [[nodiscard]] std::span<const float> y(std::size_t b) const noexcept { return {data_.data() + b * 3 * n_ + n_, n_}; }
  [[nodiscard]] std::span<const float> z(std::size_t b) const noexcept {
    return {data_.data() + b * 3 * n_ + 2 * n_, n_};
  }
  /// Body b's positions as doubles (out.size() == node_count()).
  void positions(std::size_t b, std::span<Vec3d> out) const noexcept;
  [[nodiscard]] std::vector<Vec3d> positions(std::size_t b) const;

 private:
  std::shared_ptr<const ReferenceBody> reference_;
  std::size_t n_ = 0;
  std::vector<float> data_;
  std::vector<std::string> names_;
};

/// A body that could not be produced, with the reason.
struct BodyFailure {
  std::size_t index = 0;
  std::string name;
  Status status;
};

/// A stream of bodies with one topology: generated (mannequins, MakeHuman
/// mixes) or loaded (a directory of OBJ files).
class BodySource {
 public:
  virtual ~BodySource() = default;
  [[nodiscard]] virtual std::size_t size() const = 0;
  [[nodiscard]] virtual std::shared_ptr<const ReferenceBody> reference() const = 0;
  [[nodiscard]] virtual std::string body_name(std::size_t i) const = 0;
  /// The file body `i` is read from, empty for a generated body (fully
  /// defined by the source's parameters). A resumed job compares the file's
  /// contents with the ones its record was made from (issue 27).
  [[nodiscard]] virtual std::filesystem::path body_file(std::size_t /*i*/) const { return {}; }
  /// The units and axes of the source's files (bodies are generated in the
  /// engine's, metres and Y up): what a body's outputs are written back in.
  [[nodiscard]] virtual BodyFrame frame() const { return {}; }
  /// What body `i` was made from (issue 26: measurements say what they
  /// are): the sampled or given parameters as (column name with its unit,
  /// value as text), the same names for every body of the source; empty for
  /// bodies read from files. Names never collide with measured columns.
  [[nodiscard]] virtual std::vector<std::pair<std::string, std::string>> parameters(std::size_t /*i*/) const {
    return {};
  }
  /// True when the skin is a whole person, soles to crown, so that its
  /// measured vertical extent is the stature; false for a headless form
  /// (the mannequin), whose extent is only the form's height.
  [[nodiscard]] virtual bool whole_person() const { return true; }
  /// Clears `out` and fills it with bodies [first, first + count). A body
  /// that fails is appended to `failures` and skipped; the rest complete.
  virtual void generate(std::size_t first, std::size_t count, BodySet& out, std::vector<BodyFailure>& failures,
                        const ExecContext& ctx) const = 0;
};

/// Bodies from OBJ files in a directory (sorted by file name) that share the
/// reference body's topology: same node count and the same faces. A file with
/// another topology, or a malformed one, is reported by name as a failure.
/// `frame` maps file units and axes to the engine's (metres, Y up; see
/// body_file.h); a plain `scale` converts file units to metres.
class ObjDirectorySource final : public BodySource {
 public:
  ObjDirectorySource(std::filesystem::path dir, std::shared_ptr<const ReferenceBody> reference, double scale = 1.0);
  ObjDirectorySource(std::filesystem::path dir, std::shared_ptr<const ReferenceBody> reference, BodyFrame frame);
  [[nodiscard]] std::size_t size() const override { return files_.size(); }
  [[nodiscard]] std::shared_ptr<const ReferenceBody> reference() const override { return reference_; }
  [[nodiscard]] std::string body_name(std::size_t i) const override { return files_[i].stem().string(); }
  [[nodiscard]] std::filesystem::path body_file(std::size_t i) const override { return files_[i]; }
  [[nodiscard]] BodyFrame frame() const override { return frame_; }
  void generate(std::size_t first, std::size_t count, BodySet& out, std::vector<BodyFailure>& failures,
                const ExecContext& ctx) const override;
  [[nodiscard]] const std::vector<std::filesystem::path>& files() const noexcept { return files_; }

 private:
  std::filesystem::path dir_;
  std::shared_ptr<const ReferenceBody> reference_;
  BodyFrame frame_;
  std::vector<std::filesystem::path> files_;
};

/// Reads one OBJ body and checks it has the reference's topology; returns
/// positions indexed by node index, or an error naming the file and the first
/// mismatch (node count, face count, or the first differing face).
[[nodiscard]] Expected<std::vector<Vec3d>> read_body_obj(const std::filesystem::path& file, const ReferenceBody& ref,
                                                         double scale = 1.0);
/// The same with the file's units and axes mapped to the engine's.
[[nodiscard]] Expected<std::vector<Vec3d>> read_body_obj(const std::filesystem::path& file, const ReferenceBody& ref,
                                                         const BodyFrame& frame);

}  // namespace atelier
