// voxfx — CSG on solid bit grids and CSG trees of meshes (Eisemann & Décoret, "Single-Pass GPU
// Solid Voxelization for Real-Time Applications", GI 2008, §6: Boolean operations on solid
// voxelizations are bitwise operations on the slicemaps, evaluated bottom-up over a CSG tree).
#include "voxfx/csg.hpp"

#include <algorithm>
#include <cctype>
#include <cstring>
#include <optional>

#ifdef __AVX2__
#include <immintrin.h>
#endif

#include "core/enum_names.hpp"
#include "voxfx/parallel.hpp"

namespace voxfx {

const char* toString(CsgOp op) {
    switch (op) {
    case CsgOp::Union:
        return "union";
    case CsgOp::Intersection:
        return "intersection";
    case CsgOp::Difference:
        return "difference";
    case CsgOp::Xor:
        return "xor";
    }
    return "unknown";
}

namespace {
constexpr detail::EnumName<CsgOp> kOpNames[] = {{"union", CsgOp::Union},
                                                {"intersection", CsgOp::Intersection},
                                                {"difference", CsgOp::Difference},
                                                {"xor", CsgOp::Xor},
                                                {"or", CsgOp::Union, true},
                                                {"and", CsgOp::Intersection, true},
                                                {"minus", CsgOp::Difference, true},
                                                {"sub", CsgOp::Difference, true},
                                                {"symmetric-difference", CsgOp::Xor, true}};

bool lookupCsgOp(std::string_view name, CsgOp& op) {
    const std::optional<CsgOp> found = detail::findEnum<CsgOp>(name, kOpNames);
    if (found) op = *found;
    return found.has_value();
}
const std::string kAllowedOps = detail::enumNameList<CsgOp>(kOpNames);
} // namespace

CsgOp parseCsgOp(const std::string& name) {
    return detail::parseEnum<CsgOp>(name, "CSG operation", kOpNames);
}

namespace {

void checkSameSize(const BitGrid& a, const BitGrid& b) {
    if (a.width() != b.width() || a.height() != b.height() || a.depth() != b.depth())
        fail("CSG needs grids of equal size, got ", a.width(), " x ", a.height(), " x ", a.depth(), " and ",
             b.width(), " x ", b.height(), " x ", b.depth());
}

// Words per parallel chunk (256 KiB of each operand): fixed, so the chunking does not depend on
// the thread count; large enough to amortize a task, small enough to balance two to 64 cores.
// Chunks start at multiples of 32 words, so they stay 64-byte aligned like the grids.
constexpr int64_t kChunkWords = int64_t(1) << 15;
// Outputs larger than this are written with non-temporal stores (when not in place): they go
// to memory without first reading the destination lines into the cache (the write-allocate
// read a plain store costs), and do not evict the operands. Smaller ones stay in the cache,
// where a following operation finds them (measured: streaming a 16 MiB result is slower than
// caching it, a 128 MiB one faster).
constexpr int64_t kStreamWords = int64_t(1) << 22; // 32 MiB

// o[i] = f(a[i], b[i]) for all n words, in parallel chunks. `o` may be `a` (in place): each word
// is read before it is written and no other word is involved. f is written once for words and
// for GCC vectors of four words (the operators are the same), so the loops are branch-free and
// vectorized (AVX2 with -march=x86-64-v3).
template <class F> void wordwise(const uint64_t* a, const uint64_t* b, uint64_t* o, int64_t n, F f) {
#ifdef __AVX2__
    if (o != a && n >= kStreamWords) {
        using V = uint64_t __attribute__((vector_size(32)));
        parallelFor(0, n, kChunkWords, [&](int64_t s, int64_t e) {
            int64_t i = s;
            for (; i + 4 <= e; i += 4) {
                V x, y; // unaligned-safe loads (the grids are 64-byte aligned anyway)
                std::memcpy(&x, a + i, sizeof(V));
                std::memcpy(&y, b + i, sizeof(V));
                const V r = f(x, y);
                _mm256_stream_si256(reinterpret_cast<__m256i*>(o + i), reinterpret_cast<const __m256i&>(r));
            }
            for (; i < e; ++i) o[i] = f(a[i], b[i]);
            _mm_sfence(); // the streamed words are visible before the chunk counts as done
        });
        return;
    }
#endif
    parallelFor(0, n, kChunkWords, [&](int64_t s, int64_t e) {
        for (int64_t i = s; i < e; ++i) o[i] = f(a[i], b[i]);
    });
}

// All four operations map (0, 0) to 0, so zero padding stays zero.
void apply(const uint64_t* a, const uint64_t* b, uint64_t* o, int64_t n, CsgOp op) {
    switch (op) {
    case CsgOp::Union:
        return wordwise(a, b, o, n, [](auto x, auto y) { return x | y; });
    case CsgOp::Intersection:
        return wordwise(a, b, o, n, [](auto x, auto y) { return x & y; });
    case CsgOp::Difference:
        return wordwise(a, b, o, n, [](auto x, auto y) { return x & ~y; });
    case CsgOp::Xor:
        return wordwise(a, b, o, n, [](auto x, auto y) { return x ^ y; });
    }
}

} // namespace

void csgInPlace(BitGrid& a, const BitGrid& b, CsgOp op) {
    checkSameSize(a, b);
    apply(a.words(), b.words(), a.words(), a.wordCount(), op);
}

void csg(const BitGrid& a, const BitGrid& b, CsgOp op, BitGrid& out) {
    checkSameSize(a, b);
    if (&out == &b && &out != &a) fail("CSG: the output grid may not be the second operand");
    if (&out != &a && (out.width() != a.width() || out.height() != a.height() || out.depth() != a.depth()))
        out = BitGrid(a.width(), a.height(), a.depth());
    apply(a.words(), b.words(), out.words(), a.wordCount(), op);
}

BitGrid csg(const BitGrid& a, const BitGrid& b, CsgOp op) {
    BitGrid out;
    csg(a, b, op, out);
    return out;
}

namespace {
std::string describeFrame(const Frame& f) {
    std::string s = detail::concat(f.isPerspective() ? "perspective " : "orthographic ", f.width(), " x ",
                                   f.height(), " x ", f.depth(), ", axis ", toString(f.axis()), ", ",
                                   toString(f.slicing()), " slicing");
    if (!f.isPerspective())
        s += detail::concat(", box (", f.box().lo.x, ", ", f.box().lo.y, ", ", f.box().lo.z, ") - (",
                            f.box().hi.x, ", ", f.box().hi.y, ", ", f.box().hi.z, ")");
    return s;
}
} // namespace

VoxelGrid csg(const VoxelGrid& a, const VoxelGrid& b, CsgOp op) {
    if (!a.frame.sameGrid(b.frame))
        fail("CSG needs two grids in the same frame; got [", describeFrame(a.frame), "] and [",
             describeFrame(b.frame), "] (voxelize both into one frame, e.g. with voxfx csg)");
    return {a.frame, csg(a.bits, b.bits, op)};
}

// ---- Expression parsing ------------------------------------------------------------------------

namespace {

class Parser {
public:
    explicit Parser(std::string_view text) : text_(text) {}

