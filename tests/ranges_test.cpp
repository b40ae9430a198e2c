// Range analysis: guards where the math has a continuous limit, located warnings where a slider can push
// an operation out of its domain, and --strict-ranges.
#include <catch2/catch.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "TestUtil.h"

using namespace iqc;
using namespace iqc::test;

namespace {
std::string doc(const std::string& shape_body, const std::string& decls) {
    return "❤: s\n```iheartla\nshape\n" + shape_body + "\nwhere\np ∈ ℝ³\n" + decls + "```\n```scene\n[[shapes]]\ntype = \"s\"\n```\n";
}
}  // namespace

TEST_CASE("a division by a slider range containing 0 is warned, located", "[ranges]") {
    Compiled c = compile_text("div.md", doc("D = ‖p‖ - 1/(r - 1)", "r ∈ [0,2] default = 0.5\n"));
    REQUIRE(c.result.exit_code == 0);
    CHECK_THAT(c.diagnostics, Catch::Contains("div.md:4:11: warning: division by a value that can be 0: with the parameters' "
                                              "bounds it ranges over [-1, 1]"));
    Compiled safe = compile_text("div_ok.md", doc("D = ‖p‖ - 1/(r + 1)", "r ∈ [0,2] default = 0.5\n"));
    CHECK(safe.diagnostics.empty());
    // --strict-ranges: the warning is an error.
    auto f = write_temp("div_strict.md", doc("D = ‖p‖ - 1/(r - 1)", "r ∈ [0,2] default = 0.5\n"));
    RunResult r = run_iqc("--strict-ranges " + f.string());
    CHECK(r.exit_code == 1);
    CHECK_THAT(r.err, Catch::Contains("error: division by a value that can be 0"));
}

TEST_CASE("logarithms and powers of a positive slider have their ranges: no division warning", "[ranges]") {
    // A trial (stop 54, F8): ln β, log₂ k, log₁₀ k, k^0.5, 2^k with β, k ∈ [1.5, 10] ranged over [-∞, ∞] (the ranges
    // pass had no rule for them), so dividing by them was "a value that can be 0", and --strict-ranges rejected the
    // module. Each is bounded now; a logarithm of a slider whose range reaches 1 (ln k = 0 at k = 1) is still warned.
    for (const char* divisor : {"ln(k)", "log₂(k)", "log₁₀(k)", "k^0.5", "2^k", "k^k"}) {
        INFO(divisor);
        const std::string text = doc(std::string("D = (‖p‖ - 1)/") + divisor, "k ∈ [1.5, 10] default = 2\n");
        Compiled c = compile_text("logdiv.md", text);
        REQUIRE(c.result.exit_code == 0);
        CHECK_THAT(c.diagnostics, !Catch::Contains("division by a value that can be 0"));
        RunResult r = run_iqc("--strict-ranges " + write_temp("logdiv_strict.md", text).string() + " -o /dev/null");
        CHECK(r.exit_code == 0);
    }
    Compiled one = compile_text("logdiv_one.md", doc("D = (‖p‖ - 1)/ln(k)", "k ∈ [0.5, 10] default = 2\n"));
    REQUIRE(one.result.exit_code == 0);
    CHECK_THAT(one.diagnostics, Catch::Contains("warning: division by a value that can be 0: with the parameters' bounds it ranges over [-0.6931, 2.303]"));
}

TEST_CASE("a sum that is a loop is bounded as the unrolled sum: the same warnings", "[ranges]") {
    // A new user's trial: 1/∑_i w_i warned with 31 weights (an unrolled sum of unbounded parameters) and not with
    // 32 (a loop, which the analysis did not look into). A sum of squares plus 0.5 over 40 weights is at least 20:
    // nothing is warned, as for 31.
    for (int n : {31, 40}) {
        std::string w;
        for (int k = 0; k < n; ++k) w += k ? ", 0.05" : "0.05";
        INFO(n);
        Compiled c = compile_text("sum_div.md", doc("D = ‖p‖ - 1/∑_i w_i", "w_i ∈ ℝ default = {" + w + "}\n"));
        REQUIRE(c.result.exit_code == 0);
        CHECK_THAT(c.diagnostics, Catch::Contains("sum_div.md:4:11: warning: division by a value that can be 0: with the parameters' "
                                                  "bounds it ranges over [-∞, ∞]"));
        Compiled safe = compile_text("sum_div_ok.md", doc("D = ‖p‖ - 1/∑_i (w_i² + 0.5)", "w_i ∈ ℝ default = {" + w + "}\n"));
        REQUIRE(safe.result.exit_code == 0);
        CHECK(safe.diagnostics.empty());
    }
}

