// The one signal policy of both programs (cloudgen and cloudviewer), docs/robustness.md "Interrupts":
// - SIGINT and SIGTERM set `g_interrupted`; long work polls it and stops with Cancelled (exit 130),
//   leaving no partial output.
// - Work that cannot poll (blocked on a pipe, inside a library's reader or a render) is ended
//   half a second after the signal: the process exits 130 with a line on stderr. Staged outputs
//   are anonymous temporaries (O_TMPFILE) and vanish with the process; a second signal ends it at once.
// - While an output batch renames its files into place (CommitSection) the forced exit waits, so a
//   batch is published whole or not at all.
// - A closed stdout pipe (SIGPIPE) ends the program quietly with 141, as `yes | head` does, under
//   the same commit rule.
#pragma once

#include <atomic>

namespace cloudgen {

/// Set by SIGINT/SIGTERM once install_interrupt_policy() has run.
extern std::atomic<bool> g_interrupted;

/// Installs the policy above; call first thing in main. Idempotent.
void install_interrupt_policy();

/// Throws Cancelled when a signal has arrived.
void throw_if_interrupted();

/// Marks that this process began publishing an output (a pipe being written), so a forced exit no
/// longer says "no output was written". CommitSection implies it.
void note_publishing();

/// While one lives, a forced exit waits for it to end (the renames of OutputBatch::commit).
class CommitSection {
 public:
  CommitSection();
  ~CommitSection();
  CommitSection(const CommitSection&) = delete;
  CommitSection& operator=(const CommitSection&) = delete;
};

}  // namespace cloudgen
