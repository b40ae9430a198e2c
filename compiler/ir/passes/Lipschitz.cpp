#include "ir/passes/Lipschitz.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <fmt/format.h>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <queue>
#include <set>
#include <unordered_map>

#include "ir/Builder.h"
#include "ir/CaseSplit.h"
#include "ir/Eval.h"
#include "ir/passes/CSE.h"
#include "ir/passes/DCE.h"
#include "ir/passes/Differentiate.h"
#include "ir/passes/Inline.h"
#include "ir/passes/Linear.h"
#include "ir/Support.h"
#include "sema/Builtins.h"
#include "source/Internal.h"

namespace iqc::ir {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kWorkBudget = 2e7;  // instructions evaluated per estimate (boxes and samples)
constexpr double kStallDrop = 1e-3;  // derive(): a search whose worst bound drops less than this ...
constexpr int kStallBoxes = 256;     // ... over this many boxes stops
constexpr double kUnbounded = 64;  // a derived K above this over the region is useless for marching
// A derived bound marching can use: finite and at most kUnbounded.
bool useful_bound(double derived) { return std::isfinite(derived) && derived <= kUnbounded; }
// Without a useful bound, 1.25 times the steepest sample outside the shape is marched by up to this (beyond, as if
// 1-Lipschitz: a singular spot sampled at 10⁴ would stop every ray short). Classic metaballs r − ∑_i 1/‖p − x_i‖²
// sample 47 at their surface (more at r's high end, on targets with sliders), 70(‖p‖ − 1) 70: each drawn with its
// samples' K (the metaballs at K = 235: 4.7 steps a pixel, 112 at the 99th percentile, in their support box),
// nothing drawn at 1.
constexpr double kSampledCap = 256;
constexpr double kSampledMargin = 1.25;  // without a useful bound: the steepest sample times this
constexpr size_t kMaxRefined = 16;  // items whose bounds the refinements may tighten (in the module's order)
// Interval instruction evaluations case splitting may spend: per estimate (the docs' table), and per pass over
// a module (~150 ns each in a release build, ~12× that under the sanitizers: a compile spends at most ~0.1 s
// on it, 1 s under ASan, whose fuzzing allows 10 s per input; the twisted bar's 5.7 needs less).
constexpr double kSplitWorkPerEstimate = 8e6, kSplitWorkPerModule = 5e5;
// Estimates of slider cells (K as a function of the sliders, where they are uniforms) per module: up to 27 per item
// (~5 ms each for the displaced torus), items past this keep the one K of their whole ranges.
constexpr long kMaxCellEstimates = 128;
// The analysis work (ir::analysis_work: ~180·10⁶ a second in a release build) an item's cells may take: 8 of its
// whole's estimate (the displaced torus' 25 cells took 0.6, a sampled metaballs' 7 cells 7, a smooth subtraction's 6
// cells 3 for a K of 2.2 at its defaults where its whole's is 7.5), or 10⁸ (~0.55 s) where that is more; a module's,
// 3·10⁸ (~1.7 s; 30× that in the fuzzing build: six moving instances of that smooth subtraction, each with cells, took
// 7 s, 24 of them 15 s). A sampled recurrence's 9 cells, each as costly as its whole, took 700 ms and kept none (the CI's
// fuzzing stopped at it). Past it, the item keeps the K of its sliders' ranges.
constexpr double kCellWorkRatio = 8;
constexpr uint64_t kCellWorkFloor = 100'000'000, kCellWorkPerModule = 300'000'000;
// Items whose K follows their sliders, per module: each is a value iqc_prepare computes per pixel and every step reads,
// and llvmpipe compiles a march with many such values live much more slowly (ir/passes/Hoist.cpp's cap); the others
// keep the K of their sliders' whole ranges.
constexpr size_t kMaxCellItems = 8;
// A group's members whose values iqc_prepare checks against their defaults' hull (a loop once per pixel, ~4 comparisons a
// member and slider): larger groups keep the K of their sliders' whole ranges.
constexpr size_t kMaxHullMembers = 1024;
constexpr size_t kSplitMaxInstructions = 2000;  // a function larger than this is not split
// The work of one sampled evaluation (a gradient through a recurrence of 10⁸ steps is not sampled: its
// samples stop at the first evaluation past this, with what was seen so far).
constexpr uint64_t kSampleSteps = 1000000;
constexpr uint64_t kJumpWork = 40000000;  // find_jump's evaluator steps, in all

constexpr size_t kMaxFlat = 20000;  // a flattened function larger than this is not taken apart

// A copy of `f` with its calls inlined (every call, or all but those of the functions `keep` accepts) and its
// common subexpressions merged (`twist(p, k)` written four times is one value): the form the refinements
// below take apart.
// x(1 − h) + y h, in any order of its sums and products, becomes mix(x, y, h) (in place: the same value), so that a
// blend written out (Quilez's polynomial smooth minimum as b(1 − h) + a h − k h(1 − h)) is bound as the mix form is:
// its partial in a is h + (a − b)∂h/∂a, where intervals of b·∂h/∂a and a·∂h/∂a apart gave 22.6 (a trial's, stop 54).
void mix_forms(Function& f) {
    auto one_minus = [&](ValueId v, ValueId& h) {
        const Instr& in = f.body[v];
        if (in.op != Op::Sub || in.args.size() != 2) return false;
        const Instr& one = f.body[in.args[0]];
        if (one.op != Op::Const || one.data.size() != 1 || one.data[0] != 1) return false;
        h = in.args[1];
        return true;
    };
    // x(1 − h) + y h as (x, y, h), u the product with 1 − h and v the one with h; false where it is not one.
    auto mix_of = [&](const Instr& u, const Instr& v, ValueId out[3]) {
        if (u.op != Op::Mul || v.op != Op::Mul || u.args.size() != 2 || v.args.size() != 2) return false;
        for (int su = 0; su < 2; ++su)
            for (int sv = 0; sv < 2; ++sv) {
                ValueId h;
                const ValueId x = u.args[size_t(1 - su)], y = v.args[size_t(1 - sv)];
                if (!one_minus(u.args[size_t(su)], h) || v.args[size_t(sv)] != h) continue;
                // (scalars; or vectors of one size with a scalar weight: a gradient's (1 − h)∂x + h∂y)
                const Type &tx = f.body[x].type, &ty = f.body[y].type;
                if (!f.body[h].type.is_scalar() || !(tx.is_scalar() || tx.is_vector()) || tx != ty) continue;
                out[0] = x, out[1] = y, out[2] = h;
                return true;
            }
        return false;
    };
    for (size_t i = 0; i < f.body.size(); ++i) {
        Instr& in = f.body[i];
        if (in.op != Op::Add || in.args.size() != 2 || !(in.type.is_scalar() || in.type.is_vector())) continue;
        ValueId xyh[3];
        for (int order = 0; order < 2; ++order) {
            if (!mix_of(f.body[in.args[size_t(order)]], f.body[in.args[size_t(1 - order)]], xyh)) continue;
            in.op = Op::Builtin;
            in.aux = *find_builtin("mix");
            in.args = {xyh[0], xyh[1], xyh[2]};
            break;
        }
    }
}

Function flattened(const Module& m, const Function& f, const std::function<bool(const Function&)>& keep = nullptr) {
    Function flat = keep ? inline_calls_except(m, f, keep) : inline_calls(m, f);
    eliminate_common_subexpressions(flat);
    mix_forms(flat);
    return flat;
}

EvalInputs sample_inputs() {
    EvalInputs in;
    in.max_steps = kSampleSteps;
    return in;
}

// A bound of ‖J‖₂ for the 3×3 matrix J whose rows are 3 consecutive components each of `c` (row-major):
// the square root of Gershgorin's bound of λ_max(JᵀJ), with JᵀJ's entries in interval arithmetic. Exact for
// a rotation whose angle a box pins (JᵀJ = I), where the Frobenius norm says √3.
double jacobian_norm(const std::vector<Interval>& c) {
    if (c.size() != 9) return kInf;
    double worst = 0;
    for (size_t i = 0; i < 3; ++i) {
        double row = 0;
        for (size_t j = 0; j < 3; ++j) {
            Interval e{0, 0};
            for (size_t r = 0; r < 3; ++r)
                e = iv::add(e, i == j ? iv::sqr(c[r * 3 + i]) : iv::mul(c[r * 3 + i], c[r * 3 + j]));
            row += i == j ? std::max(e.hi, 0.0) : iv::magnitude(e);
        }
        worst = std::max(worst, row);
    }
    return std::isnan(worst) ? kInf : std::sqrt(worst);
}

double result_norm(const Bounds& g, bool jacobian) {
    double n = jacobian ? std::min(g.norm, jacobian_norm(g.c)) : g.norm;
    return std::isnan(n) ? kInf : n;
}


// Interval passes a case split may spend: per box, and left in all.
struct SplitBudget {
    int per_box;
    double pool;
    bool query_point = true;  // parameter 0 is the query point p (not a cut's intermediate vector u = T(p))
};

// The norm bound of the gradient (jacobian: of the Jacobian given by its rows) over one box of p; with
// `split`, by case splitting (CaseSplit, for a function without calls) while its passes last.
thread_local long t_boxes = 0;  // box_bound's evaluations in the current estimate (LipschitzEstimate::boxes)
thread_local double t_blend_steepest = 0;  // LipschitzEstimate::blend_steepest of the current estimate
// The buffers of one search's interval analyses (IntervalScratch: reused from box to box).
struct BoxScratch {
    std::vector<Bounds> values;
    IntervalScratch calls;
};
double box_bound(BoxScratch& scratch, const Module& m, int grad, const std::vector<Interval>& box,
                 const std::vector<std::vector<Interval>>& others, bool jacobian = false, SplitBudget* split = nullptr) {
    ++t_boxes;
    std::vector<std::vector<Interval>> params = {box};
    params.insert(params.end(), others.begin(), others.end());
    if (split && split->pool >= 1) {
        CaseSplitOptions o;
        o.query_point = split->query_point;
        o.floor = 0;
        int passes = int(std::min<double>(split->per_box, split->pool)), left = 0;
        double r = case_split_bound(m, m.functions[size_t(grad)], params,
                                    [jacobian](const Bounds& g) { return result_norm(g, jacobian); }, passes, o, &left);
        split->pool -= passes - left;
        return r;
    }
    interval_analysis(scratch.calls, scratch.values, m, m.functions[size_t(grad)], params);
    return result_norm(scratch.values[m.functions[size_t(grad)].result], jacobian);
}

struct Box {
    std::vector<Interval> c;
    double bound;
    bool operator<(const Box& o) const { return bound < o.bound; }
};

// Whether a box has a point within `ball` of the origin (ball 0: every box counts).
bool meets_ball(const std::vector<Interval>& box, double ball) {
    if (ball <= 0) return true;
    double s = 0;
    for (const Interval& c : box) {
        double near = c.lo > 0 ? c.lo : c.hi < 0 ? -c.hi : 0;
        s += near * near;
    }
    return s <= ball * ball;
}

// Branch and bound: split the worst box along its longest side until the budget is spent (halves outside
// the ball are dropped); the worst box's bound then bounds the whole region. Every 8th split also bounds one
// point of the worst box, off its centre: a point's bound is no more than any box's around it, so once the
// worst box is down to the largest point bound seen, no split can lower the result and the search stops (a
// warp's rotation, whose Jacobian bound is 1 at every point, took 2,048 boxes to confirm it).
// `witness`, when given, receives the largest gradient norm known exactly at one of those points (every value there a
// point, as where the other parameters are constants): a true gradient, as a sample's, but where the bound is largest.
double derive(const Module& m, int grad, const std::vector<Interval>& region, const std::vector<std::vector<Interval>>& others,
              double ball, int budget, bool jacobian = false, SplitBudget* split = nullptr,
              std::vector<std::vector<Interval>>* worst_boxes = nullptr, double* witness = nullptr) {
    std::priority_queue<Box> q;
    BoxScratch scratch;
    q.push({region, box_bound(scratch, m, grad, region, others, jacobian, split)});
    double seen = 0;  // the largest bound at a point
    // A plateau: the worst bound lowered by less than kStallDrop over kStallBoxes splits. The points' bounds stop most
    // searches, but a worst box whose bound no split lowers (a Jacobian's bound at a warp's seam, above every point's)
    // spent the whole budget: 2,048 boxes per cut at 2.56 all the way (examples/christmas_tree.iq's tree, whose points
    // were as loose as its boxes until a point's fract and floor were points).
    double plateau = kInf;
    int plateau_from = 1;
    for (int used = 1, pops = 0; used + 2 <= budget && !q.empty(); ++pops) {
        Box worst = q.top();
        if (!std::isfinite(worst.bound) && used > budget / 2) break;
        if (std::isfinite(worst.bound)) {
            if (worst.bound < plateau * (1 - kStallDrop)) plateau = worst.bound, plateau_from = used;
            else if (used - plateau_from >= kStallBoxes) break;
        }
        if (std::isfinite(worst.bound) && pops % 8 == 0) {
            std::vector<Interval> mid = worst.c;
            // off-centre: a symmetric region's centre is where shapes are singular (‖p‖'s gradient at 0) and
            // a comparison ties (|x|'s derivative at 0 is the hull of both signs, above any true value)
            for (Interval& c : mid) c.lo = c.hi = c.lo + 0.4617 * (c.hi - c.lo);
            double here = box_bound(scratch, m, grad, mid, others, jacobian);
            if (std::isfinite(here)) seen = std::max(seen, here);  // (not counted: the budget's boxes stay)
            if (witness && !jacobian && std::isfinite(here)) {
                const Bounds& g = scratch.values[m.functions[size_t(grad)].result];
                bool exact = !g.nan && !g.c.empty();
                for (const Interval& c : g.c) exact = exact && c.hi - c.lo <= 1e-9 * (1 + std::fabs(c.lo));
                if (exact) *witness = std::max(*witness, g.norm_from_components());
            }
            if (worst.bound <= seen) break;
        }
        q.pop();
        size_t axis = 0;
        for (size_t k = 1; k < worst.c.size(); ++k)
            if (worst.c[k].hi - worst.c[k].lo > worst.c[axis].hi - worst.c[axis].lo) axis = k;
        double mid = 0.5 * (worst.c[axis].lo + worst.c[axis].hi);
        if (!(mid > worst.c[axis].lo && mid < worst.c[axis].hi)) {  // nothing left to split
            q.push(worst);
            break;
        }
        for (int half = 0; half < 2; ++half) {
            Box b = worst;
            (half ? b.c[axis].lo : b.c[axis].hi) = mid;
            if (!meets_ball(b.c, ball)) continue;
            b.bound = box_bound(scratch, m, grad, b.c, others, jacobian, split);
            q.push(std::move(b));
            ++used;
        }
    }
    double result = q.empty() ? kInf : q.top().bound;
    for (int k = 0; worst_boxes && k < 8 && !q.empty(); ++k, q.pop()) worst_boxes->push_back(q.top().c);
    return result;
}

// The instruction evaluations case splitting may still spend while the current estimate runs (set by
// estimate_lipschitz; the pass shares one allowance among its items, ~100 ns each).
thread_local double t_split_work = 0;
double split_pool_left() { return t_split_work; }

// derive() by case splitting on `grad` (flattened in place first): up to kSplitPasses interval passes per
// box, a quarter of the boxes, while the allowance lasts.
double split_derive(Module& m, int grad, const std::vector<Interval>& region, const std::vector<std::vector<Interval>>& others,
                    double ball, int budget, bool query_point = true) {
    // Case splitting needs a function without calls: `grad` is replaced by its flattened copy (calls inlined,
    // common subexpressions merged, dead code dropped).
    Function flat = flattened(m, m.functions[size_t(grad)]);
    eliminate_dead_code(flat);
    if (flat.body.empty() || flat.body.size() > kMaxFlat) return kInf;
    m.functions[size_t(grad)] = std::move(flat);
    constexpr int kSplitPasses = 1500;
    double size = double(std::max<size_t>(1, m.functions[size_t(grad)].body.size()));
    if (t_split_work < size) return kInf;
    SplitBudget split{kSplitPasses, t_split_work / size, query_point};
    double k = derive(m, grad, region, others, ball, std::max(8, budget / 4), false, &split);
    t_split_work = std::max(0.0, split.pool * size);
    return k;
}

// Deterministic uniform numbers in [0, 1) (splitmix64, Steele et al. 2014).
struct SplitMix64 {
    uint64_t state;
    double operator()() {
        state += 0x9E3779B97F4A7C15ull;
        uint64_t z = state;
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        return double((z ^ (z >> 31)) >> 11) / double(1ull << 53);
    }
};

// Uniform random arguments of a sampled function: a point of the region (unbounded sides within ±1000), and
// the other parameters (a group's member index, …) in theirs.
struct RandomArguments {
    SplitMix64 next;
    double pick(Interval i) {
        double lo = std::isfinite(i.lo) ? i.lo : -1e3, hi = std::isfinite(i.hi) ? i.hi : 1e3;
        return lo + (hi - lo) * next();
    }
    Value point(const std::vector<Interval>& region) { return {Type::vector(3), {pick(region[0]), pick(region[1]), pick(region[2])}}; }
    void others(std::vector<Value>& args, const Function& g, const std::vector<std::vector<Interval>>& others) {
        for (size_t k = 1; k < g.params.size(); ++k) {
            const Type& t = g.params[k].type;
            std::vector<double> v;
            for (const Interval& i : others[k - 1]) v.push_back(t.kind == Type::Integer ? std::floor(pick({i.lo, i.hi + 0.999})) : pick(i));
            args[k] = {t, v};
        }
    }
};

// `steps`, when given, receives the evaluator steps the samples took (EvalInputs::max_steps' unit: their cost).
// `outside`, when given, receives the steepest gradient among the samples where distance function `fn` is ≥ 0.
double sample(const Module& m, int grad, const std::vector<Interval>& region, const std::vector<std::vector<Interval>>& others,
              double ball, int samples, int* evaluated = nullptr, bool differences = false, uint64_t* steps = nullptr,
              int fn = -1, double* outside = nullptr) {
    // A field that moves (time, the mouse) is sampled at 16 moments over two minutes and mouse positions
    // over the view: its gradient at time 0 alone says nothing of time 40 (sin(time·p) steepens).
    std::vector<std::unique_ptr<Evaluator>> evs;
    SplitMix64 moments{0x2545F4914F6CDD1Dull};
    bool moves = false;
    for (const auto& fn : m.functions)
        for (const Instr& in : fn.body) moves |= in.op == Op::Input;
    for (int k = 0; k < (moves ? 16 : 1); ++k) {
        EvalInputs in = sample_inputs();
        in.time = k == 0 ? 0 : 120 * moments();
        in.mouse[0] = k == 0 ? 0 : moments();
        in.mouse[1] = k == 0 ? 0 : moments();
        evs.push_back(std::make_unique<Evaluator>(m, in));
    }
    const Function& g = m.functions[size_t(grad)];
    RandomArguments random{{0x9E3779B97F4A7C15ull}};
    double worst = 0;
    std::vector<Value> args(g.params.size());
    for (int s = 0; s < samples; ++s) {
        args[0] = random.point(region);
        if (ball > 0 && args[0].v[0] * args[0].v[0] + args[0].v[1] * args[0].v[1] + args[0].v[2] * args[0].v[2] > ball * ball) continue;
        random.others(args, g, others);
        Value r;
        try {
            Evaluator& ev = *evs[size_t(s) % evs.size()];
            if (!differences) {
                r = ev.call(grad, args);
            } else {
                // Central differences of the distance itself (`grad` is the distance function here): where the
                // gradient's IR is too large to evaluate, the distance may still be.
                double h = 1e-4 * std::max(1.0, std::sqrt(args[0].v[0] * args[0].v[0] + args[0].v[1] * args[0].v[1] +
                                                          args[0].v[2] * args[0].v[2]));
                r = {Type::vector(3), {0, 0, 0}};
                for (int a = 0; a < 3; ++a) {
                    std::vector<Value> hi = args, lo = args;
                    hi[0].v[size_t(a)] += h;
                    lo[0].v[size_t(a)] -= h;
                    r.v[size_t(a)] = (ev.call(grad, hi).v.at(0) - ev.call(grad, lo).v.at(0)) / (2 * h);
                }
            }
        } catch (const EvalLimit&) {
            break;
        }
        if (evaluated) ++*evaluated;
        if (differences) {  // a distance this large: as many points as 2·10⁷ evaluator steps allow (about 1 s)
            uint64_t spent = 0;
            for (const auto& ev : evs) spent += ev->work();
            if (spent > 20000000) samples = s;  // this one is the last
        }
        double n = 0;
        for (double x : r.v) n += x * x;
        n = std::sqrt(n);
        if (std::isfinite(n)) worst = std::max(worst, n);
        if (outside && fn >= 0 && std::isfinite(n)) {
            try {
                const Value d = evs[size_t(s) % evs.size()]->call(fn, args);
                if (!d.v.empty() && d.v[0] >= 0) *outside = std::max(*outside, n);
            } catch (const EvalLimit&) {
            }
        }
    }
    if (steps)
        for (const auto& ev : evs) *steps += ev->work();
    return worst;
}

// The steepest gradient met on `paths` walks toward the surface: from a uniform point of the region, up to 6
// damped Newton steps p ← p - 0.9·D(p)·∇D/‖∇D‖², the gradient's norm read at every point visited. Uniform
// samples over the region where an instance is marched rarely land near a shape a unit across (a thin
// shell whose distance steepens to 1.9 just outside it: every sample within 1, marched as 1-Lipschitz,
// holes in its picture; a new user's trial, stop 40); the walks end on the surface, where steps overshoot.
double sample_towards_surface(const Module& m, int fn, int grad, const std::vector<Interval>& region,
                              const std::vector<std::vector<Interval>>& others, double ball, int paths,
                              std::vector<std::array<double, 3>>* ends = nullptr, double* outside = nullptr) {
    Evaluator ev(m, sample_inputs());
    const Function& g = m.functions[size_t(grad)];
    RandomArguments random{{0xBF58476D1CE4E5B9ull}};
    double worst = 0;
    std::vector<Value> args(g.params.size());
    try {
        for (int s = 0; s < paths; ++s) {
            args[0] = random.point(region);
            random.others(args, g, others);
            for (int step = 0; step < 6; ++step) {
                const std::vector<double>& p = args[0].v;
                if (ball > 0 && p[0] * p[0] + p[1] * p[1] + p[2] * p[2] > ball * ball) break;
                bool inside = true;
                for (size_t c = 0; c < 3; ++c) inside &= !(p[c] < region[c].lo) && !(p[c] > region[c].hi);
                if (!inside) break;
                Value gv = ev.call(grad, args), dv = ev.call(fn, args);
                if (gv.v.size() != 3 || dv.v.empty()) break;
                double n2 = gv.v[0] * gv.v[0] + gv.v[1] * gv.v[1] + gv.v[2] * gv.v[2];
                if (!std::isfinite(n2) || !std::isfinite(dv.v[0])) break;
                worst = std::max(worst, std::sqrt(n2));
                if (outside && dv.v[0] >= 0) *outside = std::max(*outside, std::sqrt(n2));
                if (n2 < 1e-20) break;
                // (a point within a tenth of a unit of the surface, by the step: where the walk ends)
                if (ends && step == 5 && std::fabs(dv.v[0]) / std::sqrt(n2) < 0.1) ends->push_back({p[0], p[1], p[2]});
                for (size_t c = 0; c < 3; ++c) args[0].v[c] -= 0.9 * dv.v[0] * gv.v[c] / n2;
            }
        }
    } catch (const EvalLimit&) {
    }
    return worst;
}

// The steepest gradient at `samples` uniform points of the region where the distance is ≥ 0 (outside the shape:
// where sphere tracing steps from; a segment from such a point to its nearest surface point stays outside).
double sample_outside(const Module& m, int fn, int grad, const std::vector<Interval>& region,
                      const std::vector<std::vector<Interval>>& others, double ball, int samples) {
    Evaluator ev(m, sample_inputs());
    const Function& g = m.functions[size_t(grad)];
    RandomArguments random{{0xD1B54A32D192ED03ull}};
    double worst = 0;
    std::vector<Value> args(g.params.size());
    try {
        for (int s = 0; s < samples; ++s) {
            args[0] = random.point(region);
            const std::vector<double>& p = args[0].v;
            if (ball > 0 && p[0] * p[0] + p[1] * p[1] + p[2] * p[2] > ball * ball) continue;
            random.others(args, g, others);
            Value d = ev.call(fn, args);
            if (d.v.empty() || !(d.v[0] >= 0)) continue;
            Value r = ev.call(grad, args);
            double n = 0;
            for (double x : r.v) n += x * x;
            n = std::sqrt(n);
            if (std::isfinite(n)) worst = std::max(worst, n);
        }
    } catch (const EvalLimit&) {
    }
    return worst;
}

// The steepest gradient met on `paths` line searches for the surface: from a uniform point of the region, D along
// the ray down its gradient (up when D < 0) at 64 distances growing geometrically from 10⁻³ to the region's size;
// where D changes sign, bisection to the crossing (the gradient read there and a hundredth of a unit to either side),
// else a new search from the least |D| on the ray, up to 6 times. The Newton walks (sample_towards_surface) step by
// D/‖∇D‖, and a field that is flat far out jumps out of the region: classic metaballs r − ∑_i 1/‖p − x_i‖², slope 2/ρ³
// (~63) at their surface and ~10⁻⁵ at 100 units, had every sample within 0.28 and were marched as 1-Lipschitz (an empty
// picture: a trial's, stop 53). `ends` receives the crossings.
double sample_by_line_search(const Module& m, int fn, int grad, const std::vector<Interval>& region,
                             const std::vector<std::vector<Interval>>& others, double ball, int paths,
                             std::vector<std::array<double, 3>>* ends = nullptr, double* outside = nullptr) {
    Evaluator ev(m, sample_inputs());
    const Function& g = m.functions[size_t(grad)];
    RandomArguments random{{0x9E3779B97F4A7C15ull}};
    double worst = 0, size = 0;
    for (size_t c = 0; c < 3; ++c) {
        const double w = std::isfinite(region[c].hi - region[c].lo) ? region[c].hi - region[c].lo : 2e3;
        size = std::max(size, w);
    }
    if (ball > 0) size = std::min(size, 2 * ball);
    if (!(size > 1e-3)) return 0;
    std::vector<Value> args(g.params.size());
    auto inside = [&](const std::array<double, 3>& q) {
        if (ball > 0 && q[0] * q[0] + q[1] * q[1] + q[2] * q[2] > ball * ball) return false;
        for (size_t c = 0; c < 3; ++c)
            if (q[c] < region[c].lo || q[c] > region[c].hi) return false;
        return true;
    };
    auto distance = [&](const std::array<double, 3>& q) {
        args[0].v.assign(q.begin(), q.end());
        Value d = ev.call(fn, args);
        return d.v.empty() ? std::nan("") : d.v[0];
    };
    auto gradient = [&](const std::array<double, 3>& q, std::array<double, 3>& out) {
        args[0].v.assign(q.begin(), q.end());
        Value gv = ev.call(grad, args);
        if (gv.v.size() != 3) return -1.0;
        out = {gv.v[0], gv.v[1], gv.v[2]};
        const double n = std::sqrt(out[0] * out[0] + out[1] * out[1] + out[2] * out[2]);
        if (std::isfinite(n)) worst = std::max(worst, n);
        return n;
    };
    auto along = [](const std::array<double, 3>& p, const std::array<double, 3>& u, double t) {
        return std::array<double, 3>{p[0] + t * u[0], p[1] + t * u[1], p[2] + t * u[2]};
    };
    constexpr int kPoints = 64, kRounds = 6;
    try {
        for (int s = 0; s < paths; ++s) {
            args[0] = random.point(region);
            random.others(args, g, others);
            std::array<double, 3> p = {args[0].v[0], args[0].v[1], args[0].v[2]};
            for (int round = 0; round < kRounds; ++round) {
                std::array<double, 3> gp{};
                const double d = distance(p), n = gradient(p, gp);
                if (!std::isfinite(d) || !(n > 1e-30) || d == 0) break;
                if (outside && d > 0) *outside = std::max(*outside, n);
                std::array<double, 3> u;
                for (size_t c = 0; c < 3; ++c) u[c] = (d > 0 ? -1 : 1) * gp[c] / n;
                double t_prev = 0, best_t = 0, best = std::fabs(d);
                bool crossed = false;
                for (int j = 0; j < kPoints && !crossed; ++j) {
                    const double t = 1e-3 * std::pow(size / 1e-3, double(j) / (kPoints - 1));
                    const std::array<double, 3> q = along(p, u, t);
                    if (!inside(q)) break;
                    const double dq = distance(q);
                    if (!std::isfinite(dq)) break;
                    if ((dq > 0) != (d > 0) || dq == 0) {
                        double lo = t_prev, hi = t;  // D has d's sign at lo, not at hi
                        for (int b = 0; b < 40 && hi - lo > 1e-9 * std::max(1.0, hi); ++b) {
                            const double mid = 0.5 * (lo + hi), dm = distance(along(p, u, mid));
                            if (!std::isfinite(dm)) break;
                            ((dm > 0) == (d > 0) && dm != 0 ? lo : hi) = mid;
                        }
                        const std::array<double, 3> x = along(p, u, 0.5 * (lo + hi));
                        std::array<double, 3> unused;
                        for (double off : {0.0, -0.01, 0.01}) {
                            const std::array<double, 3> y = along(x, u, off);
                            if (!inside(y)) continue;
                            const double n_y = gradient(y, unused);
                            if (outside && distance(y) >= 0 && std::isfinite(n_y)) *outside = std::max(*outside, n_y);
                        }
                        if (ends) ends->push_back(x);
                        crossed = true;
                    } else if (std::fabs(dq) < best) {
                        best = std::fabs(dq);
                        best_t = t;
                    }
                    t_prev = t;
                }
                if (crossed || best_t == 0) break;
                p = along(p, u, best_t);
            }
        }
    } catch (const EvalLimit&) {
    }
    return worst;
}

// The chain rule at a cut. When the distance depends on the query point p only through one intermediate
// vector u = T(p) — a domain warp such as a twist, a bend or a rotation feeding a shape — then
// ‖∇D(p)‖ = ‖J_T(p)ᵀ ∇F(u)‖ ≤ sup ‖∇F‖ · sup ‖J_T‖ (D = F ∘ T), and each factor, bounded by intervals on
// its own, keeps what one interval evaluation of the whole gradient loses: the twist's sin² + cos² = 1
// (its rotation's entries are bounded one by one) multiplied into the shape's gradient. ‖J_T‖ is bounded by
// Gershgorin's bound of JᵀJ (or the Frobenius norm, if smaller) from its rows (the gradients of u's
// components) over p's region; ‖∇F‖ over the box of u that T's intervals give. Returns the smallest product over the cuts tried (∞ when there is none).
double chain_rule_bound(const Module& m, int fn, const std::vector<Interval>& region, const std::vector<std::vector<Interval>>& others,
                        double ball, int budget) {
    constexpr int kMaxCandidates = 64, kMaxCuts = 4;
    Module work = m;
    Function flat = flattened(work, work.functions[size_t(fn)]);
    const size_t n = flat.body.size();
    if (n == 0 || n > kMaxFlat) return kInf;
    auto depends = [&](ValueId blocked) {  // which values depend on p without passing through `blocked`
        std::vector<char> dep(n, 0);
        for (size_t i = 0; i < n; ++i) {
            const Instr& in = flat.body[i];
            if (ValueId(i) == blocked) continue;
            if (in.op == Op::Param && in.aux == 0) dep[i] = 1;
            for (ValueId a : in.args) dep[i] |= dep[a];
        }
        return dep;
    };
    const std::vector<char> dep = depends(ValueId(-1));
    if (!dep[flat.result]) return kInf;
    double best = kInf;
    int tried = 0, cuts = 0;
    for (size_t c = 0; c < n && tried < kMaxCandidates && cuts < kMaxCuts; ++c) {
        const Instr& cut = flat.body[c];
        // ℝ³ cuts: the gradient with respect to a parameter is taken for the query point's type.
        if (!dep[c] || !cut.type.is_vector() || cut.type.rows != 3 || ValueId(c) == flat.result || cut.op == Op::Param) continue;
        ++tried;
        if (depends(ValueId(c))[flat.result]) continue;  // p reaches D another way too
        ++cuts;
        // T: p -> u, the body up to the cut.
        Function T;
        T.name = "lipschitz_cut_T";
        T.params = flat.params;
        T.body.assign(flat.body.begin(), flat.body.begin() + long(c) + 1);
        T.result = ValueId(c);
        eliminate_dead_code(T);  // what u reads, not every value before it
        // F: (u, the other parameters) -> D: every value that depends on p, except through u, is unused by
        // D (u is a cut) and becomes a zero.
        std::vector<char> below(n, 0);
        below[c] = 1;
        for (size_t i = c + 1; i < n; ++i)
            for (ValueId a : flat.body[i].args) below[i] |= below[a];
        Function F;
        F.name = "lipschitz_cut_F";
        F.params = flat.params;
        F.params[0] = {"u", cut.type};
        bool ok = true;
        for (size_t i = 0; i < n && ok; ++i) {
            Instr in = flat.body[i];
            if (i == c) {
                Instr param;
                param.op = Op::Param;
                param.type = cut.type;
                param.aux = 0;
                in = param;
            } else if (dep[i] && !below[i]) {
                if (!in.type.is_numeric()) ok = false;  // a tuple (a loop's states) has no zero
                Instr zero;
                zero.op = Op::Const;
                zero.type = in.type;
                zero.data.assign(size_t(std::max(1, in.type.components())), 0.0);
                in = zero;
            }
            F.body.push_back(std::move(in));
        }
        if (!ok) continue;
        F.result = flat.result;
        int t_fn = int(work.functions.size());
        work.functions.push_back(T);
        int f_fn = int(work.functions.size());
        work.functions.push_back(std::move(F));
        // u's box over p's region.
        std::vector<std::vector<Interval>> t_params = {region};
        t_params.insert(t_params.end(), others.begin(), others.end());
        std::vector<Interval> u_box = interval_analysis(work, t_fn, t_params)[size_t(T.result)].c;
        bool bounded = true;
        for (const Interval& i : u_box) bounded &= std::isfinite(i.lo) && std::isfinite(i.hi);
        if (!bounded) continue;
        std::string why;
        int f_grad = differentiate(work, f_fn, 0, "lipschitz_cut_gradF", &why);
        if (f_grad < 0) continue;
        double kf = derive(work, f_grad, u_box, others, 0, budget);
        if (kf > 1 + 1e-9 && split_pool_left() > 0 && work.functions[size_t(f_grad)].body.size() <= kSplitMaxInstructions) {
            // the shape behind the warp, by case splitting
            kf = std::min(kf, split_derive(work, f_grad, u_box, others, 0, budget, false));
        }
        if (!std::isfinite(kf)) continue;
        // J_T's rows: the gradients of u's components; their Frobenius norm bounds ‖J_T‖₂.
        Function J;
        J.name = "lipschitz_cut_J";
        {
            Builder b(work, J);
            std::vector<ValueId> params;
            for (size_t k = 0; k < flat.params.size(); ++k) params.push_back(b.param(flat.params[k].name, flat.params[k].type));
            std::vector<ValueId> rows;
            for (int r = 0; r < cut.type.rows && ok; ++r) {
                Function Tr = T;
                Tr.name = fmt::format("lipschitz_cut_T{}", r);
                Instr ex;
                ex.op = Op::Extract;
                ex.type = Type::scalar();
                ex.args = {T.result};
                ex.aux = r;
                Tr.result = Tr.add(std::move(ex));
                int tr_fn = int(work.functions.size());
                work.functions.push_back(std::move(Tr));
                int g = differentiate(work, tr_fn, 0, fmt::format("lipschitz_cut_gradT{}", r), &why);
                if (g < 0) ok = false;
                else rows.push_back(b.call(g, params));
            }
            if (!ok) continue;
            J.result = b.construct(Type::vector(3 * cut.type.rows), rows);
        }
        int j_fn = int(work.functions.size());
        work.functions.push_back(std::move(J));
        // J is the warp's derivative alone, usually a few dozen instructions: more boxes for it (a twist's
        // rows tighten as p_2's interval narrows: K 16 → 11 on the bench's twisted bar).
        double kj = derive(work, j_fn, region, others, ball, T.body.size() < 200 ? 16 * budget : budget, true);
        best = std::min(best, kf * kj);
    }
    return best;
}

// Looks for a jump of f (parameter 0 ∈ ℝ³) over the region: pairs of points `delta` apart in random
// directions whose values differ by more than 1.5·K·delta (a field whose gradient is at most K, continuous
// along the segment, cannot). Records the largest in e. The 32 pairs whose difference is the largest part of
// K·delta are then bisected 16 times, keeping the half that differs more: a jump stays as large while the
// halves shrink, and shows at some depth however small it is beside K·delta (a sphere cut by repeat_angular's
// sector boundary steps by 0.3 at every radius, 0.62 allowed at the region's delta: it was never reported).
void find_jump(const Module& m, int fn, const std::vector<Interval>& region, const std::vector<std::vector<Interval>>& others,
               double ball, double K, int pairs, LipschitzEstimate& e) {
    double extent = 0;
    for (const Interval& i : region) {
        if (!std::isfinite(i.lo) || !std::isfinite(i.hi)) return;
        extent = std::max(extent, i.hi - i.lo);
    }
    if (!(extent > 0) || !std::isfinite(K)) return;
    const double delta = 1e-3 * extent;
    Evaluator ev(m, sample_inputs());
    const Function& f = m.functions[size_t(fn)];
    SplitMix64 next{0xD1B54A32D192ED03ull};
    std::vector<Value> args(f.params.size());
    for (size_t k = 1; k < f.params.size(); ++k) {  // the others at their midpoints (a group's member 0)
        std::vector<double> v;
        for (const Interval& i : others[k - 1]) v.push_back(f.params[k].type.kind == Type::Integer ? std::floor(i.lo) : 0.5 * (i.lo + i.hi));
        args[k] = {f.params[k].type, v};
    }
    using Point = std::array<double, 3>;
    auto at = [&](const Point& x) {
        args[0] = {Type::vector(3), {x[0], x[1], x[2]}};
        Value v = ev.call(fn, args);
        return v.v.empty() ? std::nan("") : v.v[0];
    };
    auto record = [&](double jump, double apart, const Point& x) {
        if (std::isfinite(jump) && jump > 1.5 * K * apart + 1e-9 && jump > e.jump) {
            e.jump = jump;
            e.delta = apart;
            e.jump_at = {x[0], x[1], x[2]};
        }
    };
    struct Pair {
        double ratio;  // |f(b) - f(a)| / (K·delta)
        Point a, b;
        double fa, fb;
        bool operator<(const Pair& o) const { return ratio > o.ratio; }  // (a min-heap of the largest)
    };
    std::priority_queue<Pair> steepest;
    try {
        // At most kJumpWork evaluator steps in all: a shape whose one evaluation is costly gets fewer pairs (a
        // trial's double sum over 200 points, 40,000 terms per evaluation, spent 20 s of its compile here).
        for (int s = 0; s < pairs && ev.work() < kJumpWork; ++s) {
            Point a, dir;
            for (size_t c = 0; c < 3; ++c) a[c] = region[c].lo + (region[c].hi - region[c].lo) * next();
            if (ball > 0 && a[0] * a[0] + a[1] * a[1] + a[2] * a[2] > ball * ball) continue;
            double n = 0;
            for (double& d : dir) {
                d = 2 * next() - 1;
                n += d * d;
            }
            if (n < 1e-6) continue;
            n = std::sqrt(n);
            Point b = {a[0] + delta * dir[0] / n, a[1] + delta * dir[1] / n, a[2] + delta * dir[2] / n};
            double fa = at(a), fb = at(b);
            if (std::isnan(fa) || std::isnan(fb)) return;
            double jump = std::fabs(fb - fa);
            record(jump, delta, a);
            if (std::isfinite(jump)) {
                steepest.push({jump / (K * delta), a, b, fa, fb});
                if (steepest.size() > 32) steepest.pop();
            }
        }
        for (; !steepest.empty(); steepest.pop()) {
            Pair p = steepest.top();
            double apart = delta;
            for (int level = 0; level < 16 && ev.work() < 2 * kJumpWork; ++level) {
                Point mid = {0.5 * (p.a[0] + p.b[0]), 0.5 * (p.a[1] + p.b[1]), 0.5 * (p.a[2] + p.b[2])};
                double fm = at(mid);
                if (std::isnan(fm)) break;
                apart *= 0.5;
                if (std::fabs(fm - p.fa) >= std::fabs(p.fb - fm)) p.b = mid, p.fb = fm;
                else p.a = mid, p.fa = fm;
                record(std::fabs(p.fb - p.fa), apart, p.a);
            }
        }
    } catch (const EvalLimit&) {  // too costly to sample: nothing said
    }
}

// The terms of a union-like result: a min or max picks one operand's value at each point (a Select one of
// two), so ‖∇D‖ is at most the largest of the operands' gradients, and each operand may have a cut of its
// own (a rotated repetition unioned with a ball at its centre has none as a whole). Up to `limit` terms.
void union_terms(const Function& f, ValueId v, std::vector<ValueId>& out, size_t limit) {
    const Instr& in = f.body[v];
    bool picks = in.op == Op::Select;
    if (in.op == Op::Builtin && in.type.is_scalar()) {
        std::string_view name = builtins()[size_t(in.aux)].name;
        picks = name == "min" || name == "max";
    }
    if (!picks || out.size() + in.args.size() > limit) {
        out.push_back(v);
        return;
    }
    for (size_t k = in.op == Op::Select ? 1 : 0; k < in.args.size(); ++k) union_terms(f, in.args[k], out, limit);
}

double union_bound(const Module& m, int fn, const std::vector<Interval>& region, const std::vector<std::vector<Interval>>& others,
                   double ball, int budget);

// Adds `f` to `work` and bounds its gradient: by intervals, then (when that exceeds 1) by the chain rule at a
// cut and, with `unions`, term by term. ∞ when it has no derivative.
double bound_added(Module& work, Function f, const std::vector<Interval>& region, const std::vector<std::vector<Interval>>& others,
                   double ball, int budget, bool unions) {
    // A term is a copy of the whole function with another result: only what the result reads is kept (the
    // tree's 16 terms were 692-instruction gradients each, and its chain-rule cuts 0.4 s; examples/christmas_tree.iq).
    f.outputs.clear();
    eliminate_dead_code(f);
    int f_fn = int(work.functions.size());
    work.functions.push_back(std::move(f));
    std::string why;
    int g = differentiate(work, f_fn, 0, work.functions[size_t(f_fn)].name + "_gradient", &why);
    if (g < 0) return kInf;
    double k = derive(work, g, region, others, ball, budget);
    if (k > 1 + 1e-9) k = std::min(k, chain_rule_bound(work, f_fn, region, others, ball, budget));
    if (unions && k > 1 + 1e-9) k = std::min(k, union_bound(work, f_fn, region, others, ball, budget));
    return k;
}

// Bounds ‖∇D‖ term by term (union_terms), each term by intervals on its own gradient and by the chain rule;
// ∞ when D is not a union of at least two terms.
double union_bound(const Module& m, int fn, const std::vector<Interval>& region, const std::vector<std::vector<Interval>>& others,
                   double ball, int budget) {
    Module work = m;
    Function flat = flattened(work, work.functions[size_t(fn)]);
    if (flat.body.empty() || flat.body.size() > kMaxFlat) return kInf;
    std::vector<ValueId> terms;
    union_terms(flat, flat.result, terms, 8);
    if (terms.size() < 2) return kInf;
    double worst = 0;
    for (ValueId t : terms) {
        Function term = flat;
        term.name = "lipschitz_term";
        term.result = t;
        worst = std::max(worst, bound_added(work, std::move(term), region, others, ball, budget, false));
        if (!std::isfinite(worst)) return kInf;
    }
    return worst;
}

// The standard library's combinators of distances (stdlib/operators.iql) and their Lipschitz factor in the
// two distances a, b (arguments 0 and 1; the others, radii, must not depend on the point): ‖∇F(a, b)‖ ≤
// factor · max(‖∇a‖, ‖∇b‖), since |∂F/∂a| + |∂F/∂b| ≤ factor everywhere. min, max and Quilez's smooth minima
// weigh the two gradients by non-negative weights that sum to 1 (the polynomial one: 1 - w and w, w =
// max(k - |a - b|, 0)/2k; the exponential one: a softmin); the chamfer's bevel (a + b - r)/√2 has √2. One
// interval evaluation of the whole gradient loses that the weights sum to 1 (each is bounded on its own), and
// a smooth union of three shapes came out at K = 9.9 where every sample is within 1 (a new user's trial,
// stop 37). tests/numerics_test.cpp checks each factor against finite differences.
}  // namespace