TEST_CASE("a loop's term is analysed with its captures' ranges", "[ranges]") {
    // A trial: w_i/∑_j w_j warned with 3 weights and not with 40 (the divisor, an index-free sum, is computed
    // before the loop and captured; the loop's body alone knew nothing of it). Its other warnings too: a square
    // root of a captured slider's value. A divisor of squares plus 0.5 warns of nothing.
    for (int n : {3, 40}) {
        std::string w;
        for (int k = 0; k < n; ++k) w += k ? ", 0.5" : "0.5";
        INFO(n);
        Compiled c = compile_text("loop_div.md", doc("D = ‖p‖ - 1 + 0.01 ∑_i w_i/∑_j w_j", "w_i ∈ ℝ default = {" + w + "}\n"));
        REQUIRE(c.result.exit_code == 0);
        CHECK_THAT(c.diagnostics, Catch::Contains("loop_div.md:4:24: warning: division by a value that can be 0: with the "
                                                  "parameters' bounds it ranges over [-∞, ∞]"));
        Compiled root = compile_text("loop_sqrt.md", doc("D = ‖p‖ - 1 + 0.01 ∑_i w_i √(r - 1)",
                                                         "w_i ∈ ℝ default = {" + w + "}\nr ∈ [0,2] default = 1.5\n"));
        REQUIRE(root.result.exit_code == 0);
        CHECK_THAT(root.diagnostics, Catch::Contains("square root of a value that can be negative: it ranges over [-1, 1]"));
        Compiled safe = compile_text("loop_div_ok.md", doc("D = ‖p‖ - 1 + 0.01 ∑_i w_i/∑_j (w_j² + 0.5)",
                                                           "w_i ∈ ℝ default = {" + w + "}\n"));
        REQUIRE(safe.result.exit_code == 0);
        CHECK(safe.diagnostics.empty());
    }
}

TEST_CASE("what the stable pass rewrote is not warned of", "[ranges]") {
    // A trial: log(e^a + e^b) and log ∑_i e^(w_i) over unbounded a, b, w warned "exp of a value that can exceed
    // 88.72" at the e^a the stable pass had replaced (max(a, b) + log(1 + e^-|a-b|)), at 1:1 for the e^(w_i - hi)
    // it made, and through the replaced loop over 40 weights. A sum of e^(w_i) with no log is computed as written:
    // warned, at its exp, also as a loop.
    for (int n : {4, 40}) {
        std::string w;
        for (int k = 0; k < n; ++k) w += k ? ", 1" : "1";
        INFO(n);
        Compiled lse = compile_text("lse.md", doc("D = ‖p‖ - 0.2 log(∑_i exp(w_i))", "w_i ∈ ℝ default = {" + w + "}\n"));
        REQUIRE(lse.result.exit_code == 0);
        CHECK(lse.diagnostics.empty());
        Compiled plain = compile_text("sum_exp.md", doc("D = ‖p‖ - 0.001 ∑_i exp(w_i)", "w_i ∈ ℝ default = {" + w + "}\n"));
        REQUIRE(plain.result.exit_code == 0);
        CHECK_THAT(plain.diagnostics, Catch::Contains("sum_exp.md:4:21: warning: exp of a value that can exceed 88.72"));
        CHECK_THAT(plain.diagnostics, !Catch::Contains(":1:1:"));
    }
    Compiled pair = compile_text("lse2.md", doc("D = ‖p‖ - 0.2 log(exp(a) + exp(b))", "a ∈ ℝ default = 1\nb ∈ ℝ default = 2\n"));
    REQUIRE(pair.result.exit_code == 0);
    CHECK(pair.diagnostics.empty());
}

