#include "app/authoring.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>

#include "cloudgen/errors.h"
#ifdef CLOUDVIEWER_HAS_CLOUDGEN
#include "cloudgen/export_preset.h"
#include "cloudgen/preset.h"
#endif
#include "cloudgen/printable.h"
#include "cloudviewer/errors.h"

namespace cloudviewer {

namespace fs = std::filesystem;

std::vector<std::string> export_preset_files(const std::string& input, const std::vector<std::string>& sets,
                                             const std::vector<std::string>& outputs,
                                             const std::function<void(double)>& progress,
                                             const std::atomic<bool>* cancel) {
#ifdef CLOUDVIEWER_HAS_CLOUDGEN
  const cloudgen::Preset p = cloudgen::load_preset(input, sets);
  cloudgen::PresetExport e;
  e.outputs = outputs;
  cloudgen::GenerateOptions go;
  go.progress = progress;
  go.cancel = cancel;
  return cloudgen::export_preset(p, input, e, go).written;
#else
  (void)sets, (void)outputs, (void)progress, (void)cancel;
  throw InputError("export " + input + ": this cloudviewer was built without the cloudgen library");
#endif
}

std::string cloudgen_program() {
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    const fs::path beside = self.parent_path() / "cloudgen";
    if (fs::is_regular_file(beside, ec)) return beside.string();
  }
  return "cloudgen";
}

std::string open_in_blender(const std::string& vdb, const std::string& blend) {
  const std::vector<std::string> args = {cloudgen_program(), "blender", vdb, "-o", blend, "-q"};
  std::vector<char*> argv;
  for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  // posix_spawn, not fork: the window has threads (a fork child may only exec), and the output
  // goes to a pipe that this thread reads.
  int pipe_fd[2];
  if (pipe(pipe_fd) != 0) throw cloudgen::IoError("open in Blender: pipe: " + std::string(std::strerror(errno)));
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_adddup2(&fa, pipe_fd[1], 1);
  posix_spawn_file_actions_adddup2(&fa, pipe_fd[1], 2);
  posix_spawn_file_actions_addclose(&fa, pipe_fd[0]);
  posix_spawn_file_actions_addclose(&fa, pipe_fd[1]);
  pid_t pid = 0;
  const int spawned = posix_spawnp(&pid, argv[0], &fa, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  if (spawned != 0) {
    close(pipe_fd[0]);
    close(pipe_fd[1]);
    throw InputError("open in Blender: cannot run " + args[0] + ": " + std::strerror(spawned));
  }
  close(pipe_fd[1]);
  std::string output;
  char buf[4096];
  for (ssize_t n; (n = read(pipe_fd[0], buf, sizeof buf)) != 0;) {
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) break;
    output.append(buf, size_t(n));
  }
  close(pipe_fd[0]);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
    throw InputError("open in Blender: `" + args[0] + " blender " + cloudgen::printable(vdb) + " -o " +
                     cloudgen::printable(blend) + "` failed" +
                     (output.empty() ? "" : ": " + output));
  return blend;
}

std::string edited_name(const std::string& input, const std::string& extension) {
  return fs::path(input).stem().string() + "_edited" + extension;
}

}  // namespace cloudviewer
