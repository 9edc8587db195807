// The inputs of one command run ("every input protected", docs/robustness.md). While an InputScope
// is alive, every input a reader opens is recorded by device and inode (links followed, so a
// symlink or a hard link to an input is that input), and every OutputBatch and atomic_write of the
// process refuses to replace one of them, before anything is written (cloudgen/output.h). Both
// programs hold one for the whole run; scopes nest (the inner one ends with its block). Without
// one (the library in tests) nothing is recorded.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace cloudgen {

class InputScope {
 public:
  InputScope();
  ~InputScope();
  InputScope(const InputScope&) = delete;
  InputScope& operator=(const InputScope&) = delete;
  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

/// Records `path` as an input of the current InputScope (none: nothing happens); `role` names it in
/// the refusal ("the input preset x.json"). Only an existing regular file is recorded; a missing
/// path or a folder is left to the reader's own error. Every reader calls it before opening, so it
/// is also the one rule on what an input may be: a pipe (FIFO), socket or device throws InputError
/// (it could block with no writer or stream without end), scope or not. Thread-safe.
void protect_input(const std::string& path, const std::string& role);

/// Forgets `path` as an input: for a command that updates a file it owns after reading it (a
/// merge records the tiles' checksums in its plan, and regenerates a damaged tile).
void release_input(const std::string& path);

/// The role of the recorded input that `path` is (links followed), or "" when it is none.
std::string protected_input_role(const std::string& path);

/// The most a text input (preset, plan, bench track, Mie table) may have: 64 MiB. The largest
/// shipped one is about 10 KiB; a bigger file is a mistake (or hostile), and reading it whole would
/// cost memory without bound.
constexpr size_t kTextInputCap = size_t(64) << 20;

/// Reads a whole input file under the one rule: protect_input first (so a pipe or device is
/// refused), then at most `cap` bytes, checked from its size before reading and while reading, or
/// InputError naming it (`what`, e.g. "--bench track.json"), its size and the cap; a missing file
/// is "no such file", a failed read an IoError with the system's reason.
std::vector<uint8_t> read_input_bytes(const std::string& path, const std::string& role, const std::string& what,
                                      size_t cap);

/// read_input_bytes for a text input, with the text inputs' cap by default.
std::string read_text_input(const std::string& path, const std::string& role, const std::string& what,
                            size_t cap = kTextInputCap);

}  // namespace cloudgen
