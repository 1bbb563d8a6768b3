// Inputs that are not regular files or are too large are refused before a byte is read (no hang
// on a FIFO, no bad_alloc on /dev/zero), by every loader; outputs are written whole or not at
// all, never replace a FIFO, device or folder, and leave no temporary file behind.
#include "featherdrive/io/files.hpp"

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include <csignal>
#include <fstream>
#include <functional>

#include "featherdrive/io/checkpoint.hpp"
#include "featherdrive/io/scene.hpp"
#include "featherdrive/io/urdf.hpp"
#include "support/source_tree.hpp"

namespace featherdrive {
namespace {

namespace fs = std::filesystem;
using test::kExamples;

// A fresh, empty folder of this test.
fs::path fresh_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() /
                       ("featherdrive-files-" + name + "-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string contents(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

void write(const fs::path& path, const std::string& text) { std::ofstream(path) << text; }

std::vector<std::string> entries(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

// The message of the exception f throws, which must be an E.
template <class E>
std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const E& e) {
    return e.what();
  } catch (const std::exception& e) {
    return std::string("wrong exception type: ") + e.what();
  }
  return "no error";
}

TEST(Files, NonRegularInputsAreRefusedBeforeReading) {
  const fs::path dir = fresh_dir("inputs");
  const fs::path fifo = dir / "pipe.yaml";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  fs::create_symlink(fifo, dir / "link-to-pipe.yaml");
  auto read = [](const fs::path& p) { return [p] { read_input_file(p); }; };
  EXPECT_EQ(message_of<InputError>(read(dir)), dir.string() + ": is a directory");
  // A FIFO with no writer: read would block forever; it is refused without a read.
  EXPECT_EQ(message_of<InputError>(read(fifo)), fifo.string() + ": is not a regular file (a FIFO)");
  EXPECT_EQ(message_of<InputError>(read(dir / "link-to-pipe.yaml")),
            (dir / "link-to-pipe.yaml").string() + ": is not a regular file (a FIFO)");
  for (const char* device : {"/dev/zero", "/dev/null", "/dev/urandom"})
    EXPECT_EQ(message_of<InputError>(read(device)),
              std::string(device) + ": is not a regular file (a character device)");
  EXPECT_EQ(message_of<InputError>(read(dir / "missing.yaml")),
            (dir / "missing.yaml").string() + ": cannot open the file: No such file or directory");
  EXPECT_EQ(message_of<InputError>([&] { read_input_file(dir / "x.ckpt", "the checkpoint"); }),
            (dir / "x.ckpt").string() + ": cannot open the checkpoint: No such file or directory");
  fs::remove_all(dir);
}

TEST(Files, InputsOverTheBoundAreRefusedAndSmallerOnesRead) {
  EXPECT_EQ(kMaxInputBytes, 64u * 1024 * 1024);
  const fs::path dir = fresh_dir("bound");
  const fs::path big = dir / "big.urdf";
  write(big, "");
  fs::resize_file(big, kMaxInputBytes + 1);  // sparse: no disk used
  EXPECT_EQ(message_of<InputError>([&] { read_input_file(big); }),
            big.string() + ": is larger than 64 MiB (67108865 bytes)");
  const fs::path small = dir / "small.txt";
  write(small, std::string("a\0b\nc", 5));
  EXPECT_EQ(read_input_file(small), std::string("a\0b\nc", 5));
  fs::create_symlink(small, dir / "link.txt");
  EXPECT_EQ(read_input_file(dir / "link.txt"), std::string("a\0b\nc", 5));
  write(dir / "empty.txt", "");
  EXPECT_EQ(read_input_file(dir / "empty.txt"), "");
  fs::remove_all(dir);
}

TEST(Files, EveryLoaderRefusesNonRegularInputsWithItsErrorType) {
  const fs::path dir = fresh_dir("loaders");
  const fs::path fifo = dir / "pipe";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const fs::path big = dir / "big";
  write(big, "");
  fs::resize_file(big, kMaxInputBytes + 4096);
  Simulation sim = make_simulation(load_scene(kExamples + "slider.yaml"));
  const std::vector<std::pair<fs::path, std::string>> cases = {
      {dir, "is a directory"},
      {fifo, "is not a regular file (a FIFO)"},
      {"/dev/zero", "is not a regular file (a character device)"},
      {big, "is larger than 64 MiB"}};
  for (const auto& c : cases) {
    const fs::path& path = c.first;  // not a structured binding: clang 14 cannot capture those
    const std::string& why = c.second;
    const std::string expected = path.string() + ": " + why;
    EXPECT_EQ(message_of<InputError>([&] { load_urdf(path); }).rfind(expected, 0), 0u) << why;
    EXPECT_EQ(message_of<InputError>([&] { load_scene(path); }).rfind(expected, 0), 0u) << why;
    EXPECT_EQ(message_of<CheckpointError>([&] { load_checkpoint(path, sim); }).rfind(expected, 0),
              0u)
        << why;
  }
  fs::remove_all(dir);
}

TEST(Files, FileIdentitySeesThroughLinksAndSpellings) {
  const fs::path dir = fresh_dir("identity");
  fs::create_directories(dir / "sub");
  write(dir / "s.yaml", "x");
  write(dir / "t.yaml", "x");
  fs::create_symlink(dir / "s.yaml", dir / "link.yaml");
  const FileIdentity s = file_identity(dir / "s.yaml");
  EXPECT_EQ(file_identity(dir / "link.yaml"), s);
  EXPECT_EQ(file_identity(dir / "sub" / ".." / "s.yaml"), s);
  EXPECT_EQ(file_identity(dir / "." / "s.yaml"), s);
  ASSERT_EQ(::link((dir / "s.yaml").c_str(), (dir / "hard.yaml").c_str()), 0);
  EXPECT_EQ(file_identity(dir / "hard.yaml"), s);
  EXPECT_FALSE(file_identity(dir / "t.yaml") == s);
  // Files that do not exist yet: the same folder and name, however spelled.
  EXPECT_EQ(file_identity(dir / "new.csv"), file_identity(dir / "sub" / ".." / "new.csv"));
  EXPECT_FALSE(file_identity(dir / "new.csv") == file_identity(dir / "sub" / "new.csv"));
  EXPECT_EQ(file_identity(dir / "a" / "b.csv"), file_identity(dir / "a" / "." / "b.csv"));
  fs::remove_all(dir);
}

TEST(Files, AtomicFileReplacesTheTargetOnlyOnCommit) {
  const fs::path dir = fresh_dir("atomic");
  const fs::path target = dir / "out.csv";
  write(target, "old\n");
  {
    AtomicFile f(target, "the trajectory");
    f.stream() << "new\n";
    EXPECT_EQ(f.temp_path().parent_path(), dir);
    EXPECT_EQ(contents(target), "old\n");  // not yet
    // No commit: an exception or an early return leaves the old file and no temporary.
  }
  EXPECT_EQ(contents(target), "old\n");
  EXPECT_EQ(entries(dir), std::vector<std::string>{"out.csv"});
  {
    AtomicFile f(target, "the trajectory");
    f.stream() << "new\n";
    f.commit();
  }
  EXPECT_EQ(contents(target), "new\n");
  EXPECT_EQ(entries(dir), std::vector<std::string>{"out.csv"});
  fs::remove_all(dir);
}

TEST(Files, AtomicFileKeepsPermissionsAndWritesThroughLinks) {
  const fs::path dir = fresh_dir("modes");
  const fs::path target = dir / "kept.csv";
  write(target, "old");
  fs::permissions(target, fs::perms(0640));
  fs::create_symlink(target, dir / "link.csv");
  AtomicFile f(dir / "link.csv");
  f.stream() << "through the link";
  f.commit();
  EXPECT_TRUE(fs::is_symlink(dir / "link.csv"));
  EXPECT_EQ(contents(target), "through the link");
  EXPECT_EQ(static_cast<int>(fs::status(target).permissions() & fs::perms::all), 0640);
  // A new file: 0666 less the umask, as an ofstream would have made it.
  const mode_t mask = ::umask(022);
  AtomicFile g(dir / "new.csv");
  g.commit();
  ::umask(mask);
  EXPECT_EQ(static_cast<int>(fs::status(dir / "new.csv").permissions() & fs::perms::all), 0644);
  fs::remove_all(dir);
}

TEST(Files, NonRegularTargetsAreNeverReplaced) {
  const fs::path dir = fresh_dir("targets");
  const fs::path fifo = dir / "pipe.ckpt";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  fs::create_directories(dir / "folder.csv");
  fs::create_symlink("/dev/null", dir / "null-link.csv");
  Simulation sim = make_simulation(load_scene(kExamples + "slider.yaml"));
  for (const fs::path& p :
       {fifo, dir / "folder.csv", dir / "null-link.csv", fs::path("/dev/null")}) {
    const std::string expected = p.string() + ": is not a regular file; refusing to replace it";
    EXPECT_EQ(message_of<std::invalid_argument>([&] { AtomicFile f(p); }), expected);
    EXPECT_EQ(message_of<std::invalid_argument>([&] { save_checkpoint(sim, p); }), expected);
  }
  EXPECT_TRUE(fs::is_fifo(fifo));
  EXPECT_TRUE(fs::is_directory(dir / "folder.csv"));
  EXPECT_TRUE(fs::is_character_file("/dev/null"));
  EXPECT_EQ(entries(dir), (std::vector<std::string>{"folder.csv", "null-link.csv", "pipe.ckpt"}));
  fs::remove_all(dir);
}

TEST(Files, WriteFailuresThrowAndLeaveNoTemporary) {
  const fs::path dir = fresh_dir("failures");
  // A folder that does not exist: the temporary cannot be made.
  EXPECT_EQ(
      message_of<std::runtime_error>([&] { AtomicFile f(dir / "none" / "x.csv", "the plot"); }),
      (dir / "none" / "x.csv").string() + ": cannot write the plot: No such file or directory");
  // A write that fails (the file size limit, as a full disk would): the target is untouched.
  write(dir / "x.csv", "old");
  struct rlimit old {};
  ASSERT_EQ(::getrlimit(RLIMIT_FSIZE, &old), 0);
  const auto old_handler = std::signal(SIGXFSZ, SIG_IGN);
  struct rlimit small = old;
  small.rlim_cur = 1000;
  ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &small), 0);
  std::string message;
  {
    AtomicFile f(dir / "x.csv", "the trajectory");
    f.stream() << std::string(200000, 'x');
    message = message_of<std::runtime_error>([&] { f.commit(); });
  }
  ::setrlimit(RLIMIT_FSIZE, &old);
  std::signal(SIGXFSZ, old_handler);
  EXPECT_EQ(message, (dir / "x.csv").string() + ": cannot write the trajectory (write): " +
                         std::strerror(EFBIG));
  EXPECT_EQ(contents(dir / "x.csv"), "old");
  EXPECT_EQ(entries(dir), std::vector<std::string>{"x.csv"});
  fs::remove_all(dir);
}

}  // namespace
}  // namespace featherdrive
