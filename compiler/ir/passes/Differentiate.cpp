#include "ir/passes/Differentiate.h"

#include <fmt/format.h>
#include <map>

#include "ir/passes/Fold.h"
#include "ir/passes/Inline.h"
#include "source/Internal.h"
#include "sema/Builtins.h"

namespace iqc::ir {

namespace {

constexpr ValueId kZero = ValueId(-1);
// The tangent of a value without a derivative rule here. It spreads to whatever uses the value, except
// the arms of a lazy If/Switch, where it becomes a zero gradient (the runtime then falls back to
// differences for that arm only).
constexpr ValueId kPoison = ValueId(-2);

struct Unsupported {
    std::string why;
};

struct Differentiator {
    Function& g;
    std::vector<ValueId> primal;   // F's value -> G's value
    std::vector<ValueId> tangent;  // F's value -> G's tangent value, or kZero
    Module* module = nullptr;      // where a loop's tangent body goes
    // A Loop of F whose tangent is a loop of G carrying the states and their tangents: per state, the index
    // of its tangent in that loop's results (-1: an integer state, no tangent).
    std::map<size_t, std::vector<int>> loop_tangents;

    ValueId emit(Op op, Type t, std::vector<ValueId> args, int aux = 0) {
        Instr in;
        in.op = op;
        in.type = t;
        in.args = std::move(args);
        in.aux = aux;
        if (!t.valid()) internal_error(fmt::format("differentiate: invalid type for {}", op_name(op)));
        return g.add(std::move(in));
    }
    const Type& type(ValueId v) const { return g.body[v].type; }
    ValueId scalar(double x) { return g.scalar(x); }
    static Type tangent_type(const Type& t) {
        if (t.is_scalar()) return Type::vector(3);
        if (t.is_vector()) return Type::matrix(t.rows, 3);
        return {};
    }
    ValueId zero_of(const Type& tt) { return g.constant(tt, std::vector<double>(size_t(tt.components()), 0.0)); }
    // The tangent of primal value `v` (of type pt) as a value, materialising zeros.
    ValueId dense(ValueId t, const Type& pt) { return t == kZero ? zero_of(tangent_type(pt)) : t; }

