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