TEST_CASE("a parameter value outside its slider bounds is an error under --strict-ranges", "[ranges]") {
    // Found by a new-user trial: a vesica's width overridden to 0 (its sliders start at 0.05) made the distance
    // NaN at every pixel, and --strict-ranges passed it: range analysis proves its guards within the bounds only.
    auto f = write_temp("outside_bounds.md", "❤: s\n```iheartla\nshape\nD = ‖p‖ - 1/r\nwhere\np ∈ ℝ³\nr ∈ [0.5,2] default = 1\n```\n"
                                             "```scene\n[[shapes]]\ntype = \"s\"\nshape_params = { r = 0 }\n```\n");
    RunResult warned = run_iqc(f.string() + " -o -");
    CHECK(warned.exit_code == 0);
    CHECK_THAT(warned.err, Catch::Contains("outside_bounds.md:12:18: warning: the value 0 of 'r' is outside its slider bounds [0.5, 2]"));
    RunResult strict = run_iqc("--strict-ranges " + f.string() + " -o -");
    CHECK(strict.exit_code == 1);
    CHECK_THAT(strict.err, Catch::Contains("outside_bounds.md:12:18: error: the value 0 of 'r' is outside its slider bounds [0.5, 2], "
                                           "where range analysis proves nothing (--strict-ranges)"));
}

TEST_CASE("sqrt, acos and pow get guards: warnings only for slider ranges", "[ranges]") {
    // acos of a dot product of unknown vectors: guarded (a rounding error can exceed 1), no warning. (The
    // shapes declare a Lipschitz factor: intervals cannot bound acos(p_1/‖p‖)'s gradient, nor p_2^a's over
    // the region; the lipschitz pass would warn, which is not what this test is about.)
    Compiled a = compile_text("acos.md", doc("# lipschitz: 2\nacos from trigonometry\nD = ‖p‖ - 1 + 0.01acos(p_1/‖p‖)", ""));
    REQUIRE(a.result.exit_code == 0);
    CHECK(a.diagnostics.empty());
    CHECK_THAT(a.result.code, Catch::Contains("acos(clamp("));
    // sqrt of a slider range that can be negative: warned and guarded.
    Compiled s = compile_text("sqrt.md", doc("D = ‖p‖ - √k", "k ∈ [-1,1] default = 0.5\n"));
    REQUIRE(s.result.exit_code == 0);
    CHECK_THAT(s.diagnostics, Catch::Contains("sqrt.md:4:11: warning: square root of a value that can be negative: it ranges over [-1, 1]"));
    CHECK_THAT(s.result.code, Catch::Contains("sqrt(max(k, 0.0))"));
    // pow of an unknown base with a fractional exponent: guarded, no warning.
    // (|p_1|^1.5, not ^0.5: the samples that walk to the surface since stop 40 find ^0.5's unbounded slope at
    // p_1 = 0 above the declared 2, rightly.)
    Compiled p = compile_text("pow.md", doc("# lipschitz: 50\nD = ‖p‖ - 1 + 0.1|p_1|^1.5 + 0.01p_2^a", "a ∈ [0.5,2] default = 1.5\n"));
    REQUIRE(p.result.exit_code == 0);
    CHECK(p.diagnostics.empty());
    CHECK_THAT(p.result.code, Catch::Contains("pow(max(p.y, 0.0), a)"));
    CHECK_THAT(p.result.code, !Catch::Contains("pow(max(abs("));  // |p_1| ≥ 0: no guard needed
}

TEST_CASE("log, mod and normalize of slider ranges are warned", "[ranges]") {
    Compiled l = compile_text("log.md", doc("D = ‖p‖ - 1 + 0.1ln(k) + 0.1mod(p_1, m) + normalize(v)_1", "k ∈ [0,1]\nm ∈ [-1,1]\nv ∈ [-1,1]x[-1,1]x[-1,1]\n"));
    REQUIRE(l.result.exit_code == 0);
    CHECK_THAT(l.diagnostics, Catch::Contains("warning: logarithm of a value that can be 0 or negative: it ranges over [0, 1]"));
    CHECK_THAT(l.diagnostics, Catch::Contains("warning: mod by a value that can be 0: it ranges over [-1, 1]"));
    CHECK_THAT(l.diagnostics, Catch::Contains("warning: normalize of a vector that can be zero"));
}

