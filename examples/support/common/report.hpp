#pragma once

// The console report of `paper` and `study`: every line goes to stdout and into a table file, and the
// files written are listed at the end.

#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "common/csv_writer.hpp"

namespace mjukf::examples::detail {

class Report {
 public:
  /// Prints `line` and keeps it for the table file.
  void say(const std::string& line) {
    std::cout << line << "\n";
    text_ += line + "\n";
  }

  /// Writes every line said to `tableFile`, adds it to `written`, and lists the files written.
  void finish(const std::string& tableFile, std::vector<std::string>& written) const {
    std::ofstream table(tableFile);
    table << text_;
    table.close();
    if (!table) throw OutputError(tableFile + ": cannot write the file");
    written.push_back(tableFile);
    std::cout << "\nwrote:\n";
    for (const auto& file : written) std::cout << "  " << file << "\n";
  }

 private:
  std::string text_;
};

}  // namespace mjukf::examples::detail