double combinator_factor(const std::string& name) {
    static const std::map<std::string, double> factors = {
        {"operators.union", 1.0},
        {"operators.intersection", 1.0},
        {"operators.subtraction", 1.0},
        {"operators.smooth_union", 1.0},
        {"operators.smooth_intersection", 1.0},
        {"operators.smooth_subtraction", 1.0},
        {"operators.smooth_union_exp", 1.0},
        {"operators.chamfer_union", std::sqrt(2.0)},
    };
    auto it = factors.find(name);
    return it == factors.end() ? 0 : it->second;
}

namespace {

// Whether calls of `f` may be bounded as blends of their arguments (blend_factor): a function of scalars to
// a scalar, such as a smooth minimum written in the scene's module.
bool blendable(const Function& f) {
    if (f.params.empty() || f.body.empty() || f.result_type().kind != Type::Scalar) return false;
    for (const FunctionParam& p : f.params)
        if (p.type.kind != Type::Scalar) return false;
    return true;
}

// The Lipschitz factor of a call f(x₁, …, x_n) in those of its arguments that depend on the point (`dep`):
// an upper bound of Σ_i |∂f/∂x_i| over the box `ranges` of the arguments, since ‖∇f(x(p))‖ ≤ Σ_i |∂f/∂x_i|
// ‖∇x_i‖ ≤ that sum · max_i ‖∇x_i‖. A smooth minimum written by hand (Quilez, "smooth minimum": mix(b, a, h)
// - k h(1 - h), -k log(e^(-a/k) + e^(-b/k)), the cubic) weighs ∇a and ∇b by h and 1 - h: an interval
// evaluation of the whole gradient bounds each weight on its own and does not see that they sum to 1 (K 525
// and 33 derived for two and eight spheres whose samples reach 1: a new user's trial, stop 39).
//
// The partials are analysed over q, where the first argument that depends on the point is q₀ and each other
// one q₀ + q_j (a blend's weights depend on the distances' difference: with b = a + d and a - b cancelled to
// -d, ir/passes/Linear.h, the blend band |d| < k is a slab of q's box, not a diagonal strip of (a, b)'s), or
// with `sums`, q_j - q₀ (Quilez's smooth subtraction weighs by b + a); the other arguments whose range is not
// a point follow as they are, up to three in all. Branch and bound over
// q's box, splitting the worst box's longest side; per box the least of the sum of the partials' magnitudes
// by interval arithmetic and, where every partial's sign σ_i is fixed on the box, the centred form of the
// signed sum S = Σ σ_i ∂f/∂x_i (Moore, "Interval Analysis", 1966): S(c) + Σ_j |∂S/∂q_j|(box)·halfwidth_j,
// whose excess falls with the square of the box's size (h + 1 - h is 1 with a zero gradient). Stops when the
// worst box is within 1% of the largest sum at a point, or after `budget` boxes. ∞ where an argument that
// depends on the point has an unbounded range or a derivative is missing.
double blend_factor(Module& work, int callee, const std::vector<Interval>& ranges, const std::vector<char>& dep, int budget,
                    bool sums = false) {
    const size_t n = work.functions[size_t(callee)].params.size();
    const std::vector<FunctionParam> fparams = work.functions[size_t(callee)].params;
    if (ranges.size() != n || dep.size() != n) return kInf;
    std::vector<int> slot(n, -1);  // the argument's component of q, or -1: a parameter of its own
    std::vector<size_t> dims;      // the arguments q's components carry
    for (int pass = 0; pass < 2; ++pass)
        for (size_t i = 0; i < n; ++i) {
            bool point = ranges[i].lo == ranges[i].hi;
            if (pass == 0 ? !dep[i] : (dep[i] || point)) continue;
            if (!std::isfinite(ranges[i].lo) || !std::isfinite(ranges[i].hi)) {
                if (dep[i]) return kInf;
                continue;
            }
            if (dims.size() == 3) {
                if (dep[i]) return kInf;
                continue;
            }
            slot[i] = int(dims.size());
            dims.push_back(i);
        }
    if (dims.empty() || !dep[dims[0]]) return kInf;
    std::vector<std::vector<Interval>> others;  // the arguments without a slot whose range is not a point
    for (size_t i = 0; i < n; ++i)
        if (slot[i] < 0 && !(ranges[i].lo == ranges[i].hi)) others.push_back({ranges[i]});
    // F(x, the other arguments) = f(...): its gradient in x is the partials of the arguments x carries.
    auto begin = [&](Function& fn, Builder& b, const char* name, std::vector<ValueId>& ps) {
        fn.name = name;
        ps.push_back(b.param("q", Type::vector(3)));
        for (size_t i = 0; i < n; ++i)
            if (slot[i] < 0 && !(ranges[i].lo == ranges[i].hi)) ps.push_back(b.param(fparams[i].name, fparams[i].type));
    };
    auto add = [&](Function fn) {
        work.functions.push_back(std::move(fn));
        return int(work.functions.size() - 1);
    };
    // A function of the analysis as interval arithmetic sees it best: calls inlined, linear terms cancelled.
    auto flatten = [&](int fn) {
        Function flat = inline_calls(work, work.functions[size_t(fn)]);
        cancel_linear_terms(flat);
        eliminate_common_subexpressions(flat);
        eliminate_dead_code(flat);
        work.functions[size_t(fn)] = std::move(flat);
    };
    int f_fn;
    {
        Function F;
        Builder b(work, F);
        std::vector<ValueId> ps;
        begin(F, b, "lipschitz_blend", ps);
        std::vector<ValueId> args(n);
        // (an argument fixed at one value is that constant: a division by it is linear, ir/passes/Linear.h)
        for (size_t i = 0, o = 1; i < n; ++i)
            args[i] = slot[i] >= 0 ? b.op(Op::Extract, {ps[0]}, slot[i]) : ranges[i].lo == ranges[i].hi ? b.scalar(ranges[i].lo) : ps[o++];
        F.result = b.call(callee, args);
        f_fn = add(std::move(F));
    }
    std::string why;
    int grad_x = differentiate(work, f_fn, 0, "lipschitz_blend_partials", &why);
    if (grad_x < 0) return kInf;
    // P(q, ...) = the partials at x(q).
    int grad;
    {
        Function P;
        Builder b(work, P);
        std::vector<ValueId> ps;
        begin(P, b, "lipschitz_blend_partials_q", ps);
        ValueId base = b.op(Op::Extract, {ps[0]}, 0);
        std::vector<ValueId> x;
        for (size_t j = 0; j < 3; ++j) {
            ValueId c = j == 0 ? base : b.op(Op::Extract, {ps[0]}, int(j));
            bool moves = j > 0 && j < dims.size() && dep[dims[j]];
            x.push_back(!moves ? c : sums ? b.op(Op::Sub, {c, base}) : b.op(Op::Add, {base, c}));
        }
        std::vector<ValueId> args = {b.construct(Type::vector(3), x)};
        args.insert(args.end(), ps.begin() + 1, ps.end());
        P.result = b.call(grad_x, args);
        grad = add(std::move(P));
        flatten(grad);
        
    }
    const std::vector<FunctionParam> params = work.functions[size_t(grad)].params;
    // Which of q's components the partials read (a blend's read only the difference: its boxes split only that)
    std::array<bool, 3> reads{};
    {
        const Function& P = work.functions[size_t(grad)];
        std::vector<char> live(P.body.size(), 0);
        live[P.result] = 1;
        for (size_t i = P.body.size(); i-- > 0;) {
            if (!live[i]) continue;
            const Instr& in = P.body[i];
            if (in.op == Op::Extract && P.body[in.args[0]].op == Op::Param && P.body[in.args[0]].aux == 0) {
                if (in.aux >= 0 && in.aux < 3) reads[size_t(in.aux)] = true;
                continue;
            }
            if (in.op == Op::Param && in.aux == 0) reads = {true, true, true};
            for (ValueId a : in.args) live[a] = 1;
        }
    }
    // A function of q (and the other arguments) summing the partials of the arguments that depend on the
    // point, each as `term` makes it of the partial's value and its slot.
    auto sum_of_partials = [&](const char* name, const std::function<ValueId(Builder&, ValueId, size_t)>& term) {
        Function S;
        Builder b(work, S);
        std::vector<ValueId> ps;
        begin(S, b, name, ps);
        ValueId g = b.call(grad, ps);
        ValueId sum = ValueId(-1);
        for (size_t j = 0; j < dims.size(); ++j) {
            if (!dep[dims[j]]) continue;
            ValueId part = term(b, b.op(Op::Extract, {g}, int(j)), j);
            sum = sum == ValueId(-1) ? part : b.op(Op::Add, {sum, part});
        }
        S.result = sum;
        return add(std::move(S));
    };
    // The signed sums' gradients, per pattern of signs (bit j: the argument in slot j falls), built when needed.
    std::map<int, int> signed_grad;
    auto signed_sum_gradient = [&](int signs) -> int {
        if (auto it = signed_grad.find(signs); it != signed_grad.end()) return it->second;
        int s_fn = sum_of_partials("lipschitz_blend_sum", [&](Builder& b, ValueId part, size_t j) {
            return (signs >> j & 1) ? b.op(Op::Neg, {part}) : part;
        });
        int g = differentiate(work, s_fn, 0, "lipschitz_blend_sum_gradient", &why);
        if (g >= 0) flatten(g);
        signed_grad[signs] = g;
        return g;
    };
    // L(q, ...) = Σ_i |∂f/∂x_i|: the sum whose bound is sought, for case splitting (a blend's kinks, |a - b| =
    // k, are where the partials' branches meet; interval arithmetic hulls each term's branches apart).
    const int sum_fn = sum_of_partials("lipschitz_blend_l1", [](Builder& b, ValueId part, size_t) { return b.builtin("abs", {part}); });
    flatten(sum_fn);
    BoxScratch scratch;
    auto analyse = [&](int fn, const std::vector<Interval>& box) -> const Bounds& {
        std::vector<std::vector<Interval>> ps = {box};
        ps.insert(ps.end(), others.begin(), others.end());
        interval_analysis(scratch.calls, scratch.values, work, work.functions[size_t(fn)], ps);
        return scratch.values[work.functions[size_t(fn)].result];
    };
    std::vector<size_t> branches;  // the partials' values that may jump: comparisons, signs, floors
    for (size_t i = 0; i < work.functions[size_t(grad)].body.size(); ++i) {
        const Instr& in = work.functions[size_t(grad)].body[i];
        std::string_view n = in.op == Op::Builtin ? builtins()[size_t(in.aux)].name : "";
        if (in.op == Op::Compare || in.op == Op::FloorInt || in.op == Op::IntMod || n == "sign" || n == "floor" || n == "ceil" ||
            n == "fract" || n == "mod" || n == "round" || n == "step" || n == "trunc")
            branches.push_back(i);
    }
    double seen = 0;  // the largest sum at a point
    // The partials' bound on a box.
    auto bound = [&](const std::vector<Interval>& box) {
        ++t_boxes;
        Bounds g = analyse(grad, box);
        // The centred form holds only where the partials are continuous on the box: a branch (a comparison, a
        // sign, a floor) that goes either way may make them jump, and a − 30 clamp(a − b, −0.05, 0.05)²'s slope
        // of 7 at the clamp's edge, a jump of ∂f/∂a from 4 to 1, came out 6.3 (a new user's trial, stop 40).
        bool continuous = true;
        for (size_t i : branches)
            for (const Interval& c : scratch.values[i].c) continuous &= c.lo == c.hi;
        double naive = 0;
        int signs = 0;
        bool fixed = continuous;
        for (size_t j = 0; j < dims.size(); ++j) {
            if (!dep[dims[j]]) continue;
            const Interval& c = g.c[j];
            naive += iv::magnitude(c);
            if (c.hi <= 0 && c.lo < 0) signs |= 1 << j;
            else fixed &= c.lo >= 0;
        }
        if (std::isnan(naive)) naive = kInf;
        auto split = [&](double have) {
            if (have <= seen * 1.01) return have;
            std::vector<std::vector<Interval>> ps = {box};
            ps.insert(ps.end(), others.begin(), others.end());
            // (strict signs where an argument's difference crosses 0, since {x = 0} is a plane of q; and the
            // case x = 0 itself, since the distances may agree on a volume of p: sign(u₁) of u = max(…, 0))
            CaseSplitOptions o;
            o.zero_cases = true;
            o.floor = 0;
            double r = case_split_bound(work, work.functions[size_t(sum_fn)], ps,
                                        [](const Bounds& g) { return result_norm(g, false); }, 32, o);
            return std::isnan(r) ? have : std::min(have, r);
        };
        if (!fixed || !(naive > 0)) return split(naive);
        int sg = signed_sum_gradient(signs);
        if (sg < 0) return split(naive);
        std::vector<Interval> centre = box;
        for (Interval& c : centre) c.lo = c.hi = 0.5 * (c.lo + c.hi);
        Bounds at = analyse(grad, centre);
        double centred = 0;
        for (size_t j = 0; j < dims.size(); ++j)
            if (dep[dims[j]]) centred += (signs >> j & 1) ? -at.c[j].lo : at.c[j].hi;
        Bounds slope = analyse(sg, box);
        for (size_t j = 0; j < dims.size(); ++j) centred += iv::magnitude(slope.c[j]) * 0.5 * (box[j].hi - box[j].lo);
        return split(std::isnan(centred) ? naive : std::min(naive, centred));
    };
    std::vector<Interval> region(3, Interval{0, 0});
    for (size_t j = 0; j < dims.size(); ++j) {
        region[j] = ranges[dims[j]];
        if (j > 0 && dep[dims[j]])
            region[j] = sums ? Interval{ranges[dims[j]].lo + ranges[dims[0]].lo, ranges[dims[j]].hi + ranges[dims[0]].hi}
                             : Interval{ranges[dims[j]].lo - ranges[dims[0]].hi, ranges[dims[j]].hi - ranges[dims[0]].lo};
    }
    std::priority_queue<Box> q;
    q.push({region, bound(region)});
    double checkpoint = q.top().bound;
    for (int used = 1, pops = 0; used + 2 <= budget && std::isfinite(q.top().bound); ++pops) {
        Box worst = q.top();
        if (pops % 128 == 127) {  // no progress in 128 splits (e^(-a/k) over a wide range of a): none to come
            if (worst.bound > 0.99 * checkpoint) break;
            checkpoint = worst.bound;
        }
        if (pops % 4 == 0) {
            std::vector<Interval> at = worst.c;
            for (Interval& c : at) c.lo = c.hi = c.lo + 0.4617 * (c.hi - c.lo);
            Bounds g = analyse(grad, at);
            double here = 0;
            for (size_t j = 0; j < dims.size(); ++j)
                if (dep[dims[j]]) here += iv::magnitude(g.c[j]);
            if (std::isfinite(here)) seen = std::max(seen, here);
            if (worst.bound <= seen * 1.01) break;
        }
        q.pop();
        size_t axis = 3;  // the longest side of those the partials read
        for (size_t k = 0; k < dims.size(); ++k)
            if (reads[k] && (axis == 3 || worst.c[k].hi - worst.c[k].lo > worst.c[axis].hi - worst.c[axis].lo)) axis = k;
        double mid = axis < 3 ? 0.5 * (worst.c[axis].lo + worst.c[axis].hi) : 0;
        if (axis == 3 || !(mid > worst.c[axis].lo && mid < worst.c[axis].hi)) {
            q.push(worst);
            break;
        }
        for (int half = 0; half < 2; ++half) {
            Box b = worst;
            (half ? b.c[axis].lo : b.c[axis].hi) = mid;
            b.bound = bound(b.c);
            q.push(std::move(b));
            ++used;
        }
    }
    t_blend_steepest = std::max(t_blend_steepest, seen);
    return q.top().bound;
}

// Bounds ‖∇D‖ through the structure of D's expression, with the standard library's combinators kept as calls:
// a combinator's bound is its factor times the larger of its distances' bounds, a min or max (or a Select)
// the largest of its operands', a sum or difference the sum of its operands' (only those that depend on the
// point), a negation or |x| its operand's, where a combinator lies below; any other value is a term bounded
// on its own (bound_added: by intervals, the chain rule at a cut, term by term over unions; at most 64 terms:
// a chain of 30 smooth unions of spheres has 30). A call of a function of scalars written in the module (a
// smooth minimum by hand) is a combinator whose factor blend_factor finds. ∞ when D has no combinator.
double combinator_bound(const Module& m, int fn, const std::vector<Interval>& region, const std::vector<std::vector<Interval>>& others,
                        double ball, int budget) {
    Module work = m;
    // Blends are kept as calls where no blend is inside them (t(a, b, c) = m(m(a, b, k), c, k) is inlined and
    // its two calls of m bounded one by one: as one function of three arguments it got 2·10⁴, a trial's).
    std::vector<int> inner(work.functions.size(), -1);  // per function: a blend or a combinator is called inside
    std::function<bool(int, int)> has_inner = [&](int f, int depth) -> bool {
        if (inner[size_t(f)] >= 0) return inner[size_t(f)] != 0;
        bool found = false;
        for (const Instr& in : work.functions[size_t(f)].body)
            if (in.op == Op::Call && !found) {
                const Function& g = work.functions[size_t(in.aux)];
                found = combinator_factor(g.name) > 0 || blendable(g) || depth > 16 || has_inner(in.aux, depth + 1);
            }
        inner[size_t(f)] = found;
        return found;
    };
    std::map<std::string, bool> leaf;
    for (size_t f = 0; f < work.functions.size(); ++f)
        if (blendable(work.functions[f])) leaf[work.functions[f].name] = !has_inner(int(f), 0);
    auto combinator = [&](const Function& f) {
        auto it = leaf.find(f.name);
        return combinator_factor(f.name) > 0 || (it != leaf.end() && it->second);
    };
    Function flat = flattened(work, work.functions[size_t(fn)], combinator);
    const size_t n = flat.body.size();
    if (n == 0 || n > kMaxFlat) return kInf;
    std::vector<char> dep(n, 0), combines(n, 0);  // depends on the point; has a combinator of such values in it
    for (size_t i = 0; i < n; ++i) {
        const Instr& in = flat.body[i];
        if (in.op == Op::Param && in.aux == 0) dep[i] = 1;
        for (ValueId a : in.args) dep[i] |= dep[a], combines[i] |= combines[a];
        combines[i] |= in.op == Op::Call && dep[i] && combinator(work.functions[size_t(in.aux)]);
    }
    // Blends written inline (mix(b, a, h) - k h(1 - h) with h a statement of a and b): a scalar value computed
    // from scalars alone (`internal`) depends on the point through its leaves, the scalars where it meets
    // anything else (a vector's length, a call, a component of p): up to three leaves and a nonlinear form
    // between them make it a blend of its leaves, bounded as a called one is (a function of the leaves outlined).
    std::vector<char> internal(n, 0), nonlinear(n, 0), tainted(n, 0);
    std::vector<std::vector<ValueId>> leaves(n);  // sorted; 4 entries: too many
    for (size_t i = 0; i < n; ++i) {
        const Instr& in = flat.body[i];
        if (dep[i]) {
            bool reduces = in.op == Op::Call || in.op == Op::Loop || in.op == Op::Member ||
                           (in.op == Op::Builtin && builtins()[size_t(in.aux)].name == std::string_view("length"));
            tainted[i] = in.op == Op::Param && in.aux == 0;
            for (ValueId a : in.args) tainted[i] |= !reduces && tainted[a];
        }
        // (a comparison of scalars is internal; so is a small vector built from them: the stable pass writes
        // √(x² + y²) as ‖(x, y)‖, Quilez's circular smooth minimum)
        bool kind = in.type.kind == Type::Scalar || in.type.kind == Type::Bool || (in.type.kind == Type::Vector && in.type.rows <= 4);
        if (!dep[i] || !kind || in.op == Op::Call || in.op == Op::Param) continue;
        bool ok = !in.args.empty();
        for (ValueId a : in.args)
            ok &= !dep[a] || internal[a] || flat.body[a].type.kind == Type::Scalar || flat.body[a].type.kind == Type::Bool;
        if (!ok) continue;
        internal[i] = 1;
        std::string_view name = in.op == Op::Builtin ? builtins()[size_t(in.aux)].name : "";
        int dep_args = 0;
        for (ValueId a : in.args) dep_args += dep[a] && flat.body[a].type.kind == Type::Scalar;
        nonlinear[i] = (in.op == Op::Mul && dep_args > 1) || (in.op == Op::Div && dep[in.args[1]]) ||
                       (in.op == Op::Builtin && name != "min" && name != "max" && name != "abs");
        // The leaves: the arguments' (an internal one's own leaves); past two, an argument that is a blend of two
        // or three leaves itself is one where that leaves fewer (a chain of smooth minima written inline: each
        // link a blend of the previous link and one distance, two dimensions to search, not three or more).
        auto root = [&](ValueId a) {
            return internal[a] && nonlinear[a] && flat.body[a].type.kind == Type::Scalar && leaves[a].size() >= 2 && leaves[a].size() <= 3;
        };
        // Where to cut an argument: down through negations, copies, sums with and products by constants (-r/k of
        // a link r of an exponential chain) to the first statement the user named that is a blend, else the blend
        // those lead to (a cut at -r/k itself would weigh r's bound by 1/k). -1: none.
        auto cut_at = [&](ValueId a) -> ValueId {
            ValueId x = a;
            for (int depth = 0; depth < 16; ++depth) {
                const Instr& e = flat.body[x];
                if (!e.name.empty() && root(x)) return x;
                int deps = 0;
                ValueId next = x;
                for (ValueId y : e.args)
                    if (dep[y]) ++deps, next = y;
                bool linear = deps == 1 && (e.op == Op::Neg || e.op == Op::Copy || e.op == Op::Add || e.op == Op::Sub || e.op == Op::Mul ||
                                            (e.op == Op::Div && dep[e.args[0]]));
                if (!linear || !internal[next]) break;
                x = next;
            }
            return root(x) ? x : ValueId(-1);
        };
        bool scalar_leaves = true;  // (a leaf must be a scalar)
        std::vector<ValueId> l;
        for (int cut = 0; cut < 2 && (cut == 0 || l.size() > 2); ++cut) {
            std::vector<ValueId> c;
            for (ValueId a : in.args) {
                if (!dep[a]) continue;
                nonlinear[i] |= nonlinear[a];
                scalar_leaves &= internal[a] || flat.body[a].type.kind == Type::Scalar;
                ValueId at = cut && internal[a] ? cut_at(a) : ValueId(-1);
                const std::vector<ValueId> own = !internal[a] ? std::vector<ValueId>{a} : at != ValueId(-1) ? std::vector<ValueId>{at} : leaves[a];
                for (ValueId x : own) c.push_back(x);
            }
            std::sort(c.begin(), c.end());
            c.erase(std::unique(c.begin(), c.end()), c.end());
            if (cut == 0 || c.size() < l.size()) l = std::move(c);  // (a chain: blends of two, link by link)
        }
        if (!scalar_leaves) {
            internal[i] = 0;
            nonlinear[i] = 0;
            continue;
        }
        // A value computed from the query point's components is geometry, not a blend of distances (‖p - c‖
        // written as √((p₁ - c₁)² + …) sums its partials to √3; a box's ‖max(q, 0)‖ of q = |p| - b, √3 in
        // |p₁|, |p₂|, |p₃|): a leaf of the blends above it. Geometry is what reads p's components without a
        // length (or a call) between (tainted).
        bool geometry = false;
        for (ValueId x : l) geometry |= tainted[x] != 0;
        if (geometry) {
            internal[i] = 0;
            nonlinear[i] = 0;
            continue;
        }
        if (l.size() > 3) l.resize(4);
        leaves[i] = std::move(l);
    }
    auto inline_blend = [&](size_t i) {
        return internal[i] && nonlinear[i] && flat.body[i].type.kind == Type::Scalar && !leaves[i].empty() && leaves[i].size() <= 3;
    };
    for (size_t i = 0; i < n; ++i) {
        if (inline_blend(i) && leaves[i].size() >= 2) combines[i] = 1;
        for (ValueId a : flat.body[i].args) combines[i] |= combines[a];
    }
    if (!combines[flat.result] || !dep[flat.result]) return kInf;
    std::map<ValueId, double> known;
    int terms = 0;
    std::vector<Bounds> values;  // every value's interval over the region (the blends' argument ranges)
    std::map<std::string, double> factors;  // the blends' factors by callee and (widened) argument ranges
    auto arg_ranges = [&]() -> const std::vector<Bounds>& {
        if (values.empty()) {
            std::vector<std::vector<Interval>> params = {region};
            params.insert(params.end(), others.begin(), others.end());
            values = interval_analysis(work, flat, params);
        }
        return values;
    };
    // Distances' ranges widened outward to 1/64 of their magnitude (a power of 2; not the other arguments': a
    // blend radius in [0.01, 1000] must not reach 0) share an analysis: 64 calls of one blend took 1.4 s (a
    // trial's). Each analysis gets 8× the boxes (a few dozen instructions of two or three scalars, ~5 µs: a
    // slider's blend radius, k ∈ [0.05, 0.6], gets 4.4 from 262 boxes, 1.66 from 1,158), up to 64 in all.
    auto cached_factor = [&](int callee, std::vector<Interval> ranges, const std::vector<char>& dep_arg, std::string key) {
        for (size_t a = 0; a < ranges.size(); ++a) {
            Interval& r = ranges[a];
            double mag = std::max({std::fabs(r.lo), std::fabs(r.hi), 1e-300});
            double quantum = std::isfinite(mag) ? std::exp2(std::ceil(std::log2(mag / 64))) : 0;
            if (dep_arg[a] && quantum > 0) r = {std::floor(r.lo / quantum) * quantum, std::ceil(r.hi / quantum) * quantum};
            key += fmt::format("|{}:{}:{}", int(dep_arg[a]), r.lo, r.hi);
        }
        auto cached = factors.find(key);
        if (cached != factors.end()) return cached->second;
        if (factors.size() >= 64) return kInf;
        double factor = blend_factor(work, callee, ranges, dep_arg, 8 * budget);
        if (factor > 1.05) factor = std::min(factor, blend_factor(work, callee, ranges, dep_arg, 8 * budget, true));
        factors[key] = factor;
        return factor;
    };
    // The value v as a function of its leaves, then of the sliders it reads (`lifted`: each a dimension of the
    // blend's search, not one interval for all of it). -1 where it reads a parameter other than p (a group's member).
    auto outline = [&](ValueId v, std::vector<ValueId>& lifted) -> int {
        std::vector<ValueId> l = leaves[v];
        for (size_t u = 0; u < n; ++u) {
            const Instr& in = flat.body[u];
            if (in.op == Op::Global && in.type.kind == Type::Scalar && !arg_ranges()[u].c.empty() &&
                arg_ranges()[u].c[0].lo < arg_ranges()[u].c[0].hi)
                lifted.push_back(ValueId(u));
        }
        std::vector<char> need(n, 0);
        std::vector<ValueId> stack = {v};
        while (!stack.empty()) {
            ValueId u = stack.back();
            stack.pop_back();
            if (need[u] || std::find(l.begin(), l.end(), u) != l.end() || std::find(lifted.begin(), lifted.end(), u) != lifted.end()) {
                if (std::find(lifted.begin(), lifted.end(), u) != lifted.end()) need[u] = 2;  // read: a parameter
                continue;
            }
            if (flat.body[u].op == Op::Param) return -1;
            need[u] = 1;
            for (ValueId a : flat.body[u].args) stack.push_back(a);
        }
        std::vector<ValueId> read;  // the sliders v reads
        for (ValueId u : lifted)
            if (need[u] == 2) read.push_back(u);
        lifted = read;
        for (ValueId u : lifted) need[u] = 0;
        l.insert(l.end(), lifted.begin(), lifted.end());
        Function g;
        g.name = "lipschitz_inline_blend";
        std::vector<ValueId> map(n, ValueId(-1));
        for (size_t j = 0; j < l.size(); ++j) {
            Instr param;
            param.op = Op::Param;
            param.type = Type::scalar();
            param.aux = int(j);
            param.name = fmt::format("x{}", j);
            g.params.push_back({param.name, param.type});
            map[l[j]] = g.add(std::move(param));
        }
        for (size_t u = 0; u < n; ++u) {
            if (!need[u]) continue;
            Instr in = flat.body[u];
            for (ValueId& a : in.args) a = map[a];
            const std::vector<Bounds>& r = arg_ranges();
            if (in.op == Op::Global && in.type.kind == Type::Scalar && r[u].c.size() == 1 && r[u].c[0].lo == r[u].c[0].hi &&
                std::isfinite(r[u].c[0].lo)) {
                // a slider that is a constant here (Shadertoy): its value, so that x/k is linear in x (Linear.h)
                in.op = Op::Const;
                in.data = {r[u].c[0].lo};
                in.aux = 0;
            }
            map[u] = g.add(std::move(in));
        }
        g.result = map[v];
        work.functions.push_back(std::move(g));
        return int(work.functions.size() - 1);
    };
    std::function<double(ValueId)> K = [&](ValueId v) -> double {
        if (!dep[v]) return 0;
        if (auto it = known.find(v); it != known.end()) return it->second;
        if (inline_blend(v) && combines[v]) {
            // a blend written inline: as a function of its leaves; the rules below where it does no better
            double blend = kInf;
            std::vector<ValueId> lifted;
            int g = factors.size() < 64 ? outline(v, lifted) : -1;
            if (g >= 0) {
                std::vector<Interval> ranges;
                std::vector<char> dep_arg(leaves[v].size(), 1);
                dep_arg.resize(leaves[v].size() + lifted.size(), 0);
                for (ValueId x : leaves[v]) ranges.push_back(arg_ranges()[x].c.empty() ? Interval{} : arg_ranges()[x].c[0]);
                for (ValueId x : lifted) ranges.push_back(arg_ranges()[x].c[0]);
                double factor = cached_factor(g, ranges, dep_arg, fmt::format("inline %{}", v));
                if (std::isfinite(factor)) {
                    double worst = 0;
                    for (ValueId x : leaves[v]) worst = std::max(worst, K(x));
                    blend = factor * worst;
                }
            }
            if (blend <= 1.05) {
                known[v] = blend;
                return blend;
            }
            known[v] = blend;  // (while the rules below run: a leaf's K never reads v)
        }
        const Instr& in = flat.body[v];
        std::string_view name = in.op == Op::Builtin ? builtins()[size_t(in.aux)].name : "";
        double k = kInf;
        bool scalar = in.type.is_scalar() && combines[v];  // below every combinator, a value is a term (a box's
                                                           // two parts, each 1-Lipschitz, sum to one that is too)
        auto largest = [&](size_t from) {
            double worst = 0;
            for (size_t a = from; a < in.args.size() && std::isfinite(worst); ++a) worst = std::max(worst, K(in.args[a]));
            return worst;
        };
        if (in.op == Op::Call && scalar && in.args.size() >= 2 && combinator_factor(work.functions[size_t(in.aux)].name) > 0) {
            bool radii_fixed = true;
            for (size_t a = 2; a < in.args.size(); ++a) radii_fixed &= !dep[in.args[a]];
            if (radii_fixed) k = combinator_factor(work.functions[size_t(in.aux)].name) * std::max(K(in.args[0]), K(in.args[1]));
        } else if (in.op == Op::Call && scalar && blendable(work.functions[size_t(in.aux)])) {
            // a function of distances written in the module (a smooth minimum): its factor by analysis
            std::vector<Interval> ranges;
            std::vector<char> dep_arg;
            for (ValueId a : in.args) {
                ranges.push_back(arg_ranges()[a].c.empty() ? Interval{} : arg_ranges()[a].c[0]);
                dep_arg.push_back(dep[a]);
            }
            double factor = cached_factor(in.aux, ranges, dep_arg, work.functions[size_t(in.aux)].name);
            if (std::isfinite(factor)) k = factor * largest(0);
        } else if (scalar && in.op == Op::Builtin && (name == "min" || name == "max")) {
            k = largest(0);
        } else if (scalar && in.op == Op::Select) {
            k = largest(1);
        } else if (scalar && (in.op == Op::Add || in.op == Op::Sub)) {
            k = K(in.args[0]) + K(in.args[1]);
        } else if (scalar && (in.op == Op::Neg || in.op == Op::Copy || (in.op == Op::Builtin && name == "abs"))) {
            k = K(in.args[0]);
        }
        if (!std::isfinite(k)) {  // a term of its own (or a form the rules above do not take apart)
            if (++terms > 64) return kInf;
            Function term = flat;
            term.name = "lipschitz_combined_term";
            term.result = v;
            term.outputs.clear();
            k = bound_added(work, std::move(term), region, others, ball, budget, true);
        }
        if (auto it = known.find(v); it != known.end()) k = std::min(k, it->second);  // an inline blend's bound
        known[v] = k;
        return k;
    };
    return K(flat.result);
}

// √ of a square form of `old` (v⋅v, x·x, a sum of square forms, a square form times or over a value that
// does not depend on p, a min, max or select of them, |s| of a square form or of its negation, a constant
// ≥ 0), built in `b` from the mapped values: ‖v‖, |x|, ‖(√s, √t)‖, √s·√k, … (-1: not a square form). What
// Quilez's exact distances write as √(min(dot2(a), dot2(b))) or √(x² + y² m): equal values, but the root's
// gradient is a unit vector's where the square's, divided by 2√s, has no useful interval near the surface
// (an interval of 1/√s). `dep`: which values depend on the query point.
ValueId root_of_square(Builder& b, const std::vector<Instr>& old, const std::vector<ValueId>& map, const std::vector<char>& dep,
                       ValueId v, int depth = 0) {
    const Instr& in = old[v];
    if (depth > 8 || !in.type.is_scalar()) return ValueId(-1);
    auto name = [&]() -> std::string_view { return in.op == Op::Builtin ? builtins()[size_t(in.aux)].name : ""; };
    auto root = [&](ValueId a) { return root_of_square(b, old, map, dep, a, depth + 1); };
    constexpr ValueId kNone = ValueId(-1);
    if (in.op == Op::Dot && in.args[0] == in.args[1]) return b.builtin("length", {map[in.args[0]]});
    if (in.op == Op::Mul && in.args[0] == in.args[1] && old[in.args[0]].type.is_scalar()) return b.builtin("abs", {map[in.args[0]]});
    if (in.op == Op::Const && in.data.size() == 1 && in.data[0] >= 0) return b.scalar(std::sqrt(in.data[0]));
    if (in.op == Op::Builtin && (name() == "min" || name() == "max")) {
        std::vector<ValueId> roots;
        for (ValueId a : in.args) {
            ValueId r = root(a);
            if (r == kNone) return r;
            roots.push_back(r);
        }
        return b.builtin(builtins()[size_t(in.aux)].name, roots);
    }
    if (in.op == Op::Builtin && name() == "abs" && in.args.size() == 1) {  // |s|, |-s|, |c ? -s : t|
        std::function<ValueId(ValueId, int)> root_abs = [&](ValueId a, int d) -> ValueId {
            const Instr& x = old[a];
            if (d > 8) return kNone;
            if (x.op == Op::Neg) return root_of_square(b, old, map, dep, x.args[0], depth + 1);
            if (x.op == Op::Select || x.op == Op::If) {
                ValueId t = root_abs(x.args[1], d + 1), e = root_abs(x.args[2], d + 1);
                if (t == kNone || e == kNone) return kNone;
                return b.op(x.op, {map[x.args[0]], t, e});
            }
            return root_of_square(b, old, map, dep, a, depth + 1);
        };
        return root_abs(in.args[0], 0);
    }
    if (in.op == Op::Select || in.op == Op::If) {
        ValueId x = root(in.args[1]), y = root(in.args[2]);
        if (x == kNone || y == kNone) return kNone;
        return b.op(in.op, {map[in.args[0]], x, y});
    }
    if (in.op == Op::Add) {  // √(s + t) = ‖(√s, √t)‖
        ValueId x = root(in.args[0]), y = root(in.args[1]);
        if (x == kNone || y == kNone) return kNone;
        return b.builtin("length", {b.construct(Type::vector(2), {x, y})});
    }
    if (in.op == Op::Mul || in.op == Op::Div) {
        // √(s·k) = √s·√k and √(s/k) = √s/√k where k does not depend on p (its root has no gradient);
        // √(s/t) of two square forms.
        for (int side = 0; side < (in.op == Op::Mul ? 2 : 1); ++side) {
            ValueId s_v = in.args[size_t(side)], k_v = in.args[size_t(1 - side)];
            if (dep[k_v] || !old[k_v].type.is_scalar()) continue;
            ValueId r = root(s_v);
            if (r == kNone) continue;
            return b.op(in.op, {r, b.builtin("sqrt", {map[k_v]})});
        }
        if (in.op == Op::Div) {
            ValueId num = root(in.args[0]), den = root(in.args[1]);
            if (num == kNone || den == kNone) return kNone;
            return b.op(Op::Div, {num, den});
        }
        return kNone;
    }
    return kNone;
}

// A copy of `f` (calls inlined, common subexpressions merged) with every √ of a square form taken as the
// root itself (root_of_square). For the estimate only: the emitted code is the user's.
Function roots_taken(const Module& m, const Function& fn, bool* changed = nullptr) {
    Function flat = flattened(m, fn);
    std::vector<Instr> old = std::move(flat.body);
    flat.body.clear();
    std::vector<ValueId> map(old.size());
    std::vector<char> dep(old.size(), 0);  // depends on the query point
    for (size_t i = 0; i < old.size(); ++i) {
        dep[i] = old[i].op == Op::Param && old[i].aux == 0;
        for (ValueId a : old[i].args) dep[i] |= dep[a];
    }
    Module scratch = m;  // Builder needs a module (for calls; there are none left)
    Builder b(scratch, flat);
    for (size_t i = 0; i < old.size(); ++i) {
        const Instr& in = old[i];
        if (in.op == Op::Builtin && in.type.is_scalar() && builtins()[size_t(in.aux)].name == std::string_view("sqrt")) {
            ValueId r = root_of_square(b, old, map, dep, in.args[0]);
            if (r != ValueId(-1)) {
                map[i] = r;
                if (changed) *changed = true;
                continue;
            }
        }
        Instr copy = in;
        for (ValueId& a : copy.args) a = map[a];
        map[i] = flat.add(std::move(copy));
    }
    flat.result = map[flat.result];
    for (auto& [name, v] : flat.outputs) v = map[v];
    return flat;
}

// The direct, chain-rule and union bounds of `fn` with its roots of squares taken (roots_taken).
double roots_bound(const Module& m, int fn, const std::vector<Interval>& region, const std::vector<std::vector<Interval>>& others,
                   double ball, int budget) {
    Module work = m;
    bool changed = false;
    Function f = roots_taken(work, work.functions[size_t(fn)], &changed);
    if (!changed) return kInf;  // nothing to take: the other refinements saw the same function
    f.name = "lipschitz_roots";
    return bound_added(work, std::move(f), region, others, ball, budget, true);
}

// The bound of ‖∇D‖ by case splitting (CaseSplit) on the gradient of `fn` with its roots of squares taken,
// calls inlined: fewer boxes, each split into up to kSplitPasses interval passes.
double split_bound(const Module& m, int fn, const std::vector<Interval>& region, const std::vector<std::vector<Interval>>& others,
                   double ball, int budget) {
    if (split_pool_left() <= 0) return kInf;  // no allowance left (a declared bound's estimate has none)
    Module work = m;
    Function f = roots_taken(work, work.functions[size_t(fn)]);
    // Past a few thousand instructions the allowance buys too few passes to split anything, and differentiating
    // and flattening alone cost more than the rest of the pass (5,000 chained statements: 0.8 s).
    if (f.body.size() > kSplitMaxInstructions) return kInf;
    f.name = "lipschitz_split";
    int f_fn = int(work.functions.size());
    work.functions.push_back(std::move(f));
    std::string why;
    int g = differentiate(work, f_fn, 0, "lipschitz_split_gradient", &why);
    if (g < 0) return kInf;
    return split_derive(work, g, region, others, ball, budget);
}

// Whether the shape stays inside its `bound` spheres: its distance at points outside each sphere (shells of
// 1.001, 1.1, 1.25, 1.5, 2 and 3 times the radius, 256 points each on a Fibonacci lattice, per member) must
// not be negative. Returns the first point found inside the shape (its distance in `d`, member in `member`),
// or an empty vector. (A shape can miss the sphere itself, a torus around a ball in its hole.)
std::vector<double> outside_bound(const Module& m, const LipschitzSpec& spec, double& d, int& member) {
    Evaluator ev(m, sample_inputs());
    const Function& f = m.functions[size_t(spec.object_fn)];
    const double golden = M_PI * (3 - std::sqrt(5.0));
    try {
        for (size_t k = 0; k < spec.bounds.size(); ++k) {
            for (double shell : {1.001, 1.1, 1.25, 1.5, 2.0, 3.0})
            for (int i = 0; i < 256; ++i) {
                const double R = spec.bounds[k] * shell;
                double y = 1 - 2 * (i + 0.5) / 256, r = std::sqrt(1 - y * y), a = golden * i;
                std::vector<Value> args = {{Type::vector(3), {R * r * std::cos(a), R * y, R * r * std::sin(a)}}};
                if (f.params.size() > 1) args.push_back({Type::integer(), {double(k)}});
                Value v = ev.call(spec.object_fn, args);
                if (!v.v.empty() && v.v[0] < -1e-6 * R) {
                    d = v.v[0];
                    member = int(k);
                    return args[0].v;
                }
            }
        }
    } catch (const EvalLimit&) {
    }
    return {};
}

// The sliders function `fn` reads, through its calls and loops: the indices of the parameter globals with bounds (with
// `unbounded`, those without too), in increasing order.
std::vector<size_t> sliders_read(const Module& m, int fn, bool unbounded = false) {
    std::vector<char> reached(m.functions.size(), 0);
    std::vector<int> todo = {fn};
    std::vector<size_t> sliders;
    while (!todo.empty()) {
        int f = todo.back();
        todo.pop_back();
        if (reached[size_t(f)]) continue;
        reached[size_t(f)] = 1;
        for (const Instr& in : m.functions[size_t(f)].body) {
            if (in.op == Op::Call || in.op == Op::Loop) todo.push_back(in.aux);
            if (in.op == Op::Global && m.globals[size_t(in.aux)].kind == Global::Kind::Parameter &&
                (unbounded || !m.globals[size_t(in.aux)].bounds.lo.empty()))
                sliders.push_back(size_t(in.aux));
        }
    }
    std::sort(sliders.begin(), sliders.end());
    sliders.erase(std::unique(sliders.begin(), sliders.end()), sliders.end());
    return sliders;
}

// v / K for a distance, or (v₀ / K, v₁) for an instrumented (distance, count) of type t; K the constant, or where
// `global` ≥ 0 the (prepared) global holding it.
ValueId divided(Builder& b, ValueId v, const Type& t, double K, int global) {
    auto divisor = [&] { return global >= 0 ? b.global(global) : b.scalar(K); };
    if (t.is_scalar()) return b.op(Op::Div, {v, divisor()});
    ValueId d = b.op(Op::Div, {b.op(Op::Extract, {v}, 0), divisor()});
    return b.construct(t, {d, b.op(Op::Extract, {v}, 1)});
}

// Divides the value of every call of `object` in function `fn` (its first component, for an instrumented
// (distance, count)) by K, leaving what `fn` computes around the calls as it is: a `bound` sphere's stand-in
// length(p) - R is a true distance, and divided by K it made rays crawl toward the sphere (a shape with K = 30
// was never reached within 128 steps). Returns whether `fn` calls `object`.
bool divide_object_calls(Module& m, int fn, int object, double K, int global) {
    // The item's distance calls the object function, or the shape's module function the object function calls.
    const Function& o = m.functions[size_t(object)];
    int shape = o.body.empty() || o.body[o.result].op != Op::Call ? -1 : o.body[o.result].aux;
    Function& f = m.functions[size_t(fn)];
    bool found = false;
    for (const Instr& in : f.body) found |= in.op == Op::Call && (in.aux == object || in.aux == shape);
    if (!found) return false;
    object = [&] {
        for (const Instr& in : f.body)
            if (in.op == Op::Call && in.aux == object) return object;
        return shape;
    }();
    std::vector<Instr> old = std::move(f.body);
    f.body.clear();
    std::vector<ValueId> map(old.size());
    Builder b(m, f);
    for (size_t i = 0; i < old.size(); ++i) {
        Instr copy = old[i];
        for (ValueId& a : copy.args) a = map[a];
        ValueId v = f.add(std::move(copy));
        if (old[i].op == Op::Call && old[i].aux == object) v = divided(b, v, old[i].type, K, global);
        map[i] = v;
    }
    f.result = map[f.result];
    for (auto& [name, v] : f.outputs) v = map[v];
    return true;
}

// Divides function `fn`'s result (its first component, for an instrumented (distance, count)) by K (or `global`).
void divide_result(Module& m, int fn, double K, int global) {
    Function& f = m.functions[size_t(fn)];
    Builder b(m, f);
    f.result = divided(b, f.result, f.body[f.result].type, K, global);
}

// The member of a group (k ∈ [0, group − 1], the last of `others`) whose gradient's samples are steepest, `samples`
// points each: where a warning about the group's gradient is located (twelve noisy rocks of one group were warned of
// at the first, the flattest, with nothing to say which one was steep: a trial's, stop 56). -1 where none was
// sampled steeper than 1.
int steepest_member(const Module& m, int fn, const std::vector<Interval>& region, std::vector<std::vector<Interval>> others,
                    double ball, int group, int samples) {
    Module work = m;
    std::string why;
    const int grad = differentiate(work, fn, 0, "lipschitz_gradient", &why);
    if (grad < 0 || others.empty()) return -1;
    int best = -1;
    double steepest = 1 + 1e-3;  // (steeper than 1: members all within it are none the steeper)
    for (int k = 0; k < group; ++k) {
        others.back() = {{double(k), double(k)}};
        const double s = sample(work, grad, region, others, ball, samples);
        if (s > steepest) steepest = s, best = k;
    }
    return best;
}

// The steepest gradient `samples` uniform samples of fn reach over the region (0 where it has no derivative):
// the check of a shape that says it is 1-Lipschitz (`# exact`, `# bound`), which is not estimated.
double sampled_gradient(const Module& m, int fn, const std::vector<Interval>& region, const std::vector<std::vector<Interval>>& others,
                        double ball, int samples) {
    Module work = m;
    std::string why;
    int grad = differentiate(work, fn, 0, "lipschitz_gradient", &why);
    return grad < 0 ? 0 : sample(work, grad, region, others, ball, samples);
}

}  // namespace

