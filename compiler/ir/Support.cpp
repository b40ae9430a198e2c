#include "ir/Support.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <map>
#include <queue>

#include "ir/CaseSplit.h"
#include "ir/ConvexBound.h"
#include "ir/passes/CSE.h"
#include "ir/passes/Fold.h"
#include "ir/passes/Inline.h"
#include "sema/Builtins.h"

namespace iqc::ir {

namespace {

struct Box {
    std::array<double, 3> lo, hi;
};

// ---- rotations of the query point in a coordinate plane ----
//
// A shape that rotates its point in a coordinate plane (Quilez's twist and bend, a rotation about an axis by a
// parameter, a constant angle) mixes two axes: over a half-space x ≥ c, with z unbounded, c·x - s·z is
// unbounded, so interval arithmetic can close no side of either axis. What it loses is the rotation's
// invariant: the rotated pair (u, w) has the norm of (p_a, p_b) (cos² + sin² = 1, whatever the angle depends
// on). support_box therefore also analyses the shape with u and w as the free coordinates of the box (p_a and
// p_b unbounded wherever else they appear): the box it finds for (u, w) bounds ‖(p_a, p_b)‖ = ‖(u, w)‖. A
// constant invertible 2×2 map of the pair works the same way, through its inverse, as does a shear: one mixed
// form paired with an axis the shape reads as it is (u = p_1 + 0.3·p_2, w = p_2).

// A coefficient of a linear form: a constant, or ±cos θ / ±sin θ of one value θ.
struct Coefficient {
    enum Kind { Constant, Cos, Sin } kind = Constant;
    double value = 0;  // Constant: the value; Cos and Sin: the sign, ±1
    ValueId angle = 0;
};

// Value v as a coefficient (a constant, ±cos θ, ±sin θ), or nothing.
std::optional<Coefficient> coefficient(const Function& g, ValueId v, double sign, int depth = 0) {
    const Instr& in = g.body[v];
    if (depth > 8 || !in.type.is_scalar()) return std::nullopt;
    if (in.op == Op::Const && in.data.size() == 1) return Coefficient{Coefficient::Constant, sign * in.data[0], 0};
    if (in.op == Op::Copy) return coefficient(g, in.args[0], sign, depth + 1);
    if (in.op == Op::Neg) return coefficient(g, in.args[0], -sign, depth + 1);
    if (in.op == Op::Builtin && in.args.size() == 1) {
        const std::string& n = builtin(in.aux).name;
        if (n == "cos") return Coefficient{Coefficient::Cos, sign, in.args[0]};
        if (n == "sin") return Coefficient{Coefficient::Sin, sign, in.args[0]};
    }
    return std::nullopt;
}

// Which component of the query point value v is (an Extract of the query parameter), or -1.
int query_axis(const Function& g, int query, ValueId v) {
    const Instr& in = g.body[v];
    if (in.op == Op::Copy) return query_axis(g, query, in.args[0]);
    if (in.op != Op::Extract || in.aux < 0 || in.aux > 2) return -1;
    const Instr& p = g.body[in.args[0]];
    return p.op == Op::Param && p.aux == query && p.type.is_vector() && p.type.rows == 3 ? in.aux : -1;
}

// A linear form of the query point's components: value = Σ terms[axis] · p_axis.
using LinearForm = std::map<int, Coefficient>;

bool add_term(LinearForm& f, int axis, Coefficient c) {
    if (axis < 0) return false;
    auto it = f.find(axis);
    if (it == f.end()) {
        if (c.kind != Coefficient::Constant || c.value != 0) f[axis] = c;
        return true;
    }
    if (it->second.kind != Coefficient::Constant || c.kind != Coefficient::Constant) return false;
    it->second.value += c.value;
    if (it->second.value == 0) f.erase(it);
    return true;
}

// Component `comp` of vector value v (or scalar v, comp -1) as a linear form of the query's components,
// times `sign`, added to f; false when it is not one (an offset, a product of two coordinates, ...).
bool linear_form(const Function& g, int query, ValueId v, int comp, double sign, LinearForm& f, int depth = 0) {
    const Instr& in = g.body[v];
    if (depth > 16) return false;
    if (comp < 0) {
        if (!in.type.is_scalar()) return false;
        if (int a = query_axis(g, query, v); a >= 0) return add_term(f, a, {Coefficient::Constant, sign, 0});
        switch (in.op) {
            case Op::Copy: return linear_form(g, query, in.args[0], -1, sign, f, depth + 1);
            case Op::Neg: return linear_form(g, query, in.args[0], -1, -sign, f, depth + 1);
            case Op::Add:
            case Op::Sub:
                return linear_form(g, query, in.args[0], -1, sign, f, depth + 1) &&
                       linear_form(g, query, in.args[1], -1, in.op == Op::Sub ? -sign : sign, f, depth + 1);
            case Op::Mul: {
                if (!g.body[in.args[0]].type.is_scalar() || !g.body[in.args[1]].type.is_scalar()) return false;
                for (int k : {0, 1})
                    if (auto c = coefficient(g, in.args[size_t(k)], sign)) {
                        int a = query_axis(g, query, in.args[size_t(1 - k)]);
                        if (a >= 0) return add_term(f, a, *c);
                    }
                // A constant times a linear form of constant coefficients (a rotation by a constant angle of
                // a point already rotated by one): the form scaled. Not of cos θ and sin θ: their scaled
                // values would pass for a rotation's.
                for (int k : {0, 1}) {
                    const Instr& c = g.body[in.args[size_t(k)]];
                    if (c.op != Op::Const || c.data.size() != 1) continue;
                    LinearForm sub;
                    if (!linear_form(g, query, in.args[size_t(1 - k)], -1, 1, sub, depth + 1)) return false;
                    for (const auto& [axis, t] : sub)
                        if (t.kind != Coefficient::Constant || !add_term(f, axis, {Coefficient::Constant, sign * c.data[0] * t.value, 0}))
                            return false;
                    return true;
                }
                return false;
            }
            case Op::Extract: {
                const Instr& src = g.body[in.args[0]];
                return src.type.is_vector() && linear_form(g, query, in.args[0], in.aux, sign, f, depth + 1);
            }
            default: return false;
        }
    }
    // A vector's component: of a Construct of scalars, or of a matrix (a Construct of scalars, or a constant)
    // times a vector (a Construct of scalars, or the query point itself).
    if (in.op == Op::Copy) return linear_form(g, query, in.args[0], comp, sign, f, depth + 1);
    if (in.op == Op::Construct) {
        if (size_t(comp) >= in.args.size()) return false;
        for (ValueId a : in.args)
            if (!g.body[a].type.is_scalar()) return false;
        return linear_form(g, query, in.args[size_t(comp)], -1, sign, f, depth + 1);
    }
    if (in.op != Op::Mul) return false;
    const Instr& M = g.body[in.args[0]];
    const Instr& x = g.body[in.args[1]];
    if (!M.type.is_matrix() || !x.type.is_vector() || M.type.cols != x.type.rows || comp >= M.type.rows) return false;
    const int cols = M.type.cols;
    for (int j = 0; j < cols; ++j) {
        size_t e = size_t(comp * cols + j);
        std::optional<Coefficient> c;
        if (M.op == Op::Const && M.data.size() == size_t(M.type.rows * cols)) c = Coefficient{Coefficient::Constant, sign * M.data[e], 0};
        else if (M.op == Op::Construct && M.args.size() == size_t(M.type.rows * cols)) c = coefficient(g, M.args[e], sign);
        if (!c) return false;
        if (c->kind == Coefficient::Constant && c->value == 0) continue;
        int a = -1;
        if (x.op == Op::Param && x.aux == query && x.type.rows == 3) a = j;
        else if (x.op == Op::Construct && x.args.size() == size_t(cols)) a = query_axis(g, query, x.args[size_t(j)]);
        if (!add_term(f, a, *c)) return false;
    }
    return true;
}

// One rotated (or linearly mixed) pair: values u and w (component comp of a vector value; -1: scalars) are
// the query's axes a and b through the 2×2 map M = [[α, β], [γ, δ]]: an orthogonal one of cos and sin of one
// angle (`orthogonal`), or an invertible constant one (`inverse` holds M⁻¹, row-major).
struct PlanePair {
    ValueId u = 0, w = 0;
    int u_comp = -1, w_comp = -1;
    int a = 0, b = 1;
    bool orthogonal = false;
    std::array<double, 4> inverse{};
};

std::optional<PlanePair> plane_pair(const LinearForm& fu, const LinearForm& fw) {
    if (fu.size() != 2 || fw.size() != 2 || fu.begin()->first != fw.begin()->first || fu.rbegin()->first != fw.rbegin()->first)
        return std::nullopt;
    PlanePair p;
    p.a = fu.begin()->first;
    p.b = fu.rbegin()->first;
    const Coefficient &al = fu.at(p.a), &be = fu.at(p.b), &ga = fw.at(p.a), &de = fw.at(p.b);
    using K = Coefficient::Kind;
    if (al.kind == K::Constant && be.kind == K::Constant && ga.kind == K::Constant && de.kind == K::Constant) {
        double det = al.value * de.value - be.value * ga.value;
        double scale = std::max({std::fabs(al.value), std::fabs(be.value), std::fabs(ga.value), std::fabs(de.value)});
        if (!(std::fabs(det) > 1e-9 * scale * scale) || !std::isfinite(det)) return std::nullopt;
        p.inverse = {de.value / det, -be.value / det, -ga.value / det, al.value / det};
        return p;
    }
    // cos θ and sin θ of one θ: [[±c, ±s], [±s, ±c]] (or the sines first) is orthogonal when its rows are.
    bool trig = al.kind != K::Constant && be.kind != K::Constant && ga.kind != K::Constant && de.kind != K::Constant;
    if (!trig || al.angle != be.angle || al.angle != ga.angle || al.angle != de.angle) return std::nullopt;
    if (al.kind != de.kind || be.kind != ga.kind || al.kind == be.kind) return std::nullopt;
    if (al.value * ga.value != -be.value * de.value) return std::nullopt;
    p.orthogonal = true;
    return p;
}

// The rotated pairs of the query's components in g (at most one per plane: the first found). A plane with no
// pair of two mixed forms may pair one mixed form with one of its axes read as it is: a shear such as
// (p_1 + 0.3·p_2, p_2, p_3), whose u = p_1 + 0.3·p_2 and w = p_2 are the map [[1, 0.3], [0, 1]].
std::vector<PlanePair> plane_pairs(const Function& g, int query) {
    struct Candidate {
        ValueId v;
        int comp;
        LinearForm f;
    };
    std::vector<Candidate> c, single;  // forms of two axes; an axis times a constant
    auto keep = [&](ValueId v, int comp, LinearForm f) {
        if (f.size() == 2) c.push_back({v, comp, std::move(f)});
        else if (f.size() == 1 && f.begin()->second.kind == Coefficient::Constant) single.push_back({v, comp, std::move(f)});
    };
    for (size_t i = 0; i < g.body.size(); ++i) {
        const Instr& in = g.body[i];
        if (in.type.is_scalar() && (in.op == Op::Add || in.op == Op::Sub || query_axis(g, query, ValueId(i)) >= 0)) {
            LinearForm f;
            if (linear_form(g, query, ValueId(i), -1, 1, f)) keep(ValueId(i), -1, std::move(f));
        } else if (in.op == Op::Mul && in.type.is_vector() && in.type.rows <= 4) {
            for (int k = 0; k < in.type.rows; ++k) {
                LinearForm f;
                if (linear_form(g, query, ValueId(i), k, 1, f)) keep(ValueId(i), k, std::move(f));
            }
        }
    }
    std::vector<PlanePair> out;
    std::array<bool, 3> plane_done{};  // by the axis left out
    // The shape's reads of the query's axes a and b outside the expressions of u and w: those stay unknown in
    // the pair's analysis. Of a plane's pairs, the one with the fewest is taken: the first of those, or a later
    // one computed from its values (of nested rotations by constant angles, the outer one, whose box needs no
    // rotation of the inner one's box by intervals).
    auto trees = [&](ValueId u, ValueId w) {  // the instructions u and w are computed from
        std::vector<char> in_pair(g.body.size(), 0);
        std::vector<ValueId> todo = {u, w};
        while (!todo.empty()) {
            ValueId x = todo.back();
            todo.pop_back();
            if (in_pair[x]) continue;
            in_pair[x] = 1;
            for (ValueId y : g.body[x].args) todo.push_back(y);
        }
        return in_pair;
    };
    auto outside_reads = [&](ValueId u, ValueId w, int a, int b) {
        std::vector<char> in_pair = trees(u, w);
        int reads = 0;
        for (size_t i = 0; i < g.body.size(); ++i) {
            if (in_pair[i]) continue;
            for (ValueId y : g.body[i].args) {
                int axis = query_axis(g, query, y);
                const Instr& yi = g.body[y];
                bool whole = yi.op == Op::Param && yi.aux == query && g.body[i].op != Op::Extract;
                reads += whole || axis == a || axis == b;
            }
        }
        return reads;
    };
    std::array<std::optional<PlanePair>, 3> best;
    std::array<int, 3> best_reads{}, weighed{};  // per plane: the best pair's outside reads, pairs weighed
    for (size_t i = 0; i < c.size(); ++i)
        for (size_t j = i + 1; j < c.size(); ++j) {
            auto p = plane_pair(c[i].f, c[j].f);
            if (!p) continue;
            size_t plane = size_t(3 - p->a - p->b);
            if (++weighed[plane] > 16) continue;  // each weighing walks the function: a shape of many copies'
                                                  // rotations would weigh their pairs pairwise
            p->u = c[i].v, p->u_comp = c[i].comp, p->w = c[j].v, p->w_comp = c[j].comp;
            int reads = outside_reads(p->u, p->w, p->a, p->b);
            bool better = !best[plane] || reads < best_reads[plane];
            if (!better && reads == best_reads[plane]) {  // a pair computed from the best one's values
                std::vector<char> t = trees(p->u, p->w);
                better = t[best[plane]->u] && t[best[plane]->w];
            }
            if (better) best[plane] = p, best_reads[plane] = reads;
        }
    for (size_t plane = 0; plane < 3; ++plane)
        if (best[plane]) {
            out.push_back(*best[plane]);
            plane_done[plane] = true;
        }
    // The axis to pair with u is one the shape reads outside u (the shear's p_2, not its p_1, which only u
    // reads: paired with p_1, p_2 would stay unknown wherever else the shape reads it).
    std::vector<int> users(g.body.size(), 0);
    for (const Instr& in : g.body)
        for (ValueId a : in.args) users[a]++;
    auto inside = [&](ValueId root, ValueId v) {  // v's uses by the instructions root is computed from
        std::vector<char> tree = trees(root, root);
        int uses = 0;
        for (size_t x = 0; x < g.body.size(); ++x)
            if (tree[x])
                for (ValueId a : g.body[x].args) uses += a == v;
        return uses;
    };
    for (const Candidate& u : c)
        for (const Candidate& w : single) {
            int a = u.f.begin()->first, b = u.f.rbegin()->first, axis = w.f.begin()->first;
            if ((axis != a && axis != b) || plane_done[size_t(3 - a - b)]) continue;
            if (w.comp < 0 && users[w.v] <= inside(u.v, w.v)) continue;
            LinearForm fw = w.f;
            fw[axis == a ? b : a] = {Coefficient::Constant, 0, 0};
            auto p = plane_pair(u.f, fw);
            if (!p) continue;
            p->u = u.v, p->u_comp = u.comp, p->w = w.v, p->w_comp = w.comp;
            plane_done[size_t(3 - a - b)] = true;
            out.push_back(*p);
        }
    return out;
}

}  // namespace

namespace {

// Case splitting (ir/CaseSplit.h) where the hull of a piecewise choice loses what each case knows: the
// octahedron's q is one of three permutations of |p|, and each component's hull over them is every one of
// |p|'s, so ‖(q₁, q₂ − s + k, q₃ − k)‖ may be 0 anywhere and no half-space beyond a plane is proven free,
// though in each case one component is at least p₁. Without it the standard library's octahedron and
// round_cone_ab had no box (rays not clipped; no derived `bound`: 100 octahedra evaluated all 100 at every
// step), the pyramid's was open on two sides. Interval passes per box, tried only where one pass leaves the
// box unproven (the octahedron's cases take up to ~15 passes, each up to 3 rounds of narrowing).
constexpr int kSplitPasses = 32;

// A copy of `f` with its calls inlined, constants folded and common subexpressions merged (the form case
// splitting, which splits a function's own comparisons, and the rotated pairs take apart); nothing where it
// is too large (20,000 instructions).
std::optional<Function> flattened(const Module& m, const Function& f) {
    std::optional<Function> g;
    try {
        g = inline_calls_as_emitted(m, f);
    } catch (const SizeLimit&) {
        return std::nullopt;
    }
    if (g->body.size() > 20000) return std::nullopt;
    // A constant that float moves by more than 1e-6 (16777217 in a local function's body): folded here in double,
    // with the argument the shader passes, it would be neither the shader's value nor a range holding it (the
    // interval analysis holds both: ir/Intervals.cpp). The analyses of the flattened copy are not made then.
    for (const Instr& in : g->body)
        if (in.op == Op::Const && in.type.kind != Type::Integer && in.type.elem != Type::Integer)
            for (double v : in.data)
                if (std::fabs(double(float(v)) - v) > 1e-6) return std::nullopt;
    fold_constants(m, *g);
    eliminate_common_subexpressions(*g);
    return g;
}

// Whether `g` has a comparison or a sign for case splitting to split.
bool has_cases(const Function& g) {
    for (const Instr& in : g.body)
        if (in.op == Op::Compare || (in.op == Op::Builtin && builtins()[size_t(in.aux)].name == std::string_view("sign")))
            return true;
    return false;
}

// flattened(m, f) where it has cases to split; nothing elsewhere.
std::optional<Function> splittable(const Module& m, const Function& f) {
    std::optional<Function> g = flattened(m, f);
    if (g && !has_cases(*g)) g.reset();
    return g;
}

// The distance's lowest value over the cases of `g` (its first component's lower end), `params` as given,
// where it is above `level`; −∞ where it is not, or unknown.
double split_lowest(const Module& m, const Function& g, const std::vector<std::vector<Interval>>& params, double level,
                    int loop_trips, long* work) {
    CaseSplitOptions o;
    o.query_point = false;  // sound at every point, x = 0 too (a sign's closed halves)
    o.loop_trips = loop_trips;
    o.work = work;
    o.target = -level;  // a case at or below the level: the box is not proven free, whatever the others
    double worst = case_split_bound(
        m, g, params,
        [](const Bounds& r) {
            double lo = r.c.empty() ? -INFINITY : r.c[0].lo;
            return std::isnan(lo) ? INFINITY : -lo;
        },
        kSplitPasses, o);
    return std::isnan(worst) || worst >= o.target ? -INFINITY : -worst;
}

}  // namespace

namespace {

std::optional<std::pair<AffineMap, SupportBox>> mapped_box(const Module& m, const Function& g, int query,
                                                           std::vector<std::vector<Interval>> params, double level,
                                                           int per_proof, int loop_trips, long work);
bool boxable(const Module& m, int fn, int query, size_t params);
SupportBox box_of(const Module& m, const Function& f, const std::optional<Function>& g, int query,
                  std::vector<std::vector<Interval>> params, double level, int per_proof, int loop_trips, long work,
                  int depth);

// support_radius by interval arithmetic alone (branch and bound over boxes, with case splitting on `flat`, the
// function's flattened copy, where it has cases).
std::optional<double> interval_radius(const Module& m, int fn, int query, std::vector<std::vector<Interval>> params,
                                      double reach, int budget, const std::optional<Function>& flat) {
    if (fn < 0 || size_t(fn) >= m.functions.size() || query < 0 || size_t(query) >= params.size()) return std::nullopt;
    const Function& f = m.functions[size_t(fn)];
    if (!f.body[f.result].type.is_scalar()) return std::nullopt;
    // The distance's lowest value over a box. (One scratch for every box: a fresh one planned the function's
    // refinements (UnivariatePlan) again per box, 13% of 100 tori's compile on WebGL2.)
    IntervalScratch scratch;
    std::vector<Bounds> v;
    auto lowest = [&](const Box& b) {
        params[size_t(query)] = {{b.lo[0], b.hi[0]}, {b.lo[1], b.hi[1]}, {b.lo[2], b.hi[2]}};
        interval_analysis(scratch, v, m, f, params);
        const Bounds& r = v[f.result];
        double lo = r.c.empty() ? -INFINITY : r.c[0].lo;
        return std::isnan(lo) ? -INFINITY : lo;
    };
    // The same, and where one pass leaves the box unproven, by case splitting on a flattened copy (its
    // instructions count against the budget, a box's worth per function's length).
    const Function* g = flat && has_cases(*flat) ? &*flat : nullptr;
    auto lowest_split = [&](const Box& b) {
        double lo = lowest(b);
        if (lo > 0 || !g) return lo;
        // Not where the box's centre lies in the solid: no case can prove that box free.
        if (std::isfinite(b.lo[0] + b.hi[0] + b.lo[1] + b.hi[1] + b.lo[2] + b.hi[2])) {
            Box c;
            for (size_t a = 0; a < 3; ++a) c.lo[a] = c.hi[a] = 0.5 * (b.lo[a] + b.hi[a]);
            if (lowest(c) <= 0) return lo;
        }
        long work = long(std::max(0, budget)) * long(std::max<size_t>(1, g->body.size()));
        const long given = work;
        params[size_t(query)] = {{b.lo[0], b.hi[0]}, {b.lo[1], b.hi[1]}, {b.lo[2], b.hi[2]}};
        lo = std::max(lo, split_lowest(m, *g, params, 0, 0, &work));
        budget -= int((given - work) / long(std::max<size_t>(1, g->body.size())));
        return lo;
    };
    // One pass: the boxes of `domain`, split `depth` times where they may hold the solid; false when one
    // touching the domain's boundary does (when `open`), or the budget runs out.
    auto pass = [&](const Box& domain, int depth, bool open, std::vector<Box>& kept) {
        std::vector<std::pair<Box, int>> stack = {{domain, 0}};
        kept.clear();
        while (!stack.empty()) {
            auto [b, level] = stack.back();
            stack.pop_back();
            if (--budget < 0) return false;
            if (lowest_split(b) > 0) continue;
            if (level == depth) {
                if (open)
                    for (int c = 0; c < 3; ++c)
                        if (b.lo[size_t(c)] <= domain.lo[size_t(c)] || b.hi[size_t(c)] >= domain.hi[size_t(c)]) return false;
                kept.push_back(b);
                continue;
            }
            for (int o = 0; o < 8; ++o) {
                Box c;
                for (size_t a = 0; a < 3; ++a) {
                    double mid = 0.5 * (b.lo[a] + b.hi[a]);
                    bool upper = (o >> a) & 1;
                    c.lo[a] = upper ? mid : b.lo[a];
                    c.hi[a] = upper ? b.hi[a] : mid;
                }
                stack.push_back({c, level + 1});
            }
        }
        return true;
    };
    Box domain{{-reach, -reach, -reach}, {reach, reach, reach}};
    std::vector<Box> kept;
    // Coarse: the solid must stay off the boundary of the big cube (levels of 1/64 of it).
    if (!pass(domain, 6, true, kept)) return std::nullopt;
    if (kept.empty()) return std::nullopt;  // nothing where the distance can be ≤ 0: no solid to bound
    // Nor beyond the cube: each of the six half-spaces past a face (the other axes unbounded) must be free, or a
    // part of the solid farther than `reach` (a model in millimetres scaled to metres) would be cut off.
    for (size_t a = 0; a < 3; ++a)
        for (int side : {-1, 1}) {
            Box slab{{-INFINITY, -INFINITY, -INFINITY}, {INFINITY, INFINITY, INFINITY}};
            if (side > 0) slab.lo[a] = reach;
            else slab.hi[a] = -reach;
            if (--budget < 0 || !(lowest_split(slab) > 0)) return std::nullopt;
        }
    // Fine: the hull of what is left, widened by half a cell, split again (four times: each cell is 1/8 of the
    // last hull, which shrinks to the solid's).
    for (int round = 0; round < 4; ++round) {
        Box hull{{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}};
        double cell = 0;
        for (const Box& b : kept)
            for (size_t a = 0; a < 3; ++a) {
                hull.lo[a] = std::min(hull.lo[a], b.lo[a]);
                hull.hi[a] = std::max(hull.hi[a], b.hi[a]);
                cell = std::max(cell, b.hi[a] - b.lo[a]);
            }
        for (size_t a = 0; a < 3; ++a) {
            hull.lo[a] -= 0.5 * cell;
            hull.hi[a] += 0.5 * cell;
        }
        std::vector<Box> finer;
        if (!pass(hull, 3, false, finer)) break;  // keep the coarser answer
        kept = std::move(finer);
    }
    // The radius: the farthest corner of a box left, refined where it is decided (best first: the box with the
    // farthest corner is split until it is small against the radius, or the budget ends).
    auto far_corner = [](const Box& b) {
        double s = 0;
        for (size_t a = 0; a < 3; ++a) s += std::pow(std::max(std::fabs(b.lo[a]), std::fabs(b.hi[a])), 2);
        return std::sqrt(s);
    };
    auto size = [](const Box& b) { return std::max({b.hi[0] - b.lo[0], b.hi[1] - b.lo[1], b.hi[2] - b.lo[2]}); };
    auto farther = [&](const Box& a, const Box& b) { return far_corner(a) < far_corner(b); };
    std::priority_queue<Box, std::vector<Box>, decltype(farther)> queue(farther, std::move(kept));
    double r = 0;
    while (!queue.empty()) {
        Box b = queue.top();
        if (size(b) <= 0.002 * far_corner(b) || budget < 8) {
            r = far_corner(b);
            break;
        }
        queue.pop();
        for (int o = 0; o < 8; ++o) {
            Box c;
            for (size_t a = 0; a < 3; ++a) {
                double mid = 0.5 * (b.lo[a] + b.hi[a]);
                bool upper = (o >> a) & 1;
                c.lo[a] = upper ? mid : b.lo[a];
                c.hi[a] = upper ? b.hi[a] : mid;
            }
            --budget;
            if (lowest_split(c) <= 0) queue.push(c);
        }
    }
    return std::nextafter(r * (1 + 1e-9), INFINITY);
}

}  // namespace

std::optional<double> support_radius(const Module& m, int fn, int query, std::vector<std::vector<Interval>> params,
                                      double reach, int budget) {
    if (fn < 0 || size_t(fn) >= m.functions.size() || query < 0 || size_t(query) >= params.size()) return std::nullopt;
    // A convex polytope written as the largest of its planes' distances (ir/ConvexBound.h): its farthest
    // vertex, where intervals find no radius (every plane's distance is unbounded below over a half-space).
    // The flattened copy, once: case splitting's, the polytope's and the rotation's.
    const std::optional<Function> g = flattened(m, m.functions[size_t(fn)]);
    std::optional<double> polytope;
    if (g)
        if (auto pieces = convex_lower_bound(m, *g, query, params)) polytope = polytope_radius(*pieces, 0);
    std::optional<double> r = interval_radius(m, fn, query, params, reach, budget, g);
    if (polytope && (!r || *polytope < *r)) return polytope;
    // A rotation written inside the module (mapped_box): the farthest of v's box's corners mapped back through
    // A⁻¹ (‖A⁻¹(v − b)‖ is convex in v: its largest value over the box is at a corner).
    if (!r && g)
        if (auto mb = mapped_box(m, *g, query, params, 0, 48, 16, 300000)) {
            const auto& [map, v] = *mb;
            double far = 0;
            for (int corner = 0; corner < 8 && std::isfinite(far); ++corner) {
                double n2 = 0;
                for (size_t k = 0; k < 3; ++k) {
                    double x = 0;
                    for (size_t j = 0; j < 3; ++j)
                        x += map.inverse[k][j] * (((corner >> j) & 1 ? v.hi[j] : v.lo[j]) - map.b[j]);
                    n2 += x * x;
                }
                far = std::max(far, std::sqrt(n2));
            }
            if (std::isfinite(far)) r = std::nextafter(far * (1 + 1e-9), INFINITY);
        }
    // Else the farthest corner of the box support_box finds at level 0 (a union of a turned part and a ball: its
    // operands are boxed one by one there), on the flattened copy above (support_box's own analyses, with its
    // default budgets). Not where that box is empty (nothing is ≤ 0: nothing to bound) or reaches past `reach`
    // (as above: a part that far is no bound's business).
    if (!r && boxable(m, fn, query, params.size())) {
        const SupportBox box = box_of(m, m.functions[size_t(fn)], g, query, params, 0, 48, 16, 1500000, 0);
        double far = 0;
        bool empty = false;
        for (size_t k = 0; k < 3; ++k) {
            empty |= box.lo[k] > box.hi[k];
            far += std::pow(std::max(std::fabs(box.lo[k]), std::fabs(box.hi[k])), 2);
        }
        far = std::sqrt(far);
        if (!empty && far <= reach) r = std::nextafter(far * (1 + 1e-9), INFINITY);
    }
    return r;
}

namespace {

using BoxRange = std::function<Interval(const Box&)>;  // the distance's interval over a box
// The distance's lowest value over a box by case splitting (splittable, split_lowest) where it is above the
// level (else −∞), spending `allowance` (instructions) and the analysis's work.
using BoxSplit = std::function<double(const Box&, double level, long& allowance)>;
constexpr long kSplitPerProof = 16000;  // a proof's allowance for splits (a proof that holds spends ~1,500)
constexpr double kUnboundedAt = 1048576.0;              // 2^20: beyond this, a side is unbounded

// Whether no point of `start` has a distance ≤ level (false: not proven, or a point found that has): the boxes
// where `range` may reach the level are split at their widest side up to `per_proof` times, spending `work`; a
// box's centre at or below the level ends the proof at once. Among unbounded sides the first axis is split, or
// with `rotate` the next after the axis the box was last split along: a half-space beyond a plane along x, split
// along x alone, stays a half-space (its far half is unbounded again) and never has its other axes narrowed,
// where a fold needs them (the hexagonal prism's reflection p − 2 min(k⋅p, 0) k proves its x side only over
// bounded y; stop 48). box_of asks for it only on the sides every other analysis leaves open.
bool free_of(const BoxRange& range, const BoxSplit& split, const Box& start, double level, int per_proof, long& work,
             bool rotate = false) {
    // A point inside an interval, and its halves (an unbounded side grows geometrically).
    auto centre = [](double lo, double hi) {
        if (std::isinf(lo) && std::isinf(hi)) return 0.0;
        if (std::isinf(hi)) return lo + std::max(1.0, std::fabs(lo));
        if (std::isinf(lo)) return hi - std::max(1.0, std::fabs(hi));
        return 0.5 * (lo + hi);
    };
    // A point of the set ends the proof at once: the start's point nearest the origin first (a shape's own
    // space has its solid around the origin: a plane through it is disproved by one sample, where case
    // splitting would spend its allowance on boxes it cannot prove), then each box's centre.
    Box near;
    for (size_t a = 0; a < 3; ++a) near.lo[a] = near.hi[a] = std::clamp(0.0, start.lo[a], start.hi[a]);
    if (range(near).hi <= level) return false;
    // Each box with the axis it was last split along (3: none yet).
    std::vector<std::pair<Box, size_t>> stack = {{start, 3}};
    int left = per_proof;
    long allowance = kSplitPerProof;
    while (!stack.empty()) {
        if (work <= 0) return false;
        auto [b, last] = stack.back();
        stack.pop_back();
        if (range(b).lo > level) continue;
        if (--left < 0) return false;
        Box c;
        for (size_t a = 0; a < 3; ++a) c.lo[a] = c.hi[a] = centre(b.lo[a], b.hi[a]);
        if (range(c).hi <= level) return false;
        if (split && allowance > 0 && split(b, level, allowance) > level) continue;  // proven case by case
        size_t w = 0;
        double widest = -1;
        for (size_t a = 0; a < 3; ++a) {
            double len = b.hi[a] - b.lo[a];
            if (len > widest) widest = len, w = a;
        }
        if (!(widest > 0)) return false;
        if (rotate && std::isinf(widest) && last < 3)
            for (size_t j = 1; j <= 3; ++j)
                if (std::isinf(b.hi[(last + j) % 3] - b.lo[(last + j) % 3])) {
                    w = (last + j) % 3;
                    break;
                }
        Box lo = b, hi = b;
        lo.hi[w] = hi.lo[w] = c.lo[w];
        stack.push_back({lo, w});
        stack.push_back({hi, w});
    }
    return true;
}

// The half-space beyond the plane at c along axis a (above it when `upper`, else below).
Box half_space(size_t a, bool upper, double c) {
    Box b{{-INFINITY, -INFINITY, -INFINITY}, {INFINITY, INFINITY, INFINITY}};
    if (upper) b.lo[a] = c;
    else b.hi[a] = c;
    return b;
}

// support_box's search, side by side, for a distance whose interval over a box `range` gives (spending `work`).
// `rotate`: free_of splits the unbounded sides in turn, and the half-space beyond R is tried with half the splits
// (box_of runs this on the sides every other analysis left open: a side that stays open, a ground's, pays for
// one proof); `want` (lo, hi per axis): the sides searched, the others left unbounded.
SupportBox box_sides(const BoxRange& range, const BoxSplit& split, double level, int per_proof, long& work, bool rotate = false,
                     const std::array<bool, 6>* want = nullptr) {
    constexpr double R = kUnboundedAt;
    SupportBox out;
    // One side's edge: the nearest plane c (along axis a, from below or above) beyond which nothing is ≤ level;
    // ±∞ where the half-space beyond R is not proven free.
    auto edge_of = [&](size_t a, bool upper) {
        auto beyond = [&](double c) { return free_of(range, split, half_space(a, upper, c), level, per_proof, work, rotate); };
        const double sgn = upper ? 1 : -1;
        // (Rotating, the first proof with half the splits: a side that stays open, a ground or the hills of
        // examples/christmas_tree.iq, pays for it; measured in a first arrangement that retried within this
        // search, with all of them that scene's compile took 0.71 s instead of 0.55, with half 0.65, and every
        // side the rotation closes was closed; a quarter left the prisms and the cone open.)
        if (!(rotate ? free_of(range, split, half_space(a, upper, sgn * R), level, per_proof / 2, work, true) : beyond(sgn * R)))
            return sgn * INFINITY;
        // A plane that is not proven (in) and one that is (out): planes ±1, ±2, ±4, … from 0 outward (or
        // inward, where the half-space beyond 0 is already free), then bisection to 1e-3 of the scale.
        double in = NAN, out_c = NAN;
        if (beyond(0)) {
            out_c = 0;
            for (double c = 1; c <= R && std::isnan(in); c *= 2) (beyond(-sgn * c) ? out_c : in) = -sgn * c;
            if (std::isnan(in)) return -sgn * R;  // free on both sides: nothing is ≤ level anywhere
        } else {
            in = 0;
            // Planes out to 1,024 units (a shape's own space rarely reaches further; beyond, the side stays at
            // R rather than spending the budget on proofs that keep failing, as over fbm noise).
            for (double c = 1; c <= 1024 && std::isnan(out_c); c *= 2) (beyond(sgn * c) ? out_c : in) = sgn * c;
            if (std::isnan(out_c)) return sgn * R;
        }
        while (std::fabs(out_c - in) > 1e-3 * std::max(1.0, std::fabs(out_c))) {
            double mid = 0.5 * (in + out_c);
            (beyond(mid) ? out_c : in) = mid;
        }
        return out_c;
    };
    // Each side searched gets its share of the budget (an open side spends all of it on trying).
    int sides = 6;
    if (want) sides = int(std::count(want->begin(), want->end(), true));
    const long share = work / std::max(1, sides);
    long left = work;
    for (size_t a = 0; a < 3; ++a)
        for (bool upper : {false, true}) {
            if (want && !(*want)[2 * a + (upper ? 1 : 0)]) {
                (upper ? out.hi[a] : out.lo[a]) = upper ? INFINITY : -INFINITY;
                continue;
            }
            work = std::min(left, share);
            const long given = work;
            double e = edge_of(a, upper);
            left -= given - work;
            (upper ? out.hi[a] : out.lo[a]) = e;
        }
    return out;
}

}  // namespace

namespace {

// The first component of a result's interval ([-∞, ∞] where unknown or NaN).
Interval first_component(const Bounds& r) {
    Interval x = r.c.empty() ? Interval{} : r.c[0];
    if (std::isnan(x.lo)) x.lo = -INFINITY;
    if (std::isnan(x.hi)) x.hi = INFINITY;
    return x;
}

// Whether support_box can use function `fn`: a scalar distance, or a scene's (distance, id) whose first
// component is the distance, and a query parameter that exists.
bool boxable(const Module& m, int fn, int query, size_t params) {
    if (fn < 0 || size_t(fn) >= m.functions.size() || query < 0 || size_t(query) >= params) return false;
    const Function& f = m.functions[size_t(fn)];
    const Type& rt = f.body[f.result].type;
    return rt.is_scalar() || rt.is_vector();
}

// The distance's interval over a box of the query point (the other parameters as given), spending `work`;
// one set of buffers for every box.
struct DistanceRange {
    const Module& m;
    const Function& f;
    int query;
    std::vector<std::vector<Interval>>& params;
    int loop_trips;
    long& work;
    std::vector<Bounds> values{};
    IntervalScratch scratch{};
    Interval operator()(const Box& b) {
        params[size_t(query)] = {{b.lo[0], b.hi[0]}, {b.lo[1], b.hi[1]}, {b.lo[2], b.hi[2]}};
        interval_analysis(scratch, values, m, f, params, {}, loop_trips, &work);
        return first_component(values[f.result]);
    }
    // Case splitting (a BoxSplit) on `flat`, f made splittable; nothing where it is not. Its instructions
    // come from a pool of their own, as large as the analysis's `work` when it begins (so that what the
    // intervals alone proved they still prove: a terrain's top at 32 was left open when splits, which its
    // noise never decides, spent the side's share first).
    std::optional<Function> flat{};
    long split_work = 0;
    BoxSplit splitter() {
        if (!flat) return nullptr;
        split_work = work;
        return [this](const Box& b, double level, long& allowance) {
            params[size_t(query)] = {{b.lo[0], b.hi[0]}, {b.lo[1], b.hi[1]}, {b.lo[2], b.hi[2]}};
            long spend = std::min(allowance, split_work);
            const long given = spend;
            double lo = split_lowest(m, *flat, params, level, loop_trips, &spend);
            allowance -= given - spend;
            split_work -= given - spend;
            return lo;
        };
    }
};

}  // namespace

namespace {

// A constant affine map of the query point that mixes its axes, v = A p + b (ir/ConvexBound.h's affine_maps: a
// rotation written inside the module, q = R p or R (p − c)): over a half-space beyond a plane each of v's
// components is unbounded, so the analysis of p's boxes closes no side. The shape is analysed over boxes of v
// instead (p itself unbounded wherever else the shape reads it, so that what is proven holds): the last such
// value (a composition of rotations: the whole map) and v's box, where it has a finite side; the box's search
// as support_box's (`work` its own budget).
std::optional<std::pair<AffineMap, SupportBox>> mapped_box(const Module& m, const Function& g, int query,
                                                           std::vector<std::vector<Interval>> params, double level,
                                                           int per_proof, int loop_trips, long work) {
    std::vector<AffineMap> maps = affine_maps(m, g, query, params);
    // Only the maps the result is computed from (a union's operand, analysed alone, shares the body).
    std::vector<char> used(g.body.size(), 0);
    used[g.result] = 1;
    for (size_t i = g.body.size(); i-- > 0;)
        if (used[i])
            for (ValueId a : g.body[i].args) used[a] = 1;
    std::erase_if(maps, [&](const AffineMap& x) { return !used[x.value]; });
    if (maps.empty()) return std::nullopt;
    const AffineMap map = maps.back();
    Box cur;
    IntervalHook hook = [&](size_t i, std::vector<Bounds>& r) {
        if (i == map.value) {
            r[i].c = {{cur.lo[0], cur.hi[0]}, {cur.lo[1], cur.hi[1]}, {cur.lo[2], cur.hi[2]}};
            r[i].norm = r[i].norm_from_components();
            r[i].unit = false;
        }
        return true;
    };
    IntervalScratch scratch;
    std::vector<Bounds> values;
    auto mapped = [&](const Box& b) {
        cur = b;
        params[size_t(query)] = {{}, {}, {}};
        interval_analysis(scratch, values, m, g, params, hook, loop_trips, &work);
        Interval x = values[g.result].c.empty() ? Interval{} : values[g.result].c[0];
        if (std::isnan(x.lo)) x.lo = -INFINITY;
        if (std::isnan(x.hi)) x.hi = INFINITY;
        return x;
    };
    SupportBox v = box_sides(mapped, nullptr, level, per_proof, work);
    bool any = false;
    for (size_t a = 0; a < 3; ++a) any |= std::isfinite(v.lo[a]) || std::isfinite(v.hi[a]);
    if (!any) return std::nullopt;
    return std::make_pair(map, v);
}

}  // namespace

bool support_box_open(const Module& m, int fn, int query, std::vector<std::vector<Interval>> params, double level,
                      int per_proof, int loop_trips, long work) {
    if (!boxable(m, fn, query, params.size())) return true;
    DistanceRange distance{m, m.functions[size_t(fn)], query, params, loop_trips, work};
    distance.flat = splittable(m, m.functions[size_t(fn)]);
    auto range = [&](const Box& b) { return distance(b); };
    const BoxSplit split = distance.splitter();
    // (The first split order only: box_sides may still close a side this finds open, by splitting the unbounded
    // sides in turn. This test only orders the analyses: a ground plane, open, would pay twice.)
    for (size_t a = 0; a < 3; ++a)
        for (bool upper : {false, true})
            if (!free_of(range, split, half_space(a, upper, upper ? kUnboundedAt : -kUnboundedAt), level, per_proof, work)) return true;
    return false;
}

namespace {

// support_box's analyses of function f, whose flattened copy is g (f itself may be g): the box of the points where
// its distance may be ≤ level (±∞ on a side none closes). `depth` counts the unions taken apart above.
SupportBox box_of(const Module& m, const Function& f, const std::optional<Function>& g, int query,
                  std::vector<std::vector<Interval>> params, double level, int per_proof, int loop_trips, long work,
                  int depth) {
    auto first = first_component;
    const long budget = work;
    DistanceRange distance{m, f, query, params, loop_trips, work};
    // (A union's operand is not split case by case: the whole was, and its operands' proofs would repeat it.)
    if (g && depth == 0 && has_cases(*g)) distance.flat = g;
    auto range = [&](const Box& b) { return distance(b); };
    const BoxSplit split = distance.splitter();
    SupportBox out = box_sides(range, split, level, per_proof, work);
    // A convex polytope written as the largest of its planes' distances (ir/ConvexBound.h): its sides, which
    // intervals cannot close (each plane's distance is unbounded below over a half-space).
    if (g)
        if (auto pieces = convex_lower_bound(m, *g, query, params)) {
            SupportBox pb = polytope_box(*pieces, level);
            for (size_t a = 0; a < 3; ++a) {
                out.lo[a] = std::max(out.lo[a], pb.lo[a]);
                out.hi[a] = std::min(out.hi[a], pb.hi[a]);
            }
        }

    // Rotated pairs of the query's axes (see plane_pair): once more per plane, in the pair's coordinates, on
    // the copy with its calls inlined and common subexpressions merged (so that cos θ and sin θ are seen to
    // share θ), with a budget of its own. (Too large to inline: the axis-aligned box stands.)
    if (g) {
        for (const PlanePair& pp : plane_pairs(*g, query)) {
            const int o = 3 - pp.a - pp.b;  // the axis the pair leaves alone
            Box cur;  // the box of (u at a, p_o at o, w at b) being analysed
            auto set = [](Bounds& r, int comp, Interval x) {
                if (comp < 0) r.c = {x};
                else if (size_t(comp) < r.c.size()) r.c[size_t(comp)] = x;
                r.norm = r.norm_from_components();
            };
            IntervalHook hook = [&](size_t i, std::vector<Bounds>& r) {
                if (i == pp.u) set(r[i], pp.u_comp, {cur.lo[size_t(pp.a)], cur.hi[size_t(pp.a)]});
                if (i == pp.w) set(r[i], pp.w_comp, {cur.lo[size_t(pp.b)], cur.hi[size_t(pp.b)]});
                return true;
            };
            long rotated_work = budget;
            auto rotated = [&](const Box& b) {
                cur = b;
                // p_a and p_b themselves are unknown (wherever else the shape reads them); p_o is the box's.
                params[size_t(query)] = {{}, {}, {}};
                params[size_t(query)][size_t(o)] = {b.lo[size_t(o)], b.hi[size_t(o)]};
                interval_analysis(distance.scratch, distance.values, m, *g, params, hook, loop_trips, &rotated_work);
                return first(distance.values[g->result]);
            };
            SupportBox v = box_sides(rotated, nullptr, level, per_proof, rotated_work);
            // (p_a, p_b) from (u, w): the same norm (orthogonal), or M⁻¹ applied to the box.
            std::array<Interval, 2> pab;
            Interval ua{v.lo[size_t(pp.a)], v.hi[size_t(pp.a)]}, wb{v.lo[size_t(pp.b)], v.hi[size_t(pp.b)]};
            if (pp.orthogonal) {
                // ‖(u, w)‖ over the rectangle's cells where the distance may be ≤ level, best first (the cell
                // with the farthest corner is split until it is small against that distance): the twisted
                // box's rounded corner, not its rectangle's.
                auto far_corner = [&](const Box& b) {
                    return std::hypot(std::max(std::fabs(b.lo[size_t(pp.a)]), std::fabs(b.hi[size_t(pp.a)])),
                                      std::max(std::fabs(b.lo[size_t(pp.b)]), std::fabs(b.hi[size_t(pp.b)])));
                };
                auto size = [&](const Box& b) {
                    return std::max(b.hi[size_t(pp.a)] - b.lo[size_t(pp.a)], b.hi[size_t(pp.b)] - b.lo[size_t(pp.b)]);
                };
                auto nearer = [&](const Box& x, const Box& y) { return far_corner(x) < far_corner(y); };
                const Box whole{v.lo, v.hi};
                double rho = far_corner(whole);
                if (std::isfinite(rho)) {
                    std::priority_queue<Box, std::vector<Box>, decltype(nearer)> cells(nearer);
                    cells.push(whole);
                    for (int splits = 0; !cells.empty(); ++splits) {
                        Box b = cells.top();
                        if (size(b) <= 0.002 * far_corner(b) || splits >= 2000 || rotated_work <= 0) break;
                        cells.pop();
                        for (int q = 0; q < 4; ++q) {
                            Box c = b;
                            for (int k = 0; k < 2; ++k) {
                                size_t axis = size_t(k == 0 ? pp.a : pp.b);
                                double mid = 0.5 * (b.lo[axis] + b.hi[axis]);
                                ((q >> k) & 1 ? c.lo[axis] : c.hi[axis]) = mid;
                            }
                            if (!(rotated(c).lo > level)) cells.push(c);
                        }
                    }
                    if (!cells.empty()) rho = std::min(rho, far_corner(cells.top()));
                }
                rho = std::nextafter(rho * (1 + 1e-9), INFINITY);
                pab = {Interval{-rho, rho}, Interval{-rho, rho}};
            } else {
                for (size_t r = 0; r < 2; ++r)
                    pab[r] = iv::add(iv::mul({pp.inverse[r * 2], pp.inverse[r * 2]}, ua), iv::mul({pp.inverse[r * 2 + 1], pp.inverse[r * 2 + 1]}, wb));
            }
            auto narrow = [&](size_t axis, Interval x) {
                if (std::isnan(x.lo) || std::isnan(x.hi)) return;
                out.lo[axis] = std::max(out.lo[axis], x.lo);
                out.hi[axis] = std::min(out.hi[axis], x.hi);
            };
            narrow(size_t(pp.a), pab[0]);
            narrow(size_t(pp.b), pab[1]);
            narrow(size_t(o), {v.lo[size_t(o)], v.hi[size_t(o)]});
        }
    }
    // A constant affine map of the query point that mixes its axes (mapped_box): v's box mapped back through A⁻¹.
    if (g)
        if (auto mb = mapped_box(m, *g, query, params, level, per_proof, loop_trips, budget)) {
            const auto& [map, v] = *mb;
            for (size_t k = 0; k < 3; ++k) {
                Interval x{0, 0};
                for (size_t j = 0; j < 3; ++j) {
                    const double c = map.inverse[k][j];
                    if (c == 0) continue;
                    x = iv::add(x, iv::mul({c, c}, iv::add({v.lo[j], v.hi[j]}, {-map.b[j], -map.b[j]})));
                }
                if (std::isnan(x.lo) || std::isnan(x.hi)) continue;
                // Rounded outward (the solve of A⁻¹ and the sums): a relative margin.
                out.lo[k] = std::max(out.lo[k], x.lo - 1e-9 * std::max(1.0, std::fabs(x.lo)));
                out.hi[k] = std::min(out.hi[k], x.hi + 1e-9 * std::max(1.0, std::fabs(x.hi)));
            }
        }
    // A union, min(d₁, d₂, …), left open on a side: the points where it is ≤ level are those where some operand
    // is, so the hull of the operands' boxes holds them, each found by whichever analysis closes it (a part
    // turned inside the module beside another turned otherwise, or beside an unturned ball: the rotated
    // analysis of the whole leaves the other part's coordinates unbounded). Up to 8 operands, one level, each
    // with a quarter of the budget shared, without case splitting (the whole was split), and only in a function
    // of at most 160 instructions: the example Christmas tree's angular repetitions (179 and 376) took 0.5 s
    // more to close nothing.
    bool open = false;
    for (size_t a = 0; a < 3; ++a) open |= !std::isfinite(out.lo[a]) || !std::isfinite(out.hi[a]);
    if (open && g && depth < 1 && g->body.size() <= 160 && g->body[g->result].type.is_scalar()) {
        // Through a rounding or a scale of the union, k·min(…) + c with constants k > 0 and c (a rounded union,
        // min(a, b) − 0.1): it is ≤ level where the union is ≤ (level − c)/k.
        ValueId r = g->result;
        double part_level = level;
        auto constant = [&](ValueId v) -> std::optional<double> {
            const Instr& c = g->body[v];
            if (c.op != Op::Const || c.data.size() != 1 || !std::isfinite(c.data[0])) return std::nullopt;
            return c.data[0];
        };
        for (int steps = 0; steps < 16; ++steps) {
            const Instr& x = g->body[r];
            if (x.op == Op::Copy) {
                r = x.args[0];
                continue;
            }
            if (x.op == Op::Add || x.op == Op::Sub) {
                auto c1 = constant(x.args[1]);
                auto c0 = x.op == Op::Add ? constant(x.args[0]) : std::nullopt;
                if (c1) {
                    part_level += x.op == Op::Add ? -*c1 : *c1;
                    r = x.args[0];
                } else if (c0) {
                    part_level -= *c0;
                    r = x.args[1];
                } else {
                    break;
                }
                continue;
            }
            if (x.op == Op::Mul || x.op == Op::Div) {
                auto c1 = constant(x.args[1]);
                auto c0 = x.op == Op::Mul ? constant(x.args[0]) : std::nullopt;
                if (c1 && *c1 > 0) {
                    part_level = x.op == Op::Mul ? part_level / *c1 : part_level * *c1;
                    r = x.args[0];
                } else if (c0 && *c0 > 0) {
                    part_level /= *c0;
                    r = x.args[1];
                } else {
                    break;
                }
                continue;
            }
            break;
        }
        const Instr& in = g->body[r];
        if (in.op == Op::Builtin && builtin(in.aux).name == std::string_view("min") && in.args.size() >= 2 &&
            in.args.size() <= 8 && g->body[in.args[0]].type.is_scalar() && g->body[in.args[1]].type.is_scalar()) {
            SupportBox hull;
            hull.lo.fill(INFINITY);
            hull.hi.fill(-INFINITY);
            for (ValueId operand : in.args) {
                std::optional<Function> part = *g;
                part->result = operand;
                SupportBox b = box_of(m, *part, part, query, params, part_level, per_proof, loop_trips,
                                      budget / (4 * long(in.args.size())), depth + 1);
                for (size_t a = 0; a < 3; ++a) {
                    hull.lo[a] = std::min(hull.lo[a], b.lo[a]);
                    hull.hi[a] = std::max(hull.hi[a], b.hi[a]);
                }
            }
            for (size_t a = 0; a < 3; ++a) {
                out.lo[a] = std::max(out.lo[a], hull.lo[a]);
                out.hi[a] = std::min(out.hi[a], hull.hi[a]);
            }
        }
    }
    // Sides every analysis above left open: the search once more, splitting the unbounded sides of its
    // half-spaces in turn (free_of's `rotate`). A half-space beyond a plane along x, split along x alone, stays
    // a half-space and never has y narrowed, where a fold needs it: the hexagonal and octagonal prisms' reflection
    // p − 2 min(k⋅p, 0) k, the cones' choice by a cross product's sign (stop 48: closed along x, and z). Last, so
    // that whatever the other analyses close keeps their edges; not in a union's operands (the whole's turn).
    // With twice the splits per proof (one hexagonal prism's x side 1.11 with as many, 0.89 with twice, for its
    // 0.82; with four times the budget's shares ran out first: an octagonal prism's 1.09 → 1.22).
    std::array<bool, 6> want{};
    bool still_open = false;
    for (size_t a = 0; a < 3; ++a) {
        want[2 * a] = !std::isfinite(out.lo[a]);
        want[2 * a + 1] = !std::isfinite(out.hi[a]);
        still_open |= want[2 * a] || want[2 * a + 1];
    }
    if (still_open && depth == 0) {
        long rotated_work = budget;
        // Its case splits from a pool of an eighth of the budget: with all that the first search left, a scene of
        // two cones and a solid angle compiled in 0.56 s instead of 0.07 (a trial's), with an eighth 0.27 (the
        // cone's x and z sides 0.93 for its 0.78 instead of 0.78; the capped_cone_ab's x side stays open).
        distance.split_work = std::min(distance.split_work, budget / 8);
        SupportBox r = box_sides(range, split, level, 2 * per_proof, rotated_work, true, &want);
        for (size_t a = 0; a < 3; ++a) {
            out.lo[a] = std::max(out.lo[a], r.lo[a]);
            out.hi[a] = std::min(out.hi[a], r.hi[a]);
        }
    }
    return out;
}

}  // namespace

std::optional<SupportBox> support_box(const Module& m, int fn, int query, std::vector<std::vector<Interval>> params,
                                      double level, int per_proof, int loop_trips, long work) {
    if (!boxable(m, fn, query, params.size())) return std::nullopt;
    const Function& f = m.functions[size_t(fn)];
    // The flattened copy: case splitting's, where it has cases, the polytope's, the rotations' and the unions'.
    const std::optional<Function> g = flattened(m, f);
    SupportBox out = box_of(m, f, g, query, std::move(params), level, per_proof, loop_trips, work, 0);
    bool any = false;
    for (size_t a = 0; a < 3; ++a) any |= std::isfinite(out.lo[a]) || std::isfinite(out.hi[a]);
    if (!any) return std::nullopt;
    return out;
}

std::optional<double> deepest_bound(const Module& m, int fn, int query, std::vector<std::vector<Interval>> params,
                                    const std::array<double, 3>& lo, const std::array<double, 3>& hi, int loop_trips, long work) {
    if (!boxable(m, fn, query, params.size())) return std::nullopt;
    for (size_t a = 0; a < 3; ++a)
        if (!std::isfinite(lo[a]) || !std::isfinite(hi[a]) || lo[a] > hi[a]) return std::nullopt;
    DistanceRange distance{m, m.functions[size_t(fn)], query, params, loop_trips, work};
    // Boxes by the depth their interval allows (−lo of d), deepest first.
    using Entry = std::pair<double, Box>;
    auto shallower = [](const Entry& x, const Entry& y) { return x.first < y.first; };
    std::priority_queue<Entry, std::vector<Entry>, decltype(shallower)> queue(shallower);
    auto push = [&](const Box& b) {
        Interval d = distance(b);
        if (d.lo < 0) queue.push({-d.lo, b});  // boxes where d stays ≥ 0 hold no depth
    };
    double found = 0;  // a depth some point has (d at a box's centre)
    push(Box{lo, hi});
    // (work is spent by the analysis of each box; a cap on the splits too, for a function of almost no code)
    for (int splits = 0; !queue.empty() && work > 0 && splits < 20000; ++splits) {
        auto [bound, b] = queue.top();
        if (!std::isfinite(bound)) {
            if (b.hi[0] - b.lo[0] + b.hi[1] - b.lo[1] + b.hi[2] - b.lo[2] <= 0) return std::nullopt;
        } else if (bound <= 1.1 * found) {
            return bound;
        }
        queue.pop();
        Box centre;
        for (size_t a = 0; a < 3; ++a) centre.lo[a] = centre.hi[a] = 0.5 * (b.lo[a] + b.hi[a]);
        Interval at = distance(centre);
        if (std::isfinite(at.hi)) found = std::max(found, -at.hi);
        size_t wide = 0;
        for (size_t a = 1; a < 3; ++a)
            if (b.hi[a] - b.lo[a] > b.hi[wide] - b.lo[wide]) wide = a;
        const double mid = 0.5 * (b.lo[wide] + b.hi[wide]);
        if (!(mid > b.lo[wide] && mid < b.hi[wide])) return std::isfinite(bound) ? std::optional<double>(bound) : std::nullopt;
        Box left = b, right = b;
        left.hi[wide] = mid;
        right.lo[wide] = mid;
        push(left);
        push(right);
    }
    if (queue.empty()) return 0.0;  // no point of the box is inside the solid
    double bound = queue.top().first;
    return std::isfinite(bound) ? std::optional<double>(bound) : std::nullopt;
}

}  // namespace iqc::ir
