#pragma once
// Files written so that a failure never leaves the target half-written: the bytes go to a temporary
// file in the target's folder, which is flushed to disk and then renamed over the target. Until the
// rename the target keeps its old contents (an in-place `convert a.glb a.glb` that fails keeps a.glb);
// on any failure, or when the writer is destroyed without commit(), the temporary is removed.
// A symbolic link is followed (the file it names is replaced); a device or a pipe (/dev/null, a fifo)
// cannot be replaced and is written directly.
#include <cstddef>
#include <cstdio>
#include <string>

#include "scenelod/lodcore/status.h"

namespace scenelod {

class AtomicFile {
 public:
  AtomicFile() = default;
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;
  ~AtomicFile();  // removes the temporary unless commit() succeeded

  // Creates the temporary beside `path` (same folder, so the rename cannot cross file systems).
  // Errors name `path`: a folder that does not exist or cannot be written.
  Error open(const std::string& path);
  // Appends bytes. A failure (disk full, file-size limit) is remembered and reported by commit().
  void write(const void* data, size_t bytes);
  void write(const std::string& text) { write(text.data(), text.size()); }
  // The stream, for callers that print into it (fprintf); null before open().
  std::FILE* stream() { return file_; }
  // Flushes, syncs and closes the temporary, then renames it over the target. After an error the
  // target is untouched and the temporary gone.
  Error commit();

 private:
  void discard();

  std::string path_, target_path_, temp_path_;  // as given; after symlinks; the temporary
  std::FILE* file_ = nullptr;
  int write_errno_ = 0;
  bool direct_ = false;  // the target is a device or pipe, written in place
};

// The whole file in one call: open, write, commit.
Error writeFileAtomic(const std::string& path, const void* data, size_t bytes);

}  // namespace scenelod