LipschitzEstimate estimate_lipschitz(const Module& m, int fn, const std::vector<Interval>& box,
                                     const std::vector<std::vector<Interval>>& others, double ball, int samples, int boxes,
                                     bool refine_bound, double* split_work, bool jumps, bool derived_suffices,
                                     RefinedBound* shared) {
    LipschitzEstimate e;
    double own_work = kSplitWorkPerEstimate;
    if (!split_work) split_work = &own_work;
    t_split_work = *split_work;
    t_boxes = 0;
    t_blend_steepest = 0;
    Module work = m;  // the gradient is a function of its own, here only
    std::string why;
    int grad = differentiate(work, fn, 0, "lipschitz_gradient", &why);
    if (grad < 0) {
        e.derived = kInf;
        e.why = why;
        return e;
    }
    // One value for each value written twice: a weight read in ∑_i w_i t_i and again in ∑_j w_j is one weight, which
    // the interval analysis' convex combinations need (ir/Intervals.cpp, convex_form).
    eliminate_common_subexpressions(work.functions[size_t(grad)]);
    mix_forms(work.functions[size_t(grad)]);  // (1 − h)∂x + h∂y: mix's rule (a blend of value noise's corners)
    // The work is boxes and samples times the gradient's size: a huge shape (a min of 100,000 terms) gets
    // fewer of both, so the pass stays within about a second (its bound is then looser, never smaller).
    size_t size = 0;
    for (const auto& f : work.functions) size += f.body.size();
    double scale = std::min(1.0, kWorkBudget / (double(size) * double(boxes + samples)));
    boxes = std::max(4, int(boxes * scale));
    samples = std::max(16, int(samples * scale));
    std::vector<std::vector<Interval>> worst;
    double witness = 0;  // (exact gradients at the search's points: where the bound is largest)
    e.derived = derive(work, grad, box, others, ball, boxes, false, nullptr, &worst, &witness);
    int evaluated = 0;
    uint64_t steps = 0;
    e.sampled = sample(work, grad, box, others, ball, samples, &evaluated, false, &steps);
    e.sampled = std::max(e.sampled, witness);
    // The samples near the shape and at the sliders' ends take ~2,000 evaluations: fewer where one costs more than
    // 2·10⁴ evaluator steps (a sum of 3,600 terms costs 10⁵: those samples were 60% of its compile, 4 s).
    const double per_eval = evaluated > 0 ? double(steps) / evaluated : 1;
    auto scaled = [&](int n) { return std::max(4, int(n * std::min(1.0, 2e4 / std::max(per_eval, 1.0)))); };
    if (evaluated == 0) {
        // The gradient's IR is beyond the evaluator's step limit at every point (a 15,000-step recurrence): its
        // samples said 0 and the shape was marched with K = 1 where its slope is 3 (a new user's trial). Central
        // differences of the distance instead, at fewer points (six evaluations each).
        e.sampled = sample(work, fn, box, others, ball, std::max(16, samples / 8), &evaluated, true);
        e.unevaluable = evaluated == 0;
        if (e.unevaluable)
            e.why = fmt::format("neither its gradient nor its distance can be evaluated within {} steps of iqc's evaluator",
                                kSampleSteps);
    }
    // The refinements only ever lower a bound that stands without them: one that cannot be built (a form the
    // differentiator has no rule for once a cut is a parameter) leaves the bound as it is. They run only where
    // the bound decides something: above 2, or above 1 where samples exceed 1 (within 2 with every sample
    // within 1, the distance is not divided at all).
    // The combinators' bound runs within 2 too: a blend written in the module whose partials sum to more than 1
    // somewhere (LipschitzEstimate::blend_steepest) is marched by its derived bound, not as 1-Lipschitz (a
    // half-corrected smooth minimum, slope 1.36 in a band no sample met: a new user's trial, stop 40).
    auto refine = [&](auto bound, bool within_too = false) {
        bool within = e.derived <= 2 * (1 + 1e-9) && e.sampled <= 1 + 1e-3 && !(shared && shared->force);
        if (!refine_bound || e.derived <= 1 + 1e-9 || (within && !within_too)) return;
        try {
            e.derived = std::min(e.derived, bound(m, fn, box, others, ball, boxes));
        } catch (const InternalError&) {
        } catch (const SizeLimit&) {
        }
    };
    if (shared && shared->valid) {  // (the same shape and sliders' ranges, refined over a box that holds this one)
        e.derived = std::min(e.derived, shared->derived);
        t_blend_steepest = std::max(t_blend_steepest, shared->blend_steepest);
    } else {
        refine(chain_rule_bound);
        refine(union_bound);
        refine(combinator_bound, true);
        refine(roots_bound);
        refine(split_bound);
    }
    // After the refinements (the bound they leave decides what the samples decide), samples where the bound
    // is largest: a shape whose slope exceeds 1 only in a thin band (a blend whose weights
    // overshoot where |a - b| is near k: slope 1.36 there, derived 1.5) had every uniform sample within 1 and
    // was marched as 1-Lipschitz (a new user's trial, stop 40). 32 samples in each of the 8 worst boxes.
    // (Only where the samples decide what is applied: a bound within 2 whose samples stay within 1 is not
    // applied, and no useful bound falls back to the samples'. Elsewhere they only word warnings, and the walks'
    // evaluations of a large gradient cost the Christmas tree 20-35 ms.)
    // A declaration (`# lipschitz: K`, refine_bound off) is checked by these samples too: a ramp of slope 7 in a band
    // 0.05 wide passed `# lipschitz: 1` unwarned, holes in its picture (a trial's, stop 52).
    // Where sliders are uniforms and the bound is over 3× the samples (the "up to N× slower" warning), the samples
    // at the sliders' ends too: ‖p‖/(k m) over k ∈ [0.25, 3], m ∈ [0.5, 2] is 8, exactly the bound, where samples at
    // the defaults reached 1 and the warning invited a declaration that would have made holes (a trial's, stop 54).
    const bool decides = !useful_bound(e.derived) || (e.derived <= 2 * (1 + 1e-9) && e.sampled <= 1 + 1e-3) ||
                         !refine_bound || (!work.constant_parameters && e.derived > 3 * std::max(e.sampled, 1.0));
    if (evaluated > 0 && e.derived > 1 + 1e-9 && decides && !(derived_suffices && useful_bound(e.derived))) {
        std::vector<std::array<double, 3>> ends;
        // (without a useful bound, the samples outside the shape are kept apart: they choose the K marched by)
        // (a field that moves is sampled over time by `sample` only: its outside samples, at time 0, are not taken)
        bool moves = false;
        for (const auto& f : work.functions)
            for (const Instr& in : f.body) moves = moves || in.op == Op::Input;
        const bool no_bound = !useful_bound(e.derived) && !moves;
        double* outside = no_bound ? &e.outside : nullptr;
        for (const auto& b : worst) e.sampled = std::max(e.sampled, sample(work, grad, b, others, ball, 32, nullptr, false, nullptr, fn, outside));
        e.sampled = std::max(e.sampled, sample_towards_surface(work, fn, grad, box, others, ball, 64, &ends, outside));
        e.sampled = std::max(e.sampled, sample_by_line_search(work, fn, grad, box, others, ball, scaled(16), &ends, outside));
        if (no_bound) e.outside = std::max(e.outside, sample_outside(work, fn, grad, box, others, ball, scaled(samples)));
        // And within the box that holds the shape (support_box, where intervals prove D > 0 outside it), half as wide
        // again each way: narrow Gaussian blobs 0.5 − ∑ e^(-40‖p − x_i‖²) have a gradient of exactly 0 in doubles a
        // few units out, where every walk and line search stops; samples reached 0, K = 1 was applied where the slope
        // is 5.3, and the blobs were drawn as hollow rings (a trial's, stop 54).
        if (no_bound) {
            std::vector<std::vector<Interval>> params = {box};
            params.insert(params.end(), others.begin(), others.end());
            std::optional<SupportBox> held;
            // (with uniforms, a sequence of points has no bounds and no box holds the shape over them: the box at the
            // sliders' defaults then, where the samples are taken)
            for (int fixed = 0; fixed < 2 && !held; ++fixed) {
                if (fixed && work.constant_parameters) break;
                work.constant_parameters = work.constant_parameters || fixed;
                try {
                    held = support_box(work, fn, 0, params, 0.0, 48, 16, 400000);
                } catch (const InternalError&) {
                } catch (const SizeLimit&) {
                }
                if (fixed) work.constant_parameters = false;
            }
            std::vector<Interval> near(3);
            bool finite = held.has_value();
            for (size_t c = 0; c < 3 && finite; ++c) {
                const double lo = held->lo[c], hi = held->hi[c];
                finite = std::isfinite(lo) && std::isfinite(hi) && lo <= hi;
                const double margin = 0.5 * (hi - lo) + 0.05;
                near[c] = {std::max(lo - margin, box[c].lo), std::min(hi + margin, box[c].hi)};
                finite = finite && near[c].lo < near[c].hi;
            }
            if (finite) {
                e.sampled = std::max(e.sampled, sample(work, grad, near, others, ball, scaled(samples), nullptr, false, nullptr, fn, outside));
                e.outside = std::max(e.outside, sample_outside(work, fn, grad, near, others, ball, scaled(samples)));
                e.sampled = std::max(e.sampled, sample_by_line_search(work, fn, grad, near, others, ball, scaled(16), &ends, outside));
            }
        }
        // Uniform samples, and walks, near the shape: over the hull of the walks' ends at two scales, a quarter wider
        // and three times its size each way. A region of ±105 around four blobs a unit across, one of them twice as
        // steep (an exponential smooth minimum with one weight 16 where the others are 8: slope 2 within 0.27 of its
        // centre), had every sample within 1: uniform ones missed it, and every walk from afar ends on the flatter
        // blobs, nearer in distance there (a trial's, stop 52); so did a ball twice as steep 2 units beside a unit
        // ball, min(‖p‖ − 1, 2‖p − (3, 0, 0)‖ − 1.6), and a sharper point 4 units from a cluster (another's: holes).
        auto near_samples = [&](const std::vector<std::array<double, 3>>& from, int uniform, int walks) {
            if (from.size() < 4) return;
            std::vector<Interval> hull(3, Interval{kInf, -kInf});
            for (const auto& q : from)
                for (size_t c = 0; c < 3; ++c) hull[c] = iv::hull(hull[c], {q[c], q[c]});
            double extent = 0, whole = 1;
            for (size_t c = 0; c < 3; ++c) {
                extent = std::max(extent, hull[c].hi - hull[c].lo);
                whole *= box[c].hi - box[c].lo;
            }
            for (double scale : {0.25, 3.0}) {
                std::vector<Interval> near = hull;
                double volume = 1;
                for (size_t c = 0; c < 3; ++c) {
                    const double margin = std::max(scale * extent, 0.05);
                    near[c] = {std::max(near[c].lo - margin, box[c].lo), std::min(near[c].hi + margin, box[c].hi)};
                    volume *= near[c].hi - near[c].lo;
                }
                if (!(volume > 0) || volume * 8 > whole) break;
                e.sampled = std::max(e.sampled, sample(work, grad, near, others, ball, uniform, nullptr, false, nullptr, fn, outside));
                e.sampled = std::max(e.sampled, sample_towards_surface(work, fn, grad, near, others, ball, walks, nullptr, outside));
                if (no_bound) e.outside = std::max(e.outside, sample_outside(work, fn, grad, near, others, ball, uniform));
            }
        };
        near_samples(ends, scaled(samples), scaled(64));
        // Where the sliders are uniforms (WebGL2, GLSL, …) the bound holds over their ranges and so must the
        // samples: at settings of the sliders the shape reads besides their defaults (below), since a slope of 1.9
        // at a slider's end, 1 at its default, was marched as 1-Lipschitz (a trial's, stop 40).
        if (!work.constant_parameters && shared && shared->settings_valid) {
            e.sampled = std::max(e.sampled, shared->settings_sampled);
            if (outside) e.outside = std::max(e.outside, shared->settings_outside);
        } else if (!work.constant_parameters) {
            // (the settings' own samples apart, for the items that share them)
            const double sampled_before = e.sampled, outside_before = e.outside;
            e.sampled = 0, e.outside = 0;
            const std::vector<size_t> sliders = sliders_read(work, fn);
            size_t size = 0;
            for (const auto& f : work.functions) size += f.body.size();
            SplitMix64 settings{0x94D049BB133111EBull};
            // (the sliders' values set in `work` itself, restored after: a copy of the module per setting copied
            // every function for a few values)
            std::vector<std::vector<double>> defaults;
            for (size_t gi : sliders) defaults.push_back(work.globals[gi].value);
            // The settings, each slider at its low end (0), its high end (1), its default (-1) or at random (2):
            // every slider low, every slider high, the other corners of the sliders' box where they are at most 4
            // (0.5k/m is steepest at k high and m low: a trial's, which no setting below met), each of the first 6 at
            // either end with the others at their defaults (with samples near the shape, as at the defaults), then 4
            // at random (a slope 1/(2k) over k ∈ [0.25, 2] is 2 only at k's low end, which random settings of 23–93%
            // of the range never met: a trial's, stop 52).
            std::vector<std::vector<int>> ends;
            const size_t n_sliders = sliders.size();
            ends.push_back(std::vector<int>(n_sliders, 0));
            ends.push_back(std::vector<int>(n_sliders, 1));
            if (n_sliders >= 2 && n_sliders <= 4)
                for (size_t corner = 1; corner + 1 < (size_t(1) << n_sliders); ++corner) {
                    std::vector<int> e_k(n_sliders);
                    for (size_t k = 0; k < n_sliders; ++k) e_k[k] = int((corner >> k) & 1);
                    ends.push_back(std::move(e_k));
                }
            for (size_t k = 0; k < std::min<size_t>(n_sliders, 6); ++k)
                for (int end = 0; end < 2; ++end) {
                    std::vector<int> e_k(n_sliders, -1);
                    e_k[k] = end;
                    ends.push_back(std::move(e_k));
                }
            const size_t ends_settings = ends.size();
            // (16 random settings where they are taken once for several items, which each took 4 of their own)
            for (int r = 0; r < (shared ? 16 : 4); ++r) ends.push_back(std::vector<int>(n_sliders, 2));
            for (size_t v = 0; v < ends.size() && !sliders.empty() && size < 200000; ++v) {
                for (size_t k = 0; k < sliders.size(); ++k) {
                    Global& gl = work.globals[sliders[k]];
                    const size_t n = gl.bounds.lo.size();
                    const int end = ends[v][k];
                    for (size_t c = 0; c < gl.value.size() && n > 0 && gl.bounds.hi.size() == n; ++c) {
                        double lo = gl.bounds.lo[c % n], hi = gl.bounds.hi[c % n];
                        if (!(std::isfinite(lo) && std::isfinite(hi) && lo <= hi)) continue;
                        gl.value[c] = end == 0 ? lo : end == 1 ? hi : end == 2 ? lo + (hi - lo) * settings() : defaults[k][c];
                    }
                }
                std::vector<std::array<double, 3>> moved;
                e.sampled = std::max(e.sampled, sample(work, grad, box, others, ball, v < 2 ? 64 : scaled(64), nullptr, false, nullptr, fn, outside));
                e.sampled = std::max(e.sampled, sample_towards_surface(work, fn, grad, box, others, ball, v < 2 ? 16 : scaled(16), &moved, outside));
                if (no_bound && v < ends_settings)
                    e.sampled = std::max(e.sampled, sample_by_line_search(work, fn, grad, box, others, ball, scaled(8), &moved, outside));
                if (v < ends_settings) near_samples(moved, scaled(32), scaled(16));
            }
            for (size_t k = 0; k < sliders.size(); ++k) work.globals[sliders[k]].value = std::move(defaults[k]);
            if (shared) {
                shared->settings_valid = true;
                shared->settings_sampled = e.sampled;
                shared->settings_outside = outside ? e.outside : 0;
            }
            e.sampled = std::max(e.sampled, sampled_before);
            e.outside = std::max(e.outside, outside_before);
        }
    }
    if (!work.constant_parameters && evaluated > 0 && e.derived > 1 + 1e-9 && e.derived <= 2 * (1 + 1e-9) && e.sampled <= 1 + 1e-3 &&
        refine_bound) {
        work.constant_parameters = true;
        e.at_defaults = derive(work, grad, box, others, ball, boxes, false, nullptr, nullptr, nullptr);
        work.constant_parameters = false;
    }
    *split_work = t_split_work;
    t_split_work = 0;
    e.boxes = t_boxes;
    e.blend_steepest = t_blend_steepest;
    e.derived = std::max(e.derived, e.sampled);  // rounding in the intervals' ends never claims less than seen
    if (jumps && std::isfinite(e.derived)) find_jump(m, fn, box, others, ball, std::max(e.derived, 1.0), 4 * samples, e);
    return e;
}

