// voxfx tests — deep shadow maps (voxfx/dsm.hpp): visibility functions, ε-compression, the fixed
// and chunked storages and their lookups. Oracles: a direct evaluation of the events (products of
// per-surface and per-segment transmittances), an independent linear-scan evaluator of node lists
// with both one-sided limits at steps, brute-force counts, and properties (ε-band, monotonicity).
#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "voxfx/dsm.hpp"
#include "voxfx/error.hpp"
#include "voxfx/parallel.hpp"

namespace voxfx {
namespace {

// Rounding slack: nodes are stored as floats.
constexpr double kTol = 2e-6;

// Independent evaluator: value of the node list just before (left) or just after (right) depth d.
double evalSide(const std::vector<DsmNode>& n, double d, bool right) {
    if (n.empty()) return 1.0;
    if (right) {
        int64_t i = -1;
        for (size_t k = 0; k < n.size(); ++k)
            if (double(n[k].z) <= d) i = int64_t(k);
        if (i < 0) return n.front().v;
        if (i + 1 == int64_t(n.size())) return n.back().v;
        const DsmNode a = n[size_t(i)], b = n[size_t(i) + 1];
        return a.v + (d - a.z) / (double(b.z) - a.z) * (double(b.v) - a.v);
    }
    size_t j = n.size();
    for (size_t k = n.size(); k-- > 0;)
        if (double(n[k].z) >= d) j = k;
    if (j == n.size()) return n.back().v;
    if (j == 0) return n.front().v;
    const DsmNode a = n[j - 1], b = n[j];
    if (double(b.z) == d) return b.v;
    return a.v + (d - a.z) / (double(b.z) - a.z) * (double(b.v) - a.v);
}

// Random surfaces and volume segments, overlapping freely, in depths [0, 100].
std::vector<DsmEvent> randomEvents(std::mt19937& rng) {
    std::uniform_real_distribution<float> depth(0.0f, 100.0f), unit(0.0f, 1.0f);
    std::uniform_int_distribution<int> count(0, 12), samples(1, 40);
    std::vector<DsmEvent> ev;
    const int surfaces = count(rng), volumes = count(rng) / 3;
    for (int i = 0; i < surfaces; ++i) {
        DsmEvent e;
        e.kind = DsmEvent::Kind::Surface;
        e.z0 = e.z1 = depth(rng);
        const float r = unit(rng);
        e.alpha = r < 0.1f ? 1.0f : (r < 0.2f ? 0.0f : unit(rng) * 0.6f);
        ev.push_back(e);
    }
    for (int i = 0; i < volumes; ++i) {
        DsmEvent e;
        e.kind = DsmEvent::Kind::Volume;
        e.z0 = depth(rng);
        e.z1 = std::min(100.0f, e.z0 + depth(rng) * 0.3f);
        e.sigma = unit(rng) * 0.2f;
        e.samples = samples(rng);
        ev.push_back(e);
    }
    return ev;
}

std::vector<DsmNode> build(const std::vector<DsmEvent>& ev, double eps) {
    std::vector<DsmNode> out;
    buildVisibility(ev, eps, out);
    return out;
}

// Depths to compare two functions at: every node depth of both (both sides), midpoints between
// consecutive distinct depths, and dense uniform samples.
std::vector<double> probeDepths(const std::vector<DsmNode>& a, const std::vector<DsmNode>& b) {
    std::vector<double> d;
    for (const auto& n : a) d.push_back(n.z);
    for (const auto& n : b) d.push_back(n.z);
    std::sort(d.begin(), d.end());
    d.erase(std::unique(d.begin(), d.end()), d.end());
    const size_t k = d.size();
    for (size_t i = 0; i + 1 < k; ++i)
        for (double t : {0.25, 0.5, 0.75}) d.push_back(d[i] + t * (d[i + 1] - d[i]));
    for (int i = 0; i <= 400; ++i) d.push_back(-1.0 + 102.0 * i / 400.0);
    return d;
}

// Largest |a - b| over the probe depths, both one-sided limits.
double maxDeviation(const std::vector<DsmNode>& a, const std::vector<DsmNode>& b) {
    double worst = 0;
    for (double z : probeDepths(a, b))
        for (bool right : {false, true})
            worst = std::max(worst, std::abs(evalSide(a, z, right) - evalSide(b, z, right)));
    return worst;
}

void expectNonIncreasing(const std::vector<DsmNode>& n) {
    for (size_t i = 0; i < n.size(); ++i) {
        ASSERT_LE(n[i].v, 1.0f);
        ASSERT_GE(n[i].v, 0.0f);
        if (i > 0) {
            ASSERT_GE(n[i].z, n[i - 1].z) << i;
            ASSERT_LE(n[i].v, n[i - 1].v) << i;
        }
    }
}

TEST(Dsm, ExactFunctionMatchesDirectEvaluationOfTheEvents) {
    // Disjoint volume segments, surfaces outside them: V(z) is the product of every surface in
    // front of z and of each segment's transmittance, linear between the segment's samples.
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    for (int f = 0; f < 500; ++f) {
        std::vector<double> cuts;
        for (int i = 0; i < 8; ++i) cuts.push_back(std::round(unit(rng) * 1000.0) / 10.0);
        std::sort(cuts.begin(), cuts.end());
        std::vector<DsmEvent> ev;
        for (int i = 0; i + 1 < 8; i += 2) {
            if (cuts[size_t(i)] == cuts[size_t(i) + 1]) continue;
            DsmEvent e;
            e.kind = DsmEvent::Kind::Volume;
            e.z0 = float(cuts[size_t(i)]);
            e.z1 = float(cuts[size_t(i) + 1]);
            e.sigma = float(unit(rng) * 0.3);
            e.samples = 1 + int(unit(rng) * 20);
            ev.push_back(e);
        }
        for (int i = 0; i < 6; ++i) {
            const float z = float(unit(rng) * 100.0);
            bool inside = false;
            for (const auto& e : ev) inside = inside || (z >= e.z0 && z <= e.z1);
            if (inside) continue;
            DsmEvent e;
            e.z0 = e.z1 = z;
            e.alpha = float(unit(rng));
            ev.push_back(e);
        }
        const auto direct = [&](double z, bool right) {
            double v = 1;
            for (const auto& e : ev) {
                if (e.kind == DsmEvent::Kind::Surface) {
                    if (e.z0 < z || (right && e.z0 == z)) v *= 1.0 - e.alpha;
                    continue;
                }
                const double dz = (double(e.z1) - e.z0) / e.samples;
                if (z <= e.z0) continue;
                if (z >= e.z1) {
                    v *= std::pow(std::exp(-double(e.sigma) * dz), e.samples);
                    continue;
                }
                const double s = (z - e.z0) / dz;
                const double k = std::min(std::floor(s), double(e.samples - 1));
                const double a = std::pow(std::exp(-double(e.sigma) * dz), k);
                const double b = a * std::exp(-double(e.sigma) * dz);
                v *= a + (s - k) * (b - a);
            }
            return v;
        };
        const auto exact = build(ev, -1);
        const auto comp = build(ev, 0.05);
        for (int i = 0; i <= 2000; ++i) {
            const double z = -1.0 + 102.0 * i / 2000.0;
            for (bool right : {false, true}) {
                ASSERT_NEAR(evalSide(exact, z, right), direct(z, right), 1e-5)
                    << "function " << f << " z " << z;
                ASSERT_NEAR(evalSide(comp, z, right), direct(z, right), 0.05 + 1e-5)
                    << "function " << f << " z " << z;
            }
        }
        for (const auto& e : ev)
            for (bool right : {false, true})
                ASSERT_NEAR(evalSide(exact, e.z0, right), direct(e.z0, right), 1e-5) << "function " << f;
    }
}

TEST(Dsm, CompressedStaysWithinEpsilonEverywhereAndNonIncreasing) {
    std::mt19937 rng(1);
    int64_t checked = 0;
    for (int f = 0; f < 3000; ++f) {
        const auto ev = randomEvents(rng);
        const auto exact = build(ev, -1);
        expectNonIncreasing(exact);
        for (double eps : {0.0, 0.01, 0.05, 0.1, 0.2, 0.5}) {
            const auto comp = build(ev, eps);
            expectNonIncreasing(comp);
            ASSERT_LE(maxDeviation(exact, comp), eps + kTol) << "function " << f << " eps " << eps;
            ASSERT_LE(comp.size(), exact.size()) << "compression never adds nodes";
            ASSERT_EQ(exact.empty(), comp.empty());
            ++checked;
        }
    }
    EXPECT_EQ(checked, 3000 * 6);
}

TEST(Dsm, CompressorKeepsRandomStaircasesWithPlateausInTheBand) {
    // Node lists straight into the compressor: random non-increasing values with plateaus, steps
    // (equal depths) and ramps of random length, the shapes where a segment may end below the
    // function and a later line could otherwise rise.
    std::mt19937 rng(9);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    for (int f = 0; f < 3000; ++f) {
        std::vector<DsmNode> exact;
        double z = unit(rng), v = 1;
        for (int i = 0, n = 2 + int(unit(rng) * 40); i < n; ++i) {
            exact.push_back({float(z), float(v)});
            const double r = unit(rng);
            if (r < 0.3) { // plateau
            } else if (r < 0.5) {
                v *= unit(rng); // step at the same depth
                exact.push_back({float(z), float(v)});
            } else {
                v *= 1 - 0.3 * unit(rng); // ramp
            }
            z += unit(rng) < 0.1 ? 1e-4 : unit(rng) * 5;
        }
        for (double eps : {0.0, 0.02, 0.1, 0.3}) {
            std::vector<DsmNode> comp;
            DsmCompressor c(eps, comp);
            for (const auto& n : exact) c.push(n.z, n.v);
            c.finish();
            expectNonIncreasing(comp);
            ASSERT_LE(maxDeviation(exact, comp), eps + kTol) << "function " << f << " eps " << eps;
        }
    }
    // A segment that must end below a plateau (exact binary values, ε = 1/8): the first segment
    // ends at z = 2 about 0.1 under V = 0.25, and the next line may not rise back towards it.
    std::vector<DsmNode> comp;
    DsmCompressor c(0.125, comp);
    for (const auto& n :
         std::vector<DsmNode>{{0, 1}, {1, 0.5f}, {1.5f, 0.25f}, {2, 0.25f}, {3, 0.25f}, {4, 0.25f}})
        c.push(n.z, n.v);
    c.finish();
    ASSERT_GE(comp.size(), 3u);
    EXPECT_LT(comp[1].v, 0.25f - 0.05f) << "the case needs a segment ending below the plateau";
    expectNonIncreasing(comp);
}

TEST(Dsm, LibraryLookupAgreesWithIndependentEvaluator) {
    std::mt19937 rng(2);
    std::uniform_real_distribution<float> depth(-1.0f, 101.0f);
    for (int f = 0; f < 500; ++f) {
        const auto n = build(randomEvents(rng), 0.02);
        std::vector<float> zs;
        for (const auto& x : n) zs.push_back(x.z);
        for (int i = 0; i < 200; ++i) zs.push_back(depth(rng));
        for (float z : zs)
            ASSERT_NEAR(evalVisibility(n.data(), int64_t(n.size()), z), evalSide(n, z, false), 1e-6) << f;
    }
}

TEST(Dsm, EpsilonZeroKeepsTheFunctionExact) {
    std::mt19937 rng(3);
    for (int f = 0; f < 1000; ++f) {
        const auto ev = randomEvents(rng);
        const auto exact = build(ev, -1), comp = build(ev, 0.0);
        ASSERT_LE(maxDeviation(exact, comp), kTol) << f;
    }
}

TEST(Dsm, NodeCountsShrinkAsEpsilonGrows) {
    std::mt19937 rng(4);
    const std::vector<double> eps = {0.0, 0.01, 0.05, 0.1, 0.2};
    std::vector<int64_t> total(eps.size(), 0);
    for (int f = 0; f < 2000; ++f) {
        const auto ev = randomEvents(rng);
        for (size_t i = 0; i < eps.size(); ++i) total[i] += int64_t(build(ev, eps[i]).size());
    }
    for (size_t i = 1; i < eps.size(); ++i) EXPECT_LT(total[i], total[i - 1]) << "eps " << eps[i];
    // A smooth ramp of 1000 samples compresses to a handful of nodes.
    DsmEvent e;
    e.kind = DsmEvent::Kind::Volume;
    e.z0 = 0;
    e.z1 = 10;
    e.sigma = 0.2f;
    e.samples = 1000;
    EXPECT_EQ(build({e}, -1).size(), 1001u);
    EXPECT_LT(build({e}, 0.01).size(), 12u);
}

TEST(Dsm, OpaqueSurfacesGiveTheStandardShadowMapStep) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> depth(0.0f, 100.0f);
    std::uniform_int_distribution<int> count(1, 8);
    for (int f = 0; f < 1000; ++f) {
        std::vector<DsmEvent> ev;
        float nearest = 1e30f; // the standard shadow map's depth: the nearest opaque fragment
        for (int i = count(rng); i > 0; --i) {
            DsmEvent e;
            e.z0 = e.z1 = depth(rng);
            nearest = std::min(nearest, e.z0);
            ev.push_back(e);
        }
        for (double eps : {0.0, 0.05, 0.2}) {
            const auto n = build(ev, eps);
            const auto lookup = [&](float z) { return evalVisibility(n.data(), int64_t(n.size()), z); };
            ASSERT_EQ(lookup(nearest), 1.0f) << "lit at the stored depth";
            ASSERT_EQ(lookup(std::nextafter(nearest, 1e30f)), 0.0f) << "shadowed just behind it";
            for (int i = 0; i < 50; ++i) {
                const float z = depth(rng);
                ASSERT_EQ(lookup(z), z <= nearest ? 1.0f : 0.0f) << z << " vs " << nearest;
            }
        }
    }
}

TEST(Dsm, InvalidEventsRaiseErrors) {
    std::vector<DsmNode> out;
    DsmEvent s;
    s.alpha = 1.5f;
    EXPECT_THROW(buildVisibility(std::vector<DsmEvent>{s}, 0.1, out), Error);
    s.alpha = 0.5f;
    s.z0 = std::nanf("");
    EXPECT_THROW(buildVisibility(std::vector<DsmEvent>{s}, 0.1, out), Error);
    DsmEvent v;
    v.kind = DsmEvent::Kind::Volume;
    v.z0 = 2;
    v.z1 = 1;
    EXPECT_THROW(buildVisibility(std::vector<DsmEvent>{v}, 0.1, out), Error);
    v.z1 = 3;
    v.samples = 0;
    EXPECT_THROW(buildVisibility(std::vector<DsmEvent>{v}, 0.1, out), Error);
    v.samples = 2;
    v.sigma = -1;
    EXPECT_THROW(buildVisibility(std::vector<DsmEvent>{v}, 0.1, out), Error);
    const DsmTexelFunction none = [](int64_t, int64_t, VisibilityBuilder&) {};
    DsmBuildOptions o;
    o.fixedNodes = 1;
    EXPECT_THROW(DsmFixed::build(4, 4, none, o), Error);
    o.fixedNodes = 8;
    o.epsilon = -1;
    EXPECT_THROW(DsmFixed::build(4, 4, none, o), Error);
    EXPECT_THROW(DsmChunked::build(0, 4, none, 0.1), Error);
}

// A map whose texels hold random functions seeded by their position.
DsmTexelFunction randomMap() {
    return [](int64_t x, int64_t y, VisibilityBuilder& b) {
        std::mt19937 rng(uint32_t(x * 7919 + y * 104729 + 17));
        auto ev = randomEvents(rng);
        // Feed in depth order through the builder (as a renderer would), via the sorted nodes.
        std::vector<DsmNode> exact;
        buildVisibility(ev, -1, exact);
        // Replay: steps where two nodes share a depth, ramps otherwise.
        double v = 1;
        for (size_t i = 0; i < exact.size(); ++i) {
            const DsmNode n = exact[i];
            if (i + 1 < exact.size() && exact[i + 1].z == n.z && exact[i + 1].v < n.v && n.v > 0) {
                b.ramp(n.z, n.v / v);
                b.surface(n.z, 1.0 - double(exact[i + 1].v) / n.v);
                v = exact[i + 1].v;
                ++i;
            } else {
                b.ramp(n.z, v > 0 ? n.v / v : 0.0);
                v = n.v;
            }
        }
    };
}

std::vector<DsmNode> fixedTexel(const DsmFixed& m, int64_t x, int64_t y) {
    const auto s = m.texel(x, y);
    return {s.begin(), s.end()};
}

bool sameNodes(const std::vector<DsmNode>& a, const std::vector<DsmNode>& b) {
    return a.size() == b.size() &&
           (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(DsmNode)) == 0);
}

