// voxfx tests — the general shared helper header: temporary folders, environment variables, file
// writing, fetched data, meshes and oracles. What the tests of one family of techniques share lives
// in tests/support/ (shadow_reference.hpp, volume_reference.hpp, glass_scenes.hpp, ground_scenes.hpp).
#pragma once

#include <atomic>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <string_view>

#include <gtest/gtest.h>
#include <unistd.h>

namespace voxfx::test {

/// A fresh folder under the system temp directory, removed with everything in it on destruction.
class TempDir {
public:
    TempDir() {
        static std::atomic<int> counter{0};
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        std::string name = "voxfx-" + std::to_string(::getpid()) + "-" + std::to_string(counter++);
        if (info) name += std::string("-") + info->test_suite_name() + "-" + info->name();
        path_ = std::filesystem::temp_directory_path() / name;
        std::filesystem::remove_all(path_);
        std::filesystem::create_directories(path_);
    }
    ~TempDir() {
        std::error_code ec;
        std::filesystem::remove_all(path_, ec);
    }
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;

    const std::filesystem::path& path() const { return path_; }
    /// Path of `name` inside the folder, as a string.
    std::string file(std::string_view name) const { return (path_ / name).string(); }

private:
    std::filesystem::path path_;
};

/// Sets an environment variable for one scope (the test process's own environment): the old value,
/// or its absence, comes back on destruction.
class ScopedEnv {
public:
    ScopedEnv(const char* name, const std::string& value) : name_(name) {
        if (const char* old = std::getenv(name)) old_ = old, had_ = true;
        ::setenv(name, value.c_str(), 1);
    }
    ~ScopedEnv() {
        if (had_)
            ::setenv(name_, old_.c_str(), 1);
        else
            ::unsetenv(name_);
    }
    ScopedEnv(const ScopedEnv&) = delete;
    ScopedEnv& operator=(const ScopedEnv&) = delete;

private:
    const char* name_;
    std::string old_;
    bool had_ = false;
};

/// The whole file at `path`, byte for byte ("" when it cannot be read).
inline std::string readFileBytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

/// Base64 (RFC 4648, with padding) of `bytes`, for data URIs in hand-written glTF files.
inline std::string base64(std::string_view bytes) {
    static const char* kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    for (std::size_t i = 0; i < bytes.size(); i += 3) {
        uint32_t n = uint32_t(uint8_t(bytes[i])) << 16;
        if (i + 1 < bytes.size()) n |= uint32_t(uint8_t(bytes[i + 1])) << 8;
        if (i + 2 < bytes.size()) n |= uint32_t(uint8_t(bytes[i + 2]));
        out += kAlphabet[(n >> 18) & 63];
        out += kAlphabet[(n >> 12) & 63];
        out += i + 1 < bytes.size() ? kAlphabet[(n >> 6) & 63] : '=';
        out += i + 2 < bytes.size() ? kAlphabet[n & 63] : '=';
    }
    return out;
}

/// The bytes of base64 `text` (up to its padding); a character outside the alphabet is a test
/// failure.
inline std::string unbase64(std::string_view text) {
    static const std::string_view kAlphabet =
        "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    uint32_t acc = 0;
    int bits = 0;
    for (const char c : text) {
        if (c == '=') break;
        const std::size_t v = kAlphabet.find(c);
        if (v == std::string_view::npos) {
            ADD_FAILURE() << "not base64: '" << c << "'";
            return out;
        }
        acc = (acc << 6) | uint32_t(v);
        bits += 6;
        if (bits >= 8) {
            bits -= 8;
            out += char((acc >> bits) & 0xFF);
        }
    }
    return out;
}

/// Writes `bytes` to `path` exactly (binary mode) and returns the path.
inline std::string writeFile(const std::string& path, std::string_view bytes) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    EXPECT_TRUE(out.good()) << "cannot write " << path;
    return path;
}

/// Folder of the fetched data (scripts/fetch-data.sh): $VOXFX_DATA_DIR when set (the fetch script
/// honours the same variable), else the source tree's data/.
inline std::filesystem::path dataDir() {
    const char* env = std::getenv("VOXFX_DATA_DIR");
    return (env && *env) ? std::filesystem::path(env) : std::filesystem::path(VOXFX_DATA_DIR);
}

