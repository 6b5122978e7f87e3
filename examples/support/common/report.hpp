#pragma once

// The console report of `paper` and `study`: every line goes to stdout and into a table file, which
// ends the run: it joins the run's other files, all are put in place together, and they are listed.

#include <iostream>
#include <string>

#include "common/atomic_file.hpp"

namespace mjukf::examples::detail {

class Report {
 public:
  /// Prints `line` and keeps it for the table file.
  void say(const std::string& line) {
    std::cout << line << "\n";
    text_ += line + "\n";
  }

  /// Writes every line said to `table`, one of `outputs`, commits them, and lists the files written.
  void finish(const OutputFile& table, OutputFiles& outputs) const {
    writeText(table, text_);
    outputs.commit();
    std::cout << "\nwrote:\n";
    for (const auto& file : outputs.committed()) std::cout << "  " << file << "\n";
  }

 private:
  std::string text_;
};

}  // namespace mjukf::examples::detail