// What a shape's Lipschitz estimate and bound check depend on, but for the box it is analysed over: its object
// function's instructions, with each global it reads replaced by that global's kind, value and slider bounds
// (every instance has an object function of its own, reading its own parameter globals), and the spec's ball,
// group and declared bound. Instances of one shape with equal parameters get equal keys and one analysis (see
// analysis_clusters for the box): 2,000 moving spheres with `bound` were 2,000 bound checks, 1,000 moving rings
// 1,000 estimates (11.7 s), n² with the evaluators' set-up.
std::string analysis_key(const Module& m, const LipschitzSpec& spec, bool slider_values) {
    std::string k;
    auto put = [&](const void* p, size_t n) { k.append(static_cast<const char*>(p), n); };
    auto num = [&](double v) { put(&v, sizeof v); };
    auto whole = [&](long long v) { put(&v, sizeof v); };
    auto nums = [&](const std::vector<double>& v) {
        whole((long long)v.size());
        for (double x : v) num(x);
    };
    auto type = [&](const Type& t) {
        int a[5] = {int(t.kind), t.rows, t.cols, int(t.elem), t.count};
        put(a, sizeof a);
    };
    auto bounds = [&](const ValueBounds& b) {
        whole(b.input);
        nums(b.lo);
        nums(b.hi);
    };
    num(spec.ball);
    whole(spec.group);
    num(spec.declared);
    whole(spec.trusted);
    const Function& f = m.functions[size_t(spec.object_fn)];
    whole((long long)f.params.size());
    for (const auto& p : f.params) type(p.type);
    whole((long long)f.param_bounds.size());
    for (const auto& b : f.param_bounds) bounds(b);
    whole((long long)f.body.size());
    for (const Instr& in : f.body) {
        whole(int(in.op));
        type(in.type);
        whole((long long)in.args.size());
        for (ValueId a : in.args) whole(a);
        nums(in.data);
        if (in.op == Op::Global && in.aux >= 0 && size_t(in.aux) < m.globals.size()) {
            const Global& g = m.globals[size_t(in.aux)];
            whole(int(g.kind));
            type(g.type);
            if (g.kind == Global::Kind::Prepared) whole(in.aux);  // computed per pixel: only itself is equal
            if (slider_values || g.kind != Global::Kind::Parameter || m.constant_parameters) nums(g.value);
            bounds(g.bounds);
        } else {
            whole(in.aux);
        }
    }
    whole(f.result);
    return k;
}

