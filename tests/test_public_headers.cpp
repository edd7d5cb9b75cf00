// What a program that renders compiles: the include closure of voxfx/render.hpp, followed through
// the #include lines of include/voxfx/, against what docs/ARCHITECTURE.md ("## Public headers")
// states it is: the voxfx headers and the standard headers, both lists. The document is the oracle:
// a technique header (shadow.hpp, glass.hpp, gbuffer.hpp, ...) or a standard header such as
// <algorithm> that reaches render.hpp fails the test, and so does a listed header that no longer
// comes, so the list stays true. Nearly all of such a program's compile time is standard headers
// (BENCHMARKS.md, "#36 public headers"), which is why they are listed too.
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "test_util.hpp"

namespace {

namespace public_headers {

const std::string kRoot = VOXFX_SOURCE_DIR;

/// What the document says render.hpp brings.
struct Stated {
    std::set<std::string> voxfx; ///< "render.hpp", ...
    std::set<std::string> std;   ///< "<vector>", ...
};

/// The backquoted names of the bullets "- voxfx headers: ..." and "- standard headers: ..." under
/// "## Public headers" (a bullet goes on over its continuation lines).
Stated parseStated(const std::string& doc) {
    Stated s;
    std::stringstream in(doc);
    bool inSection = false;
    std::set<std::string>* into = nullptr;
    for (std::string line; std::getline(in, line);) {
        if (line.rfind("## ", 0) == 0) inSection = line.rfind("## Public headers", 0) == 0;
        if (!inSection) continue;
        if (line.rfind("- voxfx headers:", 0) == 0)
            into = &s.voxfx;
        else if (line.rfind("- standard headers:", 0) == 0)
            into = &s.std;
        else if (line.empty() || line.rfind("- ", 0) == 0)
            into = nullptr;
        if (!into) continue;
        for (std::size_t a = line.find('`'); a != std::string::npos; a = line.find('`', a + 1)) {
            const std::size_t b = line.find('`', a + 1);
            if (b == std::string::npos) break;
            into->insert(line.substr(a + 1, b - a - 1));
            a = b;
        }
    }
    return s;
}

/// The closure of include/voxfx/HEADER: each voxfx header reached (without "voxfx/") and each other
/// include ("<vector>", or "\"name\"" for a quoted one outside voxfx/), each with the header
/// that first included it.
struct Closure {
    std::map<std::string, std::string> voxfx, other;
};

void closureOf(const std::string& header, Closure& c) {
    std::vector<std::string> todo{header};
    c.voxfx[header] = "(the program)";
    while (!todo.empty()) {
        const std::string h = todo.back();
        todo.pop_back();
        std::stringstream in(voxfx::test::readFileBytes(kRoot + "/include/voxfx/" + h));
        for (std::string line; std::getline(in, line);) {
            const std::size_t hash = line.find_first_not_of(" \t");
            if (hash == std::string::npos || line.compare(hash, 8, "#include") != 0) continue;
            const std::size_t open = line.find_first_of("<\"", hash + 8);
            const std::size_t close = line.find(line[open] == '<' ? '>' : '"', open + 1);
            ASSERT_NE(close, std::string::npos) << h << ": " << line;
            const std::string name = line.substr(open + 1, close - open - 1);
            if (name.rfind("voxfx/", 0) == 0) {
                if (c.voxfx.emplace(name.substr(6), h).second) todo.push_back(name.substr(6));
            } else {
                c.other.emplace(line[open] == '<' ? "<" + name + ">" : "\"" + name + "\"", h);
            }
        }
    }
}

/// Both ways: what the closure has that the document does not state, and what it states that the
/// closure lacks.
void expectSame(const std::map<std::string, std::string>& got, const std::set<std::string>& stated,
                const char* what) {
    for (const auto& [name, from] : got)
        EXPECT_TRUE(stated.count(name))
            << "render.hpp brings " << what << " " << name << " (included by " << from
            << "), which docs/ARCHITECTURE.md's \"Public headers\" does not list";
    for (const std::string& name : stated)
        EXPECT_TRUE(got.count(name)) << "docs/ARCHITECTURE.md lists " << what << " " << name
                                     << " under \"Public headers\", but render.hpp no longer brings it";
}

} // namespace public_headers

TEST(PublicHeaders, RenderHeaderBringsExactlyTheHeadersTheArchitectureLists) {
    using namespace public_headers;
    const Stated stated = parseStated(voxfx::test::readFileBytes(kRoot + "/docs/ARCHITECTURE.md"));
    ASSERT_FALSE(stated.voxfx.empty()) << "no \"- voxfx headers:\" bullet under \"## Public headers\"";
    ASSERT_FALSE(stated.std.empty()) << "no \"- standard headers:\" bullet under \"## Public headers\"";
    Closure closure;
    ASSERT_NO_FATAL_FAILURE(closureOf("render.hpp", closure));
    expectSame(closure.voxfx, stated.voxfx, "voxfx header");
    expectSame(closure.other, stated.std, "header");
}

TEST(PublicHeaders, ClosureFollowsIncludesThroughEveryLevel) {
    // The walker itself: the umbrella reaches the techniques, and build_context.hpp, which only
    // shadow.hpp and deep_shadow.hpp include; a header reaches what its includes include, each
    // named with the header that brought it (image.hpp -> math.hpp -> error.hpp -> <sstream>), and
    // nothing else.
    using namespace public_headers;
    Closure umbrella;
    ASSERT_NO_FATAL_FAILURE(closureOf("voxfx.hpp", umbrella));
    EXPECT_TRUE(umbrella.voxfx.count("shadow.hpp"));
    EXPECT_TRUE(umbrella.voxfx.count("build_context.hpp"));
    Closure image;
    ASSERT_NO_FATAL_FAILURE(closureOf("image.hpp", image));
    EXPECT_EQ(image.voxfx.at("error.hpp"), "math.hpp");
    EXPECT_EQ(image.other.at("<sstream>"), "error.hpp");
    EXPECT_FALSE(image.voxfx.count("scene.hpp"));
}

} // namespace
