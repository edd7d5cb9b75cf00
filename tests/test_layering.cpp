// The layering of the library, checked against what docs/ARCHITECTURE.md states: the table under
// "## Layers" lists the layers bottom up, each with its source folders and public headers. Every
// #include "..." of src/ and include/voxfx/ is resolved to a layer, and a file may include only its
// own layer and the layers below it (which also rules out cycles between folders of different
// layers: every edge of such a cycle cannot point downwards). The document is the oracle: a folder
// or public header it does not place, an upward include, or a listed exception that no longer
// occurs fails the test, so the document and the code cannot drift apart. The umbrella header must
// reach every public header.
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace {

namespace fs = std::filesystem;

const fs::path kRoot = VOXFX_SOURCE_DIR;

std::string readText(const fs::path& p) {
    std::ifstream in(p);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

std::string trim(std::string s) {
    const auto notSpace = [](char c) { return c != ' ' && c != '`' && c != '\t'; };
    s.erase(s.begin(), std::find_if(s.begin(), s.end(), notSpace));
    s.erase(std::find_if(s.rbegin(), s.rend(), notSpace).base(), s.end());
    return s;
}

std::vector<std::string> split(const std::string& s, char sep) {
    std::vector<std::string> out;
    std::stringstream in(s);
    for (std::string item; std::getline(in, item, sep);)
        if (const std::string t = trim(item); !t.empty() && t != "-") out.push_back(t);
    return out;
}

/// The layers as the document states them.
struct Layering {
    std::vector<std::string> layers;                          ///< bottom up
    std::map<std::string, int> folderLayer;                   ///< "render" -> index (folders under src/)
    std::map<std::string, int> headerLayer;                   ///< "shadow.hpp" -> index
    std::set<std::pair<std::string, std::string>> exceptions; ///< (file, include) allowed upward
};

/// Reads the first Markdown table after "## Layers" (layer | folders | public headers) and the
/// list under "### Known upward includes" (lines "- `FILE` includes `INCLUDE`").
Layering parseArchitecture(const std::string& doc) {
    Layering l;
    std::stringstream in(doc);
    std::string line;
    bool inLayers = false, inTable = false, inExceptions = false;
    while (std::getline(in, line)) {
        if (line.rfind("## ", 0) == 0) inLayers = line == "## Layers";
        if (line.rfind("### ", 0) == 0) inExceptions = line == "### Known upward includes";
        if (inLayers && line.rfind("| layer |", 0) == 0) {
            inTable = true;
            continue;
        }
        if (inTable) {
            if (line.rfind("|", 0) != 0) {
                inTable = false;
            } else if (line.rfind("|---", 0) != 0) {
                std::vector<std::string> cells;
                std::stringstream row(line.substr(1));
                for (std::string cell; std::getline(row, cell, '|');) cells.push_back(cell);
                if (cells.size() < 3) continue;
                const int index = int(l.layers.size());
                l.layers.push_back(trim(cells[0]));
                for (const std::string& f : split(cells[1], ',')) l.folderLayer[f] = index;
                for (const std::string& h : split(cells[2], ',')) l.headerLayer[h] = index;
            }
        }
        if (inExceptions && line.rfind("- `", 0) == 0) {
            const std::size_t a = line.find('`') + 1, b = line.find('`', a), c = line.find('`', b + 1) + 1,
                              d = line.find('`', c);
            if (d != std::string::npos) l.exceptions.insert({line.substr(a, b - a), line.substr(c, d - c)});
        }
    }
    return l;
}

/// The quoted includes of a file.
std::vector<std::string> includesOf(const fs::path& file) {
    std::vector<std::string> out;
    std::stringstream in(readText(file));
    for (std::string line; std::getline(in, line);) {
        const std::size_t at = line.find("#include \"");
        if (at != 0) continue;
        const std::size_t end = line.find('"', 10);
        if (end != std::string::npos) out.push_back(line.substr(10, end - 10));
    }
    return out;
}

bool isSource(const fs::path& p) {
    const std::string e = p.extension().string();
    return e == ".cpp" || e == ".hpp" || e == ".cu" || e == ".inc";
}

/// Every source file of src/ and include/voxfx/, relative to the root.
std::vector<std::string> sourceFiles() {
    std::vector<std::string> out;
    for (const char* top : {"src", "include/voxfx"})
        for (const auto& e : fs::recursive_directory_iterator(kRoot / top))
            if (e.is_regular_file() && isSource(e.path()))
                out.push_back(fs::relative(e.path(), kRoot).string());
    std::sort(out.begin(), out.end());
    return out;
}

struct Resolver {
    const Layering& l;
    /// The layer of a file of the tree (src/FOLDER/..., or a public header); -1 when the document
    /// does not place it.
    int layerOfFile(const std::string& rel) const {
        if (rel.rfind("include/voxfx/", 0) == 0) {
            const auto it = l.headerLayer.find(rel.substr(14));
            return it == l.headerLayer.end() ? -1 : it->second;
        }
        if (rel.rfind("src/", 0) == 0) {
            const std::string folder = rel.substr(4, rel.find('/', 4) - 4);
            const auto it = l.folderLayer.find(folder);
            return it == l.folderLayer.end() ? -1 : it->second;
        }
        return -1;
    }
    /// The tree file an include of `from` names ("" when it is outside the tree).
    std::string resolve(const std::string& from, const std::string& inc) const {
        if (inc.rfind("voxfx/", 0) == 0) return "include/" + inc;
        const fs::path sibling = fs::path(from).parent_path() / inc;
        if (fs::exists(kRoot / sibling)) return sibling.lexically_normal().string();
        if (fs::exists(kRoot / "src" / inc)) return "src/" + inc;
        return {};
    }
};

TEST(LayeringTest, EveryIncludeGoesToTheSameOrALowerLayerAsArchitectureMdStates) {
    const Layering l = parseArchitecture(readText(kRoot / "docs/ARCHITECTURE.md"));
    ASSERT_GE(l.layers.size(), 8u) << "no layer table under \"## Layers\" in docs/ARCHITECTURE.md";
    const Resolver r{l};
    std::set<std::pair<std::string, std::string>> seenExceptions;
    for (const std::string& file : sourceFiles()) {
        const int from = r.layerOfFile(file);
        EXPECT_GE(from, 0) << file << ": its folder or header is in no layer of docs/ARCHITECTURE.md";
        if (from < 0) continue;
        for (const std::string& inc : includesOf(kRoot / file)) {
            const std::string target = r.resolve(file, inc);
            if (target.empty()) continue; // a third-party header
            const int to = r.layerOfFile(target);
            EXPECT_GE(to, 0) << file << " includes " << inc << ", which is in no layer";
            if (to <= from) continue;
            if (l.exceptions.count({file, inc})) {
                seenExceptions.insert({file, inc});
                continue;
            }
            ADD_FAILURE() << file << " includes " << inc << ": layer " << l.layers[size_t(from)]
                          << " may not include " << l.layers[size_t(to)] << ", a layer above it "
                          << "(docs/ARCHITECTURE.md, \"## Layers\")";
        }
    }
    for (const auto& e : l.exceptions)
        EXPECT_TRUE(seenExceptions.count(e))
            << "docs/ARCHITECTURE.md lists " << e.first << " includes " << e.second
            << " as a known upward include, but it no longer is one";
}

TEST(LayeringTest, EveryPublicHeaderIsPlacedAndTheUmbrellaHeaderReachesIt) {
    const Layering l = parseArchitecture(readText(kRoot / "docs/ARCHITECTURE.md"));
    std::set<std::string> reached, todo{"include/voxfx/voxfx.hpp"};
    while (!todo.empty()) {
        const std::string f = *todo.begin();
        todo.erase(todo.begin());
        if (!reached.insert(f).second) continue;
        for (const std::string& inc : includesOf(kRoot / f))
            if (inc.rfind("voxfx/", 0) == 0) todo.insert("include/" + inc);
    }
    for (const auto& e : fs::directory_iterator(kRoot / "include/voxfx")) {
        const std::string name = e.path().filename().string();
        EXPECT_TRUE(l.headerLayer.count(name))
            << "include/voxfx/" << name << " is in no layer of docs/ARCHITECTURE.md";
        EXPECT_TRUE(reached.count("include/voxfx/" + name))
            << "voxfx.hpp does not reach include/voxfx/" << name;
    }
    for (const auto& [header, layer] : l.headerLayer)
        EXPECT_TRUE(fs::exists(kRoot / "include/voxfx" / header))
            << "docs/ARCHITECTURE.md places " << header << ", which is not in include/voxfx/";
}

TEST(LayeringTest, TheCheckFindsAnUpwardInclude) {
    // The parser and the resolver on a made-up document: render above scene, scene including render
    // is upward.
    const Layering l =
        parseArchitecture("## Layers\n\n| layer | folders | public headers |\n|---|---|---|\n"
                          "| scene | `scene` | `scene.hpp` |\n| render | `render` | `render.hpp` |\n\n"
                          "### Known upward includes\n\n- `src/scene/a.cpp` includes `voxfx/render.hpp`\n");
    ASSERT_EQ(l.layers, (std::vector<std::string>{"scene", "render"}));
    const Resolver r{l};
    EXPECT_EQ(r.layerOfFile("src/scene/scene.cpp"), 0);
    EXPECT_EQ(r.layerOfFile("include/voxfx/render.hpp"), 1);
    EXPECT_EQ(r.layerOfFile("include/voxfx/other.hpp"), -1);
    EXPECT_EQ(r.resolve("src/scene/scene.cpp", "voxfx/render.hpp"), "include/voxfx/render.hpp");
    EXPECT_TRUE(l.exceptions.count({"src/scene/a.cpp", "voxfx/render.hpp"}));
}

} // namespace