    ValueId op2(Op op, ValueId a, ValueId b) { return emit(op, result_type(op, {type(a), type(b)}, 0), {a, b}); }
    ValueId add(ValueId a, ValueId b) {
        if (a == kZero) return b;
        if (b == kZero) return a;
        return op2(Op::Add, a, b);
    }
    ValueId sub(ValueId a, ValueId b) {
        if (b == kZero) return a;
        if (a == kZero) return emit(Op::Neg, type(b), {b});
        return op2(Op::Sub, a, b);
    }
    ValueId mul(ValueId a, ValueId b) {  // any IR product
        if (a == kZero || b == kZero) return kZero;
        return op2(Op::Mul, a, b);
    }
    ValueId builtin(const char* name, std::vector<ValueId> args) {
        int id = *find_builtin(name);
        std::vector<Type> ts;
        for (ValueId a : args) ts.push_back(type(a));
        return emit(Op::Builtin, check_builtin(id, ts).type, std::move(args), id);
    }
    // v ⊗ ∇s: the Jacobian of v·s's dependence through s (v ∈ ℝⁿ, ∇s ∈ ℝ³).
    ValueId outer(ValueId v, ValueId grad) {
        if (grad == kZero) return kZero;
        ValueId row = emit(Op::Transpose, Type::matrix(1, 3), {grad});
        return op2(Op::Mul, v, row);
    }
    // diag(v) J: row i of J scaled by v_i.
    ValueId scale_rows(ValueId v, ValueId J) {
        if (J == kZero) return kZero;
        int n = type(v).rows;
        std::vector<ValueId> rows;
        for (int i = 0; i < n; ++i) {
            ValueId vi = emit(Op::Extract, Type::scalar(), {v}, i);
            ValueId ri = emit(Op::Row, Type::vector(3), {J}, i);
            rows.push_back(op2(Op::Mul, vi, ri));
        }
        return emit(Op::Construct, Type::matrix(n, 3), rows);
    }
    // f'(x) applied to a tangent: scalar x -> f'·∇x; vector x -> diag(f') J.
    ValueId chain(ValueId fprime, ValueId x_primal, ValueId t) {
        if (t == kZero) return kZero;
        if (type(x_primal).is_scalar()) return op2(Op::Mul, fprime, t);
        return scale_rows(fprime, t);
    }
    // Component-wise choice between two tangents by a condition per component (min, max, clamp).
    ValueId select_rows(ValueId a, ValueId b, const Type& pt, CompareKind k, ValueId ta, ValueId tb) {
        if (ta == kZero && tb == kZero) return kZero;
        ValueId da = dense(ta, pt), db = dense(tb, pt);
        if (pt.is_scalar()) {
            ValueId c = emit(Op::Compare, Type::boolean(), {a, b}, int(k));
            return emit(Op::Select, Type::vector(3), {c, da, db});
        }
        std::vector<ValueId> rows;
        for (int i = 0; i < pt.rows; ++i) {  // a scalar operand stands for every component (clamp(v, 0, 1))
            ValueId ai = type(a).is_scalar() ? a : emit(Op::Extract, Type::scalar(), {a}, i);
            ValueId bi = type(b).is_scalar() ? b : emit(Op::Extract, Type::scalar(), {b}, i);
            ValueId c = emit(Op::Compare, Type::boolean(), {ai, bi}, int(k));
            rows.push_back(emit(Op::Select, Type::vector(3), {c, emit(Op::Row, Type::vector(3), {da}, i),
                                                              emit(Op::Row, Type::vector(3), {db}, i)}));
        }
        return emit(Op::Construct, Type::matrix(pt.rows, 3), rows);
    }
    ValueId elementwise_const(const Type& t, double x) {
        return t.is_scalar() ? scalar(x) : g.constant(t, std::vector<double>(size_t(t.components()), x));
    }

