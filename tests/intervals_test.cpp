// Interval arithmetic on the IR (ir/Intervals.h): rules that must contain every value and should not lose
// what a formula makes obvious.
#include <catch2/catch.hpp>

#include <cmath>
#include <string>

#include "ir/Intervals.h"
#include "ir/Parse.h"

using namespace iqc;

namespace {
// The module in `text` (the IR's text form); the test stops with the parser's message where it is none.
ir::Module parsed(const char* text) {
    ir::Module m;
    std::string error;
    const bool ok = ir::parse_module(text, m, error);
    INFO(error);
    REQUIRE(ok);
    return m;
}
}  // namespace

TEST_CASE("mix with a weight in [0, 1] stays between its ends, outside it the affine formula", "[intervals]") {
    const char* text = R"(function f(u: ℝ, v: ℝ, t: ℝ) -> ℝ {
  %0 = ℝ Param #0 u  ; u
  %1 = ℝ Param #1 v  ; v
  %2 = ℝ Param #2 t  ; t
  %3 = ℝ Builtin mix %0, %1, %2
  return %3
}
)";
    const ir::Module m = parsed(text);
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
    const ir::Module m = parsed(text);
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
    const ir::Module m = parsed(text);
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

TEST_CASE("an array of known values read by a known index is that element, not the hull", "[intervals]") {
    // A trial (stop 51): a weighted mean ∑_i w_i t_i/∑_j w_j over constant weights got K ≤ 11 (unrolled) or no
    // bound at all (a loop), where it is 1: every element read was the hull of all the weights, so ∑_j w_j was
    // 40 times the hull. Known values (a constant global, Bounds::elements) reach a callee through its argument
    // and a loop's body through its capture; an element read by a constant index, by a point, or by a range of
    // indices is that element or the hull of those it may read. A choice between two arrays knows neither.
    const char* text = R"(global @0 w: ℝ[4] constant = 1, 2, 3, 4
global @1 v: ℝ[4] constant = 5, 6, 7, 8
function sum_j(j: ℤ, sum: ℝ, w: ℝ[4]) -> ℝ {
  %0 = ℤ Param #0 j  ; j
  %1 = ℝ[4] Param #2 w  ; w
  %2 = ℝ Index %1, %0
  %3 = ℝ Param #1 sum  ; sum
  %4 = ℝ Add %3, %2
  return %4
  output sum = %4
}
function g(w: ℝ[4], k: ℝ) -> ℝ {
  %0 = ℝ[4] Param #0 w  ; w
  %1 = ℝ Param #1 k  ; k
  %2 = ℝ Element [2] %0
  %3 = ℝ At %0, %1
  %4 = ℝ Mul %2, %3
  return %4
}
function f(k: ℝ, c: ℝ) -> ℝ {
  %0 = ℝ Param #0 k  ; k
  %1 = ℝ Param #1 c  ; c
  %2 = ℝ[4] Global @0 w
  %3 = ℝ Call g %2, %0
  %4 = ℝ Const 3
  %5 = ℝ Const 0
  %6 = tuple(1) Loop from 0 sum_j %4, %5, %2
  %7 = ℝ Member .0 %6
  %8 = ℝ[4] Global @1 v
  %9 = condition Compare lt %1, %5
  %10 = ℝ[4] Select %9, %2, %8
  %11 = ℝ Element [0] %10
  %12 = ℝ Element [1] %2
  %13 = ℝ[2] Construct %1, %4
  %14 = ℝ Element [1] %13
  %15 = ℝ At %13, %0
  return %3
}
)";
    const ir::Module m = parsed(text);
    const int f = int(m.functions.size()) - 1;
    auto at = [&](ir::Interval k, ir::Interval c, size_t value) { return ir::interval_analysis(m, f, {{k}, {c}})[value].c[0]; };
    // Element [2] (3) times element k: k = 0 reads 1 (3 in all), k over [1.2, 2.4] rounds to 1 or 2 (6 to 9).
    ir::Interval r = at({0, 0}, {1, 1}, 3);
    CHECK(r.lo == 3);
    CHECK(r.hi == 3);
    r = at({1.2, 2.4}, {1, 1}, 3);
    CHECK(r.lo == 6);
    CHECK(r.hi == 9);
    // An index past the end is clamped (At): the last element.
    r = at({7, 9}, {1, 1}, 3);
    CHECK(r.lo == 12);
    CHECK(r.hi == 12);
    // An unbounded index: the hull, 3·[1, 4].
    r = at({-ir::Interval{}.hi, ir::Interval{}.hi}, {1, 1}, 3);
    CHECK(r.lo == 3);
    CHECK(r.hi == 12);
    // The loop's sum, run element by element: exactly 10 (the hull would say [4, 16]).
    r = at({0, 0}, {1, 1}, 7);
    CHECK(r.lo == 10);
    CHECK(r.hi == 10);
    // A choice between w and v: element 0 is 1 or 5 (the hull of both arrays' elements, not w's 1 alone).
    r = at({0, 0}, {-1, 1}, 11);
    CHECK(r.lo <= 1);
    CHECK(r.hi >= 8);
    // A decided choice takes its array's values: c > 0 picks v.
    r = at({0, 0}, {1, 1}, 11);
    CHECK(r.lo == 5);
    CHECK(r.hi == 5);
    r = at({0, 0}, {1, 1}, 12);
    CHECK(r.lo == 2);
    CHECK(r.hi == 2);
    // An array built of values (c, 3) keeps each element's bounds: element 1 is 3, element k ∈ [0, 1] is c or 3.
    r = at({0, 0}, {-1, 1}, 14);
    CHECK(r.lo == 3);
    CHECK(r.hi == 3);
    r = at({0, 1}, {-1, 1}, 15);
    CHECK(r.lo == -1);
    CHECK(r.hi == 3);
}