/// Path of a fetched data file, e.g. dataPath("meshes/bunny00.off").
inline std::string dataPath(std::string_view relative) { return (dataDir() / relative).string(); }

/// Whether a missing data file fails the test instead of skipping it: the environment variable
/// VOXFX_REQUIRE_DATA set to anything but "" or "0" (CI sets it after fetching the data, so a
/// failed fetch cannot pass as a row of skips).
inline bool dataRequired() {
    const char* env = std::getenv("VOXFX_REQUIRE_DATA");
    return env && *env && std::string_view(env) != "0";
}

/// Why the data file (or folder) `relative` cannot be used, or "" when it is there.
inline std::string missingData(std::string_view relative) {
    const std::string path = dataPath(relative);
    if (std::filesystem::exists(path)) return {};
    return "missing test data " + path + " (run scripts/fetch-data.sh" +
           (dataRequired() ? "; VOXFX_REQUIRE_DATA is set, so this is a failure)" : ")");
}

} // namespace voxfx::test

/// Skips the current test, visibly and naming the file and the fetch script, when the fetched
/// data file `relative` (e.g. "meshes/bunny00.off") is missing; fails it instead when
/// VOXFX_REQUIRE_DATA=1. Use at the top level of a TEST body (GTEST_SKIP returns from it).
#define VOXFX_REQUIRE_DATA(relative)                                                                         \
    do {                                                                                                     \
        const std::string voxfxMissing_ = ::voxfx::test::missingData(relative);                              \
        if (!voxfxMissing_.empty()) {                                                                        \
            if (::voxfx::test::dataRequired()) GTEST_FAIL() << voxfxMissing_;                                \
            GTEST_SKIP() << voxfxMissing_;                                                                   \
        }                                                                                                    \
    } while (false)

// ---- Small synthetic meshes (closed, outward counter-clockwise) for edge cases ----------------
#include <cmath>
#include <vector>

#include "voxfx/bitgrid.hpp"
#include "voxfx/mesh.hpp"

namespace voxfx::test {

/// Appends the closed box [lo, hi] (12 triangles, outward CCW) to `mesh`.
inline void appendBox(Mesh& mesh, const Vec3d& lo, const Vec3d& hi) {
    const auto base = uint32_t(mesh.positions.size());
    for (int k = 0; k < 8; ++k)
        mesh.positions.push_back(
            Vec3f(Vec3d{(k & 1) ? hi.x : lo.x, (k & 2) ? hi.y : lo.y, (k & 4) ? hi.z : lo.z}));
    // Corner k has x from bit 0, y from bit 1, z from bit 2.
    static const uint32_t quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                         {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (const auto& q : quads)
        for (const uint32_t t : {q[0], q[1], q[2], q[0], q[2], q[3]}) mesh.indices.push_back(base + t);
}

/// Appends the quad with centre c and half-edge vectors u, v (two triangles, counter-clockwise
/// seen from u x v): leaves, ground planes and walls of the renderer and shadow tests.
inline void appendQuad(Mesh& m, const Vec3d& c, const Vec3d& u, const Vec3d& v) {
    const auto b = uint32_t(m.positions.size());
    for (const Vec3d& p : {c - u - v, c + u - v, c + u + v, c - u + v}) m.positions.push_back(Vec3f(p));
    m.indices.insert(m.indices.end(), {b, b + 1, b + 2, b, b + 2, b + 3});
}

// Every bit of the grid's words beyond slice D - 1 of each column is zero (checked bit by bit,
// not through BitGrid::lastWordMask).
inline bool paddingIsZero(const BitGrid& g) {
    for (int64_t c = 0; c < g.columnCount(); ++c)
        for (int64_t s = g.depth(); s < 64 * g.wordsPerColumn(); ++s)
            if ((g.column(c)[s >> 6] >> (s & 63)) & 1u) return false;
    return true;
}

// The octahedron |x - c.x| + |y - c.y| + |z - c.z| <= r: 6 vertices, 8 faces, outward CCW.
inline Mesh makeOctahedron(const Vec3d& c, double r) {
    Mesh m;
    for (int a = 0; a < 3; ++a)
        for (double s : {r, -r}) {
            Vec3d p = c;
            p[a] += s;
            m.positions.push_back(Vec3f(p));
        }
    for (uint32_t sx : {0u, 1u})
        for (uint32_t sy : {0u, 1u})
            for (uint32_t sz : {0u, 1u}) {
                // Vertex 2a + s is the tip along axis a on side s (0: +, 1: -); an odd number of
                // minus signs mirrors the face, which flips its corner order.
                const uint32_t x = sx, y = 2 + sy, z = 4 + sz;
                const bool mirrored = (sx + sy + sz) % 2 == 1;
                for (uint32_t v : {x, mirrored ? z : y, mirrored ? y : z}) m.indices.push_back(v);
            }
    return m;
}

inline Mesh makeBox(const Vec3d& lo, const Vec3d& hi) {
    Mesh m;
    appendBox(m, lo, hi);
    return m;
}

/// A closed torus around the z axis through `center`: major radius R, minor r, n x m quads.
inline Mesh makeTorus(const Vec3d& center, double R, double r, int n, int m) {
    Mesh mesh;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < m; ++j) {
            const double u = 2 * M_PI * i / n, v = 2 * M_PI * j / m;
            mesh.positions.push_back(
                Vec3f(center + Vec3d{(R + r * std::cos(v)) * std::cos(u), (R + r * std::cos(v)) * std::sin(u),
                                     r * std::sin(v)}));
        }
    auto id = [&](int i, int j) { return uint32_t(((i + n) % n) * m + (j + m) % m); };
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < m; ++j)
            for (const uint32_t t :
                 {id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j), id(i + 1, j + 1), id(i, j + 1)})
                mesh.indices.push_back(t);
    return mesh;
}

