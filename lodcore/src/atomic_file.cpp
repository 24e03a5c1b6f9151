// Atomic file replacement: write a temporary in the target's folder, fsync it, rename it over the
// target (rename(2) replaces the target in one step on POSIX file systems).
#include "scenelod/lodcore/atomic_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <vector>

namespace scenelod {

namespace {

std::string errnoText(int e) { return std::strerror(e); }

// the process's umask without changing it (umask(2) can only read by writing, which races with other
// threads creating files): Linux reports it in /proc/self/status; 022 where it does not
mode_t currentUmask() {
  mode_t mask = 022;
  if (std::FILE* f = std::fopen("/proc/self/status", "r")) {
    char line[256];
    unsigned value = 0;
    while (std::fgets(line, sizeof line, f))
      if (std::sscanf(line, "Umask: %o", &value) == 1) {
        mask = static_cast<mode_t>(value);
        break;
      }
    std::fclose(f);
  }
  return mask;
}

}  // namespace

AtomicFile::~AtomicFile() { discard(); }

void AtomicFile::discard() {
  if (file_) std::fclose(file_);
  file_ = nullptr;
  if (!temp_path_.empty() && !direct_) ::unlink(temp_path_.c_str());
  temp_path_.clear();
}

Error AtomicFile::open(const std::string& path) {
  discard();
  path_ = path;
  write_errno_ = 0;
  direct_ = false;
  struct stat st;
  const bool exists = ::stat(path.c_str(), &st) == 0;
  if (exists && !S_ISREG(st.st_mode)) {
    // a device or a pipe (-o /dev/null, a fifo) cannot be replaced: write into it directly
    file_ = std::fopen(path.c_str(), "wb");
    if (!file_) return {Status::kIoError, path + ": cannot open for writing (" + errnoText(errno) + ")"};
    direct_ = true;
    return {};
  }
  target_path_ = path;
  if (char* real = exists ? ::realpath(path.c_str(), nullptr) : nullptr) {
    target_path_ = real;  // through symbolic links: replace the file, not the link
    std::free(real);
  }
  // mkstemp wants a writable template: "<target>.tmp-XXXXXX" stays in the target's folder
  std::vector<char> name(target_path_.begin(), target_path_.end());
  const char suffix[] = ".tmp-XXXXXX";
  name.insert(name.end(), suffix, suffix + sizeof suffix);
  const int fd = ::mkstemp(name.data());
  if (fd < 0) return {Status::kIoError, path + ": cannot create file (" + errnoText(errno) + ")"};
  temp_path_ = name.data();
  // mkstemp creates the file 0600: keep the replaced file's mode, else what fopen would give
  ::fchmod(fd, exists ? st.st_mode & 07777 : 0666 & ~currentUmask());
  file_ = ::fdopen(fd, "wb");
  if (!file_) {
    const int e = errno;
    ::close(fd);
    discard();
    return {Status::kIoError, path + ": cannot create file (" + errnoText(e) + ")"};
  }
  return {};
}

void AtomicFile::write(const void* data, size_t bytes) {
  if (!file_ || write_errno_ != 0 || bytes == 0) return;
  if (std::fwrite(data, 1, bytes, file_) != bytes) write_errno_ = errno ? errno : EIO;
}

Error AtomicFile::commit() {
  if (!file_) return {Status::kIoError, path_ + ": write error (the file was not opened)"};
  if (write_errno_ == 0 && std::fflush(file_) != 0) write_errno_ = errno ? errno : EIO;
  if (write_errno_ == 0 && !direct_ && ::fsync(::fileno(file_)) != 0) write_errno_ = errno ? errno : EIO;
  const int close_result = std::fclose(file_);
  file_ = nullptr;
  if (write_errno_ == 0 && close_result != 0) write_errno_ = errno ? errno : EIO;
  if (write_errno_ != 0) {
    const int e = write_errno_;
    discard();
    if (direct_) return {Status::kIoError, path_ + ": write error (" + errnoText(e) + ")"};
    return {Status::kIoError, path_ + ": write error (" + errnoText(e) + "); the file was left as it was"};
  }
  if (direct_) return {};
  if (std::rename(temp_path_.c_str(), target_path_.c_str()) != 0) {
    const int e = errno;
    discard();
    return {Status::kIoError, path_ + ": cannot replace the file (" + errnoText(e) + "); it was left as it was"};
  }
  temp_path_.clear();
  return {};
}

Error writeFileAtomic(const std::string& path, const void* data, size_t bytes) {
  AtomicFile f;
  if (Error e = f.open(path); !e.ok()) return e;
  f.write(data, bytes);
  return f.commit();
}

}  // namespace scenelod
