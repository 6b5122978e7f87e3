#pragma once

// Figures drawn by gnuplot from the CSV files the programs write. Each figure's script is kept next
// to its PNG (name.gp), so a user can restyle a plot without rerunning anything.

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <csignal>
#include <fstream>
#include <iostream>
#include <mutex>
#include <string>
#include <vector>

#include "common/atomic_file.hpp"

extern char** environ;  // POSIX: the environment gnuplot inherits

namespace mjukf::examples {

namespace detail {

// Runs `gnuplot arguments…` with no shell in between, so that no path is ever read as shell text;
// `quiet` sends its output to /dev/null. Returns its wait status, or -1 when it could not be started.
// The child is listed for interrupt.hpp, which stops it with the program, and starts with no signal
// blocked and SIGXFSZ at its default (the program blocks the one and ignores the other).
inline int runGnuplot(std::vector<std::string> arguments, bool quiet) {
  arguments.insert(arguments.begin(), "gnuplot");
  std::vector<char*> argv;
  for (auto& argument : arguments) argv.push_back(argument.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawnattr_t attributes;
  if (posix_spawn_file_actions_init(&actions) != 0) return -1;
  if (posix_spawnattr_init(&attributes) != 0) {
    posix_spawn_file_actions_destroy(&actions);
    return -1;
  }
  if (quiet) {
    posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
    posix_spawn_file_actions_adddup2(&actions, 1, 2);
  }
  sigset_t none, fileSize;
  sigemptyset(&none);
  sigemptyset(&fileSize);
  sigaddset(&fileSize, SIGXFSZ);
  posix_spawnattr_setsigmask(&attributes, &none);
  posix_spawnattr_setsigdefault(&attributes, &fileSize);
  posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETSIGDEF);
  auto& pending = PendingOutputs::get();
  pid_t pid = 0;
  int error = 0;
  {
    const std::lock_guard<std::mutex> lock(pending.mutex);
    error = posix_spawnp(&pid, "gnuplot", &actions, &attributes, argv.data(), environ);
    if (error == 0) pending.child = pid;
  }
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attributes);
  if (error != 0) return -1;
  int status = 0;
  pid_t waited = 0;
  while ((waited = waitpid(pid, &status, 0)) < 0 && errno == EINTR) {
  }
  const std::lock_guard<std::mutex> lock(pending.mutex);
  pending.child = 0;
  return waited == pid ? status : -1;
}

inline std::string describeStatus(int status) {
  if (status < 0) return "it could not be started";
  if (WIFSIGNALED(status)) return "killed by signal " + std::to_string(WTERMSIG(status));
  return "exit status " + std::to_string(WEXITSTATUS(status));
}

// Whether `path` is a whole PNG: the signature first and the IEND chunk last. gnuplot can exit with 0
// after a write failed (a full disk), leaving a PNG cut short.
inline bool isWholePng(const std::string& path) {
  static constexpr std::array<unsigned char, 8> signature{0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  static constexpr std::array<unsigned char, 12> end{0, 0, 0, 0, 'I', 'E', 'N', 'D', 0xAE, 0x42, 0x60, 0x82};
  std::ifstream in(path, std::ios::binary);
  std::array<char, 12> head{}, tail{};
  if (!in.read(head.data(), 8) || !in.seekg(-12, std::ios::end) || !in.read(tail.data(), 12)) return false;
  return std::equal(signature.begin(), signature.end(), head.begin(),
                    [](unsigned char a, char b) { return a == static_cast<unsigned char>(b); }) &&
         std::equal(end.begin(), end.end(), tail.begin(),
                    [](unsigned char a, char b) { return a == static_cast<unsigned char>(b); });
}

// Flushes a file another process wrote to the disk, as closeWhole() does for ours.
inline bool syncFile(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return false;
  const bool ok = ::fsync(fd) == 0;
  return ::close(fd) == 0 && ok;
}

// `text` as a gnuplot single-quoted string, where a quote is written twice and nothing else is special.
inline std::string gnuplotQuote(const std::string& text) {
  std::string quoted = "'";
  for (char c : text) quoted += c == '\'' ? std::string("''") : std::string(1, c);
  return quoted + "'";
}

}  // namespace detail

/// One curve: column `y` against column `x` (1-based) of a CSV file with a header row.
struct Series {
  std::string file;
  int x = 1;
  int y = 2;
  std::string title;
  std::string style;  ///< gnuplot style, e.g. "lines lw 2 lc rgb '#d62728'"
  int every = 1;      ///< plot every n-th row, to keep dense measurements light
};

struct Panel {
  std::string title;
  std::string xLabel;
  std::string yLabel;
  std::vector<Series> series;
};

/// A PNG of panels laid out in `rows` × `columns`.
struct Figure {
  std::string png;
  std::string title;
  int rows = 1;
  int columns = 1;
  int width = 1000;
  int height = 700;
  std::vector<Panel> panels;
};

/// Renders figures with gnuplot into the files of a run (atomic_file.hpp), or says once that it cannot.
class Plotter {
 public:
  Plotter() {
    if (detail::runGnuplot({"-e", "set terminal pngcairo"}, true) == 0)
      terminal_ = "pngcairo";
    else if (detail::runGnuplot({"-e", "set terminal png"}, true) == 0)
      terminal_ = "png";
  }

