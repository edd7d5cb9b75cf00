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

#include <nlohmann/json.hpp>

#include "voxfx/parallel.hpp"

namespace voxfx {

const char* toString(CsgOp op) { return enumName(op, kCsgOpNames); }

namespace {
bool lookupCsgOp(std::string_view name, CsgOp& op) {
    const std::optional<CsgOp> found = findEnum<CsgOp>(name, kCsgOpNames);
    if (found) op = *found;
    return found.has_value();
}
const std::string kAllowedOps = enumNameList<CsgOp>(kCsgOpNames);
} // namespace

CsgOp parseCsgOp(const std::string& name) { return parseEnum<CsgOp>(name, "CSG operation", kCsgOpNames); }

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

[[noreturn]] void parseFail(size_t column, const std::string& what) {
    fail("CSG expression, column ", column, ": ", what);
}

// nlohmann's message without its "[json.exception.parse_error.101] parse error at line 1,
// column 7: " prefix: the caller names the position in its own terms.
std::string jsonReason(const nlohmann::json::parse_error& e) {
    const std::string what = e.what();
    const size_t colon = what.find(": ");
    return colon == std::string::npos ? what : what.substr(colon + 2);
}

// ---- JSON syntax: node := string | {"op": string, "args": [node, ...]}, read by nlohmann-json.
// Syntax errors carry nlohmann's byte position (the column of the one-line text); errors in a
// well-formed document name the node by its JSON pointer ("/args/1/op").

[[noreturn]] void jsonFail(const std::string& pointer, const std::string& what) {
    fail("CSG expression, at ", pointer.empty() ? std::string("the top level") : pointer, ": ", what);
}

// Deeper trees are refused: parsing, printing and evaluation recurse once per level, and a hostile
// "union(union(union(..." must end in an error, not in a stack overflow.
constexpr int kMaxCsgDepth = 256;

CsgNode nodeFromJson(const nlohmann::json& j, const std::string& pointer, int depth = 0) {
    if (depth > kMaxCsgDepth)
        jsonFail(pointer, detail::concat("operations nested deeper than ", kMaxCsgDepth, " levels"));
    CsgNode node;
    if (j.is_string()) {
        node.mesh = j.get<std::string>();
        if (node.mesh.empty()) jsonFail(pointer, "empty mesh path");
        return node;
    }
    if (!j.is_object())
        jsonFail(pointer,
                 detail::concat("expected a string (mesh path) or an object, found ", j.type_name()));
    if (j.empty()) jsonFail(pointer, "empty object: a CSG node needs \"op\" and \"args\"");
    for (const auto& [key, value] : j.items())
        if (key != "op" && key != "args")
            jsonFail(pointer,
                     detail::concat("unknown member \"", key, "\" (a CSG node has \"op\" and \"args\")"));
    if (!j.contains("op")) jsonFail(pointer, "object without \"op\"");
    if (!j.contains("args")) jsonFail(pointer, "object without \"args\"");
    const nlohmann::json& op = j["op"];
    if (!op.is_string())
        jsonFail(pointer + "/op", detail::concat("\"op\" must be a string, found ", op.type_name()));
    const std::string name = op.get<std::string>();
    if (!lookupCsgOp(name, node.op))
        jsonFail(pointer + "/op",
                 detail::concat("unknown operation '", name, "' (allowed: ", kAllowedOps, ")"));
    const nlohmann::json& args = j["args"];
    if (!args.is_array())
        jsonFail(pointer + "/args", detail::concat("\"args\" must be an array, found ", args.type_name()));
    if (args.empty()) jsonFail(pointer + "/args", "\"args\" needs at least one argument");
    node.isMesh = false;
    for (size_t i = 0; i < args.size(); ++i)
        node.args.push_back(nodeFromJson(args[i], detail::concat(pointer, "/args/", i), depth + 1));
    return node;
}

// nlohmann's parse_error.byte is the 1-based position of the last character it read: the end of
// the offending token. The column names the token's first character, where a reader looks.
size_t tokenColumn(std::string_view text, size_t byte) {
    if (byte == 0 || byte > text.size()) return byte; // the text ended
    size_t i = byte - 1;
    if (text[i] == '"' && i > 0) { // a complete string: back to its opening quote
        for (size_t j = i; j-- > 0;) {
            size_t backslashes = 0;
            while (backslashes < j && text[j - 1 - backslashes] == '\\') ++backslashes;
            if (text[j] == '"' && backslashes % 2 == 0) return j + 1;
        }
        return byte;
    }
    const auto inWord = [](char c) {
        return std::isalnum(static_cast<unsigned char>(c)) || c == '+' || c == '-' || c == '.';
    };
    while (i > 0 && inWord(text[i]) && inWord(text[i - 1])) --i; // a number or a literal
    return i + 1;
}

CsgNode parseJsonExpression(std::string_view text) {
    nlohmann::json doc;
    try {
        doc = nlohmann::json::parse(text.begin(), text.end());
    } catch (const nlohmann::json::parse_error& e) {
        parseFail(tokenColumn(text, e.byte), jsonReason(e));
    } catch (const nlohmann::json::out_of_range& e) {
        // A number past double's range (1e999): nlohmann names the token, not its position.
        const std::string what = e.what();
        const size_t open = what.find('\''), close = what.rfind('\'');
        const std::string token = open < close ? what.substr(open + 1, close - open - 1) : std::string();
        const size_t at = token.empty() ? std::string_view::npos : text.find(token);
        parseFail(at == std::string_view::npos ? 1 : at + 1, "number out of range: " + token);
    }
    return nodeFromJson(doc, "");
}

// ---- functional syntax, by hand (it is the project's own notation).
class Parser {
public:
    explicit Parser(std::string_view text) : text_(text) {}