/// Brute-force inside test for closed meshes: parity of crossings of a ray in a fixed generic
/// direction (no axis alignment, so degenerate hits on edges are practically impossible).
/// Shares nothing with the rasterizer; O(triangles) per query.
inline bool insideByRay(const MeshView& mesh, const Vec3d& p) {
    const Vec3d dir = normalize(Vec3d{0.5773502691896258, 0.6123724356957945, 0.5400617248673217});
    int crossings = 0;
    for (size_t t = 0; t < mesh.triangleCount; ++t) {
        const Vec3d a = mesh.vertex(mesh.index(t, 0)), b = mesh.vertex(mesh.index(t, 1)),
                    c = mesh.vertex(mesh.index(t, 2));
        // Moller-Trumbore.
        const Vec3d e1 = b - a, e2 = c - a, h = cross(dir, e2);
        const double det = dot(e1, h);
        if (det == 0) continue;
        const double inv = 1.0 / det;
        const Vec3d s = p - a;
        const double u = dot(s, h) * inv;
        if (u < 0 || u > 1) continue;
        const Vec3d q = cross(s, e1);
        const double v = dot(dir, q) * inv;
        if (v < 0 || u + v > 1) continue;
        if (dot(e2, q) * inv > 0) ++crossings;
    }
    return crossings % 2 == 1;
}

} // namespace voxfx::test

// ---- Boolean operations, cell by cell (the CSG and level-set tests' oracle) --------------------
#include "voxfx/csg.hpp"

namespace voxfx::test {

/// Whether a point is inside `a op b`, from whether it is inside a and inside b.
inline bool csgInside(CsgOp op, bool a, bool b) {
    switch (op) {
    case CsgOp::Union:
        return a || b;
    case CsgOp::Intersection:
        return a && b;
    case CsgOp::Difference:
        return a && !b;
    case CsgOp::Xor:
        return a != b;
    }
    return false;
}

} // namespace voxfx::test

// ---- Random voxel grids (grid I/O and re-slicing tests) ----------------------------------------
#include <random>

#include "voxfx/voxel_grid.hpp"

