// Interval arithmetic on the IR: for every value of a function, an interval per component that contains
// every value it can take when the parameters lie in given intervals, and an upper bound of its Euclidean
// norm (a vector's length, a matrix's Frobenius norm, a scalar's magnitude) — tracked apart from the
// components because it survives where components do not: a unit vector such as v/‖v‖ has components in
// [-1, 1] but norm 1, and a sum of two unit vectors has norm at most 2, however its components vary.
//
// Used by range analysis (guards and warnings from slider bounds, ir/passes/Ranges.h) and by the Lipschitz
// analysis (a bound of ‖∇D‖ from the gradient's IR, ir/passes/Lipschitz.h). Rules are the textbook ones
// (Moore, "Interval Analysis", 1966): sums and products of bounds, monotone functions at the ends,
// periodic functions exactly on intervals shorter than a period.
#pragma once

#include <array>
#include <functional>
#include <initializer_list>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "ir/IR.h"

namespace iqc::ir {

struct Interval {
    double lo = -std::numeric_limits<double>::infinity();
    double hi = std::numeric_limits<double>::infinity();
};

namespace iv {
Interval hull(Interval a, Interval b);
Interval add(Interval a, Interval b);
Interval neg(Interval a);
Interval mul(Interval a, Interval b);
Interval sqr(Interval a);                // x², never negative
Interval div(Interval a, Interval b);    // unbounded when b holds 0
bool contains_zero(Interval a);
double magnitude(Interval a);            // max |x|
Interval periodic(Interval a, bool is_sin);  // sin (or cos) over a: exact on spans shorter than 2π, else [-1, 1]
std::string text(Interval a);            // "[0, 2]", "[-∞, 1]"
}  // namespace iv

// The components' intervals of one value: up to four in place (scalars and vectors), more in a heap block
// (matrices). The interval analysis makes one per instruction of every box it bounds, and a heap block each
// was a third of its time (perf, examples/christmas_tree.iq's scene box and Lipschitz bound). Converts to
// and from std::vector<Interval> (parameters, calls' arguments).
class IntervalVec {
public:
    IntervalVec() = default;
    IntervalVec(size_t n, Interval v) { assign(n, v); }
    IntervalVec(std::initializer_list<Interval> l) {
        for (const Interval& x : l) push_back(x);
    }
    IntervalVec(const std::vector<Interval>& v) {  // NOLINT: implicit, as the vector it replaced
        for (const Interval& x : v) push_back(x);
    }
    operator std::vector<Interval>() const { return {begin(), end()}; }  // NOLINT
    size_t size() const { return n_; }
    bool empty() const { return n_ == 0; }
    Interval* data() { return n_ > kInPlace ? heap_.data() : in_place_.data(); }
    const Interval* data() const { return n_ > kInPlace ? heap_.data() : in_place_.data(); }
    Interval& operator[](size_t i) { return data()[i]; }
    const Interval& operator[](size_t i) const { return data()[i]; }
    Interval* begin() { return data(); }
    Interval* end() { return data() + n_; }
    const Interval* begin() const { return data(); }
    const Interval* end() const { return data() + n_; }
    Interval& back() { return data()[n_ - 1]; }
    const Interval& back() const { return data()[n_ - 1]; }
    void clear() {
        n_ = 0;
        heap_.clear();
    }
    void push_back(Interval x) {
        if (n_ < kInPlace) in_place_[n_] = x;
        else {
            if (n_ == kInPlace) heap_.assign(in_place_.begin(), in_place_.end());
            heap_.push_back(x);
        }
        ++n_;
    }
    void assign(const Interval* from, const Interval* to) {
        clear();
        for (; from != to; ++from) push_back(*from);
    }
    void assign(size_t n, Interval v) {
        n_ = n;
        if (n <= kInPlace) {
            heap_.clear();
            for (size_t k = 0; k < n; ++k) in_place_[k] = v;
        } else {
            heap_.assign(n, v);
        }
    }

private:
    static constexpr size_t kInPlace = 4;
    std::array<Interval, kInPlace> in_place_;
    std::vector<Interval> heap_;  // every component, when there are more than kInPlace
    size_t n_ = 0;
};

// What is known of one value: its components' intervals and a bound of its norm (a vector's length, a
// matrix's operator norm ‖A‖₂ — so that ‖Av‖ ≤ ‖A‖‖v‖ and a diagonal Jacobian's bound is its largest
// entry, not the root of their squares).
struct Bounds {
    IntervalVec c;            // per component (matrices row-major)
    double norm = std::numeric_limits<double>::infinity();
    bool unit = false;        // exactly a unit vector (or zero): normalize, v/‖v‖
    // Some point of the box may make this value NaN or ±∞ in the shader's 32-bit floats (a function outside its
    // domain, a division by what may be 0, a result past float's range, e^x or b^x growing past it at a finite
    // point, or an operand that may: an infinity makes NaN through 0·∞ or ∞ − ∞), which the intervals do not
    // show; only operations known to stay finite on finite operands leave it unset. Every ordered comparison
    // of a NaN is false, so a comparison of such a value is never decided true (nor `!=` false), and case
    // splitting (ir/CaseSplit.h) does not take its falsity for the opposite comparison. An unbounded interval
    // alone does not set it (a box reaching to infinity holds finite points, x² there is finite); a product of
    // huge constants that passes float's range only outside the box's finite ends is not seen ((1e19·x)² on
    // x ≥ 0.1).
    bool nan = false;
    int rows = 0, cols = 0;   // a matrix's shape (0: not a matrix)
    // An array whose values are known (a constant global's, or a parameter's where parameters are constants):
    // element k's component q is (*elements)[k·n + q], n its element's components; `c` still holds their hull.
    // An element read by a known index is then that point, not the hull: a weighted mean ∑_i w_i t_i/∑_j w_j
    // over constant weights keeps ∑_j w_j exact, and its gradient's bound is 1, not 11 (a trial's, stop 51).
    // Carried by copies and calls' arguments only (the module outlives every analysis).
    const std::vector<double>* elements = nullptr;
    // A symbolic factor of this value, where it has one (Factored, below): the value is Π_j s_j^(p_j) · y. Owned by
    // the analysis' IntervalScratch, and read only while it runs (a plain pointer: Bounds are moved by the million).
    const struct Factored* factor = nullptr;
    double norm_from_components() const;
};

// Monomial factors (Bounds::factor). Interval arithmetic bounds k·u/k over a slider k ∈ [1, 32] by 32·‖u‖: it
// takes k and 1/k each on its own. Carried as a factor, k cancels: the gradient of an exponential smooth minimum
// -log(Σ_i e^(-k d_i))/k whose k is a uniform, (Σ_i e_i·(-k ∇d_i)/S)/k, is a convex combination of the ∇d_i (a
// new user's trial derived K = 32 where it is 1: marching 27× slower). The value is Π_j s_j^(p_j) · y, with y
// within `co` (bounds without a factor of their own) and s_j the value of instruction `powers[j].first` of the
// function analysed — a scalar parameter (Param or Global) some value is divided by (itself, or times constants),
// whose interval is not a point and leaves out 0; at most 4 of them, sorted. Only the analysed function's values
// carry one (a callee's result and a loop's states drop it: their symbols are another function's).
struct Factored {
    std::vector<std::pair<ValueId, int>> powers;
    Bounds co;
};

// The bounds of every value of function `fn` when its parameters lie in `params` (one entry per
// parameter: its components' intervals) and globals are their values (constants, and parameters where
// Module::constant_parameters) or their slider bounds (parameters). Calls are analysed through the callee;
// loops and inputs are unbounded.
//
// `hook`, when given, is called with each value index i of `fn` itself (not of its callees) right after the
// rule for value i, in order, with every value so far; it may narrow values up to i in place (what a case
// split knows, ir/passes/Lipschitz.cpp); returning false stops the analysis there (later values unknown).
//
// `loop_trips` > 0 analyses a Loop whose trip count is a constant of at most that many iterations by running
// its body's analysis once per iteration (the states' bounds carried from one to the next); other loops, and
// every loop when 0 (the default: the passes' analyses), are unbounded. `work`, when given, is a budget of
// instructions (those of callees and loop bodies included) decremented as they are analysed: once it is spent,
// every value not yet analysed is unbounded.
using IntervalHook = std::function<bool(size_t, std::vector<Bounds>&)>;
std::vector<Bounds> interval_analysis(const Module& m, int fn, const std::vector<std::vector<Interval>>& params,
                                      const IntervalHook& hook = {}, int loop_trips = 0, long* work = nullptr);
// The same for a function `f` outside the module (a scratch copy: ir/Support.cpp's inlined shape); its calls
// and loops name functions of `m`.
std::vector<Bounds> interval_analysis(const Module& m, const Function& f, const std::vector<std::vector<Interval>>& params,
                                      const IntervalHook& hook = {}, int loop_trips = 0, long* work = nullptr);
// The callees' values and arguments, one vector of each per depth of calls: what one analysis needs besides
// its result. The support and Lipschitz searches analyse one function over thousands of boxes; fresh vectors
// per call and per callee were most of their time under AddressSanitizer (its allocator fills and faults in
// each block) and a sixth of it without. Owned by the search, so nothing outlives it.
struct UnivariatePlan;  // (ir/Intervals.cpp)
struct IntervalScratch {
    std::vector<std::unique_ptr<std::vector<Bounds>>> values;
    std::vector<std::unique_ptr<std::vector<IntervalVec>>> args;
    std::vector<std::unique_ptr<std::vector<const std::vector<double>*>>> elements;  // the args' Bounds::elements
    std::vector<std::unique_ptr<std::vector<char>>> symbols;  // which args are a symbol of Bounds::factor in the caller
    // Bounds::factor's, of the analysis running (reused from one to the next: `factors_used` of them are live).
    std::vector<std::unique_ptr<Factored>> factors;
    size_t factors_used = 0;
    // The final states of loops run iteration by iteration over known arrays, by the loop and its arguments'
    // bounds: one that reads nothing of the box (∑_j w_j) is run once per search, not once per box.
    std::map<std::vector<uint64_t>, std::vector<Bounds>> known_loops;
    // Per function analysed (and its size), per value: bit 1, an operand of a sum of its own type — the inner
    // partial sums of a chain, whose convex combinations are not looked for (only the whole sum's: every partial
    // sum of an unrolled ∑ of 100 quotients walking its subtree was 60% of a compile); bit 2, a scalar Param or
    // Global some value is divided by (directly, or through products and negations): a symbol of Bounds::factor.
    std::map<std::pair<const Function*, size_t>, std::vector<char>> marks;
    // Per function analysed (and its size): its components that are functions of one other component alone, read
    // more than once (ir/Intervals.cpp, UnivariatePlan), bounded on pieces of that component's interval.
    std::map<std::pair<const Function*, size_t>, std::shared_ptr<const UnivariatePlan>> univariate;
    size_t depth = 0;
};
// The same into `r` (resized; every value written), with `scratch` reused from call to call.
void interval_analysis(IntervalScratch& scratch, std::vector<Bounds>& r, const Module& m, const Function& f,
                       const std::vector<std::vector<Interval>>& params, const IntervalHook& hook = {}, int loop_trips = 0,
                       long* work = nullptr);

// Whether `a k b` holds for every a, b in the intervals (1), for none (0), or is undecided (-1).
int decided(CompareKind k, Interval a, Interval b);

// The bounds of one instruction from its operands' (the rule interval_analysis applies).
Bounds bounds_of(const Module& m, const Function& f, const Instr& in, const std::vector<const Bounds*>& args);

}  // namespace iqc::ir