TEST_CASE("a negative power of a base that can be 0 is warned", "[ranges]") {
    // A trial (stop 52): s^(-0.5) with s ∈ [0, 1] is ∞ at s = 0 (the shape vanished), unwarned where 1/√s was warned of.
    Compiled c = compile_text("npow.md", doc("sin from trigonometry\nD = ‖p‖ - 1 + 0.1 sin(s^(-0.5))", "s ∈ [0,1] default = 0.5\n"));
    REQUIRE(c.result.exit_code == 0);
    CHECK_THAT(c.diagnostics, Catch::Contains("npow.md:5:23: warning: a power with the negative exponent -0.5 of a base that can be 0 or below "
                                              "(∞ there: a negative base is taken as 0): the base ranges over [0, 1]"));
    Compiled e = compile_text("npow_e.md", doc("sin from trigonometry\nD = ‖p‖ - 1 + 0.1 sin(s^e)", "s ∈ [0,1] default = 0.5\ne ∈ [-1,2] default = 0.5\n"));
    CHECK_THAT(e.diagnostics, Catch::Contains("an exponent that can be negative, [-1, 2]"));
    // A negative base and a negative exponent: one warning (there were two, one of a base 'that can be 0'), no "-0".
    Compiled neg = compile_text("npow_neg.md", doc("sin from trigonometry\nD = ‖p‖ - 1 + 0.1 sin(s^(-1.5))", "s ∈ [-1,0] default = -0.5\n"));
    REQUIRE(neg.result.exit_code == 0);
    CHECK_THAT(neg.diagnostics, Catch::Contains("a power with the negative exponent -1.5 of a base that can be 0 or below"));
    CHECK_THAT(neg.diagnostics, Catch::Contains("the base ranges over [-1, 0]"));
    CHECK(neg.diagnostics.find("warning:", neg.diagnostics.find("warning:") + 1) == std::string::npos);
    // A condition that keeps the base above 0 (exactly, not by a float's rounding): nothing (a trial's [1.388e-17, 0.9]).
    for (const char* ok : {"r = { (s - 0.1)^(-0.5) if s > 0.1\n      1 otherwise }", "r = { 1/(s - 0.1) if s > 0.1\n      1 otherwise }",
                           "r = { log(s - 0.1) if s > 0.1\n      1 otherwise }"}) {
        INFO(ok);
        Compiled c3 = compile_text("npow_cond.md", doc("D = ‖p‖ - 1 + 0.01 r\n" + std::string(ok), "s ∈ [0,1] default = 0.5\n"));
        REQUIRE(c3.result.exit_code == 0);
        CHECK(c3.diagnostics.empty());
    }
    for (const char* ok : {"sin from trigonometry\nD = ‖p‖ - 1 + 0.1 sin((s + 1)^(-0.5))", "sin from trigonometry\nD = ‖p‖ - 1 + 0.1 sin(s^0.5)"}) {
        Compiled c2 = compile_text("npow_ok.md", doc(ok, "s ∈ [0,1] default = 0.5\n"));
        REQUIRE(c2.result.exit_code == 0);
        CHECK(c2.diagnostics.empty());
    }
}

TEST_CASE("atan2(0, 0) is 0 in the shader as in the evaluator", "[ranges]") {
    Compiled a = compile_text("atan.md", doc("atan2 from trigonometry\nD = ‖p‖ - 1 + 0.01atan2(p_2, p_1)", ""));
    REQUIRE(a.result.exit_code == 0);
    CHECK_THAT(a.result.code, Catch::Contains("(p.y == 0.0) && (p.x == 0.0)"));
}

