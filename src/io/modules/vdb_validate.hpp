// voxfx_vdb — checks a .vdb file's bytes before OpenVDB reads them (io/modules/vdb_read.cpp).
//
// OpenVDB trusts the counts and sizes in a file: a corrupt one makes it allocate what a field
// says (hundreds of GB), load bytes that are not 0 or 1 as bool, overflow int32 coordinates, and
// leak the nodes it was building when a read fails inside the tree topology (RootNode and
// InternalNode::readTopology allocate a child with new before reading it). This walker follows the
// stream layout that OpenVDB 10's io::Stream reads for the grids voxfx uses, and refuses a file
// before OpenVDB sees it when anything is out of place:
//
//   header       magic, file format 222..224, library version, offsets flag, 36-character UUID
//   metadata     file and grid metadata: counts and string, type and value sizes against the bytes
//                left; fixed-size types must have their size; "__delayedload" counts bounded
//   descriptors  grid count against the bytes left; grid type Tree_{bool,float,double}_5_4_3
//                (float/double optionally _HalfFloat); no instancing; the grid, block and end
//                offsets, when written, equal the positions walked
//   grid         compression flags (zip, active mask, blosc), transform map type and its size
//   topology     root tiles and children (aligned, distinct origins, bool bytes 0 or 1), internal
//                nodes' masks and compressed values (per-node metadata 0..6, inactive values,
//                selection mask, zip/blosc chunk sizes against the bytes left and against what
//                they must inflate to; topology chunks are inflated here, so a corrupt chunk
//                cannot throw inside OpenVDB's topology reading, where it would leak)
//   buffers      per leaf, in the order OpenVDB reads them: masks, bool leaf origins equal to
//                the topology's, value chunks' sizes (not inflated: a corrupt leaf chunk throws
//                in readBuffers, whose nodes the grid already owns, so nothing leaks)
//
// What it cannot check without decoding every voxel twice is the content of leaf value chunks
// (their sizes are checked); see the README's "Untrusted input".
#pragma once

#include <algorithm>
#include <bit>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

#include <blosc.h>
#include <zlib.h>

#include "voxfx/error.hpp"

namespace voxfx::detail::vdbcheck {

static_assert(std::endian::native == std::endian::little,
              "the walker reads node masks as little-endian words");

enum : uint32_t { kZip = 1, kActiveMask = 2, kBlosc = 4 };

class Walker {
public:
    explicit Walker(std::string_view bytes) : b_(bytes) {}

    /// Offsets of the "__delayedload" metadata type names found by walkFile().
    const std::vector<uint64_t>& delayedLoadTypes() const { return delayedLoad_; }

    void walkFile() {
        header();
        metadata("file metadata");
        const int32_t grids = get<int32_t>("the grid count");
        // A grid descriptor takes at least three length fields and three offsets (36 bytes).
        if (grids < 0 || uint64_t(grids) > left() / 36)
            bad("the grid count ", grids, " is negative or more than the ", left(), " bytes left can hold");
        for (int32_t g = 0; g < grids; ++g) grid(g);
    }

private:
    // ---- primitive reads ------------------------------------------------------------------
    template <class... A> [[noreturn]] void bad(const A&... args) const {
        fail("not a valid .vdb file for voxfx (byte ", pos_, "): ", args...);
    }
    uint64_t left() const { return b_.size() - pos_; }
    void need(uint64_t n, const char* what) const {
        if (n > left()) bad(what, " needs ", n, " bytes, but only ", left(), " remain (truncated?)");
    }
    template <class T> T get(const char* what) {
        need(sizeof(T), what);
        T v;
        std::memcpy(&v, b_.data() + pos_, sizeof(T));
        pos_ += sizeof(T);
        return v;
    }
    void skip(uint64_t n, const char* what) {
        need(n, what);
        pos_ += n;
    }
    std::string_view string(const char* what) {
        const uint32_t n = get<uint32_t>(what);
        need(n, what);
        const std::string_view s = b_.substr(pos_, n);
        pos_ += n;
        return s;
    }
    void boolByte(const char* what) {
        need(1, what);
        const auto v = uint8_t(b_[pos_]);
        if (v > 1) bad(what, " is ", int(v), ", not a bool (0 or 1)");
        ++pos_;
    }