// Items analysed as one: equal analysis_key and boxes that nearly coincide. Each item's box is where its
// instance is marched, in its own space (the scene's reach through its transform), so instances of one shape
// at different places have different boxes; a bound derived over the boxes' hull holds in each, and where the
// hull is at most 1.25 times as wide as each member's box on every axis it is hardly looser. Returns, per
// function, its cluster (-1: no item) and, per cluster, the box to analyse.
struct Clusters {
    std::vector<int> of;
    std::vector<std::vector<Interval>> box;
    std::vector<std::string> key;
};
Clusters analysis_clusters(const Module& m, bool slider_values = true) {
    // (items that share only a refined bound: nearer, since the bound over the hull is theirs, samples and all; sixty
    // moving cups' boxes ±136 across, shifted by their x: their hull 1.1× as wide took 7.49 where each alone 4.15)
    const double kWider = slider_values ? 1.25 : 1.05;
    Clusters c;
    c.of.assign(m.functions.size(), -1);
    std::vector<std::array<double, 3>> narrowest;  // per cluster: its members' smallest width per axis
    std::unordered_map<std::string, std::vector<int>> by_key;
    for (size_t fi = 0; fi < m.functions.size(); ++fi) {
        const LipschitzSpec& spec = m.functions[fi].lipschitz;
        if (spec.object_fn < 0) continue;
        std::vector<Interval> own;
        for (size_t k = 0; k < 3; ++k) own.push_back({spec.region.lo[k], spec.region.hi[k]});
        std::string key = analysis_key(m, spec, slider_values);
        std::vector<int>& same = by_key[key];
        int joined = -1;
        for (int ci : same) {
            std::vector<Interval> hull = c.box[size_t(ci)];
            bool fits = true;
            for (size_t k = 0; k < 3 && fits; ++k) {
                if (own[k].lo == hull[k].lo && own[k].hi == hull[k].hi) continue;  // (also an infinite side)
                hull[k] = {std::min(hull[k].lo, own[k].lo), std::max(hull[k].hi, own[k].hi)};
                double width = hull[k].hi - hull[k].lo, least = std::min(narrowest[size_t(ci)][k], own[k].hi - own[k].lo);
                fits = std::isfinite(width) && width <= kWider * least;
            }
            if (!fits) continue;
            joined = ci;
            c.box[size_t(ci)] = hull;
            for (size_t k = 0; k < 3; ++k) narrowest[size_t(ci)][k] = std::min(narrowest[size_t(ci)][k], own[k].hi - own[k].lo);
            break;
        }
        if (joined < 0) {
            joined = int(c.box.size());
            c.box.push_back(own);
            c.key.push_back(key);
            narrowest.push_back({own[0].hi - own[0].lo, own[1].hi - own[1].lo, own[2].hi - own[2].lo});
            same.push_back(joined);
        }
        c.of[fi] = joined;
    }
    return c;
}

