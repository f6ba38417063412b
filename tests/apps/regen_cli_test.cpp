// `atelier encode` and `atelier regen` (the batch job on files): outputs,
// determinism across thread counts, resume after a kill, failure isolation
// and bad input.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
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

using atelier::testing::encoded_templates;
using atelier::testing::read_bytes;
using atelier::testing::template_args;

using CliRun = atelier::testing::CommandResult;
using atelier::testing::run_cli;
using atelier::testing::scratch_dir;

}  // namespace

TEST(RegenCli, EncodeWritesReadableTemplates) {
  for (const char* n : {"top", "skirt", "trousers"}) {
    const fs::path f = encoded_templates() / (std::string(n) + ".template.json");
    ASSERT_TRUE(fs::exists(f)) << f;
    const auto j = nlohmann::json::parse(read_bytes(f));
    EXPECT_EQ(j.value("name", ""), n);
    EXPECT_TRUE(fs::exists(encoded_templates() / (std::string(n) + ".obj")));
  }
}

TEST(RegenCli, ByteIdenticalForOneAndTwoThreads) {
  const fs::path a = scratch_dir("regen_t1"), b = scratch_dir("regen_t2");
  const CliRun r1 =
      run_cli("--threads 1 --seed 5 regen" + template_args() + " --count 6 --meshes 2 --out " + a.string());
  const CliRun r2 =
      run_cli("--threads 2 --seed 5 regen" + template_args() + " --count 6 --meshes 2 --out " + b.string());
  ASSERT_EQ(r1.code, 0) << r1.out;
  ASSERT_EQ(r2.code, 0) << r2.out;
  EXPECT_EQ(read_bytes(a / "report.json"), read_bytes(b / "report.json"));
  std::size_t meshes = 0;
  for (const auto& e : fs::recursive_directory_iterator(a / "bodies")) {
    if (!e.is_regular_file()) continue;
    const fs::path rel = fs::relative(e.path(), a);
    EXPECT_EQ(read_bytes(e.path()), read_bytes(b / rel)) << rel;
    meshes += e.path().extension() == ".obj";
  }
  EXPECT_EQ(meshes, 2u * (3u + 1u));  // per body: three templates and the body itself (issue 26)
  const auto rep = nlohmann::json::parse(read_bytes(a / "report.json"));
  // The streamed merge writes what a dump of the whole report would be.
  EXPECT_EQ(read_bytes(a / "report.json"), rep.dump(1));
  EXPECT_EQ(rep["summary"]["completed"], 6);
  EXPECT_EQ(rep["summary"]["inside_nodes_total"], 0);
  EXPECT_EQ(rep["summary"]["max_crack_m"], 0.0);
}

TEST(RegenCli, ResumeAfterAKillLosesNothingFinished) {
  const fs::path out = scratch_dir("regen_kill");
  const std::string cmd =
      std::string(ATELIER_CLI) + " --threads 2 regen" + template_args() + " --count 60 --chunk 4 --out " + out.string();
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
    if (e.path().extension() == ".json") {
      EXPECT_FALSE(nlohmann::json::parse(read_bytes(e.path()), nullptr, false).is_discarded()) << e.path();
    }
  // A temporary of the killed writer (a kill between open and rename leaves
  // one): the rerun removes it.
  const fs::path stale = out / "bodies" / ("mannequin-00059.json.tmp." + std::to_string(pid) + ".0");
  std::ofstream(stale) << "{\"body\": \"mannequin-00059\", \"ok\": tr";
  // The same folder with a changed job (another seed, other levels) is
  // refused, naming the difference, and left as it was.
  for (const std::string& changed :
       {std::string("--seed 9 --threads 2 regen") + template_args() + " --count 60 --chunk 4 --out " + out.string(),
        std::string("--threads 2 regen") + template_args() + " --count 60 --chunk 4 --levels 1 --out " +
            out.string()}) {
    const CliRun refused = run_cli(changed);
    EXPECT_EQ(refused.code, 2) << refused.out;
    EXPECT_NE(refused.out.find(changed.find("--seed") == 0 ? "seed: 1 in the folder, 9 now" : "levels"),
              std::string::npos)
        << refused.out;
    EXPECT_EQ(records(), before);
  }
  const CliRun again = run_cli("--threads 2 regen" + template_args() + " --count 60 --chunk 4 --out " + out.string());
  ASSERT_EQ(again.code, 0) << again.out;
  EXPECT_FALSE(fs::exists(stale));
  for (const auto& e : fs::recursive_directory_iterator(out))
    EXPECT_EQ(e.path().filename().string().find(".tmp."), std::string::npos) << "left behind: " << e.path();
  const auto timing = nlohmann::json::parse(read_bytes(out / "timing.json"));
  if (before < 60) {
    EXPECT_GE(timing["skipped_complete"].get<std::size_t>(), before);
  }
  const auto rep = nlohmann::json::parse(read_bytes(out / "report.json"));
  EXPECT_EQ(rep["summary"]["completed"], 60);
  EXPECT_EQ(rep["bodies"].size(), 60u);
}

