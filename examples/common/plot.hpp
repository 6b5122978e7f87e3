#pragma once

// Figures drawn by gnuplot from the CSV files the programs write. Each figure's script is kept next
// to its PNG (name.gp), so a user can restyle a plot without rerunning anything.

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

namespace mjukf::examples {

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
    if (std::system("gnuplot -e 'set terminal pngcairo' >/dev/null 2>&1") == 0)
      terminal_ = "pngcairo";
    else if (std::system("gnuplot -e 'set terminal png' >/dev/null 2>&1") == 0)
      terminal_ = "png";
  }

  bool available() const { return !terminal_.empty(); }

  /// Writes `figure.png` with a script beside it; returns whether the PNG was made.
  bool draw(const Figure& figure) {
    if (!available()) {
      if (!warned_)
        std::cout << "gnuplot (with a PNG terminal) was not found: no plots, the CSV files are written "
                     "(Debian: apt-get install gnuplot-nox)\n";
      warned_ = true;
      return false;
    }
    const std::string scriptPath = figure.png.substr(0, figure.png.rfind('.')) + ".gp";
    {
      std::ofstream script(scriptPath);
      script << this->script(figure);
      if (!script) {
        std::cout << "could not write " << scriptPath << ": no plot\n";
        return false;
      }
    }
    const std::string command = "gnuplot '" + scriptPath + "'";
    if (std::system(command.c_str()) != 0) {
      std::cout << "gnuplot failed on " << scriptPath << "\n";
      return false;
    }
    return true;
  }

 private:
  std::string script(const Figure& figure) const {
    std::string s;
    s += "set terminal " + terminal_ + " size " + std::to_string(figure.width) + "," +
         std::to_string(figure.height) + (terminal_ == "pngcairo" ? " enhanced font 'Sans,10'" : "") + "\n";
    s += "set output '" + figure.png + "'\n";
    s += "set datafile separator ','\n";
    s += "set grid\nset key outside right top vertical Left reverse\n";
    s += "set multiplot layout " + std::to_string(figure.rows) + "," + std::to_string(figure.columns) +
         " title \"" + figure.title + "\" font ',12'\n";
    for (const Panel& panel : figure.panels) {
      s += "set title \"" + panel.title + "\"\n";
      s += "set xlabel \"" + panel.xLabel + "\"\n";
      s += "set ylabel \"" + panel.yLabel + "\"\n";
      s += "plot ";
      for (std::size_t i = 0; i < panel.series.size(); ++i) {
        const Series& c = panel.series[i];
        if (i > 0) s += ", \\\n     ";
        s += "'" + c.file + "' skip 1 every " + std::to_string(c.every) + " using " + std::to_string(c.x) + ":" +
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