    CsgNode parse() {
        skipBlanks();
        if (pos_ >= text_.size()) error("expected a CSG expression, the text is empty");
        CsgNode root = text_[pos_] == '{' ? parseJsonNode() : parseFunctional();
        skipBlanks();
        if (pos_ < text_.size())
            error(detail::concat("unexpected '", text_[pos_], "' after the end of the expression"));
        return root;
    }

private:
    [[noreturn]] void error(const std::string& what) const {
        fail("CSG expression, column ", pos_ + 1, ": ", what);
    }
    void skipBlanks() {
        while (pos_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[pos_]))) ++pos_;
    }
    bool peek(char c) {
        skipBlanks();
        return pos_ < text_.size() && text_[pos_] == c;
    }
    void expect(char c, const char* context) {
        skipBlanks();
        if (pos_ >= text_.size()) error(detail::concat("expected '", c, "' ", context, ", the text ended"));
        if (text_[pos_] != c)
            error(detail::concat("expected '", c, "' ", context, ", found '", text_[pos_], "'"));
        ++pos_;
    }

    // ---- functional syntax
    CsgNode parseFunctional() {
        skipBlanks();
        CsgNode node;
        node.column = int(pos_) + 1;
        if (pos_ >= text_.size()) error("expected a mesh path or an operation, the text ended");
        if (text_[pos_] == '"') {
            node.mesh = parseQuoted();
            if (node.mesh.empty()) error("empty mesh path");
            return node;
        }
        const size_t start = pos_;
        while (pos_ < text_.size() && text_[pos_] != ',' && text_[pos_] != '(' && text_[pos_] != ')' &&
               text_[pos_] != '"')
            ++pos_;
        std::string_view word = text_.substr(start, pos_ - start);
        while (!word.empty() && std::isspace(static_cast<unsigned char>(word.back()))) word.remove_suffix(1);
        if (word.empty()) {
            if (pos_ < text_.size())
                error(detail::concat("expected a mesh path or an operation, found '", text_[pos_], "'"));
            error("expected a mesh path or an operation, the text ended");
        }
        if (pos_ < text_.size() && text_[pos_] == '(') {
            CsgOp op;
            if (!lookupCsgOp(word, op)) {
                pos_ = start;
                error(detail::concat("unknown operation '", word, "' (allowed: ", kAllowedOps, ")"));
            }
            ++pos_;
            node.isMesh = false;
            node.op = op;
            if (peek(')')) error(detail::concat(toString(op), " needs at least one argument"));
            node.args.push_back(parseFunctional());
            while (peek(',')) {
                ++pos_;
                node.args.push_back(parseFunctional());
            }
            expect(
                ')',
                detail::concat("to close ", toString(op), " (opened at column ", node.column, ")").c_str());
            return node;
        }
        node.mesh = std::string(word);
        return node;
    }

