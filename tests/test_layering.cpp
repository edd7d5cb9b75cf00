// The layering of the library, checked against what docs/ARCHITECTURE.md states: the table under
// "## Layers" lists the layers bottom up, each with its source folders and public headers. Every
// #include "..." of src/ and include/voxfx/ is resolved to a layer, and a file may include only its
// own layer and the layers below it (which also rules out cycles between folders of different
// layers: every edge of such a cycle cannot point downwards); folders of one row may include each
// other, but not in a cycle (cuda -> voxelize -> cuda). The document is the oracle: a folder
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

/// The folder under src/ of a tree file ("" for a public header).
std::string srcFolderOf(const std::string& rel) {
    if (rel.rfind("src/", 0) != 0) return {};
    return rel.substr(4, rel.find('/', 4) - 4);
}

/// Includes between two distinct folders of one layer row: folder -> folder it includes, with the
/// first include seen for each edge ("src/cuda/a.cu includes voxelize/b.hpp").
struct RowFolderGraph {
    std::map<std::string, std::map<std::string, std::string>> edges;

    /// Adds the edge of `file` including `inc` (resolved to `target`) when both are in src/, in
    /// different folders of one row.
    void add(const Layering& l, const std::string& file, const std::string& inc, const std::string& target) {
        const std::string from = srcFolderOf(file), to = srcFolderOf(target);
        if (from.empty() || to.empty() || from == to) return;
        const auto a = l.folderLayer.find(from), b = l.folderLayer.find(to);
        if (a == l.folderLayer.end() || b == l.folderLayer.end() || a->second != b->second) return;
        edges[from].emplace(to, file + " includes " + inc);
    }

    /// A cycle of folders, first folder repeated at the end ("cuda", "voxelize", "cuda"); empty when
    /// there is none. Depth-first, in name order, so the answer is the same on every run.
    std::vector<std::string> findCycle() const {
        std::map<std::string, int> state; // 1: on the path, 2: done
        std::vector<std::string> path;
        std::vector<std::string> cycle;
        const auto visit = [&](const auto& self, const std::string& f) -> void {
            state[f] = 1;
            path.push_back(f);
            if (const auto it = edges.find(f); it != edges.end())
                for (const auto& [to, why] : it->second) {
                    if (!cycle.empty()) break;
                    if (state[to] == 1) {
                        cycle.assign(std::find(path.begin(), path.end(), to), path.end());
                        cycle.push_back(to);
                    } else if (state[to] == 0) {
                        self(self, to);
                    }
                }
            path.pop_back();
            state[f] = 2;
        };
        for (const auto& [f, out] : edges)
            if (cycle.empty() && state[f] == 0) visit(visit, f);
        return cycle;
    }

    /// "cuda -> voxelize -> cuda (src/cuda/a.cu includes ...; src/voxelize/b.cpp includes ...)".
    std::string describe(const std::vector<std::string>& cycle) const {
        std::string names, why;
        for (std::size_t i = 0; i < cycle.size(); ++i) {
            names += (i ? " -> " : "") + cycle[i];
            if (i + 1 < cycle.size()) why += (i ? "; " : "") + edges.at(cycle[i]).at(cycle[i + 1]);
        }
        return names + " (" + why + ")";
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

TEST(LayeringTest, NoCycleBetweenTheFoldersOfOneLayerRow) {
    // The row check lets a folder include another of its own row either way, so a row of several
    // folders could hide a cycle between them: none may have one.
    const Layering l = parseArchitecture(readText(kRoot / "docs/ARCHITECTURE.md"));
    const Resolver r{l};
    RowFolderGraph g;
    for (const std::string& file : sourceFiles())
        for (const std::string& inc : includesOf(kRoot / file))
            if (const std::string target = r.resolve(file, inc); !target.empty()) g.add(l, file, inc, target);
    const std::vector<std::string> cycle = g.findCycle();
    EXPECT_TRUE(cycle.empty()) << "a cycle between folders of one layer row of docs/ARCHITECTURE.md: "
                               << g.describe(cycle);
}

TEST(LayeringTest, TheCycleCheckFindsACycle) {
    // A made-up row of two folders that include each other, and a third folder in a row above.
    const Layering l = parseArchitecture("## Layers\n\n| layer | folders | public headers |\n|---|---|---|\n"
                                         "| voxelize | `voxelize`, `cuda` | `voxelize.hpp` |\n"
                                         "| grid | `grid` | `csg.hpp` |\n");
    RowFolderGraph g;
    g.add(l, "src/cuda/cuda_module.cu", "voxelize/consumers.hpp", "src/voxelize/consumers.hpp");
    g.add(l, "src/grid/ops.cpp", "cuda/cuda_api.hpp", "src/cuda/cuda_api.hpp");      // another row: no edge
    g.add(l, "src/voxelize/fill.cpp", "voxelize/fill.hpp", "src/voxelize/fill.hpp"); // one folder: none
    EXPECT_TRUE(g.findCycle().empty());
    g.add(l, "src/voxelize/device.cpp", "cuda/cuda_api.hpp", "src/cuda/cuda_api.hpp");
    const std::vector<std::string> cycle = g.findCycle();
    EXPECT_EQ(cycle, (std::vector<std::string>{"cuda", "voxelize", "cuda"}));
    EXPECT_EQ(g.describe(cycle),
              "cuda -> voxelize -> cuda (src/cuda/cuda_module.cu includes "
              "voxelize/consumers.hpp; src/voxelize/device.cpp includes cuda/cuda_api.hpp)");
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
