// Helpers shared by the test files: temporary folders, running the cloudgen binary with
// controlled environment, limits and signals, reading and comparing files, the test output folder.
// The viewer tests add test_util_viewer.h (GL context, renders, settings, cloudviewer runs).
#pragma once

#include <fcntl.h>
#include <algorithm>
#include <cerrno>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

// The suite runs twice (scripts/test.sh): optimised, then built with clang's ASan+UBSan. Under the
// sanitizers the costliest tests draw smaller frames (testutil::sized): the same code
// paths and the same assertions over fewer pixels, so the second run checks memory and undefined
// behaviour in a fraction of the time. Their full sizes run in the optimised build.
#if defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(undefined_behavior_sanitizer)
#define CLOUD_TEST_SANITIZED 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__) && !defined(CLOUD_TEST_SANITIZED)
#define CLOUD_TEST_SANITIZED 1
#endif

// The source tree and the build folder (tests/test_paths.cpp; CLOUD_SOURCE_DIR and CLOUD_BINARY_DIR
// call these).
const char* cloud_test_source_dir();
const char* cloud_test_binary_dir();

namespace testutil {

namespace fs = std::filesystem;

#ifdef CLOUD_TEST_SANITIZED
inline constexpr bool kSanitized = true;
#else
inline constexpr bool kSanitized = false;
#endif

/// `full` in the optimised build, `sanitized` under ASan+UBSan (see above).
template <class T>
constexpr T sized(T full, T sanitized) {
  return kSanitized ? sanitized : full;
}

inline const std::string kPresets = std::string(CLOUD_SOURCE_DIR) + "/presets/";
inline const std::string kCli = std::string(CLOUD_BINARY_DIR) + "/bin/cloudgen";

struct TempDir {
  fs::path path;
  TempDir() {
    char tmpl[] = "/tmp/cloudgen-test-XXXXXX";
    path = ::mkdtemp(tmpl);
  }
  ~TempDir() {
    std::error_code ec;
    fs::permissions(path, fs::perms::owner_all, fs::perm_options::add, ec);
    fs::remove_all(path, ec);
  }
  std::string operator/(const std::string& f) const { return (path / f).string(); }
};

/// Runs `cmd` through the shell with stderr folded into the output; returns the exit code.
inline int run_shell(const std::string& cmd, std::string* out = nullptr) {
  FILE* p = ::popen((cmd + " 2>&1").c_str(), "r");
  std::string s;
  char buf[4096];
  while (size_t n = std::fread(buf, 1, sizeof buf, p)) s.append(buf, n);
  const int st = ::pclose(p);
  if (out) *out = s;
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

/// `cloudgen ARGS` (shell words) with stderr folded into the output.
inline int run_cli(const std::string& args, std::string* out = nullptr) { return run_shell(kCli + " " + args, out); }

/// One run of the cloudgen binary with full control, no shell in between.
struct Process {
  std::string program = kCli;
  std::vector<std::string> args;  ///< after the program name
  std::vector<std::string> env;   ///< extra "KEY=VALUE"
  long long fsize_limit = -1;     ///< RLIMIT_FSIZE in bytes (a small "disk")
  std::string signal_on;          ///< send `sig` once the output contains this text
  int sig = SIGINT;
  std::string cwd;
  size_t max_output = 1 << 20;    ///< stop collecting (and kill) beyond this many bytes
  bool stdout_closed = false;     ///< stdout a pipe whose reader is gone (`| head` after it quit); `out` is stderr

  struct Result {
    int code = -1;        ///< exit status, or -1 if killed by a signal
    int term_signal = 0;  ///< the signal that ended it, if any
    std::string out;      ///< stdout + stderr
    bool signalled = false;
  };

  Result run() const {
    int fds[2];
    if (::pipe(fds) != 0) return {};
    int gone[2] = {-1, -1};
    if (stdout_closed && ::pipe(gone) != 0) return {};
    if (stdout_closed) ::close(gone[0]);
    const pid_t pid = ::fork();
    if (pid == 0) {
      ::dup2(stdout_closed ? gone[1] : fds[1], 1);
      ::dup2(fds[1], 2);
      ::close(fds[0]);
      ::close(fds[1]);
      for (const std::string& e : env) ::putenv(const_cast<char*>(e.c_str()));
      if (fsize_limit >= 0) {
        struct rlimit rl{rlim_t(fsize_limit), rlim_t(fsize_limit)};
        ::setrlimit(RLIMIT_FSIZE, &rl);
      }
      if (!cwd.empty() && ::chdir(cwd.c_str()) != 0) ::_exit(98);
      std::vector<char*> argv{const_cast<char*>(program.c_str())};
      for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
      argv.push_back(nullptr);
      ::execv(program.c_str(), argv.data());
      ::_exit(99);
    }
    ::close(fds[1]);
    if (stdout_closed) ::close(gone[1]);
    Result r;
    char buf[4096];
    for (ssize_t n; (n = ::read(fds[0], buf, sizeof buf)) != 0;) {
      if (n < 0) {
        if (errno == EINTR) continue;
        break;
      }
      if (r.out.size() < max_output) r.out.append(buf, size_t(n));
      else ::kill(pid, SIGKILL);
      if (!r.signalled && !signal_on.empty() && r.out.find(signal_on) != std::string::npos) {
        ::kill(pid, sig);
        r.signalled = true;
      }
    }
    ::close(fds[0]);
    int st = 0;
    ::waitpid(pid, &st, 0);
    if (WIFEXITED(st)) r.code = WEXITSTATUS(st);
    if (WIFSIGNALED(st)) r.term_signal = WTERMSIG(st);
    return r;
  }
};

inline std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

inline void write_text(const std::string& path, const std::string& s) { std::ofstream(path, std::ios::binary) << s; }

/// The names in a folder, sorted.
inline std::vector<std::string> list_dir(const fs::path& d) {
  std::vector<std::string> v;
  for (auto& e : fs::directory_iterator(d)) v.push_back(e.path().filename().string());
  std::sort(v.begin(), v.end());
  return v;
}

/// CLOUD_BINARY_DIR/test_output/NAME, created: where a test leaves pictures for a human to look at.
inline fs::path test_output_dir(const std::string& name) {
  fs::path d = fs::path(CLOUD_BINARY_DIR) / "test_output" / name;
  fs::create_directories(d);
  return d;
}

/// Bit-for-bit equality of two float arrays (memcmp: NaN payloads and signed zeros count).
inline bool same_bytes(const std::vector<float>& a, const std::vector<float>& b) {
  // memcmp on the null data() of empty vectors is undefined even for 0 bytes (UBSan)
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0);
}

/// Deterministic uniform numbers in [a, b) (Knuth's MMIX LCG, its top 53 bits): the same points
/// on every machine, from the same start.
struct Lcg {
  uint64_t state;
  double operator()(double a, double b) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return a + (b - a) * double(state >> 11) * (1.0 / 9007199254740992.0);
  }
};

}  // namespace testutil
