// voxfx_assimp — the Assimp module: the one conversion of an Assimp scene to world-space meshes,
// used both by loadMesh (glTF and the long tail of formats) and by the glTF scene loader.
//
// Assimp is asked to validate (broken indices become an error instead of a crash) and to
// fan-triangulate polygons, not to join vertices, so each mesh keeps its own vertex order. The
// node tree is walked here (not flattened by aiProcess_PreTransformVertices): every mesh instance
// gets its node's world transform, and a transform with a negative determinant (a mirror) has its
// triangles' corner order reversed, so that closed meshes stay outward-oriented.
#include <cmath>
#include <exception>
#include <string>
#include <utility>
#include <vector>

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include "io/module_api.hpp"
#include "voxfx/error.hpp"
#include "voxfx/math.hpp"

namespace voxfx::detail {

namespace {

// Node transforms compose as voxfx::Mat4d (header-only, so the module still names no voxfx symbol).
using Affine = Mat4d;

/// Determinant of the linear part: negative for a mirroring transform.
double det3(const Affine& t) {
    const auto& m = t.m;
    return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
           m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
           m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}

Affine fromAssimp(const aiMatrix4x4& a) {
    Affine t;
    const float* p = &a.a1; // row-major a1..a4, b1..b4, ...
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) t.m[r][c] = p[r * 4 + c];
    return t;
}

void convert(const aiScene* ai, AssimpScene& out) {
    out.materials.resize(ai->mNumMaterials);
    for (unsigned i = 0; i < ai->mNumMaterials; ++i) {
        aiString name;
        ai->mMaterials[i]->Get(AI_MATKEY_NAME, name);
        aiColor4D base(1, 1, 1, 1);
        ai->mMaterials[i]->Get(AI_MATKEY_BASE_COLOR, base);
        out.materials[i].name = name.C_Str();
        out.materials[i].baseColor[0] = base.r;
        out.materials[i].baseColor[1] = base.g;
        out.materials[i].baseColor[2] = base.b;
        out.materials[i].baseColor[3] = base.a;
    }
    std::vector<std::pair<const aiNode*, Affine>> stack{{ai->mRootNode, Affine{}}};
    while (!stack.empty()) {
        const auto [node, parent] = stack.back();
        stack.pop_back();
        const Affine m = parent * fromAssimp(node->mTransformation);
        for (unsigned k = node->mNumChildren; k-- > 0;) stack.push_back({node->mChildren[k], m});
        // Normals transform with the inverse transpose; a mirroring transform flips the winding.
        const double det = det3(m);
        const bool mirrored = det < 0;
        double normalMatrix[3][3]; // cofactor matrix = det * inverse transpose
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) {
                const int r1 = (r + 1) % 3, r2 = (r + 2) % 3, c1 = (c + 1) % 3, c2 = (c + 2) % 3;
                normalMatrix[r][c] = m.m[r1][c1] * m.m[r2][c2] - m.m[r1][c2] * m.m[r2][c1];
            }
        for (unsigned k = 0; k < node->mNumMeshes; ++k) {
            if (node->mMeshes[k] >= ai->mNumMeshes)
                fail("node '", node->mName.C_Str(), "' uses mesh ", node->mMeshes[k],
                     ", which does not exist");
            const aiMesh* src = ai->mMeshes[node->mMeshes[k]];
            AssimpPart part;
            part.nodeName = node->mName.C_Str();
            part.name = node->mName.length ? node->mName.C_Str() : src->mName.C_Str();
            if (node->mNumMeshes > 1) {
                part.name += '#';
                part.name += std::to_string(k);
            }
            part.material = src->mMaterialIndex;
            part.positions.reserve(3 * size_t(src->mNumVertices));
            for (unsigned v = 0; v < src->mNumVertices; ++v) {
                const aiVector3D& p = src->mVertices[v];
                const double x = p.x, y = p.y, z = p.z;
                for (int r = 0; r < 3; ++r)
                    part.positions.push_back(
                        float(m.m[r][0] * x + m.m[r][1] * y + m.m[r][2] * z + m.m[r][3]));
            }
            if (src->mNormals) {
                part.normals.reserve(3 * size_t(src->mNumVertices));
                for (unsigned v = 0; v < src->mNumVertices; ++v) {
                    const aiVector3D& n = src->mNormals[v];
                    double w[3];
                    for (int r = 0; r < 3; ++r)
                        w[r] = normalMatrix[r][0] * n.x + normalMatrix[r][1] * n.y + normalMatrix[r][2] * n.z;
                    double len = std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
                    if (mirrored) len = -len;
                    for (int r = 0; r < 3; ++r) part.normals.push_back(float(len != 0 ? w[r] / len : w[r]));
                }
            }
            part.indices.reserve(3 * size_t(src->mNumFaces));
            for (unsigned f = 0; f < src->mNumFaces; ++f) {
                const aiFace& face = src->mFaces[f];
                // After triangulation a face has 1, 2 or 3 corners: points and lines are not surfaces.
                if (face.mNumIndices != 3) {
                    ++out.skippedFaces;
                    continue;
                }
                for (int c = 0; c < 3; ++c)
                    if (face.mIndices[c] >= src->mNumVertices)
                        fail("mesh '", src->mName.C_Str(), "' face ", f, ": vertex index ", face.mIndices[c],
                             " is out of range (the mesh has ", src->mNumVertices, " vertices)");
                const unsigned i0 = face.mIndices[0], i1 = mirrored ? face.mIndices[2] : face.mIndices[1],
                               i2 = mirrored ? face.mIndices[1] : face.mIndices[2];
                part.indices.insert(part.indices.end(), {i0, i1, i2});
            }
            out.parts.push_back(std::move(part));
        }
    }
}

bool load(const char* path, AssimpScene* out, std::string* error) {
    try {
        Assimp::Importer importer;
        const aiScene* ai = importer.ReadFile(path, aiProcess_ValidateDataStructure | aiProcess_Triangulate);
        if (!ai || !ai->mRootNode) fail("Assimp could not read the file: ", importer.GetErrorString());
        *out = AssimpScene{};
        convert(ai, *out);
        return true;
    } catch (const std::bad_alloc&) { *error = "out of memory"; } catch (const std::exception& e) {
        *error = e.what();
    } catch (...) { *error = "unknown error in the Assimp module"; }
    return false;
}

bool readsExtension(const char* extension) {
    try {
        Assimp::Importer importer;
        return importer.IsExtensionSupported(std::string(".") + extension);
    } catch (...) { return false; }
}

void extensions(std::string* out) {
    out->clear();
    try {
        Assimp::Importer importer;
        std::string list; // "*.3ds;*.obj;..."
        importer.GetExtensionList(list);
        for (std::size_t i = 0; i < list.size(); ++i) {
            if (list[i] == '*') continue;
            *out += list[i] == ';' ? ' ' : list[i];
        }
    } catch (...) {}
}

constexpr AssimpModule kTable{kModuleAbi, sizeof(AssimpModule), load, readsExtension, extensions};

} // namespace
} // namespace voxfx::detail

extern "C" const void* voxfx_module_assimp(uint32_t abi) {
    return abi == voxfx::detail::kModuleAbi ? &voxfx::detail::kTable : nullptr;
}