    // ---- structure --------------------------------------------------------------------------
    void header() {
        if (get<int64_t>("the magic number") != 0x56444220) bad("no OpenVDB magic number");
        version_ = get<uint32_t>("the file format version");
        // 222: node mask compression (OpenVDB 3, 2014); earlier layouts are not walked.
        if (version_ < 222 || version_ > 224)
            bad("file format version ", version_, " is not supported (222 to 224: OpenVDB 3 to 10)");
        skip(8, "the library version");
        const auto offsets = uint8_t(get<char>("the grid offsets flag"));
        if (offsets > 1) bad("the grid offsets flag is ", int(offsets));
        hasOffsets_ = offsets == 1;
        need(36, "the UUID");
        for (int i = 0; i < 36; ++i) {
            const char c = b_[pos_ + std::size_t(i)];
            const bool dash = i == 8 || i == 13 || i == 18 || i == 23;
            const bool hex = (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f') || (c >= 'A' && c <= 'F');
            if (dash ? c != '-' : !hex) bad("the UUID is malformed");
        }
        pos_ += 36;
    }

    static int64_t fixedMetadataSize(std::string_view type) {
        static constexpr std::pair<std::string_view, int64_t> kSizes[] = {
            {"bool", 1},   {"int32", 4},  {"int64", 8},  {"float", 4},  {"double", 8}, {"vec2i", 8},
            {"vec2s", 8},  {"vec2d", 16}, {"vec3i", 12}, {"vec3s", 12}, {"vec3d", 24}, {"vec4i", 16},
            {"vec4s", 16}, {"vec4d", 32}, {"mat4s", 64}, {"mat4d", 128}};
        for (const auto& [name, size] : kSizes)
            if (name == type) return size;
        return -1;
    }

    void metadata(const char* what) {
        const uint32_t count = get<uint32_t>(what);
        // Each item: name length, type length, value size (12 bytes at least).
        if (count > left() / 12) bad(what, ": ", count, " items cannot fit in the ", left(), " bytes left");
        for (uint32_t i = 0; i < count; ++i) {
            string("a metadata name");
            const std::string_view type = string("a metadata type");
            const uint32_t size = get<uint32_t>("a metadata value size");
            need(size, "a metadata value");
            const int64_t fixed = fixedMetadataSize(type);
            if (fixed >= 0 && int64_t(size) != fixed)
                bad("metadata of type ", type, " has ", size, " bytes instead of ", fixed);
            // OpenVDB's delayed-load table (written with zip compression) sizes its arrays from
            // fields of its own, and serves only delayed loading, which voxfx does not use: its
            // type is renamed for OpenVDB to skip it as unknown "__" metadata (see neutralize).
            if (type == "__delayedload") delayedLoad_.push_back(pos_ - 4 - type.size());
            if (type == "bool" && uint8_t(b_[pos_]) > 1) bad("bool metadata is not 0 or 1");
            pos_ += size;
        }
    }

    void grid(int32_t g) {
        string("a grid name");
        std::string_view type = string("a grid type");
        half_ = type.ends_with("_HalfFloat");
        if (half_) type.remove_suffix(10);
        if (type == "Tree_bool_5_4_3" && !half_)
            valueBytes_ = 1, isBool_ = true;
        else if (type == "Tree_float_5_4_3")
            valueBytes_ = 4, isBool_ = false;
        else if (type == "Tree_double_5_4_3")
            valueBytes_ = 8, isBool_ = false;
        else
            bad("grid ", g, " has type '", type.substr(0, 64), half_ ? "_HalfFloat" : "",
                "'; voxfx reads files whose grids are all bool, float or double trees (5_4_3)");
        chunkValueBytes_ = half_ ? 2 : valueBytes_;
        if (!string("the instance parent").empty()) bad("grid ", g, " is an instance of another grid");
        const auto gridPos = get<int64_t>("the grid offset"), blockPos = get<int64_t>("the block offset"),
                   endPos = get<int64_t>("the end offset");
        if (hasOffsets_ && (gridPos != int64_t(pos_) || blockPos < gridPos || endPos < blockPos ||
                            uint64_t(endPos) > b_.size()))
            bad("grid ", g, "'s offsets (", gridPos, ", ", blockPos, ", ", endPos,
                ") do not match the file's layout (", b_.size(), " bytes)");

        compression_ = get<uint32_t>("the grid compression flags");
        if (compression_ & ~uint32_t(kZip | kActiveMask | kBlosc))
            bad("unknown compression flags ", compression_);
        metadata("grid metadata");
        transform();
        leaves_.clear();
        topology();
        if (hasOffsets_ && int64_t(pos_) != blockPos)
            bad("grid ", g, "'s topology ends at byte ", pos_, ", its block offset says ", blockPos);
        buffers();
        if (hasOffsets_ && int64_t(pos_) != endPos)
            bad("grid ", g, "'s data ends at byte ", pos_, ", its end offset says ", endPos);
    }

    void transform() {
        const std::string_view map = string("the transform's map type");
        static constexpr std::pair<std::string_view, uint64_t> kMaps[] = {{"AffineMap", 128},
                                                                          {"UnitaryMap", 128},
                                                                          {"ScaleMap", 120},
                                                                          {"UniformScaleMap", 120},
                                                                          {"TranslationMap", 24},
                                                                          {"ScaleTranslateMap", 144},
                                                                          {"UniformScaleTranslateMap", 144}};
        for (const auto& [name, size] : kMaps)
            if (name == map) return skip(size, "the transform");
        bad("transform map '", map.substr(0, 64), "' is not an affine map voxfx reads");
    }

    // ---- tree -----------------------------------------------------------------------------
    struct Coord {
        int32_t x, y, z;
        auto operator<=>(const Coord&) const = default;
    };

    void topology() {
        if (get<int32_t>("the tree's buffer count") != 1) bad("the tree's buffer count is not 1");
        if (isBool_)
            boolByte("the background");
        else
            skip(valueBytes_, "the background");
        const uint32_t tiles = get<uint32_t>("the root tile count");
        const uint32_t children = get<uint32_t>("the root child count");
        // A tile: origin + value + active byte; a child: origin + two 4096-byte masks at least.
        if (tiles > left() / (13 + valueBytes_) || children > left() / (12 + 8192))
            bad("the root declares ", tiles, " tiles and ", children, " children, more than the ", left(),
                " bytes left can hold");
        std::vector<Coord> keys;
        keys.reserve(std::size_t(tiles) + children);
        auto origin = [&](const char* what) {
            Coord c{get<int32_t>(what), get<int32_t>(what), get<int32_t>(what)};
            // Root entries sit on a 4096-voxel lattice: aligned, c + 4095 cannot overflow int32.
            if ((c.x | c.y | c.z) & 4095)
                bad(what, " (", c.x, ", ", c.y, ", ", c.z, ") is not aligned to 4096");
            return c;
        };
        for (uint32_t t = 0; t < tiles; ++t) {
            keys.push_back(origin("a root tile origin"));
            if (isBool_)
                boolByte("a root tile value");
            else
                skip(valueBytes_, "a root tile value");
            boolByte("a root tile's active flag");
        }
        std::vector<std::pair<Coord, std::vector<Coord>>> roots; // child origin -> its leaves, in order
        for (uint32_t c = 0; c < children; ++c) {
            const Coord o = origin("a root child origin");
            keys.push_back(o);
            std::vector<Coord> leaves;
            internal(o, 5, leaves);
            roots.emplace_back(o, std::move(leaves));
        }
        std::sort(keys.begin(), keys.end());
        if (std::adjacent_find(keys.begin(), keys.end()) != keys.end())
            bad("the root holds two entries at one origin");
        // OpenVDB reads buffers in the root's map order (sorted origins).
        std::sort(roots.begin(), roots.end());
        for (auto& r : roots) leaves_.insert(leaves_.end(), r.second.begin(), r.second.end());
    }

    // An internal node of 2^log2 entries per axis (5: 32^3 of 4^3-voxel... children; 4: 16^3 of leaves).
    void internal(const Coord& o, int log2, std::vector<Coord>& leaves) {
        const uint32_t n = uint32_t(1) << (3 * log2);
        const uint32_t maskBytes = n / 8;
        need(2 * uint64_t(maskBytes), "an internal node's masks");
        const std::string_view childMask = b_.substr(pos_, maskBytes);
        const std::string_view valueMask = b_.substr(pos_ + maskBytes, maskBytes);
        pos_ += 2 * maskBytes;
        compressedValues(n, popcount(valueMask), /*inflate=*/true);
        const int childLog2 = log2 == 5 ? 4 : 3; // child total: 4 + 3 = 7 below level 2, 3 below level 1
        const int childTotal = log2 == 5 ? 7 : 3;
        // Children in entry order, a mask word at a time (most of a node's 2^15 entries are empty).
        for (uint32_t w = 0; w < maskBytes / 8; ++w) {
            uint64_t word;
            std::memcpy(&word, childMask.data() + 8 * w, 8);
            for (; word; word &= word - 1)
                child(o, log2, childLog2, childTotal, 64 * w + uint32_t(std::countr_zero(word)), leaves);
        }
    }

    // Entry i of an internal node at `o`: (x << 2 log2) | (y << log2) | z, each scaled by the child's size.
    void child(const Coord& o, int log2, int childLog2, int childTotal, uint32_t i,
               std::vector<Coord>& leaves) {
        const uint32_t x = i >> (2 * log2), y = (i >> log2) & ((1u << log2) - 1), z = i & ((1u << log2) - 1);
        const Coord c{o.x + int32_t(x << childTotal), o.y + int32_t(y << childTotal),
                      o.z + int32_t(z << childTotal)};
        if (log2 == 5) {
            internal(c, childLog2, leaves);
        } else {
            skip(64, "a leaf's value mask");
            leaves.push_back(c);
        }
    }

    static uint32_t popcount(std::string_view mask) { // masks are whole 64-bit words
        uint32_t on = 0;
        for (std::size_t i = 0; i + 8 <= mask.size(); i += 8) {
            uint64_t word;
            std::memcpy(&word, mask.data() + i, 8);
            on += uint32_t(std::popcount(word));
        }
        return on;
    }

    // io::readCompressedValues for `count` values, `active` of them active; `inflate` checks the
    // chunk's content too (bool values 0 or 1).
    void compressedValues(uint32_t count, uint32_t active, bool inflate) {
        const auto meta = uint8_t(get<char>("a node's compression metadata"));
        if (meta > 6) bad("node compression metadata ", int(meta), " is not 0..6");
        if (meta == 2 || meta == 4 || meta == 5) {
            for (int i = meta == 5 ? 2 : 1; i > 0; --i) {
                if (isBool_)
                    boolByte("an inactive value");
                else
                    skip(valueBytes_, "an inactive value");
            }
        }
        if (meta >= 3 && meta <= 5) skip(count / 8, "a selection mask");
        const uint32_t stored = (compression_ & kActiveMask) && meta != 6 ? active : count;
        if (stored == 0 && half_) return; // io::HalfReader reads nothing for no values
        chunk(uint64_t(stored) * chunkValueBytes_, inflate);
    }

    // io::readData: a zip or blosc chunk (int64 size, negative for stored bytes) or raw bytes.
    void chunk(uint64_t bytes, bool inflate) {
        if (!(compression_ & (kZip | kBlosc))) {
            need(bytes, "node values");
            if (inflate && isBool_) checkBools(b_.substr(pos_, bytes));
            pos_ += bytes;
            return;
        }
        const int64_t n = get<int64_t>("a compressed chunk's size");
        if (n <= 0) {
            const uint64_t stored = uint64_t(-(n + 1)) + 1; // -n without overflow at INT64_MIN
            if (stored != bytes) bad("a stored chunk of ", stored, " bytes where ", bytes, " are expected");
            need(bytes, "a stored chunk");
            if (inflate && isBool_) checkBools(b_.substr(pos_, bytes));
            pos_ += bytes;
            return;
        }
        need(uint64_t(n), "a compressed chunk");
        const auto* src = reinterpret_cast<const unsigned char*>(b_.data() + pos_);
        if (compression_ & kBlosc) {
            std::size_t nbytes = 0, cbytes = 0, blocksize = 0;
            if (uint64_t(n) < BLOSC_MIN_HEADER_LENGTH) bad("a blosc chunk of ", n, " bytes");
            blosc_cbuffer_sizes(src, &nbytes, &cbytes, &blocksize);
            if (nbytes != bytes || cbytes != uint64_t(n))
                bad("a blosc chunk holds ", nbytes, " bytes in ", cbytes, " where ", bytes, " in ", n,
                    " are expected");
            if (inflate) {
                std::vector<char> out(bytes + 1);
                if (blosc_decompress_ctx(src, out.data(), out.size(), 1) != int(bytes))
                    bad("a blosc chunk is corrupt");
                if (isBool_) checkBools({out.data(), bytes});
            }
        } else if (inflate) {
            std::vector<char> out(bytes + 1);
            uLongf got = uLongf(out.size());
            if (::uncompress(reinterpret_cast<Bytef*>(out.data()), &got, src, uLong(n)) != Z_OK ||
                got != bytes)
                bad("a zip chunk is corrupt or does not inflate to ", bytes, " bytes");
            if (isBool_) checkBools({out.data(), bytes});
        }
        pos_ += uint64_t(n);
    }

    void checkBools(std::string_view values) const {
        // Eight bytes at a time: any bit but the lowest of a byte set means a byte above 1.
        std::size_t i = 0;
        for (; i + 8 <= values.size(); i += 8) {
            uint64_t word;
            std::memcpy(&word, values.data() + i, 8);
            if (word & ~uint64_t(0x0101010101010101)) break;
        }
        for (; i < values.size(); ++i)
            if (uint8_t(values[i]) > 1) bad("a bool node value is ", int(uint8_t(values[i])), ", not 0 or 1");
    }

    void buffers() {
        for (const Coord& leaf : leaves_) {
            skip(64, "a leaf's value mask");
            if (isBool_) {
                Coord o{get<int32_t>("a leaf origin"), get<int32_t>("a leaf origin"),
                        get<int32_t>("a leaf origin")};
                if (o != leaf)
                    bad("a bool leaf's origin (", o.x, ", ", o.y, ", ", o.z,
                        ") is not its place in the tree (", leaf.x, ", ", leaf.y, ", ", leaf.z, ")");
                skip(64, "a bool leaf's values");
            } else {
                const std::string_view mask = b_.substr(pos_ - 64, 64);
                compressedValues(512, popcount(mask), /*inflate=*/false);
            }
        }
    }

    std::string_view b_;
    uint64_t pos_ = 0;
    uint32_t version_ = 0;
    bool hasOffsets_ = false;
    uint32_t compression_ = 0;
    bool half_ = false, isBool_ = false;
    uint64_t valueBytes_ = 0, chunkValueBytes_ = 0;
    std::vector<Coord> leaves_;
    std::vector<uint64_t> delayedLoad_;
};

/// A byte that OpenVDB must read as another value than the file's.
struct ByteOverride {
    uint64_t at;
    char value;
};

/// Throws voxfx::Error when the bytes are not a .vdb file this walker can vouch for; otherwise
/// returns, by increasing position, the bytes to read differently (the bytes themselves are left
/// alone: the caller's buffer is read-only): the delayed-load metadata type is renamed
/// ("__delayedload" -> "__xelayedload", same length) so that OpenVDB reads past it as unknown
/// metadata instead of trusting the sizes inside it.
inline std::vector<ByteOverride> validate(std::string_view bytes) {
    Walker walker(bytes);
    walker.walkFile();
    std::vector<ByteOverride> overrides;
    for (const uint64_t typeName : walker.delayedLoadTypes()) overrides.push_back({typeName + 2, 'x'});
    std::sort(overrides.begin(), overrides.end(),
              [](const ByteOverride& a, const ByteOverride& b) { return a.at < b.at; });
    return overrides;
}

} // namespace voxfx::detail::vdbcheck
