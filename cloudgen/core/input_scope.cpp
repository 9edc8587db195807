// The inputs of one command run: (device, inode) -> role, in the innermost live InputScope.
#include "cloudgen/input_scope.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include <map>
#include <mutex>
#include <utility>

#include "cloudgen/errors.h"
#include "cloudgen/printable.h"

namespace cloudgen {

struct InputScope::Impl {
  std::map<std::pair<dev_t, ino_t>, std::string> inputs;
  Impl* outer = nullptr;
};

namespace {
std::mutex g_mutex;
InputScope::Impl* g_scope = nullptr;  // the innermost live scope, or none
}  // namespace

InputScope::InputScope() : impl_(std::make_unique<Impl>()) {
  std::lock_guard<std::mutex> lock(g_mutex);
  impl_->outer = g_scope;
  g_scope = impl_.get();
}

InputScope::~InputScope() {
  std::lock_guard<std::mutex> lock(g_mutex);
  if (g_scope == impl_.get()) g_scope = impl_->outer;
}

void protect_input(const std::string& path, const std::string& role) {
  struct stat st;
  if (::stat(path.c_str(), &st) != 0 || S_ISDIR(st.st_mode)) return;  // the reader says what is missing
  if (!S_ISREG(st.st_mode)) {
    const char* kind = S_ISFIFO(st.st_mode)  ? "a pipe (FIFO)"
                       : S_ISSOCK(st.st_mode) ? "a socket"
                                              : "a device";
    throw InputError(printable(path) + ": is " + kind +
                     ", not a regular file; every input must be a regular file (a pipe or a device can "
                     "block or never end: save it to a file first)");
  }
  std::lock_guard<std::mutex> lock(g_mutex);
  if (g_scope) g_scope->inputs.emplace(std::make_pair(st.st_dev, st.st_ino), role);
}

void release_input(const std::string& path) {
  struct stat st;
  if (::stat(path.c_str(), &st) != 0) return;
  std::lock_guard<std::mutex> lock(g_mutex);
  if (g_scope) g_scope->inputs.erase({st.st_dev, st.st_ino});
}

std::string protected_input_role(const std::string& path) {
  struct stat st;
  if (::stat(path.c_str(), &st) != 0) return {};
  std::lock_guard<std::mutex> lock(g_mutex);
  if (!g_scope) return {};
  auto it = g_scope->inputs.find({st.st_dev, st.st_ino});
  return it == g_scope->inputs.end() ? std::string() : it->second;
}

std::vector<uint8_t> read_input_bytes(const std::string& path, const std::string& role, const std::string& what,
                                      size_t cap) {
  protect_input(path, role);
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    const int e = errno;
    throw InputError(printable(what) + (e == ENOENT ? ": no such file" : ": cannot open: " + std::string(std::strerror(e))));
  }
  struct stat st;
  if (::fstat(fd, &st) == 0 && S_ISDIR(st.st_mode)) {
    ::close(fd);
    throw InputError(printable(what) + ": is a folder, not a file");
  }
  const std::string cap_text =
      cap % (size_t(1) << 20) == 0 ? std::to_string(cap >> 20) + " MiB" : std::to_string(cap) + " bytes";
  const auto too_big = [&](const std::string& size) {
    ::close(fd);
    return InputError(printable(what) + ": " + size + " is more than the " + cap_text + " this reader accepts");
  };
  if (uint64_t(st.st_size) > cap) throw too_big(std::to_string(st.st_size) + " bytes");
  std::vector<uint8_t> bytes;
  bytes.reserve(size_t(st.st_size));
  unsigned char buf[1 << 16];
  for (;;) {
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      const int e = errno;
      ::close(fd);
      throw IoError(printable(what) + ": read failed: " + std::strerror(e));
    }
    if (n == 0) break;
    if (bytes.size() + size_t(n) > cap) throw too_big("the file (it grew while read)");
    bytes.insert(bytes.end(), buf, buf + n);
  }
  ::close(fd);
  return bytes;
}

std::string read_text_input(const std::string& path, const std::string& role, const std::string& what, size_t cap) {
  const std::vector<uint8_t> bytes = read_input_bytes(path, role, what, cap);
  return std::string(bytes.begin(), bytes.end());
}

}  // namespace cloudgen