TEST(Dsm, FixedAndChunkedStorageGiveIdenticalLookups) {
    const int64_t w = 37, h = 29; // not multiples of the 8x8 tiles
    DsmBuildOptions o;
    o.epsilon = 0.02;
    o.fixedNodes = 512; // large enough for every texel
    const auto fn = randomMap();
    const DsmFixed fixed = DsmFixed::build(w, h, fn, o);
    const DsmChunked chunked = DsmChunked::build(w, h, fn, o.epsilon);
    EXPECT_EQ(fixed.stats().overflowTexels, 0);
    EXPECT_EQ(fixed.stats().nodes, chunked.stats().nodes);
    EXPECT_EQ(fixed.stats().maxNodes, chunked.stats().maxNodes);
    int64_t longest = 0;
    for (int64_t y = 0; y < h; ++y)
        for (int64_t x = 0; x < w; ++x) {
            ASSERT_TRUE(sameNodes(fixedTexel(fixed, x, y), chunked.texel(x, y))) << x << "," << y;
            longest = std::max(longest, int64_t(chunked.texel(x, y).size()));
        }
    EXPECT_GT(longest, 0);
    std::mt19937 rng(6);
    std::uniform_real_distribution<float> depth(-1.0f, 101.0f), u(-2.0f, float(w) + 2),
        v(-2.0f, float(h) + 2);
    const auto fv = fixed.view();
    const auto cv = chunked.view();
    for (int i = 0; i < 20000; ++i) {
        const int64_t x = int64_t(rng() % uint32_t(w)), y = int64_t(rng() % uint32_t(h));
        const float z = depth(rng);
        ASSERT_EQ(fv.visibility(x, y, z), cv.visibility(x, y, z));
        const float uu = u(rng), vv = v(rng);
        ASSERT_EQ(fv.visibilityBilinear(uu, vv, z), cv.visibilityBilinear(uu, vv, z));
    }
    // At node depths too (the step edges).
    for (int64_t y = 0; y < h; ++y)
        for (int64_t x = 0; x < w; ++x)
            for (const auto& n : chunked.texel(x, y)) {
                ASSERT_EQ(fv.visibility(x, y, n.z), cv.visibility(x, y, n.z));
                ASSERT_EQ(fv.visibility(x, y, std::nextafter(n.z, 1e30f)),
                          cv.visibility(x, y, std::nextafter(n.z, 1e30f)));
            }
}

