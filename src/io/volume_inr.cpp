// voxfx — INRIMAGE-4 reader (the format of CGAL's images: ImageIO's inr_impl.h), plain or gzipped.
//
//   #INRIMAGE-4#{           magic line
//   XDIM=64 YDIM=.. ZDIM=.. one KEY=VALUE per line; VDIM (default 1) must be 1
//   TYPE=unsigned fixed     or "signed fixed" or "float"
//   PIXSIZE=16 bits         8, 16, 32 (fixed) or 32, 64 (float)
//   CPU=decm                decm, pc, alpha: little endian; sun, sgi: big endian
//   VX=.. VY=.. VZ=..       voxel size (default 1)
//   TX=.. TY=.. TZ=..       centre of voxel (0, 0, 0) (default 0), as CGAL reads it
//   #...                    comments; other keys (SCALE, XO, RX...) carry nothing we use
//   ##}                     end of the header, usually padded to 256 * k bytes with newlines
// The samples follow the "##}\n" line at once, x fastest, then y, then z.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <string_view>

#include "io/volume_formats.hpp"

namespace voxfx::detail {

namespace {

constexpr std::string_view kMagic = "#INRIMAGE-4#{";
constexpr std::string_view kEnd = "##}\n";
constexpr std::size_t kMaxHeaderBytes = std::size_t(1) << 16;

std::string_view trim(std::string_view s) {
    while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
    while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
    return s;
}

template <class T> bool parseWhole(std::string_view s, T& v) {
    s = trim(s);
    if (!s.empty() && s.front() == '+') s.remove_prefix(1);
    const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
    return r.ec == std::errc() && r.ptr == s.data() + s.size() && r.ptr != s.data();
}

struct InrHeader {
    Vec3i dims{0, 0, 0};
    int64_t vdim = 1;
    ScalarType type = ScalarType::UInt8;
    Vec3d spacing{1, 1, 1};
    Vec3d centre0{0, 0, 0};
    bool bigEndian = false;
};

// Parses the header text (magic line to the "##}" line, excluded).
InrHeader parseHeader(std::string_view text, const std::string& path) {
    InrHeader h;
    bool have[3] = {false, false, false};
    std::string_view kind, pixsize, cpu;
    std::size_t pos = text.find('\n');
    pos = pos == std::string_view::npos ? text.size() : pos + 1; // past the magic line
    int line = 1;
    while (pos < text.size()) {
        std::size_t eol = text.find('\n', pos);
        if (eol == std::string_view::npos) eol = text.size();
        const std::string_view l = trim(text.substr(pos, eol - pos));
        pos = eol + 1;
        ++line;
        if (l.empty() || l.front() == '#') continue;
        const std::size_t eq = l.find('=');
        if (eq == std::string_view::npos)
            fail(path, ":", line, ": INR header line without KEY=VALUE: '", l, "'");
        const std::string_view key = trim(l.substr(0, eq)), value = trim(l.substr(eq + 1));
        const auto number = [&](auto& v, const char* what) {
            if (!parseWhole(value, v))
                fail(path, ":", line, ": INR ", what, " must be a number, got '", value, "'");
        };
        if (key == "XDIM" || key == "YDIM" || key == "ZDIM") {
            const int a = key[0] - 'X';
            number(h.dims[a], key == "XDIM" ? "XDIM" : (key == "YDIM" ? "YDIM" : "ZDIM"));
            have[a] = true;
        } else if (key == "VDIM") {
            number(h.vdim, "VDIM");
        } else if (key == "TYPE") {
            kind = value;
        } else if (key == "PIXSIZE") {
            pixsize = value;
        } else if (key == "CPU") {
            cpu = value;
        } else if (key == "VX" || key == "VY" || key == "VZ") {
            number(h.spacing[key[1] - 'X'], key == "VX" ? "VX" : (key == "VY" ? "VY" : "VZ"));
        } else if (key == "TX" || key == "TY" || key == "TZ") {
            number(h.centre0[key[1] - 'X'], key == "TX" ? "TX" : (key == "TY" ? "TY" : "TZ"));
        }
    }
    for (int a = 0; a < 3; ++a)
        if (!have[a]) fail(path, ": INR header has no ", "XYZ"[a], "DIM");
    if (h.dims.x < 1 || h.dims.y < 1 || h.dims.z < 1)
        fail(path, ": INR dimensions must be at least 1, got ", h.dims.x, " x ", h.dims.y, " x ", h.dims.z);
    if (h.vdim != 1)
        fail(path, ": INR VDIM=", h.vdim,
             " (vector-valued voxels) is not supported, only scalar images (VDIM=1)");
    if (kind.empty()) fail(path, ": INR header has no TYPE");
    if (pixsize.empty()) fail(path, ": INR header has no PIXSIZE");
    int bits = 0;
    const std::size_t sp = pixsize.find(' ');
    if (sp == std::string_view::npos || trim(pixsize.substr(sp)) != "bits" ||
        !parseWhole(pixsize.substr(0, sp), bits))
        fail(path, ": INR PIXSIZE must read '<8|16|32|64> bits', got '", pixsize, "'");
    if (kind == "unsigned fixed" || kind == "signed fixed") {
        const bool sign = kind[0] == 's';
        if (bits == 8)
            h.type = sign ? ScalarType::Int8 : ScalarType::UInt8;
        else if (bits == 16)
            h.type = sign ? ScalarType::Int16 : ScalarType::UInt16;
        else if (bits == 32)
            h.type = sign ? ScalarType::Int32 : ScalarType::UInt32;
        else
            fail(path, ": INR ", kind, " samples of ", bits, " bits are not supported (8, 16 or 32 bits)");
    } else if (kind == "float") {
        if (bits == 32)
            h.type = ScalarType::Float32;
        else if (bits == 64)
            h.type = ScalarType::Float64;
        else
            fail(path, ": INR float samples of ", bits, " bits are not supported (32 or 64 bits)");
    } else {
        fail(path, ": INR TYPE '", kind, "' is not supported (unsigned fixed, signed fixed or float)");
    }
    if (cpu == "decm" || cpu == "pc" || cpu == "alpha")
        h.bigEndian = false;
    else if (cpu == "sun" || cpu == "sgi")
        h.bigEndian = true;
    else if (!cpu.empty())
        fail(path, ": INR CPU '", cpu, "' is unknown (decm, pc, alpha: little endian; sun, sgi: big endian)");
    else if (bits > 8)
        fail(path, ": INR header has no CPU (byte order) for ", bits, "-bit samples");
    for (int a = 0; a < 3; ++a) {
        if (!(std::isfinite(h.spacing[a]) && h.spacing[a] > 0))
            fail(path, ": INR V", "XYZ"[a], " (voxel size) must be positive and finite, got ", h.spacing[a]);
        if (!std::isfinite(h.centre0[a])) fail(path, ": INR T", "XYZ"[a], " (translation) must be finite");
    }
    return h;
}

// Where the header's "##}\n" line ends in `head`, or npos when it is not there.
std::size_t headerEnd(std::string_view head) {
    for (std::size_t p = head.find(kEnd); p != std::string_view::npos; p = head.find(kEnd, p + 1))
        if (p == 0 || head[p - 1] == '\n') return p + kEnd.size();
    return std::string_view::npos;
}

Volume makeVolume(const InrHeader& h) {
    return Volume(h.dims, h.centre0 - h.spacing * 0.5, h.spacing, h.type);
}

} // namespace

Volume readInr(std::span<const uint8_t> bytes, const std::string& path, VolumeLoadReport& report) {
    report.gzip = isGzip(bytes);
    if (!report.gzip) {
        const std::string_view all(reinterpret_cast<const char*>(bytes.data()), bytes.size());
        if (!all.starts_with(kMagic))
            fail(path, ": not an INR file (it does not start with '#INRIMAGE-4#{')");
        const std::size_t end = headerEnd(all.substr(0, kMaxHeaderBytes));
        if (end == std::string_view::npos)
            fail(path, ": INR header is truncated (no '##}' line in its first ",
                 std::min(all.size(), kMaxHeaderBytes), " bytes)");
        const InrHeader h = parseHeader(all.substr(0, end - kEnd.size()), path);
        const uint64_t expected = checkedSampleBytes(h.dims, h.type, path);
        const uint64_t available = all.size() - end;
        if (available < expected)
            fail(path, ": INR data is truncated: the file holds ", available, " of the ", expected,
                 " bytes of samples its header declares (", h.dims.x, " x ", h.dims.y, " x ", h.dims.z, " ",
                 toString(h.type), ")");
        if (available > expected)
            fail(path, ": INR file holds ", available - expected, " bytes more than the ", expected,
                 " bytes of samples its header declares (wrong sizes or type?)");
        checkVolumeMemory(h.dims, 0, path);
        Volume v = makeVolume(h);
        decodeSamples(bytes.data() + end, h.type, h.bigEndian, v, path);
        return v;
    }

    // Gzipped: inflate the header block by block, then exactly the samples it declares.
    GzipStream in(bytes, path);
    std::vector<uint8_t> head;
    std::size_t end = std::string_view::npos;
    while (end == std::string_view::npos) {
        if (head.size() >= kMaxHeaderBytes)
            fail(path, ": INR header is truncated (no '##}' line in its first ", kMaxHeaderBytes, " bytes)");
        const std::size_t old = head.size();
        head.resize(old + 256);
        const std::size_t got = in.read(head.data() + old, 256);
        head.resize(old + got);
        const std::string_view text(reinterpret_cast<const char*>(head.data()), head.size());
        if (old == 0 && !text.starts_with(kMagic))
            fail(path, ": not an INR file (its gzip data does not start with '#INRIMAGE-4#{')");
        end = headerEnd(text);
        if (end == std::string_view::npos && got < 256)
            fail(path, ": INR header is truncated (no '##}' line)");
    }
    const std::string_view text(reinterpret_cast<const char*>(head.data()), head.size());
    const InrHeader h = parseHeader(text.substr(0, end - kEnd.size()), path);
    const uint64_t expected = checkedSampleBytes(h.dims, h.type, path);
    if (expected > maxInflatedBytes(bytes.size()))
        fail(path, ": INR header declares ", expected, " bytes of samples (", h.dims.x, " x ", h.dims.y,
             " x ", h.dims.z, " ", toString(h.type), "), more than ", bytes.size(),
             " bytes of gzip data can hold (truncated or wrong sizes?)");
    checkVolumeMemory(h.dims, expected, path);
    // The samples grow with what the stream holds, from those already inflated with the header.
    const bool extraInHead = head.size() - end > expected;
    std::vector<uint8_t> data =
        inflateUpTo(in, expected, std::vector<uint8_t>(head.begin() + std::ptrdiff_t(end), head.end()));
    if (data.size() < expected)
        fail(path, ": INR data is truncated: the gzip data holds ", data.size(), " of the ", expected,
             " bytes of samples its header declares");
    uint8_t extra[1];
    if (extraInHead || in.read(extra, 1) != 0)
        fail(path, ": INR gzip data holds more than the ", expected,
             " bytes of samples its header declares (wrong sizes or type?)");
    Volume v = makeVolume(h);
    decodeSamples(data.data(), h.type, h.bigEndian, v, path);
    return v;
}

} // namespace voxfx::detail