namespace voxfx::test {

/// An orthographic grid over `box`, sliced along `axis`, with world dimensions `dims` (cells along
/// x, y, z); each voxel is on with probability `density`, from a fixed-seed generator.
inline VoxelGrid randomVoxelGrid(const Box3d& box, Axis axis, const Vec3i& dims, double density,
                                 uint64_t seed) {
    const int64_t w = dims[columnXAxis(axis)], h = dims[columnYAxis(axis)], d = dims[sliceAxis(axis)];
    VoxelGrid g{Frame::orthographic(box, axis, w, h, d), BitGrid(w, h, d)};
    std::mt19937_64 rng(seed);
    std::bernoulli_distribution on(density);
    for (int64_t y = 0; y < h; ++y)
        for (int64_t x = 0; x < w; ++x)
            for (int64_t s = 0; s < d; ++s)
                if (on(rng)) g.bits.set(x, y, s);
    return g;
}

/// Cells whose occupancy differs between two grids of the same world dimensions, compared by
/// world index (i, j, k) whatever each grid's slicing axis.
inline int64_t worldMismatches(const VoxelGrid& a, const VoxelGrid& b) {
    const Vec3i n = a.worldDims();
    int64_t mismatches = 0;
    for (int64_t i = 0; i < n.x; ++i)
        for (int64_t j = 0; j < n.y; ++j)
            for (int64_t k = 0; k < n.z; ++k)
                mismatches += a.atWorldIndex(i, j, k) != b.atWorldIndex(i, j, k);
    return mismatches;
}

/// A W x H x D bit grid, each cell on with probability `density` (fixed seed): the bits of
/// randomVoxelGrid sliced along z (grid tool tests: density, morphology, CSG, queries).
inline BitGrid randomBits(int64_t w, int64_t h, int64_t d, double density, uint64_t seed) {
    return randomVoxelGrid({{0, 0, 0}, {double(w), double(h), double(d)}}, Axis::Z, {w, h, d}, density, seed)
        .bits;
}

} // namespace voxfx::test

// ---- Spheres and exact mesh volumes (grid query, particle and surface tests) -------------------
namespace voxfx::test {

/// A closed UV sphere (outward CCW): `rings` latitude bands, `segments` longitudes, poles shared.
inline Mesh makeUvSphere(const Vec3d& center, double radius, int rings, int segments) {
    Mesh mesh;
    mesh.positions.push_back(Vec3f(center + Vec3d{0, 0, -radius}));
    for (int i = 1; i < rings; ++i)
        for (int j = 0; j < segments; ++j) {
            const double theta = M_PI * i / rings, phi = 2 * M_PI * j / segments;
            mesh.positions.push_back(
                Vec3f(center + Vec3d{radius * std::sin(theta) * std::cos(phi),
                                     radius * std::sin(theta) * std::sin(phi), -radius * std::cos(theta)}));
        }
    mesh.positions.push_back(Vec3f(center + Vec3d{0, 0, radius}));
    const auto top = uint32_t(mesh.positions.size() - 1);
    auto ring = [&](int i, int j) { return uint32_t(1 + (i - 1) * segments + (j + segments) % segments); };
    for (int j = 0; j < segments; ++j) {
        for (const uint32_t t : {uint32_t(0), ring(1, j + 1), ring(1, j)}) mesh.indices.push_back(t);
        for (const uint32_t t : {top, ring(rings - 1, j), ring(rings - 1, j + 1)}) mesh.indices.push_back(t);
        for (int i = 1; i + 1 < rings; ++i)
            for (const uint32_t t : {ring(i, j), ring(i, j + 1), ring(i + 1, j + 1), ring(i, j),
                                     ring(i + 1, j + 1), ring(i + 1, j)})
                mesh.indices.push_back(t);
    }
    return mesh;
}

/// Exact enclosed volume of a closed, consistently oriented mesh (divergence theorem: the sum of
/// signed tetrahedra from the origin), in double. Positive for outward orientation.
/// The mesh with every triangle's corner order reversed: its orientation flipped.
inline Mesh flippedMesh(Mesh mesh) {
    for (std::size_t t = 0; t + 2 < mesh.indices.size(); t += 3)
        std::swap(mesh.indices[t + 1], mesh.indices[t + 2]);
    return mesh;
}

inline double meshVolume(const MeshView& mesh) {
    double v = 0;
    for (std::size_t t = 0; t < mesh.triangleCount; ++t) {
        const Vec3d a = mesh.vertex(mesh.index(t, 0)), b = mesh.vertex(mesh.index(t, 1)),
                    c = mesh.vertex(mesh.index(t, 2));
        v += dot(a, cross(b, c)) / 6.0;
    }
    return v;
}

} // namespace voxfx::test