TEST_CASE("a loop's state that keeps itself or a term ends within their hull", "[intervals]") {
    // A rolled max_i x_i (and its derivative, the choice of one tangent) was unbounded: a loop is bounded only where
    // each state accumulates (s + t). A state that each step keeps itself or t (max, min, a choice) ends within the
    // hull of its first value and t's bounds (ir/IR.h, selected_term); an accumulation beside it still adds up.
    const char* text = R"(function body(k: ℤ, hi: ℝ, sum: ℝ, x: ℝ[4]) -> ℝ {
  %0 = ℤ Param #0 k  ; k
  %1 = ℝ Param #1 hi  ; hi
  %2 = ℝ Param #2 sum  ; sum
  %3 = ℝ[4] Param #3 x  ; x
  %4 = ℝ Index %3, %0
  %5 = ℝ Builtin max %1, %4
  %6 = ℝ Add %2, %4
  return %5
  output hi = %5
  output sum = %6
}
function f(x: ℝ[4]) -> ℝ {
  %0 = ℝ[4] Param #0 x  ; x
  %1 = ℝ Const 3
  %2 = ℝ Const -5
  %3 = ℝ Const 0
  %4 = tuple(2) Loop from 0 body %1, %2, %3, %0
  %5 = ℝ Member .0 %4
  %6 = ℝ Member .1 %4
  return %5
}
)";
    const ir::Module m = parsed(text);
    auto r = ir::interval_analysis(m, 1, {{{1, 2}}});
    CHECK(r[5].c[0].lo == -5);  // (the first value: the hull)
    CHECK(r[5].c[0].hi == 2);
    CHECK(r[6].c[0].lo == 4);
    CHECK(r[6].c[0].hi == 8);
}

