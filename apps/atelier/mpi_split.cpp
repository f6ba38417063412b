#include "mpi_split.h"

#include <cstdlib>
#include <string>
#include <utility>

#include <atelier/engine/status.h>

#ifdef ATELIER_WITH_MPI
#include <mpi.h>
#endif

namespace atelier::cli::mpi {

namespace {

/// A non-negative integer environment variable, or -1.
int env_int(const char* name) noexcept {
  const char* v = std::getenv(name);
  if (!v || !*v) return -1;
  char* end = nullptr;
  const long x = std::strtol(v, &end, 10);
  return (*end == '\0' && x >= 0 && x < (1L << 30)) ? static_cast<int>(x) : -1;
}

#ifdef ATELIER_WITH_MPI
void check(int rc, const char* what) {
  if (rc == MPI_SUCCESS) return;
  char msg[MPI_MAX_ERROR_STRING];
  int len = 0;
  MPI_Error_string(rc, msg, &len);
  throw Error(Status(ErrorCode::kInternal, std::string(what) + ": " + std::string(msg, static_cast<std::size_t>(len))));
}
#endif

}  // namespace

bool built_with_mpi() noexcept {
#ifdef ATELIER_WITH_MPI
  return true;
#else
  return false;
#endif
}

LaunchInfo launch_info_from_env() noexcept {
  LaunchInfo li;
  // Open MPI's mpirun; then MPICH/Hydra and Slurm's PMI-2; then PMIx (srun
  // --mpi=pmix), which announces a rank but no size.
  for (auto [r, s] : {std::pair{"OMPI_COMM_WORLD_RANK", "OMPI_COMM_WORLD_SIZE"}, std::pair{"PMI_RANK", "PMI_SIZE"},
                      std::pair{"PMIX_RANK", static_cast<const char*>(nullptr)}}) {
    const int rank = env_int(r);
    if (rank < 0) continue;
    li.launched = true;
    li.rank = rank;
    li.size = s ? env_int(s) : 0;
    if (li.size < 0) li.size = 0;
    return li;
  }
  return li;
}

ProcessGroup::ProcessGroup() {
  const LaunchInfo li = launch_info_from_env();
  if (!li.launched) return;
#ifdef ATELIER_WITH_MPI
  int already = 0;
  MPI_Initialized(&already);
  if (!already) {
    // Threads: only the main thread calls MPI (TBB workers never do).
    int provided = 0;
    check(MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided), "MPI_Init_thread");
    initialised_ = true;
  }
  check(MPI_Comm_rank(MPI_COMM_WORLD, &rank_), "MPI_Comm_rank");
  check(MPI_Comm_size(MPI_COMM_WORLD, &size_), "MPI_Comm_size");
#else
  // A launcher started several copies of a build without MPI: each copy would
  // regenerate every body. Only the caller can say so and stop.
  launched_without_mpi_ = li.rank != 0 || li.size > 1;
#endif
}

ProcessGroup::~ProcessGroup() {
#ifdef ATELIER_WITH_MPI
  if (initialised_) {
    int finalized = 0;
    MPI_Finalized(&finalized);
    if (!finalized) MPI_Finalize();
  }
#endif
}

void ProcessGroup::barrier() const {
  if (!distributed()) return;
#ifdef ATELIER_WITH_MPI
  check(MPI_Barrier(MPI_COMM_WORLD), "MPI_Barrier");
#endif
}

int ProcessGroup::max_all(int value) const {
  if (!distributed()) return value;
#ifdef ATELIER_WITH_MPI
  int out = value;
  check(MPI_Allreduce(&value, &out, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD), "MPI_Allreduce");
  return out;
#else
  return value;
#endif
}

std::vector<double> ProcessGroup::all_gather(std::span<const double> mine) const {
  if (!distributed()) return {mine.begin(), mine.end()};
  std::vector<double> out(mine.size() * static_cast<std::size_t>(size_));
#ifdef ATELIER_WITH_MPI
  check(MPI_Allgather(mine.data(), static_cast<int>(mine.size()), MPI_DOUBLE, out.data(),
                      static_cast<int>(mine.size()), MPI_DOUBLE, MPI_COMM_WORLD),
        "MPI_Allgather");
#endif
  return out;
}

}  // namespace atelier::cli::mpi
