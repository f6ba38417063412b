// `mpirun -np 2 atelier regen` (issue #6, beyond one machine): both ranks do
// a share of the bodies, and the merged outputs are the bytes a one-process
// run writes. Skipped when the CLI was built without MPI or mpirun is absent.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "support/run_command.h"

namespace fs = std::filesystem;

namespace {

using atelier::testing::encoded_templates;
using atelier::testing::read_bytes;
using atelier::testing::template_args;

using atelier::testing::CommandResult;
using atelier::testing::run_cli;
using atelier::testing::run_command;
using atelier::testing::scratch_dir;

/// Why the MPI run cannot be tested here, or "" when it can.
std::string mpi_unavailable() {
  if (run_command("command -v mpirun").code != 0) return "mpirun not found (install openmpi-bin)";
  const CommandResult help = run_cli("regen --help");
  if (help.out.find("mpirun") == std::string::npos) return "the atelier CLI was built without MPI";
  return "";
}

/// `mpirun -np <ranks>` of the CLI with `args`, set up for a container: root
/// allowed, shared-memory transport without single-copy (no ptrace there),
/// more ranks than cores allowed. Sanitizer builds: Open MPI's own
/// allocations outlive MPI_Finalize, so leak checking is off in the ranks.
CommandResult mpirun_cli(int ranks, const std::string& args) {
  std::string cmd =
      "OMPI_MCA_btl_vader_single_copy_mechanism=none OMPI_MCA_rmaps_base_oversubscribe=1 "
      "ASAN_OPTIONS=detect_leaks=0 mpirun -np " +
      std::to_string(ranks) + " --oversubscribe --mca btl self,vader -x ASAN_OPTIONS";
  if (geteuid() == 0) cmd += " --allow-run-as-root";
  return run_command(cmd + " " + ATELIER_CLI + " " + args);
}

const fs::path& top_template() {
  static const fs::path f = [] {
    const fs::path d = atelier::testing::process_scratch_dir("mpi_regen_templates");
    const CommandResult r = run_cli("encode --template top --out " + d.string());
    EXPECT_EQ(r.code, 0) << r.out;
    return d / "top.template.json";
  }();
  return f;
}

/// Every file under `a` has the same bytes under `b`, and the other way round.
void expect_same_tree(const fs::path& a, const fs::path& b) {
  std::set<fs::path> seen;
  for (const auto& e : fs::recursive_directory_iterator(a)) {
    if (!e.is_regular_file()) continue;
    const fs::path rel = fs::relative(e.path(), a);
    seen.insert(rel);
    ASSERT_TRUE(fs::exists(b / rel)) << rel;
    EXPECT_EQ(read_bytes(e.path()), read_bytes(b / rel)) << rel;
  }
  for (const auto& e : fs::recursive_directory_iterator(b))
    if (e.is_regular_file()) {
      EXPECT_TRUE(seen.count(fs::relative(e.path(), b))) << fs::relative(e.path(), b);
    }
}

}  // namespace

