#include "scenelod/lodcore/atomic_file.h"

#include <dirent.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include <csignal>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "scenelod/lodcore/obj_io.h"
#include "test_support.h"

using namespace scenelod;

namespace {

std::string folder(const std::string& name) {
  const std::string dir = test::scratchDir() + "/" + name;
  ::mkdir(dir.c_str(), 0755);
  return dir;
}

std::string readText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

void writeText(const std::string& path, const std::string& text) { std::ofstream(path, std::ios::binary) << text; }

std::vector<std::string> filesIn(const std::string& dir) {
  std::vector<std::string> names;
  if (DIR* d = ::opendir(dir.c_str())) {
    while (const dirent* e = ::readdir(d))
      if (std::string(e->d_name) != "." && std::string(e->d_name) != "..") names.push_back(e->d_name);
    ::closedir(d);
  }
  return names;
}

// a file-size limit for this process, lifted however the test ends; SIGXFSZ ignored meanwhile so that
// an oversized write fails with EFBIG instead of killing the process
class FileSizeLimit {
 public:
  explicit FileSizeLimit(rlim_t bytes) {
    ::getrlimit(RLIMIT_FSIZE, &old_);
    old_handler_ = std::signal(SIGXFSZ, SIG_IGN);
    rlimit r = old_;
    r.rlim_cur = bytes;
    ::setrlimit(RLIMIT_FSIZE, &r);
  }
  ~FileSizeLimit() {
    ::setrlimit(RLIMIT_FSIZE, &old_);
    std::signal(SIGXFSZ, old_handler_);
  }

 private:
  rlimit old_{};
  void (*old_handler_)(int) = nullptr;
};

}  // namespace

TEST(AtomicFile, ReplacesTheTargetAndLeavesNoTemporary) {
  const std::string dir = folder("atomic_replace");
  const std::string path = dir + "/out.txt";
  writeText(path, "old contents");
  const std::string text = "new contents\n";
  ASSERT_TRUE(writeFileAtomic(path, text.data(), text.size()).ok());
  EXPECT_EQ(readText(path), text);
  EXPECT_EQ(filesIn(dir), std::vector<std::string>{"out.txt"});
}

TEST(AtomicFile, KeepsTheReplacedFilesMode) {
  const std::string dir = folder("atomic_mode");
  const std::string path = dir + "/out.txt";
  writeText(path, "old");
  ASSERT_EQ(::chmod(path.c_str(), 0640), 0);
  ASSERT_TRUE(writeFileAtomic(path, "new", 3).ok());
  struct stat st;
  ASSERT_EQ(::stat(path.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0640u);
}

TEST(AtomicFile, FailedWriteLeavesTheTargetAsItWas) {
  const std::string dir = folder("atomic_limit");
  const std::string path = dir + "/big.bin";
  writeText(path, "the original");
  const std::vector<char> big(1 << 20, 'x');
  Error e;
  {
    FileSizeLimit limit(64 * 1024);
    e = writeFileAtomic(path, big.data(), big.size());
  }
  ASSERT_FALSE(e.ok());
  EXPECT_EQ(e.status, Status::kIoError);
  EXPECT_NE(e.message.find(path), std::string::npos) << e.message;
  EXPECT_NE(e.message.find("left as it was"), std::string::npos) << e.message;
  EXPECT_EQ(readText(path), "the original");
  EXPECT_EQ(filesIn(dir), std::vector<std::string>{"big.bin"});  // the temporary is gone
}

TEST(AtomicFile, InPlaceObjWriteThatFailsKeepsTheInput) {
  // the case a user meets: `simplify x.obj -o x.obj` on a full disk must not destroy x.obj
  const std::string dir = folder("atomic_obj");
  const std::string path = dir + "/model.obj";
  writeText(path, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  Mesh m;
  ASSERT_TRUE(readObj(path, m).ok());
  for (int i = 0; i < 20000; ++i) m.positions.push_back(glm::vec3(float(i), 0.5f, 0.25f));
  Error e;
  {
    FileSizeLimit limit(16 * 1024);
    e = writeObj(path, m);
  }
  ASSERT_FALSE(e.ok());
  Mesh again;
  ASSERT_TRUE(readObj(path, again).ok());
  EXPECT_EQ(again.vertexCount(), 3u);
  EXPECT_EQ(filesIn(dir), std::vector<std::string>{"model.obj"});
}

TEST(AtomicFile, WithoutCommitTheTargetIsUntouched) {
  const std::string dir = folder("atomic_abandon");
  const std::string path = dir + "/out.txt";
  writeText(path, "kept");
  {
    AtomicFile f;
    ASSERT_TRUE(f.open(path).ok());
    f.write(std::string("half of it"));
  }
  EXPECT_EQ(readText(path), "kept");
  EXPECT_EQ(filesIn(dir), std::vector<std::string>{"out.txt"});
}

TEST(AtomicFile, MissingFolderIsAnErrorNamingThePath) {
  const std::string path = test::scratchDir() + "/no_such_folder/out.txt";
  const Error e = writeFileAtomic(path, "x", 1);
  ASSERT_FALSE(e.ok());
  EXPECT_EQ(e.status, Status::kIoError);
  EXPECT_NE(e.message.find(path), std::string::npos) << e.message;
}

TEST(AtomicFile, FollowsASymbolicLink) {
  const std::string dir = folder("atomic_link");
  const std::string target = dir + "/real.txt", link = dir + "/link.txt";
  writeText(target, "old");
  ::unlink(link.c_str());
  ASSERT_EQ(::symlink("real.txt", link.c_str()), 0);
  ASSERT_TRUE(writeFileAtomic(link, "new", 3).ok());
  struct stat st;
  ASSERT_EQ(::lstat(link.c_str(), &st), 0);
  EXPECT_TRUE(S_ISLNK(st.st_mode));  // still a link
  EXPECT_EQ(readText(target), "new");
}

TEST(AtomicFile, WritesIntoADeviceDirectly) {
  ASSERT_TRUE(writeFileAtomic("/dev/null", "x", 1).ok());
  struct stat st;
  ASSERT_EQ(::stat("/dev/null", &st), 0);
  EXPECT_TRUE(S_ISCHR(st.st_mode));
}
