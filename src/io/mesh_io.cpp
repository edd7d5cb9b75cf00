// voxfx — loadMesh: picks a reader by extension, then validates and cleans what it returns.
//
// OFF, OBJ, PLY and STL have dedicated readers (mesh_off/obj/ply/stl.cpp): they keep the file's
// vertices shared and in order, say which line or byte is wrong, and never trust a header count;
// Assimp aborts on some truncated files and duplicates vertices per face. glTF and everything else
// go through Assimp (mesh_assimp.cpp).
#include "voxfx/mesh_io.hpp"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <string_view>
#include <utility>

#include <sys/mman.h>
#include <sys/stat.h>

#include "io/mesh_formats.hpp"
#include "voxfx/file_name.hpp"

namespace voxfx {

namespace detail {

std::string locationPrefix(const std::string& path, FileLocation where) {
    if (where.kind == FileLocation::Kind::kLine) return concat(path, ":", where.value, ": ");
    return concat(path, ": byte ", where.value, ": ");
}

} // namespace detail

namespace {

using detail::ParsedMesh;

enum class Reader { kOff, kObj, kPly, kStl, kAssimp };

// The whole file: mapped read-only when it is a regular file (no copy into a buffer, no fresh
// pages to fault: the pages are the page cache's), read into memory otherwise (pipes, devices).
// A file truncated by another process while mapped would fault on access; files being
// rewritten under a running loader are not supported either way.
class FileBytes {
public:
    FileBytes() = default;
    FileBytes(const FileBytes&) = delete;
    FileBytes& operator=(const FileBytes&) = delete;
    FileBytes(FileBytes&& o) noexcept
        : map_(std::exchange(o.map_, nullptr)), owned_(std::move(o.owned_)), data_(o.data_),
          size_(std::exchange(o.size_, 0)) {}
    ~FileBytes() {
        if (map_) ::munmap(map_, size_);
    }
    std::string_view view() const { return {data_, size_}; }
    std::size_t size() const { return size_; }

    void map(void* mapping, std::size_t bytes) {
        map_ = mapping;
        data_ = static_cast<const char*>(mapping);
        size_ = bytes;
    }
    void own(std::unique_ptr<char[]> buffer, std::size_t bytes) {
        owned_ = std::move(buffer);
        data_ = owned_.get();
        size_ = bytes;
    }

private:
    void* map_ = nullptr;
    std::unique_ptr<char[]> owned_;
    const char* data_ = "";
    std::size_t size_ = 0;
};

using FilePtr = std::unique_ptr<std::FILE, int (*)(std::FILE*)>;

FilePtr openFile(const std::string& path) {
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) fail(path, ": cannot read mesh file: it is a directory");
    std::FILE* file = std::fopen(path.c_str(), "rb");
    if (!file) fail(path, ": cannot open mesh file: ", std::strerror(errno));
    return {file, &std::fclose};
}

FileBytes readWholeFile(const std::string& path) {
    const FilePtr owner = openFile(path);
    std::FILE* file = owner.get();
    FileBytes bytes;
    struct stat st {};
    if (::fstat(::fileno(file), &st) == 0 && S_ISREG(st.st_mode) && st.st_size > 0) {
        void* m = ::mmap(nullptr, std::size_t(st.st_size), PROT_READ, MAP_PRIVATE | MAP_POPULATE,
                         ::fileno(file), 0);
        if (m != MAP_FAILED) {
            ::madvise(m, std::size_t(st.st_size), MADV_SEQUENTIAL);
            bytes.map(m, std::size_t(st.st_size));
            return bytes;
        }
    }
    if (std::fseek(file, 0, SEEK_END) != 0) fail(path, ": cannot read mesh file: ", std::strerror(errno));
    const long size = std::ftell(file);
    if (size < 0 || std::fseek(file, 0, SEEK_SET) != 0)
        fail(path, ": cannot read mesh file: ", std::strerror(errno));
    const auto n = std::size_t(size);
    auto buffer = std::make_unique_for_overwrite<char[]>(std::max<std::size_t>(n, 1));
    if (std::fread(buffer.get(), 1, n, file) != n)
        fail(path, ": cannot read mesh file: ",
             std::ferror(file) ? std::strerror(errno) : "it got shorter while reading");
    bytes.own(std::move(buffer), n);
    return bytes;
}

Reader readerFor(const std::string& path, const std::string& ext) {
    if (ext == "off") return Reader::kOff;
    if (ext == "obj") return Reader::kObj;
    if (ext == "ply") return Reader::kPly;
    if (ext == "stl") return Reader::kStl;
    if (ext == "gltf" || ext == "glb" || (!ext.empty() && detail::assimpReadsExtension(ext)))
        return Reader::kAssimp;
    if (ext.empty())
        fail(path, ": cannot tell the mesh format: the file name has no extension (expected .off .obj .ply "
                   ".stl .gltf "
                   ".glb or another format Assimp reads)");
    fail(path, ": unknown mesh format '.", ext,
         "' (supported: .off .obj .ply .stl .gltf .glb, and through Assimp:", detail::assimpExtensions(),
         ")");
}

// The first non-finite vertex that a triangle uses, reported where the parser found it.
void checkNonFiniteVertices(const ParsedMesh& parsed, const std::string& path) {
    if (parsed.nonFiniteVertices.empty()) return;
    const Mesh& mesh = parsed.mesh;
    std::vector<uint8_t> used(mesh.positions.size(), 0);
    for (uint32_t v : mesh.indices)
        if (v < used.size()) used[v] = 1;
    for (const auto& [v, where] : parsed.nonFiniteVertices) {
        if (!used[v]) continue;
        const Vec3f& p = mesh.positions[v];
        fail(detail::locationPrefix(path, where), "vertex ", uint64_t(v) + parsed.firstVertexNumber,
             " has a non-finite coordinate (", p.x, " ", p.y, " ", p.z, ")");
    }
}

} // namespace

