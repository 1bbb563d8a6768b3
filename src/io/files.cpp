#include "featherdrive/io/files.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <streambuf>
#include <vector>

#include "featherdrive/io/error.hpp"

namespace featherdrive {
namespace fs = std::filesystem;
namespace {

const char* kind(mode_t mode) {
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a file";
}

// The refusal of a file that stat describes, or "" when it may be read.
std::string refusal(const struct stat& st) {
  if (S_ISDIR(st.st_mode)) return "is a directory";
  if (!S_ISREG(st.st_mode)) return std::string("is not a regular file (") + kind(st.st_mode) + ")";
  if (static_cast<std::uintmax_t>(st.st_size) > kMaxInputBytes)
    return "is larger than " + std::to_string(kMaxInputBytes >> 20) + " MiB (" +
           std::to_string(st.st_size) + " bytes)";
  return "";
}

struct Fd {
  int fd = -1;
  ~Fd() {
    if (fd >= 0) ::close(fd);
  }
};

// The process's umask, read without changing it (umask() would race with other threads).
mode_t current_umask() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("Umask:", 0) == 0)
      return static_cast<mode_t>(std::stoul(line.substr(6), nullptr, 8));
  return 022;
}

}  // namespace

// Not in the anonymous namespace: AtomicFile::Impl (external linkage) holds one, which gcc
// refuses (-Wsubobject-linkage) where this file is compiled inside the library's unity unit.
namespace files_detail {

// A stream buffer over a file descriptor; the first failed write keeps its errno.
class FdBuf : public std::streambuf {
 public:
  explicit FdBuf(int fd) : fd_(fd), buffer_(1 << 16) {
    setp(buffer_.data(), buffer_.data() + buffer_.size());
  }
  int error() const { return error_; }

 protected:
  int_type overflow(int_type c) override {
    if (!drain()) return traits_type::eof();
    if (!traits_type::eq_int_type(c, traits_type::eof())) {
      *pptr() = traits_type::to_char_type(c);
      pbump(1);
    }
    return traits_type::not_eof(c);
  }
  int sync() override { return drain() ? 0 : -1; }

 private:
  bool drain() {
    const char* p = pbase();
    while (error_ == 0 && p < pptr()) {
      const ssize_t n = ::write(fd_, p, static_cast<size_t>(pptr() - p));
      if (n < 0 && errno != EINTR) error_ = errno;
      if (n == 0) error_ = EIO;  // not for a regular file; never loop on it
      if (n > 0) p += n;
    }
    setp(buffer_.data(), buffer_.data() + buffer_.size());
    return error_ == 0;
  }

  int fd_;
  std::vector<char> buffer_;
  int error_ = 0;
};

}  // namespace files_detail

std::string read_input_file(const fs::path& path, const char* what) {
  auto fail = [&](const std::string& why) { throw InputError(path.string() + ": " + why); };
  auto cannot_open = [&] {
    const int err = errno;
    fail(std::string("cannot open ") + what + ": " + std::strerror(err));
  };
  // stat first so that a FIFO or device is refused without opening it; the descriptor is
  // checked again in case the path changed in between.
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) cannot_open();
  if (const std::string why = refusal(st); !why.empty()) fail(why);
  Fd f{::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC)};
  if (f.fd < 0) cannot_open();
  if (::fstat(f.fd, &st) != 0) cannot_open();
  if (const std::string why = refusal(st); !why.empty()) fail(why);
  std::string bytes;
  bytes.reserve(static_cast<size_t>(st.st_size));
  char chunk[1 << 16];
  for (;;) {
    const ssize_t n = ::read(f.fd, chunk, sizeof chunk);
    if (n == 0) break;
    if (n < 0) {
      if (errno == EINTR) continue;
      fail(std::string("cannot read ") + what + ": " + std::strerror(errno));
    }
    bytes.append(chunk, static_cast<size_t>(n));
    if (bytes.size() > kMaxInputBytes)  // grew while being read
      fail("is larger than " + std::to_string(kMaxInputBytes >> 20) + " MiB");
  }
  // gzip's magic (RFC 1952): featherdrive reads no compressed files (no zlib), so say what it is
  // rather than fail on its bytes later.
  if (bytes.size() >= 2 && bytes[0] == '\x1f' && bytes[1] == '\x8b')
    fail("is gzip-compressed: decompress it first (gunzip -k " + path.string() + ")");
  return bytes;
}

