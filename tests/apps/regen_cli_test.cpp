// `atelier encode` and `atelier regen` (the batch job on files): outputs,
// determinism across thread counts, resume after a kill, failure isolation
// and bad input.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <thread>

#include "support/run_command.h"

namespace fs = std::filesystem;

namespace {

using CliRun = atelier::testing::CommandResult;
using atelier::testing::scratch_dir;
CliRun run(const std::string& args) { return atelier::testing::run_cli(args); }
fs::path dir(const std::string& name) { return scratch_dir(name); }

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

const fs::path& templates() {
  static const fs::path d = [] {
    fs::path t = dir("regen_templates");
    const CliRun r = run("encode --template all --out " + t.string());
    EXPECT_EQ(r.code, 0) << r.out;
    return t;
  }();
  return d;
}

std::string template_args() {
  std::string a;
  for (const char* n : {"top", "skirt", "trousers"}) a += " --template " + (templates() / (std::string(n) + ".template.json")).string();
  return a;
}

}  // namespace

TEST(RegenCli, EncodeWritesReadableTemplates) {
  for (const char* n : {"top", "skirt", "trousers"}) {
    const fs::path f = templates() / (std::string(n) + ".template.json");
    ASSERT_TRUE(fs::exists(f)) << f;
    const auto j = nlohmann::json::parse(slurp(f));
    EXPECT_EQ(j.value("name", ""), n);
    EXPECT_TRUE(fs::exists(templates() / (std::string(n) + ".obj")));
  }
}

TEST(RegenCli, ByteIdenticalForOneAndTwoThreads) {
  const fs::path a = dir("regen_t1"), b = dir("regen_t2");
  const CliRun r1 = run("--threads 1 --seed 5 regen" + template_args() + " --count 6 --meshes 2 --out " + a.string());
  const CliRun r2 = run("--threads 2 --seed 5 regen" + template_args() + " --count 6 --meshes 2 --out " + b.string());
  ASSERT_EQ(r1.code, 0) << r1.out;
  ASSERT_EQ(r2.code, 0) << r2.out;
  EXPECT_EQ(slurp(a / "report.json"), slurp(b / "report.json"));
  std::size_t meshes = 0;
  for (const auto& e : fs::recursive_directory_iterator(a / "bodies")) {
    if (!e.is_regular_file()) continue;
    const fs::path rel = fs::relative(e.path(), a);
    EXPECT_EQ(slurp(e.path()), slurp(b / rel)) << rel;
    meshes += e.path().extension() == ".obj";
  }
  EXPECT_EQ(meshes, 2u * 3u);
  const auto rep = nlohmann::json::parse(slurp(a / "report.json"));
  EXPECT_EQ(rep["summary"]["completed"], 6);
  EXPECT_EQ(rep["summary"]["inside_nodes_total"], 0);
  EXPECT_EQ(rep["summary"]["max_crack_m"], 0.0);
}

TEST(RegenCli, ResumeAfterAKillLosesNothingFinished) {
  const fs::path out = dir("regen_kill");
  const std::string cmd = std::string(ATELIER_CLI) + " --threads 2 regen" + template_args() +
                          " --count 60 --chunk 4 --out " + out.string();
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    execl("/bin/sh", "sh", "-c", ("exec " + cmd + " > /dev/null 2>&1").c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  // Kill it once some bodies are complete.
  auto records = [&] {
    std::size_t n = 0;
    if (fs::exists(out / "bodies"))
      for (const auto& e : fs::directory_iterator(out / "bodies")) n += e.path().extension() == ".json";
    return n;
  };
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (records() < 8 && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  kill(pid, SIGKILL);
  int st = 0;
  waitpid(pid, &st, 0);
  const std::size_t before = records();
  ASSERT_GE(before, 8u);
  // Every record left behind is complete JSON (atomic writes), and no
  // temporary file is mistaken for one.
  for (const auto& e : fs::directory_iterator(out / "bodies"))
    if (e.path().extension() == ".json") EXPECT_FALSE(nlohmann::json::parse(slurp(e.path()), nullptr, false).is_discarded()) << e.path();
  const CliRun again = run("--threads 2 regen" + template_args() + " --count 60 --chunk 4 --out " + out.string());
  ASSERT_EQ(again.code, 0) << again.out;
  const auto timing = nlohmann::json::parse(slurp(out / "timing.json"));
  if (before < 60) EXPECT_GE(timing["skipped_complete"].get<std::size_t>(), before);
  const auto rep = nlohmann::json::parse(slurp(out / "report.json"));
  EXPECT_EQ(rep["summary"]["completed"], 60);
  EXPECT_EQ(rep["bodies"].size(), 60u);
}

TEST(RegenCli, BadInputIsReportedWithExitCodes) {
  const fs::path out = dir("regen_bad");
  // Missing template file: bad input (3), naming the file.
  CliRun r = run("regen --template " + (out / "nope.template.json").string() + " --count 2 --out " + out.string());
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_NE(r.out.find("nope.template.json"), std::string::npos) << r.out;
  // A corrupted template: bad input, naming the file.
  {
    std::string text = slurp(templates() / "skirt.template.json");
    text.resize(text.size() / 2);
    std::ofstream(out / "half.template.json") << text;
  }
  r = run("regen --template " + (out / "half.template.json").string() + " --count 2 --out " + out.string());
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_NE(r.out.find("half.template.json"), std::string::npos) << r.out;
  // A directory body set whose reference has another topology: refused with what to do.
  fs::create_directories(out / "objs");
  {
    std::ofstream f(out / "objs" / "ref.obj");
    f << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
  }
  fs::copy_file(out / "objs" / "ref.obj", out / "objs" / "b1.obj");
  r = run("regen" + template_args() + " --source " + (out / "objs").string() + " --reference " +
          (out / "objs" / "ref.obj").string() + " --out " + (out / "run").string());
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_NE(r.out.find("atelier encode"), std::string::npos) << r.out;
}
