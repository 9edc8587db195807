// The signal policy of both programs: cloudgen/interrupt.h.
#include "cloudgen/interrupt.h"

#include <signal.h>
#include <sys/time.h>
#include <unistd.h>

#include <cstring>

#include "cloudgen/errors.h"

namespace cloudgen {

std::atomic<bool> g_interrupted{false};

namespace {

std::atomic<int> g_commit_depth{0};
std::atomic<int> g_pending_exit{0};  // the exit code a forced exit waits to use, 0 if none
std::atomic<bool> g_published{false};  // an output batch began publishing in this process

void say(const char* s) {
  ssize_t n = ::write(STDERR_FILENO, s, std::strlen(s));
  (void)n;
}

// Async-signal-safe: write(2) and _exit(2) only.
void exit_now(int code) {
  if (code == 130)
    say(g_published.load() ? "\ninterrupted: the outputs published before the signal stay; the others were discarded\n"
                           : "\ninterrupted: no output was written or replaced\n");
  ::_exit(code);
}

void exit_or_wait(int code) {
  if (g_commit_depth.load() > 0) {
    g_pending_exit.store(code);  // ~CommitSection exits with it
    return;
  }
  exit_now(code);
}

void on_alarm(int) { exit_or_wait(130); }

void on_interrupt(int) {
  if (g_interrupted.exchange(true)) {
    exit_or_wait(130);  // the second signal: the user insists
    return;
  }
  // Cooperative work stops well within half a second; blocked work is ended by on_alarm.
  struct itimerval half{};
  half.it_value.tv_usec = 500000;
  ::setitimer(ITIMER_REAL, &half, nullptr);
}

void on_pipe(int) { exit_or_wait(128 + SIGPIPE); }

void set_handler(int sig, void (*fn)(int)) {
  struct sigaction sa;
  std::memset(&sa, 0, sizeof sa);
  sa.sa_handler = fn;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART;  // library calls never see EINTR; blocked ones are ended by the alarm
  ::sigaction(sig, &sa, nullptr);
}

}  // namespace

void install_interrupt_policy() {
  set_handler(SIGINT, on_interrupt);
  set_handler(SIGTERM, on_interrupt);
  set_handler(SIGALRM, on_alarm);
  set_handler(SIGPIPE, on_pipe);
}

void throw_if_interrupted() {
  if (g_interrupted.load()) throw Cancelled();
}

void note_publishing() { g_published.store(true); }

CommitSection::CommitSection() {
  g_commit_depth.fetch_add(1);
  g_published.store(true);
}

CommitSection::~CommitSection() {
  if (g_commit_depth.fetch_sub(1) == 1) {
    const int code = g_pending_exit.load();
    if (code == 130) {
      say("\ninterrupted: after publishing the outputs of the batch it was finishing\n");
      ::_exit(code);
    }
    if (code) ::_exit(code);
  }
}

}  // namespace cloudgen