    CsgNode parse() {
        skipBlanks();
        if (pos_ >= text_.size()) error("expected a CSG expression, the text is empty");
        CsgNode root = parseFunctional();
        skipBlanks();
        if (pos_ < text_.size())
            error(detail::concat("unexpected '", text_[pos_], "' after the end of the expression"));
        return root;
    }

private:
    [[noreturn]] void error(const std::string& what) const { parseFail(pos_ + 1, what); }
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

    CsgNode parseFunctional(int depth = 0) {
        skipBlanks();
        if (depth > kMaxCsgDepth)
            error(detail::concat("operations nested deeper than ", kMaxCsgDepth, " levels"));
        CsgNode node;
        const size_t column = pos_ + 1;
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
            node.args.push_back(parseFunctional(depth + 1));
            while (peek(',')) {
                ++pos_;
                node.args.push_back(parseFunctional(depth + 1));
            }
            expect(')',
                   detail::concat("to close ", toString(op), " (opened at column ", column, ")").c_str());
            return node;
        }
        node.mesh = std::string(word);
        return node;
    }

    // A double-quoted string with JSON's escapes (\" \\ \/ \b \f \n \r \t \uXXXX, surrogate
    // pairs included); any other byte stands for itself, since a path is bytes (control
    // characters and non-UTF-8 names included), so every name toString quotes reads back.
    std::string parseQuoted() {
        const size_t open = pos_++;
        std::string out;
        auto hex4 = [&](size_t at) {
            if (at + 4 > text_.size()) parseFail(at + 1, "\\u needs four hexadecimal digits");
            unsigned v = 0;
            for (size_t k = at; k < at + 4; ++k) {
                const char c = text_[k];
                const int d = c >= '0' && c <= '9'   ? c - '0'
                              : c >= 'a' && c <= 'f' ? c - 'a' + 10
                              : c >= 'A' && c <= 'F' ? c - 'A' + 10
                                                     : -1;
                if (d < 0) parseFail(k + 1, "\\u needs four hexadecimal digits");
                v = v * 16 + unsigned(d);
            }
            return v;
        };
        for (;;) {
            if (pos_ >= text_.size()) parseFail(open + 1, "unterminated string");
            const char c = text_[pos_++];
            if (c == '"') return out;
            if (c != '\\') {
                out += c;
                continue;
            }
            if (pos_ >= text_.size()) parseFail(open + 1, "unterminated string");
            const char e = text_[pos_++];
            switch (e) {
            case '"':
            case '\\':
            case '/':
                out += e;
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
                unsigned cp = hex4(pos_);
                pos_ += 4;
                if (cp >= 0xD800 && cp <= 0xDBFF) { // a high surrogate: its low half must follow
                    if (pos_ + 6 > text_.size() || text_[pos_] != '\\' || text_[pos_ + 1] != 'u')
                        parseFail(pos_ + 1, "a \\u surrogate pair is incomplete");
                    const unsigned low = hex4(pos_ + 2);
                    if (low < 0xDC00 || low > 0xDFFF) parseFail(pos_ + 1, "a \\u surrogate pair is invalid");
                    pos_ += 6;
                    cp = 0x10000 + ((cp - 0xD800) << 10) + (low - 0xDC00);
                } else if (cp >= 0xDC00 && cp <= 0xDFFF) {
                    parseFail(pos_ - 5, "a lone \\u surrogate");
                }
                if (cp < 0x80) {
                    out += char(cp);
                } else if (cp < 0x800) {
                    out += char(0xC0 | (cp >> 6));
                    out += char(0x80 | (cp & 0x3F));
                } else if (cp < 0x10000) {
                    out += char(0xE0 | (cp >> 12));
                    out += char(0x80 | ((cp >> 6) & 0x3F));
                    out += char(0x80 | (cp & 0x3F));
                } else {
                    out += char(0xF0 | (cp >> 18));
                    out += char(0x80 | ((cp >> 12) & 0x3F));
                    out += char(0x80 | ((cp >> 6) & 0x3F));
                    out += char(0x80 | (cp & 0x3F));
                }
                break;
            }
            default:
                parseFail(pos_, detail::concat("unknown escape '\\", e, "' in a quoted path"));
            }
        }
    }

    std::string_view text_;
    size_t pos_ = 0;
};

bool needsQuotes(const std::string& path) {
    // A leading '{' would read back as the JSON syntax.
    if (path.empty() || path.front() == '{') return true;
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

CsgNode parseCsgExpression(std::string_view text) {
    const size_t first = text.find_first_not_of(" \t\n\r\f\v");
    if (first != std::string_view::npos && text[first] == '{') return parseJsonExpression(text);
    return Parser(text).parse();
}

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
        vo.report = m.report;
        vo.slicing = Slicing::Uniform;
        return std::move(voxfx::voxelize(m.mesh, frame, vo).bits);
    });
    return {frame, std::move(bits)};
}

} // namespace voxfx