TEST_CASE("a scalar parameter that a value is divided by cancels as a symbolic factor", "[intervals]") {
    // A trial (stop 52, F2): the exponential smooth minimum -log(∑_i e^(-k d_i))/k with k on a slider (k ∈ [1, 32]) got
    // K ≤ 32 on every target with uniforms, where it is 1: its gradient is (∑_i e_i·(-k ∇d_i)/S)/k, and intervals take k
    // and 1/k each on its own. A parameter some value is divided by is a symbol (ir/Intervals.h, Factored): k·x keeps
    // k as a factor through sums, choices, negations and products, and a division by k cancels it. Two different
    // parameters do not cancel, nor does one whose interval holds 0. A rolled sum of k·u (a loop capturing k) ends with
    // the factor too.
    const char* text = R"(function body(i: ℤ, sum: ℝ³, k: ℝ, u: ℝ³) -> ℝ³ {
  %0 = ℤ Param #0 i  ; i
  %1 = ℝ³ Param #1 sum  ; sum
  %2 = ℝ Param #2 k  ; k
  %3 = ℝ³ Param #3 u  ; u
  %4 = ℝ³ Mul %2, %3
  %5 = ℝ³ Add %1, %4
  return %5
  output sum = %5
}
function f(k: ℝ, x: ℝ, c: ℝ, m: ℝ, u: ℝ³) -> ℝ {
  %0 = ℝ Param #0 k  ; k
  %1 = ℝ Param #1 x  ; x
  %2 = ℝ Param #2 c  ; c
  %3 = ℝ Param #3 m  ; m
  %4 = ℝ³ Param #4 u  ; u
  %5 = ℝ Mul %0, %1
  %6 = ℝ Div %5, %0
  %7 = ℝ Const 2
  %8 = ℝ Mul %0, %7
  %9 = ℝ Add %5, %8
  %10 = ℝ Div %9, %0
  %11 = ℝ Const 0
  %12 = condition Compare lt %2, %11
  %13 = ℝ Select %12, %5, %8
  %14 = ℝ Neg %13
  %15 = ℝ Div %14, %0
  %16 = ℝ Const 1
  %17 = ℝ Div %16, %0
  %18 = ℝ Mul %17, %5
  %19 = ℝ Div %5, %3
  %20 = ℝ Add %5, %1
  %21 = ℝ Div %20, %0
  %22 = ℝ Const 3
  %23 = ℝ³ Const 0, 0, 0
  %24 = tuple(1) Loop from 0 body %22, %23, %0, %4
  %25 = ℝ³ Member .0 %24
  %26 = ℝ³ Div %25, %0
  %27 = ℝ Mul %19, %3
  %28 = ℝ Div %27, %0
  return %6
}
)";
    const ir::Module m = parsed(text);
    const int f = int(m.functions.size()) - 1;
    const ir::Interval k{1, 32}, x{-1, 1}, c{-1, 1};
    auto r = ir::interval_analysis(m, f, {{k}, {x}, {c}, {k}, {x, x, x}});
    auto check = [&](size_t v, double lo, double hi) {
        INFO("%" << v << ": [" << r[v].c[0].lo << ", " << r[v].c[0].hi << "]");
        CHECK(r[v].c[0].lo == Approx(lo));
        CHECK(r[v].c[0].hi == Approx(hi));
    };
    check(6, -1, 1);    // k·x/k (intervals alone: [-32, 32])
    check(10, 1, 3);    // (k·x + k·2)/k
    check(15, -2, 1);   // -(c < 0 ? k·x : k·2)/k
    check(18, -1, 1);   // (1/k)·(k·x)
    check(19, -32, 32); // k·x/m: another parameter
    check(28, -1, 1);   // ((k·x/m)·m)/k: two symbols, each cancelled
    CHECK(r[21].c[0].hi >= 32);  // (k·x + x)/k: no common factor
    // The rolled sum of k·u over 4 iterations, divided by k: 4u.
    for (size_t q = 0; q < 3; ++q) {
        CHECK(r[26].c[q].lo == Approx(-4));
        CHECK(r[26].c[q].hi == Approx(4));
    }
    CHECK(r[26].norm <= 4 * std::sqrt(3.0) + 1e-9);
    // k ∈ [-1, 1] holds 0: k·x/k is no symbol's (there x/0 is NaN).
    auto z = ir::interval_analysis(m, f, {{c}, {x}, {c}, {k}, {x, x, x}});
    CHECK(!(z[6].c[0].hi <= 1));
}

TEST_CASE("a factor that does not cancel bounds its value by the monomial's range", "[intervals]") {
    // A trial (stop 53, F9): k²‖p‖/k with k ∈ [0.25, 3] got K ≤ 36 (k² within 9, 1/k within 4, each on its own) where it
    // is 3. The factor k¹ · ‖∇‖p‖‖ is within 3 · 1. Likewise k²x/(k m) is (k/m)·x, within 6 for m ∈ [0.5, 2] (intervals
    // alone: 72), and a quotient by k/2 (a local function's argument: -ln(t)/q called with q = k/2) makes k a symbol.
    const char* text = R"(function f(k: ℝ, x: ℝ, m: ℝ) -> ℝ {
  %0 = ℝ Param #0 k  ; k
  %1 = ℝ Param #1 x  ; x
  %2 = ℝ Param #2 m  ; m
  %3 = ℝ Mul %0, %0
  %4 = ℝ Mul %3, %1
  %5 = ℝ Div %4, %0
  %6 = ℝ Mul %0, %2
  %7 = ℝ Div %4, %6
  %8 = ℝ Mul %0, %1
  %9 = ℝ Const 2
  %10 = ℝ Div %0, %9
  %11 = ℝ Div %8, %10
  return %5
}
)";
    const ir::Module m = parsed(text);
    auto r = ir::interval_analysis(m, 0, {{ir::Interval{0.25, 3}}, {ir::Interval{-1, 1}}, {ir::Interval{0.5, 2}}});
    auto check = [&](size_t v, double lo, double hi) {
        INFO("%" << v << ": [" << r[v].c[0].lo << ", " << r[v].c[0].hi << "]");
        CHECK(r[v].c[0].lo == Approx(lo));
        CHECK(r[v].c[0].hi == Approx(hi));
    };
    check(5, -3, 3);    // k²x/k = k·x (intervals alone: [-36, 36])
    check(7, -6, 6);    // k²x/(k m) = (k/m)·x (alone: [-72, 72])
    check(11, -2, 2);   // k·x/(k/2) = 2x
}