    // A double-quoted string with JSON escapes (\" \\ \/ \b \f \n \r \t \uXXXX for ASCII).
    std::string parseQuoted() {
        const size_t open = pos_;
        ++pos_;
        std::string out;
        while (true) {
            if (pos_ >= text_.size()) {
                pos_ = open;
                error("unterminated string");
            }
            const char c = text_[pos_++];
            if (c == '"') break;
            if (c != '\\') {
                out += c;
                continue;
            }
            if (pos_ >= text_.size()) error("unterminated escape in string");
            const char e = text_[pos_++];
            switch (e) {
            case '"':
                out += '"';
                break;
            case '\\':
                out += '\\';
                break;
            case '/':
                out += '/';
                break;
            case 'b':
                out += '\b';
                break;
            case 'f':
                out += '\f';
                break;
            case 'n':
                out += '\n';
                break;
            case 'r':
                out += '\r';
                break;
            case 't':
                out += '\t';
                break;
            case 'u': {
                unsigned v = 0;
                for (int i = 0; i < 4; ++i) {
                    if (pos_ >= text_.size() || !std::isxdigit(static_cast<unsigned char>(text_[pos_])))
                        error("expected four hex digits after \\u");
                    const char h = text_[pos_++];
                    v = v * 16 + unsigned(std::isdigit(static_cast<unsigned char>(h))
                                              ? h - '0'
                                              : (std::tolower(h) - 'a' + 10));
                }
                if (v >= 0x80) error("only ASCII \\u escapes are supported in paths");
                out += char(v);
                break;
            }
            default:
                --pos_;
                error(detail::concat("unknown escape '\\", e, "'"));
            }
        }
        return out;
    }

    // ---- JSON syntax: node := string | {"op": string, "args": [node, ...]}
    CsgNode parseJsonNode() {
        skipBlanks();
        CsgNode node;
        node.column = int(pos_) + 1;
        if (pos_ >= text_.size()) error("expected a string or an object, the text ended");
        if (text_[pos_] == '"') {
            node.mesh = parseQuoted();
            if (node.mesh.empty()) {
                pos_ = size_t(node.column - 1);
                error("empty mesh path");
            }
            return node;
        }
        if (text_[pos_] != '{')
            error(detail::concat("expected a string (mesh path) or an object, found '", text_[pos_], "'"));
        ++pos_;
        node.isMesh = false;
        bool haveOp = false, haveArgs = false;
        bool first = true;
        while (true) {
            skipBlanks();
            if (peek('}')) {
                if (first) error("empty object: a CSG node needs \"op\" and \"args\"");
                ++pos_;
                break;
            }
            if (!first) expect(',', "between object members");
            first = false;
            skipBlanks();
            if (pos_ >= text_.size() || text_[pos_] != '"') error("expected a member name in double quotes");
            const size_t keyPos = pos_;
            const std::string key = parseQuoted();
            expect(':', "after a member name");
            skipBlanks();
            if (key == "op") {
                if (pos_ >= text_.size() || text_[pos_] != '"') error("\"op\" must be a string");
                const size_t opPos = pos_;
                const std::string name = parseQuoted();
                if (!lookupCsgOp(name, node.op)) {
                    pos_ = opPos;
                    error(detail::concat("unknown operation '", name, "' (allowed: ", kAllowedOps, ")"));
                }
                haveOp = true;
            } else if (key == "args") {
                expect('[', "to open \"args\"");
                if (peek(']')) error("\"args\" needs at least one argument");
                node.args.push_back(parseJsonNode());
                while (peek(',')) {
                    ++pos_;
                    node.args.push_back(parseJsonNode());
                }
                expect(']', "to close \"args\"");
                haveArgs = true;
            } else {
                pos_ = keyPos;
                error(detail::concat("unknown member \"", key, "\" (a CSG node has \"op\" and \"args\")"));
            }
        }
        if (!haveOp || !haveArgs) {
            pos_ = size_t(node.column - 1);
            error(haveOp ? "object without \"args\"" : "object without \"op\"");
        }
        return node;
    }