TEST_CASE("a constant power of a negative base is guarded and warned as a slider range is and never becomes another constant", "[ranges]") {
    // Found by a new-user trial: fold made pow(-2, 0.5) a NaN constant, and CSE (keyed on doubles) merged
    // it with the constant -2, so D lost its 0.001 factor in both the shader and iqc eval.
    Compiled c = compile_text("nan.md", doc("D = ‖p‖ - 1 + 0.001⋅pow(-2, 0.5)", ""));
    REQUIRE(c.result.exit_code == 0);
    CHECK_THAT(c.diagnostics, Catch::Contains("nan.md:4:21: warning: a power of a base that can be negative: it is -2"));
    CHECK_THAT(c.result.code, !Catch::Contains("+ (-2.0)"));
    auto path = write_temp("nan_pow.iql", "shape\nD = ‖p‖ - 1 + 0.001⋅pow(-2, 0.5)\nwhere\np ∈ ℝ³\n");
    RunResult e = run_iqc("eval " + path.string() + " --set 'p=(2,0,0)'");
    CHECK(e.exit_code == 0);
    CHECK(e.out == "D = 1\n");  // the guard's meaning: pow(max(-2, 0), 0.5) = 0
}

TEST_CASE("values past the largest float are warned where they start: a folded constant and exp of a slider range", "[ranges]") {
    // iqc eval computes in double and prints 1e+40; a shader's 32-bit float is ∞ (issue 12, float range).
    auto path = write_temp("overflow.iql", "y = 10^40 + exp(x)\nwhere\nx ∈ [0, 100] default = 1\n");
    RunResult e = run_iqc("eval " + path.string());
    CHECK(e.exit_code == 0);
    CHECK_THAT(e.err, Catch::Contains("overflow.iql:1:5: warning: this value is beyond the largest 32-bit float (3.4e38): a "
                                      "shader computes ∞; it is 1e+40"));
    CHECK_THAT(e.err, Catch::Contains("overflow.iql:1:13: warning: exp of a value that can exceed 88.72: a shader's 32-bit "
                                      "float overflows to ∞ there; it ranges over [0, 100]"));
    // Once, where it starts: the sum is not warned again.
    size_t n = 0;
    for (size_t at = e.err.find("beyond the largest"); at != std::string::npos; at = e.err.find("beyond the largest", at + 1)) ++n;
    CHECK(n == 1);
    // Within range: no word.
    RunResult ok = run_iqc("eval " + write_temp("in_range.iql", "y = 10^38 + exp(x)\nwhere\nx ∈ [0, 80] default = 1\n").string());
    CHECK(ok.err.empty());
}

TEST_CASE("values below the smallest normal float are warned where they start, and a division by one can be by 0", "[ranges]") {
    // Found by a new-user trial: (‖p‖ - 1)(1e-20 1e-20)/(1e-20 1e-20) folded to 1e-40, which a GPU flushes to 0
    // (0/0 at every pixel, no word); exp(-a) with a = 100 is 3.7e-44, the same 0/0.
    Compiled c = compile_text("tiny.md", doc("D = (‖p‖ - 1)(1e-20 1e-20)/(1e-20 1e-20)", ""));
    REQUIRE(c.result.exit_code == 0);
    CHECK_THAT(c.diagnostics, Catch::Contains("tiny.md:4:14: warning: this value is below the smallest normal 32-bit float "
                                              "(1.2e-38): a shader may compute 0; it ranges over [0, 1e-40]"));
    CHECK_THAT(c.diagnostics, Catch::Contains("tiny.md:4:1: warning: division by a value that can be 0 (it can fall below the "
                                              "smallest normal 32-bit float, 1.2e-38, which a shader may flush to 0)"));
    Compiled e = compile_text("exp_tiny.md", doc("D = (‖p‖ - 1) exp(-a)/exp(-a)", "a ∈ [0,200] default = 100\n"));
    REQUIRE(e.result.exit_code == 0);
    CHECK_THAT(e.diagnostics, Catch::Contains("exp_tiny.md:4:1: warning: division by a value that can be 0 (it can fall below "
                                              "the smallest normal 32-bit float"));
    // Small but normal: no word.
    Compiled ok = compile_text("small_ok.md", doc("D = (‖p‖ - 1)(1e-10 1e-10)/(1e-10 1e-10)", ""));
    CHECK(ok.diagnostics.empty());
}