TEST(Dsm, MapTexelsMatchTheSingleFunctionBuild) {
    // The map's builder path (events fed through VisibilityBuilder) stays within ε of the exact
    // function of the texel's events.
    const auto fn = randomMap();
    const DsmChunked m = DsmChunked::build(16, 16, fn, 0.05);
    for (int64_t y = 0; y < 16; ++y)
        for (int64_t x = 0; x < 16; ++x) {
            std::mt19937 rng(uint32_t(x * 7919 + y * 104729 + 17));
            const auto exact = build(randomEvents(rng), -1);
            const auto got = m.texel(x, y);
            expectNonIncreasing(got);
            ASSERT_LE(maxDeviation(exact, got), 0.05 + 1e-5) << x << "," << y;
        }
}

TEST(Dsm, FixedStorageRebuildsOverfullTexelsWithLargerEpsilon) {
    const int64_t w = 20, h = 20;
    const auto fn = randomMap();
    DsmBuildOptions o;
    o.epsilon = 0.01;
    o.fixedNodes = 6;
    const DsmFixed fixed = DsmFixed::build(w, h, fn, o);
    const DsmChunked ref = DsmChunked::build(w, h, fn, o.epsilon);
    int64_t over = 0;
    for (int64_t y = 0; y < h; ++y)
        for (int64_t x = 0; x < w; ++x) {
            const auto want = ref.texel(x, y), got = fixedTexel(fixed, x, y);
            ASSERT_LE(got.size(), 6u);
            expectNonIncreasing(got);
            if (want.size() > 6) {
                ++over;
                std::mt19937 rng(uint32_t(x * 7919 + y * 104729 + 17));
                const auto exact = build(randomEvents(rng), -1);
                ASSERT_LE(maxDeviation(exact, got), fixed.stats().maxEpsilon + 1e-5);
            } else {
                ASSERT_TRUE(sameNodes(want, got)) << x << "," << y;
            }
        }
    EXPECT_GT(over, 0);
    EXPECT_EQ(fixed.stats().overflowTexels, over);
    EXPECT_GT(fixed.stats().maxEpsilon, o.epsilon);
    EXPECT_LE(fixed.stats().maxEpsilon, 1.0);
}