TEST(RegenCli, BadInputIsReportedWithExitCodes) {
  const fs::path out = scratch_dir("regen_bad");
  // Missing template file: bad input (3), naming the file.
  CliRun r = run_cli("regen --template " + (out / "nope.template.json").string() + " --count 2 --out " + out.string());
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_NE(r.out.find("nope.template.json"), std::string::npos) << r.out;
  // A corrupted template: bad input, naming the file.
  {
    std::string text = read_bytes(encoded_templates() / "skirt.template.json");
    text.resize(text.size() / 2);
    std::ofstream(out / "half.template.json") << text;
  }
  r = run_cli("regen --template " + (out / "half.template.json").string() + " --count 2 --out " + out.string());
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_NE(r.out.find("half.template.json"), std::string::npos) << r.out;
  // A directory body set whose reference has another topology: refused with what to do.
  fs::create_directories(out / "objs");
  {
    std::ofstream f(out / "objs" / "ref.obj");
    f << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
  }
  fs::copy_file(out / "objs" / "ref.obj", out / "objs" / "b1.obj");
  r = run_cli("regen" + template_args() + " --source " + (out / "objs").string() + " --reference " +
              (out / "objs" / "ref.obj").string() + " --out " + (out / "run").string());
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_NE(r.out.find("atelier encode"), std::string::npos) << r.out;
}

TEST(RegenCli, CountsClearancesAndLevelsOutOfRangeAreUsageErrors) {
  // Issue 27: "--count -1" used to wrap to 2^64-1 and loop forever; a
  // clearance of 1e300 made one body take minutes. Each is refused before
  // any work (exit 2) with the option named.
  const fs::path out = scratch_dir("regen_ranges");
  const std::string tpl = " --template " + (encoded_templates() / "skirt.template.json").string();
  struct Case {
    std::string args, says;
  };
  for (const Case& c : std::vector<Case>{{"--count -1", "--count"},
                                         {"--count 18446744073709551616", "--count"},
                                         {"--count 0", "--count"},
                                         {"--count 2.5", "--count"},
                                         {"--count 2 --clearance -0.01", "--clearance"},
                                         {"--count 2 --clearance nan", "--clearance"},
                                         {"--count 2 --clearance inf", "--clearance"},
                                         {"--count 2 --clearance 1e300", "--clearance"},
                                         {"--count 2 --levels 99", "--levels"},
                                         {"--count 2 --levels -3", "--levels"}}) {
    const CliRun r = run_cli("regen" + tpl + " " + c.args + " --out " + (out / "run").string());
    EXPECT_EQ(r.code, 2) << c.args << "\n" << r.out;
    EXPECT_NE(r.out.find(c.says), std::string::npos) << c.args << "\n" << r.out;
  }
  EXPECT_FALSE(fs::exists(out / "run" / "bodies")) << "nothing is started for a usage error";
  const CliRun b = run_cli("bodies --count -5 --out " + (out / "bodies").string());
  EXPECT_EQ(b.code, 2) << b.out;
}