// ---- K as a function of the sliders (targets where sliders are uniforms) ----
//
// A bound over the sliders' whole ranges holds at every setting, but a field whose slope grows with a slider is
// marched at every setting as at the slider's steepest end: the displaced torus (a ∈ [0, 0.3], f ∈ [1, 60]) with
// K = 32.6 where its default setting needs 8.7, the sine terrain 28.3 where 2.7 (10× the steps, WebGL2 against
// Shadertoy). The sliders' box is cut into cells (per slider a narrow one around its default, wider ones further
// out), the bound estimated over each cell as over the whole (the sliders' bounds narrowed to the cell), and iqc_prepare
// picks the cell of the sliders' values once per pixel: the distance is divided by that cell's K, and the hit test
// multiplies it back. Each cell's K is a bound over the cell (or, where the whole has no useful bound, the cell's
// samples with the same margin), never above the whole's.

// What an estimate of a shape with no declaration or pragma decides (apply_lipschitz_bounds words it, the cells take
// its K): 1 where every sample is within 1 and the bound within 2 (unless within 1 at the sliders' defaults: the rest
// comes from their ranges); the derived bound where useful (at most kUnbounded); else the samples' steepest (outside the
// shape where the inside is over 4× steeper) times the margin, or the derived bound where smaller; or 1 where even the
// samples' margin is too steep to march by.
struct Decision {
    enum Kind { OneLipschitz, Derived, Sampled, TooSteep } kind = OneLipschitz;
    double K = 1;
    bool apart = false;  // (no useful bound) the samples outside the shape chose
    double steep = 0;    // (no useful bound) the steepest sample the K comes from
};
Decision decide(const LipschitzEstimate& e) {
    Decision d;
    if (e.sampled <= 1 + 1e-3 && e.derived <= 2 * (1 + 1e-9) && e.blend_steepest <= 1 + 1e-3 &&
        !(e.at_defaults > 0 && e.at_defaults <= 1 + 1e-9))
        return d;
    if (useful_bound(e.derived)) {
        d.kind = Decision::Derived;
        d.K = e.derived;
        return d;
    }
    d.apart = e.outside > 0 && e.sampled > 4 * e.outside;
    d.steep = d.apart ? e.outside : e.sampled;
    if (d.steep > 1 + 1e-3 && kSampledMargin * d.steep <= kSampledCap) {
        d.kind = Decision::Sampled;
        d.K = std::min(kSampledMargin * d.steep, std::isfinite(e.derived) ? e.derived : kInf);
    } else {
        d.kind = Decision::TooSteep;  // (K 1: as if 1-Lipschitz where the samples are steeper than 1)
    }
    return d;
}

// A cell's factor: its derived bound where that is useful (proven over the cell: never the rule that takes 1 where
// every sample is within 1, since a cell's fewer samples missed a slope of 2 at a slider's end that the whole's had
// met: a trial's, stop 55), else its samples' steepest times the margin, at most `cap`; where even that is too steep,
// `fallback` (the whole's).
double cell_factor(const LipschitzEstimate& e, double cap, double fallback) {
    if (useful_bound(e.derived)) return std::clamp(e.derived, 1.0, cap);
    const Decision d = decide(e);
    return d.kind == Decision::TooSteep && d.steep > 1 + 1e-3 ? fallback : std::clamp(d.K, 1.0, cap);
}

// The cells of one analysis (shared by the items of a cluster: their sliders in the same order).
struct SliderComponent {
    size_t k = 0, c = 0;  // a slider, by its position in sliders_read's order, and a component of it (a vector slider's)
};
struct SliderCells {
    std::vector<SliderComponent> which;      // the sliders (components) cut
    std::vector<std::vector<double>> edges;  // per slider cut: its low end = e₀ < e₁ < … < e_n = its high end
    std::vector<double> K;                   // per cell, the first slider's cell index varying slowest
    double at_defaults = 0;                  // the cell holding the defaults' K
    double sampled_at_defaults = 0;          // and the steepest gradient its samples met
    size_t estimated = 0;                    // the cells estimated (nearest the defaults first); the others keep the whole's K
    bool window = false;                     // one cell around the defaults estimated (slider_cells' window), the whole's K outside
    // A group's per-member tables past 16 members (too many for a cell per member): every estimate holds with each
    // table's component within the hull [lo, hi] of its members' values (float-rounded outward), and iqc_prepare
    // takes the cells' K only while every member's value is within it (a loop over the members), else the whole's.
    // Where they are the only sliders cut (`which` empty), tiers: K[t] holds within tier t's [lo[t], hi[t]] (the hull,
    // then the hull widened by kHullWidening of the range each side: a member's slider moved a little keeps a K near it).
    struct Hull {
        SliderComponent which;
        std::vector<double> lo, hi;  // per tier
    };
    std::vector<Hull> hull;
};

// The widening of a group's hull tier past the first, in its slider's range each side (SliderCells::Hull).
constexpr double kHullWidening = 1.0 / 8;

// The half-width of the cell around a slider's default d: f·r (r its range), at most half the default's magnitude, and
// at least r/4096 (a frequency f ∈ [0, 1000] whose default 1 was the cell [0, 63.5] marched its terrain with K = 174
// where Shadertoy's is 2.3, rays stopped short; a default 0, [0, 15.6]: 220 against 4.3; a trial's, stop 56).
double inner_width(double r, double d, double f) { return std::min(f * r, std::max(std::fabs(d) / 2, r / 4096)); }

// The edges of a slider's cells: a cell around the default d, `fractions` of the range r wide on each side (the first,
// the narrowest, as inner_width has it), and cells bounded by d ± f·r for each larger fraction f, up to the ends.
std::vector<double> cell_edges(double lo, double hi, double d, const std::vector<double>& fractions) {
    const double r = hi - lo;
    std::vector<double> e = {lo, hi};
    for (size_t i = 0; i < fractions.size(); ++i) {
        const double w = i == 0 ? inner_width(r, d, fractions[i]) : fractions[i] * r;
        for (double x : {d - w, d + w})  // (in float: the shader compares a uniform with the same number)
            if (x > lo + 1e-4 * r && x < hi - 1e-4 * r) e.push_back(double(float(x)));
    }
    std::sort(e.begin(), e.end());
    std::vector<double> out;
    for (double x : e)
        if (out.empty() || x > out.back() + 1e-4 * r) out.push_back(x);
    if (out.back() < hi) out.back() = hi;
    return out;
}

// The edges of a slider's window around its default d: ±1/64 of the range as inner_width has it (a ripple frequency 5 of
// [0, 1000] is 5 ± 2.5, not 5 ± 15.6: the window's K is the picture's at the defaults), up to the ends.
std::vector<double> window_edges(double lo, double hi, double d) { return cell_edges(lo, hi, d, {1.0 / 64}); }

