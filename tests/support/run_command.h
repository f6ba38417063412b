// Running commands from tests (the built CLI, cmake, chromium): exit code
// and combined output, plus a fresh scratch folder under $ATELIER_TMP.
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

namespace atelier::testing {

struct CommandResult {
  int code = -1;    // exit status, -1 when the command did not exit normally
  std::string out;  // stdout and stderr
};

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

/// Runs the built atelier CLI with `args`.
inline CommandResult run_cli(const std::string& args) { return run_command(std::string(ATELIER_CLI) + " " + args); }

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

}  // namespace atelier::testing