FileIdentity file_identity(const fs::path& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0) return {st.st_dev, st.st_ino, ""};
  const fs::path dir = path.has_parent_path() ? path.parent_path() : ".";
  if (::stat(dir.c_str(), &st) == 0) return {st.st_dev, st.st_ino, path.filename().string()};
  // Neither exists yet (outputs make their folders): the spelled-out path is all there is.
  std::error_code ec;
  return {0, 0, fs::weakly_canonical(fs::absolute(path, ec), ec).string()};
}

void check_replaceable(const fs::path& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode))
    throw std::invalid_argument(path.string() + ": is not a regular file; refusing to replace it");
}

struct AtomicFile::Impl {
  fs::path target, temp;
  std::string what;
  int fd = -1;
  std::unique_ptr<files_detail::FdBuf> buf;
  std::unique_ptr<std::ostream> stream;
  bool committed = false;

  [[noreturn]] void fail(const char* step, int err) {
    if (fd >= 0) ::close(fd);
    fd = -1;
    ::unlink(temp.c_str());
    committed = true;  // nothing left for the destructor
    throw std::runtime_error(target.string() + ": cannot write " + what + " (" + step +
                             "): " + std::strerror(err));
  }
};

AtomicFile::AtomicFile(const fs::path& target, const std::string& what)
    : impl_(std::make_unique<Impl>()) {
  check_replaceable(target);
  Impl& m = *impl_;
  m.what = what;
  m.target = target;
  std::error_code ec;
  if (fs::is_symlink(target, ec) && fs::exists(target, ec)) m.target = fs::canonical(target, ec);
  if (ec) m.target = target;
  const fs::path dir = m.target.has_parent_path() ? m.target.parent_path() : ".";
  std::string name = (dir / ("." + m.target.filename().string() + ".XXXXXX")).string();
  m.fd = ::mkstemp(name.data());
  if (m.fd < 0)
    throw std::runtime_error(target.string() + ": cannot write " + what + ": " +
                             std::strerror(errno));
  m.temp = name;
  struct stat st {};
  const mode_t mode =
      ::stat(m.target.c_str(), &st) == 0 ? (st.st_mode & 07777) : (0666 & ~current_umask());
  (void)::fchmod(m.fd, mode);
  m.buf = std::make_unique<files_detail::FdBuf>(m.fd);
  m.stream = std::make_unique<std::ostream>(m.buf.get());
}

AtomicFile::~AtomicFile() {
  if (impl_->committed) return;
  if (impl_->fd >= 0) ::close(impl_->fd);
  ::unlink(impl_->temp.c_str());
}

std::ostream& AtomicFile::stream() { return *impl_->stream; }
const fs::path& AtomicFile::temp_path() const { return impl_->temp; }
const fs::path& AtomicFile::target() const { return impl_->target; }

void AtomicFile::commit() {
  Impl& m = *impl_;
  m.stream->flush();
  if (m.buf->error() != 0) m.fail("write", m.buf->error());
  if (!*m.stream) m.fail("write", EIO);
  if (::fsync(m.fd) != 0) m.fail("fsync", errno);
  const int fd = m.fd;
  m.fd = -1;
  if (::close(fd) != 0) m.fail("close", errno);
  if (std::rename(m.temp.c_str(), m.target.c_str()) != 0) m.fail("rename", errno);
  m.committed = true;
  // The rename itself reaches the disk with an fsync of the folder (best effort).
  const fs::path dir = m.target.has_parent_path() ? m.target.parent_path() : ".";
  Fd d{::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC)};
  if (d.fd >= 0) (void)::fsync(d.fd);
}

}  // namespace featherdrive
