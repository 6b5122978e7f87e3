#pragma once

// SIGINT, SIGTERM and SIGHUP stop a program cleanly: the temporaries of its outputs (atomic_file.hpp)
// are removed, a gnuplot it runs is stopped, and it exits with 128 + the signal's number, as a shell
// reports a program the signal killed. The signals are taken by a thread of their own (sigwait), where
// locks and strings are safe, rather than by a handler.

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <cstdlib>
#include <mutex>
#include <string>
#include <thread>

#include "common/atomic_file.hpp"

namespace mjukf::examples {

namespace detail {
inline const char* signalName(int signal) {
  return signal == SIGINT ? "SIGINT" : signal == SIGTERM ? "SIGTERM" : signal == SIGHUP ? "SIGHUP" : "a signal";
}
}  // namespace detail

/// Takes over SIGINT, SIGTERM and SIGHUP for the rest of the program; call it before any thread starts
/// (threads inherit the blocked signals). A signal ignored on entry (nohup, a background job) stays
/// ignored.
inline void handleInterrupts(const char* program) {
  // A file-size limit then fails the write (EFBIG, reported like a full disk) instead of killing the
  // program with its temporaries left behind.
  std::signal(SIGXFSZ, SIG_IGN);
  sigset_t signals;
  sigemptyset(&signals);
  bool any = false;
  for (int signal : {SIGINT, SIGTERM, SIGHUP}) {
    struct sigaction action {};
    if (sigaction(signal, nullptr, &action) == 0 && action.sa_handler != SIG_IGN) {
      sigaddset(&signals, signal);
      any = true;
    }
  }
  if (!any) return;
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  std::thread([signals, program] {
    int signal = 0;
    while (sigwait(&signals, &signal) != 0) {
    }
    auto& pending = detail::PendingOutputs::get();
    const std::lock_guard<std::mutex> lock(pending.mutex);  // never in the middle of a commit
    if (pending.child > 0) {
      ::kill(pending.child, SIGKILL);
      ::waitpid(pending.child, nullptr, 0);
    }
    for (const auto& temporary : pending.temporaries) ::unlink(temporary.c_str());
    std::string message = std::string(program) + ": interrupted (" + detail::signalName(signal) + ")";
    if (!pending.temporaries.empty())
      message += ": " + std::to_string(pending.temporaries.size()) +
                 " unfinished output files removed, the files they were to replace left as they were";
    message += "\n";
    // write(), not stdio: the main thread may hold stderr's lock, blocked on a full pipe.
    [[maybe_unused]] const auto written = ::write(STDERR_FILENO, message.data(), message.size());
    std::_Exit(128 + signal);
  }).detach();
}

}  // namespace mjukf::examples
