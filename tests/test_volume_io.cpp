// Tests of loadVolume: INR (CGAL's images and files written here), NRRD and raw + JSON of every
// scalar type and both byte orders, plain and gzipped, OpenVDB float grids, and every kind of bad
// input.
//
// Oracles: the files are written here byte by byte (samples shifted out in the byte order the
// header names, gzip by zlib's deflate); CGAL's images are decoded here with plain code from the
// bytes after the header. Placement is checked against each format's own definition of where
// sample (i, j, k) lies in the world.
#include <bit>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <zlib.h>

#include "io/module_api.hpp"
#include "test_util.hpp"
#include "voxfx/grid_io.hpp"
#include "voxfx/scene_io.hpp"
#include "voxfx/volume_io.hpp"
#include "voxfx/volume_scene.hpp"

namespace voxfx {
namespace {

using test::TempDir;
using test::writeFile;

// ---- Writing samples byte by byte -------------------------------------------------------------

// One sample as bytes in the given order: the value's bit pattern shifted out byte by byte.
template <class T> std::string sampleBytes(T v, bool bigEndian) {
    uint64_t bits = 0;
    if constexpr (sizeof(T) == 1)
        bits = std::bit_cast<uint8_t>(v);
    else if constexpr (sizeof(T) == 2)
        bits = std::bit_cast<uint16_t>(v);
    else if constexpr (sizeof(T) == 4)
        bits = std::bit_cast<uint32_t>(v);
    else
        bits = std::bit_cast<uint64_t>(v);
    std::string out(sizeof(T), '\0');
    for (std::size_t b = 0; b < sizeof(T); ++b) {
        const std::size_t shift = 8 * (bigEndian ? sizeof(T) - 1 - b : b);
        out[b] = char((bits >> shift) & 0xFF);
    }
    return out;
}

// Test values of a type: its extremes, zero, and a spread in between (floats: fractions, values
// float cannot hold exactly, subnormals).
template <class T> std::vector<T> valuesOf(std::size_t n) {
    std::vector<T> v;
    if constexpr (std::is_integral_v<T>) {
        v = {std::numeric_limits<T>::min(), std::numeric_limits<T>::max(), T(0), T(1)};
        if constexpr (std::is_signed_v<T>) v.push_back(T(-1));
    } else {
        v = {T(0), T(-2.5), T(1e-3), T(0.1), std::numeric_limits<T>::denorm_min(), T(-3.0e38), T(3.0e38)};
    }
    uint64_t state = 0x243f6a8885a308d3ull;
    while (v.size() < n) {
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        if constexpr (std::is_integral_v<T>)
            v.push_back(T(state >> 32));
        else
            v.push_back(T(double(int64_t(state >> 40) - (int64_t(1) << 23)) / 1024.0));
    }
    v.resize(n);
    return v;
}

template <class T> std::string samplesBytes(const std::vector<T>& v, bool bigEndian) {
    std::string out;
    for (T x : v) out += sampleBytes(x, bigEndian);
    return out;
}

std::string gzip(std::string_view data) {
    z_stream z{};
    EXPECT_EQ(deflateInit2(&z, 9, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY), Z_OK);
    std::string out(deflateBound(&z, uLong(data.size())) + 64, '\0');
    z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(data.data()));
    z.avail_in = uInt(data.size());
    z.next_out = reinterpret_cast<Bytef*>(out.data());
    z.avail_out = uInt(out.size());
    EXPECT_EQ(deflate(&z, Z_FINISH), Z_STREAM_END);
    out.resize(z.total_out);
    deflateEnd(&z);
    return out;
}

std::string gunzipFile(const std::string& path) {
    gzFile f = gzopen(path.c_str(), "rb");
    EXPECT_NE(f, nullptr);
    std::string out;
    char buf[65536];
    int n;
    while ((n = gzread(f, buf, sizeof(buf))) > 0) out.append(buf, std::size_t(n));
    gzclose(f);
    return out;
}

std::string readAll(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Calls f, expects a voxfx::Error whose message holds every one of `parts`.
void expectError(const std::function<void()>& f, std::initializer_list<std::string> parts) {
    try {
        f();
        ADD_FAILURE() << "no error; expected one mentioning '" << *parts.begin() << "'";
    } catch (const Error& e) {
        const std::string msg = e.what();
        for (const std::string& p : parts)
            EXPECT_NE(msg.find(p), std::string::npos) << "'" << p << "' not in: " << msg;
    }
}

// The INR header CGAL writes, padded with newlines to 256 bytes.
std::string inrHeader(const std::string& fields) {
    std::string h = "#INRIMAGE-4#{\n" + fields;
    const std::string end = "##}\n";
    const std::size_t total = (h.size() + end.size() + 255) / 256 * 256;
    h.append(total - h.size() - end.size(), '\n');
    return h + end;
}

struct TypeCase {
    ScalarType type;
    const char* inrType;
    int bits;
    const char* nrrdType;
    const char* jsonType;
};
const TypeCase kTypes[] = {
    {ScalarType::UInt8, "unsigned fixed", 8, "uchar", "uint8"},
    {ScalarType::Int8, "signed fixed", 8, "signed char", "int8"},
    {ScalarType::UInt16, "unsigned fixed", 16, "ushort", "uint16"},
    {ScalarType::Int16, "signed fixed", 16, "short", "int16"},
    {ScalarType::UInt32, "unsigned fixed", 32, "unsigned int", "uint32"},
    {ScalarType::Int32, "signed fixed", 32, "int", "int32"},
    {ScalarType::Float32, "float", 32, "float", "float32"},
    {ScalarType::Float64, "float", 64, "double", "float64"},
};

// The samples of a type as bytes and as the floats they must become (static_cast: the value
// itself, rounded to float).
struct Samples {
    std::string bytes;
    std::vector<float> expected;
};
Samples makeSamples(ScalarType type, std::size_t n, bool bigEndian) {
    Samples s;
    const auto fill = [&](auto tag) {
        using T = decltype(tag);
        const std::vector<T> v = valuesOf<T>(n);
        s.bytes = samplesBytes(v, bigEndian);
        for (T x : v) s.expected.push_back(static_cast<float>(x));
    };
    switch (type) {
    case ScalarType::UInt8:
        fill(uint8_t{});
        break;
    case ScalarType::Int8:
        fill(int8_t{});
        break;
    case ScalarType::UInt16:
        fill(uint16_t{});
        break;
    case ScalarType::Int16:
        fill(int16_t{});
        break;
    case ScalarType::UInt32:
        fill(uint32_t{});
        break;
    case ScalarType::Int32:
        fill(int32_t{});
        break;
    case ScalarType::Float32:
        fill(float{});
        break;
    case ScalarType::Float64:
        fill(double{});
        break;
    }
    return s;
}

// Every voxel of `v` against the samples in file order (x fastest).
void expectSamples(const Volume& v, const Vec3i& dims, const std::vector<float>& expected) {
    ASSERT_EQ(v.dims(), dims);
    int bad = 0;
    for (int64_t k = 0; k < dims.z; ++k)
        for (int64_t j = 0; j < dims.y; ++j)
            for (int64_t i = 0; i < dims.x; ++i) {
                const float e = expected[std::size_t(i + dims.x * (j + dims.y * k))];
                if (v.at(i, j, k) != e && bad++ < 5)
                    ADD_FAILURE() << "voxel (" << i << ", " << j << ", " << k << "): " << v.at(i, j, k)
                                  << " != " << e;
            }
}

void expectVecNear(const Vec3d& a, const Vec3d& b, double tol = 1e-9) {
    EXPECT_NEAR(a.x, b.x, tol);
    EXPECT_NEAR(a.y, b.y, tol);
    EXPECT_NEAR(a.z, b.z, tol);
}

const Vec3i kDims{3, 4, 5};

// ---- CGAL's images ----------------------------------------------------------------------------

// Decodes the samples after an INR header with plain code: little-endian (CPU=decm).
std::vector<float> decodeInrPayload(const std::string& file, const std::string& type, int bits) {
    const std::size_t end = file.find("##}\n") + 4;
    std::vector<float> out;
    for (std::size_t p = end; p + std::size_t(bits / 8) <= file.size(); p += std::size_t(bits / 8)) {
        uint64_t u = 0;
        for (int b = 0; b < bits / 8; ++b) u |= uint64_t(uint8_t(file[p + std::size_t(b)])) << (8 * b);
        if (type == "float" && bits == 32)
            out.push_back(std::bit_cast<float>(uint32_t(u)));
        else if (type == "unsigned fixed" && bits == 8)
            out.push_back(float(u));
        else
            ADD_FAILURE() << "decoder does not handle " << type << " " << bits;
    }
    return out;
}

struct CgalImage {
    const char* name;
    Vec3i dims;
    Vec3d spacing;
    ScalarType type;
};

TEST(VolumeIo, EveryCgalImageLoadsWithItsDimsSpacingTypeAndSamples) {
    const CgalImage images[] = {
        {"skull_2.9.inr", {64, 64, 64}, {3.943050, 3.943050, 3.650790}, ScalarType::Float32},
        {"liver.inr.gz", {438, 353, 165}, {0.617188, 0.617188, 1.33333}, ScalarType::UInt8},
        {"small-scalar.inr", {2, 2, 2}, {100, 100, 100}, ScalarType::Float32},
        {"12323.inr", {2, 2, 2}, {100, 100, 100}, ScalarType::UInt8},
        {"20012323.inr", {2, 2, 2}, {100, 100, 100}, ScalarType::UInt8},
        {"40420.inr", {2, 2, 2}, {100, 100, 100}, ScalarType::UInt8},
        {"420.inr", {2, 2, 2}, {100, 100, 100}, ScalarType::UInt8},
    };
    for (const CgalImage& img : images) {
        SCOPED_TRACE(img.name);
        VOXFX_REQUIRE_DATA(std::string("images/") + img.name);
        const std::string path = test::dataPath(std::string("images/") + img.name);
        VolumeLoadReport report;
        const Volume v = loadVolume(path, &report);
        EXPECT_EQ(report.format, VolumeFormat::Inr);
        EXPECT_EQ(report.gzip, std::string(img.name).ends_with(".gz"));
        EXPECT_EQ(v.dims(), img.dims);
        EXPECT_EQ(v.sourceType(), img.type);
        expectVecNear(v.spacing(), img.spacing, 0);
        // No TX/TY/TZ: CGAL puts the sample of voxel (0, 0, 0) at the world origin.
        expectVecNear(v.voxelCenter(0, 0, 0), {0, 0, 0}, 1e-12);

        const std::string bytes = report.gzip ? gunzipFile(path) : readAll(path);
        const bool isFloat = img.type == ScalarType::Float32;
        const std::vector<float> expected =
            decodeInrPayload(bytes, isFloat ? "float" : "unsigned fixed", isFloat ? 32 : 8);
        ASSERT_EQ(int64_t(expected.size()), v.voxelCount());
        expectSamples(v, img.dims, expected);
        EXPECT_EQ(v.minValue(), *std::min_element(expected.begin(), expected.end()));
        EXPECT_EQ(v.maxValue(), *std::max_element(expected.begin(), expected.end()));
    }
}

// ---- INR written here -------------------------------------------------------------------------

TEST(VolumeIo, InrOfEveryTypeAndByteOrderPlainAndGzippedReadsBack) {
    TempDir dir;
    for (const TypeCase& t : kTypes)
        for (const bool big : {false, true})
            for (const bool gz : {false, true}) {
                SCOPED_TRACE(std::string(toString(t.type)) + (big ? " big" : " little") + (gz ? " gz" : ""));
                const Samples s = makeSamples(t.type, std::size_t(kDims.x * kDims.y * kDims.z), big);
                const std::string header = inrHeader(
                    "XDIM=3\nYDIM=4\nZDIM=5\nVDIM=1\nTYPE=" + std::string(t.inrType) +
                    "\nPIXSIZE=" + std::to_string(t.bits) + " bits\nSCALE=2**0\nCPU=" + (big ? "sgi" : "pc") +
                    "\nVX=0.5\nVY=2\nVZ=1.25\nTX=10\nTY=-4\nTZ=0.75\n#GEOMETRY=CARTESIAN\n");
                const std::string name = dir.file(std::string(toString(t.type)) + (big ? "-big" : "-little") +
                                                  (gz ? ".inr.gz" : ".inr"));
                writeFile(name, gz ? gzip(header + s.bytes) : header + s.bytes);
                const Volume v = loadVolume(name);
                EXPECT_EQ(v.sourceType(), t.type);
                expectSamples(v, kDims, s.expected);
                expectVecNear(v.spacing(), {0.5, 2, 1.25}, 0);
                // TX, TY, TZ: the world position of the sample of voxel (0, 0, 0) (CGAL's ImageIO).
                for (int64_t i : {0, 2})
                    expectVecNear(v.voxelCenter(i, 3, 4),
                                  Vec3d{10, -4, 0.75} + Vec3d{0.5 * i, 2.0 * 3, 1.25 * 4});
            }
}

TEST(VolumeIo, InrHeaderNeedNotFillWholeBlocks) {
    // CGAL's small-scalar.inr ends its header at byte 240: the samples follow "##}" at once.
    TempDir dir;
    const std::string header =
        "#INRIMAGE-4#{\nXDIM=2\nYDIM=1\nZDIM=1\nTYPE=unsigned fixed\nPIXSIZE=8 bits\n##}\n";
    const Volume v = loadVolume(writeFile(dir.file("short.inr"), header + std::string("\x07\x09", 2)));
    EXPECT_EQ(v.at(0, 0, 0), 7.0f);
    EXPECT_EQ(v.at(1, 0, 0), 9.0f);
}

TEST(VolumeIo, GzipOfSeveralMembersAndWithoutExtensionReads) {
    // gzip allows concatenated members (what `cat a.gz b.gz` makes); the name need not say .gz.
    TempDir dir;
    const Samples s = makeSamples(ScalarType::UInt16, 60, true);
    const std::string header =
        inrHeader("XDIM=3\nYDIM=4\nZDIM=5\nTYPE=unsigned fixed\nPIXSIZE=16 bits\nCPU=sun\n");
    const std::string twoMembers = gzip(header + s.bytes.substr(0, 7)) + gzip(s.bytes.substr(7));
    expectSamples(loadVolume(writeFile(dir.file("two.inr.gz"), twoMembers)), kDims, s.expected);
    VolumeLoadReport report;
    expectSamples(loadVolume(writeFile(dir.file("scan"), twoMembers), &report), kDims, s.expected);
    EXPECT_EQ(report.format, VolumeFormat::Inr);
    EXPECT_TRUE(report.gzip);
}

// ---- NRRD -------------------------------------------------------------------------------------

std::string nrrdHeader(const std::string& type, bool big, const std::string& encoding,
                       const std::string& extra) {
    return "NRRD0004\n# written by the test\ntype: " + type +
           "\ndimension: 3\nsizes: 3 4 5\nendian: " + (big ? "big" : "little") + "\nencoding: " + encoding +
           "\nkinds: domain domain domain\nspace: right-anterior-superior\n" + extra + "\n";
}

TEST(VolumeIo, NrrdOfEveryTypeAndByteOrderRawAndGzipReadsBackWherePlaced) {
    TempDir dir;
    const Vec3d origin{-1.5, 2, 30};
    const Vec3d step{0.25, 0.5, 3};
    for (const TypeCase& t : kTypes)
        for (const bool big : {false, true})
            for (const bool gz : {false, true}) {
                SCOPED_TRACE(std::string(t.nrrdType) + (big ? " big" : " little") + (gz ? " gzip" : " raw"));
                const Samples s = makeSamples(t.type, std::size_t(kDims.x * kDims.y * kDims.z), big);
                const std::string header =
                    nrrdHeader(t.nrrdType, big, gz ? "gzip" : "raw",
                               "space directions: (0.25,0,0) (0,0.5,0) (0,0,3)\nspace origin: (-1.5,2,30)\n");
                VolumeLoadReport report;
                const Volume v =
                    loadVolume(writeFile(dir.file(std::string(toString(t.type)) + (big ? "-big" : "-little") +
                                                  (gz ? "-gz" : "") + ".nrrd"),
                                         header + (gz ? gzip(s.bytes) : s.bytes)),
                               &report);
                EXPECT_EQ(report.format, VolumeFormat::Nrrd);
                EXPECT_EQ(report.gzip, gz);
                EXPECT_EQ(v.sourceType(), t.type);
                expectSamples(v, kDims, s.expected);
                // NRRD: sample (i, j, k) lies at space origin + i * dir0 + j * dir1 + k * dir2.
                expectVecNear(v.voxelCenter(2, 1, 4), origin + Vec3d{2, 1, 4} * step);
            }
}

TEST(VolumeIo, NrrdNegativeDirectionIsMirroredSoEverySampleKeepsItsWorldPosition) {
    TempDir dir;
    const Samples s = makeSamples(ScalarType::Int16, 60, false);
    const std::string header = nrrdHeader(
        "short", false, "raw", "space directions: (-2,0,0) (0,1,0) (0,0,-0.5)\nspace origin: (10,0,7)\n");
    const Volume v = loadVolume(writeFile(dir.file("lps.nrrd"), header + s.bytes));
    ASSERT_EQ(v.dims(), kDims);
    expectVecNear(v.spacing(), {2, 1, 0.5}, 0);
    for (int64_t k = 0; k < 5; ++k)
        for (int64_t j = 0; j < 4; ++j)
            for (int64_t i = 0; i < 3; ++i) {
                const Vec3d world{10 - 2.0 * double(i), double(j), 7 - 0.5 * double(k)};
                // The voxel whose centre is that world point holds the file's sample (i, j, k).
                const Vec3d u =
                    (world - v.lo()) * Vec3d(1 / v.spacing().x, 1 / v.spacing().y, 1 / v.spacing().z);
                const Vec3i idx{int64_t(std::floor(u.x)), int64_t(std::floor(u.y)), int64_t(std::floor(u.z))};
                expectVecNear(v.voxelCenter(idx.x, idx.y, idx.z), world);
                EXPECT_EQ(v.at(idx.x, idx.y, idx.z), s.expected[std::size_t(i + 3 * (j + 4 * k))]);
            }
}

TEST(VolumeIo, NrrdObliqueDirectionsTurnTheVolumeSoEverySampleKeepsItsWorldPosition) {
    // Directions turned 30 degrees about z (voxel sizes 2, 1, 0.5): voxel (i, j, k)'s centre is
    // origin + i d0 + j d1 + k d2, computed here from the header's numbers.
    TempDir dir;
    const Samples s = makeSamples(ScalarType::Int16, 60, false);
    const double c = std::cos(M_PI / 6), n = std::sin(M_PI / 6);
    const Vec3d d0{2 * c, 2 * n, 0}, d1{-n, c, 0}, d2{0, 0, 0.5}, origin{10, 0, 7};
    char directions[256];
    std::snprintf(directions, sizeof directions,
                  "space directions: (%.17g,%.17g,0) (%.17g,%.17g,0) (0,0,0.5)\nspace origin: (10,0,7)\n",
                  d0.x, d0.y, d1.x, d1.y);
    const Volume v = loadVolume(
        writeFile(dir.file("oblique.nrrd"), nrrdHeader("short", false, "raw", directions) + s.bytes));
    ASSERT_EQ(v.dims(), kDims);
    EXPECT_FALSE(v.axisAligned());
    expectVecNear(v.spacing(), {2, 1, 0.5}, 1e-12);
    for (int64_t k = 0; k < 5; ++k)
        for (int64_t j = 0; j < 4; ++j)
            for (int64_t i = 0; i < 3; ++i) {
                const Vec3d world = origin + d0 * double(i) + d1 * double(j) + d2 * double(k);
                expectVecNear(v.voxelCenter(i, j, k), world, 1e-9);
                const float want = s.expected[std::size_t(i + 3 * (j + 4 * k))];
                EXPECT_EQ(v.at(i, j, k), want);
                EXPECT_NEAR(v.sample(world), want, 1e-6 * (1 + std::fabs(want)));
            }
    // The box holds every corner; a point beyond the turned box samples "outside".
    const Box3d b = v.box();
    for (const Vec3d& corner : {origin - (d0 + d1 + d2) * 0.5, origin + d0 * 2.5 + d1 * 3.5 + d2 * 4.5})
        for (int a = 0; a < 3; ++a) {
            EXPECT_GE(corner[a], b.lo[a] - 1e-9);
            EXPECT_LE(corner[a], b.hi[a] + 1e-9);
        }
    EXPECT_EQ(v.sample(origin - d0, -7.0f), -7.0f);
}

TEST(VolumeIo, NrrdDetachedHeaderSpacingsAndSkipsRead) {
    TempDir dir;
    const Samples s = makeSamples(ScalarType::UInt16, 60, true);
    writeFile(dir.file("data.raw"), "skip this line\n" + std::string("XYZ") + s.bytes);
    const std::string header =
        "NRRD0005\ntype: uint16\ndimension: 3\nsizes: 3 4 5\nendian: big\nencoding: raw\n"
        "spacings: 2 3 4\nline skip: 1\nbyte skip: 3\ndata file: data.raw\n";
    const Volume v = loadVolume(writeFile(dir.file("v.nhdr"), header));
    expectSamples(v, kDims, s.expected);
    expectVecNear(v.spacing(), {2, 3, 4}, 0);
    expectVecNear(v.lo(), {0, 0, 0}, 0); // no origin: the box starts at 0, as voxfx's grid reader has it

    // byte skip -1: the samples are the last bytes of the file.
    writeFile(dir.file("tail.raw"), std::string(17, 'x') + s.bytes);
    const std::string tail =
        "NRRD0004\ntype: uint16\ndimension: 3\nsizes: 3 4 5\nendian: big\nencoding: raw\n"
        "byte skip: -1\ndata file: tail.raw\n\n";
    expectSamples(loadVolume(writeFile(dir.file("tail.nhdr"), tail)), kDims, s.expected);
}

// ---- Raw + JSON -------------------------------------------------------------------------------

TEST(VolumeIo, RawWithJsonHeaderOfEveryTypeAndByteOrderReadsBack) {
    TempDir dir;
    for (const TypeCase& t : kTypes)
        for (const bool big : {false, true})
            for (const bool gz : {false, true}) {
                SCOPED_TRACE(std::string(t.jsonType) + (big ? " big" : " little") + (gz ? " gzip" : ""));
                const Samples s = makeSamples(t.type, 60, big);
                const std::string stem =
                    std::string(t.jsonType) + (big ? "-big" : "-little") + (gz ? "-gz" : "");
                writeFile(dir.file(stem + ".raw"), gz ? gzip(s.bytes) : "HDR!" + s.bytes);
                const std::string json = "{\"file\": \"" + stem +
                                         ".raw\", \"dims\": [3, 4, 5], \"type\": \"" + t.jsonType +
                                         "\", \"endian\": \"" + (big ? "big" : "little") +
                                         "\", \"spacing\": [1, 2, 0.5], \"origin\": [5, 6, 7]" +
                                         (gz ? ", \"encoding\": \"gzip\"" : ", \"offset\": 4") + "}";
                VolumeLoadReport report;
                const Volume v = loadVolume(writeFile(dir.file(stem + ".json"), json), &report);
                EXPECT_EQ(report.format, VolumeFormat::RawJson);
                EXPECT_EQ(v.sourceType(), t.type);
                expectSamples(v, kDims, s.expected);
                expectVecNear(v.voxelCenter(0, 0, 0), {5, 6, 7});
                expectVecNear(v.voxelCenter(2, 3, 4), {7, 12, 9});
            }
}

// ---- Bad input --------------------------------------------------------------------------------

TEST(VolumeIo, BadInrGivesAnErrorNamingTheFileAndTheProblem) {
    TempDir dir;
    const std::string ok = "XDIM=2\nYDIM=2\nZDIM=2\nTYPE=unsigned fixed\nPIXSIZE=16 bits\nCPU=decm\n";
    const std::string eight(16, '\x01');
    struct Case {
        std::string name, bytes, expect;
    };
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    const std::string floats = "XDIM=2\nYDIM=1\nZDIM=1\nTYPE=float\nPIXSIZE=32 bits\nCPU=decm\n";
    const Case cases[] = {
        {"truncated.inr", inrHeader(ok) + eight.substr(0, 15), "truncated"},
        {"longer.inr", inrHeader(ok) + eight + "x", "bytes more"},
        {"vector.inr", inrHeader(ok + "VDIM=3\n") + eight, "VDIM=3"},
        {"packed.inr", inrHeader("XDIM=2\nYDIM=2\nZDIM=2\nTYPE=packed\nPIXSIZE=8 bits\n") + eight,
         "TYPE 'packed'"},
        {"bits.inr", inrHeader("XDIM=2\nYDIM=2\nZDIM=2\nTYPE=float\nPIXSIZE=16 bits\nCPU=decm\n") + eight,
         "16 bits"},
        {"cpu.inr", inrHeader(ok + "CPU=vax\n") + eight, "CPU 'vax'"},
        {"nocpu.inr", inrHeader("XDIM=2\nYDIM=2\nZDIM=2\nTYPE=signed fixed\nPIXSIZE=16 bits\n") + eight,
         "no CPU"},
        {"zero.inr", inrHeader("XDIM=0\nYDIM=2\nZDIM=2\nTYPE=unsigned fixed\nPIXSIZE=8 bits\n"),
         "at least 1"},
        {"negative.inr", inrHeader("XDIM=-3\nYDIM=2\nZDIM=2\nTYPE=unsigned fixed\nPIXSIZE=8 bits\n"),
         "at least 1"},
        {"overflow.inr",
         inrHeader(
             "XDIM=4000000000\nYDIM=4000000000\nZDIM=4000000000\nTYPE=unsigned fixed\nPIXSIZE=8 bits\n"),
         "2^40"},
        // 10^12 voxels fit the limit but not the file: found before 4 TB are allocated.
        {"huge.inr",
         inrHeader("XDIM=10000\nYDIM=10000\nZDIM=10000\nTYPE=unsigned fixed\nPIXSIZE=8 bits\n") + eight,
         "truncated"},
        {"nodim.inr", inrHeader("XDIM=2\nYDIM=2\nTYPE=unsigned fixed\nPIXSIZE=8 bits\n") + eight, "no ZDIM"},
        {"word.inr", inrHeader("XDIM=two\nYDIM=2\nZDIM=2\nTYPE=unsigned fixed\nPIXSIZE=8 bits\n"),
         "XDIM must be"},
        {"spacing.inr", inrHeader(ok + "VX=-1\n") + eight, "VX"},
        {"noend.inr", "#INRIMAGE-4#{\n" + ok + std::string(300, '\n'), "no '##}'"},
        {"magic.inr", "#INRIMAGE-5#{\n" + ok + "##}\n", "not an INR file"},
        {"nan.inr", inrHeader(floats) + sampleBytes(1.0f, false) + sampleBytes(nan, false), "NaN"},
        {"inf.inr", inrHeader(floats) + sampleBytes(-inf, false) + sampleBytes(1.0f, false), "infinite"},
        {"double.inr",
         inrHeader("XDIM=1\nYDIM=1\nZDIM=1\nTYPE=float\nPIXSIZE=64 bits\nCPU=decm\n") +
             sampleBytes(1e300, false),
         "beyond the range of float"},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        const std::string path = writeFile(dir.file(c.name), c.bytes);
        expectError([&] { loadVolume(path); }, {path, c.expect});
    }
}

TEST(VolumeIo, NanErrorNamesTheVoxel) {
    TempDir dir;
    std::string data;
    for (int n = 0; n < 8; ++n)
        data += sampleBytes(n == 5 ? std::numeric_limits<float>::quiet_NaN() : 1.0f, true);
    const std::string path =
        writeFile(dir.file("nan.inr"),
                  inrHeader("XDIM=2\nYDIM=2\nZDIM=2\nTYPE=float\nPIXSIZE=32 bits\nCPU=sun\n") + data);
    expectError([&] { loadVolume(path); }, {path, "voxel (1, 0, 1)", "NaN"}); // 5 = 1 + 2 * (0 + 2 * 1)
}

TEST(VolumeIo, BadGzipGivesAnErrorNamingTheFile) {
    TempDir dir;
    const std::string header = inrHeader("XDIM=64\nYDIM=64\nZDIM=16\nTYPE=unsigned fixed\nPIXSIZE=8 bits\n");
    std::string payload;
    for (int n = 0; n < 64 * 64 * 16; ++n) payload += char((n * 7919) >> 5);
    const std::string good = gzip(header + payload);
    ASSERT_NO_THROW(loadVolume(writeFile(dir.file("good.inr.gz"), good)));

    std::string corrupt = good;
    for (std::size_t p = corrupt.size() / 2; p < corrupt.size() / 2 + 16; ++p) corrupt[p] = char(~corrupt[p]);
    const std::string c = writeFile(dir.file("corrupt.inr.gz"), corrupt);
    expectError([&] { loadVolume(c); }, {c, "gzip"});

    const std::string t = writeFile(dir.file("truncated.inr.gz"), good.substr(0, good.size() / 2));
    expectError([&] { loadVolume(t); }, {t, "truncated"});

    // A header claiming more samples than any deflate stream of this size can hold.
    const std::string liar = writeFile(
        dir.file("liar.inr.gz"),
        gzip(inrHeader("XDIM=5000\nYDIM=5000\nZDIM=5000\nTYPE=unsigned fixed\nPIXSIZE=8 bits\n") + "abc"));
    expectError([&] { loadVolume(liar); }, {liar, "more than"});

    const std::string shortData =
        writeFile(dir.file("short.inr.gz"), gzip(header + payload.substr(0, payload.size() - 1)));
    expectError([&] { loadVolume(shortData); }, {shortData, "truncated"});
    const std::string longData = writeFile(dir.file("long.inr.gz"), gzip(header + payload + "z"));
    expectError([&] { loadVolume(longData); }, {longData, "more than"});

    const std::string nrrd =
        writeFile(dir.file("corrupt.nrrd"), nrrdHeader("uchar", false, "gzip", "") +
                                                corrupt.substr(10, corrupt.size() - 10)); // no gzip header
    expectError([&] { loadVolume(nrrd); }, {nrrd, "gzip"});
}

TEST(VolumeIo, BadNrrdGivesAnErrorNamingTheFileAndTheProblem) {
    TempDir dir;
    const std::string data(60, '\x02');
    const std::string shorts(120, '\x02');
    struct Case {
        std::string name, bytes, expect;
    };
    const Case cases[] = {
        {"int64.nrrd", nrrdHeader("int64", false, "raw", "") + std::string(480, '\0'), "type 'int64'"},
        {"block.nrrd", nrrdHeader("block", false, "raw", "") + data, "type 'block'"},
        {"notype.nrrd", "NRRD0004\ndimension: 3\nsizes: 3 4 5\nencoding: raw\n\n" + data, "no 'type'"},
        {"dim4.nrrd", "NRRD0004\ntype: uchar\ndimension: 4\nsizes: 3 4 5 1\nencoding: raw\n\n" + data,
         "dimension must be 3"},
        {"sizes2.nrrd", "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 3 4\nencoding: raw\n\n" + data, "sizes"},
        {"zero.nrrd", "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 3 0 5\nencoding: raw\n\n", "at least 1"},
        {"noendian.nrrd", "NRRD0004\ntype: short\ndimension: 3\nsizes: 3 4 5\nencoding: raw\n\n" + shorts,
         "'endian'"},
        {"bzip2.nrrd", nrrdHeader("uchar", false, "bzip2", "") + data, "encoding 'bzip2'"},
        {"truncated.nrrd", nrrdHeader("short", false, "raw", "") + shorts.substr(1), "truncated"},
        {"longer.nrrd", nrrdHeader("short", false, "raw", "") + shorts + "!", "bytes more"},
        {"huge.nrrd",
         "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 10000 10000 10000\nencoding: raw\n\n" + data,
         "truncated"},
        {"overflow.nrrd",
         "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 9223372036854775807 2 2\nencoding: raw\n\n" + data,
         "2^40"},
        {"rotated.nrrd",
         nrrdHeader("uchar", false, "raw", "space directions: (1,1,0) (0,1,0) (0,0,1)\n") + data,
         "orthogonal"},
        {"flat.nrrd", nrrdHeader("uchar", false, "raw", "spacings: 1 0 1\n") + data, "positive"},
        {"nodata.nrrd", nrrdHeader("uchar", false, "raw", ""), "no data"},
        {"missing.nhdr", nrrdHeader("uchar", false, "raw", "data file: nowhere.raw\n"), "nowhere.raw"},
        {"magic.nrrd", "NRRD0009\ntype: uchar\n\n" + data, "not a NRRD file"},
        {"nan.nrrd",
         "NRRD0004\ntype: double\ndimension: 3\nsizes: 1 1 1\nendian: little\nencoding: raw\n\n" +
             sampleBytes(std::numeric_limits<double>::quiet_NaN(), false),
         "NaN"},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        const std::string path = writeFile(dir.file(c.name), c.bytes);
        expectError([&] { loadVolume(path); }, {path, c.expect});
    }
}

TEST(VolumeIo, BadRawJsonGivesAnErrorNamingTheFileAndTheProblem) {
    TempDir dir;
    writeFile(dir.file("v.raw"), std::string(60, '\x03'));
    const std::string good = R"({"file": "v.raw", "dims": [3, 4, 5], "type": "uint8"})";
    ASSERT_NO_THROW(loadVolume(writeFile(dir.file("good.json"), good)));
    struct Case {
        std::string name, json, expect;
    };
    const Case cases[] = {
        {"syntax.json", R"({"file": "v.raw", "dims": [3, 4, 5],)", "not valid JSON"},
        {"nofile.json", R"({"dims": [3, 4, 5], "type": "uint8"})", "no \"file\""},
        {"nodims.json", R"({"file": "v.raw", "type": "uint8"})", "no \"dims\""},
        {"type.json", R"({"file": "v.raw", "dims": [3, 4, 5], "type": "complex64"})", "unknown scalar type"},
        {"key.json", R"({"file": "v.raw", "dims": [3, 4, 5], "type": "uint8", "spacings": [1, 1, 1]})",
         "unknown key \"spacings\""},
        {"dims2.json", R"({"file": "v.raw", "dims": [3, 4], "type": "uint8"})", "three integers"},
        {"dimsneg.json", R"({"file": "v.raw", "dims": [3, -4, 5], "type": "uint8"})", "at least 1"},
        {"dimsbig.json", R"({"file": "v.raw", "dims": [3, 4, 18446744073709551615], "type": "uint8"})",
         "2^40"},
        {"endian.json", R"({"file": "v.raw", "dims": [3, 2, 5], "type": "uint16"})", "\"endian\""},
        {"sizes.json", R"({"file": "v.raw", "dims": [3, 4, 6], "type": "uint8"})", "truncated"},
        {"more.json", R"({"file": "v.raw", "dims": [3, 4, 4], "type": "uint8"})", "bytes more"},
        {"offset.json", R"({"file": "v.raw", "dims": [3, 4, 5], "type": "uint8", "offset": 1})", "truncated"},
        {"spacing.json", R"({"file": "v.raw", "dims": [3, 4, 5], "type": "uint8", "spacing": [1, -1, 1]})",
         "positive"},
        {"missing.json", R"({"file": "gone.raw", "dims": [3, 4, 5], "type": "uint8"})", "gone.raw"},
        {"nan.json", R"({"file": "v.raw", "dims": [3, 4, 5], "type": "uint8", "origin": [0, NaN, 0]})",
         "not valid JSON"},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        const std::string path = writeFile(dir.file(c.name), c.json);
        expectError([&] { loadVolume(path); }, {path, c.expect});
    }
}

// Every prefix of valid files, and valid files with bytes of the header or data changed, either
// load or raise voxfx::Error: no other exception, no crash (run under the sanitizers too).
TEST(VolumeIo, CutOrDamagedFilesLoadOrRaiseErrorNeverCrash) {
    TempDir dir;
    const Samples s = makeSamples(ScalarType::Float32, 60, false);
    const std::string inr =
        inrHeader("XDIM=3\nYDIM=4\nZDIM=5\nTYPE=float\nPIXSIZE=32 bits\nCPU=decm\nTX=1\n") + s.bytes;
    const std::string nrrd =
        nrrdHeader("float", false, "raw",
                   "space directions: (-1,0,0) (0,2,0) (0,0,1)\nspace origin: (1,2,3)\n") +
        s.bytes;
    const std::string nrrdGz = nrrdHeader("float", false, "gzip", "") + gzip(s.bytes);
    const struct {
        const char* name;
        std::string bytes;
    } files[] = {{"f.inr", inr}, {"f.inr.gz", gzip(inr)}, {"f.nrrd", nrrd}, {"g.nrrd", nrrdGz}};
    std::mt19937 rng(99);
    int count = 0;
    // Each variant gets a fresh file: rewriting one file in place makes ext4 flush it on close.
    const auto tryLoad = [&](const std::string& name, const std::string& bytes) {
        const std::string path = writeFile(dir.file(std::to_string(count++) + "-" + name), bytes);
        try {
            loadVolume(path);
        } catch (const Error&) {
        } catch (const std::exception& e) { ADD_FAILURE() << path << ": not a voxfx::Error: " << e.what(); }
        std::filesystem::remove(path);
    };
    for (const auto& f : files) {
        SCOPED_TRACE(f.name);
        for (std::size_t n = 0; n < f.bytes.size(); n += 1 + n / 64) tryLoad(f.name, f.bytes.substr(0, n));
        for (int trial = 0; trial < 300; ++trial) {
            std::string damaged = f.bytes;
            const int changes = 1 + int(rng() % 4);
            for (int c = 0; c < changes; ++c) {
                // Mostly the header, where sizes and types live.
                const std::size_t limit =
                    rng() % 4 ? std::min<std::size_t>(damaged.size(), 300) : damaged.size();
                const char pool[] = "0123456789-+.eE=:\n #()xXnaNinf\xff";
                damaged[rng() % limit] = pool[rng() % (sizeof(pool) - 1)];
            }
            tryLoad(f.name, damaged);
        }
    }
}

TEST(VolumeIo, UnknownOrMissingFilesGiveAClearError) {
    TempDir dir;
    const std::string txt = writeFile(dir.file("notes.txt"), "hello");
    expectError([&] { loadVolume(txt); }, {txt, "unknown volume format"});
    const std::string vdb = writeFile(dir.file("smoke.vdb"), "not really");
    expectError([&] { loadVolume(vdb); }, {vdb, "OpenVDB"});
    const std::string gone = dir.file("gone.nrrd");
    expectError([&] { loadVolume(gone); }, {gone, "cannot open"});
    expectError([&] { loadVolume(dir.path().string()); }, {"directory"});
}

// ---- OpenVDB float grids ---------------------------------------------------------------------
// Written by the voxfx_vdb module's float writer (OpenVDB's own FloatGrid and File), read back by
// loadVolume: the samples must be the values written and the placement the writer's transform
// (index (i, j, k) at centre0 + (i, j, k) * cell).

namespace vdbvol {

const Vec3i kDims{6, 5, 4};
constexpr double kCell[3] = {0.5, 0.25, 2.0}, kCentre0[3] = {-1.0, 3.0, 0.75};

float value(int64_t i, int64_t j, int64_t k) {
    if (i == kDims.x - 1 || (i + j + k) % 7 == 0) return 0.0f; // zeros: inactive, and an empty border
    return float(i + 1) + 10.0f * float(j) - 3.5f * float(k);
}

std::string write(const TempDir& dir, const std::string& name) {
    std::vector<float> values;
    for (int64_t k = 0; k < kDims.z; ++k)
        for (int64_t j = 0; j < kDims.y; ++j)
            for (int64_t i = 0; i < kDims.x; ++i) values.push_back(value(i, j, k));
    const std::string path = dir.file(name);
    detail::VdbPlacement placement;
    for (int a = 0; a < 3; ++a) {
        placement.cell[a] = kCell[a];
        placement.centre0[a] = kCentre0[a];
    }
    const int64_t dims[3] = {kDims.x, kDims.y, kDims.z};
    std::string error;
    EXPECT_TRUE(
        detail::vdbModule().writeFloats(path.c_str(), dims, values.data(), placement, "density", &error))
        << error;
    return path;
}

} // namespace vdbvol

TEST(VolumeIo, VdbTurnedFloatGridKeepsEverySampleWhereItWas) {
    // tests/fixtures/turned-float-grid.vdb (written by make_turned_float_grid.cpp next to it):
    // index axes turned 30 degrees about z, voxel sizes (2, 1, 0.5), index (0, 0, 0) centred at
    // (10, 0, 7), value 1 + i + 10 j + 100 k. Every voxel's centre is where the generator put it.
    const Volume v = loadVolume(std::string(VOXFX_FIXTURES_DIR) + "/turned-float-grid.vdb");
    ASSERT_TRUE(v.dims() == (Vec3i{3, 4, 5}));
    EXPECT_FALSE(v.axisAligned());
    expectVecNear(v.spacing(), {2, 1, 0.5}, 1e-12);
    const double c = std::cos(M_PI / 6), n = std::sin(M_PI / 6);
    const Vec3d d0{2 * c, 2 * n, 0}, d1{-n, c, 0}, d2{0, 0, 0.5}, origin{10, 0, 7};
    for (int64_t k = 0; k < 5; ++k)
        for (int64_t j = 0; j < 4; ++j)
            for (int64_t i = 0; i < 3; ++i) {
                const Vec3d world = origin + d0 * double(i) + d1 * double(j) + d2 * double(k);
                const float want = float(1 + i + 10 * j + 100 * k);
                expectVecNear(v.voxelCenter(i, j, k), world, 1e-9);
                EXPECT_EQ(v.at(i, j, k), want);
                EXPECT_NEAR(v.sample(world), want, 1e-4);
            }
}

TEST(VolumeIo, VdbFloatGridReadsBackItsSamplesAndTransform) {
    TempDir dir;
    const std::string path = vdbvol::write(dir, "density.vdb");
    for (const std::string grid : {"", "density"}) {
        VolumeLoadReport report;
        VolumeLoadOptions options;
        options.vdbGrid = grid;
        const Volume v = loadVolume(path, options, &report);
        EXPECT_EQ(report.format, VolumeFormat::Vdb);
        EXPECT_EQ(report.gridName, "density");
        EXPECT_EQ(report.gridClass, "fog volume");
        EXPECT_EQ(v.sourceType(), ScalarType::Float32);
        ASSERT_TRUE(v.dims() == vdbvol::kDims) << v.dims().x << " x " << v.dims().y << " x " << v.dims().z;
        int64_t nonzero = 0;
        for (int64_t k = 0; k < vdbvol::kDims.z; ++k)
            for (int64_t j = 0; j < vdbvol::kDims.y; ++j)
                for (int64_t i = 0; i < vdbvol::kDims.x; ++i) {
                    ASSERT_EQ(v.at(i, j, k), vdbvol::value(i, j, k)) << i << ", " << j << ", " << k;
                    nonzero += v.at(i, j, k) != 0;
                    const Vec3d c = v.voxelCenter(i, j, k);
                    const Vec3d ijk{double(i), double(j), double(k)};
                    for (int a = 0; a < 3; ++a)
                        EXPECT_NEAR(c[a], vdbvol::kCentre0[a] + ijk[a] * vdbvol::kCell[a], 1e-12);
                    EXPECT_EQ(v.sample(c), vdbvol::value(i, j, k));
                }
        EXPECT_GT(nonzero, 60);
        for (int a = 0; a < 3; ++a) EXPECT_EQ(v.spacing()[a], vdbvol::kCell[a]);
    }
}

TEST(VolumeIo, VdbVolumeErrorsNameTheFileAndTheCause) {
    TempDir dir;
    const std::string good = vdbvol::write(dir, "density.vdb");
    VolumeLoadOptions other;
    other.vdbGrid = "smoke";
    expectError([&] { loadVolume(good, other); }, {good, "no grid named 'smoke'", "'density'"});
    // A bool grid is not a volume.
    const std::string bools = dir.file("bools.vdb");
    writeGrid(test::randomVoxelGrid(Box3d{{0, 0, 0}, {1, 1, 1}}, Axis::Z, {8, 8, 8}, 0.5, 3), bools);
    expectError([&] { loadVolume(bools); }, {bools, "no float or double grid", "(bool)"});
    // Truncated and corrupt files: clear errors, no volume.
    const std::string bytes = test::readFileBytes(good);
    ASSERT_GT(bytes.size(), 100u);
    for (const std::size_t cut : {std::size_t(0), std::size_t(20), bytes.size() / 2, bytes.size() - 1}) {
        const std::string p = writeFile(dir.file("cut" + std::to_string(cut) + ".vdb"), bytes.substr(0, cut));
        expectError([&] { loadVolume(p); }, {p});
    }
    std::string corrupt = bytes;
    corrupt[0] ^= 0x5a; // the magic number
    const std::string bad = writeFile(dir.file("magic.vdb"), corrupt);
    expectError([&] { loadVolume(bad); }, {bad, "not a valid .vdb"});
    expectError([&] { loadVolume(dir.file("missing.vdb")); }, {"missing.vdb", "No such file"});
    const std::string inr = writeFile(dir.file("x.inr"), "");
    expectError([&] { loadVolume(inr, other); }, {inr, "only for .vdb"});
}

TEST(VolumeIo, VdbGridNamedInASceneFileBecomesTheObjectsVolume) {
    TempDir dir;
    vdbvol::write(dir, "density.vdb");
    writeFile(dir.file("scene.json"), R"({"objects": [
      {"name": "cloud", "kind": "volume", "volume": {"file": "density.vdb", "grid": "density"}, "scale": 2,
       "translate": [1, 0, 0], "transfer": {"color": [[0, 1, 1, 1]], "opacity": [[0, 0], [40, 1]]}}]})");
    const Scene scene = loadScene(dir.file("scene.json"));
    ASSERT_TRUE(scene.volumeScene);
    ASSERT_EQ(scene.volumeScene->volumes.size(), 1u);
    const Volume& v = *scene.volumeScene->volumes[0];
    ASSERT_TRUE(v.dims() == vdbvol::kDims);
    EXPECT_EQ(v.at(2, 3, 1), vdbvol::value(2, 3, 1));
    // Placement: world = file position * scale + translate.
    EXPECT_NEAR(v.voxelCenter(0, 0, 0).x, vdbvol::kCentre0[0] * 2 + 1, 1e-12);
    EXPECT_NEAR(v.spacing().z, vdbvol::kCell[2] * 2, 1e-12);
    writeFile(dir.file("bad.json"), R"({"objects": [
      {"name": "cloud", "kind": "volume", "volume": {"file": "density.vdb", "grid": "smoke"},
       "transfer": {"color": [[0, 1, 1, 1]], "opacity": [[0, 0], [40, 1]]}}]})");
    expectError([&] { loadScene(dir.file("bad.json")); }, {"density.vdb", "no grid named 'smoke'"});
}

} // namespace
} // namespace voxfx