TEST(Dsm, FixedStorageSizedByTheWorstTexelHoldsEveryTexelUnchanged) {
    const int64_t w = 30, h = 22;
    const auto fn = randomMap();
    DsmBuildOptions o;
    o.epsilon = 0.05;
    o.fixedNodes = 0;
    const DsmFixed fixed = DsmFixed::build(w, h, fn, o);
    const DsmChunked chunked = DsmChunked::build(w, h, fn, o.epsilon);
    int64_t worst = 0;
    for (int64_t y = 0; y < h; ++y)
        for (int64_t x = 0; x < w; ++x) {
            ASSERT_TRUE(sameNodes(fixedTexel(fixed, x, y), chunked.texel(x, y))) << x << "," << y;
            worst = std::max(worst, int64_t(chunked.texel(x, y).size()));
        }
    EXPECT_EQ(fixed.view().n, std::max<int64_t>(2, worst));
    EXPECT_EQ(fixed.stats().overflowTexels, 0);
    EXPECT_EQ(fixed.stats().bytes,
              w * h * fixed.view().n * int64_t(sizeof(DsmNode)) + w * h * int64_t(sizeof(uint16_t)));
}

TEST(Dsm, DeepShadowMapLooksUpThroughTheChosenStorage) {
    const int64_t w = 19, h = 11;
    const auto fn = randomMap();
    DsmBuildOptions o;
    o.epsilon = 0.02;
    o.fixedNodes = 0;
    const DeepShadowMap f = DeepShadowMap::build(w, h, fn, parseDsmStorage("fixed"), o);
    const DeepShadowMap c = DeepShadowMap::build(w, h, fn, parseDsmStorage("Chunked"), o);
    EXPECT_EQ(f.storage(), DsmStorage::Fixed);
    EXPECT_EQ(c.storage(), DsmStorage::Chunked);
    EXPECT_EQ(f.view().storage, DsmStorage::Fixed);
    EXPECT_EQ(c.view().storage, DsmStorage::Chunked);
    EXPECT_EQ(parseDsmStorage(toString(DsmStorage::Fixed)), DsmStorage::Fixed);
    EXPECT_EQ(parseDsmStorage(toString(DsmStorage::Chunked)), DsmStorage::Chunked);
    EXPECT_THROW(parseDsmStorage("linked"), Error);
    EXPECT_EQ(f.stats().nodes, c.stats().nodes);
    EXPECT_GT(f.stats().bytes, c.stats().bytes);
    const DsmChunked direct = DsmChunked::build(w, h, fn, o.epsilon);
    std::mt19937 rng(10);
    std::uniform_real_distribution<float> depth(-1.0f, 101.0f), u(-1.0f, float(w) + 1),
        v(-1.0f, float(h) + 1);
    for (int i = 0; i < 5000; ++i) {
        const int64_t x = int64_t(rng() % uint32_t(w)), y = int64_t(rng() % uint32_t(h));
        const float z = depth(rng), uu = u(rng), vv = v(rng);
        ASSERT_EQ(f.view().visibility(x, y, z), direct.view().visibility(x, y, z));
        ASSERT_EQ(c.view().visibility(x, y, z), direct.view().visibility(x, y, z));
        ASSERT_EQ(f.view().visibilityBilinear(uu, vv, z), direct.view().visibilityBilinear(uu, vv, z));
        ASSERT_EQ(c.view().visibilityBilinear(uu, vv, z), direct.view().visibilityBilinear(uu, vv, z));
        ASSERT_TRUE(sameNodes(f.texel(x, y), direct.texel(x, y)));
        ASSERT_TRUE(sameNodes(c.texel(x, y), direct.texel(x, y)));
    }
}