TEST_CASE("a piecewise arm and a conditional sum's term are analysed under their conditions", "[ranges]") {
    // A trial (stop 51): `∑_(i for w_i > 0.5) 1/w_i` warned of a division by 0, and so did every guarded form of
    // the kind `1/s if s > 0.1`, `log(s) if s > 0`, `√(s − 0.2) if s ≥ 0.2` (and guarded what needs no guard).
    const std::string s = "s ∈ [-1,1] default = 0.5\nt ∈ [-1,1] default = 0.5\n";
    for (const char* body : {"r = { 1/s if s > 0.1\n      1 otherwise }", "r = { log(s) if s > 0\n      0.5 otherwise }",
                             "r = { √(s - 0.25) if s ≥ 0.25\n      0.5 otherwise }", "r = { 1 if s ≤ 0.1\n      1/s otherwise }",
                             "r = { 1/s if s > 0.1\n      1/(s - 0.5) otherwise }", "r = { 1/s if s ∈ [0.2, 0.9]\n      1 otherwise }",
                             "r = { 1/s if s > 0.1 and t > 0\n      1 otherwise }", "r = { 1/s if 0.1 < s\n      1 otherwise }",
                             "r = { 1 if s < 0.1\n      1/s if t > 0\n      1/(s + 2) otherwise }", "r = { 1/s if s ≠ 0\n      1 otherwise }"}) {
        INFO(body);
        Compiled c = compile_text("arm.md", doc("D = ‖p‖ - r\n" + std::string(body), s));
        REQUIRE(c.result.exit_code == 0);
        CHECK(c.diagnostics.empty());
        CHECK_THAT(c.result.code, !Catch::Contains("max(s - 0.25"));
    }
    // A trial (stop 52): s ≥ 0.03 makes s/0.03 − 1 ≥ 0 in real arithmetic, but the shader's s·33.333332 − 1 is −6e-8 at
    // s = 0.03, and a square root of it NaN at every pixel (the guard had been dropped; eval said 0). The guard stays
    // where float's rounding can take the value below 0; no warning (the real value is not). The same without a
    // condition where the slider's own bound is 0.03, and for a fold in double (0.3 − 0.1 is 0.19999999999999998).
    for (const char* body : {"r = { √(s/0.03 - 1) if s ≥ 0.03\n      0 otherwise }", "r = { √(1 - s/0.101) if s ≤ 0.101\n      0 otherwise }",
                             "r = { √(10 s - 7) if s ≥ 0.7\n      0 otherwise }", "r = { √(s s - 0.49) if s ≥ 0.7\n      0 otherwise }",
                             "r = { √(0.3 - 0.1 - s) if s ≤ 0.2\n      0 otherwise }"}) {
        INFO(body);
        Compiled c = compile_text("arm_float.md", doc("D = ‖p‖ - 1 + 0.1 r\n" + std::string(body), s));
        REQUIRE(c.result.exit_code == 0);
        CHECK(c.diagnostics.empty());
        CHECK_THAT(c.result.code, Catch::Contains("sqrt(max("));
    }
    Compiled bound = compile_text("bound_float.md", doc("D = ‖p‖ - 1 + 0.1 √(s/0.03 - 1)", "s ∈ [0.03,1] default = 0.03\n"));
    REQUIRE(bound.result.exit_code == 0);
    CHECK(bound.diagnostics.empty());
    CHECK_THAT(bound.result.code, Catch::Contains("sqrt(max("));
    // What the condition does not exclude is still warned: s > -0.5 leaves 0 in; a value both arms read; a
    // condition on another parameter; an `or`.
    for (const char* body : {"r = { 1/s if s > -0.5\n      1 otherwise }", "r = { 1/s + 1 if s > 0.1\n      1/s otherwise }",
                             "r = { 1/s if t > 0.1\n      1 otherwise }", "r = { 1/s if s > 0.1 or t > 0\n      1 otherwise }"}) {
        INFO(body);
        Compiled c = compile_text("arm_bad.md", doc("D = ‖p‖ - r\n" + std::string(body), s));
        REQUIRE(c.result.exit_code == 0);
        CHECK_THAT(c.diagnostics, Catch::Contains("warning: division by a value that can be 0"));
    }
    Compiled narrowed = compile_text("arm_range.md", doc("D = ‖p‖ - r\nr = { 1/s if s > -0.5\n      1 otherwise }", s));
    CHECK_THAT(narrowed.diagnostics, Catch::Contains("arm_range.md:5:7: warning: division by a value that can be 0: with the "
                                                     "parameters' bounds it ranges over [-0.5, 1]"));
    // A conditional sum, unrolled (3 weights) and rolled (40).
    for (int n : {3, 40}) {
        std::string w;
        for (int k = 0; k < n; ++k) w += fmt::format("{}{:.2f}", k ? ", " : "", 0.1 + 0.02 * k);
        INFO(n);
        Compiled c = compile_text("cond_sum.md", doc("D = ‖p‖ - 0.5 + 0.001 ∑_(i for w_i > 0.5) 1/w_i", "w_i ∈ ℝ default = {" + w + "}\n"));
        REQUIRE(c.result.exit_code == 0);
        CHECK(c.diagnostics.empty());
        Compiled bad = compile_text("cond_sum_bad.md", doc("D = ‖p‖ - 0.5 + 0.001 ∑_(i for w_i > -0.5) 1/w_i", "w_i ∈ ℝ default = {" + w + "}\n"));
        REQUIRE(bad.result.exit_code == 0);
        CHECK_THAT(bad.diagnostics, Catch::Contains("cond_sum_bad.md:4:44: warning: division by a value that can be 0"));
    }
}