TEST(MpiRegen, TwoRanksSplitTheBodiesAndMergeTheSameReport) {
  if (const std::string why = mpi_unavailable(); !why.empty()) GTEST_SKIP() << why;
  const fs::path one = scratch_dir("mpi_regen_one"), two = scratch_dir("mpi_regen_two");
  // Chunks of one body: chunk c goes to rank c mod 2, so each rank owns 3.
  const std::string args = "--threads 1 --seed 7 regen --template " + top_template().string() +
                           " --count 6 --chunk 1 --levels 1 --meshes 2 --out ";
  const CommandResult single = run_cli(args + (one / "run").string());
  ASSERT_EQ(single.code, 0) << single.out;
  const CommandResult mpi = mpirun_cli(2, args + (two / "run").string());
  ASSERT_EQ(mpi.code, 0) << mpi.out;

  // Both ranks did their share, and said so.
  EXPECT_NE(mpi.out.find("rank 0 of 2: regenerated 3 bodies"), std::string::npos) << mpi.out;
  EXPECT_NE(mpi.out.find("rank 1 of 2: regenerated 3 bodies"), std::string::npos) << mpi.out;
  const auto timing = nlohmann::json::parse(read_bytes(two / "run" / "timing.json"));
  ASSERT_EQ(timing["ranks"].size(), 2u) << timing.dump();
  for (int r = 0; r < 2; ++r) {
    EXPECT_EQ(timing["ranks"][r]["rank"], r);
    EXPECT_EQ(timing["ranks"][r]["regenerated_now"], 3) << timing.dump();
  }
  EXPECT_EQ(timing["regenerated_now"], 6);
  // Only rank 0 printed the summary (one report line).
  const std::string line = "report: " + fs::absolute(two / "run" / "report.json").string();
  const std::size_t at = mpi.out.find(line);
  ASSERT_NE(at, std::string::npos) << mpi.out;
  EXPECT_EQ(mpi.out.find(line, at + 1), std::string::npos) << mpi.out;

  // The merged report and every body's record and meshes: the bytes of the
  // one-process run (timing.json differs by nature and is left out).
  EXPECT_EQ(read_bytes(one / "run" / "report.json"), read_bytes(two / "run" / "report.json"));
  expect_same_tree(one / "run" / "bodies", two / "run" / "bodies");
  const auto rep = nlohmann::json::parse(read_bytes(two / "run" / "report.json"));
  EXPECT_EQ(rep["summary"]["completed"], 6);
  EXPECT_EQ(rep["bodies"].size(), 6u);

  // Resume on another rank count: a rerun with 2 ranks finds every body
  // complete (each rank skips its own share) and merges the same report.
  const std::string before = read_bytes(two / "run" / "report.json");
  const CommandResult again = mpirun_cli(2, args + (two / "run").string());
  ASSERT_EQ(again.code, 0) << again.out;
  const auto timing2 = nlohmann::json::parse(read_bytes(two / "run" / "timing.json"));
  EXPECT_EQ(timing2["regenerated_now"], 0) << timing2.dump();
  EXPECT_EQ(timing2["skipped_complete"], 6) << timing2.dump();
  EXPECT_EQ(read_bytes(two / "run" / "report.json"), before);
}

TEST(MpiRegen, AFailureOnOneRankSetsTheExitCodeOfTheJob) {
  if (const std::string why = mpi_unavailable(); !why.empty()) GTEST_SKIP() << why;
  const fs::path d = scratch_dir("mpi_regen_fail");
  // A directory body set of mannequin OBJs (the first is also the
  // reference); the second body (chunk 1, rank 1's) is a truncated file.
  const CommandResult bodies = run_cli("--seed 3 bodies --count 4 --meshes 4 --out " + (d / "set").string());
  ASSERT_EQ(bodies.code, 0) << bodies.out;
  std::vector<fs::path> objs;
  for (const auto& e : fs::directory_iterator(d / "set"))
    if (e.path().extension() == ".obj") objs.push_back(e.path());
  ASSERT_EQ(objs.size(), 4u);
  std::sort(objs.begin(), objs.end());
  {
    std::string text = read_bytes(objs[1]);
    text.resize(text.size() / 3);
    std::ofstream(objs[1], std::ios::binary) << text;
  }
  const std::string args = "--threads 1 regen --template " + top_template().string() + " --source " +
                           (d / "set").string() + " --reference " + objs[0].string() + " --chunk 1 --levels 1 --out ";
  const CommandResult single = run_cli(args + (d / "one").string());
  const CommandResult mpi = mpirun_cli(2, args + (d / "two").string());
  // Exit code 1 (some bodies failed) from the job, as from one process.
  EXPECT_EQ(single.code, 1) << single.out;
  EXPECT_EQ(mpi.code, 1) << mpi.out;
  ASSERT_TRUE(fs::exists(d / "two" / "report.json")) << mpi.out;
  EXPECT_EQ(read_bytes(d / "one" / "report.json"), read_bytes(d / "two" / "report.json"));
  const auto rep = nlohmann::json::parse(read_bytes(d / "two" / "report.json"));
  EXPECT_EQ(rep["summary"]["failed"], 1) << rep.dump();
  EXPECT_EQ(rep["summary"]["completed"], 3) << rep.dump();
  const auto timing = nlohmann::json::parse(read_bytes(d / "two" / "timing.json"));
  EXPECT_EQ(timing["ranks"][1]["regenerated_now"], 1) << timing.dump();
}

TEST(MpiRegen, BadInputOnEveryRankExitsWithTheInputCodeAndNoReport) {
  if (const std::string why = mpi_unavailable(); !why.empty()) GTEST_SKIP() << why;
  const fs::path d = scratch_dir("mpi_regen_bad");
  // The ranks must not wait for each other forever: each reports the error
  // and the job exits 3 (bad input), writing no report.
  const CommandResult r = mpirun_cli(
      2, "regen --template " + (d / "missing.template.json").string() + " --count 2 --out " + (d / "run").string());
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_NE(r.out.find("missing.template.json"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(d / "run" / "report.json"));
}
