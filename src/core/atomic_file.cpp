#include "core/atomic_file.hpp"

#include <atomic>
#include <cerrno>
#include <cstring>
#include <string>
#include <system_error>

#include <fcntl.h>
#include <unistd.h>

#include "voxfx/error.hpp"

namespace voxfx::detail {

namespace fs = std::filesystem;

namespace {
std::atomic<uint64_t> tempCounter{0};

// errno after a failed stream operation is usually the cause, but the standard does not promise
// it; say so rather than print "Success".
std::string systemReason(int err) { return err ? std::strerror(err) : "unknown I/O error"; }
} // namespace

AtomicFile::AtomicFile(fs::path target) : target_(std::move(target)) {
    std::error_code ec;
    if (fs::is_directory(target_, ec)) fail("cannot write '", target_.string(), "': it is a directory");
    const fs::path dir = target_.has_parent_path() ? target_.parent_path() : fs::path(".");
    const std::string name = target_.filename().string();
    if (name.empty()) fail("cannot write '", target_.string(), "': the path names no file");
    temp_ = dir / ("." + name + ".tmp." + std::to_string(::getpid()) + "." + std::to_string(tempCounter++));
    // O_EXCL: never share (or clobber) a temporary with another writer.
    const int fd = ::open(temp_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd < 0) {
        const int err = errno;
        temp_.clear();
        fail("cannot write '", target_.string(), "': cannot create a temporary file in '", dir.string(),
             "': ", systemReason(err));
    }
    ::close(fd);
}

AtomicFile::~AtomicFile() {
    if (committed_ || temp_.empty()) return;
    out_.reset();
    std::error_code ec;
    fs::remove(temp_, ec);
}

std::ostream& AtomicFile::stream() {
    if (!out_) {
        out_ = std::make_unique<std::ofstream>();
        // Not zero-filled: clearing 1 MiB (and faulting in all of its pages) per file cost more
        // than writing a small grid (batches write thousands of them); only what is written is
        // touched.
        buffer_.reset(new char[kBufferBytes]);
        out_->rdbuf()->pubsetbuf(buffer_.get(), std::streamsize(kBufferBytes));
        errno = 0;
        out_->open(temp_, std::ios::binary | std::ios::trunc);
        if (!*out_) fail("cannot write '", temp_.string(), "': ", systemReason(errno));
    }
    return *out_;
}

void AtomicFile::commit() {
    VOXFX_CHECK(!committed_ && !temp_.empty());
    if (out_) {
        errno = 0;
        out_->flush();
        const bool flushed = bool(*out_);
        const int err = errno;
        out_->close();
        if (!flushed || out_->fail())
            fail("cannot write '", target_.string(), "': ", systemReason(err ? err : errno));
        out_.reset();
    }
    std::error_code ec;
    fs::rename(temp_, target_, ec);
    if (ec) fail("cannot write '", target_.string(), "': renaming the temporary file failed: ", ec.message());
    committed_ = true;
}

} // namespace voxfx::detail
