// Reading inputs and writing outputs without surprises: an input that is not a regular file (a
// directory, a FIFO, /dev/zero) or is too large is refused before a byte is read, and an output
// is written to a temporary file beside its target and renamed over it only when complete, so
// that the target is either untouched or whole and a device or FIFO is never replaced.
#pragma once

#include <sys/types.h>

#include <cstdint>
#include <filesystem>
#include <memory>
#include <ostream>
#include <string>

namespace featherdrive {

/// The largest input file read (scene, URDF, checkpoint): 64 MiB. The URDFs of real robots are
/// below 1 MiB and the checkpoint of a 10 000-dof model about 2 MiB.
inline constexpr std::uintmax_t kMaxInputBytes = std::uintmax_t{64} << 20;

/// The whole of an input file. Throws InputError, one line naming the file, for a file that
/// cannot be opened ("FILE: cannot open WHAT: <reason>"), is a directory ("FILE: is a
/// directory"), is not a regular file ("FILE: is not a regular file (a FIFO)") or is larger than
/// kMaxInputBytes ("FILE: is larger than 64 MiB (N bytes)"). A FIFO is opened without blocking.
std::string read_input_file(const std::filesystem::path& path, const char* what = "the file");

/// What a path names, for "is this output one of the inputs?": the device and inode of the file
/// (through symbolic links), or for a path that does not exist yet, its folder's and its name.
struct FileIdentity {
  dev_t device = 0;
  ino_t inode = 0;
  std::string name;  ///< empty when the file exists
  bool operator==(const FileIdentity&) const = default;
};
FileIdentity file_identity(const std::filesystem::path& path);

/// Throws std::invalid_argument "FILE: is not a regular file; refusing to replace it" when the
/// path exists and is not a regular file (a directory, a FIFO, /dev/null, a device).
void check_replaceable(const std::filesystem::path& path);

/// An output file written in full or not at all: the bytes go to a temporary file made with
/// mkstemp in the target's folder, and commit() renames it over the target (after an fsync).
/// The destructor removes the temporary unless it was committed. A target that is a symbolic
/// link is written where the link points. The file gets the target's permissions when it exists,
/// else 0666 less the umask.
class AtomicFile {
 public:
  /// `what` names the output in messages ("the checkpoint"). Throws std::invalid_argument for a
  /// target that is not a regular file (check_replaceable), std::runtime_error when the
  /// temporary cannot be made.
  explicit AtomicFile(const std::filesystem::path& target, const std::string& what = "the file");
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  /// Writes into the temporary file.
  std::ostream& stream();
  /// The temporary file, for a program that writes the output itself (e.g. a plot script).
  const std::filesystem::path& temp_path() const;
  const std::filesystem::path& target() const;
  /// Flushes, fsyncs and renames the temporary over the target. Throws std::runtime_error
  /// "TARGET: cannot write WHAT (step): reason" and removes the temporary when any step fails.
  void commit();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace featherdrive
