// Tests of src/grid/csg.cpp: grid CSG against per-cell Booleans on random grids (sizes that are
// not multiples of 64), frames that differ, the expression parser (both syntaxes, error
// columns), left-associative folding, and mesh CSG against CGAL's exact inside tests of the
// voxel centres (tests/cgal_oracle.hpp).
#include <filesystem>
#include <map>
#include <random>

#include <gtest/gtest.h>

#include "cgal_oracle.hpp"
#include "test_util.hpp"
#include "voxfx/csg.hpp"
#include "voxfx/grid_io.hpp"
#include "voxfx/mesh_io.hpp"

namespace voxfx {
namespace {

using test::randomBits;

TEST(CsgTest, GridOperationsMatchCellwiseBooleansOnRandomGrids) {
    for (const int64_t D : {1, 63, 64, 65, 100, 129}) {
        const BitGrid a = randomBits(5, 3, D, 0.5, uint64_t(D)),
                      b = randomBits(5, 3, D, 0.3, uint64_t(D + 99));
        for (const CsgOp op : {CsgOp::Union, CsgOp::Intersection, CsgOp::Difference, CsgOp::Xor}) {
            const BitGrid r = csg(a, b, op);
            BitGrid inPlace = a;
            csgInPlace(inPlace, b, op);
            EXPECT_EQ(inPlace, r);
            BitGrid reused = randomBits(5, 3, D, 0.5, 77); // stale bits of the right size
            const uint64_t* words = reused.words();
            csg(a, b, op, reused);
            EXPECT_EQ(reused, r);
            EXPECT_EQ(reused.words(), words);
            int64_t wrong = 0;
            for (int64_t y = 0; y < 3; ++y)
                for (int64_t x = 0; x < 5; ++x)
                    for (int64_t s = 0; s < D; ++s)
                        wrong += r.get(x, y, s) != test::csgInside(op, a.get(x, y, s), b.get(x, y, s));
            EXPECT_EQ(wrong, 0) << toString(op) << " D " << D;
            EXPECT_TRUE(test::paddingIsZero(r)) << toString(op) << " D " << D;
        }
    }
}

TEST(CsgTest, LargeGridsTakeTheStreamingPathAndStayExact) {
    // Over 2^22 words (32 MiB), so the out-of-place form streams its stores; an odd word count
    // leaves a tail after the last four-word vector. Every word against a plain loop, a sample of
    // cells against the Booleans.
    const int64_t W = 2003, H = 701, D = 130;
    BitGrid a(W, H, D), b(W, H, D);
    std::mt19937_64 rng(12);
    for (BitGrid* g : {&a, &b}) {
        for (int64_t i = 0; i < g->wordCount(); ++i) g->words()[i] = rng();
        for (int64_t c = 0; c < g->columnCount(); ++c)
            g->column(c)[g->wordsPerColumn() - 1] &= g->lastWordMask();
    }
    ASSERT_GT(a.wordCount(), int64_t(1) << 22);
    ASSERT_NE(a.wordCount() % 4, 0);
    BitGrid r;
    for (const CsgOp op : {CsgOp::Union, CsgOp::Intersection, CsgOp::Difference, CsgOp::Xor}) {
        csg(a, b, op, r);
        int64_t wrongWords = 0;
        for (int64_t i = 0; i < a.wordCount(); ++i) {
            const uint64_t x = a.words()[i], y = b.words()[i];
            const uint64_t want = op == CsgOp::Union          ? (x | y)
                                  : op == CsgOp::Intersection ? (x & y)
                                  : op == CsgOp::Difference   ? (x & ~y)
                                                              : (x ^ y);
            wrongWords += r.words()[i] != want;
        }
        EXPECT_EQ(wrongWords, 0) << toString(op);
        int64_t wrongCells = 0;
        for (int i = 0; i < 20000; ++i) {
            const int64_t x = int64_t(rng() % uint64_t(W)), y = int64_t(rng() % uint64_t(H)),
                          s = int64_t(rng() % uint64_t(D));
            wrongCells += r.get(x, y, s) != test::csgInside(op, a.get(x, y, s), b.get(x, y, s));
        }
        EXPECT_EQ(wrongCells, 0) << toString(op);
        EXPECT_TRUE(test::paddingIsZero(r)) << toString(op);
    }
}

TEST(CsgTest, GridsOfDifferentFramesOrSizesAreAClearError) {
    const Box3d box{{0, 0, 0}, {1, 1, 1}};
    const VoxelGrid a{Frame::orthographic(box, Axis::Z, 4, 4, 4), BitGrid(4, 4, 4)};
    const VoxelGrid moved{Frame::orthographic({{0, 0, 0.5}, {1, 1, 1.5}}, Axis::Z, 4, 4, 4),
                          BitGrid(4, 4, 4)};
    const VoxelGrid otherAxis{Frame::orthographic(box, Axis::X, 4, 4, 4), BitGrid(4, 4, 4)};
    for (const VoxelGrid* b : {&moved, &otherAxis}) {
        try {
            csg(a, *b, CsgOp::Union);
            ADD_FAILURE() << "expected an error";
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find("same frame"), std::string::npos) << e.what();
        }
    }
    EXPECT_THROW(csg(BitGrid(4, 4, 4), BitGrid(4, 4, 5), CsgOp::Union), Error);
    EXPECT_EQ(csg(a, a, CsgOp::Xor).bits.count(), 0);
}

TEST(CsgTest, ParserReadsBothSyntaxesIntoTheSameTree) {
    const CsgNode f = parseCsgExpression(" difference( bunny.off , union(a.stl,\"b c.stl\") ) ");
    const CsgNode j = parseCsgExpression(
        R"({"op":"difference","args":["bunny.off",{"op":"union","args":["a.stl","b c.stl"]}]})");
    EXPECT_EQ(toString(f), "difference(bunny.off, union(a.stl, \"b c.stl\"))");
    EXPECT_EQ(toString(j), toString(f));
    EXPECT_EQ(csgMeshes(f), (std::vector<std::string>{"bunny.off", "a.stl", "b c.stl"}));
    // Aliases, n-ary nodes, a bare path, and a path that looks like an operation name.
    EXPECT_EQ(toString(parseCsgExpression("AND(x, y, z)")), "intersection(x, y, z)");
    EXPECT_EQ(toString(parseCsgExpression("meshes/dir with space/m.off")), "\"meshes/dir with space/m.off\"");
    EXPECT_EQ(toString(parseCsgExpression("xor(union, \"a,b\")")), "xor(union, \"a,b\")");
    // The round trip of the canonical form is a fixed point.
    EXPECT_EQ(toString(parseCsgExpression(toString(f))), toString(f));
}

std::string parseError(const std::string& text) {
    try {
        parseCsgExpression(text);
    } catch (const Error& e) { return e.what(); }
    return "no error";
}

TEST(CsgTest, ParseErrorsNameTheColumn) {
    // Columns are 1-based positions in the text where parsing stopped.
    EXPECT_NE(parseError("union(a.off,, b.off)").find("column 13"), std::string::npos)
        << parseError("union(a.off,, b.off)");
    EXPECT_NE(parseError("union(a.off, b.off").find("column 19"), std::string::npos)
        << parseError("union(a.off, b.off");
    EXPECT_NE(parseError("onion(a.off, b.off)").find("column 1"), std::string::npos);
    EXPECT_NE(parseError("onion(a.off, b.off)").find("unknown operation 'onion'"), std::string::npos);
    EXPECT_NE(parseError("union(a.off) x").find("column 14"), std::string::npos)
        << parseError("union(a.off) x");
    EXPECT_NE(parseError("union()").find("column 7"), std::string::npos) << parseError("union()");
    EXPECT_NE(parseError("").find("column 1"), std::string::npos);
    EXPECT_NE(parseError(R"({"op":"union","args":["a.off" "b.off"]})").find("column 31"), std::string::npos)
        << parseError(R"({"op":"union","args":["a.off" "b.off"]})");
    EXPECT_NE(parseError(R"({"op":"unite","args":["a"]})").find("at /op: unknown operation 'unite'"),
              std::string::npos)
        << parseError(R"({"op":"unite","args":["a"]})");
    EXPECT_NE(parseError(R"({"args":["a"]})").find("without \"op\""), std::string::npos);
    EXPECT_NE(parseError(R"({"op":"union","args":["a"], "extra": 1})").find("unknown member"),
              std::string::npos);
    EXPECT_NE(parseError("union(\"a.off, b.off)").find("unterminated string"), std::string::npos);
}

// The column a message must name: where `token` first stands in `text` (1-based), found by
// searching the text, not by the parser.
std::string columnOf(const std::string& text, const std::string& token) {
    return "column " + std::to_string(text.find(token) + 1) + ":";
}

TEST(CsgTest, MalformedJsonSaysWhatAndWhere) {
    // Syntax errors: the column of the character where the JSON reader stopped.
    const std::string missingComma = R"({"op":"union","args":["a.off" "b.off"]})";
    EXPECT_NE(parseError(missingComma).find(columnOf(missingComma, "\"b.off")), std::string::npos)
        << parseError(missingComma);
    const std::string trailing = R"({"op":"union","args":["a"]} x)";
    EXPECT_NE(parseError(trailing).find(columnOf(trailing, "x")), std::string::npos) << parseError(trailing);
    const std::string unclosed = R"({"op":"union","args":["a")";
    EXPECT_NE(parseError(unclosed).find("column " + std::to_string(unclosed.size() + 1)), std::string::npos)
        << parseError(unclosed);
    const std::string badLiteral = R"({"op":"union","args":[nul]})";
    EXPECT_NE(parseError(badLiteral).find("column"), std::string::npos) << parseError(badLiteral);
    EXPECT_NE(parseError(R"({"op":"union","args":["a)").find("missing closing quote"), std::string::npos)
        << parseError(R"({"op":"union","args":["a)");
    // Well-formed JSON that is no CSG tree: the JSON pointer of the node and what is wrong there.
    const auto says = [](const std::string& text, const std::string& where, const std::string& what) {
        const std::string m = parseError(text);
        EXPECT_NE(m.find("at " + where + ":"), std::string::npos) << text << " -> " << m;
        EXPECT_NE(m.find(what), std::string::npos) << text << " -> " << m;
    };
    says(R"({"op":"union","args":["a",{"op":"xor","args":["b",{"op":"nand","args":["c"]}]}]})",
         "/args/1/args/1/op", "unknown operation 'nand'");
    says(R"({"op":1,"args":["a"]})", "/op", "must be a string");
    says(R"({"op":"union","args":"a"})", "/args", "must be an array");
    says(R"({"op":"union","args":[]})", "/args", "at least one argument");
    says(R"({"op":"union","args":["a", 3]})", "/args/1", "found number");
    says(R"({"op":"union","args":["a", ""]})", "/args/1", "empty mesh path");
    says(R"({"op":"union","args":["a", {}]})", "/args/1", "empty object");
    says(R"({"op":"union"})", "the top level", "without \"args\"");
    says(R"({"op":"union","args":["a"],"extra":1})", "the top level", "unknown member \"extra\"");
}

TEST(CsgTest, JsonAcceptsBlanksNewlinesAndEscapesLikeTheFunctionalForm) {
    const CsgNode j =
        parseCsgExpression("\n  {\n \"args\" : [ \"a\\/b.off\", \"\\u0063.stl\" ],\n \"op\" : \"minus\" }\n");
    EXPECT_EQ(toString(j), "difference(a/b.off, c.stl)");
    // The functional form decodes the same JSON escapes inside quotes.
    EXPECT_EQ(toString(parseCsgExpression("minus(\"a\\/b.off\", \"\\u0063.stl\")")), toString(j));
    // nlohmann stops at the character that cannot follow the backslash.
    const std::string badEscape = "union(a, \"b\\q\")";
    EXPECT_NE(parseError(badEscape).find(columnOf(badEscape, "q\"")), std::string::npos)
        << parseError(badEscape);
}

TEST(CsgTest, NaryOperationsFoldLeft) {
    // Expected cells: the Booleans folded left to right, cell by cell (no csg() call).
    std::map<std::string, BitGrid> grids;
    for (int i = 0; i < 3; ++i)
        grids.emplace(std::string(1, char('a' + i)), randomBits(4, 3, 70, 0.5, uint64_t(i + 5)));
    auto leaf = [&](const std::string& name) { return grids.at(name); };
    const BitGrid &a = grids.at("a"), &b = grids.at("b"), &c = grids.at("c");
    struct Case {
        const char* expression;
        bool (*cell)(bool, bool, bool);
    };
    const Case cases[] = {
        {"difference(a, b, c)", [](bool x, bool y, bool z) { return (x && !y) && !z; }},
        {"xor(a, b, c)", [](bool x, bool y, bool z) { return (x != y) != z; }},
        {"union(a)", [](bool x, bool, bool) { return x; }},
        {"intersection(a, union(b, c))", [](bool x, bool y, bool z) { return x && (y || z); }},
        {"union(b, difference(c, a))", [](bool x, bool y, bool z) { return y || (z && !x); }},
    };
    for (const Case& k : cases) {
        const BitGrid r = evaluateCsg(parseCsgExpression(k.expression), leaf);
        ASSERT_EQ(r.width(), 4);
        ASSERT_EQ(r.height(), 3);
        ASSERT_EQ(r.depth(), 70);
        int64_t wrong = 0, set = 0;
        for (int64_t y = 0; y < 3; ++y)
            for (int64_t x = 0; x < 4; ++x)
                for (int64_t s = 0; s < 70; ++s) {
                    const bool want = k.cell(a.get(x, y, s), b.get(x, y, s), c.get(x, y, s));
                    wrong += r.get(x, y, s) != want;
                    set += want;
                }
        EXPECT_EQ(wrong, 0) << k.expression;
        EXPECT_GT(set, 0) << k.expression;
        EXPECT_TRUE(test::paddingIsZero(r)) << k.expression;
    }
}

// Mesh CSG against the CGAL oracle: every mesh's inside test of the voxel centres, combined with
// the same Booleans, must equal the grid result everywhere except at centres the oracle leaves
// out (centres exactly on a surface).
void expectCsgMatchesOracle(const std::string& expression, const std::map<std::string, const Mesh*>& meshes,
                            int64_t resolution) {
    const CsgNode root = parseCsgExpression(expression);
    std::vector<CsgMesh> list;
    for (const auto& [name, mesh] : meshes) list.push_back({name, mesh->view(), Fill::Parity});
    FitOptions fit;
    fit.resolution = resolution;
    fit.marginCells = 1;
    const VoxelGrid grid = voxelizeCsg(root, list, fit);
    const test::CellGeometry geometry = test::CellGeometry::of(grid);
    std::map<std::string, test::SolidOracle> oracle;
    test::WorldGrid ignore(geometry.dims);
    for (const auto& [name, mesh] : meshes) {
        oracle.emplace(name, test::oracleSolid(mesh->view(), geometry));
        ASSERT_TRUE(oracle.at(name).closed) << name << " must be a closed mesh";
        for (size_t c = 0; c < ignore.cells.size(); ++c) ignore.cells[c] |= oracle.at(name).leftOut.cells[c];
    }
    // Evaluate the same tree on the oracle's cells.
    std::function<test::WorldGrid(const CsgNode&)> eval = [&](const CsgNode& n) {
        if (n.isMesh) return oracle.at(n.mesh).inside;
        test::WorldGrid acc = eval(n.args[0]);
        for (size_t i = 1; i < n.args.size(); ++i) {
            const test::WorldGrid next = eval(n.args[i]);
            for (size_t c = 0; c < acc.cells.size(); ++c)
                acc.cells[c] = test::csgInside(n.op, acc.cells[c], next.cells[c]);
        }
        return acc;
    };
    const test::WorldGrid expected = eval(root);
    const test::GridDiff d = test::compareGrids(test::toWorldGrid(grid), expected, &ignore);
    EXPECT_TRUE(d.equal()) << expression << ": " << d;
    EXPECT_GT(expected.count(), 100) << expression;
}

TEST(CsgTest, MeshCsgEqualsCgalInsideTestsOfVoxelCentres) {
    VOXFX_REQUIRE_DATA("meshes/bunny00.off");
    const Mesh bunny = loadMesh(test::dataPath("meshes/bunny00.off"));
    const Box3d bb = computeBounds(bunny.view());
    const Vec3d c = bb.center(), e = bb.extent();
    // A sphere through the bunny's middle and a slab across its lower part.
    const Mesh sphere = test::makeUvSphere(c + Vec3d{0.1 * e.x, 0, 0.05 * e.z}, 0.3 * e.x, 24, 48);
    const Mesh slab = test::makeBox(bb.lo + Vec3d{-0.1 * e.x, 0.2 * e.y, -0.1 * e.z},
                                    Vec3d{bb.hi.x + 0.1 * e.x, bb.lo.y + 0.45 * e.y, bb.hi.z + 0.1 * e.z});
    const std::map<std::string, const Mesh*> meshes{{"bunny", &bunny}, {"sphere", &sphere}, {"slab", &slab}};
    expectCsgMatchesOracle("difference(bunny, union(sphere, slab))", meshes, 48);
    expectCsgMatchesOracle("xor(bunny, sphere)", meshes, 40);
    expectCsgMatchesOracle(
        R"({"op":"intersection","args":["bunny",{"op":"union","args":["sphere","slab"]}]})", meshes, 40);
}

TEST(CsgTest, CommandLineWritesTheCgalDifferenceOfTwoMeshes) {
    test::TempDir dir;
    Mesh a = test::makeBox({0, 0, 0}, {2, 2, 2});
    Mesh b = test::makeUvSphere({2, 1, 1}, 0.8, 12, 24);
    // OFF files written by hand (the format is three lines of header plus vertices and faces).
    auto writeOff = [&](const Mesh& m, const std::string& name) {
        std::string s =
            "OFF\n" + std::to_string(m.positions.size()) + " " + std::to_string(m.triangleCount()) + " 0\n";
        for (const Vec3f& p : m.positions) s += detail::concat(p.x, " ", p.y, " ", p.z, "\n");
        for (size_t t = 0; t < m.triangleCount(); ++t)
            s += detail::concat("3 ", m.indices[3 * t], " ", m.indices[3 * t + 1], " ", m.indices[3 * t + 2],
                                "\n");
        return test::writeFile(dir.file(name), s);
    };
    const std::string pa = writeOff(a, "a.off"), pb = writeOff(b, "b.off");
    const std::string out = dir.file("out.binvox");
    const test::CommandRun run =
        test::runVoxfx(dir, "csg \"difference(" + pa + ", " + pb + ")\" -r 24 -q -o " + out);
    ASSERT_EQ(run.exitCode, 0) << run.err;
    // The file, decoded from the format's description, against CGAL's inside tests of its cell
    // centres for the meshes as read from the same files (CGAL's own OFF reader).
    const test::BinvoxFile f = test::readBinvoxBySpec(out);
    ASSERT_EQ(std::max({f.dims.x, f.dims.y, f.dims.z}), 24);
    const test::CellGeometry geometry{f.translate, Vec3d{1, 1, 1} * f.cell(), f.dims};
    const test::SolidOracle inA =
        test::oracleSolid(test::meshOfSoup(test::readWithCgal(pa)).view(), geometry);
    const test::SolidOracle inB =
        test::oracleSolid(test::meshOfSoup(test::readWithCgal(pb)).view(), geometry);
    ASSERT_TRUE(inA.closed && inB.closed);
    int64_t wrong = 0, set = 0, ignored = 0;
    for (int64_t k = 0; k < f.dims.z; ++k)
        for (int64_t j = 0; j < f.dims.y; ++j)
            for (int64_t i = 0; i < f.dims.x; ++i) {
                const size_t c = inA.inside.index(i, j, k);
                if (inA.leftOut.cells[c] || inB.leftOut.cells[c]) {
                    ++ignored;
                    continue;
                }
                const bool want = inA.inside.cells[c] && !inB.inside.cells[c];
                wrong += f.at(i, j, k) != want;
                set += want;
            }
    EXPECT_EQ(wrong, 0) << ignored << " centres on a surface left out";
    EXPECT_GT(set, 100);
    // Grid leaves: grids of one frame combine; grids of different frames are refused with a
    // message naming both.
    const std::string same = dir.file("same.binvox");
    const test::CommandRun xorRun =
        test::runVoxfx(dir, "csg \"xor(" + out + ", " + out + ")\" -q -o " + same);
    ASSERT_EQ(xorRun.exitCode, 0) << xorRun.err;
    EXPECT_EQ(test::readBinvoxBySpec(same).count(), 0);
    const std::string coarse = dir.file("coarse.binvox");
    const Mesh la = loadMesh(pa);
    FitOptions fit12;
    fit12.resolution = 12;
    writeGrid(voxelizeCsg(parseCsgExpression("a"), {{"a", la.view()}}, fit12), coarse);
    const test::CommandRun mixed =
        test::runVoxfx(dir, "csg \"union(" + out + ", " + coarse + ")\" -q -o " + same);
    EXPECT_NE(mixed.exitCode, 0);
    EXPECT_NE(mixed.err.find("different frames"), std::string::npos) << mixed.err;
    // A parse error exits non-zero and names the column.
    const test::CommandRun bad = test::runVoxfx(dir, "csg \"union(" + pa + "\" -q -o " + out);
    EXPECT_NE(bad.exitCode, 0);
    EXPECT_NE(bad.err.find("column"), std::string::npos) << bad.err;
}

} // namespace
} // namespace voxfx
