#include <gtest/gtest.h>

#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fstream>

#include <atelier/io/atomic_file.h>
#include <atelier/io/native.h>
#include <atelier/io/obj.h>
#include <atelier/io/off.h>
#include <atelier/io/ply.h>
#include "io_test_support.h"
#include "support/run_command.h"

using namespace atelier;
using namespace atelier::test;

TEST(AtomicFile, CommitRenamesIntoPlace) {
  TempDir dir;
  {
    AtomicFile f(dir / "out.txt");
    EXPECT_EQ(f.temp_path().parent_path(), dir.path());
    EXPECT_NE(f.temp_path().filename().string().find("out.txt.tmp."), std::string::npos);
    f.write("hello ");
    std::string big(200000, 'x');  // larger than the buffer
    f.write(big);
    EXPECT_FALSE(std::filesystem::exists(dir / "out.txt"));  // nothing visible before commit
    f.commit();
    EXPECT_TRUE(f.committed());
  }
  EXPECT_EQ(slurp(dir / "out.txt"), "hello " + std::string(200000, 'x'));
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"out.txt"});
}

TEST(AtomicFile, UncommittedLeavesNothingAndKeepsOldFile) {
  TempDir dir;
  spit(dir / "keep.txt", "old contents");
  {
    AtomicFile f(dir / "keep.txt");
    f.write("new contents that are never committed");
  }
  EXPECT_EQ(slurp(dir / "keep.txt"), "old contents");
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"keep.txt"});
  {
    AtomicFile f(dir / "fresh.txt");
    f.write("x");
  }
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"keep.txt"});
}

TEST(AtomicFile, ProducerThatThrowsMidwayLeavesOldFileIntact) {
  TempDir dir;
  spit(dir / "a.obj", "old");
  EXPECT_THROW(write_atomically(dir / "a.obj",
                                [](AtomicFile& f) {
                                  f.write(std::string(100000, 'y'));  // some bytes reach the disk
                                  throw std::runtime_error("boom");
                                }),
               std::runtime_error);
  EXPECT_EQ(slurp(dir / "a.obj"), "old");
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"a.obj"});
}

TEST(AtomicFile, TwoWritersGetDistinctTemporaries) {
  TempDir dir;
  AtomicFile a(dir / "x"), b(dir / "x");
  EXPECT_NE(a.temp_path(), b.temp_path());
  a.write("a");
  b.write("b");
  a.commit();
  b.commit();
  EXPECT_EQ(slurp(dir / "x"), "b");  // last rename wins, whole
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"x"});
}

TEST(AtomicFile, MissingDirectoryIsAnIoErrorAndCreatesNothing) {
  TempDir dir;
  const auto target = dir / "no" / "such" / "dir" / "m.obj";
  const Model m = model_of(cube(), "cube");
  expect_error([&] { write_obj(m, target); }, ErrorCode::kIo, {"m.obj"});
  expect_error([&] { write_ply(m, dir / "no" / "m.ply"); }, ErrorCode::kIo, {"m.ply"});
  expect_error([&] { write_off(m, dir / "no" / "m.off"); }, ErrorCode::kIo, {"m.off"});
  expect_error([&] { write_model(m, dir / "no" / "m.atm"); }, ErrorCode::kIo, {"m.atm"});
  EXPECT_TRUE(dir.entries().empty());
}

TEST(AtomicFile, ReadOnlyDirectoryIsAnIoError) {
  if (::geteuid() == 0) GTEST_SKIP() << "root ignores directory permissions";
  TempDir dir;
  std::filesystem::create_directory(dir / "ro");
  std::filesystem::permissions(dir / "ro", std::filesystem::perms::owner_read | std::filesystem::perms::owner_exec);
  expect_error([&] { write_obj(model_of(cube(), "c"), dir / "ro" / "c.obj"); }, ErrorCode::kIo, {"c.obj"});
  std::filesystem::permissions(dir / "ro", std::filesystem::perms::owner_all);
  EXPECT_TRUE(std::filesystem::is_empty(dir / "ro"));
}

TEST(AtomicFile, WriterFailingMidwayLeavesOldFileIntact) {
  // A model whose last node is not finite: each writer has already written
  // part of the file when it refuses that node.
  Model m = model_of(jittered_grid(30, 30, 1), "grid");
  m.nodes.position.back().y() = std::numeric_limits<double>::quiet_NaN();
  TempDir dir;
  for (const char* name : {"old.obj", "old.ply", "old.off"}) {
    SCOPED_TRACE(name);
    spit(dir / name, "previous good contents");
    const std::string ext = std::filesystem::path(name).extension().string();
    expect_error(
        [&] {
          if (ext == ".obj") write_obj(m, dir / name);
          if (ext == ".ply") write_ply(m, dir / name, false);
          if (ext == ".off") write_off(m, dir / name);
        },
        ErrorCode::kInvalidArgument, {name, "non-finite"});
    EXPECT_EQ(slurp(dir / name), "previous good contents");
  }
  EXPECT_EQ(dir.entries(), (std::vector<std::string>{"old.obj", "old.off", "old.ply"}));
}


// Issue 27: a run killed between AtomicFile's open and its rename leaves
// `<name>.tmp.<pid>.<n>`; a later run removes those whose writer is gone
// and keeps those of live writers (this process, another running job).
TEST(AtomicFile, StaleTemporariesOfDeadWritersAreRemovedLiveOnesKept) {
  TempDir dir;
  const pid_t gone = atelier::testing::dead_pid();
  ASSERT_GT(gone, 0);
  ASSERT_NE(::kill(gone, 0), 0) << "the exited child is still a process";
  const std::string dead = std::to_string(gone);
  auto touch = [&](const std::string& name) { std::ofstream(dir / name) << "partial"; };
  touch("b.json.tmp." + dead + ".0");
  touch("b.json.tmp." + dead + ".12");
  touch("report.json.tmp." + dead + ".3");
  touch("mine.json.tmp." + std::to_string(getpid()) + ".0");  // a live writer: this process
  touch("init.json.tmp.1.0");                                  // pid 1 is always alive
  // Not temporaries of AtomicFile: kept whatever their numbers say.
  touch("notes.tmp");
  touch("a.json");
  touch("x.tmp." + dead);
  touch("y.tmp." + dead + ".");
  touch("z.tmp.abc.0");
  touch("w.tmp." + dead + ".0x");
  std::filesystem::create_directories(dir / ("sub.tmp." + dead + ".0"));  // a folder, never removed
  EXPECT_EQ(remove_stale_temporaries(dir.path()), 3u);
  EXPECT_EQ(dir.entries(), (std::vector<std::string>{"a.json", "init.json.tmp.1.0",
                                                      "mine.json.tmp." + std::to_string(getpid()) + ".0",
                                                      "notes.tmp", "sub.tmp." + dead + ".0", "w.tmp." + dead + ".0x",
                                                      "x.tmp." + dead, "y.tmp." + dead + ".", "z.tmp.abc.0"}));
  // A missing folder is nothing to clean.
  EXPECT_EQ(remove_stale_temporaries(dir / "absent"), 0u);
  // A temporary this process really has open is kept until it commits.
  {
    AtomicFile f(dir / "live.json");
    EXPECT_EQ(remove_stale_temporaries(dir.path()), 0u);
    EXPECT_TRUE(std::filesystem::exists(f.temp_path()));
  }
}
