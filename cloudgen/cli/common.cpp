// What the cloudgen commands share: the cancel flag, the progress bar, shipped presets, the test hold.
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <mutex>

#include "cloudgen/preset_save.h"
#include "commands.h"

namespace fs = std::filesystem;

namespace cloudgen::cli {

bool g_cancel_reported = false;

std::function<void(double)> progress_bar(const std::string& label, bool quiet) {
  if (quiet || !::isatty(STDERR_FILENO)) return {};
  auto mtx = std::make_shared<std::mutex>();
  auto last = std::make_shared<int>(-1);
  auto t0 = std::chrono::steady_clock::now();
  return [=](double f) {
    std::lock_guard<std::mutex> lock(*mtx);
    int pct = int(f * 100);
    if (pct == *last) return;
    *last = pct;
    const int w = 30, fill = int(f * w);
    double el = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::fprintf(stderr, "\r%-10s [%s%s] %3d%%  %.1fs", label.c_str(), std::string(fill, '#').c_str(),
                 std::string(w - fill, '.').c_str(), pct, el);
    if (f >= 1) std::fprintf(stderr, "\n");
  };
}

std::string preset_dir() { return shipped_preset_dir(); }

std::string resolve_preset_path(const std::string& p) {
  if (fs::exists(p)) return p;
  fs::path shipped = fs::path(preset_dir()) / (p + (fs::path(p).extension().empty() ? ".json" : ""));
  if (fs::exists(shipped)) return shipped.string();
  return p;  // load_preset reports the missing file
}

/// Test hook (tests/test_cloudgen.cpp): CLOUDGEN_TEST_HOLD=generate pauses at the first progress
/// report, =commit pauses with every output staged but none published (=frames: a sequence with
/// its first frame staged); each prints a line and waits for SIGINT/SIGTERM, so a test can
/// interrupt at a known point without sleeping. =generate:stuck stands for work that cannot poll
/// the flag (blocked inside a library): it never returns, and only the signal policy's forced exit
/// ends it (cloudgen/interrupt.h).
void test_hold(const char* where) {
  const char* e = std::getenv("CLOUDGEN_TEST_HOLD");
  if (!e) return;
  const bool stuck = std::string(e) == std::string(where) + ":stuck";
  if (std::string(e) != where && !stuck) return;
  std::fprintf(stderr, "cloudgen: test hold at %s\n", where);
  std::fflush(stderr);
  while (stuck || !g_cancel) ::usleep(1000);
}

}  // namespace cloudgen::cli