    ValueId rule(const Module& m, const Function& f, size_t i) {
        const Instr& in = f.body[i];
        auto P = [&](size_t k) { return primal[in.args[k]]; };
        auto T = [&](size_t k) { return tangent[in.args[k]]; };
        auto PT = [&](size_t k) { return f.body[in.args[k]].type; };
        // An element of a sequence the module computes element-wise (y_i = x_i - p, unrolled): its element's own.
        if (in.op == Op::Element && f.body[in.args[0]].op == Op::Construct && f.body[in.args[0]].type.is_array())
            return tangent[f.body[in.args[0]].args[size_t(in.aux)]];
        bool all_zero = true, poisoned = false;
        for (size_t k = 0; k < in.args.size(); ++k) {
            all_zero &= T(k) == kZero;
            poisoned |= T(k) == kPoison;
        }
        auto arm = [&](size_t k) { return T(k) == kPoison ? kZero : T(k); };
        if (poisoned && in.op != Op::If && in.op != Op::Switch) return kPoison;
        if (in.op != Op::Param && all_zero) return kZero;
        if (in.type.kind == Type::Integer) return kZero;  // integer values have no derivative
        auto no_rule = [&](const std::string& what) -> ValueId {
            throw Unsupported{fmt::format("{} depends on the query point", what)};
        };
        switch (in.op) {
            case Op::Const:
            case Op::Input:
            case Op::Compare:
            case Op::And:
            case Op::Or:
            case Op::Global:  // globals (sliders, per-instance data) do not depend on the query point
            case Op::IntDiv:  // ℤ
            case Op::IntMod:
            case Op::FloorInt:
                return kZero;
            case Op::If: {
                // The derivative of the arm taken, as lazy as the choice itself.
                Type pt = in.type;
                if (arm(1) == kZero && arm(2) == kZero) return kZero;
                return emit(Op::If, tangent_type(pt), {P(0), dense(arm(1), pt), dense(arm(2), pt)});
            }
            case Op::Switch: {
                Type pt = in.type;
                bool none = true;
                for (size_t k = 1; k < in.args.size(); ++k) none &= arm(k) == kZero;
                if (none) return kZero;
                std::vector<ValueId> a = {P(0)};
                for (size_t k = 1; k < in.args.size(); ++k) a.push_back(dense(arm(k), pt));
                ValueId v = emit(Op::Switch, tangent_type(pt), std::move(a));
                g.body[v].data = in.data;
                return v;
            }
            case Op::Param: return kZero;  // the query point is seeded by the caller
            case Op::Copy: return T(0);
            case Op::Add: return add(T(0), T(1));
            case Op::Sub: return sub(T(0), T(1));
            case Op::Neg: return emit(Op::Neg, type(T(0)), {T(0)});
            case Op::Mul: {
                const Type &a = PT(0), &b = PT(1);
                if (a.is_scalar() && b.is_scalar()) return add(mul(P(0), T(1)), mul(P(1), T(0)));
                if (a.is_scalar() && b.is_vector()) return add(outer(P(1), T(0)), mul(P(0), T(1)));
                if (a.is_vector() && b.is_scalar()) return add(outer(P(0), T(1)), mul(P(1), T(0)));
                if (a.is_matrix() && b.is_vector() && T(0) == kZero) return mul(P(0), T(1));
                return no_rule("a matrix product");
            }
            case Op::Div: {
                // (∂a·s - a ⊗ ∂s) / s²; ∂a/s where the divisor does not change (a weighted mean's ∑_j w_j: the
                // convex combinations of ir/Intervals.cpp read ∂a/s, and s·∂a/s² rounds twice)
                const Type& a = PT(0);
                ValueId s = P(1);
                if (T(1) == kZero) return T(0) == kZero ? kZero : op2(Op::Div, T(0), s);
                ValueId num = a.is_scalar() ? sub(mul(s, T(0)), mul(P(0), T(1))) : sub(mul(s, T(0)), outer(P(0), T(1)));
                if (num == kZero) return kZero;
                return op2(Op::Div, num, op2(Op::Mul, s, s));
            }
            case Op::Hadamard: return add(scale_rows(P(1), T(0)), scale_rows(P(0), T(1)));
            case Op::Dot: {
                ValueId r = kZero;
                if (T(0) != kZero) r = add(r, op2(Op::Mul, emit(Op::Transpose, Type::matrix(3, PT(0).rows), {T(0)}), P(1)));
                if (T(1) != kZero) r = add(r, op2(Op::Mul, emit(Op::Transpose, Type::matrix(3, PT(1).rows), {T(1)}), P(0)));
                return r;
            }
            case Op::Cross: {
                // d(a × b) = [a]× ∂b - [b]× ∂a, with [v]× the cross-product matrix of v.
                auto skew = [&](ValueId v) {
                    ValueId x = emit(Op::Extract, Type::scalar(), {v}, 0), y = emit(Op::Extract, Type::scalar(), {v}, 1),
                            z = emit(Op::Extract, Type::scalar(), {v}, 2);
                    ValueId o = scalar(0);
                    auto neg = [&](ValueId s) { return emit(Op::Neg, Type::scalar(), {s}); };
                    return emit(Op::Construct, Type::matrix(3, 3), {o, neg(z), y, z, o, neg(x), neg(y), x, o});
                };
                return sub(mul(skew(P(0)), T(1)), mul(skew(P(1)), T(0)));
            }
            case Op::Transpose:
            case Op::Inverse:
            case Op::Det:
                return no_rule("a matrix");
            case Op::Index:  // (an array that depends on the query point: no rule, below)
                return no_rule("a sequence read at a loop's index");
            case Op::Construct: {
                if (in.type.is_matrix()) return no_rule("a matrix");
                // A sequence of values that depend on it (y_i = x_i - p as an array): its elements read whole have
                // no rule (Element reads of it take their element's tangent, above). The Jacobian's rows below are
                // a vector's: an array of 32 vectors made a 3×3 matrix of 96 rows (a heap overflow when folded).
                if (in.type.is_array()) return no_rule("a sequence read whole (an array)");
                std::vector<ValueId> rows;
                for (size_t k = 0; k < in.args.size(); ++k) {
                    const Type& t = PT(k);
                    if (t.is_scalar()) {
                        rows.push_back(dense(T(k), t));
                    } else {
                        ValueId J = dense(T(k), t);
                        for (int r = 0; r < t.rows; ++r) rows.push_back(emit(Op::Row, Type::vector(3), {J}, r));
                    }
                }
                return emit(Op::Construct, Type::matrix(in.type.rows, 3), rows);
            }
            case Op::Extract:
                if (PT(0).is_vector()) return emit(Op::Row, Type::vector(3), {T(0)}, in.aux);
                return no_rule("a matrix");
            case Op::Row:
            case Op::Column:
                return no_rule("a matrix");
            case Op::Select: {
                Type pt = in.type;
                return emit(Op::Select, tangent_type(pt), {P(0), dense(T(1), pt), dense(T(2), pt)});
            }
            case Op::Builtin: {
                const BuiltinInfo& b = iqc::builtin(in.aux);
                std::string n = b.name;
                const Type& t = in.type;
                ValueId x = P(0), r = primal[i];
                auto one = [&] { return elementwise_const(PT(0), 1.0); };
                auto sq = [&](ValueId v) { return op2(t.is_scalar() ? Op::Mul : Op::Hadamard, v, v); };
                auto recip = [&](ValueId v) {  // 1 / v, elementwise
                    if (t.is_scalar()) return op2(Op::Div, scalar(1), v);
                    std::vector<ValueId> c;
                    for (int k = 0; k < t.rows; ++k)
                        c.push_back(op2(Op::Div, scalar(1), emit(Op::Extract, Type::scalar(), {v}, k)));
                    return emit(Op::Construct, t, c);
                };
                if (n == "sin") return chain(builtin("cos", {x}), x, T(0));
                if (n == "cos") return chain(emit(Op::Neg, t, {builtin("sin", {x})}), x, T(0));
                if (n == "tan") return chain(op2(Op::Add, one(), sq(r)), x, T(0));
                if (n == "asin") return chain(recip(builtin("sqrt", {op2(Op::Sub, one(), sq(x))})), x, T(0));
                if (n == "acos") return chain(emit(Op::Neg, t, {recip(builtin("sqrt", {op2(Op::Sub, one(), sq(x))}))}), x, T(0));
                if (n == "atan") return chain(recip(op2(Op::Add, one(), sq(x))), x, T(0));
                if (n == "sinh") return chain(builtin("cosh", {x}), x, T(0));
                if (n == "cosh") return chain(builtin("sinh", {x}), x, T(0));
                if (n == "tanh") return chain(op2(Op::Sub, one(), sq(r)), x, T(0));
                if (n == "exp") return chain(r, x, T(0));
                if (n == "log" || n == "ln") return chain(recip(x), x, T(0));
                // log₂ x = ln x / ln 2, log₁₀ x = ln x / ln 10
                if (n == "log_2" || n == "log_10")
                    return chain(op2(Op::Mul, scalar(1 / std::log(n == "log_2" ? 2.0 : 10.0)), recip(x)), x, T(0));
                if (n == "sqrt") {
                    // 1 / (2√x), guarded at 0 (the derivative's limit is infinite; a huge finite slope keeps
                    // the normal's direction)
                    ValueId safe = builtin("max", {r, elementwise_const(t, 1e-12)});
                    return chain(recip(op2(t.is_scalar() ? Op::Mul : Op::Mul, scalar(2), safe)), x, T(0));
                }
                if (n == "abs") return chain(builtin("sign", {x}), x, T(0));
                if (n == "floor" || n == "ceil" || n == "sign" || n == "step" || n == "round") return kZero;
                if (n == "fract") return T(0);
                if (n == "mod") {
                    // mod(x, y) = x - y⌊x/y⌋: ∂x - ⌊x/y⌋∂y (a constant modulus, a repetition's, leaves ∂x).
                    if (T(1) == kZero) return T(0);
                    ValueId fl = builtin("floor", {op2(Op::Div, x, P(1))});
                    if (PT(1).is_vector() && !t.is_scalar() && PT(1).rows != t.rows) return no_rule("mod by a vector of another size");
                    ValueId dy = t.is_scalar() ? mul(fl, T(1)) : PT(1).is_scalar() ? outer(fl, T(1)) : scale_rows(fl, T(1));
                    return sub(dense(T(0), t), dy);
                }
                if (n == "min" || n == "max") {
                    // At a tie, the first argument's derivative (a subgradient; never 0 where both sides have one).
                    CompareKind k = n == "min" ? CompareKind::Le : CompareKind::Ge;
                    return select_rows(P(0), P(1), t, k, T(0), T(1));
                }
                if (n == "pow") {
                    if (T(1) != kZero) {
                        // d(a^b) = b a^(b-1) ∂a + a^b ln(a) ∂b (a > 0)
                        if (!t.is_scalar()) return no_rule("a vector power with a varying exponent");
                        ValueId da = T(0) == kZero ? kZero
                                                   : mul(op2(Op::Mul, P(1), builtin("pow", {x, op2(Op::Sub, P(1), scalar(1))})), T(0));
                        return add(da, mul(op2(Op::Mul, r, builtin("log", {x})), T(1)));
                    }
                    ValueId e1 = op2(Op::Sub, P(1), elementwise_const(PT(1), 1.0));
                    return chain(op2(t.is_scalar() ? Op::Mul : Op::Hadamard, P(1), builtin("pow", {x, e1})), x, T(0));
                }
                if (n == "atan2") {
                    // (x ∂y - y ∂x) / (x² + y²), scalars
                    if (!t.is_scalar()) return no_rule("atan2 of vectors");
                    ValueId y = P(0), xx = P(1);
                    ValueId num = sub(mul(xx, T(0)), mul(y, T(1)));
                    ValueId den = builtin("max", {op2(Op::Add, op2(Op::Mul, xx, xx), op2(Op::Mul, y, y)), scalar(1e-30)});
                    return op2(Op::Div, num, den);
                }
                if (n == "smoothstep") {
                    // 6t(1 - t)/(e1 - e0) ∂x inside the edges (constant edges)
                    if (!t.is_scalar() || T(0) != kZero || T(1) != kZero) return no_rule("smoothstep with varying edges");
                    ValueId w = op2(Op::Sub, P(1), P(0));
                    ValueId tt = builtin("clamp", {op2(Op::Div, op2(Op::Sub, P(2), P(0)), w), scalar(0), scalar(1)});
                    ValueId d = op2(Op::Div, op2(Op::Mul, scalar(6), op2(Op::Mul, tt, op2(Op::Sub, scalar(1), tt))), w);
                    return mul(d, T(2));
                }
                if (n == "clamp") {
                    // min(max(x, lo), hi), as the evaluator computes it (and GPUs do; GLSL leaves lo > hi undefined),
                    // per component: m = max(x, lo) picks ∂x or ∂lo, then min(m, hi) picks ∂m or ∂hi. Quilez's
                    // elongation clamps the query point. A scalar bound of a vector x that varies has no tangent of
                    // x's shape.
                    if (!t.is_scalar() && ((PT(1).is_scalar() && T(1) != kZero) || (PT(2).is_scalar() && T(2) != kZero)))
                        return no_rule("clamp of a vector between varying scalars");
                    ValueId m = builtin("max", {P(0), P(1)});
                    ValueId dm = select_rows(P(0), P(1), t, CompareKind::Ge, T(0), T(1));
                    return select_rows(m, P(2), t, CompareKind::Le, dm, T(2));
                }
                if (n == "mix") {
                    // (1 - s) ∂a + s ∂b + (b - a) ⊗ ∂s
                    const Type& st = PT(2);
                    if (!st.is_scalar() && !t.is_scalar()) {
                        // a weight per component (mix(p, 2p, 0.3) broadcasts 0.3): each row of the Jacobians is
                        // scaled by its own weight, diag(1 - s) ∂a + diag(s) ∂b + diag(b - a) ∂s
                        auto diag = [&](ValueId v) {
                            std::vector<ValueId> parts;
                            for (int i = 0; i < t.rows; ++i)
                                for (int j = 0; j < t.rows; ++j)
                                    parts.push_back(i == j ? emit(Op::Extract, Type::scalar(), {v}, i) : scalar(0));
                            return emit(Op::Construct, Type::matrix(t.rows, t.rows), std::move(parts));
                        };
                        ValueId s = P(2), one_minus = op2(Op::Sub, g.constant(st, std::vector<double>(size_t(st.rows), 1.0)), s);
                        ValueId r1 = add(T(0) == kZero ? kZero : mul(diag(one_minus), T(0)), T(1) == kZero ? kZero : mul(diag(s), T(1)));
                        return add(r1, T(2) == kZero ? kZero : mul(diag(op2(Op::Sub, P(1), P(0))), T(2)));
                    }
                    ValueId s = P(2), one_minus = op2(Op::Sub, scalar(1), s);
                    ValueId r1 = add(mul(one_minus, T(0)), mul(s, T(1)));
                    ValueId diff = op2(Op::Sub, P(1), P(0));
                    return add(r1, t.is_scalar() ? mul(diff, T(2)) : outer(diff, T(2)));
                }
                if (n == "length") {
                    // Jᵀ (v / ‖v‖) (0 at v = 0): the unit vector first, so that bounds of the result see it
                    ValueId Jt = emit(Op::Transpose, Type::matrix(3, PT(0).rows), {T(0)});
                    ValueId safe = builtin("max", {r, scalar(1e-30)});
                    return op2(Op::Mul, Jt, op2(Op::Div, x, safe));
                }
                if (n == "normalize") {
                    // (J - n ⊗ (Jᵀ n)) / ‖v‖
                    ValueId len = builtin("max", {builtin("length", {x}), scalar(1e-30)});
                    ValueId Jt = emit(Op::Transpose, Type::matrix(3, PT(0).rows), {T(0)});
                    ValueId proj = outer(r, op2(Op::Mul, Jt, r));
                    return op2(Op::Div, op2(Op::Sub, T(0), proj), len);
                }
                return no_rule(fmt::format("the built-in '{}'", n));
            }
            case Op::Call: return no_rule("a call");  // inlined before
            case Op::Element:
            case Op::At:
                return no_rule("an element of a sequence");
            case Op::Loop: return loop_rule(f, i);
            case Op::Member: {
                auto it = loop_tangents.find(in.args[0]);
                if (it == loop_tangents.end() || it->second[size_t(in.aux)] < 0) return kZero;
                return emit(Op::Member, tangent_type(in.type), {T(0)}, it->second[size_t(in.aux)]);
            }
        }
        return no_rule("an operation");
    }

