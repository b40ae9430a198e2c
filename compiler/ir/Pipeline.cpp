#include "ir/Pipeline.h"

#include <chrono>
#include <fmt/format.h>
#include <functional>

#include "ir/passes/BindArrays.h"
#include "ir/passes/CSE.h"
#include "ir/passes/DCE.h"
#include "ir/passes/Differentiate.h"
#include "ir/passes/Fold.h"
#include "ir/passes/Hoist.h"
#include "ir/passes/Inline.h"
#include "ir/passes/IntervalExtension.h"
#include "ir/passes/Lipschitz.h"
#include "ir/passes/IfConvert.h"
#include "ir/passes/MergeCalls.h"
#include "ir/passes/Stable.h"
#include "ir/passes/Tables.h"
#include "source/Internal.h"

namespace iqc::ir {

namespace {

void fold_all(Module& m) {
    for (auto& f : m.functions) fold_constants(m, f);
}
void cse_all(Module& m) {
    for (auto& f : m.functions) eliminate_common_subexpressions(f);
}

// iqc_gradient from iqc_distance_of, when the scene asks for analytic normals (it then has both names: the
// scene lowering adds iqc_gradient as a placeholder that this pass fills).
void gradient(Module& m, PipelineResult& r) {
    int dist = m.find(names::kDistanceOf), grad = m.find(names::kGradient);
    if (dist < 0 || grad < 0) return;
    std::string why;
    std::vector<std::pair<Span, std::string>> fallbacks;
    int g = differentiate(m, dist, 0, names::kGradient, &why, &fallbacks);
    if (g < 0) internal_error("gradient: the scene's distance has no derivative rule (" + why + ")");
    for (auto& [span, reason] : fallbacks)
        r.warnings.push_back({span, fmt::format("no analytic normal here ({}): the normals of the shapes that use it come "
                                                "from tetrahedron differences", reason)});
    Function made = std::move(m.functions[size_t(g)]);
    m.functions.pop_back();
    made.entry = m.functions[size_t(grad)].entry;
    if (made.body[made.result].name.empty()) made.body[made.result].name = "g";
    made.glsl_name = m.functions[size_t(grad)].glsl_name;
    m.functions[size_t(grad)] = std::move(made);
}

// Reorders f's body as a depth-first post-order from its result (operands in order; parameters first): the
// same function whatever order a builder appended the instructions in. C++ leaves the order in which a call's
// arguments are evaluated unspecified, and the interval extension's helpers append instructions from within
// argument lists: gcc and clang built it in different orders (different IR text, different GLSL names).
// Instructions the result does not reach are dropped.
void canonical_order(Function& f) {
    std::vector<char> placed(f.body.size(), 0);
    std::vector<ValueId> order;
    for (size_t i = 0; i < f.body.size(); ++i)
        if (f.body[i].op == Op::Param) {
            order.push_back(ValueId(i));
            placed[i] = 1;
        }
    std::vector<ValueId> roots = {f.result};
    for (const auto& [name, v] : f.outputs) roots.push_back(v);
    for (ValueId root : roots) {
        std::vector<std::pair<ValueId, size_t>> stack = {{root, 0}};
        while (!stack.empty()) {
            auto& [v, next] = stack.back();
            if (placed[v]) {
                stack.pop_back();
                continue;
            }
            if (next < f.body[v].args.size()) {
                ValueId a = f.body[v].args[next++];
                if (!placed[a]) stack.push_back({a, 0});
                continue;
            }
            placed[v] = 1;
            order.push_back(v);
            stack.pop_back();
        }
    }
    std::vector<ValueId> index(f.body.size(), 0);
    std::vector<Instr> body;
    for (ValueId v : order) {
        index[v] = ValueId(body.size());
        Instr in = std::move(f.body[v]);
        for (ValueId& a : in.args) a = index[a];
        body.push_back(std::move(in));
    }
    f.body = std::move(body);
    f.result = index[f.result];
    for (auto& [name, v] : f.outputs) v = index[v];
}

// iqc_segment_gain(lo, hi, rd) and iqc_segment_clear(lo, hi) for segment tracing (Galin et al. 2020), when
// the scene asks for it (the scene lowering adds placeholders returning 1 and -1e30).
//
// Gain: per instance k, the interval extension of the gradient of its distance g_k (as the march steps by it:
// divided by its Lipschitz factor) over the box gives a bound λ_k of |∇g_k · rd| at every point of the segment
// the box holds; while g_k(t) ≥ F(t), the scene's distance, g_k(t + u) ≥ F(t) - λ_k u > 0 for u < F(t)/λ_k.
// So the step may be F(t)·min_k 1/λ_k. λ_k is widened by 0.1% and 1e-6 (32-bit rounding); the gain is at most
// 10⁴ and at least 1 (a bound no better than the factor the distance was divided by gains nothing). The
// gradient knows nothing of jumps (a floor's derivative is 0: a voxelised sphere was skipped whole): where the
// distance's own extension finds an operation that may jump within the box (IntervalCode::continuous), that
// instance gains nothing.
//
// Clear: the least lower bound of the instances' distances over the box (Mitchell 1990): above the hit
// tolerance, nothing in the segment can be hit and the march takes all of it.
//
// An instance whose own box (Module::instance_boxes) the segment's box misses is skipped by both. Scenes the
// pass cannot bound instance by instance (groups of instances, more than kMaxItems, a gradient without an
// interval rule) keep the placeholders: the march steps as sphere tracing does, and a warning says why.
void segment(Module& m, PipelineResult& r) {
    // Each step evaluates every instance's bounds (those whose box the segment meets): with 6 instances the
    // frame took 3x sphere tracing's on llvmpipe, with 12 about 6x, for half the evaluations (a new user's
    // trial); with 4 (bench/few_shapes) 1.14x.
    constexpr int kMaxItems = 4;
    int dist = m.find(names::kDistanceOf), seg = m.find(names::kSegmentGain), clear = m.find(names::kSegmentClear);
    if (dist < 0 || seg < 0 || clear < 0) return;
    // Refused: the placeholders are no longer entries (dead code removes them) and the march is sphere tracing
    // (Compile leaves MARCH_SEGMENT out: no bound is evaluated or counted).
    auto refuse = [&](const std::string& why) {
        r.segment_refused = why;
        m.functions[size_t(seg)].entry = false;
        m.functions[size_t(clear)].entry = false;
    };
    // The instances: the cases of iqc_distance_of's dispatch on the id.
    std::vector<long long> ids;
    const Function& df = m.functions[size_t(dist)];
    const Instr& res = df.body[df.result];
    if (res.op == Op::Switch) {
        for (int c = 0; c < switch_cases(res); ++c) {
            long long lo = (long long)res.data[size_t(2 * c)], hi = (long long)res.data[size_t(2 * c + 1)];
            if (hi - lo != 1) return refuse(fmt::format("a group of instances (bounds are derived per instance, for scenes of "
                                                        "up to {} instances, none in a group)", kMaxItems));
            ids.push_back(lo);
        }
    } else {
        ids.push_back(0);
    }
    if (int(ids.size()) > kMaxItems)
        return refuse(fmt::format("{} instances (each step evaluates the bounds of every instance: at most {}, beyond which "
                                  "they cost more than they save)", ids.size(), kMaxItems));
    // Whether the box [lo, hi] meets instance id's own box (Module::instance_boxes), as a condition; -1 where
    // the instance has none. Outside its box an instance's nearness exceeds the scene box's level (ten hit
    // tolerances at least): it can be neither hit nor approached within the segment, so its bounds are not
    // computed there (a lazy choice: llvmpipe skips the code where no pixel of a group needs it).
    auto meets_box = [&](Builder& bb, long long id, ValueId lo_, ValueId hi_) -> ValueId {
        auto it = m.instance_boxes.find(id);
        if (it == m.instance_boxes.end()) return ValueId(-1);
        const auto& x = it->second;
        ValueId box_lo = bb.constant(Type::vector(3), {x[0], x[1], x[2]}), box_hi = bb.constant(Type::vector(3), {x[3], x[4], x[5]});
        ValueId all = ValueId(-1);
        for (int a = 0; a < 3; ++a) {
            ValueId c = bb.op(Op::And, {bb.compare(CompareKind::Le, bb.op(Op::Extract, {lo_}, a), bb.op(Op::Extract, {box_hi}, a)),
                                        bb.compare(CompareKind::Ge, bb.op(Op::Extract, {hi_}, a), bb.op(Op::Extract, {box_lo}, a))});
            all = all == ValueId(-1) ? c : bb.op(Op::And, {all, c});
        }
        return all;
    };
    size_t before = m.functions.size();
    std::string why;
    int g = differentiate(m, dist, 0, "iqc_segment_gradient", &why);
    if (g < 0) {
        m.functions.resize(before);
        return refuse("no derivative of the scene's distance (" + why + ")");
    }
    // Constants folded first: the extension knows the sign of a constant factor (Jacobians of linear maps
    // are mostly 0 and 1) and writes less code for it.
    fold_constants(m, m.functions[size_t(g)]);
    eliminate_common_subexpressions(m.functions[size_t(g)]);
    Function made;
    made.name = names::kSegmentGain;
    made.glsl_name = m.functions[size_t(seg)].glsl_name;
    made.entry = true;
    Builder b(m, made);
    ValueId lo = b.param("lo", Type::vector(3)), hi = b.param("hi", Type::vector(3)), rd = b.param("rd", Type::vector(3));
    ValueId gain = b.scalar(1e4);
    for (long long id : ids) {
        IntervalCode ic = emit_interval_extension(b, m, g, 0, lo, hi, {lo, b.integer(id)});
        if (!ic.ok) {
            m.functions.resize(before);
            return refuse("no interval rule for an instance's gradient (" + ic.why + ")");
        }
        // The gradient says nothing of jumps (⌊x⌋'s derivative is 0): where the distance may jump within the
        // box, no gain (a plain step, as sphere tracing takes).
        IntervalCode value = emit_interval_extension(b, m, dist, 0, lo, hi, {lo, b.integer(id)});
        // ∇g · rd over the box: each component's product with rd's (exact) component, summed.
        ValueId a = b.op(Op::Hadamard, {rd, ic.lo}), c = b.op(Op::Hadamard, {rd, ic.hi});
        ValueId one = b.constant(Type::vector(3), {1, 1, 1});
        ValueId d_lo = b.op(Op::Dot, {b.builtin("min", {a, c}), one}), d_hi = b.op(Op::Dot, {b.builtin("max", {a, c}), one});
        ValueId lam = b.builtin("max", {b.op(Op::Neg, {d_lo}), d_hi});
        lam = b.op(Op::Add, {b.op(Op::Mul, {lam, b.scalar(1.001)}), b.scalar(1e-6)});
        // NaN or ≥ 1: no gain (a comparison with NaN is false).
        ValueId useful = b.compare(CompareKind::Lt, lam, b.scalar(1));
        if (!value.ok) useful = b.constant(Type::boolean(), {0});
        else if (value.continuous != ValueId(-1)) useful = b.op(Op::And, {useful, value.continuous});
        ValueId k = b.op(Op::Select, {useful, b.op(Op::Div, {b.scalar(1), b.builtin("max", {lam, b.scalar(1e-4)})}), b.scalar(1)});
        if (ValueId near = meets_box(b, id, lo, hi); near != ValueId(-1)) k = b.if_(near, k, b.scalar(1e4));
        gain = b.builtin("min", {gain, k});
    }
    made.result = b.named(gain, "gain");
    // iqc_segment_clear: the smallest lower bound of the instances' distances over the box (the interval
    // extension of the distance itself, Mitchell 1990: where it is above the hit tolerance, no point of the
    // segment can be hit, and the march takes the whole segment).
    Function low;
    low.name = names::kSegmentClear;
    low.glsl_name = m.functions[size_t(clear)].glsl_name;
    low.entry = true;
    Builder lb(m, low);
    ValueId llo = lb.param("lo", Type::vector(3)), lhi = lb.param("hi", Type::vector(3));
    ValueId least = lb.scalar(1e30);
    for (long long id : ids) {
        IntervalCode ic = emit_interval_extension(lb, m, dist, 0, llo, lhi, {llo, lb.integer(id)});
        if (!ic.ok) {  // a distance with no rule (the gradient had one): nothing is known clear
            least = lb.scalar(-1e30);
            break;
        }
        ValueId low_i = ic.lo;
        if (ValueId near = meets_box(lb, id, llo, lhi); near != ValueId(-1)) low_i = lb.if_(near, low_i, lb.scalar(1e30));
        least = lb.builtin("min", {least, low_i});
    }
    low.result = lb.named(least, "least");
    m.functions.resize(before);
    for (Function* f : {&made, &low}) {
        fold_constants(m, *f);
        eliminate_common_subexpressions(*f);
        eliminate_dead_code(*f);  // each instance's extension also extends the other instances' (untaken) arms
        canonical_order(*f);
    }
    m.functions[size_t(seg)] = std::move(made);
    m.functions[size_t(clear)] = std::move(low);
}

// The runtime calls iqc_distance_of and iqc_gradient only with the id of an instance (a hit's, from iqc_scene,
// or a glowing instance's): a dispatch on that id with a single case (a scene of one shape, or of one group of
// instances) takes the case without testing the id. The test and its fall-back value cost llvmpipe's driver
// compile 2-3% on bench/fractal.iq and bench/instances_100.iq, and every normal tap a branch. Returns how many
// dispatches were taken out. Runs after the segment pass, which reads the dispatch's cases.
int exhaustive_dispatch(Module& m) {
    int changed = 0;
    for (const char* name : {names::kDistanceOf, names::kGradient}) {
        int fi = m.find(name);
        if (fi < 0) continue;
        Function& f = m.functions[size_t(fi)];
        const Instr& res = f.body[f.result];
        if (res.op != Op::Switch || switch_cases(res) != 1) continue;
        f.result = res.args[2];
        ++changed;
    }
    return changed;
}

struct Pass {
    PassInfo info;
    std::function<void(Module&, const PipelineOptions&, PipelineResult&)> run;
};

const std::vector<Pass>& passes() {
    static const std::vector<Pass> list = {
        {{"stable", "stable rewrites of forms that fail in 32-bit floats: log-sum-exp, hypot, 1 - cos"},
         [](Module& m, const PipelineOptions&, PipelineResult& r) {
             for (auto& w : rewrite_unstable_forms(m)) r.rewrites.push_back(std::move(w));
         }},
        {{"lipschitz", "each shape's Lipschitz bound, derived from its gradient; distances divided by it"},
         [](Module& m, const PipelineOptions&, PipelineResult& r) {
             for (auto& w : apply_lipschitz_bounds(m, &r.lipschitz, &r.lipschitz_largest)) r.warnings.push_back(std::move(w));
         }},
        {{"inline", "inline the scene's building blocks into the scene functions"},
         [](Module& m, const PipelineOptions&, PipelineResult&) { inline_marked(m); }},
        {{"tables", "compile-time tables on a lattice become arithmetic on the index"},
         [](Module& m, const PipelineOptions&, PipelineResult&) { compress_tables(m); }},
        {{"fold", "constant folding and algebraic identities"},
         [](Module& m, const PipelineOptions&, PipelineResult&) { fold_all(m); }},
        {{"cse", "common subexpression elimination"},
         [](Module& m, const PipelineOptions&, PipelineResult&) { cse_all(m); }},
        {{"ranges", "range analysis: guards and slider warnings"},
         [](Module& m, const PipelineOptions& o, PipelineResult& r) { r.range_issues = analyze_ranges(m, o.guard_ranges); }},
        {{"gradient", "analytic normals: forward-mode differentiation of the scene distance"},
         [](Module& m, const PipelineOptions&, PipelineResult& r) { gradient(m, r); }},
        {{"segment", "segment tracing: local Lipschitz bounds by interval arithmetic on each instance's gradient"},
         [](Module& m, const PipelineOptions&, PipelineResult& r) { segment(m, r); }},
        {{"calls", "calls to one function from several cases of a switch: one call on switched arguments"},
         [](Module& m, const PipelineOptions&, PipelineResult&) { merge_switch_calls(m); }},
        {{"dispatch", "an instance's distance and gradient with a single case: no test of the id (the runtime passes only instances' ids)"},
         [](Module& m, const PipelineOptions&, PipelineResult&) { exhaustive_dispatch(m); }},
        {{"select", "if-conversion: a call's switched argument whose arms are cheap and safe to compute becomes selects"},
         [](Module& m, const PipelineOptions&, PipelineResult&) { convert_cheap_choices(m); }},
        {{"arrays", "array arguments: a call that passes a global array whole (a sequence parameter) calls a copy of its callee that reads the global in place (uniform targets)"},
         [](Module& m, const PipelineOptions&, PipelineResult&) { bind_array_arguments(m); }},
        {{"hoist", "values holding a loop that read nothing of the query point (a ∑ over a sequence): computed once per pixel by iqc_prepare"},
         [](Module& m, const PipelineOptions&, PipelineResult&) { hoist_pixel_invariants(m); }},
        {{"simplify", "fold and CSE again"},
         [](Module& m, const PipelineOptions&, PipelineResult&) {
             fold_all(m);
             cse_all(m);
         }},
        {{"dce", "dead code: instructions, then unreachable functions and globals"},
         [](Module& m, const PipelineOptions&, PipelineResult&) { eliminate_dead_code(m); }},
    };
    return list;
}

void check(const Module& m, const char* when) {
    std::string fault = verify(m);
    if (!fault.empty()) internal_error(fmt::format("invalid IR {}: {}", when, fault));
}

}  // namespace

const std::vector<PassInfo>& pipeline_passes() {
    static const std::vector<PassInfo> infos = [] {
        std::vector<PassInfo> v;
        for (const auto& p : passes()) v.push_back(p.info);
        return v;
    }();
    return infos;
}

bool is_pass_name(const std::string& name) {
    if (name == "lower") return true;
    for (const auto& p : passes())
        if (name == p.info.name) return true;
    return false;
}

bool run_pass(const std::string& name, Module& m, const PipelineOptions& o, PipelineResult& r) {
    for (const auto& p : passes())
        if (name == p.info.name) {
            p.run(m, o, r);
            return true;
        }
    return false;
}

PipelineResult run_pipeline(Module& m, const PipelineOptions& o) {
    PipelineResult r;
    if (o.verify_each) check(m, "after lowering");
    if (o.dump_after == "lower") r.dump = print(m);
    for (const auto& p : passes()) {
        auto t0 = std::chrono::steady_clock::now();
        if (o.inject_fault == p.info.name) internal_error(fmt::format("{}: injected fault (--inject-fault)", p.info.name));
        p.run(m, o, r);
        if (o.verify_each) check(m, fmt::format("after the {} pass", p.info.name).c_str());
        if (o.dump_after == p.info.name) r.dump = print(m);
        r.pass_ms.push_back({p.info.name, std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count()});
    }
    if (!o.verify_each) check(m, "after the pipeline");
    return r;
}

}  // namespace iqc::ir
