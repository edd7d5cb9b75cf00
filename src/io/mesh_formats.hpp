// voxfx — internal to io/: the dedicated mesh parsers behind loadMesh and their shared text reader.
//
// Each parser reads a whole file held in memory and returns the mesh in file order (vertices as
// stored, faces fan-triangulated), throwing voxfx::Error with the file name and the line or byte
// offset on malformed or truncated input. Nothing here trusts a count from a header before checking
// it against the bytes that remain.
#pragma once

#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

#include "voxfx/error.hpp"
#include "voxfx/mesh.hpp"

namespace voxfx::detail {

/// Where in a file something was found: a 1-based line for text, a 0-based byte offset for binary.
struct FileLocation {
    enum class Kind : uint8_t { kLine, kByte };
    Kind kind = Kind::kLine;
    uint64_t value = 0;
};

/// "path:12: " for a line, "path: byte 84: " for a byte offset.
std::string locationPrefix(const std::string& path, FileLocation where);

/// What a parser returns: the mesh, plus the vertices with a NaN or infinite coordinate and where
/// they are. Those are only an error when a triangle uses them, which is known at the end.
struct ParsedMesh {
    Mesh mesh;
    std::vector<std::pair<uint32_t, FileLocation>> nonFiniteVertices;
    uint32_t firstVertexNumber = 0; ///< how the format counts vertices in messages (OBJ: 1)
    /// Per-vertex RGB colours (PLY red/green/blue, COFF), one per vertex, or empty.
    std::vector<Vec3f> colors;
};

ParsedMesh parseOff(std::string_view bytes, const std::string& path);
ParsedMesh parseObj(std::string_view bytes, const std::string& path);
ParsedMesh parsePly(std::string_view bytes, const std::string& path);
ParsedMesh parseStl(std::string_view bytes, const std::string& path);

/// Loads any format Assimp reads (glTF 2.0 and the long tail) with node transforms applied.
Mesh loadWithAssimp(const std::string& path);
/// True when Assimp has an importer for the extension (lower case, without the dot).
bool assimpReadsExtension(const std::string& extension);
/// Assimp's extensions as ".a .b .c".
std::string assimpExtensions();

/// Largest vertex count a Mesh can index with 32-bit indices.
inline constexpr uint64_t kMaxVertices = std::numeric_limits<uint32_t>::max();

/// A float from a double, overflowing to +-infinity instead of undefined behaviour.
inline float toFloat(double v) {
    if (std::fabs(v) > double(std::numeric_limits<float>::max()))
        return std::copysign(std::numeric_limits<float>::infinity(), float(v > 0 ? 1 : -1));
    return float(v);
}

/// A forward reader over text with line tracking, for the text formats. Every read checks the
/// end of the buffer; errors name the file and the current line.
class TextReader {
public:
    /// `comment`: the character that starts a comment running to the end of the line, or 0.
    TextReader(std::string_view text, const std::string& path, char comment, uint64_t firstLine = 1)
        : p_(text.data()), end_(text.data() + text.size()), path_(path), line_(firstLine), comment_(comment) {
    }

    bool eof() const { return p_ == end_; }
    uint64_t line() const { return line_; }
    FileLocation location() const { return {FileLocation::Kind::kLine, line_}; }
    const std::string& path() const { return path_; }

    /// Skips blanks (space, tab, carriage return, vertical tab, form feed) and a comment, never the
    /// newline.
    void skipBlanks() {
        // Every space but the newline: word() stops at the same set (isSpace), so a token never
        // starts at a space this leaves (a vertical tab here once made word() read nothing,
        // forever, in a list of 2^31 entries).
        while (p_ != end_ && *p_ != '\n' && isSpace(*p_)) ++p_;
        if (p_ != end_ && *p_ == comment_ && comment_ != 0) {
            const void* nl = std::memchr(p_, '\n', std::size_t(end_ - p_));
            p_ = nl ? static_cast<const char*>(nl) : end_;
        }
    }
    /// True at the end of the line (or file), after blanks and comments.
    bool atLineEnd() {
        skipBlanks();
        return p_ == end_ || *p_ == '\n';
    }
    /// Skips the rest of the current line and its newline.
    void nextLine() {
        const void* nl = std::memchr(p_, '\n', std::size_t(end_ - p_));
        if (nl) {
            p_ = static_cast<const char*>(nl) + 1;
            ++line_;
        } else {
            p_ = end_;
        }
    }
    /// Skips whitespace, newlines and comments up to the next token (or the end of the file).
    void skipSpace() {
        for (;;) {
            skipBlanks();
            if (p_ == end_ || *p_ != '\n') return;
            ++p_;
            ++line_;
        }
    }
    /// The next run of non-blank characters on this line (empty at the end of the line).
    std::string_view word() {
        skipBlanks();
        const char* start = p_;
        while (p_ != end_ && !isSpace(*p_)) ++p_;
        return {start, std::size_t(p_ - start)};
    }
    /// The next word without moving past it.
    std::string_view peekWord() {
        skipBlanks();
        const char* q = p_;
        while (q != end_ && !isSpace(*q)) ++q;
        return {p_, std::size_t(q - p_)};
    }
    /// True when no newline follows: the current line is the file's last, maybe cut short.
    bool onLastLine() const { return std::memchr(p_, '\n', std::size_t(end_ - p_)) == nullptr; }
    /// The current read position (for a caller that switches to binary data).
    const char* position() const { return p_; }
    /// The next character, or 0 at the end of the file.
    char peek() const { return p_ != end_ ? *p_ : '\0'; }
    void advance() {
        if (p_ != end_) ++p_;
    }

