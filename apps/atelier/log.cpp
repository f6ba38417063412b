#include "log.h"

#include <unistd.h>

#include <cstdio>
#include <nlohmann/json.hpp>

namespace atelier::cli {

Log::Log(bool quiet, bool json) : quiet_(quiet), json_(json), tty_(isatty(STDERR_FILENO) != 0) {}

void Log::emit(const char* level, std::string_view msg) const {
  if (json_) {
    nlohmann::json j = {{"level", level}, {"msg", std::string(msg)}};
    std::fprintf(stderr, "%s\n", j.dump().c_str());
  } else {
    std::fprintf(stderr, "atelier: %s%.*s\n", std::string_view(level) == "info" ? "" : (std::string(level) + ": ").c_str(),
                 static_cast<int>(msg.size()), msg.data());
  }
}

void Log::info(std::string_view msg) const {
  if (!quiet_) emit("info", msg);
}
void Log::warn(std::string_view msg) const { emit("warning", msg); }
void Log::error(std::string_view msg) const { emit("error", msg); }

void Log::progress(std::string_view stage, std::size_t done, std::size_t total) {
  if (quiet_ || total == 0) return;
  const auto now = std::chrono::steady_clock::now();
  if (stage != stage_) {
    stage_ = std::string(stage);
    start_ = now;
    last_decile_ = -1;
  }
  const double secs = std::chrono::duration<double>(now - start_).count();
  const double rate = secs > 0 ? static_cast<double>(done) / secs : 0.0;
  const double eta = rate > 0 ? static_cast<double>(total - done) / rate : 0.0;
  if (json_) {
    const int decile = static_cast<int>(10 * done / total);
    if (decile == last_decile_) return;
    last_decile_ = decile;
    nlohmann::json j = {{"level", "progress"}, {"stage", stage_}, {"done", done}, {"total", total},
                        {"rate", rate},        {"eta_s", eta}};
    std::fprintf(stderr, "%s\n", j.dump().c_str());
    return;
  }
  if (tty_) {
    const int width = 30;
    const int filled = static_cast<int>(width * done / total);
    std::fprintf(stderr, "\r%-10s [%.*s%*s] %zu/%zu  %.1f/s  ETA %.0fs ", stage_.c_str(), filled,
                 "##############################", width - filled, "", done, total, rate, eta);
    std::fflush(stderr);
  } else {
    const int decile = static_cast<int>(10 * done / total);
    if (decile == last_decile_) return;
    last_decile_ = decile;
    std::fprintf(stderr, "atelier: %s %zu/%zu (%.1f/s, ETA %.0fs)\n", stage_.c_str(), done, total, rate, eta);
  }
}

void Log::end_progress() {
  if (tty_ && !quiet_ && !json_ && !stage_.empty()) std::fprintf(stderr, "\n");
  stage_.clear();
}

}  // namespace atelier::cli
