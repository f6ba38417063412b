// Install + package: `cmake --install` the build tree into a fresh prefix,
// configure examples/ (a standalone project doing find_package(atelier))
// against it, build it and run the example, which regenerates a garment on
// bodies held in memory with progress and cancellation.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "support/run_command.h"

namespace fs = std::filesystem;

namespace {

using Outcome = atelier::testing::CommandResult;
using atelier::testing::run_command;

std::string q(const fs::path& p) {
  return "'" + p.string() + "'";
}

TEST(Install, DownstreamProjectBuildsAndRunsTheEmbeddingExample) {
  if (const char* skip = std::getenv("ATELIER_SKIP_LONG_TESTS"); skip && *skip)
    GTEST_SKIP() << "ATELIER_SKIP_LONG_TESTS is set (this test builds a downstream project)";
  const fs::path build = fs::path(ATELIER_CLI).parent_path();  // the build tree holds the CLI
  const fs::path source = fs::path(ATELIER_TEST_DATA).parent_path().parent_path();
  ASSERT_TRUE(fs::exists(build / "CMakeCache.txt")) << build;
  ASSERT_TRUE(fs::exists(source / "examples" / "CMakeLists.txt")) << source;
  const char* env = std::getenv("ATELIER_TMP");
  const fs::path work =
      (env && *env ? fs::path(env) : fs::temp_directory_path()) / ("install-test-" + std::to_string(::getpid()));
  fs::remove_all(work);
  fs::create_directories(work);
  const fs::path prefix = work / "prefix";

  const Outcome install = run_command("cmake --install " + q(build) + " --prefix " + q(prefix));
  ASSERT_EQ(install.code, 0) << install.out;
  EXPECT_TRUE(fs::exists(prefix / "bin" / "atelier"));
  EXPECT_TRUE(fs::exists(prefix / "include" / "atelier" / "systems" / "garment" / "detail_template.h"));
  EXPECT_TRUE(fs::exists(prefix / "include" / "atelier" / "engine" / "exec_context.h"));
  bool config = false;
  for (const auto& e : fs::recursive_directory_iterator(prefix))
    config = config || e.path().filename() == "atelierConfig.cmake";
  EXPECT_TRUE(config);

  const bool ninja = run_command("command -v ninja").code == 0;
  const Outcome configure =
      run_command("cmake -S " + q(source / "examples") + " -B " + q(work / "build") + (ninja ? " -G Ninja" : "") +
                  " -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=" + q(prefix));
  ASSERT_EQ(configure.code, 0) << configure.out;
  const Outcome compile = run_command("cmake --build " + q(work / "build") + " -j 2");
  ASSERT_EQ(compile.code, 0) << compile.out;
  // The example must not pick up the source tree's headers: it compiled
  // against the installed ones only.
  const Outcome flags =
      run_command("grep -r -l -E -- " + q("(-I|-isystem )" + source.string() + "( |$)") + " " + q(work / "build"));
  EXPECT_NE(flags.code, 0) << flags.out;

  const Outcome example = run_command(q(work / "build" / "embed"));
  EXPECT_EQ(example.code, 0) << example.out;
  EXPECT_NE(example.out.find("atelier embed: 6 bodies"), std::string::npos) << example.out;
  EXPECT_NE(example.out.find("cancelled after 2 of 6 bodies; encode cancelled"), std::string::npos) << example.out;
  EXPECT_NE(example.out.find("bodies 6/6"), std::string::npos) << example.out;  // progress callback
  fs::remove_all(work);
}

}  // namespace