TEST_CASE("floor, ceil, round, fract and mod within one cell are the value shifted by its cell, smoothstep is monotone",
          "[intervals]") {
    // A point box's fract was [0, 1] and its floor two integers (value noise's lattice corner at one point: the
    // Lipschitz search's point bounds were as loose as its boxes').
    const char* text = R"(function f(x: ℝ) -> ℝ {
  %0 = ℝ Param #0 x  ; x
  %1 = ℝ Builtin floor %0
  %2 = ℝ Builtin ceil %0
  %3 = ℝ Builtin round %0
  %4 = ℝ Builtin fract %0
  %5 = ℝ Const 2.5
  %6 = ℝ Builtin mod %0, %5
  %7 = ℝ Const 1
  %8 = ℝ Const 3
  %9 = ℝ Builtin smoothstep %7, %8, %0
  %10 = ℝ Builtin smoothstep %8, %7, %0
  return %10
}
)";
    const ir::Module m = parsed(text);
    auto at = [&](ir::Interval x, size_t v) { return ir::interval_analysis(m, 0, {{x}})[v].c[0]; };
    // (the ends as computed in double: -8.043 + 9 is 0.957 within a rounding)
    auto within = [](ir::Interval r, double lo, double hi) { return std::fabs(r.lo - lo) <= 1e-12 && std::fabs(r.hi - hi) <= 1e-12; };
    CHECK(within(at({-8.043, -8.043}, 1), -9, -9));
    CHECK(within(at({-8.043, -8.043}, 4), 0.957, 0.957));
    CHECK(within(at({2.2, 2.7}, 4), 0.2, 0.7));
    CHECK(within(at({2.2, 3.7}, 4), 0, 1));      // across a lattice line: all of [0, 1)
    CHECK(within(at({2.2, 3.7}, 1), 2, 3));
    CHECK(within(at({2.2, 3.7}, 2), 3, 4));
    CHECK(within(at({2.2, 2.4}, 3), 2, 2));
    CHECK(within(at({2.4, 2.6}, 3), 2, 3));      // a tie goes either way
    CHECK(within(at({-6.0, -5.5}, 6), 1.5, 2));  // -6 − 2.5·⌊-2.4⌋ = 1.5
    CHECK(within(at({-6.0, -4.0}, 6), 0, 2.5));  // across a period
    CHECK(within(at({1.5, 2}, 9), 0.15625, 0.5));
    CHECK(within(at({0, 4}, 9), 0, 1));
    CHECK(within(at({1.5, 2}, 10), 0.5, 0.84375));  // reversed edges: decreasing
}