  bool available() const { return !terminal_.empty(); }

  /// Adds `figure.png` and its script to `outputs`; returns whether there is a figure (see drawScript).
  bool draw(OutputFiles& outputs, const Figure& figure) {
    std::vector<std::string> files;
    for (const Panel& panel : figure.panels)
      for (const Series& series : panel.series)
        if (std::find(files.begin(), files.end(), series.file) == files.end()) files.push_back(series.file);
    return drawScript(outputs, figure.png, figure.width, figure.height, files, script(figure, files));
  }

  /// Adds `png`, drawn by the gnuplot commands `body`, and its script (`png` with .gp) to `outputs`. The
  /// body reads `files` as the variables csv1, csv2, …, set in the script's first lines with the terminal
  /// and the output. Returns false, with a note on stderr, when gnuplot is missing or a path has a line
  /// break; throws OutputError when gnuplot fails or leaves an incomplete PNG, as the run has then failed.
  bool drawScript(OutputFiles& outputs, const std::string& png, int width, int height,
                  const std::vector<std::string>& files, const std::string& body) {
    if (!available()) {
      if (!warned_)
        std::cerr << "gnuplot (with a PNG terminal) was not found: no plots, the other files are written "
                     "(Debian: apt-get install gnuplot-nox)\n";
      warned_ = true;
      return false;
    }
    // A gnuplot string cannot hold a line break, so such a path cannot be plotted.
    std::vector<std::string> paths{png};
    paths.insert(paths.end(), files.begin(), files.end());
    for (const std::string& path : paths)
      if (path.find_first_of("\n\r") != std::string::npos) {
        std::cerr << "cannot plot with a line break in a path: no " << png << "\n";
        return false;
      }
    // The script kept beside the PNG names the files; gnuplot runs a copy naming their temporaries, as
    // nothing is in place before the run's commit.
    const auto text = [&](auto name) {
      std::string s = "set terminal " + terminal_ + " size " + std::to_string(width) + "," + std::to_string(height) +
                      (terminal_ == "pngcairo" ? " enhanced font 'Sans,10'" : "") + "\n";
      s += "set output " + detail::gnuplotQuote(name(png)) + "\n";
      for (std::size_t i = 0; i < files.size(); ++i)
        s += "csv" + std::to_string(i + 1) + " = " + detail::gnuplotQuote(name(files[i])) + "\n";
      return s + body;
    };
    const std::string scriptPath = png.substr(0, png.rfind('.')) + ".gp";
    writeText(outputs.add(scriptPath), text([](const std::string& path) { return path; }));
    const OutputFile& image = outputs.add(png);
    OutputFiles running;  // the copy gnuplot runs, removed on return
    const OutputFile& runScript = running.add(scriptPath);
    writeText(runScript, text([&](const std::string& path) { return outputs.current(path); }));
    const int status = detail::runGnuplot({runScript.temporary}, false);
    if (status != 0) throw OutputError(png + ": gnuplot failed (" + detail::describeStatus(status) + "): no figure");
    if (!detail::isWholePng(image.temporary) || !detail::syncFile(image.temporary))
      throw OutputError(png + ": gnuplot left an incomplete PNG (a full disk?)");
    return true;
  }

 private:
  // The figure's commands, reading file i of `files` as csv<i + 1>.
  std::string script(const Figure& figure, const std::vector<std::string>& files) const {
    const auto variable = [&](const std::string& file) {
      return "csv" + std::to_string(std::find(files.begin(), files.end(), file) - files.begin() + 1);
    };
    std::string s;
    s += "set datafile separator ','\n";
    s += "set grid\nset key outside right top vertical Left reverse\n";
    s += "set multiplot layout " + std::to_string(figure.rows) + "," + std::to_string(figure.columns) + " title \"" +
         figure.title + "\" font ',12'\n";
    for (const Panel& panel : figure.panels) {
      s += "set title \"" + panel.title + "\"\n";
      s += "set xlabel \"" + panel.xLabel + "\"\n";
      s += "set ylabel \"" + panel.yLabel + "\"\n";
      s += "plot ";
      for (std::size_t i = 0; i < panel.series.size(); ++i) {
        const Series& c = panel.series[i];
        if (i > 0) s += ", \\\n     ";
        s += variable(c.file) + " skip 1 every " + std::to_string(c.every) + " using " + std::to_string(c.x) + ":" +
             std::to_string(c.y) + " with " + c.style + " title \"" + c.title + "\"";
      }
      s += "\n";
    }
    s += "unset multiplot\n";
    return s;
  }

  std::string terminal_;
  bool warned_ = false;
};

}  // namespace mjukf::examples
