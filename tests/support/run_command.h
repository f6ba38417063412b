// Running commands from tests (the built CLI, cmake, chromium): exit code
// and combined output, plus a fresh scratch folder under $ATELIER_TMP.
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <map>
#include <sstream>
#include <string>

namespace atelier::testing {

struct CommandResult {
  int code = -1;    // exit status, -1 when the command did not exit normally
  std::string out;  // stdout and stderr
};

/// The pid of a process that has exited (and been reaped): no process has it
/// until the kernel reuses it, which takes a full turn of the pid space. A
/// temporary file named after it is one a killed writer left.
inline pid_t dead_pid() {
  const pid_t child = fork();
  if (child == 0) _exit(0);
  int st = 0;
  waitpid(child, &st, 0);
  return child;
}

/// Runs `command` through the shell, capturing stdout and stderr.
inline CommandResult run_command(const std::string& command) {
  CommandResult r;
  FILE* p = popen((command + " 2>&1").c_str(), "r");
  if (!p) return r;
  char buf[4096];
  std::size_t n;
  while ((n = fread(buf, 1, sizeof buf, p)) > 0) r.out.append(buf, n);
  const int st = pclose(p);
  r.code = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  return r;
}

/// Whether `text` contains `part` (CLI output, reports).
inline bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

/// Runs the built atelier CLI with `args`.
inline CommandResult run_cli(const std::string& args) {
  return run_command(std::string(ATELIER_CLI) + " " + args);
}

/// An empty folder `name` under $ATELIER_TMP (or the system temp folder).
inline std::filesystem::path scratch_dir(const std::string& name) {
  const char* env = std::getenv("ATELIER_TMP");
  std::filesystem::path d =
      (env ? std::filesystem::path(env) : std::filesystem::temp_directory_path() / "atelier-tests") / name;
  std::filesystem::remove_all(d);
  std::filesystem::create_directories(d);
  return d;
}

/// scratch_dir(name) private to this process: for set-up shared by the
/// tests of one binary (ctest runs each test in its own process, in
/// parallel, so a shared name would be wiped under a running test).
inline std::filesystem::path process_scratch_dir(const std::string& name) {
  return scratch_dir(name + "-" + std::to_string(static_cast<long>(getpid())));
}

/// The bytes of a file ("" when it cannot be read).
inline std::string read_bytes(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

/// The folder of the project templates encoded once per process by
/// `atelier encode --template <which>` (top, skirt, trousers or all).
inline const std::filesystem::path& encoded_templates(const std::string& which = "all") {
  static std::map<std::string, std::filesystem::path> made;
  auto it = made.find(which);
  if (it == made.end()) {
    const std::filesystem::path d = process_scratch_dir("templates-" + which);
    const CommandResult r = run_cli("encode --template " + which + " --out " + d.string());
    if (r.code != 0) std::fprintf(stderr, "encode --template %s failed: %s\n", which.c_str(), r.out.c_str());
    it = made.emplace(which, d).first;
  }
  return it->second;
}

/// " --template <folder>/<name>.template.json" for each name, the templates
/// encoded by encoded_templates().
inline std::string template_args(std::initializer_list<const char*> names = {"top", "skirt", "trousers"}) {
  const std::filesystem::path& d = encoded_templates(names.size() == 1 ? *names.begin() : "all");
  std::string a;
  for (const char* n : names) a += " --template " + (d / (std::string(n) + ".template.json")).string();
  return a;
}

}  // namespace atelier::testing
