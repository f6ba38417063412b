// The process group of one `atelier` run (issue #6, beyond one machine).
//
// Every MPI call of the project lives in mpi_split.cpp behind this small
// interface. When the CLI is built without MPI (ATELIER_WITH_MPI off), or the
// process was not started by an MPI launcher (mpirun, mpiexec, srun
// --mpi=pmix), the group is this one process: rank 0 of 1, and MPI is never
// initialised, so a plain `atelier regen` behaves exactly as before.
//
// How `atelier regen` uses it: chunk c of the body set belongs to rank
// c mod size (regen_share), every rank writes its bodies' records into the
// shared output folder, then rank 0 merges them after all ranks are done.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace atelier::cli::mpi {

/// True when this executable was linked with MPI.
[[nodiscard]] bool built_with_mpi() noexcept;

/// The rank and size an MPI launcher announced in the environment before
/// MPI_Init (Open MPI's OMPI_COMM_WORLD_*, PMIx's PMIX_RANK, MPICH/Hydra's
/// PMI_*); {0, 1} when there is none. Size 0 means "launched, size unknown".
struct LaunchInfo {
  bool launched = false;
  int rank = 0;
  int size = 1;
};
[[nodiscard]] LaunchInfo launch_info_from_env() noexcept;

/// One run's process group. Constructing it initialises MPI only when the
/// launcher's environment asks for it and MPI is linked; the destructor
/// finalises what it initialised. Collectives must be called by every rank in
/// the same order (they block until all ranks arrive).
class ProcessGroup {
 public:
  ProcessGroup();
  ~ProcessGroup();
  ProcessGroup(const ProcessGroup&) = delete;
  ProcessGroup& operator=(const ProcessGroup&) = delete;

  [[nodiscard]] int rank() const noexcept { return rank_; }
  [[nodiscard]] int size() const noexcept { return size_; }
  [[nodiscard]] bool distributed() const noexcept { return size_ > 1; }
  /// Launched as one of several ranks by a launcher, but this build has no
  /// MPI: the caller must refuse to run (every copy would do all the work).
  [[nodiscard]] bool launched_without_mpi() const noexcept { return launched_without_mpi_; }

  /// Blocks until every rank has called it.
  void barrier() const;
  /// The largest `value` over all ranks, on every rank (exit codes: the worst
  /// one wins, as they are ordered ok < partial < usage < input < internal).
  [[nodiscard]] int max_all(int value) const;
  /// Every rank's `mine` (all of the same length), concatenated in rank
  /// order, on every rank.
  [[nodiscard]] std::vector<double> all_gather(std::span<const double> mine) const;

 private:
  int rank_ = 0;
  int size_ = 1;
  bool initialised_ = false;  // by us: finalise on destruction
  bool launched_without_mpi_ = false;
};

/// Whether chunk `chunk` of a body set belongs to `rank` of `size`:
/// round-robin over chunks, so every rank streams one chunk at a time, the
/// ranks' shares differ by at most one chunk, and the split depends only on
/// (--chunk, size), never on timing.
[[nodiscard]] constexpr bool regen_share(std::size_t chunk, int rank, int size) noexcept {
  return size <= 1 || chunk % static_cast<std::size_t>(size) == static_cast<std::size_t>(rank);
}

}  // namespace atelier::cli::mpi