TEST(Dsm, MemoryAccountingCountsWhatIsHeld) {
    const int64_t w = 45, h = 19;
    const auto fn = randomMap();
    DsmBuildOptions o;
    o.epsilon = 0.05;
    o.fixedNodes = 200;
    const DsmFixed fixed = DsmFixed::build(w, h, fn, o);
    const DsmChunked chunked = DsmChunked::build(w, h, fn, o.epsilon);
    EXPECT_EQ(fixed.stats().bytes,
              w * h * 200 * int64_t(sizeof(DsmNode)) + w * h * int64_t(sizeof(uint16_t)));
    // Chunks per tile: ceil(nodes of the tile's texels / 64), brute force over the texels.
    int64_t chunks = 0, nodes = 0, maxNodes = 0;
    for (int64_t ty = 0; ty < h; ty += 8)
        for (int64_t tx = 0; tx < w; tx += 8) {
            int64_t n = 0;
            for (int64_t y = ty; y < std::min(h, ty + 8); ++y)
                for (int64_t x = tx; x < std::min(w, tx + 8); ++x) {
                    const int64_t k = int64_t(fixedTexel(fixed, x, y).size());
                    n += k;
                    maxNodes = std::max(maxNodes, k);
                }
            chunks += (n + 63) / 64;
            nodes += n;
        }
    EXPECT_EQ(chunked.chunkCount(), chunks);
    EXPECT_EQ(chunked.stats().bytes,
              chunks * int64_t(sizeof(DsmChunk)) + w * h * int64_t(sizeof(DsmTexelHead)));
    EXPECT_EQ(chunked.stats().nodes, nodes);
    EXPECT_EQ(chunked.stats().maxNodes, maxNodes);
    EXPECT_LT(chunked.stats().bytes, fixed.stats().bytes);
}