// ---- Running the voxfx command (end-to-end tests of the CLI subcommands) ----------------------
#include <sys/wait.h>

namespace voxfx::test {

struct CommandRun {
    int exitCode = -1;
    std::string out, err;
};

/// Runs `voxfx ARGS` (no stdin), capturing stdout and stderr through files in `dir`.
inline CommandRun runVoxfx(const TempDir& dir, const std::string& args) {
    const std::string out = dir.file("voxfx-stdout.txt"), err = dir.file("voxfx-stderr.txt");
    const std::string cmd =
        std::string(VOXFX_CLI_PATH) + " " + args + " >" + out + " 2>" + err + " </dev/null";
    const int status = std::system(cmd.c_str());
    CommandRun r;
    r.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : 128;
    r.out = readFileBytes(out);
    r.err = readFileBytes(err);
    return r;
}

} // namespace voxfx::test

// ---- A .binvox decoder written from the format's description -----------------------------------
#include <algorithm>
#include <sstream>
#include <vector>

namespace voxfx::test {

/// A .binvox file as the format describes it, decoded here without voxfx: header lines "#binvox 1",
/// "dim", "translate", "scale", "data", then (value, count) byte pairs, count 1..255, voxel order
/// index = x * (ny * nz) + z * ny + y; "dim" lists the counts slowest first (nx nz ny). Problems
/// with the file are reported as test failures.
struct BinvoxFile {
    Vec3i dims{0, 0, 0}; ///< cells along world x, y, z
    Vec3d translate;     ///< world position of the grid's lower corner
    double scale = 0;    ///< world length of the longest side (cells are cubes of scale / max dims)
    std::vector<uint8_t> voxels;

    bool at(int64_t i, int64_t j, int64_t k) const {
        return voxels[std::size_t(i * dims.y * dims.z + k * dims.y + j)] != 0;
    }
    int64_t count() const { return int64_t(std::count(voxels.begin(), voxels.end(), uint8_t(1))); }
    double cell() const { return scale / double(std::max({dims.x, dims.y, dims.z})); }
};

inline BinvoxFile readBinvoxBySpec(const std::string& path) {
    BinvoxFile f;
    const std::string bytes = readFileBytes(path);
    const std::size_t dataPos = bytes.find("\ndata\n");
    if (dataPos == std::string::npos) {
        ADD_FAILURE() << path << ": no \"data\" line";
        return f;
    }
    std::istringstream header(bytes.substr(0, dataPos));
    std::string magic, dimKey, translateKey, scaleKey;
    int version = 0;
    header >> magic >> version >> dimKey >> f.dims.x >> f.dims.z >> f.dims.y;
    header >> translateKey >> f.translate.x >> f.translate.y >> f.translate.z >> scaleKey >> f.scale;
    EXPECT_EQ(magic, "#binvox") << path;
    EXPECT_EQ(version, 1) << path;
    EXPECT_EQ(dimKey, "dim") << path;
    EXPECT_EQ(translateKey, "translate") << path;
    EXPECT_EQ(scaleKey, "scale") << path;
    const std::size_t first = dataPos + 6;
    EXPECT_EQ((bytes.size() - first) % 2, 0u) << path << ": a run without its count";
    int64_t badRuns = 0;
    for (std::size_t p = first; p + 1 < bytes.size(); p += 2) {
        const auto value = uint8_t(bytes[p]), count = uint8_t(bytes[p + 1]);
        badRuns += count == 0 || value > 1;
        f.voxels.insert(f.voxels.end(), count, value);
    }
    EXPECT_EQ(badRuns, 0) << path << ": runs must be (0 or 1, 1..255)";
    const int64_t cells = f.dims.x * f.dims.y * f.dims.z;
    EXPECT_EQ(int64_t(f.voxels.size()), cells) << path;
    f.voxels.resize(std::size_t(std::max<int64_t>(cells, 0)), 0);
    return f;
}

} // namespace voxfx::test
