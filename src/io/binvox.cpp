// voxfx — binvox reader and writer.
//
// Format: Patrick Min's binvox (https://www.patrickmin.com/binvox/binvox.html, layout by Michael
// Kazhdan). ASCII header "#binvox 1", "dim", "translate", "scale", "data\n", then (value, count)
// byte pairs, count 1..255, run-length encoding the voxels in the order
//     index = x * (ny * nz) + z * ny + y        (x slowest, then z, y fastest)
// which is read_binvox.cc's "x * wxh + z * width + y". Voxel (i, j, k) has its centre at
// translate + scale * ((i, j, k) + 0.5) / d for a d^3 grid, so translate is the box corner and
// scale its edge length.
//
// Non-cubic grids (classic readers require dim d d d): "dim" lists the counts in data order,
// slowest first (nx nz ny), which is what read_binvox.cc ("depth height width" with
// y < width, z < height) and binvox-rw-py (reshape(dims) in x, z, y order) decode. The single
// scale is the longest box extent and cells are taken as cubes of scale / max(nx, ny, nz), so
// a grid with non-cubic cells reads back with cubic cells (the voxels survive, the box does not).
#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <string_view>
#include <vector>

#include "core/bitops.hpp"
#include "io/grid_formats.hpp"
#include "voxfx/parallel.hpp"

namespace voxfx::detail {

namespace {

void writeBinvoxHeader(const Frame& frame, const Vec3i& n, std::ostream& out) {
    const Box3d& box = frame.box();
    const Vec3d ext = box.extent();
    const double scale = std::max({ext.x, ext.y, ext.z});
    out << "#binvox 1\n"
        << "dim " << n.x << ' ' << n.z << ' ' << n.y << '\n'
        << "translate " << formatDouble(box.lo.x) << ' ' << formatDouble(box.lo.y) << ' '
        << formatDouble(box.lo.z) << '\n'
        << "scale " << formatDouble(scale) << '\n'
        << "data\n";
}

// The (value, count) pairs of binvox's data, from columns of y bits in binvox's order; a run
// carries over from one call of `columns` to the next.
class BinvoxRuns {
public:
    explicit BinvoxRuns(std::ostream& out) : out_(out) { buf_.reserve(size_t(1) << 20); }

    // Sliced along y, columns run along (z, x): column c = x * nz + z holds the bits of y, so
    // walking the columns in memory order walks binvox's order and runs come straight from words.
    void columns(const BitGrid& ySliced) {
        const int64_t columns = ySliced.columnCount(), wpc = ySliced.wordsPerColumn(), ny = ySliced.depth();
        for (int64_t c = 0; c < columns; ++c) {
            const uint64_t* col = ySliced.column(c);
            for (int64_t w = 0; w < wpc; ++w) {
                const int bits = int(std::min<int64_t>(64, ny - 64 * w));
                const uint64_t word = col[w];
                int pos = 0;
                while (pos < bits) {
                    // Length of the run of `value` starting at bit pos (capped at the valid bits).
                    const uint64_t rest = word >> pos;
                    const int len =
                        std::min(value_ ? std::countr_one(rest) : std::countr_zero(rest), bits - pos);
                    run_ += len;
                    pos += len;
                    if (pos < bits) {
                        emit(value_, run_);
                        value_ ^= 1;
                        run_ = 0;
                    }
                }
            }
        }
    }

