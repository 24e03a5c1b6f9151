#pragma once
// A progress bar on stderr for work that takes more than a second: nothing is printed before one
// second has passed, then the bar is redrawn at most ten times a second. On a terminal it redraws
// in place; otherwise (CI logs) it prints a line every 10 %.
#include <chrono>
#include <cstdio>
#include <string>

#include <unistd.h>

#include "scenelod/lodcore/progress.h"

namespace scenelod::tool {

class ProgressBar {
 public:
  explicit ProgressBar(std::string label) : label_(std::move(label)), start_(Clock::now()), tty_(isatty(2) != 0) {}
  ~ProgressBar() { finish(); }

  void update(double fraction, const char* stage) {
    const auto now = Clock::now();
    const double elapsed = std::chrono::duration<double>(now - start_).count();
    if (elapsed < 1.0) return;
    if (tty_) {
      if (shown_ && std::chrono::duration<double>(now - last_).count() < 0.1 && fraction < 1.0) return;
      const int width = 30, filled = static_cast<int>(fraction * width + 0.5);
      std::fprintf(stderr, "\r%s [%.*s%*s] %3.0f%% %-24.24s", label_.c_str(), filled,
                   "##############################", width - filled, "", fraction * 100.0, stage ? stage : "");
    } else {
      const int decile = static_cast<int>(fraction * 10.0);
      if (shown_ && decile <= last_decile_) return;
      last_decile_ = decile;
      std::fprintf(stderr, "%s: %3.0f%% %s (%.1f s)\n", label_.c_str(), fraction * 100.0, stage ? stage : "", elapsed);
    }
    std::fflush(stderr);
    shown_ = true;
    last_ = now;
  }

  void finish() {
    if (shown_ && tty_) std::fprintf(stderr, "\n");
    shown_ = false;
  }

  // A lodcore callback that forwards to this bar.
  ProgressCallback callback() {
    ProgressCallback cb;
    cb.fn = [](void* self, double f, const char* stage) { static_cast<ProgressBar*>(self)->update(f, stage); };
    cb.user = this;
    return cb;
  }

 private:
  using Clock = std::chrono::steady_clock;
  std::string label_;
  Clock::time_point start_, last_;
  bool tty_;
  bool shown_ = false;
  int last_decile_ = -1;
};

}  // namespace scenelod::tool