Mesh loadMesh(const std::string& path, MeshLoadReport* report) { return loadMesh(path, report, nullptr); }

Mesh loadMesh(const std::string& path, MeshLoadReport* report, std::vector<Vec3f>* vertexColors) {
    if (vertexColors) vertexColors->clear();
    std::string ext = fileExtension(path);
    if (!ext.empty()) ext.erase(0, 1);
    const Reader reader = readerFor(path, ext);

    Mesh mesh;
    std::size_t fileBytes = 0;
    if (reader == Reader::kAssimp) {
        // Assimp reads the file itself (a .gltf may name further buffer files); opening it here
        // first gives the same clear message as the other formats for a missing file.
        openFile(path);
        std::error_code ec;
        fileBytes = std::size_t(std::filesystem::file_size(path, ec));
        mesh = detail::loadWithAssimp(path);
    } else {
        const FileBytes bytes = readWholeFile(path);
        fileBytes = bytes.size();
        ParsedMesh parsed;
        switch (reader) {
        case Reader::kOff:
            parsed = detail::parseOff(bytes.view(), path);
            break;
        case Reader::kObj:
            parsed = detail::parseObj(bytes.view(), path);
            break;
        case Reader::kPly:
            parsed = detail::parsePly(bytes.view(), path);
            break;
        default:
            parsed = detail::parseStl(bytes.view(), path);
            break;
        }
        checkNonFiniteVertices(parsed, path);
        mesh = std::move(parsed.mesh);
        // Degenerate triangles go below, vertices never: the colours stay one per vertex.
        if (vertexColors && parsed.colors.size() == mesh.positions.size())
            *vertexColors = std::move(parsed.colors);
    }

    validateMesh(mesh.view(), path);
    const std::size_t inputTriangles = mesh.triangleCount();
    const std::size_t degenerate = removeDegenerateTriangles(mesh);
    if (mesh.triangleCount() == 0) {
        if (degenerate > 0)
            fail(path, ": no triangles with a nonzero area (all ", degenerate, " are degenerate)");
        fail(path, ": no triangles in the file");
    }
    if (report) {
        report->format = ext == "glb" ? "gltf" : ext;
        report->fileBytes = fileBytes;
        report->inputTriangles = inputTriangles;
        report->degenerateRemoved = degenerate;
    }
    return mesh;
}

} // namespace voxfx
