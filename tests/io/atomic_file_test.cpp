#include <gtest/gtest.h>

#include <sys/stat.h>

#include <atelier/io/atomic_file.h>
#include <atelier/io/native.h>
#include <atelier/io/obj.h>
#include <atelier/io/off.h>
#include <atelier/io/ply.h>
#include "io_test_support.h"

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