TEST_CASE("a component read more than once through one source is bounded on pieces of that source", "[intervals]") {
    // Value noise's weight u = f·f·(3 − 2f) of f = fract(x), and its derivative 2f(3 − 2f) − 2f², read by a
    // product with y (another component of the point: another leaf): f ∈ [0, 1] made u [0, 3] and u′ [-2, 6] taken operand by operand, where
    // they are [0, 1] and [0, 1.5] (a displacement by value noise derived K 51.6, its slope ≤ 2.1: trial76). Also
    // w(1 − w) of w = f² (through w to f) and a vector's components apart. Only periodic values are sources: x(1 − x)
    // of the box's own x is left to smaller boxes.
    const char* text = R"(function f(q: ℝ²) -> ℝ {
  %0 = ℝ² Param #0 q  ; q
  %1 = ℝ Extract [0] %0
  %2 = ℝ Extract [1] %0
  %3 = ℝ Builtin fract %1
  %4 = ℝ Hadamard %3, %3
  %5 = ℝ Const 3
  %6 = ℝ Const 2
  %7 = ℝ Mul %6, %3
  %8 = ℝ Sub %5, %7
  %9 = ℝ Mul %4, %8
  %10 = ℝ Mul %7, %8
  %11 = ℝ Mul %6, %4
  %12 = ℝ Sub %10, %11
  %13 = ℝ Mul %9, %2
  %14 = ℝ Mul %12, %2
  %15 = ℝ Mul %3, %3
  %16 = ℝ Const 1
  %17 = ℝ Sub %16, %15
  %18 = ℝ Mul %15, %17
  %19 = ℝ Mul %18, %2
  %20 = ℝ² Construct %3, %1
  %21 = ℝ² Hadamard %20, %20
  %22 = ℝ Extract [0] %21
  %23 = ℝ Mul %22, %2
  %24 = ℝ Add %13, %14
  %25 = ℝ Add %24, %19
  %26 = ℝ Add %25, %23
  %27 = ℝ Sub %16, %1
  %28 = ℝ Mul %1, %27
  %29 = ℝ Mul %28, %2
  %30 = ℝ Add %26, %29
  return %30
}
)";
    const ir::Module m = parsed(text);
    const ir::Interval x{-10.3, 7.9};
    auto r = ir::interval_analysis(m, 0, {{x, {1, 2}}});
    const ir::Interval u = r[9].c[0], du = r[12].c[0];
    INFO("u " << ir::iv::text(u) << ", u' " << ir::iv::text(du));
    CHECK(u.lo <= 0);
    CHECK(u.hi >= 1);
    CHECK(u.lo >= -0.01);
    CHECK(u.hi <= 1.07);
    CHECK(du.lo <= 0);
    CHECK(du.hi >= 1.5);
    CHECK(du.lo >= -0.06);
    CHECK(du.hi <= 1.8);
    // w(1 − w), w = f² ∈ [0, 1]: within [0, ¼] (plain: [0, 1]), through w to f
    const ir::Interval b = r[18].c[0];
    INFO("w(1 - w) " << ir::iv::text(b));
    CHECK(b.hi >= 0.25);
    CHECK(b.hi <= 0.3);
    CHECK(b.lo <= 0);
    CHECK(b.lo >= -0.05);
    // the first component of (f, x)∘(f, x): f², within [0, 1]
    CHECK(r[22].c[0].lo >= 0);
    CHECK(r[22].c[0].hi <= 1.000001);
    CHECK(r[21].c[1].hi >= 10.3 * 10.3);  // (the second, x²)
    // x(1 − x) over the box's x: not refined (the box search splits x)
    const ir::Interval plain = ir::iv::mul(x, ir::iv::add({1, 1}, ir::iv::neg(x)));
    CHECK(r[28].c[0].lo == plain.lo);
    CHECK(r[28].c[0].hi == plain.hi);
    // Every point's values are inside (the pieces cover the source's interval).
    for (int k = 0; k <= 2000; ++k) {
        const double xv = x.lo + (x.hi - x.lo) * k / 2000.0, f = xv - std::floor(xv);
        const double uv = f * f * (3 - 2 * f), dv = 2 * f * (3 - 2 * f) - 2 * f * f, w = f * f;
        INFO("x = " << xv);
        CHECK((uv >= u.lo && uv <= u.hi));
        CHECK((dv >= du.lo && dv <= du.hi));
        CHECK((w * (1 - w) >= b.lo && w * (1 - w) <= b.hi));
    }
}

TEST_CASE("a mix of two vectors by one weight within [0, 1] is no longer than the longer", "[intervals]") {
    // Gradient noise blends its corners' unit gradients: each component's hull is [-1, 1], the norm 1, not √3.
    const char* text = R"(function f(u: ℝ³, v: ℝ³, t: ℝ) -> ℝ³ {
  %0 = ℝ³ Param #0 u  ; u
  %1 = ℝ³ Param #1 v  ; v
  %2 = ℝ Param #2 t  ; t
  %3 = ℝ³ Builtin normalize %0
  %4 = ℝ³ Builtin normalize %1
  %5 = ℝ³ Builtin mix %3, %4, %2
  return %5
}
)";
    const ir::Module m = parsed(text);
    const ir::Interval any{-1, 1};
    auto r = ir::interval_analysis(m, 0, {{any, any, any}, {any, any, any}, {{0, 1}}});
    CHECK(r[5].norm <= 1 + 1e-12);
    CHECK(r[5].c[0].lo == -1);
    // A weight past 1 extrapolates: no such bound
    r = ir::interval_analysis(m, 0, {{any, any, any}, {any, any, any}, {{0, 2}}});
    CHECK(r[5].norm > 1.5);
}
