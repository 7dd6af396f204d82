// The store's choice of connection from what a process may do to a database
// file (sqlite_support.hpp): how a reader connects, and what refuses a
// writer, for every answer the system could give (the answers injected, so
// that the choice is tested whoever runs the test, root included); and
// file_access on real files for what does not depend on who runs it.
#include "sqlite_support.hpp"

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "loopfarm/farm/results_database.hpp"
#include "refusal.hpp"

namespace loopfarm {
namespace {

namespace fs = std::filesystem;
using store::FileAccess;
using store::ReaderConnection;
using testing::refusal;

// An existing, writable file in a writable directory, nothing beside it.
FileAccess alone() {
  FileAccess access;
  access.exists = true;
  access.mode = 0644;
  access.file_writable = true;
  access.directory_exists = true;
  access.directory_writable = true;
  return access;
}

TEST(ReaderConnection, AFileNothingHasOpenIsReadReadWriteWhenItsCompanionsCanBeRemoved) {
  EXPECT_EQ(store::reader_connection(alone()), ReaderConnection::read_write);
}

TEST(ReaderConnection, AFileOrDirectoryThatMayNotBeWrittenIsReadAsImmutable) {
  FileAccess file = alone();
  file.mode = 0444;
  file.file_writable = false;
  EXPECT_EQ(store::reader_connection(file), ReaderConnection::immutable);
  FileAccess directory = alone();
  directory.directory_writable = false;
  EXPECT_EQ(store::reader_connection(directory), ReaderConnection::immutable);
  FileAccess both = file;
  both.directory_writable = false;
  EXPECT_EQ(store::reader_connection(both), ReaderConnection::immutable);
}

TEST(ReaderConnection, CompanionsThereAreLeftToAReadOnlyConnectionWhateverMayBeWritten) {
  for (const bool file_writable : {true, false}) {
    for (const bool directory_writable : {true, false}) {
      for (const char* suffix : {"-wal", "-shm"}) {
        FileAccess access = alone();
        access.file_writable = file_writable;
        access.directory_writable = directory_writable;
        access.companions = {std::string("r.sqlite") + suffix};
        EXPECT_EQ(store::reader_connection(access), ReaderConnection::read_only)
            << suffix << " file_writable " << file_writable << " directory_writable " << directory_writable;
      }
    }
  }
}

TEST(WriterAccess, AWritableFileInAWritableDirectoryPasses) {
  EXPECT_EQ(refusal([] { store::check_writer_access("d/r.sqlite", alone(), true); }), "");
  FileAccess missing = alone();
  missing.exists = false;
  missing.mode = 0;
  missing.file_writable = false;
  EXPECT_EQ(refusal([&] { store::check_writer_access("d/r.sqlite", missing, false); }), "");
  // Companions it may write (a run of its own that crashed) are no obstacle.
  FileAccess companions = alone();
  companions.companions = {"d/r.sqlite-wal", "d/r.sqlite-shm"};
  EXPECT_EQ(refusal([&] { store::check_writer_access("d/r.sqlite", companions, true); }), "");
}

TEST(WriterAccess, AnUnwritableDirectoryIsNamed) {
  FileAccess access = alone();
  access.directory_writable = false;
  for (const bool file_too : {true, false}) {
    const std::string text = refusal([&] { store::check_writer_access("results/r.sqlite", access, file_too); });
    EXPECT_NE(text.find("results database results/r.sqlite: its directory results is not writable"), std::string::npos)
        << text;
  }
  // A bare name's directory is the working directory.
  EXPECT_NE(refusal([&] { store::check_writer_access("r.sqlite", access, false); }).find("its directory . is not"),
            std::string::npos);
  // A new file too: nothing could be created there.
  access.exists = false;
  access.file_writable = false;
  EXPECT_NE(refusal([&] {
              store::check_writer_access("results/r.sqlite", access, false);
            }).find("its directory results is not writable"),
            std::string::npos);
  access.directory_exists = false;
  EXPECT_NE(refusal([&] {
              store::check_writer_access("results/r.sqlite", access, false);
            }).find("its directory results does not exist"),
            std::string::npos);
}

TEST(WriterAccess, CompanionsThatMayNotBeWrittenAreNamed) {
  FileAccess access = alone();
  access.companions = {"d/r.sqlite-wal", "d/r.sqlite-shm"};
  access.locked_companions = access.companions;
  const std::string both = refusal([&] { store::check_writer_access("d/r.sqlite", access, true); });
  EXPECT_NE(both.find("results database d/r.sqlite: d/r.sqlite-wal and d/r.sqlite-shm beside it are not writable"),
            std::string::npos)
      << both;
  EXPECT_NE(both.find("remove them"), std::string::npos) << both;
  access.locked_companions = {"d/r.sqlite-shm"};
  const std::string one = refusal([&] { store::check_writer_access("d/r.sqlite", access, false); });
  EXPECT_NE(one.find("d/r.sqlite-shm beside it is not writable"), std::string::npos) << one;
  EXPECT_EQ(one.find("d/r.sqlite-wal"), std::string::npos) << one;
}

TEST(WriterAccess, OnlyUpdateModeRefusesAReadOnlyFile) {
  FileAccess access = alone();
  access.mode = 0444;
  access.file_writable = false;
  const std::string text = refusal([&] { store::check_writer_access("d/r.sqlite", access, true); });
  EXPECT_NE(text.find("d/r.sqlite: a read-only file (mode 0444)"), std::string::npos) << text;
  EXPECT_EQ(refusal([&] { store::check_writer_access("d/r.sqlite", access, false); }), "");
}

// What the system says, in a directory of the test's own.
class FileAccessTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("loopfarm_sqlite_support_test_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string touch(const std::string& name) const {
    const std::string path = (dir_ / name).string();
    std::ofstream(path) << "x";
    return path;
  }

  fs::path dir_;
};

TEST_F(FileAccessTest, SaysWhatExistsBesideTheFile) {
  const std::string path = (dir_ / "r.sqlite").string();
  FileAccess access = store::file_access(path);
  EXPECT_FALSE(access.exists);
  EXPECT_TRUE(access.directory_exists);
  EXPECT_TRUE(access.companions.empty());
  touch("r.sqlite");
  touch("r.sqlite-shm");
  access = store::file_access(path);
  EXPECT_TRUE(access.exists);
  EXPECT_EQ(access.companions, std::vector<std::string>{path + "-shm"});
  touch("r.sqlite-wal");
  EXPECT_EQ(store::file_access(path).companions, (std::vector<std::string>{path + "-wal", path + "-shm"}));
  EXPECT_FALSE(store::file_access((dir_ / "none" / "r.sqlite").string()).directory_exists);
  EXPECT_EQ(store::directory_of("r.sqlite"), ".");
  EXPECT_EQ(store::directory_of("a/b/r.sqlite"), "a/b");
}

// A file made read-only on purpose counts as read-only for root too.
TEST_F(FileAccessTest, AFileWithoutAWriteBitIsNotWritableWhoeverAsks) {
  const std::string path = touch("r.sqlite");
  fs::permissions(path, fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
  FileAccess access = store::file_access(path);
  EXPECT_EQ(access.mode, 0640u);
  EXPECT_TRUE(access.file_writable);
  fs::permissions(path, fs::perms::owner_read | fs::perms::group_read | fs::perms::others_read);
  access = store::file_access(path);
  EXPECT_EQ(access.mode, 0444u);
  EXPECT_FALSE(access.file_writable);
  EXPECT_EQ(store::reader_connection(access), ReaderConnection::immutable);
}

}  // namespace
}  // namespace loopfarm