// Estimates the cells of an item whose whole bound `whole` (applied) comes from its estimate, where its sliders are
// uniforms: nothing (nullopt) where no slider is a scalar with finite bounds, where the cell of the defaults gains
// less than a fifth, past `budget` estimates (decremented by those taken), or where the cells' analysis work would pass
// kCellWorkRatio × `whole_work` (the whole's estimate's; kCellWorkFloor where that is more) or `work_left` (the
// module's, decremented by the work taken).
std::optional<SliderCells> slider_cells(const Module& m, const LipschitzSpec& spec, const std::vector<Interval>& region,
                                        const std::vector<std::vector<Interval>>& others, double whole, bool sampled,
                                        uint64_t whole_work, long& budget, uint64_t& work_left, std::string& over_budget) {
    const uint64_t start = analysis_work();
    const uint64_t work_allowed =
        std::min(work_left, std::max(uint64_t(kCellWorkRatio * double(whole_work)), kCellWorkFloor));
    struct Spend {  // (however it returns: the work taken comes off the module's)
        uint64_t& left;
        uint64_t start;
        ~Spend() { left -= std::min(left, analysis_work() - start); }
    } spend{work_left, start};
    // Which limit stops the cells, in the report's words.
    const std::string past_work = work_allowed == work_left ? "the scene's cells' analysis past ~1.7 s"
                                                            : "an item's cells' analysis past 8× its whole's or ~0.55 s";
    // (what is left of the module's below the whole's own work, or below the floor where that is less: a few cells
    // would spend it and keep none)
    if (work_allowed < std::min(whole_work, kCellWorkFloor)) {
        over_budget = past_work;
        return std::nullopt;
    }
    const std::vector<size_t> all = sliders_read(m, spec.object_fn);
    // Each component of a scalar or vector slider with a finite range (a vector's ‖t∘p‖ - 1, t ∈ [0.5, 4]³, marched with
    // 4 where its default needs 1.2: a trial's), and of a group's per-member table of one (up to 16 members: the group's
    // K is the largest of its members' cells' K; six bumpy balls in a group took 52× Shadertoy's steps: a trial's).
    // A group's per-member tables past 16 members (up to kMaxHullMembers), each component alike over its members: `large`,
    // pinned to the hull of their values (48 bumpy balls on a floor: K 53 over the sliders' ranges where Shadertoy's
    // constants give 4.2, 287 steps a pixel against 29; a trial's, trial77 #2).
    std::vector<SliderComponent> candidates, large;
    auto shape_of = [&](const Global& g, size_t& n, size_t& count) {  // components per element, elements
        n = size_t(g.type.is_array() ? g.type.element().components() : g.type.components());
        count = n > 0 ? g.value.size() / n : 0;
        return n > 0 && count >= 1 && g.value.size() == n * count && (g.type.is_array() || count == 1) &&
               (g.bounds.lo.size() == n || g.bounds.lo.size() == n * count) && g.bounds.hi.size() == g.bounds.lo.size();
    };
    for (size_t k = 0; k < all.size(); ++k) {
        const Global& g = m.globals[all[k]];
        size_t n = 0, count = 0;
        const bool shaped = shape_of(g, n, count), hull = g.type.is_array() && g.per_member && count > 16;
        // (a table past 16 members with a component of no finite range: no hull, since the loop would not test it and
        // the tiers' K held only near its values; trial78 #1: a ∈ ℝ moved in the page drew holes)
        if (hull && !shaped) return std::nullopt;
        if (!shaped || (count > 16 && (!hull || count > kMaxHullMembers))) continue;
        for (size_t c = 0; c < n; ++c) {
            bool ok = true;  // (every member's range of the component the same, finite and wide)
            for (size_t j = c; j < g.bounds.lo.size(); j += n)
                ok = ok && g.bounds.lo[j] == g.bounds.lo[c] && g.bounds.hi[j] == g.bounds.hi[c] && std::isfinite(g.bounds.lo[j]) &&
                     std::isfinite(g.bounds.hi[j]) && g.bounds.lo[j] < g.bounds.hi[j];
            if (hull && !ok) return std::nullopt;  // (as above)
            if (ok) (hull ? large : candidates).push_back({k, c});
        }
    }
    // (a table past 16 members without a range, which sliders_read leaves out: no hull, as above)
    if (!large.empty())
        for (size_t gi : sliders_read(m, spec.object_fn, true)) {
            const Global& g = m.globals[gi];
            if (g.bounds.lo.empty() && g.type.is_array() && g.per_member && g.value.size() > 16 * size_t(g.type.element().components()))
                return std::nullopt;
        }
    if ((candidates.empty() && large.empty()) || candidates.size() > 8) return std::nullopt;
    if (budget <= 0) {  // (said: items past it were marched by their whole's K with nothing to say why; a trial's, stop 56)
        over_budget = fmt::format("{} cell estimates a scene", kMaxCellEstimates);
        return std::nullopt;
    }
    Module work = m;
    auto stride = [&](const SliderComponent& s) {
        size_t n = 0, count = 0;
        shape_of(m.globals[all[s.k]], n, count);
        return n;
    };
    // A component's values: one, or one per member; their hull; and its range.
    auto values_of = [&](const SliderComponent& s) {
        std::vector<double> v;
        const Global& g = m.globals[all[s.k]];
        for (size_t j = s.c; j < g.value.size(); j += stride(s)) v.push_back(g.value[j]);
        return v;
    };
    auto set = [&](const SliderComponent& s, double lo, double hi) {
        Global& g = work.globals[all[s.k]];
        const size_t n = stride(s);
        for (size_t j = s.c; j < g.bounds.lo.size(); j += n) {
            g.bounds.lo[j] = lo;
            g.bounds.hi[j] = hi;
        }
        for (size_t j = s.c; j < g.value.size(); j += n) g.value[j] = std::clamp(m.globals[all[s.k]].value[j], lo, hi);
    };
    auto reset = [&](const SliderComponent& s) {
        const Global& g = m.globals[all[s.k]];
        set(s, g.bounds.lo[s.c], g.bounds.hi[s.c]);
    };
    auto pin = [&](const SliderComponent& s) {  // to the hull of its values
        const std::vector<double> v = values_of(s);
        set(s, *std::min_element(v.begin(), v.end()), *std::max_element(v.begin(), v.end()));
    };
    // The large tables' hulls, in every estimate below (float-rounded outward: the shader compares the uniforms, floats,
    // with them).
    std::vector<SliderCells::Hull> hulls;
    for (const SliderComponent& k : large) {
        Global& g = work.globals[all[k.k]];
        const size_t n = size_t(g.type.element().components());
        double lo = kInf, hi = -kInf;
        for (size_t j = k.c; j < g.value.size(); j += n) lo = std::min(lo, g.value[j]), hi = std::max(hi, g.value[j]);
        float flo = float(lo), fhi = float(hi);
        if (double(flo) > lo) flo = std::nextafter(flo, -std::numeric_limits<float>::infinity());
        if (double(fhi) < hi) fhi = std::nextafter(fhi, std::numeric_limits<float>::infinity());
        lo = std::max(double(flo), g.bounds.lo[k.c]), hi = std::min(double(fhi), g.bounds.hi[k.c]);
        for (size_t j = k.c; j < g.bounds.lo.size(); j += n) g.bounds.lo[j] = lo, g.bounds.hi[j] = hi;
        hulls.push_back({k, {lo}, {hi}});
    }
    auto set_hulls = [&](size_t tier) {
        for (const SliderCells::Hull& h : hulls) {
            Global& g = work.globals[all[h.which.k]];
            const size_t n = size_t(g.type.element().components());
            for (size_t j = h.which.c; j < g.bounds.lo.size(); j += n) g.bounds.lo[j] = h.lo[tier], g.bounds.hi[j] = h.hi[tier];
        }
    };
    // Which sliders the bound depends on: intervals alone (no samples, no refinements) with every slider at its
    // default, then each in turn over its range.
    std::string why;
    const int grad = differentiate(work, spec.object_fn, 0, "lipschitz_cells_gradient", &why);
    if (grad < 0) return std::nullopt;
    for (const SliderComponent& k : candidates) pin(k);
    // No bound at the defaults either (metaballs' singular centres, a recurrence): intervals cannot tell, and where the
    // K comes from samples every slider counts (the first two); a derived K would not come from cells.
    const double pinned = derive(work, grad, region, others, spec.ball, 48);
    if (!std::isfinite(pinned) && !sampled) return std::nullopt;
    std::vector<std::pair<double, SliderComponent>> influence;
    for (const SliderComponent& k : candidates) {
        if (!std::isfinite(pinned)) {
            influence.push_back({kInf, k});
            continue;
        }
        reset(k);
        const double ranged = derive(work, grad, region, others, spec.ball, 48);
        // (where the K comes from samples and even the defaults' bound is too large to march by, what moves the bound says
        // nothing of what moves the samples: every slider counts, the bound's ratio first)
        if (!(ranged <= 1.1 * pinned) || (sampled && !useful_bound(pinned))) influence.push_back({ranged / pinned, k});
        pin(k);
    }
    for (const SliderComponent& k : candidates) reset(k);
    work.functions.resize(m.functions.size());  // (the gradient: each estimate differentiates its own)
    if (influence.empty() && hulls.empty()) return std::nullopt;
    // Only the large tables: one estimate, within their hulls (as costly as the whole's where its K comes from samples).
    if (influence.empty()) {
        if (budget <= 0) {
            over_budget = fmt::format("{} cell estimates a scene", kMaxCellEstimates);
            return std::nullopt;
        }
        if (sampled && double(whole_work) > double(work_allowed) - double(analysis_work() - start)) {
            over_budget = past_work;
            return std::nullopt;
        }
        double allowance = kSplitWorkPerEstimate / 16;
        const LipschitzEstimate e =
            estimate_lipschitz(work, spec.object_fn, region, others, spec.ball, sampled ? 1000 : 250, sampled ? 128 : 64, true, &allowance);
        --budget;
        SliderCells c;
        c.K = {cell_factor(e, sampled ? kSampledCap : whole, whole)};
        c.at_defaults = c.K[0];
        c.sampled_at_defaults = e.sampled;
        c.estimated = 1;
        if (c.at_defaults > whole / 1.2 && c.K[0] <= whole) return std::nullopt;
        // The widened tier, where the work allows another estimate as costly and it gains a fifth on the whole's.
        const uint64_t one = analysis_work() - start;
        if (budget > 0 && double(analysis_work() - start) + double(one) <= double(work_allowed)) {
            bool wider = false;
            for (SliderCells::Hull& h : hulls) {
                const Global& g = m.globals[all[h.which.k]];
                const double w = kHullWidening * (g.bounds.hi[h.which.c] - g.bounds.lo[h.which.c]);
                h.lo.push_back(std::max(g.bounds.lo[h.which.c], double(float(h.lo[0] - w))));
                h.hi.push_back(std::min(g.bounds.hi[h.which.c], double(float(h.hi[0] + w))));
                wider = wider || h.lo[1] < h.lo[0] || h.hi[1] > h.hi[0];
            }
            if (wider) {
                set_hulls(1);
                allowance = kSplitWorkPerEstimate / 128;
                const LipschitzEstimate w = estimate_lipschitz(work, spec.object_fn, region, others, spec.ball, sampled ? 1000 : 64,
                                                               sampled ? 128 : 32, true, &allowance, false, !sampled);
                --budget;
                ++c.estimated;
                const double K = cell_factor(w, sampled ? kSampledCap : whole, whole);
                if (K <= whole / 1.2) c.K.push_back(std::max(K, c.K[0]));
            }
            for (SliderCells::Hull& h : hulls) h.lo.resize(c.K.size()), h.hi.resize(c.K.size());
        }
        c.hull = std::move(hulls);
        return c;
    }
    std::stable_sort(influence.begin(), influence.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
    // Two layouts. The cells: where the K comes from samples (each cell's estimate as costly as the whole's: 27 cells of a
    // twisted, rippled smooth union took 1.8 s), up to two sliders, 7 or 3×3 cells; else up to three, 7, 5×5 or 3×3×3.
    // The window, where the whole's K comes from samples (or it is marched as if 1-Lipschitz, too steep for them) and
    // the cells find nothing or would pass the allowance: up to five sliders, the defaults' cell (window_edges),
    // estimated alone (a twist, an amplitude and a frequency f ∈ [0, 500]: the uncut slider over its whole range in
    // every cell of two left each too steep; a trial's, stop 56). Outside it, the whole's K.
    auto layout = [&](bool window) -> std::optional<SliderCells> {
        std::vector<std::pair<double, SliderComponent>> cut = influence;
        const size_t cut_most = window ? 5 : sampled ? 2 : 3;
        if (cut.size() > cut_most) cut.resize(cut_most);
        SliderCells c;
        c.window = window;
        c.hull = hulls;
        static const std::vector<double> kFractions[] = {{1.0 / 64, 1.0 / 16, 1.0 / 4}, {1.0 / 32, 1.0 / 6}, {1.0 / 16}};
        const size_t fractions = window ? 0 : sampled && cut.size() == 2 ? 2 : cut.size() - 1;
        size_t cells = 1;
        for (const auto& [ratio, k] : cut) {
            const Global& g = m.globals[all[k.k]];
            c.which.push_back(k);
            c.edges.push_back(window ? window_edges(g.bounds.lo[k.c], g.bounds.hi[k.c], g.value[k.c])
                                     : cell_edges(g.bounds.lo[k.c], g.bounds.hi[k.c], g.value[k.c], kFractions[fractions]));
            cells *= c.edges.back().size() - 1;
        }
        c.K.assign(cells, whole);
        // The cells of the defaults: each member's values' (one for an instance).
        std::set<size_t> default_cells;
        {
            std::vector<std::vector<double>> values;  // per slider cut: its values (one, or one per member)
            size_t members = 1;
            for (const SliderComponent& k : c.which) {
                values.push_back(values_of(k));
                members = std::max(members, values.back().size());
            }
            for (size_t member = 0; member < members; ++member) {
                size_t cell = 0;
                for (size_t s = 0; s < c.which.size(); ++s) {
                    const std::vector<double>& e = c.edges[s];
                    const double d = values[s][std::min(member, values[s].size() - 1)];
                    size_t i = 0;
                    while (i + 2 < e.size() && !(d < e[i + 1])) ++i;  // (the shader's choice: the first edge above it)
                    cell = cell * (e.size() - 1) + i;
                }
                default_cells.insert(cell);
            }
        }
        // Where the K comes from samples, each cell's estimate is as costly as the whole's (as many samples, at the same
        // settings of the sliders): none is taken where the defaults' cells alone (a group's: one per member) would pass
        // the allowance, or the scene's count of estimates.
        if (sampled && double(default_cells.size()) * double(whole_work) > double(work_allowed) - double(analysis_work() - start)) {
            over_budget = past_work;
            return std::nullopt;
        }
        if (long(default_cells.size()) > budget) {
            over_budget = fmt::format("{} cell estimates a scene", kMaxCellEstimates);
            return std::nullopt;
        }
        std::vector<double> sampled_in(cells, 0);
        // A cell's index along each slider cut (the first slider's varying slowest).
        auto indices = [&](size_t cell) {
            std::vector<size_t> at(c.which.size());
            for (size_t s = c.which.size(); s-- > 0;) {
                at[s] = cell % (c.edges[s].size() - 1);
                cell /= c.edges[s].size() - 1;
            }
            return at;
        };
        // The defaults' cells first, then the others nearest them first (in cells along the farthest slider, then along all):
        // each cell not estimated keeps the whole's K, which holds over every value, so the budget only stops the estimates.
        std::vector<size_t> order(default_cells.begin(), default_cells.end());
        {
            std::vector<std::pair<std::pair<size_t, size_t>, size_t>> rest;  // ((farthest, total), cell)
            for (size_t cell = 0; cell < cells; ++cell) {
                if (default_cells.count(cell)) continue;
                const std::vector<size_t> at = indices(cell);
                std::pair<size_t, size_t> nearest{SIZE_MAX, SIZE_MAX};
                for (size_t d : default_cells) {
                    const std::vector<size_t> home = indices(d);
                    size_t farthest = 0, total = 0;
                    for (size_t s = 0; s < at.size(); ++s) {
                        const size_t apart = at[s] > home[s] ? at[s] - home[s] : home[s] - at[s];
                        farthest = std::max(farthest, apart);
                        total += apart;
                    }
                    nearest = std::min(nearest, std::pair<size_t, size_t>{farthest, total});
                }
                rest.push_back({nearest, cell});
            }
            std::stable_sort(rest.begin(), rest.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
            for (const auto& r : rest) order.push_back(r.second);
        }
        // (where the K comes from samples and the cells could not all be taken, each as costly as the whole: the window,
        // tighter at the defaults, where the picture starts, at the cost of their cell)
        if (!window && sampled && double(cells) * double(whole_work) > double(work_allowed)) {
            over_budget = past_work;
            return std::nullopt;
        }
        // Each cell away from the defaults is taken where the work so far, and what it is predicted to cost (as much as
        // those away from the defaults taken so far, or before any, as the defaults' each), is within the allowance;
        // the window's, none.
        uint64_t others_start = 0;
        for (size_t n = 0; n < order.size(); ++n) {
            const size_t cell = order[n];
            const bool holds_defaults = n < default_cells.size();
            if (!holds_defaults) {
                if (window) break;
                const uint64_t spent = analysis_work() - start;
                const double each = n == default_cells.size() ? double(others_start - start) / double(n)
                                                              : double(analysis_work() - others_start) / double(n - default_cells.size());
                if (double(spent) + each > double(work_allowed) || budget <= 0) {
                    over_budget = budget <= 0 ? fmt::format("{} cell estimates a scene", kMaxCellEstimates) : past_work;
                    break;
                }
            }
            const std::vector<size_t> at = indices(cell);
            for (size_t s = 0; s < c.which.size(); ++s) set(c.which[s], c.edges[s][at[s]], c.edges[s][at[s] + 1]);
            // The cell of the defaults, where the picture starts, with the case splitting a whole's estimate may spend;
            // elsewhere less (the twisted bar's 7 cells took 480 ms with it everywhere), and, where the cell's K is its
            // derived bound, fewer samples (they only word the warning). Where the whole's K came from its samples, each
            // cell has as many as the whole had: the K is theirs.
            double allowance = kSplitWorkPerEstimate / (holds_defaults ? 16 : 128);
            const int samples = sampled ? 1000 : holds_defaults ? 250 : 64, boxes = sampled ? 128 : holds_defaults ? 64 : 32;
            // (away from the defaults, a derived K is the cell's: its samples would word nothing)
            LipschitzEstimate e =
                estimate_lipschitz(work, spec.object_fn, region, others, spec.ball, samples, boxes, true, &allowance, false, !holds_defaults && !sampled);
            --budget;
            ++c.estimated;
            if (n + 1 == default_cells.size()) others_start = analysis_work();
            c.K[cell] = cell_factor(e, sampled ? kSampledCap : whole, whole);
            sampled_in[cell] = e.sampled;
        }
        for (size_t cell : default_cells) {  // (a group's: the steepest of its members' cells)
            c.at_defaults = std::max(c.at_defaults, c.K[cell]);
            c.sampled_at_defaults = std::max(c.sampled_at_defaults, sampled_in[cell]);
        }
        // Kept where the defaults' cell gains a fifth, or where some cell is steeper than the whole (marched as if
        // 1-Lipschitz, its samples too steep over the sliders' whole ranges: a frequency f ∈ [0, 10⁴] made holes at f = 20).
        if (c.at_defaults > whole / 1.2 && *std::max_element(c.K.begin(), c.K.end()) <= whole) return std::nullopt;
        return c;
    };
    // Where the K comes from samples and more sliders count than the cells cut, the window alone: each cell would hold
    // the others' whole ranges (five sliders of a displaced smooth minimum, three uncut in every cell: nothing gained,
    // 35.9 where Shadertoy's is 1.5; three whose product sets the slope: 20.5 at the defaults where 1.35; a trial's, stop
    // 56). Elsewhere the cells, and the window where they gain nothing.
    std::optional<SliderCells> found;
    if (!(sampled && influence.size() > 2)) found = layout(false);
    if (!found && sampled) {
        const std::string first = over_budget;
        over_budget.clear();
        found = layout(true);
        if (!found && over_budget.empty()) over_budget = first;
    }
    return found;
}

// Makes `factor` (the item's factor global) a prepared global that iqc_prepare sets to its cell's K from the sliders
// `all` (sliders_read's) as `cells` cut them: outside a slider's range, the whole's K (`whole`).
void prepare_cell_factor(Module& m, int factor, const std::vector<size_t>& all, const SliderCells& cells, double whole) {
    int prep = m.find(names::kPrepare);
    // A group's large tables: a loop over the members (one per table length) whose states (per tier) stay 1 while each
    // member's values are within the tier's hull; the cells' K where every one stays, else the whole's. (First: adding
    // the loops' bodies moves the functions.)
    const size_t tiers = cells.hull.empty() ? 0 : cells.hull[0].lo.size();
    std::vector<std::vector<ValueId>> hull_states;  // per table length, per tier
    {
        std::map<size_t, std::vector<MemberTest>> by_count;
        for (const SliderCells::Hull& h : cells.hull) {
            const Global& g = m.globals[all[h.which.k]];
            by_count[g.value.size() / size_t(g.type.element().components())].push_back({int(all[h.which.k]), int(h.which.c), h.lo, h.hi});
        }
        std::vector<std::string> states;
        for (size_t t = 0; t < tiers; ++t) states.push_back(t == 0 ? "inside" : fmt::format("inside_{}", t));
        for (const auto& [count, tests] : by_count)
            hull_states.push_back(members_within(m, prep, fmt::format("{}.{}.members_within_hull", names::kPrepare, m.globals[size_t(factor)].name),
                                                 count, tests, states));
    }
    if (prep < 0) prep = prepare_function(m);
    Function& f = m.functions[size_t(prep)];
    Builder b(m, f);
    // The table as selects over the first slider's cell (rows), each row over the next slider's, …: a few comparisons
    // once per pixel; outside a slider's range, the whole's K. For a group's per-member tables, per member, and the
    // largest of the members' K.
    size_t members = 1;
    for (const SliderComponent& k : cells.which)
        if (m.globals[all[k.k]].type.is_array())
            members = std::max(members, m.globals[all[k.k]].value.size() / size_t(m.globals[all[k.k]].type.element().components()));
    ValueId K = 0;
    for (size_t member = 0; member < members; ++member) {
        std::vector<ValueId> value, inside;
        for (const SliderComponent& k : cells.which) {
            const Global& g = m.globals[all[k.k]];
            ValueId u = b.global(int(all[k.k]));
            Type t = g.type;
            if (t.is_array()) {
                u = b.op(Op::Index, {u, b.integer((long long)member)});
                t = t.element();
            }
            value.push_back(t.is_scalar() ? u : b.op(Op::Extract, {u}, int(k.c)));
            inside.push_back(b.op(Op::And, {b.compare(CompareKind::Ge, value.back(), b.scalar(g.bounds.lo[k.c])),
                                            b.compare(CompareKind::Le, value.back(), b.scalar(g.bounds.hi[k.c]))}));
        }
        std::function<ValueId(size_t, size_t)> table = [&](size_t s, size_t base) -> ValueId {
            const std::vector<double>& e = cells.edges[s];
            const size_t n = e.size() - 1;
            size_t stride = 1;
            for (size_t t = s + 1; t < cells.edges.size(); ++t) stride *= cells.edges[t].size() - 1;
            auto cell = [&](size_t i) { return s + 1 == cells.edges.size() ? b.scalar(cells.K[base + i]) : table(s + 1, base + i * stride); };
            ValueId v = cell(n - 1);
            for (size_t i = n - 1; i-- > 0;) v = b.op(Op::Select, {b.compare(CompareKind::Lt, value[s], b.scalar(e[i + 1])), cell(i), v});
            return v;
        };
        if (cells.which.empty()) {  // (a group's large tables alone: their hulls' tiers, below)
            K = b.scalar(whole);
            break;
        }
        ValueId own = table(0, 0);
        ValueId in = inside[0];
        for (size_t s = 1; s < inside.size(); ++s) in = b.op(Op::And, {in, inside[s]});
        own = b.op(Op::Select, {in, own, b.scalar(whole)});
        K = member == 0 ? own : b.builtin("max", {K, own});
    }
    // (each tier: every table's loop says its members are within it)
    std::vector<ValueId> within(tiers, 0);
    for (size_t l = 0; l < hull_states.size(); ++l)
        for (size_t t = 0; t < tiers; ++t) {
            const ValueId in = b.compare(CompareKind::Gt, hull_states[l][t], b.scalar(0.5));
            within[t] = l == 0 ? in : b.op(Op::And, {within[t], in});
        }
    if (cells.which.empty()) {  // (the tiers, widest first: the narrowest that holds the values chooses)
        for (size_t t = tiers; t-- > 0;) K = b.op(Op::Select, {within[t], b.scalar(cells.K[t]), K});
    } else if (tiers > 0) {
        K = b.op(Op::Select, {within[0], K, b.scalar(whole)});
    }
    Global& g = m.globals[size_t(factor)];
    g.kind = Global::Kind::Prepared;
    g.comment = cells.which.empty()
                    ? fmt::format("the Lipschitz factor dividing its distance (the hit test multiplies it back): {:.4g} while its members' "
                                  "sliders are within the hull of their defaults, {}{:.4g} beyond", cells.at_defaults,
                                  cells.K.size() > 1 ? fmt::format("{:.4g} within {:g} of their ranges around it, ", cells.K[1], kHullWidening) : "",
                                  whole)
                    : fmt::format("the Lipschitz factor dividing its distance (the hit test multiplies it back): per cell of its sliders' "
                                  "values, {} cells ({:.4g} at their defaults){}", cells.K.size(), cells.at_defaults,
                                  cells.hull.empty() ? "" : ", while its members' sliders are within the hull of their defaults");
    g.value.clear();
    g.bounds = ValueBounds{};
    g.bounds.input = true;
    f.outputs.push_back({g.name, K});
    f.result = f.outputs[0].second;
}

// A group's bound member by member, where its parameters are constants: the group's own bound holds k ∈ [0, n − 1] and
// reads the hull of each per-member table, so a blend radius 0.1 in one cup and 0.6 in another bounds every cup's blend
// as if it could be either (six smooth-subtraction cups: 7 for the group, where each derives ≤ 1.005 alone; a trial's,
// stop 56). Each member's estimate with k fixed: `derived`, the largest of theirs (∞ where one has no useful bound, or
// where the members' analysis work would pass `work_allowed`, predicted from those taken: 16 members at most, so the
// first tells). With `sampled` (the group's K comes from samples), each member takes as many samples as a whole
// (the group's spread over its members: six ripple planes sampled 1.03 as a group, 1.58 the steepest alone, a hole at
// its centre; a trial's, stop 56), and `steepest`/`outside` are the steepest of theirs; else 16, which only word.
struct MemberBounds {
    double derived = kInf, steepest = 0, outside = 0;
};
MemberBounds member_bounds(const Module& m, int fn, const std::vector<Interval>& region, std::vector<std::vector<Interval>> others,
                           double ball, int group, uint64_t work_allowed, bool sampled) {
    const uint64_t start = analysis_work();
    MemberBounds b;
    double worst = 0, split_work = kSplitWorkPerEstimate;
    bool useful = true;
    for (int k = 0; k < group; ++k) {
        others.back() = {{double(k), double(k)}};
        const LipschitzEstimate e = estimate_lipschitz(m, fn, region, others, ball, sampled ? 1000 : 16, 128, true, &split_work, false, true);
        useful = useful && useful_bound(e.derived);
        if (!useful && !sampled) return b;
        worst = std::max(worst, e.derived);
        b.steepest = std::max(b.steepest, e.sampled);
        b.outside = std::max(b.outside, e.outside);
        const uint64_t spent = analysis_work() - start;
        if (k + 1 < group && double(spent) / double(k + 1) * double(group) > double(work_allowed)) return b;
    }
    if (useful) b.derived = worst;
    return b;
}

std::vector<RangeIssue> apply_lipschitz_bounds(Module& m, std::vector<std::string>* report, double* largest) {
    std::vector<RangeIssue> warnings;
    if (largest) *largest = 1;
    bool scaled = false;
    std::map<int, LipschitzEstimate> estimated;  // by object function: a shape's variants share one estimate
    const Clusters clusters = analysis_clusters(m);  // before the loop: it changes the functions it bounds
    std::map<int, LipschitzEstimate> analysed;       // by cluster: equal instances share one estimate
    // Uniform targets: the items analysed as one where the sliders' values are left out (their defaults), how many
    // analyses each holds, and the refined bound they share where more than one.
    const Clusters ranges = m.constant_parameters ? Clusters{} : analysis_clusters(m, false);
    std::vector<int> ranges_analysed(ranges.box.size(), 0);
    {
        std::vector<std::set<int>> seen(ranges.box.size());
        for (size_t fi = 0; fi < ranges.of.size() && fi < clusters.of.size(); ++fi)
            if (ranges.of[fi] >= 0 && clusters.of[fi] >= 0 && seen[size_t(ranges.of[fi])].insert(clusters.of[fi]).second)
                ++ranges_analysed[size_t(ranges.of[fi])];
    }
    std::map<int, RefinedBound> refined;
    // outside_bound's answers by object function and spheres: instances of one shape with one `bound` are one
    // check (1,536 evaluations each), not one per instance (1,000 moving spheres: 1,000 checks).
    struct Outside {
        std::vector<double> at;
        double d = 0;
        int member = 0;
    };
    std::unordered_map<std::string, Outside> outside;  // by analysis_key and the spheres (the box is not used)
    // Case splitting for the items whose derived bound is applied (a declared one only words a warning).
    double split_work = kSplitWorkPerModule;
    std::set<std::string> trusted_checked;  // the shapes saying `# exact` or `# bound` whose samples were checked
    std::map<int, std::optional<SliderCells>> cut;  // by cluster: the cells of the sliders (uniform targets)
    long cell_budget = kMaxCellEstimates;
    uint64_t cell_work = kCellWorkPerModule;
    size_t cell_items = 0;
    std::set<int> factor_done;  // the factor globals set (a constant) or prepared (per cell of the sliders)
    for (size_t fi = 0; fi < m.functions.size(); ++fi) {
        LipschitzSpec spec = m.functions[fi].lipschitz;
        if (spec.object_fn < 0 || fi >= clusters.of.size()) continue;
        const int cluster = clusters.of[fi];
        const std::vector<Interval>& region = clusters.box[size_t(cluster)];  // the box of the items analysed as one
        std::vector<std::vector<Interval>> others;
        if (spec.group > 0) others.push_back({{0, double(spec.group - 1)}});
        LipschitzEstimate e;
        size_t warned = warnings.size();
        bool repeat = estimated.count(spec.object_fn) > 0;  // a variant of an item already reported
        if (!spec.trusted || spec.declared > 0) {
            auto known = estimated.find(spec.object_fn);
            if (known == estimated.end()) {
                auto same = analysed.find(cluster);
                if (same == analysed.end()) {
                    double allowance = spec.declared > 0 ? 0 : std::min(kSplitWorkPerEstimate, split_work), given = allowance;
                    // A declared bound is applied as it is: the refinements only word its warning, where samples
                    // exceed it (the Christmas tree's declared 1.55: the pass's median 109 → 88 ms), and its jump search
                    // compares with the bound intervals give (a looser one: a jump must be larger to be proven).
                    const bool refine = analysed.size() < kMaxRefined;
                    LipschitzEstimate est;
                    const uint64_t before = analysis_work();
                    try {
                        // Where sliders are uniforms, items that differ only in their sliders' defaults (analysed apart:
                        // their samples are taken there) share one refined bound, over the hull of their boxes: six moving
                        // cups, each with its own blend k, were six estimates of 0.2 s, 90% of it the refinements, and the
                        // 17th to 24th, past kMaxRefined, derived 101 unrefined and were marched as if 1-Lipschitz (a
                        // trial's, stop 56).
                        RefinedBound* shared = nullptr;
                        if (spec.declared <= 0 && !m.constant_parameters && fi < ranges.of.size() && ranges.of[fi] >= 0 &&
                            ranges_analysed[size_t(ranges.of[fi])] >= 2) {
                            RefinedBound& rb = refined[ranges.of[fi]];
                            if (!rb.valid) {
                                double hull_work = kSplitWorkPerEstimate;
                                rb.force = true;
                                const LipschitzEstimate h = estimate_lipschitz(m, spec.object_fn, ranges.box[size_t(ranges.of[fi])], others,
                                                                               spec.ball, 16, 128, true, &hull_work, false, true, &rb);
                                rb.valid = true, rb.force = false, rb.derived = h.derived, rb.blend_steepest = h.blend_steepest;
                            }
                            shared = &rb;
                        }
                        est = estimate_lipschitz(m, spec.object_fn, region, others, spec.ball, 1000, 128,
                                                 refine && spec.declared <= 0, &allowance, refine, false, shared);
                        if (refine && spec.declared > 0 && est.sampled > spec.declared * (1 + 1e-3)) {
                            const double seen = est.sampled;  // (the check's samples: the warning quotes the steepest)
                            est = estimate_lipschitz(m, spec.object_fn, region, others, spec.ball, 1000, 128, true, &allowance);
                            est.sampled = std::max(est.sampled, seen);
                            est.derived = std::max(est.derived, est.sampled);
                        }
                    } catch (SizeLimit& limit) {
                        // A gradient past the size limit is the input's (code that unrolls too far), an error
                        // located where it grew, else at the instance (a new user's trial: it had no location).
                        if (!limit.span.valid()) limit.span = spec.where;
                        throw;
                    }
                    // (a group of constants: its members' bounds where the group's would be applied or is not useful)
                    if (spec.group >= 2 && spec.group <= 16 && m.constant_parameters && spec.declared <= 0 && refine &&
                        (decide(est).K > 1 + 1e-9 || !useful_bound(est.derived)) && cell_work > 0) {
                        const uint64_t allowed =
                            std::min(cell_work, std::max(uint64_t(kCellWorkRatio * double(analysis_work() - before)), kCellWorkFloor));
                        const uint64_t members_start = analysis_work();
                        const bool sampled = !useful_bound(est.derived);
                        const MemberBounds members =
                            member_bounds(m, spec.object_fn, region, others, spec.ball, spec.group, allowed, sampled);
                        cell_work -= std::min(cell_work, analysis_work() - members_start);
                        if (members.derived < est.derived) {
                            est.derived = members.derived;
                            est.per_member = true;
                        }
                        if (sampled) {
                            est.sampled = std::max(est.sampled, members.steepest);
                            est.outside = std::max(est.outside, members.outside);
                        }
                    }
                    est.work = analysis_work() - before;
                    same = analysed.emplace(cluster, std::move(est)).first;
                    split_work -= given - allowance;
                }
                known = estimated.emplace(spec.object_fn, same->second).first;
            }
            e = known->second;
        }
        // Where the sliders are uniforms and the K comes from the estimate: K per cell of the sliders' box (the warnings
        // below say what it is at the sliders' defaults and as they move).
        // Also where the whole has no useful bound (above 64, or none): a slider's wide range may be why (a frequency
        // f ∈ [0, 10⁴] was marched as if 1-Lipschitz, holes at its default 20, where Shadertoy derives 4.5).
        const SliderCells* cells = nullptr;
        std::string cells_skipped;  // (past the cells' budget: which limit, the report says)
        const bool useful = useful_bound(e.derived);
        const Decision decision = spec.declared > 0 || spec.trusted ? Decision{} : decide(e);
        const double decided = decision.K;
        if ((decided > 1 + 1e-9 || !useful) && !m.constant_parameters && spec.declared <= 0 && !spec.trusted && spec.factor_global >= 0 &&
            size_t(spec.factor_global) < m.globals.size()) {
            auto known = cut.find(cluster);
            if (known == cut.end()) {
                std::string over;
                known = cut.emplace(cluster, slider_cells(m, spec, region, others, decided, !useful, e.work, cell_budget,
                                                          cell_work, over)).first;
                cells_skipped = over;
            }
            if (known->second && cell_items < kMaxCellItems) cells = &*known->second;
            if (known->second && !cells && cells_skipped.empty()) cells_skipped = fmt::format("{} items with cells a scene", kMaxCellItems);
        }
        // "K = 194", or with cells "K = 46.5 at its sliders' defaults (10.2–194 as they move)".
        auto k_words = [&](double K) {
            if (!cells) return fmt::format("K = {:.3g}", K);
            if (cells->which.empty())
                return fmt::format("K = {:.3g} while its members' sliders stay within the span of their values ({}{} beyond it: the shader "
                                   "checks them)", cells->at_defaults,
                                   cells->K.size() > 1 ? fmt::format("{:.3g} within {:g} of their ranges around it, ", cells->K[1], kHullWidening) : "",
                                   K > 1 + 1e-9 ? fmt::format("{:.3g}", K) : std::string("as if 1-Lipschitz"));
            if (cells->window)
                return fmt::format("K = {:.3g} near its sliders' defaults ({} beyond a window around them: the shader picks it from their "
                                   "values)", cells->at_defaults, K > 1 + 1e-9 ? fmt::format("{:.3g}", K) : std::string("as if 1-Lipschitz"));
            return fmt::format("K = {:.3g} at its sliders' defaults ({:.3g}–{:.3g} as they move: the shader picks it from their values)",
                               cells->at_defaults, *std::min_element(cells->K.begin(), cells->K.end()),
                               *std::max_element(cells->K.begin(), cells->K.end()));
        };
        double applied = 1;
        std::string how;
        if (spec.declared > 0) {
            applied = spec.declared;
            how = "declared";
            // (outside the shape where those samples were taken, without a useful bound: metaballs declared 64 were
            // warned of their 8·10⁴ near a centre, inside, where no step starts; a trial's, stop 54)
            const bool inside_steeper = e.outside > 0 && e.sampled > 4 * e.outside;  // (as below, without a bound)
            const double steep = inside_steeper ? e.outside : e.sampled;
            if (steep > spec.declared * (1 + 1e-3))
                warnings.push_back({spec.where, fmt::format("shape '{}' declares '# lipschitz: {}', but its gradient reaches {:.3g} "
                                                            "here{} (iqc derives K ≤ {:.3g}): marching may step through its surface; "
                                                            "remove the pragma and iqc uses its own bound",
                                                            spec.shape, spec.declared, steep, inside_steeper ? " outside the shape" : "",
                                                            e.derived)});
        } else if (spec.trusted) {
            how = "exact or bound by its pragma";
            // Its samples, once per shape (16 at most): `# bound` on a twisted box, slope 3, was taken at its word
            // where a `# lipschitz: 1` would have been checked (a new user's trial, stop 39).
            if (trusted_checked.size() < 16 && trusted_checked.insert(spec.shape).second) {
                double steepest = 0;
                try {
                    steepest = sampled_gradient(m, spec.object_fn, region, others, spec.ball, 256);
                } catch (const SizeLimit&) {
                }
                if (steepest > 1 + 1e-3)
                    warnings.push_back({spec.where, fmt::format("shape '{}' says it is 1-Lipschitz (`# exact` or `# bound` in its module), "
                                                                "but its gradient reaches {:.3g} here: marching may step through its "
                                                                "surface; remove the pragma and iqc derives its own bound",
                                                                spec.shape, steepest)});
            }
        } else if (decision.kind == Decision::OneLipschitz) {
            how = "1-Lipschitz at every sample";
        } else if (decision.kind != Decision::Derived) {
            how = "no useful bound";
            // Without a bound worth marching by, the samples' steepest gradient with a margin: not proven (a
            // steeper spot between samples may still be stepped through), but 1 would skip what samples saw.
            // The samples outside the shape (D ≥ 0, where steps start) where any were taken: a field steeper inside, as
            // metaballs near their centres (10⁴), is marched by its slope outside (47). Only where the inside is far steeper (over 4×: a singular centre): elsewhere the steepest sample anywhere,
            // as samples outside may miss a steep shell the others met (a ball of slope 2 beside a cluster: 2.47 → 1.45,
            // before this rule).
            const bool apart = decision.apart;
            const double steep = decision.steep;
            if (decision.kind == Decision::Sampled) {  // (beyond kSampledCap, as useless as the bound)
                applied = decision.K;
                how = fmt::format("no useful bound: {:g} times the steepest sample{}, not proven", kSampledMargin, apart ? " outside the shape" : "");
            }
            // The derived bound itself, where the samples' margin would exceed it: proven, only slow (‖p‖/k² over
            // k ∈ [0.1, 3]: 100; 70(‖p‖ − 1): 70). Said so, not "may step through its surface" (a trial's, stop 54).
            if (applied > 1 && std::isfinite(e.derived) && applied == e.derived) {
                how = fmt::format("derived, above {:g}: slow to march", kUnbounded);
                warnings.push_back({spec.where, fmt::format("shape '{}' is marched with K = {:.3g}{}, the bound iqc derives for its gradient (its "
                                                            "samples reach {:.3g}): each step is 1/{:.3g} of its distance{}, so marching "
                                                            "takes many steps; if it need not be this steep, scale its distance down or "
                                                            "narrow the range of a slider it is steep at the end of",
                                                            spec.shape, applied,
                                                            cells ? fmt::format(" where its sliders make it steepest ({:.3g} at their defaults)", cells->at_defaults) : "",
                                                            e.sampled, applied, cells ? " there" : "")});
            } else {
                bool bounded = !spec.bounds.empty() || spec.ball > 0;
                std::string reason = !e.why.empty() ? (e.unevaluable ? e.why : "iqc cannot differentiate it (" + e.why + ")")
                                     : e.sampled <= 1 + 1e-3
                                         ? fmt::format("samples of its gradient reach only {:.3g}, but iqc cannot bound it where the instance "
                                                       "is marched; if it is 1-Lipschitz, say `# bound` in the module", e.sampled)
                                     : std::isfinite(e.derived)
                                         ? fmt::format("its gradient reaches {:.4g}{}, and the bound iqc derives where the instance is marched, "
                                                       "{:.3g}, would take too many steps", steep, apart ? fmt::format(" outside it ({:.4g} inside)", e.sampled) : "", e.derived)
                                         : fmt::format("its gradient reaches {:.4g}{} and iqc cannot bound it where the instance is marched",
                                                       steep, apart ? fmt::format(" outside it ({:.4g} inside)", e.sampled) : "");
                // (and where even the samples' K is too large to march by, it says that it marches with K = 1: two
                // new users' trials, stop 40, read the warning as if some K were applied)
                std::string marched = cells && cells->window && !(applied > 1)
                                          ? fmt::format("iqc marches it with {}, {:g} times the steepest gradient its samples reach "
                                                        "there, which is not a proven bound: ", k_words(applied), kSampledMargin)
                                      : cells && !(applied > 1) ? fmt::format("iqc marches it with {}, from each cell of the sliders' ranges "
                                                                              "(its derived bound, or {:g} times the steepest gradient its samples reach, "
                                                                              "which is not a proven bound; as if 1-Lipschitz where that is too steep): ",
                                                                              k_words(applied), kSampledMargin)
                                      : applied > 1 ? fmt::format("iqc marches it with {}, {:g} times the steepest gradient its samples "
                                                                "reach{}, which is not a proven bound: ", k_words(applied), kSampledMargin, apart ? " outside it" : "")
                                      : e.sampled > 1 + 1e-3 ? "iqc marches it as if it were 1-Lipschitz: "
                                                             : "";
                std::string fix = bounded ? "declare `# lipschitz: K` in the module (the instance's `bound` does not make its gradient boundable)"
                                          : "give the instance `bound = R` (a sphere around the shape) so iqc can bound its gradient there, "
                                            "or declare `# lipschitz: K`";
                // (where it has cells, a slider's range is what leaves it without a useful bound: a frequency f ∈ [0, 10⁴]
                // whose default 20 needs 4.5; a trial's)
                if (cells) fix = "narrow the range of a slider it is steep at the end of, " + fix;
                // (where cells were not taken for the budget, that they might have bounded it: a trial's, stop 56, saw
                // WebGL2 march as if 1-Lipschitz what Shadertoy bounds, and nothing said why)
                else if (!cells_skipped.empty())
                    fix = "narrow the range of a slider it is steep at the end of (iqc bounds it per cell of its sliders' values only within "
                          "its compile budget, past here: " + cells_skipped + "), " + fix;
                warnings.push_back({spec.where, fmt::format("shape '{}' {} ({}): {}marching may step through its surface; {}", spec.shape,
                                                            e.why.empty() && e.sampled <= 1 + 1e-3 ? "has no Lipschitz bound iqc can derive" : "is not 1-Lipschitz",
                                                            reason, marched, fix)});
            }
        } else {
            applied = decision.K;  // (the derived bound)
            how = e.at_defaults > 0 && e.at_defaults <= 1 + 1e-9 && e.sampled <= 1 + 1e-3
                      ? fmt::format("derived: within {:.4g} at the sliders' defaults", e.at_defaults)
                      : "derived";
            // Interval bounds can be loose (a twist's rotation is bounded component by component): say what
            // it costs, since steps shrink by the factor. 3×: beyond the slack of an honest bound.
            // (with cells, as at the sliders' defaults: the K and the samples of the cell that holds them)
            const double K = cells ? cells->at_defaults : e.derived, seen = cells ? cells->sampled_at_defaults : e.sampled;
            if (K > 3 * std::max(seen, 1.0))
                warnings.push_back({spec.where, fmt::format("shape '{}' is marched with steps divided by {}, the bound iqc "
                                                            "derives for its gradient, but samples of the gradient reach only "
                                                            "{:.3g}{}: marching is up to {:.0f}× slower than it may need to be; "
                                                            "declare `# lipschitz: K` only for a K you know (samples can miss a "
                                                            "thin steep part, and iqc warns only where its samples exceed K)",
                                                            spec.shape, k_words(e.derived), seen, cells ? " there" : "", K / std::max(seen, 1.0))});
        }
        // A group's warnings about its gradient at its steepest member, which they name (one K serves them all).
        if (spec.group >= 2 && spec.member_where.size() == size_t(spec.group) && warnings.size() > warned && !repeat) {
            int k = -1;
            try {
                k = steepest_member(m, spec.object_fn, region, others, spec.ball, spec.group, 64);
            } catch (const SizeLimit&) {
            }
            const std::string named = fmt::format("shape '{}'", spec.shape);
            for (size_t w = warned; k >= 0 && w < warnings.size(); ++w) {
                if (warnings[w].message.rfind(named, 0) != 0) continue;
                warnings[w].span = spec.member_where[size_t(k)];
                warnings[w].message.insert(named.size(), fmt::format(" (here at the steepest of a group of {} instances, which share one K)", spec.group));
            }
        }
        if (e.jump > 0)
            warnings.push_back({spec.where, fmt::format("shape '{}' has a discontinuous distance: it jumps by {:.3g} between two points "
                                                        "{:.3g} apart near ({:.3g}, {:.3g}, {:.3g}) in its own space (a floor, a mod, or a "
                                                        "repetition of a shape that crosses its cell), where no Lipschitz bound holds: "
                                                        "sphere tracing may step through the faces of the jump; keep a repeated shape "
                                                        "inside its cell (and symmetric in it), or march it with `march = \"fixed\"`",
                                                        spec.shape, e.jump, e.delta, e.jump_at[0], e.jump_at[1], e.jump_at[2])});
        if (!spec.bounds.empty()) {
            std::string spheres = clusters.key[size_t(cluster)];
            for (double r : spec.bounds) spheres.append(reinterpret_cast<const char*>(&r), sizeof r);
            auto found = outside.find(spheres);
            if (found == outside.end()) {
                Outside o;
                o.at = outside_bound(m, spec, o.d, o.member);
                found = outside.emplace(std::move(spheres), std::move(o)).first;
            }
            const std::vector<double>& at = found->second.at;
            double d = found->second.d;
            int member = found->second.member;
            // At the `bound` as written (the instance's type where the compiler derived it).
            Span bound_at = size_t(member) < spec.bound_where.size() && spec.bound_where[size_t(member)].valid()
                                ? spec.bound_where[size_t(member)]
                                : spec.where;
            if (!at.empty())
                warnings.push_back({bound_at, fmt::format("`bound = {:g}` is too small for shape '{}'{}: the shape reaches past its "
                                                            "sphere (its distance is {:.3g} at ({:.3g}, {:.3g}, {:.3g}), outside the sphere, "
                                                            "in its own space), so the bound clips it; give a larger `bound`",
                                                            spec.bounds[size_t(member)], spec.shape,
                                                            spec.group > 0 ? fmt::format(" (member {} of the group)", member) : "",
                                                            d, at[0], at[1], at[2])});
        }
        if (repeat) warnings.resize(warned);
        // (steps up to the steepest cell's K shorter: the step cap grows by it)
        const double steepest = cells ? std::max(applied, *std::max_element(cells->K.begin(), cells->K.end())) : applied;
        if (largest && steepest > *largest) *largest = steepest;
        if (applied > 1 + 1e-9 || cells) {
            const int g = spec.factor_global >= 0 && size_t(spec.factor_global) < m.globals.size() ? spec.factor_global : -1;
            // (an item's variants share its factor: the first to reach here decides whether it follows the sliders)
            if (g >= 0 && factor_done.insert(g).second) {
                if (cells) {
                    prepare_cell_factor(m, g, sliders_read(m, spec.object_fn), *cells, applied);
                    ++cell_items;
                } else {
                    m.globals[size_t(g)].value = {applied};
                }
            }
            if (g >= 0) scaled = true;
            const int by = g >= 0 && m.globals[size_t(g)].kind == Global::Kind::Prepared ? g : -1;
            if (!divide_object_calls(m, int(fi), spec.object_fn, applied, by)) divide_result(m, int(fi), applied, by);
            if (by < 0) cells = nullptr;  // (for the report)
        } else {
            cells = nullptr;
        }
        if (report && spec.trusted && spec.declared <= 0)
            report->push_back(fmt::format("{} ({}): not derived, {:.4g} applied ({})", spec.shape, m.functions[fi].glsl_name, applied, how));
        else if (report)
            report->push_back(fmt::format("{} ({}): K ≤ {:.4g} derived{}, {:.4g} sampled, {:.4g} applied ({}){}", spec.shape,
                                          m.functions[fi].glsl_name, e.derived,
                                          e.per_member ? fmt::format(" (its {} members' largest)", spec.group) : "", e.sampled, applied, how,
                                          e.jump > 0 ? fmt::format("; jumps by {:.3g} (discontinuous)", e.jump) : "") +
                              (cells && cells->which.empty()
                                   ? fmt::format("; by the members' sliders {:.4g} within the hull of their values, {}{:.4g} beyond it",
                                                 cells->at_defaults,
                                                 cells->K.size() > 1 ? fmt::format("{:.4g} within {:g} of their ranges around it, ", cells->K[1], kHullWidening) : "",
                                                 applied)
                               : cells && cells->window
                                   ? fmt::format("; by the sliders' values {:.4g} in a window around their defaults, {:.4g} outside it{}",
                                                 cells->at_defaults, applied, cells->hull.empty() ? "" : " or the members' hull")
                               : cells ? fmt::format("; by the sliders' values {:.4g} at their defaults, {:.4g}–{:.4g} over {} cells{}", cells->at_defaults,
                                                   *std::min_element(cells->K.begin(), cells->K.end()),
                                                   *std::max_element(cells->K.begin(), cells->K.end()), cells->K.size(),
                                                   cells->estimated < cells->K.size()
                                                       ? fmt::format(" ({} estimated, nearest the defaults; the others keep the whole's K: past the "
                                                                     "cells' budget ({}))", cells->estimated, cells_skipped)
                                                       : "") + (cells->hull.empty() ? "" : fmt::format(" within the members' hull, {:.4g} beyond it", applied))
                                     : !cells_skipped.empty() ? "; not by the sliders' values: past the cells' budget (" + cells_skipped + ")"
                                                              : ""));
        m.functions[fi].lipschitz.object_fn = -1;  // done
    }
    // The runtime's hit test reads the factors back (a distance divided by K is a step, not a proximity):
    // iqc_lipschitz becomes an entry point only where some instance is divided.
    if (int f = m.find(names::kLipschitz); scaled && f >= 0) m.functions[size_t(f)].entry = true;
    // A factor that stayed 1 is the number 1 where it is read (a blend multiplies its members' distances by their
    // factors and divides by the largest: x·1, max(1, 1) and x/1 fold away).
    std::set<int> ones;
    for (const Function& f : m.functions)
        if (int g = f.lipschitz.factor_global; g >= 0 && size_t(g) < m.globals.size() && m.globals[size_t(g)].value == std::vector<double>{1})
            ones.insert(g);
    if (!ones.empty())
        for (Function& f : m.functions)
            for (Instr& in : f.body)
                if (in.op == Op::Global && ones.count(in.aux) && in.type.is_scalar()) {
                    in.op = Op::Const;
                    in.aux = 0;
                    in.data = {1};
                }
    return warnings;
}

}  // namespace iqc::ir