    /// Reads a float on the current line; `what` names it in the error ("x of vertex 3").
    template <class... What> float readFloat(const What&... what) {
        skipBlanks();
        const char* s = p_;
        if (s != end_ && *s == '+') ++s; // from_chars takes no leading '+'
        float v = 0;
        auto [ptr, ec] = std::from_chars(s, end_, v);
        if (ec == std::errc::result_out_of_range)
            v = outOfRangeFloat(s, ptr);
        else if (ec != std::errc())
            unexpected(what...);
        if (!endsToken(ptr)) unexpected(what...);
        p_ = ptr;
        return v;
    }
    /// Reads a non-negative integer on the current line.
    template <class... What> uint64_t readUnsigned(const What&... what) {
        skipBlanks();
        uint64_t v = 0;
        auto [ptr, ec] = std::from_chars(p_, end_, v);
        if (ec != std::errc() || !endsToken(ptr)) unexpected(what...);
        p_ = ptr;
        return v;
    }
    /// Reads a signed integer; with `allowSlash` it may be followed by '/' (OBJ's v/vt/vn).
    template <class... What> int64_t readSigned(bool allowSlash, const What&... what) {
        skipBlanks();
        const char* s = p_;
        if (s != end_ && *s == '+') ++s;
        int64_t v = 0;
        auto [ptr, ec] = std::from_chars(s, end_, v);
        if (ec != std::errc() || !(endsToken(ptr) || (allowSlash && *ptr == '/'))) unexpected(what...);
        p_ = ptr;
        return v;
    }

    /// Throws "path:line: message".
    template <class... Args> [[noreturn]] void error(const Args&... args) const {
        fail(path_, ":", line_, ": ", args...);
    }
    /// Throws "expected <what>, found <the next token | end of line | end of file>".
    template <class... What> [[noreturn]] void unexpected(const What&... what) {
        skipBlanks();
        if (p_ == end_) error("expected ", what..., ", found the end of the file (truncated?)");
        if (*p_ == '\n') error("expected ", what..., ", found the end of the line");
        const char* s = p_;
        while (s != end_ && !isSpace(*s) && s - p_ < 40) ++s;
        error("expected ", what..., ", found '", std::string_view(p_, std::size_t(s - p_)), "'",
              s == end_ ? " at the end of the file (truncated?)" : "");
    }

    static bool isSpace(char c) {
        return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f';
    }

private:
    bool endsToken(const char* q) const {
        return q == end_ || isSpace(*q) || (comment_ != 0 && *q == comment_);
    }

    // from_chars leaves the value alone when it does not fit a float: overflow becomes +-inf (then
    // reported as a non-finite coordinate), underflow the nearest float (0 or a subnormal).
    float outOfRangeFloat(const char* s, const char* tokenEnd) const {
        double d = 0;
        auto [ptr, ec] = std::from_chars(s, end_, d);
        if (ec == std::errc() && ptr == tokenEnd) return toFloat(d);
        const bool negative = *s == '-';
        bool tiny = false;
        for (const char* q = s; q != tokenEnd; ++q)
            if ((*q == 'e' || *q == 'E') && q + 1 != tokenEnd && q[1] == '-') tiny = true;
        const float magnitude = tiny ? 0.0f : std::numeric_limits<float>::infinity();
        return negative ? -magnitude : magnitude;
    }

    const char* p_;
    const char* end_;
    const std::string& path_;
    uint64_t line_;
    char comment_;
};

/// Appends the fan (first, previous, current) for the k-th corner of a polygon (k >= 2).
inline void appendFanTriangle(std::vector<uint32_t>& indices, uint32_t first, uint32_t previous,
                              uint32_t current) {
    indices.push_back(first);
    indices.push_back(previous);
    indices.push_back(current);
}

/// Unaligned little- or big-endian load of a trivially copyable value.
template <class T> inline T loadValue(const unsigned char* p, bool bigEndianFile) {
    T v;
    std::memcpy(&v, p, sizeof(T));
    if (bigEndianFile != (std::endian::native == std::endian::big)) {
        unsigned char b[sizeof(T)];
        std::memcpy(b, &v, sizeof(T));
        for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
        std::memcpy(&v, b, sizeof(T));
    }
    return v;
}

} // namespace voxfx::detail