    void finish() {
        emit(value_, run_);
        out_.write(reinterpret_cast<const char*>(buf_.data()), std::streamsize(buf_.size()));
        buf_.clear();
    }

private:
    void emit(uint8_t value, int64_t count) {
        for (; count > 0; count -= 255) {
            buf_.push_back(value);
            buf_.push_back(uint8_t(std::min<int64_t>(count, 255)));
            if (buf_.size() == buf_.capacity()) {
                out_.write(reinterpret_cast<const char*>(buf_.data()), std::streamsize(buf_.size()));
                buf_.clear();
            }
        }
    }
    std::ostream& out_;
    std::vector<uint8_t> buf_;
    uint8_t value_ = 0;
    int64_t run_ = 0;
};

} // namespace

namespace {

// The runs of one chunk of binvox's data: the first run and the last stay open (a neighbouring
// chunk may continue them), the runs between are encoded already.
struct RunChunk {
    std::vector<uint8_t> middle; ///< (value, count) pairs of the closed runs after the first
    uint8_t headValue = 0, tailValue = 0;
    int64_t headLength = 0, tailLength = 0;
    bool split = false; ///< more than one run (head and tail differ); else only the tail is set
};

void appendPairs(std::vector<uint8_t>& bytes, uint8_t value, int64_t count) {
    for (; count > 0; count -= 255) {
        bytes.push_back(value);
        bytes.push_back(uint8_t(std::min<int64_t>(count, 255)));
    }
}

// Runs from words of bits, in order, into a RunChunk.
class ChunkEncoder {
public:
    explicit ChunkEncoder(RunChunk& chunk) : c_(chunk) {}
    // The low `bits` bits of `word`, bit 0 first.
    void add(uint64_t word, int bits) {
        if (!started_) {
            value_ = uint8_t(word & 1);
            started_ = true;
        }
        // Whole words of the current value extend the run (most words of a solid grid).
        if (bits == 64 && word == (value_ ? ~uint64_t(0) : 0)) {
            run_ += 64;
            return;
        }
        for (int pos = 0; pos < bits;) {
            const uint64_t rest = word >> pos;
            const int len = std::min(value_ ? std::countr_one(rest) : std::countr_zero(rest), bits - pos);
            run_ += len;
            pos += len;
            if (pos < bits) {
                close();
                value_ ^= 1;
                run_ = 0;
            }
        }
    }
    void finish() {
        c_.tailValue = value_;
        c_.tailLength = run_;
    }

private:
    void close() {
        if (!c_.split) {
            c_.split = true;
            c_.headValue = value_;
            c_.headLength = run_;
        } else {
            appendPairs(c_.middle, value_, run_);
        }
    }
    RunChunk& c_;
    uint8_t value_ = 0;
    int64_t run_ = 0;
    bool started_ = false;
};

// binvox's data straight from a z-sliced grid (columns (x, y), bits along z): for each x, 64 x 64
// bit blocks of (y, z) are transposed so that each word holds 64 consecutive y of one z, binvox's
// fastest index; chunks of x are encoded in parallel and their runs joined in order, so the bytes
// are those of one serial pass (maximal runs, each split into counts of 255 from its start).
void writeBinvoxZ(const BitGrid& bits, std::ostream& out) {
    const int64_t nx = bits.width(), ny = bits.height(), nz = bits.depth(), wpc = bits.wordsPerColumn();
    const int64_t yBlocks = (ny + 63) / 64;
    constexpr int64_t kSlicesPerChunk = 4;
    const int64_t chunks = (nx + kSlicesPerChunk - 1) / kSlicesPerChunk;
    std::vector<RunChunk> encoded(static_cast<size_t>(chunks));
    parallelFor(0, nx, kSlicesPerChunk, [&](int64_t x0, int64_t x1) {
        const int64_t xs = x1 - x0;
        RunChunk& chunk = encoded[size_t(x0 / kSlicesPerChunk)];
        ChunkEncoder enc(chunk);
        // The chunk's columns of one row are consecutive in memory: each row of a block of 64 rows
        // is read once, whole, into blocks[(xi * wpc + w) * 64 + j] (x0 + xi, row j, word w).
        std::vector<uint64_t> blocks(size_t(xs * wpc * 64));
        // zy[(xi * wpc * 64 + z) * yBlocks + b]: bits y = 64 b .. 64 b + 63 of slice z at x0 + xi.
        std::vector<uint64_t> zy(size_t(xs * wpc * 64 * yBlocks));
        for (int64_t b = 0; b < yBlocks; ++b) {
            const int64_t rows = std::min<int64_t>(64, ny - 64 * b);
            for (int64_t j = 0; j < 64; ++j) {
                const uint64_t* row = j < rows ? bits.column((64 * b + j) * nx + x0) : nullptr;
                for (int64_t i = 0; i < xs * wpc; ++i) blocks[size_t(i * 64 + j)] = row ? row[i] : 0;
            }
            for (int64_t i = 0; i < xs * wpc; ++i) {
                uint64_t* block = &blocks[size_t(i * 64)];
                uint64_t any = 0;
                for (int k = 0; k < 64; ++k) any |= block[k];
                if (any != 0) transpose64(block);
                // i = xi * wpc + w: slices z = 64 w + k of x0 + xi start at row i * 64 of zy.
                uint64_t* dst = &zy[size_t(i * 64 * yBlocks + b)];
                for (int k = 0; k < 64; ++k) dst[k * yBlocks] = block[k];
            }
        }
        for (int64_t xi = 0; xi < xs; ++xi)
            for (int64_t z = 0; z < nz; ++z)
                for (int64_t b = 0; b < yBlocks; ++b)
                    enc.add(zy[size_t((xi * wpc * 64 + z) * yBlocks + b)],
                            int(std::min<int64_t>(64, ny - 64 * b)));
        enc.finish();
    });
    // Join the chunks: a chunk's head continues the run carried from before when the values match.
    std::vector<uint8_t> pairs;
    uint8_t value = 0;
    int64_t run = 0;
    auto carry = [&](uint8_t v, int64_t length) {
        if (v == value) {
            run += length;
            return;
        }
        appendPairs(pairs, value, run);
        value = v;
        run = length;
    };
    for (const RunChunk& c : encoded) {
        if (c.split) {
            carry(c.headValue, c.headLength);
            appendPairs(pairs, value, run);
            out.write(reinterpret_cast<const char*>(pairs.data()), std::streamsize(pairs.size()));
            pairs.clear();
            out.write(reinterpret_cast<const char*>(c.middle.data()), std::streamsize(c.middle.size()));
            value = c.tailValue;
            run = c.tailLength;
        } else {
            carry(c.tailValue, c.tailLength);
        }
    }
    appendPairs(pairs, value, run);
    out.write(reinterpret_cast<const char*>(pairs.data()), std::streamsize(pairs.size()));
}

} // namespace

void writeBinvox(const VoxelGrid& grid, std::ostream& out) {
    writeBinvoxHeader(grid.frame, grid.worldDims(), out);
    if (grid.frame.axis() == Axis::Z && grid.frame.slicing() == Slicing::Uniform &&
        !grid.frame.isPerspective() && !grid.frame.isOriented()) {
        writeBinvoxZ(grid.bits, out);
        return;
    }
    BinvoxRuns runs(out);
    runs.columns(reslice(grid, Axis::Y).bits);
    runs.finish();
}

void writeBinvoxSlabs(const Frame& frame, const Vec3i& n, int64_t slab,
                      const std::function<VoxelGrid(int64_t, int64_t)>& cells, std::ostream& out) {
    writeBinvoxHeader(frame, n, out);
    BinvoxRuns runs(out);
    for (int64_t x0 = 0; x0 < n.x; x0 += slab) {
        const VoxelGrid g = cells(x0, std::min(n.x, x0 + slab));
        runs.columns(g.frame.axis() == Axis::Y ? g.bits : reslice(g, Axis::Y).bits);
    }
    runs.finish();
}

namespace {
// Whitespace-separated header tokens, bounded by the header size limit.
class HeaderReader {
public:
    HeaderReader(std::span<const uint8_t> bytes, size_t limit)
        : bytes_(bytes), end_(std::min(limit, bytes.size())) {}

