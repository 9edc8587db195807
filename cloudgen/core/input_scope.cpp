// The inputs of one command run: (device, inode) -> role, in the innermost live InputScope.
#include "cloudgen/input_scope.h"

#include <sys/stat.h>

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

}  // namespace cloudgen