    std::string_view text_;
    size_t pos_ = 0;
};

bool needsQuotes(const std::string& path) {
    if (path.empty()) return true;
    for (const char c : path)
        if (std::isspace(static_cast<unsigned char>(c)) || c == ',' || c == '(' || c == ')' || c == '"' ||
            c == '\\')
            return true;
    return false;
}

void appendCanonical(const CsgNode& node, std::string& out) {
    if (node.isMesh) {
        if (!needsQuotes(node.mesh)) {
            out += node.mesh;
            return;
        }
        out += '"';
        for (char c : node.mesh) {
            if (c == '"' || c == '\\') out += '\\';
            out += c;
        }
        out += '"';
        return;
    }
    out += toString(node.op);
    out += '(';
    for (size_t i = 0; i < node.args.size(); ++i) {
        if (i) out += ", ";
        appendCanonical(node.args[i], out);
    }
    out += ')';
}

void collectMeshes(const CsgNode& node, std::vector<std::string>& out) {
    if (node.isMesh) {
        if (std::find(out.begin(), out.end(), node.mesh) == out.end()) out.push_back(node.mesh);
        return;
    }
    for (const CsgNode& a : node.args) collectMeshes(a, out);
}

} // namespace

CsgNode parseCsgExpression(std::string_view text) { return Parser(text).parse(); }

std::string toString(const CsgNode& node) {
    std::string out;
    appendCanonical(node, out);
    return out;
}

std::vector<std::string> csgMeshes(const CsgNode& node) {
    std::vector<std::string> out;
    collectMeshes(node, out);
    return out;
}

BitGrid evaluateCsg(const CsgNode& node, const std::function<BitGrid(const std::string&)>& leaf) {
    if (node.isMesh) return leaf(node.mesh);
    if (node.args.empty()) fail("CSG operation ", toString(node.op), " without arguments");
    BitGrid acc = evaluateCsg(node.args[0], leaf);
    for (size_t i = 1; i < node.args.size(); ++i) {
        const BitGrid next = evaluateCsg(node.args[i], leaf);
        csgInPlace(acc, next, node.op);
    }
    return acc;
}

VoxelGrid voxelizeCsg(const CsgNode& node, const std::vector<CsgMesh>& meshes, const FitOptions& fit,
                      const VoxelizeOptions& voxelize) {
    const std::vector<std::string> names = csgMeshes(node);
    Box3d bounds;
    for (const std::string& name : names) {
        auto it =
            std::find_if(meshes.begin(), meshes.end(), [&](const CsgMesh& m) { return m.path == name; });
        if (it == meshes.end()) fail("CSG expression names mesh '", name, "', which was not given");
        validateMesh(it->mesh, name);
        bounds.extend(computeBounds(it->mesh));
    }
    FitOptions f = fit;
    if (f.bounds.empty()) f.bounds = bounds;
    if (f.bounds.empty()) fail("CSG: the meshes have no triangles, nothing to fit a grid to");
    const Frame frame = fitFrame(f.bounds, f);
    BitGrid bits = evaluateCsg(node, [&](const std::string& name) {
        const CsgMesh& m =
            *std::find_if(meshes.begin(), meshes.end(), [&](const CsgMesh& x) { return x.path == name; });
        VoxelizeOptions vo = voxelize;
        vo.mode = VoxelizeMode::Solid;
        vo.fill = m.fill;
        vo.slicing = Slicing::Uniform;
        return std::move(voxfx::voxelize(m.mesh, frame, vo).bits);
    });
    return {frame, std::move(bits)};
}

} // namespace voxfx