TEST(Dsm, MapsAreIdenticalForOneAndManyThreads) {
    const int64_t w = 53, h = 41;
    const auto fn = randomMap();
    DsmBuildOptions o;
    o.epsilon = 0.03;
    o.fixedNodes = 8; // some texels overflow and are rebuilt
    std::vector<DsmFixed> fixed(2);
    std::vector<DsmChunked> chunked(2);
    withThreads(1, [&] {
        fixed[0] = DsmFixed::build(w, h, fn, o);
        chunked[0] = DsmChunked::build(w, h, fn, o.epsilon);
    });
    withThreads(4, [&] {
        fixed[1] = DsmFixed::build(w, h, fn, o);
        chunked[1] = DsmChunked::build(w, h, fn, o.epsilon);
    });
    EXPECT_GT(fixed[0].stats().overflowTexels, 0);
    EXPECT_EQ(fixed[0].stats().overflowTexels, fixed[1].stats().overflowTexels);
    EXPECT_EQ(fixed[0].stats().maxEpsilon, fixed[1].stats().maxEpsilon);
    ASSERT_EQ(chunked[0].chunkCount(), chunked[1].chunkCount());
    const auto c0 = chunked[0].view(), c1 = chunked[1].view();
    const auto f0 = fixed[0].view(), f1 = fixed[1].view();
    EXPECT_EQ(std::memcmp(c0.heads, c1.heads, size_t(w * h) * sizeof(DsmTexelHead)), 0);
    EXPECT_EQ(std::memcmp(c0.chunks, c1.chunks, size_t(chunked[0].chunkCount()) * sizeof(DsmChunk)), 0);
    EXPECT_EQ(std::memcmp(f0.counts, f1.counts, size_t(w * h) * sizeof(uint16_t)), 0);
    EXPECT_EQ(std::memcmp(f0.nodes, f1.nodes, size_t(w * h * o.fixedNodes) * sizeof(DsmNode)), 0);
}

