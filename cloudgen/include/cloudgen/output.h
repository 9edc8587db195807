// Safe output files: nothing a run writes is visible until all of it is complete, nothing it
// replaces is lost when it fails, and nothing that is not a regular file is ever replaced.
//
// Rules (docs/robustness.md):
//  - Content is written into an anonymous temporary (O_TMPFILE) in the destination's folder, so a
//    crash or `kill -9` while writing leaves no debris; where the filesystem lacks O_TMPFILE a
//    named `.NAME.tmp-PID-N` file is used and removed by the next run once PID is gone.
//  - Every write, flush, fsync and close is checked; a failure names the path and the system's
//    reason (IoError, exit code 2), and the previous file stays byte for byte.
//  - An OutputBatch publishes all of its files at the end, by rename, and puts every replaced file
//    back if one rename fails: several outputs of one run are all-or-nothing.
//  - A symlink destination is followed: its target is replaced atomically in the target's folder
//    and the link stays. A character device or FIFO (/dev/null, /dev/stdout, a pipe) is written
//    through, never replaced. A folder, block device or socket is refused.
//  - A folder the batch creates (new_folder: a texture pack's) is published whole: its files are
//    staged beside it, moved at commit into a temporary sibling folder `.NAME.tmp-PID-N`, which is
//    then renamed to NAME (never over anything that appeared meanwhile). Until then NAME does not
//    exist; a run killed in the commit's last moments leaves the hidden sibling, which the next run
//    that creates NAME removes.
//  - An output that would replace one of the run's inputs (those given to protect(), and every
//    input the readers recorded in the live InputScope, by device and inode), or another output
//    of the same run (a sidecar included), is refused before anything is written.
#pragma once

#include <functional>
#include <memory>
#include <ostream>
#include <string>
#include <vector>

#include "cloudgen/input_scope.h"

namespace cloudgen {

/// The system's text for errno value `err` ("No space left on device").
std::string system_error_text(int err);

/// A canonical key for "the same file": symlinks followed, "." and ".." removed; for a path that
/// does not exist yet, its folder made canonical. Used to detect outputs that collide.
std::string file_identity(const std::string& path);

class OutputBatch {
 public:
  OutputBatch();
  ~OutputBatch();  ///< discards every staged file that was not committed
  OutputBatch(const OutputBatch&) = delete;
  OutputBatch& operator=(const OutputBatch&) = delete;

  /// `path` is an input of the run (`role` says which, e.g. "the preset"): no output may replace it.
  void protect(const std::string& path, const std::string& role);
  /// Throws InputError if writing `path` would replace a protected input or a file already staged
  /// or claimed, or is a folder/block device/socket; otherwise records the claim. Call this for
  /// every planned output before long work so collisions are reported up front.
  void claim(const std::string& path, const std::string& role);
  /// `dir` (absent now) is created by this batch, whole, at commit: every file staged as
  /// `dir/NAME` goes into it, and `dir` appears with all of them or not at all (see the file
  /// comment). InputError if `dir` exists or its parent folder cannot take it (missing, not
  /// writable), before any work.
  void new_folder(const std::string& dir, const std::string& role);
  /// Writes the content of `path` now: `fill(tmp)` writes to `tmp`, a path it may open, write and
  /// close (any library that takes a file name works). Nothing is visible at `path` until commit().
  void stage(const std::string& path, const std::function<void(const std::string& tmp)>& fill);
  /// As stage(), for content written by another program (Blender): `tmp` is a named file
  /// `.NAME.tmp-PID-N` in the destination's folder that the program may replace by rename; it
  /// is removed if anything fails and by the next run if this one is killed.
  void stage_named(const std::string& path, const std::function<void(const std::string& tmp)>& fill);
  /// Publishes every staged file in staging order; all or nothing (see the file comment).
  /// Returns the destination paths written.
  std::vector<std::string> commit();
  size_t staged() const;

 private:
  void stage_impl(const std::string& path, const std::function<void(const std::string&)>& fill, bool named);
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// A one-file batch: writes `path` atomically with the rules above.
void atomic_write(const std::string& path, const std::function<void(const std::string& tmp)>& fill);

/// For fill functions: writes `n` bytes to `path`, checking every write and the close.
void write_file_bytes(const std::string& path, const void* data, size_t n);
/// For fill functions that stream: opens `path` for binary writing, calls `body(stream)`, then
/// flushes and closes, throwing IoError with the system's reason if any step failed.
void write_file_stream(const std::string& path, const std::function<void(std::ostream&)>& body);

/// Reads a whole file; InputError when it cannot be opened, IoError when reading fails.
/// `max_bytes` bounds what is read (a larger file is an InputError naming the limit).
std::vector<uint8_t> read_file_bytes(const std::string& path, size_t max_bytes = size_t(1) << 36);

}  // namespace cloudgen