    std::string_view token() {
        while (pos_ < end_ && isSpace(bytes_[pos_])) ++pos_;
        const size_t b = pos_;
        while (pos_ < end_ && !isSpace(bytes_[pos_])) ++pos_;
        if (pos_ == end_ && end_ < bytes_.size()) fail("binvox header is longer than ", end_, " bytes");
        return {reinterpret_cast<const char*>(bytes_.data()) + b, pos_ - b};
    }
    template <class T> T number(const char* what) {
        const std::string_view t = token();
        T v{};
        const auto r = std::from_chars(t.data(), t.data() + t.size(), v);
        if (t.empty() || r.ec != std::errc() || r.ptr != t.data() + t.size())
            fail("binvox header: bad ", what, " '", t, "'");
        return v;
    }
    void skipLine() {
        while (pos_ < end_ && bytes_[pos_] != '\n') ++pos_;
    }
    size_t position() const { return pos_; }
    bool atEnd() const { return pos_ >= bytes_.size(); }

private:
    static bool isSpace(uint8_t c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }
    std::span<const uint8_t> bytes_;
    size_t end_;
    size_t pos_ = 0;
};

constexpr size_t kMaxHeaderBytes = 4096;
constexpr int64_t kMaxDim = int64_t(1) << 20;
} // namespace

VoxelGrid readBinvox(std::span<const uint8_t> bytes) {
    HeaderReader h(bytes, kMaxHeaderBytes);
    if (h.token() != "#binvox") fail("not a binvox file (it does not start with '#binvox')");
    const int version = h.number<int>("version");
    if (version != 1 && version != 2) fail("unsupported binvox version ", version, " (supported: 1, 2)");
    int64_t dim[3] = {0, 0, 0};
    Vec3d translate{0, 0, 0};
    double scale = 1;
    bool haveDim = false;
    for (;;) {
        const std::string_view key = h.token();
        if (key.empty()) fail("binvox header ends without a 'data' line");
        if (key == "data") break;
        if (key == "dim") {
            for (int64_t& d : dim) {
                d = h.number<int64_t>("dim");
                if (d <= 0 || d > kMaxDim) fail("binvox dim ", d, " out of range [1, ", kMaxDim, "]");
            }
            haveDim = true;
        } else if (key == "translate") {
            translate.x = h.number<double>("translate");
            translate.y = h.number<double>("translate");
            translate.z = h.number<double>("translate");
            if (!isFinite(translate)) fail("binvox translate is not finite");
        } else if (key == "scale") {
            scale = h.number<double>("scale");
            if (!(std::isfinite(scale) && scale > 0))
                fail("binvox scale ", scale, " is not positive and finite");
        } else {
            h.skipLine(); // unknown keywords are skipped, as read_binvox.cc does
        }
    }
    if (!haveDim) fail("binvox header has no 'dim' line");
    // Exactly one linefeed separates "data" from the voxel bytes.
    size_t p = h.position();
    if (p >= bytes.size() || bytes[p] != '\n') fail("binvox 'data' is not followed by a linefeed");
    ++p;

    const int64_t nx = dim[0], nz = dim[1], ny = dim[2];
    // Each pair encodes at most 255 voxels: reject short data before allocating the grid.
    const int64_t total = nx * ny * nz;
    if (uint64_t(bytes.size() - p) < 2 * uint64_t((total + 254) / 255))
        fail("binvox data is truncated: ", bytes.size() - p, " bytes cannot encode ", total, " voxels");
    const double cell = scale / double(std::max({nx, ny, nz}));
    const Box3d box{translate, translate + Vec3d(double(nx), double(ny), double(nz)) * cell};
    // Sliced along y: column (x' = z, y' = x) = x * nz + z holds y, as binvox orders the data.
    VoxelGrid g{Frame::orthographic(box, Axis::Y, nz, nx, ny), BitGrid(nz, nx, ny)};
    const int64_t wpc = g.bits.wordsPerColumn();
    uint64_t* words = g.bits.words();
    int64_t index = 0;
    for (; index < total && p + 1 < bytes.size(); p += 2) {
        const uint8_t value = bytes[p];
        int64_t count = bytes[p + 1];
        if (count > total - index)
            fail("binvox run-length data overruns the ", total, " voxels (run of ", count, " at voxel ",
                 index, ")");
        if (value) {
            // Set the run, splitting it where it crosses columns.
            for (int64_t i = index, left = count; left > 0;) {
                const int64_t c = i / ny, y = i % ny, n = std::min(left, ny - y);
                uint64_t* col = words + c * wpc;
                for (int64_t b = y; b < y + n;) {
                    const int64_t w = b >> 6, lo = b & 63, hi = std::min<int64_t>(64, lo + (y + n - b));
                    col[w] |= bitRange(int(lo), int(hi));
                    b += hi - lo;
                }
                i += n;
                left -= n;
            }
        }
        index += count;
    }
    if (index < total) fail("binvox data is truncated: it ends after ", index, " of ", total, " voxels");
    if (p < bytes.size())
        fail("binvox data overruns the ", total, " voxels (", bytes.size() - p,
             " bytes after the last voxel)");
    return reslice(g, Axis::Z);
}

} // namespace voxfx::detail
