#pragma once

// Running the example programs from a test as a user runs them: the command through the shell with
// its output captured, and scratch files of the test's own.

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>

#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>

extern char** environ;  // POSIX: what a started program inherits

namespace mjukf::program_tests {

struct Result {
  int exitCode = -1;
  std::string output;  // stdout and stderr together (run), or stdout alone (runSeparately)
  std::string errors;  // stderr (runSeparately only)
};

// The shell command `line`, its stdout read.
inline Result capture(const std::string& line) {
  Result result;
  std::FILE* pipe = popen(line.c_str(), "r");
  if (pipe == nullptr) return result;
  char buffer[4096];
  while (std::fgets(buffer, sizeof buffer, pipe) != nullptr) result.output += buffer;
  const int status = pclose(pipe);
  result.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

inline Result run(const std::string& command) { return capture(command + " 2>&1"); }

inline std::string readText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// A scratch path of this test's own, so that tests may run in parallel.
inline std::string scratch(const std::string& name) {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const std::filesystem::path dir =
      std::filesystem::path(MJUKF_SCRATCH_DIR) / (std::string(info->test_suite_name()) + "." + info->name());
  std::filesystem::create_directories(dir);
  return (dir / name).string();
}

inline std::string writeFile(const std::string& name, const std::string& text) {
  const std::string path = scratch(name);
  std::ofstream(path) << text;
  return path;
}

// `text` as one word for the shell.
inline std::string shellQuote(const std::string& text) {
  std::string quoted = "'";
  for (char c : text) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

// `command` with stdout and stderr kept apart, stderr through the file `errorsFile`.
inline Result runSeparately(const std::string& command, const std::string& errorsFile) {
  Result result = capture("{ " + command + "; } 2>" + shellQuote(errorsFile));
  result.errors = readText(errorsFile);
  return result;
}

// Every entry of `dir`, hidden ones included, with its bytes: what a run must leave as it was.
inline std::map<std::string, std::string> listing(const std::filesystem::path& dir) {
  std::map<std::string, std::string> entries;
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    entries[entry.path().filename().string()] = entry.is_regular_file() ? readText(entry.path().string()) : "<dir>";
  return entries;
}

// Starts `argv` without waiting for it, its stdout and stderr to `log`, with SIGINT and SIGTERM at their
// defaults (a shell may have had them ignored for a background job). Returns its pid, or -1.
inline pid_t start(const std::vector<std::string>& argv, const std::string& log) {
  std::vector<char*> args;
  for (const auto& word : argv) args.push_back(const_cast<char*>(word.c_str()));
  args.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  posix_spawnattr_t attributes;
  posix_spawnattr_init(&attributes);
  sigset_t defaults, none;
  sigemptyset(&defaults);
  sigaddset(&defaults, SIGINT);
  sigaddset(&defaults, SIGTERM);
  sigemptyset(&none);
  posix_spawnattr_setsigdefault(&attributes, &defaults);
  posix_spawnattr_setsigmask(&attributes, &none);
  posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETSIGDEF | POSIX_SPAWN_SETSIGMASK);
  pid_t pid = -1;
  if (posix_spawn(&pid, args[0], &actions, &attributes, args.data(), environ) != 0) pid = -1;
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attributes);
  return pid;
}

}  // namespace mjukf::program_tests
