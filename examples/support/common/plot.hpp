#pragma once

// Figures drawn by gnuplot from the CSV files the programs write. Each figure's script is kept next
// to its PNG (name.gp), so a user can restyle a plot without rerunning anything.

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>

#include <cerrno>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

extern char** environ;  // POSIX: the environment gnuplot inherits

namespace mjukf::examples {

namespace detail {

// Runs `gnuplot arguments…` with no shell in between, so that no path is ever read as shell text;
// `quiet` sends its output to /dev/null. Returns whether it ran and exited with 0.
inline bool runGnuplot(std::vector<std::string> arguments, bool quiet) {
  arguments.insert(arguments.begin(), "gnuplot");
  std::vector<char*> argv;
  for (auto& argument : arguments) argv.push_back(argument.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  if (posix_spawn_file_actions_init(&actions) != 0) return false;
  if (quiet) {
    posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
    posix_spawn_file_actions_adddup2(&actions, 1, 2);
  }
  pid_t pid = 0;
  const int error = posix_spawnp(&pid, "gnuplot", &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (error != 0) return false;
  int status = 0;
  while (waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) return false;
  return WIFEXITED(status) && WEXITSTATUS(status) == 0;
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

/// Renders figures with gnuplot, or says once that it cannot.
class Plotter {
 public:
  Plotter() {
    if (detail::runGnuplot({"-e", "set terminal pngcairo"}, true))
      terminal_ = "pngcairo";
    else if (detail::runGnuplot({"-e", "set terminal png"}, true))
      terminal_ = "png";
  }

  bool available() const { return !terminal_.empty(); }

  /// Writes `figure.png` with a script beside it; returns whether the PNG was made.
  bool draw(const Figure& figure) {
    std::vector<const std::string*> files;
    for (const Panel& panel : figure.panels)
      for (const Series& series : panel.series) files.push_back(&series.file);
    return drawScript(figure.png, figure.width, figure.height, files, script(figure));
  }

  /// Writes `png` from the gnuplot commands `body` (which read `files`), with the terminal and output
  /// set first and the whole script kept beside the PNG; returns whether the PNG was made.
  bool drawScript(const std::string& png, int width, int height, const std::vector<const std::string*>& files,
                  const std::string& body) {
    if (!available()) {
      if (!warned_)
        std::cout << "gnuplot (with a PNG terminal) was not found: no plots, the CSV files are written "
                     "(Debian: apt-get install gnuplot-nox)\n";
      warned_ = true;
      return false;
    }
    // A gnuplot string cannot hold a line break, so such a path cannot be plotted.
    std::vector<const std::string*> paths{&png};
    paths.insert(paths.end(), files.begin(), files.end());
    for (const std::string* path : paths)
      if (path->find_first_of("\n\r") != std::string::npos) {
        std::cout << "cannot plot with a line break in a path: no " << png << "\n";
        return false;
      }
    const std::string scriptPath = png.substr(0, png.rfind('.')) + ".gp";
    {
      std::ofstream script(scriptPath);
      script << "set terminal " + terminal_ + " size " + std::to_string(width) + "," + std::to_string(height) +
                    (terminal_ == "pngcairo" ? " enhanced font 'Sans,10'" : "") + "\n";
      script << "set output " + detail::gnuplotQuote(png) + "\n" << body;
      if (!script) {
        std::cout << "could not write " << scriptPath << ": no plot\n";
        return false;
      }
    }
    if (!detail::runGnuplot({scriptPath}, false)) {
      std::cout << "gnuplot failed on " << scriptPath << "\n";
      return false;
    }
    return true;
  }

 private:
  std::string script(const Figure& figure) const {
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
        s += detail::gnuplotQuote(c.file) + " skip 1 every " + std::to_string(c.every) + " using " +
             std::to_string(c.x) + ":" + std::to_string(c.y) + " with " + c.style + " title \"" + c.title + "\"";
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
