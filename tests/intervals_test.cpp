// Interval arithmetic on the IR (ir/Intervals.h): rules that must contain every value and should not lose
// what a formula makes obvious.
#include <catch2/catch.hpp>

#include <string>

#include "ir/Intervals.h"
#include "ir/Parse.h"

using namespace iqc;

TEST_CASE("mix with a weight in [0, 1] stays between its ends, outside it the affine formula", "[intervals]") {
    const char* text = R"(function f(u: ℝ, v: ℝ, t: ℝ) -> ℝ {
  %0 = ℝ Param #0 u  ; u
  %1 = ℝ Param #1 v  ; v
  %2 = ℝ Param #2 t  ; t
  %3 = ℝ Builtin mix %0, %1, %2
  return %3
}
)";
    ir::Module m;
    std::string error;
    REQUIRE(ir::parse_module(text, m, error));
    INFO(error);
    auto at = [&](ir::Interval u, ir::Interval v, ir::Interval t) { return ir::interval_analysis(m, 0, {{u}, {v}, {t}})[3].c[0]; };
    // Value noise mixes lattice values in [0, 1] by weights in [0, 1]: the result is in [0, 1], not [-1, 2].
    ir::Interval r = at({0, 1}, {0, 1}, {0, 1});
    CHECK(r.lo == 0);
    CHECK(r.hi == 1);
    r = at({2, 3}, {-1, 0}, {0.25, 0.5});
    CHECK(r.lo == -1);
    CHECK(r.hi == 3);
    // Extrapolation (t up to 2): u + t(v - u) at t = 2 reaches 2v - u.
    r = at({0, 0}, {1, 1}, {0, 2});
    CHECK(r.lo <= 0);
    CHECK(r.hi >= 2);
}

TEST_CASE("a value that may be NaN is marked, and a comparison of it is never decided true", "[intervals]") {
    // l = log(x) is NaN for x < 0, where both l ≤ 1 and l > 1 are false (IEEE 754, GLSL): over x ∈ [-1, 0.5],
    // l's interval [-∞, log 0.5] alone would decide l ≤ 1 true and drop the branch a NaN takes. 0/0 likewise.
    const char* text = R"(function f(x: ℝ, y: ℝ) -> ℝ {
  %0 = ℝ Param #0 x  ; x
  %1 = ℝ Param #1 y  ; y
  %2 = ℝ Builtin log %0
  %3 = ℝ Const 1
  %4 = condition Compare le %2, %3
  %5 = condition Compare ne %2, %3
  %6 = ℝ Div %1, %0
  %7 = condition Compare lt %6, %3
  %8 = ℝ Add %2, %3
  %9 = ℝ Const 2
  %10 = ℝ Select %4, %3, %9
  return %10
}
)";
    ir::Module m;
    std::string error;
    INFO(error);
    REQUIRE(ir::parse_module(text, m, error));
    auto r = ir::interval_analysis(m, 0, {{{-1, 0.5}}, {{0, 1}}});
    CHECK(r[2].nan);       // log of a negative
    CHECK(r[8].nan);       // carried by what is computed from it
    CHECK_FALSE(r[4].nan); // a truth value is never NaN ...
    CHECK(r[4].c[0].lo == 0);  // ... but l ≤ 1 may be false (l NaN), though l ≤ log 0.5 where it is a number
    CHECK(r[4].c[0].hi == 1);
    CHECK(r[5].c[0].hi == 1);  // l ≠ 1 may be true
    CHECK(r[6].nan);       // 0/0 (x and y both hold 0)
    CHECK(r[10].c[0].lo == 1);  // the select keeps both branches: 1 where l ≤ 1, 2 where l is NaN
    CHECK(r[10].c[0].hi == 2);
    // Over x ∈ [0.1, 0.5] the logarithm is a number: decided, and one branch.
    r = ir::interval_analysis(m, 0, {{{0.1, 0.5}}, {{1, 2}}});
    CHECK_FALSE(r[2].nan);
    CHECK_FALSE(r[6].nan);
    CHECK(r[4].c[0].lo == 1);
    CHECK(r[10].c[0].lo == 1);
    CHECK(r[10].c[0].hi == 1);
}

TEST_CASE("NaN and infinity from domains, divisions, float's range and growth are marked, an unbounded box alone is not",
          "[intervals]") {
    // x ∈ [-2, 2] unless said: each value below may be NaN or ±∞ at some point (in 32-bit floats, as the shader
    // computes), so comparisons of it stay undecided.
    const char* text = R"(function f(x: ℝ, y: ℝ) -> ℝ {
  %0 = ℝ Param #0 x  ; x
  %1 = ℝ Param #1 y  ; y
  %2 = ℝ Builtin acosh %0
  %3 = ℝ Builtin atanh %0
  %4 = ℝ Builtin log_2 %0
  %5 = ℝ Const 1
  %6 = ℝ Builtin smoothstep %5, %5, %0
  %7 = ℝ Builtin exp %1
  %8 = ℝ Const 10
  %9 = ℝ Builtin pow %8, %1
  %10 = ℝ Mul %0, %0
  %11 = ℝ Div %5, %10
  %12 = ℝ Const 1e20
  %13 = ℝ Mul %12, %0
  %14 = ℝ Mul %13, %13
  %15 = ℝ Mul %1, %1
  %16 = ℝ Builtin sin %1
  %17 = ℝ Builtin tan %0
  return %17
}
)";
    ir::Module m;
    std::string error;
    INFO(error);
    REQUIRE(ir::parse_module(text, m, error));
    auto r = ir::interval_analysis(m, 0, {{{-2, 2}}, {{0, INFINITY}}});
    CHECK(r[2].nan);   // acosh below 1
    CHECK(r[3].nan);   // atanh at ±1 and beyond
    CHECK(r[4].nan);   // log₂ of ≤ 0
    CHECK(r[6].nan);   // smoothstep with equal edges (GLSL: undefined)
    CHECK(r[7].nan);   // e^y past y = 88: float's infinity at a finite point
    CHECK(r[9].nan);   // 10^y likewise
    CHECK(r[11].nan);  // 1/x² at x = 0 (and where x² underflows)
    CHECK(r[14].nan);  // (1e20 x)² past 3.4e38 at a finite x
    CHECK(r[17].nan);  // tan across ±π/2
    CHECK_FALSE(r[10].nan);  // x² on [-2, 2]
    CHECK_FALSE(r[15].nan);  // y² on [0, ∞): unbounded only because the box is; finite at every point
    CHECK_FALSE(r[16].nan);
    // Where each is defined and finite: none.
    r = ir::interval_analysis(m, 0, {{{1.5, 1.8}}, {{0, 10}}});
    CHECK_FALSE(r[2].nan);
    CHECK(r[3].nan);  // atanh beyond 1
    CHECK_FALSE(r[4].nan);
    CHECK_FALSE(r[7].nan);
    CHECK_FALSE(r[9].nan);
    CHECK_FALSE(r[11].nan);
    CHECK(r[17].nan);  // tan on [1.5, 1.8] crosses π/2
}