TEST_CASE("local functions and the standard library's are analysed with their arguments' ranges", "[ranges]") {
    // A trial (stop 52): `g() = 1/s` with s ∈ [0, 1] warned of nothing, also under --strict-ranges, and NaN reached
    // every pixel: a local function's parameters have no bounds of their own. Calls are analysed with their
    // arguments' ranges now; the warning is at the operation, in the function's definition.
    const std::string s = "s ∈ [0,1] default = 0.5\nw_i ∈ ℝ default = {0.6, 0.9, 0.2}\n";
    struct Case {
        const char* body;
        const char* where;
    };
    for (const Case& c : {Case{"g() = 1/s\nD = ‖p‖ - 1 + 0.01 g()", "loc.md:4:7: warning: division by a value that can be 0"},
                          Case{"g(q) = log(q) where q ∈ ℝ\nD = ‖p‖ - 1 + 0.01 g(s)", "loc.md:4:8: warning: logarithm of a value that can be 0"},
                          Case{"g(q) = 1/(q - 0.5) where q ∈ ℝ\nD = ‖p‖ - 1 + 0.01 g(s)", "loc.md:4:8: warning: division by a value that can be 0"},
                          Case{"g() = ∑_(i for w_i > 0.5) 1/(w_i - 0.9)\nD = ‖p‖ - 1 + 0.01 g()", "loc.md:4:27: warning: division by a value"},
                          Case{"g(q) = q - 1 where q ∈ ℝ\nD = ‖p‖ - 1 + 0.01/g(2s)", "loc.md:5:15: warning: division by a value that can be 0: with the parameters' bounds it ranges over [-1, 1]"}}) {
        INFO(c.body);
        Compiled r = compile_text("loc.md", doc(c.body, s));
        REQUIRE(r.result.exit_code == 0);
        CHECK_THAT(r.diagnostics, Catch::Contains(c.where));
    }
    auto f = write_temp("loc_strict.md", doc("g() = 1/s\nD = ‖p‖ - 1 + 0.01 g()", s));
    CHECK(run_iqc("--strict-ranges " + f.string()).exit_code == 1);
    // Arguments that keep the operation in its domain: nothing (g(s + 1) divides by [1, 2]; g(2)/g(1) by 1).
    for (const char* body : {"g(q) = 1/q where q ∈ ℝ\nD = ‖p‖ - 1 + 0.01 g(s + 1)", "g(q) = q + 1 where q ∈ ℝ\nD = ‖p‖ - 1 + 0.01 g(2)/g(1)"}) {
        INFO(body);
        Compiled r = compile_text("loc_ok.md", doc(body, s));
        REQUIRE(r.result.exit_code == 0);
        CHECK(r.diagnostics.empty());
    }
    // In the standard library's code: said at the call, naming the function (repeat divides by its cell size).
    Compiled rep = compile_text("rep.md", doc("repeat from domain\nD = ‖repeat(p, (c, 2, 2))‖ - 0.3", "c ∈ [0,2] default = 1\n"));
    REQUIRE(rep.result.exit_code == 0);
    CHECK_THAT(rep.diagnostics, Catch::Contains("rep.md:5:6: warning: in 'domain.repeat': division by a value that can be 0"));
    Compiled safe = compile_text("rep_ok.md", doc("repeat from domain\nD = ‖repeat(p, (c, 2, 2))‖ - 0.3", "c ∈ [0.5,2] default = 1\n"));
    REQUIRE(safe.result.exit_code == 0);
    CHECK(safe.diagnostics.empty());
}

