// voxfx — atomic file output (internal): write a temporary file beside the target, then rename.
//
// Readers of the target see either the old file or the complete new one, never a partial file:
// the temporary lives in the target's directory (same file system, so std::filesystem::rename
// replaces the target atomically on POSIX) and is removed again when the writer fails or is
// destroyed before commit(). No fsync: this protects against our own failures (exceptions,
// full disks, crashes of this process), not against power loss.
#pragma once

#include <filesystem>
#include <fstream>
#include <memory>
#include <vector>

namespace voxfx::detail {

class AtomicFile {
public:
    /// Creates an empty temporary file `.NAME.tmp.<pid>.<counter>` beside `target` (exclusively,
    /// so concurrent writers never share one). Throws voxfx::Error naming the path and the system
    /// error when the directory is missing or not writable, or when `target` is a directory.
    explicit AtomicFile(std::filesystem::path target);
    /// Removes the temporary file unless commit() succeeded.
    ~AtomicFile();
    AtomicFile(const AtomicFile&) = delete;
    AtomicFile& operator=(const AtomicFile&) = delete;

    const std::filesystem::path& targetPath() const { return target_; }
    /// The temporary file, for libraries that insist on opening files by name (OpenVDB).
    const std::filesystem::path& tempPath() const { return temp_; }

    /// Binary output stream on the temporary file (opened on first use, 1 MiB buffer).
    std::ostream& stream();

    /// Flushes and closes the stream, checks that every write succeeded, and renames the
    /// temporary file onto the target. Throws voxfx::Error (naming the target) on any failure;
    /// the temporary file is then removed by the destructor.
    void commit();

private:
    std::filesystem::path target_, temp_;
    static constexpr size_t kBufferBytes = size_t(1) << 20;
    std::unique_ptr<char[]> buffer_;
    std::unique_ptr<std::ofstream> out_;
    bool committed_ = false;
};

} // namespace voxfx::detail