TEST(RegenCli, TwoTemplatesOfOneNameAndAMisspeltSourceAreRefused) {
  const fs::path out = scratch_dir("regen_names");
  fs::create_directories(out / "a");
  fs::copy_file(encoded_templates() / "skirt.template.json", out / "a" / "skirt.template.json",
                fs::copy_options::overwrite_existing);
  CliRun r = run_cli("regen --template " + (encoded_templates() / "skirt.template.json").string() + " --template " +
                     (out / "a" / "skirt.template.json").string() + " --count 2 --out " + (out / "run").string());
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_NE(r.out.find("both named 'skirt'"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(out / "run" / "bodies" / "mannequin-00000.json")) << r.out;
  // A typo in --source names the source instead of asking for --reference.
  r = run_cli("bodies --source mannequinn --count 2 --out " + (out / "b").string());
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_NE(r.out.find("'mannequinn'"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("--reference is required"), std::string::npos) << r.out;
}

TEST(RegenCli, GarmentMeshesAreEncodedAsDetailTemplatesAndRegeneratedOutsideTheBody) {
  // Any garment mesh on the reference body (here the coarse top the profile
  // encoder writes) becomes a detail template (seed 001 section 6) and is
  // regenerated, then put through the collision pass, on every body.
  const fs::path d = scratch_dir("regen_garment");
  CliRun r = run_cli("encode --garment " + (encoded_templates() / "top.obj").string() + " --out " + (d / "g").string());
  ASSERT_EQ(r.code, 0) << r.out;
  ASSERT_TRUE(fs::exists(d / "g" / "top.atd"));
  ASSERT_TRUE(fs::exists(d / "g" / "top.obj"));
  const std::string args =
      " --seed 4 regen --template " + (d / "g" / "top.atd").string() + " --count 5 --meshes 1 --chunk 2 --out ";
  const CliRun r1 = run_cli("--threads 1" + args + (d / "t1").string());
  const CliRun r2 = run_cli("--threads 2" + args + (d / "t2").string());
  ASSERT_EQ(r1.code, 0) << r1.out;
  ASSERT_EQ(r2.code, 0) << r2.out;
  EXPECT_EQ(read_bytes(d / "t1" / "report.json"), read_bytes(d / "t2" / "report.json"));
  const auto rep = nlohmann::json::parse(read_bytes(d / "t1" / "report.json"));
  EXPECT_EQ(rep["summary"]["completed"], 5) << rep.dump();
  EXPECT_EQ(rep["templates"], nlohmann::json::array({"top"}));
  for (const auto& b : rep["bodies"]) {
    const auto& q = b["templates"]["top"];
    EXPECT_EQ(q["inside_nodes"], 0) << b.dump();
    EXPECT_GE(q["min_clearance_m"].get<double>(), 0.0) << b.dump();
    EXPECT_GT(q["vertices"].get<int>(), 10) << b.dump();
  }
  // The first body's garment mesh, with the encoded garment's face count.
  std::size_t faces_in = 0, faces_out = 0;
  {
    std::istringstream a(read_bytes(d / "g" / "top.obj")),
        b(read_bytes(d / "t1" / "bodies" / "mannequin-00000" / "top.obj"));
    for (std::string l; std::getline(a, l);) faces_in += l.rfind("f ", 0) == 0;
    for (std::string l; std::getline(b, l);) faces_out += l.rfind("f ", 0) == 0;
  }
  EXPECT_GT(faces_in, 0u);
  EXPECT_EQ(faces_in, faces_out);
  // Bad input: the template without its garment mesh names what is missing.
  fs::create_directories(d / "lone");
  fs::copy_file(d / "g" / "top.atd", d / "lone" / "top.atd");
  r = run_cli("regen --template " + (d / "lone" / "top.atd").string() + " --count 2 --out " + (d / "bad").string());
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_NE(r.out.find("top.obj"), std::string::npos) << r.out;
  // A garment file that does not exist.
  r = run_cli("encode --garment " + (d / "none.obj").string() + " --out " + (d / "g2").string());
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_NE(r.out.find("none.obj"), std::string::npos) << r.out;
  // Scaled frames (issue 26): stored in the .atd (version 4, unit frames
  // stay version 3), which regen then decodes with them; the garment still
  // ends outside every body, elsewhere than with unit frames.
  r = run_cli("encode --scaled-frames --garment " + (encoded_templates() / "top.obj").string() + " --out " +
              (d / "gs").string());
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(read_bytes(d / "gs" / "top.atd").substr(8, 4), std::string("\x04\0\0\0", 4));
  EXPECT_EQ(read_bytes(d / "g" / "top.atd").substr(8, 4), std::string("\x03\0\0\0", 4));
  r = run_cli("--seed 4 --threads 1 regen --template " + (d / "gs" / "top.atd").string() +
              " --count 5 --meshes 1 --chunk 2 --out " + (d / "ts").string());
  ASSERT_EQ(r.code, 0) << r.out;
  const auto reps = nlohmann::json::parse(read_bytes(d / "ts" / "report.json"));
  EXPECT_EQ(reps["summary"]["completed"], 5) << reps.dump();
  for (const auto& b : reps["bodies"]) EXPECT_EQ(b["templates"]["top"]["inside_nodes"], 0) << b.dump();
  const fs::path first = fs::path("bodies") / "mannequin-00000" / "top.obj";
  ASSERT_TRUE(fs::exists(d / "ts" / first));
  EXPECT_NE(read_bytes(d / "ts" / first), read_bytes(d / "t1" / first));
}

TEST(RegenCli, ADirectoryOfMannequinBodiesKeepsTheMannequinFeatures) {
  // OBJ files carry no features; bodies with the mannequin's topology take
  // the mannequin's, so profile templates regenerate on them.
  const fs::path d = scratch_dir("regen_objdir");
  CliRun r = run_cli("--seed 2 bodies --count 3 --meshes 3 --out " + (d / "set").string());
  ASSERT_EQ(r.code, 0) << r.out;
  std::vector<fs::path> objs;
  for (const auto& e : fs::directory_iterator(d / "set"))
    if (e.path().extension() == ".obj") objs.push_back(e.path());
  ASSERT_EQ(objs.size(), 3u);
  std::sort(objs.begin(), objs.end());
  r = run_cli("--threads 2 regen" + template_args() + " --source " + (d / "set").string() + " --reference " +
              objs[0].string() + " --out " + (d / "run").string());
  ASSERT_EQ(r.code, 0) << r.out;
  const auto rep = nlohmann::json::parse(read_bytes(d / "run" / "report.json"));
  EXPECT_EQ(rep["summary"]["completed"], 3) << rep.dump();
  EXPECT_EQ(rep["summary"]["inside_nodes_total"], 0) << rep.dump();
}
