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
