// Console output of the CLI: plain log lines on stderr, JSON lines with
// --log-json (for pipelines), and a progress bar with rate and ETA only when
// stderr is a terminal.
#pragma once

#include <chrono>
#include <cstddef>
#include <string>
#include <string_view>

namespace atelier::cli {

class Log {
 public:
  Log(bool quiet, bool json);
  void info(std::string_view msg) const;
  void warn(std::string_view msg) const;
  void error(std::string_view msg) const;
  /// Progress of a stage; draws a bar on a terminal, else logs every ~10%.
  void progress(std::string_view stage, std::size_t done, std::size_t total);
  void end_progress();

 private:
  void emit(const char* level, std::string_view msg) const;
  bool quiet_, json_, tty_;
  std::chrono::steady_clock::time_point start_;
  std::string stage_;
  int last_decile_ = -1;
};

}  // namespace atelier::cli
