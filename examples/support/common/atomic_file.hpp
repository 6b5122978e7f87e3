#pragma once

// Output files that are whole or absent. Each file of a run is written under a temporary name in its
// own directory and renamed into place only when the whole run has succeeded (OutputFiles::commit), so
// a run that fails or is stopped leaves the previous files exactly as they were and no part of a file.
// The temporaries not yet committed are also listed for interrupt.hpp, which removes them when a signal
// stops the program.

#include <fcntl.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <deque>
#include <mutex>
#include <set>
#include <stdexcept>
#include <string>

namespace mjukf::examples {

/// A file that could not be written; what() names it.
class OutputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

namespace detail {

// What a signal must undo (interrupt.hpp): the temporaries not yet committed, and the gnuplot child
// that may be writing one. Changed only under the mutex, which the signal thread takes too, so a signal
// sees a commit either not begun or finished. Never destroyed: a signal may come during exit.
struct PendingOutputs {
  std::mutex mutex;
  std::set<std::string> temporaries;
  unsigned long created = 0;  // the temporaries' serial numbers
  pid_t child = 0;

  static PendingOutputs& get() {
    static auto* pending = new PendingOutputs;
    return *pending;
  }
};

inline std::string systemError(const std::string& path, const std::string& what, int error) {
  return path + ": " + what + (error != 0 ? std::string(": ") + std::strerror(error) : std::string());
}

// A path that exists and is neither a regular file nor a directory (/dev/stdout, a pipe): written in
// place, as there is nothing to replace.
inline bool isDevice(const std::string& path) {
  struct stat status {};
  return ::stat(path.c_str(), &status) == 0 && !S_ISREG(status.st_mode) && !S_ISDIR(status.st_mode);
}

inline void requireNoDirectory(const std::string& path) {
  struct stat status {};
  if (::stat(path.c_str(), &status) == 0 && S_ISDIR(status.st_mode))
    throw OutputError(path + ": cannot write the file: a directory has that name");
}

}  // namespace detail

/// One output file: where it goes, and the name it is written under until the commit (the same name
/// for a device, which is written in place).
struct OutputFile {
  std::string path;
  std::string temporary;
};

/// Flushes a file written through `file` to the disk and closes it; false when any write failed (a full
/// disk, a file-size limit), with errno saying why.
inline bool closeWhole(std::FILE* file) {
  bool ok = std::fflush(file) == 0 && std::ferror(file) == 0;
  int error = errno;
  if (ok && ::fsync(::fileno(file)) != 0 && errno != EINVAL) {  // EINVAL: a device or pipe, nothing to sync
    ok = false;
    error = errno;
  }
  if (std::fclose(file) != 0 && ok) {
    ok = false;
    error = errno;
  }
  errno = error;
  return ok;
}

/// The files of one run, committed together: nothing replaces anything until commit(), and a run that
/// ends without it (an exception, a signal) removes its temporaries.
class OutputFiles {
 public:
  OutputFiles() = default;
  OutputFiles(const OutputFiles&) = delete;
  OutputFiles& operator=(const OutputFiles&) = delete;
  ~OutputFiles() { discard(); }

  /// Reserves the temporary name for `path`, creating it empty (so that its directory is known to take a
  /// new file before the run starts); throws OutputError when it cannot, or when `path` is a directory.
  const OutputFile& add(const std::string& path) {
    if (detail::isDevice(path)) return files_.emplace_back(OutputFile{path, path});
    detail::requireNoDirectory(path);
    const std::string::size_type slash = path.rfind('/');
    const std::string directory = slash == std::string::npos ? "" : path.substr(0, slash + 1);
    const std::string name = path.substr(directory.size());
    auto& pending = detail::PendingOutputs::get();
    const std::lock_guard<std::mutex> lock(pending.mutex);  // listed before it exists: a signal finds it
    for (unsigned attempt = 0;; ++attempt) {
      // Hidden, and unique to this process and file; the pid says whose a stray one was.
      const std::string temporary =
          directory + "." + name + ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(pending.created++);
      pending.temporaries.insert(temporary);
      const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
      if (fd >= 0) {
        ::close(fd);
        return files_.emplace_back(OutputFile{path, temporary});
      }
      const int error = errno;
      pending.temporaries.erase(temporary);
      if (error != EEXIST || attempt > 100)
        throw OutputError(detail::systemError(path, "cannot create a file in its directory", error));
    }
  }

  /// The name `path` is written under for now: its temporary while it waits for the commit, else itself.
  std::string current(const std::string& path) const {
    for (const auto& file : files_)
      if (file.path == path) return file.temporary;
    return path;
  }

  /// Renames every file into place, in the order added. Each rename is atomic; they are all done
  /// under the signals' lock, so a signal stops the run before the first or after the last.
  void commit() {
    auto& pending = detail::PendingOutputs::get();
    const std::lock_guard<std::mutex> lock(pending.mutex);
    for (const auto& file : files_) detail::requireNoDirectory(file.path);  // the one failure foreseeable
    std::string done;
    while (!files_.empty()) {
      const OutputFile& file = files_.front();
      if (file.temporary != file.path && std::rename(file.temporary.c_str(), file.path.c_str()) != 0)
        throw OutputError(detail::systemError(file.path, "cannot rename " + file.temporary + " to it", errno) +
                          (done.empty() ? "" : " (already in place:" + done + ")"));
      pending.temporaries.erase(file.temporary);
      committed_.push_back(file.path);
      done += " " + file.path;
      files_.pop_front();
    }
  }

  /// The paths committed so far, in order.
  const std::deque<std::string>& committed() const { return committed_; }

  /// Removes the temporaries not committed.
  void discard() noexcept {
    auto& pending = detail::PendingOutputs::get();
    const std::lock_guard<std::mutex> lock(pending.mutex);
    for (const auto& file : files_)
      if (file.temporary != file.path) {
        ::unlink(file.temporary.c_str());
        pending.temporaries.erase(file.temporary);
      }
    files_.clear();
  }

 private:
  std::deque<OutputFile> files_;  // a deque: add() hands out references that must stay valid
  std::deque<std::string> committed_;
};

/// Writes `text` as the whole of `file`; throws OutputError naming the file when any write fails.
inline void writeText(const OutputFile& file, const std::string& text) {
  std::FILE* out = std::fopen(file.temporary.c_str(), "w");
  if (out == nullptr) throw OutputError(detail::systemError(file.path, "cannot open the file for writing", errno));
  std::fwrite(text.data(), 1, text.size(), out);
  if (!closeWhole(out)) throw OutputError(detail::systemError(file.path, "writing the file failed", errno));
}

}  // namespace mjukf::examples