TEST_CASE("a sequence's bounds hold for each element", "[ranges]") {
    // A trial (stop 52): a weighted mean over positive weights always warned of a division by a value in [-∞, ∞] (a
    // sequence could not have bounds, and an element read by its index was unknown). Bounds on a sequence are each
    // element's: its sliders', and what range analysis assumes.
    const std::string mean = "D = ∑_i w_i(‖p - x_i‖ - 0.4)/N\nN = ∑_j w_j";
    const std::string points = "x_i ∈ ℝ³ default = {(0, 0, 0), (0.5, 0, 0), (0, 0.5, 0)}\n";
    for (Target t : {Target::Shadertoy, Target::WebGL2}) {
        CompileOptions o;
        o.target = t;
        Compiled c = compile_path(write_temp("seq_bounds.md", doc(mean, points + "w_i ∈ [0.1, 1] default = {1, 0.5, 0.7}\n")), o);
        REQUIRE(c.result.exit_code == 0);
        CHECK_THAT(c.diagnostics, !Catch::Contains("division"));
        Compiled z = compile_path(write_temp("seq_bounds_0.md", doc(mean, points + "w_i ∈ [0, 1] default = {1, 0.5, 0.7}\n")), o);
        REQUIRE(z.result.exit_code == 0);
        CHECK_THAT(z.diagnostics, Catch::Contains("division by a value that can be 0: with the parameters' bounds it ranges over [0, 3]"));
    }
    // The description for engines (--meta): each element's bounds.
    auto f = write_temp("seq_bounds_meta.md", doc(mean, points + "w_i ∈ [0.1, 1] default = {1, 0.5, 0.7}\n"));
    auto meta = f.parent_path() / "seq_bounds_meta.json";
    REQUIRE(run_iqc("--target webgl2 --meta " + meta.string() + " -o " + (f.parent_path() / "sb.frag").string() + " " + f.string()).exit_code == 0);
    nlohmann::json j = nlohmann::json::parse(read_text(meta));
    int seen = 0;
    for (const auto& p : j["parameters"])
        if (p["name"].get<std::string>().rfind("w_", 0) == 0) {
            ++seen;
            CHECK(p["bounds"] == nlohmann::json::parse("[[0.1, 1.0]]"));
        }
    CHECK(seen == 3);
}

TEST_CASE("an operation an unrolled sum copies is warned of once, with infinite ends as ∞", "[ranges]") {
    // A trial (stop 52): ∑_(i for w_i > 0) ∑_(j for w_j < w_i) 1/(w_i - w_j) said the warning twice at one caret, one of
    // them over [-1.798e+308, 1.798e+308] (a strict comparison with an unbounded value moved ∞ to the largest double).
    Compiled c = compile_text("nest.md", doc("D = ‖p‖ - 1 + 0.01 ∑_(i for w_i > 0) ∑_(j for w_j < w_i) 1/(w_i - w_j)",
                                             "w_i ∈ ℝ default = {1, 1, 2}\n"));
    REQUIRE(c.result.exit_code == 0);
    CHECK_THAT(c.diagnostics, Catch::Contains("nest.md:4:58: warning: division by a value that can be 0: with the parameters' "
                                              "bounds it ranges over [-∞, ∞]"));
    CHECK_THAT(c.diagnostics, !Catch::Contains("1.798e+308"));
    const size_t first = c.diagnostics.find("warning:");
    CHECK(c.diagnostics.find("warning:", first + 1) == std::string::npos);
}