TEST(Dsm, BilinearLookupMatchesDirectFormula) {
    const int64_t w = 13, h = 9;
    const auto fn = randomMap();
    const DsmChunked m = DsmChunked::build(w, h, fn, 0.01);
    const auto view = m.view();
    std::mt19937 rng(8);
    std::uniform_real_distribution<double> u(-3.0, double(w) + 3), v(-3.0, double(h) + 3), depth(-1.0, 101.0);
    const auto texelValue = [&](int64_t x, int64_t y, double z) {
        x = std::clamp<int64_t>(x, 0, w - 1);
        y = std::clamp<int64_t>(y, 0, h - 1);
        return evalSide(m.texel(x, y), z, false);
    };
    for (int i = 0; i < 5000; ++i) {
        // Texel centres at integer + 0.5; outside the map the border texels extend.
        const double uu = u(rng), vv = v(rng), z = depth(rng);
        const double cx = std::clamp(uu - 0.5, -1.0, double(w)), cy = std::clamp(vv - 0.5, -1.0, double(h));
        const double x0 = std::floor(cx), y0 = std::floor(cy), tx = cx - x0, ty = cy - y0;
        const auto X = int64_t(x0), Y = int64_t(y0);
        const double want = (1 - ty) * ((1 - tx) * texelValue(X, Y, z) + tx * texelValue(X + 1, Y, z)) +
                            ty * ((1 - tx) * texelValue(X, Y + 1, z) + tx * texelValue(X + 1, Y + 1, z));
        ASSERT_NEAR(view.visibilityBilinear(float(uu), float(vv), float(z)), want, 1e-5) << uu << "," << vv;
    }
    // At a texel centre the lookup is that texel's value.
    for (int64_t y = 0; y < h; ++y)
        for (int64_t x = 0; x < w; ++x)
            ASSERT_EQ(view.visibilityBilinear(float(x) + 0.5f, float(y) + 0.5f, 50.0f),
                      view.visibility(x, y, 50.0f));
}

} // namespace
} // namespace voxfx
