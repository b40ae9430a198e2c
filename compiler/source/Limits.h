// Limits on what iqc reads: every input, however hostile, ends in a located diagnostic (exit 1) within
// seconds and a bounded amount of memory, never a crash, a hang or a silent truncation.
//
// Each cap is far above what a real scene or module needs, and each has one place that enforces it
// (named beside it). docs/language.md ("Limits") and docs/scene.md list them for users.
#pragma once

#include <cmath>
#include <cstddef>
#include <cmath>
#include <cstdint>
#include <optional>
#include <string_view>

namespace iqc::limits {

// Components of one vector or matrix (ℝ^4096, ℝ^(64×64)): every size the checker computes goes through
// checked_size (sema/Check.cpp, syntax/Parser.cpp).
constexpr int kMaxComponents = 4096;
// Grammar nesting: parentheses, signs, and the operands of one chain such as a + b + … count one level
// each (syntax/Parser.cpp); the checker counts expression depth plus nested local-function calls
// (sema/Check.cpp). Every later pass recurses at most this deep, which fits the default 8 MiB stack
// with room to spare even in sanitizer builds (whose frames are several times larger).
constexpr int kMaxNesting = 256;
// Modules importing modules importing … (scene/Modules.cpp).
constexpr int kMaxImportDepth = 64;
// TOML: parts of one dotted key plus nested tables and arrays (scene/Scene.cpp; toml++ itself stops
// nested arrays at 256).
constexpr int kMaxTomlDepth = 128;
// One source file (a scene, a document, an included or imported module), and all files of one compile
// (source/Source.cpp, read_source_file). Only regular files are read: no pipes, devices or directories.
constexpr size_t kMaxFileBytes = size_t(16) << 20;
constexpr size_t kMaxTotalBytes = size_t(64) << 20;
// Work of one double-precision evaluation (`iqc eval`, compile-time transforms): one step per
// instruction plus one per component it produces; a recurrence is refused before it starts when its
// iterations alone exceed what is left (ir/Eval.cpp).
constexpr uint64_t kMaxEvalSteps = 100'000'000;
// Statements (and declarations) of one module (syntax/Parser.cpp): 100,000 chained statements compile in
// about 3 s, most of it the driver's GLSL compiler.
constexpr size_t kMaxStatements = 100'000;
// Instructions of one IR function, after local functions are expanded and sums unrolled (ir/IR.h,
// Function::add: every pass and the lowering add through it). About 200 MB of IR.
constexpr size_t kMaxFunctionInstructions = 1'000'000;

// The largest 32-bit float, and the range of a 32-bit int: the numbers a shader computes with. Values outside
// them are located errors where they are written (literals, defaults, overrides, --set).
constexpr double kFloatMax = 3.4028234663852886e38;
// Whether x is a value a shader's 32-bit float holds: finite once rounded to float. 3.4028235e38 (FLT_MAX as
// printed) rounds down to FLT_MAX and fits; 3.5e38 does not. The one range rule of literals, scene values,
// constant expressions and bounds.
inline bool fits_float(double x) { return std::isfinite(static_cast<float>(x)); }
// The smallest normal 32-bit float: below it GPUs may flush to 0 (denormals are optional in GLSL ES).
constexpr double kFloatMinNormal = 1.1754943508222875e-38;
// Whether x is nonzero but below the smallest normal float (what a shader may flush to 0).
inline bool below_normal_float(double x) { return x != 0 && std::fabs(x) < kFloatMinNormal; }
inline bool is_int32(double x) { return x >= -2147483648.0 && x <= 2147483647.0; }

// A size as counted (a literal such as `3` in ℝ^3, a sum of block heights, a concatenation's length):
// the value when it is from 1 to kMaxComponents, otherwise nothing (the caller reports where).
inline std::optional<int> checked_size(int64_t n) {
    if (n < 1 || n > kMaxComponents) return std::nullopt;
    return int(n);
}
// A size written in decimal digits (no sign, no point): the value when it is from 1 to kMaxComponents.
inline std::optional<int> checked_size(std::string_view digits) {
    if (digits.empty() || digits.size() > 9) return std::nullopt;
    int64_t n = 0;
    for (char c : digits) {
        if (c < '0' || c > '9') return std::nullopt;
        n = n * 10 + (c - '0');
    }
    return checked_size(n);
}
// A whole number held in a double (a subscript, a loop bound) as an int in [lo, hi]; nothing when it is
// not whole, not finite or out of range (a plain int(x) is undefined behaviour there).
inline std::optional<int> checked_int(double x, int lo, int hi) {
    if (!std::isfinite(x) || x != std::floor(x) || x < double(lo) || x > double(hi)) return std::nullopt;
    return int(x);
}

// Recursion depth of a parser or a checker, counted against kMaxNesting. A guard holds the levels entered
// through it and leaves them when it goes out of scope, also when an error unwinds the recursion:
//     DepthGuard g(depth_);
//     if (!g.enter()) report "nested too deeply" at the current span;
class DepthGuard {
public:
    explicit DepthGuard(int& depth) : depth_(depth) {}
    DepthGuard(const DepthGuard&) = delete;
    DepthGuard& operator=(const DepthGuard&) = delete;
    ~DepthGuard() { depth_ -= entered_; }
    // One more level; false past kMaxNesting.
    bool enter() {
        ++depth_;
        ++entered_;
        return depth_ <= kMaxNesting;
    }

private:
    int& depth_;
    int entered_ = 0;
};

}  // namespace iqc::limits