    // The tangent rule of a recurrence (forward mode through a loop): a loop of G that carries each state and
    // its tangent, whose body is the original body with its tangents (this rule, applied to the body, seeded
    // with the tangents of the states and of the captured values). Its value stands for the loop's tangent;
    // Member picks a state's tangent from it.
    ValueId loop_rule(const Function& f, size_t i) {
        const Instr& in = f.body[i];
        if (!module) throw Unsupported{"a recurrence (its loop) depends on the query point"};
        const Function body = inline_calls(*module, module->functions[size_t(in.aux)]);
        const int S = int(body.outputs.size());
        const int C = int(in.args.size()) - 1 - S;
        std::vector<int> state_tangent(size_t(S), -1), capture_tangent(size_t(C), -1);
        std::vector<Type> state_types;
        int T = 0, TC = 0;
        for (int j = 0; j < S; ++j) {
            const Type& t = f.body[in.args[size_t(1 + j)]].type;
            state_types.push_back(t);
            if (t.kind == Type::Integer) continue;
            if (!tangent_type(t).valid()) throw Unsupported{"a recurrence of matrices depends on the query point"};
            state_tangent[size_t(j)] = S + T++;
        }
        for (int c = 0; c < C; ++c) {
            ValueId t = tangent[in.args[size_t(1 + S + c)]];
            if (t != kZero) capture_tangent[size_t(c)] = TC++;
        }
        // The body: params (k, states, state tangents, captures, capture tangents).
        Function b2;
        b2.name = body.name + ".tangent";
        b2.glsl_name = body.glsl_name + "_tangent";
        b2.params.push_back(body.params[0]);
        for (int j = 0; j < S; ++j) b2.params.push_back(body.params[size_t(1 + j)]);
        for (int j = 0; j < S; ++j)
            if (state_tangent[size_t(j)] >= 0) b2.params.push_back({"d_" + body.params[size_t(1 + j)].name, tangent_type(state_types[size_t(j)])});
        for (int c = 0; c < C; ++c) b2.params.push_back(body.params[size_t(1 + S + c)]);
        for (int c = 0; c < C; ++c)
            if (capture_tangent[size_t(c)] >= 0)
                b2.params.push_back({"d_" + body.params[size_t(1 + S + c)].name, type(tangent[in.args[size_t(1 + S + c)]])});
        Differentiator d{b2, std::vector<ValueId>(body.body.size()), std::vector<ValueId>(body.body.size(), kZero), module, {}};
        auto param = [&](int index) {
            Instr p;
            p.op = Op::Param;
            p.type = b2.params[size_t(index)].type;
            p.aux = index;
            p.name = b2.params[size_t(index)].name;
            return b2.add(std::move(p));
        };
        for (size_t k = 0; k < body.body.size(); ++k) {
            const Instr& bin = body.body[k];
            if (bin.op == Op::Param) {
                int a = bin.aux;
                if (a <= S) {  // k or a state
                    d.primal[k] = param(a);
                    if (a >= 1 && state_tangent[size_t(a - 1)] >= 0) d.tangent[k] = param(1 + S + (state_tangent[size_t(a - 1)] - S));
                } else {  // a capture
                    int c = a - 1 - S;
                    d.primal[k] = param(1 + S + T + c);
                    if (capture_tangent[size_t(c)] >= 0) d.tangent[k] = param(1 + S + T + C + capture_tangent[size_t(c)]);
                }
                continue;
            }
            Instr copy = bin;
            for (ValueId& a : copy.args) a = d.primal[a];
            d.primal[k] = b2.add(std::move(copy));
            d.tangent[k] = d.rule(*module, body, k);  // Unsupported propagates: the loop has no tangent
            if (d.tangent[k] == kPoison) throw Unsupported{"a recurrence whose step has no derivative rule"};
        }
        for (int j = 0; j < S; ++j) b2.outputs.push_back({body.outputs[size_t(j)].first, d.primal[body.outputs[size_t(j)].second]});
        for (int j = 0; j < S; ++j) {
            if (state_tangent[size_t(j)] < 0) continue;
            ValueId t = d.tangent[body.outputs[size_t(j)].second];
            // A dense zero tangent is a constant in the body.
            ValueId dt = t == kZero ? d.zero_of(tangent_type(state_types[size_t(j)])) : t;
            b2.outputs.push_back({"d_" + body.outputs[size_t(j)].first, dt});
        }
        b2.result = b2.outputs[0].second;
        int fn = int(module->functions.size());
        module->functions.push_back(std::move(b2));
        // The loop: hi, states, their tangents, captures, their tangents.
        std::vector<ValueId> args = {primal[in.args[0]]};
        for (int j = 0; j < S; ++j) args.push_back(primal[in.args[size_t(1 + j)]]);
        for (int j = 0; j < S; ++j)
            if (state_tangent[size_t(j)] >= 0) args.push_back(dense(tangent[in.args[size_t(1 + j)]], state_types[size_t(j)]));
        for (int c = 0; c < C; ++c) args.push_back(primal[in.args[size_t(1 + S + c)]]);
        for (int c = 0; c < C; ++c)
            if (capture_tangent[size_t(c)] >= 0) args.push_back(tangent[in.args[size_t(1 + S + c)]]);
        Instr loop;
        loop.op = Op::Loop;
        loop.type = Type::tuple(S + T);
        loop.args = std::move(args);
        loop.aux = fn;
        loop.data = in.data;
        loop.source = in.source;
        ValueId lv = g.add(std::move(loop));
        loop_tangents[i] = state_tangent;
        return lv;
    }
};

}  // namespace

int differentiate(Module& m, int fn, int wrt_param, const std::string& name, std::string* why,
                  std::vector<std::pair<Span, std::string>>* fallbacks) {
    Function f = inline_calls(m, m.functions[size_t(fn)]);
    Function g;
    g.name = name;
    g.glsl_name = name;
    g.params = f.params;
    g.param_bounds = f.param_bounds;
    Differentiator d{g, std::vector<ValueId>(f.body.size()), std::vector<ValueId>(f.body.size(), kZero), &m, {}};
    std::vector<std::pair<Span, std::string>> missing;
    for (size_t i = 0; i < f.body.size(); ++i) {
        const Instr& in = f.body[i];
        Instr c = in;
        for (ValueId& a : c.args) a = d.primal[a];
        // A state of a loop that has a tangent loop: that loop's (it carries the states first), so that a value and
        // its tangent come from one loop (∑_i e_i and ∑_i e_i ∇x_i: the convex combinations of ir/Intervals.cpp).
        if (in.op == Op::Member && d.loop_tangents.count(in.args[0]) && d.tangent[in.args[0]] != kZero &&
            d.tangent[in.args[0]] != kPoison && g.body[d.tangent[in.args[0]]].op == Op::Loop)
            c.args[0] = d.tangent[in.args[0]];
        d.primal[i] = g.add(std::move(c));
        if (in.op == Op::Param && in.aux == wrt_param) {
            d.tangent[i] = g.constant(Type::matrix(3, 3), {1, 0, 0, 0, 1, 0, 0, 0, 1});
            continue;
        }
        try {
            d.tangent[i] = d.rule(m, f, i);
        } catch (const Unsupported& u) {
            d.tangent[i] = kPoison;
            missing.push_back({in.span, u.why});
        }
    }
    ValueId r = d.tangent[f.result];
    if (r == kPoison) {
        if (why) *why = missing.empty() ? "no derivative rule" : missing.front().second;
        return -1;
    }
    if (fallbacks) *fallbacks = std::move(missing);
    if (r == kZero) r = g.constant(Type::vector(3), {0, 0, 0});
    g.result = r;
    // The seed is the identity: fold it away (and what it makes constant).
    fold_constants(m, g);
    m.functions.push_back(std::move(g));
    return int(m.functions.size() - 1);
}

}  // namespace iqc::ir
