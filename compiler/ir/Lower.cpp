#include "ir/Lower.h"

#include <cmath>
#include <functional>
#include <optional>
#include <set>
#include <fmt/format.h>

#include "ir/Eval.h"
#include "sema/Builtins.h"
#include "source/Internal.h"

namespace iqc {

using namespace ast;
using ir::Instr;
using ir::Op;
using ir::ValueId;

namespace {

int lower_local_function(const CheckedModule& m, int fi, const std::vector<Type>& arg_types, LowerContext& ctx);
}  // namespace
int lower_module_cached(const CheckedModule& m, LowerContext& ctx);
namespace {

// f(child) for each operand of x: its arguments, a piecewise's or a matrix's rows, the `otherwise` case.
template <typename F>
void for_each_child(const Expr& x, F&& f) {
    for (const auto& a : x.args) f(*a);
    for (const auto& r : x.rows)
        for (const auto& a : r) f(*a);
    if (x.otherwise) f(*x.otherwise);
}

ValueId add_param(ir::Function& f, const std::string& name, Type t, Span span = {});

struct Env {
    const CheckedModule& m;
    LowerContext& ctx;
    ir::Function& f;
    std::vector<ValueId> params;                 // module parameters (module body)
    std::map<std::string, ValueId> values;       // assigned names
    std::vector<ValueId> locals;                 // local function parameters
    std::vector<ValueId> captures;               // local function captures
    const LocalFunction* fn = nullptr;           // when lowering a local function
    std::map<std::string, int> sum_index;        // ∑ indices being unrolled -> current 0-based value
    // ∑ indices of rolled sums (this environment lowers a Loop's body): the 0-based index, ℤ. A body of a
    // rolled sum (sum_body) reads everything else from its parent, as a capture.
    std::map<std::string, ValueId> rolled;
    bool sum_body = false;
    // Sequences: final and first values (module level); in a recurrence body, the parent environment,
    // the loop index and current states, and outer values captured as extra body parameters.
    std::map<int, ValueId> seq_first, seq_last;
    Env* parent = nullptr;
    ValueId loop_index = 0;
    std::map<int, ValueId> seq_current;
    std::map<ValueId, ValueId> captured;  // parent value -> body parameter
    std::vector<ValueId> capture_args;    // parent values, in parameter order

    Env(const CheckedModule& m, LowerContext& ctx, ir::Function& f) : m(m), ctx(ctx), f(f) {}

    ValueId capture(ValueId outer) {
        if (auto it = captured.find(outer); it != captured.end()) return it->second;
        const Instr& oi = parent->f.body[outer];
        f.params.push_back({oi.name.empty() ? fmt::format("c{}", captured.size()) : oi.name, oi.type});
        Instr in;
        in.op = Op::Param;
        in.type = oi.type;
        in.aux = int(f.params.size() - 1);
        in.name = f.params.back().name;
        ValueId v = f.add(std::move(in));
        captured[outer] = v;
        capture_args.push_back(outer);
        return v;
    }

    void lower_group(const LoopGroup& g);

    // The ℤ index (0-based) of a rolled ∑ named `index`, as seen here; none where it is unrolled (a constant).
    std::optional<ValueId> rolled_index(const std::string& index) {
        if (auto it = rolled.find(index); it != rolled.end()) return it->second;
        if (sum_index.count(index) || !sum_body) return std::nullopt;
        if (auto v = parent->rolled_index(index)) return capture(*v);
        return std::nullopt;
    }

    ValueId emit(Op op, Type t, std::vector<ValueId> args, int aux = 0, Span span = {}) {
        Instr in;
        in.op = op;
        in.type = t;
        in.args = std::move(args);
        in.aux = aux;
        in.span = span;
        return f.add(std::move(in));
    }
    const Type& type_of(ValueId v) const { return f.body[v].type; }

    // Types come from the operands, not from the AST: a local function with symbolic sizes (ℝ^n) is
    // lowered once per use with other sizes, and the checker's annotations are those of its last use.
    ValueId op2(Op op, ValueId a, ValueId b, Span span) {
        Type t = ir::result_type(op, {type_of(a), type_of(b)}, 0);
        if (!t.valid()) internal_error(std::string("lowering: operand types do not fit ") + ir::op_name(op));
        return emit(op, t, {a, b}, 0, span);
    }
    static Type scalar_or(const Type& t) { return t.is_scalar() ? Type::scalar() : t; }

    // A scalar operand widened to `t` (a vector), for built-ins whose GLSL overloads need equal types.
    ValueId broadcast(ValueId v, const Type& t) {
        if (!t.is_vector() || !type_of(v).is_scalar()) return v;
        return emit(Op::Construct, t, std::vector<ValueId>(size_t(t.rows), v));
    }

    // The value of a name that a local function captures, as seen from this environment.
    ValueId lookup_capture(const std::string& name) {
        if (parent) return capture(parent->lookup_capture(name));
        if (fn)
            for (size_t i = 0; i < fn->captures.size(); ++i)
                if (fn->captures[i].first == name) return captures[i];
        if (int pi = m.find_param(name); pi >= 0) return params[size_t(pi)];
        auto it = values.find(name);
        if (it == values.end()) internal_error("lowering: captured name '" + name + "' has no value");
        return it->second;
    }

    // The range of ∑_index: the size of what it subscripts (the checker made sure all uses agree).
    // The type of a subscripted base, for a sum's range: a value the module assigned is typed where it was
    // assigned, without lowering it here (in a recurrence's body that captured it: an element-wise sequence built
    // from p, y_i = x_i - p, captured whole left the recurrence without a derivative, though each term reads its
    // element's expression).
    Type base_type(const Expr& x) {
        if (x.kind == ExprKind::Name && x.resolved == R_Value && parent) {
            const Env* root = this;
            while (root->parent) root = root->parent;
            if (auto it = root->values.find(x.text); it != root->values.end()) return root->f.body[it->second].type;
        }
        return type_of(lower(x));
    }

    int sum_range(const Expr& body, const std::string& index) {
        int n = 0;
        std::function<void(const Expr&)> walk = [&](const Expr& x) {
            if (x.kind == ExprKind::Index && x.resolved == R_None)
                for (size_t k = 0; k < x.indices.size(); ++k) {
                    const auto& it = x.indices[k];
                    if (!it.expr || it.expr->kind != ExprKind::Name || it.expr->text != index) continue;
                    Type t = base_type(*x.args[0]);
                    size_t pos = k;
                    if (t.is_array() && k > 0) t = t.element(), pos = k - 1;  // x_i,j: a component of an element
                    if (t.is_array()) n = t.count;
                    else if (t.is_vector()) n = t.rows;
                    else if (t.is_matrix()) n = pos == 0 ? t.rows : t.cols;
                }
            for_each_child(x, walk);
        };
        walk(body);
        return n;
    }
    // A ∑'s count: its summand's, else its condition's (∑_(i for w_i > 0.5) 1/w_(i+1), as the checker reads it).
    int sum_count(const Expr& sum) {
        int n = sum_range(*sum.args[0], sum.text);
        if (n == 0 && sum.args.size() > 1) n = sum_range(*sum.args[1], sum.text);
        return n;
    }

    // x^c. A whole constant exponent up to 16 in size is multiplied out (repeated squaring: x⁵ = (x²)²·x):
    // exact for a negative base, which GLSL's pow leaves undefined (NaN on most GPUs) even for whole exponents —
    // (1 - v)⁵ with v a dot product of unit vectors that rounding lifts just past 1 (Schlick's Fresnel) was NaN.
    ValueId power(ValueId base, const Expr& ex, Span span) {
        auto c = const_eval(ex);
        if (c && c->size() == 1 && std::fabs((*c)[0]) <= 16 && (*c)[0] == std::floor((*c)[0])) {
            int n = int((*c)[0]);
            if (n == 0) return f.scalar(1.0);
            ValueId r = ValueId(-1), square = base;
            for (int k = std::abs(n);;) {
                if (k & 1) r = r == ValueId(-1) ? square : emit(Op::Mul, Type::scalar(), {r, square}, 0, span);
                k >>= 1;
                if (!k) break;
                square = emit(Op::Mul, Type::scalar(), {square, square}, 0, span);
            }
            if (n < 0) r = emit(Op::Div, Type::scalar(), {f.scalar(1.0), r}, 0, span);
            return r;
        }
        ValueId e = lower(ex);
        return builtin("pow", {base, e}, span);
    }

    ValueId builtin(const char* name, std::vector<ValueId> args, Span span) {
        return builtin_id(*find_builtin(name), std::move(args), span);
    }

    ValueId builtin_id(int id, std::vector<ValueId> args, Span span) {
        const BuiltinInfo& b = iqc::builtin(id);
        if (b.sig == Sig::Nary && args.size() > 2) {
            ValueId acc = builtin_id(id, {args[0], args[1]}, span);
            for (size_t i = 2; i < args.size(); ++i) acc = builtin_id(id, {acc, args[i]}, span);
            return acc;
        }
        if (b.sig == Sig::Elementwise1 && type_of(args[0]).is_matrix()) {
            // sin(A) entry by entry: row by row (GLSL's functions take vectors, not matrices).
            const Type t = type_of(args[0]);
            std::vector<ValueId> rows;
            for (int r = 0; r < t.rows; ++r)
                rows.push_back(builtin_id(id, {emit(Op::Row, Type::vector(t.cols), {args[0]}, r, span)}, span));
            return emit(Op::Construct, t, std::move(rows), 0, span);
        }
        if (b.sig == Sig::Elementwise2 || b.sig == Sig::Nary || b.sig == Sig::Clamp || b.sig == Sig::Mix) {
            Type common = Type::scalar();
            for (ValueId a : args)
                if (type_of(a).is_vector()) common = type_of(a);
            if (common.is_vector())
                for (auto& a : args) a = broadcast(a, common);
        }
        std::vector<Type> ts;
        for (ValueId a : args) ts.push_back(type_of(a));
        Type t = check_builtin(id, ts).type;
        return emit(Op::Builtin, t, std::move(args), id, span);
    }

    // The linear algebra module's functions, in terms of the IR's own operations.
    ValueId linear_algebra(int id, ValueId a, Span span) {
        const Type t = type_of(a);
        switch (iqc::builtin(id).sig) {
            case Sig::Det: return emit(Op::Det, Type::scalar(), {a}, 0, span);
            case Sig::Inverse: return emit(Op::Inverse, t, {a}, 0, span);
            case Sig::Trace: {
                ValueId acc = emit(Op::Extract, Type::scalar(), {a}, 0, span);
                for (int i = 1; i < t.rows; ++i)
                    acc = emit(Op::Add, Type::scalar(), {acc, emit(Op::Extract, Type::scalar(), {a}, i * t.cols + i, span)}, 0, span);
                return acc;
            }
            case Sig::Diag: {
                std::vector<ValueId> items;
                if (t.is_vector()) {
                    ValueId zero = f.scalar(0);
                    for (int r = 0; r < t.rows; ++r)
                        for (int c = 0; c < t.rows; ++c)
                            items.push_back(r == c ? emit(Op::Extract, Type::scalar(), {a}, r, span) : zero);
                    return emit(Op::Construct, Type::matrix(t.rows, t.rows), std::move(items), 0, span);
                }
                for (int i = 0; i < t.rows; ++i) items.push_back(emit(Op::Extract, Type::scalar(), {a}, i * t.cols + i, span));
                return emit(Op::Construct, Type::vector(t.rows), std::move(items), 0, span);
            }
            case Sig::Vec: {  // the columns, one after the other
                std::vector<ValueId> cols;
                for (int c = 0; c < t.cols; ++c) cols.push_back(emit(Op::Column, Type::vector(t.rows), {a}, c, span));
                return emit(Op::Construct, Type::vector(t.rows * t.cols), std::move(cols), 0, span);
            }
            default: throw std::logic_error("lowering: not a linear algebra function");
        }
    }

    // The value of `v` when it depends on constants only (a sum's condition on its index), else nullopt.
    std::optional<std::vector<double>> constant_value(ValueId v) {
        const Instr& in = f.body[v];
        if (in.op == Op::Const) return in.data;
        if (in.op == Op::Param || in.op == Op::Input || in.op == Op::Call || in.op == Op::Loop || in.op == Op::Member)
            return std::nullopt;
        std::vector<ir::Value> vals;
        for (ValueId a : in.args) {
            auto c = constant_value(a);
            if (!c) return std::nullopt;
            vals.push_back({type_of(a), *c});
        }
        std::vector<const ir::Value*> ptrs;
        for (auto& x : vals) ptrs.push_back(&x);
        return ir::eval_instr(ctx.module, f, in, ptrs).v;
    }

    // [a b; c d]: element by element, row-major, from the blocks (sized by the checker).
    ValueId matrix_literal(const Expr& e) {
        std::vector<std::vector<ValueId>> blocks;
        for (auto& row : e.rows) {
            blocks.emplace_back();
            for (auto& a : row)
                blocks.back().push_back(a->resolved == R_BlockZero || a->resolved == R_BlockOnes ||
                                                a->resolved == R_BlockIdentity
                                            ? ValueId(-1)
                                            : lower(*a));
        }
        std::vector<ValueId> items;
        ValueId zero = ValueId(-1), one = ValueId(-1);
        auto konst = [&](double v) {
            ValueId& slot = v == 0 ? zero : one;
            if (slot == ValueId(-1)) slot = f.scalar(v);
            return slot;
        };
        for (size_t br = 0; br < e.rows.size(); ++br)
            for (int i = 0; i < e.block_rows[br]; ++i)
                for (size_t bc = 0; bc < e.rows[br].size(); ++bc)
                    for (int j = 0; j < e.block_cols[bc]; ++j) {
                        const Expr& item = *e.rows[br][bc];
                        ValueId v = blocks[br][bc];
                        if (item.resolved == R_BlockZero) items.push_back(konst(0));
                        else if (item.resolved == R_BlockOnes) items.push_back(konst(1));
                        else if (item.resolved == R_BlockIdentity) items.push_back(konst(i == j ? 1 : 0));
                        else if (type_of(v).is_scalar()) items.push_back(v);
                        else if (type_of(v).is_vector()) items.push_back(emit(Op::Extract, Type::scalar(), {v}, i, item.span));
                        else items.push_back(emit(Op::Extract, Type::scalar(), {v}, i * type_of(v).cols + j, item.span));
                    }
        if (items.size() == 1) return items[0];
        int R = 0, C = 0;
        for (int h : e.block_rows) R += h;
        for (int w : e.block_cols) C += w;
        return emit(Op::Construct, C == 1 ? Type::vector(R) : Type::matrix(R, C), std::move(items), 0, e.span);
    }

    // The module's element-wise definition of a sequence named by x (y_i = 2x_i + (1, 0, 0): one index letter,
    // elements that are vectors or matrices, an array), else null.
    const Stmt* elementwise_sequence(const Expr& x) const {
        if (x.kind != ExprKind::Name || x.resolved != R_Value) return nullptr;
        for (const Stmt* s : m.order)
            if (s->kind == StmtKind::Assign && s->name == x.text && s->elem_indices.size() == 1 && s->value) return s;
        return nullptr;
    }

    // Whether ∑_index body can be a loop: the index subscripts only sequences (x_i, x_i,1: an array's element,
    // then maybe a component) or is a number (i), and no sum inside reuses the letter.
    bool rollable(const Expr& body, const std::string& index) {
        bool ok = true;
        std::function<void(const Expr&)> walk = [&](const Expr& x) {
            if (!ok || (x.kind == ExprKind::Sum && x.text == index)) return;  // (a sum inside with the letter: its own)
            if (x.kind == ExprKind::Index && x.resolved == R_None)
                for (size_t k = 0; k < x.indices.size(); ++k) {
                    const auto& it = x.indices[k];
                    if (!it.expr || it.expr->kind != ExprKind::Name || it.expr->text != index) continue;
                    // (a sequence the module computes, y_i = 2x_i + …, is an array built where it is defined: a loop
                    // over it kept it built whole per evaluation, 12 s a frame against 0.17 s with the sum written
                    // out on webgl2; unrolled, each term reads its element's expression)
                    if (k != 0) {
                        ok = false;
                    } else if (const Stmt* def = elementwise_sequence(*x.args[0])) {
                        // Its definition's expression, read with the loop's index (index()): rollable as that is. (Not
                        // lowered here: inside a recurrence that captured the whole array, built from p, and the
                        // recurrence had no derivative.)
                        if (!rollable(*def->value, def->elem_indices[0].first)) ok = false;
                    } else if (ValueId base = lower(*x.args[0]); !type_of(base).is_array() || f.body[base].op == Op::Construct) {
                        ok = false;
                    }
                }
            for_each_child(x, walk);
        };
        walk(body);
        return ok;
    }

    // ∑_i e over n ≥ kRolledSum elements of sequences: a Loop whose body adds term i to the sum, as one writes it
    // by hand. Unrolled, Mesa's compile grew faster than the terms: a sum of 100 lengths of a uniform array's
    // elements took llvmpipe 2.5 s (0.17 s as a loop), three instances of 300 took 50 s.
    // Where parameters are constants (Shadertoy) the driver folds a sequence's values into an unrolled sum's
    // code: 3x faster frames (40 distances to points, 1.6 against 6.6 ms), at an equal first-frame compile, so
    // there a sum is rolled only past kRolledConstantSum terms, to bound the code.
    static constexpr int kRolledSum = 32, kRolledConstantSum = 256;
    ValueId rolled_sum(const Expr& e, int n) {
        ir::Function body;
        body.name = f.name + ".sum_" + e.text;
        for (int k = 2; ctx.module.find(body.name) >= 0; ++k) body.name = fmt::format("{}.sum_{}_{}", f.name, e.text, k);  // (one name each: IR text)
        body.glsl_name = body.name;
        int idx = int(ctx.module.functions.size());
        ctx.module.functions.emplace_back();
        ctx.module.functions.back().name = body.name;  // (reserved: a sum lowered meanwhile takes another name)
        body.rolled_sum = true;
        Env child{m, ctx, body};
        child.parent = this;
        child.sum_body = true;
        child.sum_index = sum_index;  // outer unrolled sums' indices: constants here too
        child.sum_index.erase(e.text);
        ValueId k = add_param(body, e.text, Type::integer());
        child.rolled[e.text] = k;
        ValueId term = child.lower(*e.args[0]);
        Type t = scalar_or(child.type_of(term));
        if (e.args.size() > 1) {  // ∑_(j for condition): a term counts where its condition holds
            ValueId zero = body.constant(t, std::vector<double>(size_t(t.components()), 0.0));
            term = child.emit(Op::Select, t, {child.lower(*e.args[1]), term, zero}, 0, e.span);
        }
        // The state (the sum so far) is parameter 1, before the captures the term made.
        body.params.insert(body.params.begin() + 1, {"sum", t});
        for (Instr& in : body.body)
            if (in.op == Op::Param && in.aux >= 1) ++in.aux;
        Instr state;
        state.op = Op::Param;
        state.type = t;
        state.aux = 1;
        state.name = "sum";
        ValueId acc = body.add(std::move(state));
        ValueId next = child.op2(Op::Add, acc, term, e.span);
        body.outputs.push_back({"sum", next});
        body.result = next;
        std::vector<ValueId> args = {f.scalar(double(n - 1)), f.constant(t, std::vector<double>(size_t(t.components()), 0.0))};
        args.insert(args.end(), child.capture_args.begin(), child.capture_args.end());
        ctx.module.functions[size_t(idx)] = std::move(body);
        Instr loop;
        loop.op = Op::Loop;
        loop.type = Type::tuple(1);
        loop.args = std::move(args);
        loop.aux = idx;
        loop.data = {0.0};
        loop.span = e.span;
        ValueId lv = f.add(std::move(loop));
        return emit(Op::Member, t, {lv}, 0, e.span);
    }

    // Whether x reads one of this environment's own rolled ∑ indices (a letter not bound by a sum inside x).
    bool reads_own_rolled(const Expr& x, std::set<std::string>& bound) const {
        auto free_letter = [&](const std::string& name) { return rolled.count(name) && !bound.count(name); };
        if (x.kind == ExprKind::Name && x.resolved == R_SumIndex && free_letter(x.text)) return true;
        if (x.kind == ExprKind::Index)
            for (const auto& it : x.indices)
                if (it.expr && (it.expr->kind == ExprKind::Name ? free_letter(it.expr->text) : reads_own_rolled(*it.expr, bound)))
                    return true;
        const bool binds = x.kind == ExprKind::Sum && !bound.count(x.text);
        if (binds) bound.insert(x.text);
        bool reads = false;
        for (const auto& a : x.args) reads = reads || reads_own_rolled(*a, bound);
        for (const auto& r : x.rows)
            for (const auto& a : r) reads = reads || reads_own_rolled(*a, bound);
        if (x.otherwise) reads = reads || reads_own_rolled(*x.otherwise, bound);
        if (binds) bound.erase(x.text);
        return reads;
    }

    // How many terms the sums inside x add up to unrolled (1 where there are none).
    double inner_terms(const Expr& x) {
        double t = 0;
        std::function<void(const Expr&)> walk = [&](const Expr& y) {
            if (y.kind == ExprKind::Sum) {
                t += double(sum_count(y)) * inner_terms(*y.args[0]);
                return;
            }
            for_each_child(y, walk);
        };
        walk(x);
        return std::max(1.0, t);
    }

    // ∑_i e, unrolled (or rolled: rolled_sum): the range is a vector's, matrix's or sequence's size, known when
    // checking.
    ValueId sum(const Expr& e) {
        // In a rolled sum's body, a sum that reads nothing of the body's index is the same in every iteration: it
        // is computed once, before the loop (a trial: ∑_i w_i x_i / ∑_j w_j computed ∑_j w_j 100 times, and a frame
        // took 33 s on webgl2 against 0.76 s on Shadertoy).
        if (sum_body) {
            std::set<std::string> bound;
            if (!reads_own_rolled(e, bound)) return capture(parent->lower(e));
        }
        ValueId acc = ValueId(-1);
        int n = sum_count(e);
        // The unrolled size is what counts, nested sums included (Shadertoy's ∑_i ∑_j over 200 points unrolled
        // 40,000 terms: 9 s to compile, a 1.4 MB shader). Inside a rolled sum's body, a sum that reads its index is
        // rolled only from kRolledConstantSum: llvmpipe ends a shader invocation after 65,535 loop iterations in
        // all (Emit.cpp), and a loop in a loop spends them many times faster (∑_i ∑_j over 40 points as two loops
        // drew a wrong rim: 1,640 iterations per evaluation).
        const int threshold = ctx.module.constant_parameters || sum_body ? kRolledConstantSum : kRolledSum;
        if (n >= kRolledSum && double(n) * inner_terms(*e.args[0]) >= threshold && rollable(*e.args[0], e.text))
            return rolled_sum(e, n);
        auto outer = sum_index.find(e.text);  // an enclosing sum with the same index letter
        std::optional<int> shadowed = outer == sum_index.end() ? std::nullopt : std::optional<int>(outer->second);
        auto rolled_letter = rolled.extract(e.text);  // (a rolled sum's index of the letter: shadowed here)
        for (int k = 0; k < n; ++k) {
            sum_index[e.text] = k;
            ValueId term = lower(*e.args[0]);
            if (e.args.size() > 1) {  // ∑_(j for condition): a term counts where its condition holds
                Type t = scalar_or(type_of(term));
                ValueId zero = f.constant(t, std::vector<double>(size_t(t.components()), 0.0));
                ValueId c = lower(*e.args[1]);
                auto known = constant_value(c);
                if (!known) term = emit(Op::Select, t, {c, term, zero}, 0, e.span);
                else if ((*known)[0] == 0) term = acc == ValueId(-1) && k == n - 1 ? zero : ValueId(-1);
                if (term == ValueId(-1)) continue;
            }
            acc = acc == ValueId(-1) ? term : op2(Op::Add, acc, term, e.span);
        }
        if (shadowed) sum_index[e.text] = *shadowed;
        else sum_index.erase(e.text);
        if (!rolled_letter.empty()) rolled.insert(std::move(rolled_letter));
        return acc;
    }
    ValueId compare(const Expr& e) {
        ValueId a = lower(*e.args[0]);
        ValueId b = lower(*e.args[1]);
        ir::CompareKind k = ir::CompareKind::Eq;
        switch (e.op) {
            case BinOp::Eq: k = ir::CompareKind::Eq; break;
            case BinOp::Neq: k = ir::CompareKind::Ne; break;
            case BinOp::Lt: k = ir::CompareKind::Lt; break;
            case BinOp::Le: k = ir::CompareKind::Le; break;
            case BinOp::Gt: k = ir::CompareKind::Gt; break;
            default: k = ir::CompareKind::Ge; break;
        }
        return emit(Op::Compare, Type::boolean(), {a, b}, int(k), e.span);
    }

    // Cases are tried in order: the first true condition wins (a chain of selects from the last).
    ValueId piecewise(const Expr& e) {
        ValueId acc = ValueId(-1);
        if (e.otherwise) acc = lower(*e.otherwise);
        for (size_t i = e.rows.size(); i-- > 0;) {
            ValueId v = lower(*e.rows[i][0]);
            ValueId c = lower(*e.rows[i][1]);
            if (acc == ValueId(-1)) {  // no `otherwise`: 0
                Type t = scalar_or(type_of(v));
                acc = f.constant(t, std::vector<double>(size_t(t.components()), 0.0));
            }
            acc = emit(Op::Select, scalar_or(type_of(v)), {c, v, acc}, 0, e.span);
        }
        return acc;
    }
    // A subscripted value (see Checker::check_index): constant subscripts extract, ∑ indices are constant
    // while unrolling, ℤ values known only when running index with At (0-based, rounded and clamped).
    ValueId index(const Expr& e) {
        ValueId a = ValueId(-1);
        size_t first = 0;
        // y_i in a rolled ∑_i, y a sequence the module defines element-wise (y_i = 2x_i + (1, 0, 0)): the
        // definition's expression with its letter standing for the loop's index. Reading the array built where
        // y is defined kept it built whole per evaluation (a trial: 100 points, 12.4 s a frame on webgl2 against
        // 0.17 s with the sum written out).
        if (e.indices[0].value == -2 && e.indices[0].expr)
            if (const Stmt* def = elementwise_sequence(*e.args[0])) {
                const std::string& index = e.indices[0].expr->text;
                const auto k = rolled_index(index);
                const auto unrolled = sum_index.find(index);
                if (k || unrolled != sum_index.end()) {
                    // (unrolled too: a definition of numbers, u_i = w_i², is a vector, and GLSL has none past 4)
                    const std::string& letter = def->elem_indices[0].first;
                    const int at = k ? 0 : unrolled->second;
                    auto shadowed_rolled = rolled.extract(letter);
                    auto shadowed_unrolled = sum_index.extract(letter);
                    if (k) rolled[letter] = *k;
                    else sum_index[letter] = at;
                    ValueId element = lower(*def->value);
                    rolled.erase(letter);
                    sum_index.erase(letter);
                    if (!shadowed_rolled.empty()) rolled.insert(std::move(shadowed_rolled));
                    if (!shadowed_unrolled.empty()) sum_index.insert(std::move(shadowed_unrolled));
                    if (e.indices.size() == 1) return element;
                    a = element;
                    first = 1;
                }
            }
        if (first == 0) a = lower(*e.args[0]);
        auto constant = [&](size_t k) {
            const IndexItem& it = e.indices[k];
            return it.value == -2 ? sum_index.at(it.expr->text) : it.value;
        };
        auto dynamic = [&](size_t k) { return e.indices[k].value == -3; };
        auto position = [&](size_t k) {  // the 0-based position as a value
            const IndexItem& it = e.indices[k];
            if (!dynamic(k)) return f.scalar(double(constant(k)));
            ValueId v = lower(*it.expr);
            return it.zero_based ? v : emit(Op::Sub, Type::scalar(), {v, f.scalar(1)}, 0, it.span);
        };
        if (first == 0 && type_of(a).is_array() && e.indices[0].value == -2) {
            // a rolled ∑'s index: the loop's, in range by construction
            if (auto k = rolled_index(e.indices[0].expr->text)) {
                a = emit(Op::Index, type_of(a).element(), {a, *k}, 0, e.span);
                if (e.indices.size() == 1) return a;
                first = 1;
            }
        }
        if (first == 0 && type_of(a).is_array()) {
            Type elem = type_of(a).element();
            a = dynamic(0) ? emit(Op::At, elem, {a, position(0)}, 0, e.span) : emit(Op::Element, elem, {a}, constant(0), e.span);
            if (e.indices.size() == 1) return a;
            first = 1;
        }
        const Type t = type_of(a);
        if (t.is_vector()) {
            if (dynamic(first)) return emit(Op::At, Type::scalar(), {a, position(first)}, 0, e.span);
            return emit(Op::Extract, Type::scalar(), {a}, constant(first), e.span);
        }
        if (dynamic(first) || dynamic(first + 1))
            return emit(Op::At, Type::scalar(), {a, position(first), position(first + 1)}, 0, e.span);
        int r = constant(first), c = constant(first + 1);
        if (r < 0 && c < 0) return a;
        if (r < 0) return emit(Op::Column, Type::vector(t.rows), {a}, c, e.span);
        if (c < 0) return emit(Op::Row, Type::vector(t.cols), {a}, r, e.span);
        return emit(Op::Extract, Type::scalar(), {a}, r * t.cols + c, e.span);
    }

    // An element-wise definition (see Checker::check_elementwise), unrolled over its indices.
    ValueId elementwise(const Stmt& s) {
        std::vector<int> ranges;
        for (const auto& [letter, span] : s.elem_indices) ranges.push_back(sum_range(*s.value, letter));
        const std::string& i = s.elem_indices[0].first;
        std::vector<ValueId> items;
        if (ranges.size() == 1) {
            for (int k = 0; k < ranges[0]; ++k) {
                sum_index[i] = k;
                items.push_back(lower(*s.value));
            }
            sum_index.erase(i);
            Type elem = scalar_or(type_of(items[0]));
            Type t = elem.is_scalar() ? Type::vector(ranges[0]) : Type::array(elem, ranges[0]);
            return items.size() == 1 ? items[0] : emit(Op::Construct, t, std::move(items), 0, s.span);
        }
        const std::string& j = s.elem_indices[1].first;
        bool diagonal = i == j;
        ValueId zero = diagonal ? f.scalar(0) : ValueId(-1);
        for (int r = 0; r < ranges[0]; ++r)
            for (int c = 0; c < ranges[1]; ++c) {
                if (diagonal && r != c) {
                    items.push_back(zero);
                    continue;
                }
                sum_index[i] = r;
                sum_index[j] = c;
                items.push_back(lower(*s.value));
            }
        sum_index.erase(i);
        sum_index.erase(j);
        Type t = ranges[1] == 1 ? Type::vector(ranges[0]) : Type::matrix(ranges[0], ranges[1]);
        return items.size() == 1 ? items[0] : emit(Op::Construct, t, std::move(items), 0, s.span);
    }

    // A^k for a whole k (the checker made sure), by repeated squaring; k < 0 powers the inverse.
    ValueId matrix_power(ValueId a, int k, Span span) {
        const Type t = type_of(a);
        if (k < 0) {
            a = emit(Op::Inverse, t, {a}, 0, span);
            k = -k;
        }
        if (k == 0) {
            std::vector<double> id(size_t(t.rows * t.cols), 0.0);
            for (int i = 0; i < t.rows; ++i) id[size_t(i * t.cols + i)] = 1;
            return f.constant(t, id);
        }
        ValueId result = ValueId(-1), square = a;
        while (true) {
            if (k & 1) result = result == ValueId(-1) ? square : emit(Op::Mul, t, {result, square}, 0, span);
            k >>= 1;
            if (!k) return result;
            square = emit(Op::Mul, t, {square, square}, 0, span);
        }
    }

    // A ⊗ B: entry (i₁·r₂ + i₂, j₁·c₂ + j₂) is A(i₁, j₁)·B(i₂, j₂); vectors are columns.
    ValueId kronecker(ValueId a, ValueId b, Span span) {
        const Type ta = type_of(a), tb = type_of(b);
        int ac = ta.is_matrix() ? ta.cols : 1, bc = tb.is_matrix() ? tb.cols : 1;
        int rows = ta.rows * tb.rows, cols = ac * bc;
        std::vector<ValueId> items;
        for (int i = 0; i < rows; ++i)
            for (int j = 0; j < cols; ++j) {
                ValueId x = emit(Op::Extract, Type::scalar(), {a}, (i / tb.rows) * ac + j / bc, span);
                ValueId y = emit(Op::Extract, Type::scalar(), {b}, (i % tb.rows) * bc + j % bc, span);
                items.push_back(emit(Op::Mul, Type::scalar(), {x, y}, 0, span));
            }
        return emit(Op::Construct, cols == 1 ? Type::vector(rows) : Type::matrix(rows, cols), std::move(items), 0, span);
    }

    // A : B = ∑ A_ij B_ij: the dot product of vectors, row by row for matrices.
    ValueId frobenius(ValueId a, ValueId b, Span span) {
        const Type t = type_of(a);
        if (t.is_vector()) return emit(Op::Dot, Type::scalar(), {a, b}, 0, span);
        ValueId acc = ValueId(-1);
        for (int r = 0; r < t.rows; ++r) {
            ValueId d = emit(Op::Dot, Type::scalar(), {emit(Op::Row, Type::vector(t.cols), {a}, r, span),
                                                       emit(Op::Row, Type::vector(t.cols), {b}, r, span)}, 0, span);
            acc = acc == ValueId(-1) ? d : emit(Op::Add, Type::scalar(), {acc, d}, 0, span);
        }
        return acc;
    }

    // ‖A‖_*: the sum of A's singular values, the square roots of the eigenvalues of the smaller Gram matrix
    // G (A Aᵀ or AᵀA). For a 2×2 G, σ₁ + σ₂ = √(tr G + 2√det G); for a 3×3 G the eigenvalues of a symmetric
    // matrix in closed form (Smith, "Eigenvalues of a symmetric 3 × 3 matrix", CACM 4(4), 1961).
    ValueId nuclear(ValueId a, Span span) {
        const Type t = type_of(a);
        int k = std::min(t.rows, t.cols);
        if (k == 1) return builtin("sqrt", {frobenius(a, a, span)}, span);
        ValueId at = emit(Op::Transpose, Type::matrix(t.cols, t.rows), {a}, 0, span);
        ValueId G = t.rows <= t.cols ? emit(Op::Mul, Type::matrix(k, k), {a, at}, 0, span)
                                     : emit(Op::Mul, Type::matrix(k, k), {at, a}, 0, span);
        auto g = [&](int r, int c) { return emit(Op::Extract, Type::scalar(), {G}, r * k + c, span); };
        auto add = [&](ValueId x, ValueId y) { return emit(Op::Add, Type::scalar(), {x, y}, 0, span); };
        auto sub = [&](ValueId x, ValueId y) { return emit(Op::Sub, Type::scalar(), {x, y}, 0, span); };
        auto mulv = [&](ValueId x, ValueId y) { return emit(Op::Mul, Type::scalar(), {x, y}, 0, span); };
        auto root = [&](ValueId x) { return builtin("sqrt", {builtin("max", {x, f.scalar(0)}, span)}, span); };
        if (k == 2) {
            ValueId det = emit(Op::Det, Type::scalar(), {G}, 0, span);
            return root(add(add(g(0, 0), g(1, 1)), mulv(f.scalar(2), root(det))));
        }
        ValueId q = emit(Op::Div, Type::scalar(), {add(add(g(0, 0), g(1, 1)), g(2, 2)), f.scalar(3)}, 0, span);
        ValueId p1 = add(add(mulv(g(0, 1), g(0, 1)), mulv(g(0, 2), g(0, 2))), mulv(g(1, 2), g(1, 2)));
        ValueId d0 = sub(g(0, 0), q), d1 = sub(g(1, 1), q), d2 = sub(g(2, 2), q);
        ValueId p2 = add(add(add(mulv(d0, d0), mulv(d1, d1)), mulv(d2, d2)), mulv(f.scalar(2), p1));
        ValueId p = builtin("max", {root(emit(Op::Div, Type::scalar(), {p2, f.scalar(6)}, 0, span)), f.scalar(1e-18)}, span);
        std::vector<double> id(9, 0.0);
        id[0] = id[4] = id[8] = 1;
        ValueId shifted = emit(Op::Sub, Type::matrix(3, 3), {G, emit(Op::Mul, Type::matrix(3, 3), {q, f.constant(Type::matrix(3, 3), id)}, 0, span)}, 0, span);
        ValueId B = emit(Op::Div, Type::matrix(3, 3), {shifted, p}, 0, span);
        ValueId r = emit(Op::Div, Type::scalar(), {emit(Op::Det, Type::scalar(), {B}, 0, span), f.scalar(2)}, 0, span);
        ValueId phi = emit(Op::Div, Type::scalar(),
                           {builtin("acos", {builtin("clamp", {r, f.scalar(-1), f.scalar(1)}, span)}, span), f.scalar(3)}, 0, span);
        ValueId two_p = mulv(f.scalar(2), p);
        ValueId l1 = add(q, mulv(two_p, builtin("cos", {phi}, span)));
        ValueId l3 = add(q, mulv(two_p, builtin("cos", {add(phi, f.scalar(2 * M_PI / 3))}, span)));
        ValueId l2 = sub(sub(mulv(f.scalar(3), q), l1), l3);
        return add(add(root(l1), root(l2)), root(l3));
    }

    // ‖x‖ and |x| by what the checker resolved (see check_norm).
    ValueId norm(const Expr& e) {
        ValueId a = lower(*e.args[0]);
        const Type t = type_of(a);
        Span span = e.span;
        auto ones = [&] { return f.constant(t, std::vector<double>(size_t(t.rows), 1.0)); };
        switch (e.resolved) {
            case R_Det: return emit(Op::Det, Type::scalar(), {a}, 0, span);
            case R_Length: return builtin("length", {a}, span);
            case R_Norm1: return emit(Op::Dot, Type::scalar(), {builtin("abs", {a}, span), ones()}, 0, span);
            case R_NormMax: {
                ValueId m = builtin("abs", {a}, span);
                std::vector<ValueId> items;
                for (int i = 0; i < t.rows; ++i) items.push_back(emit(Op::Extract, Type::scalar(), {m}, i, span));
                return builtin("max", items, span);
            }
            case R_NormP: {  // (∑ |v_i|^p)^(1/p)
                ValueId p = lower(*e.args[1]);
                ValueId powered = builtin("pow", {builtin("abs", {a}, span), p}, span);
                ValueId sum = emit(Op::Dot, Type::scalar(), {powered, ones()}, 0, span);
                return builtin("pow", {sum, emit(Op::Div, Type::scalar(), {f.scalar(1), p}, 0, span)}, span);
            }
            case R_NormMatrix: {  // √(vᵀ M v)
                ValueId mv = mul(lower(*e.args[1]), a, span);
                return builtin("sqrt", {emit(Op::Dot, Type::scalar(), {a, mv}, 0, span)}, span);
            }
            case R_Frobenius: return builtin("sqrt", {frobenius(a, a, span)}, span);
            case R_Norm0: {  // the number of components that are not 0
                ValueId zero = f.scalar(0), one = f.scalar(1), acc = ValueId(-1);
                for (int i = 0; i < t.rows; ++i) {
                    ValueId c = emit(Op::Compare, Type::boolean(), {emit(Op::Extract, Type::scalar(), {a}, i, span), zero},
                                     int(ir::CompareKind::Ne), span);
                    ValueId k = emit(Op::Select, Type::scalar(), {c, one, zero}, 0, span);
                    acc = acc == ValueId(-1) ? k : emit(Op::Add, Type::scalar(), {acc, k}, 0, span);
                }
                return acc;
            }
            case R_Nuclear: return nuclear(a, span);
            default: return builtin("abs", {a}, span);
        }
    }

    ValueId mul(ValueId a, ValueId b, Span span) {
        const Instr& ai = f.body[a];
        // aᵀb is a dot product.
        if (ai.op == Op::Transpose && type_of(ai.args[0]).is_vector() && type_of(b).is_vector())
            return emit(Op::Dot, Type::scalar(), {ai.args[0], b}, 0, span);
        Type t = ir::result_type(Op::Mul, {type_of(a), type_of(b)}, 0);
        return emit(Op::Mul, t, {a, b}, 0, span);
    }

    ValueId lower(const Expr& e) {
        switch (e.kind) {
            case ExprKind::Number: return f.scalar(e.number);
            case ExprKind::Name:
                if (parent && (e.resolved == R_Param || e.resolved == R_Value || e.resolved == R_Local ||
                               e.resolved == R_Capture))
                    return capture(parent->lower(e));
                switch (e.resolved) {
                    case R_LoopIndex: return sum_body ? capture(parent->lower(e)) : loop_index;
                    case R_Param: return params[size_t(e.aux)];
                    case R_Value: return values.at(e.text);
                    case R_Local: return locals[size_t(e.aux)];
                    case R_Capture: return captures[size_t(e.aux)];
                    case R_Pi: return f.scalar(M_PI);
                    case R_Constant: return f.scalar(M_E);
                    case R_Input: return emit(Op::Input, e.aux == 0 ? Type::scalar() : Type::vector(2), {}, e.aux, e.span);
                    case R_SumIndex:
                        if (auto k = rolled_index(e.text))  // i = k + 1, a real number
                            return op2(Op::Add, emit(Op::Construct, Type::scalar(), {*k}, 0, e.span), f.scalar(1), e.span);
                        return f.scalar(double(sum_index.at(e.text) + 1));
                    default: internal_error("lowering: unresolved name " + e.text);
                }
            case ExprKind::Call: {
                if (e.resolved == R_Scale) return mul(lower(*e.args[0]), lower(*e.args[1]), e.span);
                std::vector<ValueId> args;
                for (auto& a : e.args) args.push_back(lower(*a));
                if (e.resolved == R_Builtin) {
                    Sig sig = iqc::builtin(e.aux).sig;
                    if (sig == Sig::Det || sig == Sig::Inverse || sig == Sig::Trace || sig == Sig::Diag || sig == Sig::Vec)
                        return linear_algebra(e.aux, args[0], e.span);
                    return builtin_id(e.aux, std::move(args), e.span);
                }
                if (e.resolved == R_ImportModule) {
                    const CheckedModule& callee = *m.imports[size_t(e.aux)].from;
                    int idx = lower_module_cached(callee, ctx);
                    return emit(Op::Call, ctx.module.functions[size_t(idx)].result_type(), std::move(args), idx, e.span);
                }
                const CheckedModule* owner = &m;
                int fi = e.aux;
                if (e.resolved == R_ImportFn) {
                    const ImportedFunction& im = m.imports[size_t(e.aux)];
                    owner = im.from;
                    fi = im.function;
                }
                const LocalFunction& callee = owner->functions[size_t(fi)];
                for (auto& cap : callee.captures) {
                    if (owner == &m) {
                        args.push_back(lookup_capture(cap.first));
                    } else if (int pi = owner->find_param(cap.first); pi >= 0) {
                        // a library module's own parameter: its default value
                        args.push_back(f.constant(cap.second, owner->params[size_t(pi)].value));
                    } else {  // a library module's own value, computed from its defaults
                        args.push_back(library_value(*owner, cap.first));
                    }
                }
                std::vector<Type> arg_types;
                for (size_t k = 0; k < e.args.size(); ++k) arg_types.push_back(scalar_or(type_of(args[k])));
                int idx = lower_local_function(*owner, fi, arg_types, ctx);
                return emit(Op::Call, ctx.module.functions[size_t(idx)].result_type(), std::move(args), idx, e.span);
            }
            case ExprKind::Binary: {
                ValueId a = lower(*e.args[0]);
                ValueId b = lower(*e.args[1]);
                switch (e.op) {
                    case BinOp::Add: return op2(Op::Add, a, b, e.span);
                    case BinOp::Sub: return op2(Op::Sub, a, b, e.span);
                    case BinOp::Div: return op2(Op::Div, a, b, e.span);
                    case BinOp::Hadamard: return op2(type_of(a).is_scalar() ? Op::Mul : Op::Hadamard, a, b, e.span);
                    case BinOp::Cross: return op2(Op::Cross, a, b, e.span);
                    case BinOp::Solve: return mul(emit(Op::Inverse, type_of(a), {a}, 0, e.span), b, e.span);
                    case BinOp::Kronecker: return kronecker(a, b, e.span);
                    case BinOp::Frobenius: return frobenius(a, b, e.span);
                    default:
                        if (e.op == BinOp::Dot && type_of(a).is_vector() && type_of(a) == type_of(b))
                            return emit(Op::Dot, Type::scalar(), {a, b}, 0, e.span);
                        return mul(a, b, e.span);
                }
            }
            case ExprKind::Negate: {
                ValueId a = lower(*e.args[0]);
                return emit(Op::Neg, scalar_or(type_of(a)), {a}, 0, e.span);
            }
            case ExprKind::Power: {
                if (e.args[0]->kind == ExprKind::Name && e.args[0]->resolved == R_Constant)  // eˣ
                    return builtin("exp", {lower(*e.args[1])}, e.span);
                ValueId base = lower(*e.args[0]);
                if (type_of(base).is_matrix()) return matrix_power(base, e.aux, e.span);
                return power(base, *e.args[1], e.span);
            }
            case ExprKind::Transpose: {
                ValueId a = lower(*e.args[0]);
                if (type_of(a).is_scalar()) return a;
                return emit(Op::Transpose, ir::result_type(Op::Transpose, {type_of(a)}, 0), {a}, 0, e.span);
            }
            case ExprKind::Block:
            case ExprKind::Index: {
                if (e.resolved == R_BlockZero || e.resolved == R_BlockOnes || e.resolved == R_BlockIdentity) {
                    int rows = e.block_rows[0], cols = e.block_cols[0];
                    std::vector<double> data(size_t(rows * cols), e.resolved == R_BlockOnes ? 1.0 : 0.0);
                    if (e.resolved == R_BlockIdentity)
                        for (int i = 0; i < rows; ++i) data[size_t(i * cols + i)] = 1;
                    return f.constant(cols == 1 ? Type::vector(rows) : Type::matrix(rows, cols), std::move(data));
                }
                if (e.resolved == R_SeqCurrent) return sum_body ? capture(parent->lower(e)) : seq_current.at(e.aux);
                if (e.resolved == R_SeqFirst || e.resolved == R_SeqLast) {
                    if (parent) return capture(parent->lower(e));
                    return (e.resolved == R_SeqFirst ? seq_first : seq_last).at(e.aux);
                }
                return index(e);
            }
            case ExprKind::Sequence: {
                std::vector<ValueId> items;
                for (auto& a : e.args) items.push_back(lower(*a));
                Type t = Type::array(scalar_or(type_of(items[0])), int(items.size()));
                return emit(Op::Construct, t, std::move(items), 0, e.span);
            }
            case ExprKind::Vector: {
                std::vector<ValueId> items;
                int n = 0;
                for (auto& a : e.args) {
                    items.push_back(lower(*a));
                    n += type_of(items.back()).components();
                }
                return emit(Op::Construct, Type::vector(n), std::move(items), 0, e.span);
            }
            case ExprKind::Matrix: return matrix_literal(e);
            case ExprKind::Sum: return sum(e);
            case ExprKind::Norm:
            case ExprKind::Abs: return norm(e);
            case ExprKind::Inner: {
                ValueId u = lower(*e.args[0]), v = lower(*e.args[1]);
                if (e.args.size() > 2) u = mul(lower(*e.args[2]), u, e.span);  // ⟨u, v⟩_M = vᵀ(M u)
                return emit(Op::Dot, Type::scalar(), {u, v}, 0, e.span);
            }
            case ExprKind::Floor: return builtin("floor", {lower(*e.args[0])}, e.span);
            case ExprKind::Ceil: return builtin("ceil", {lower(*e.args[0])}, e.span);
            case ExprKind::Sqrt: return builtin("sqrt", {lower(*e.args[0])}, e.span);
            case ExprKind::Compare: return compare(e);
            case ExprKind::Logic: {
                ValueId a = lower(*e.args[0]);
                ValueId b = lower(*e.args[1]);
                return emit(e.op == BinOp::And ? Op::And : Op::Or, Type::boolean(), {a, b}, 0, e.span);
            }
            case ExprKind::Piecewise: return piecewise(e);
        }
        internal_error("lowering: unknown expression");
    }

    // A value assigned in another (imported) module, computed here from that module's default parameters.
    ValueId library_value(const CheckedModule& owner, const std::string& name) {
        Env oe{owner, ctx, f};
        for (const auto& p : owner.params) oe.params.push_back(f.constant(p.type, p.value));
        for (const Stmt* s : owner.order) {
            if (s->kind == StmtKind::Recurrence) {
                for (const auto& g : owner.groups)
                    if (g.leader == s) oe.lower_group(g);
                continue;
            }
            if (s->kind != StmtKind::Assign) continue;
            ValueId v = oe.lower(*s->value);
            oe.values[s->name] = v;
            if (s->name == name) return v;
        }
        internal_error("lowering: imported function captures '" + name + "', which its module does not assign");
    }

    // Gives `v` the statement's name (or a named copy, when v is a parameter or already named).
    ValueId name_value(ValueId v, const Stmt& s) {
        Instr& in = f.body[v];
        if (in.op == Op::Param || !in.name.empty()) {
            v = emit(Op::Copy, in.type, {v}, 0, s.span);
        }
        Instr& out = f.body[v];
        out.name = s.kind == StmtKind::Return ? "" : s.name;
        out.source = s.source_line;
        out.span = s.span;
        return v;
    }
};

// Recurrences z_(k+1) = f(z_k) for k ∈ lo..hi become one Loop whose body is a function of its own.
void Env::lower_group(const LoopGroup& g) {
    std::vector<ValueId> inits;
    for (int si : g.sequences) {
        const Sequence& seq = m.sequences[size_t(si)];
        ValueId v = lower(*seq.init->value);
        inits.push_back(v);
        seq_first[si] = v;
    }
    ir::Function body;
    body.name = f.name + ".loop_" + m.sequences[size_t(g.sequences[0])].name;
    body.glsl_name = body.name;
    int idx = int(ctx.module.functions.size());
    ctx.module.functions.emplace_back();
    Env child{m, ctx, body};
    child.parent = this;
    child.loop_index = add_param(body, g.var, Type::integer());
    for (size_t j = 0; j < g.sequences.size(); ++j) {
        const Sequence& seq = m.sequences[size_t(g.sequences[j])];
        child.seq_current[g.sequences[j]] = add_param(body, seq.name, seq.type);
    }
    for (int si : g.sequences) {
        const Sequence& seq = m.sequences[size_t(si)];
        ValueId next = child.lower(*seq.rec->value);
        if (body.body[next].op == Op::Param || !body.body[next].name.empty()) {
            Instr cp;
            cp.op = Op::Copy;
            cp.type = body.body[next].type;
            cp.args = {next};
            next = body.add(std::move(cp));
        }
        body.body[next].source = seq.rec->source_line;
        body.outputs.push_back({seq.name, next});
    }
    body.result = body.outputs[0].second;
    ValueId hi = g.hi_name.empty() ? f.scalar(double(g.hi)) : lower(*g.leader->range_hi);
    std::vector<ValueId> args = {hi};
    args.insert(args.end(), inits.begin(), inits.end());
    args.insert(args.end(), child.capture_args.begin(), child.capture_args.end());
    ctx.module.functions[size_t(idx)] = std::move(body);
    Instr loop;
    loop.op = Op::Loop;
    loop.type = Type::tuple(int(g.sequences.size()));
    loop.args = std::move(args);
    loop.aux = idx;
    loop.data = {double(g.lo)};
    loop.span = g.leader->span;
    loop.source = g.leader->source_line;
    ValueId lv = f.add(std::move(loop));
    for (size_t j = 0; j < g.sequences.size(); ++j) {
        const Sequence& seq = m.sequences[size_t(g.sequences[j])];
        ValueId mv = emit(Op::Member, seq.type, {lv}, int(j), g.leader->span);
        seq_last[g.sequences[j]] = mv;
        f.outputs.push_back({fmt::format("{}_{}", seq.name, g.last()), mv});
    }
}

ValueId add_param(ir::Function& f, const std::string& name, Type t, Span span) {
    f.params.push_back({name, t});
    Instr in;
    in.op = Op::Param;
    in.type = t;
    in.aux = int(f.params.size() - 1);
    in.name = name;
    in.span = span;
    return f.add(std::move(in));
}

int lower_local_function(const CheckedModule& m, int fi, const std::vector<Type>& arg_types, LowerContext& ctx) {
    auto key = std::make_tuple(&m, fi, arg_types);
    if (auto it = ctx.functions.find(key); it != ctx.functions.end()) return it->second;
    const LocalFunction& lf = m.functions[size_t(fi)];
    ir::Function fn;
    fn.name = m.ast.name.empty() ? lf.stmt->name : m.ast.name + "." + lf.stmt->name;
    fn.glsl_name = lf.stmt->name;
    // Reserve the slot first so recursive lowering of callees gets stable indices.
    int idx = int(ctx.module.functions.size());
    ctx.functions[key] = idx;
    ctx.module.functions.emplace_back();
    Env env{m, ctx, fn};
    env.fn = &lf;
    for (size_t k = 0; k < lf.params.size(); ++k) env.locals.push_back(add_param(fn, lf.params[k].first, arg_types[k]));
    for (auto& [n, t] : lf.captures) env.captures.push_back(add_param(fn, n, t));
    ValueId r = env.lower(*lf.stmt->value);
    Instr& ri = fn.body[r];
    if (ri.source.empty()) ri.source = lf.stmt->source_line;
    fn.result = r;
    ctx.module.functions[size_t(idx)] = std::move(fn);
    return idx;
}

}  // namespace

std::vector<ir::ValueBounds> parameter_bounds(const CheckedModule& m) {
    std::vector<ir::ValueBounds> b;
    for (const auto& p : m.params) {
        ir::ValueBounds v;
        v.input = false;
        if (p.bounded) {
            v.lo = p.lo;
            v.hi = p.hi;
        }
        b.push_back(std::move(v));
    }
    // What the renderer binds is an input: the shape's query point, the material's point, normal and eye, and
    // the light a material is lit by.
    for (int r : m.roles)
        if (r >= 0) b[size_t(r)].input = true;
    if (m.ast.kind == ast::ModuleKind::Material)
        for (const char* n : {"P_L", "C_L"})
            if (int k = m.find_param(n); k >= 0) b[size_t(k)].input = true;
    return b;
}

int lower_module_cached(const CheckedModule& m, LowerContext& ctx) {
    if (auto it = ctx.modules.find(&m); it != ctx.modules.end()) return it->second;
    const std::string& name = m.ir_name.empty() ? m.ast.name : m.ir_name;
    int idx = lower_module(m, name, name, ctx);
    ctx.modules[&m] = idx;
    return idx;
}

namespace {
int lower_module_unchecked(const CheckedModule& m, const std::string& name, const std::string& glsl_name, LowerContext& ctx);
}

// An IR function grown past the size limit with no span of its own (an instruction made by a rule, not
// from source) is reported at the module.
int lower_module(const CheckedModule& m, const std::string& name, const std::string& glsl_name, LowerContext& ctx) {
    try {
        return lower_module_unchecked(m, name, glsl_name, ctx);
    } catch (ir::SizeLimit& limit) {
        if (!limit.span.valid()) limit.span = m.ast.span;
        throw;
    }
}

namespace {
int lower_module_unchecked(const CheckedModule& m, const std::string& name, const std::string& glsl_name, LowerContext& ctx) {
    ir::Function fn;
    fn.name = name;
    fn.glsl_name = glsl_name;
    int idx = int(ctx.module.functions.size());
    ctx.module.functions.emplace_back();
    Env env{m, ctx, fn};
    for (auto& p : m.params) env.params.push_back(add_param(fn, p.name, p.type, p.span));
    fn.param_bounds = parameter_bounds(m);
    ValueId result = 0;
    bool have_result = false;
    for (const Stmt* s : m.order) {
        if (s->kind == StmtKind::Recurrence) {
            for (const auto& g : m.groups)
                if (g.leader == s) env.lower_group(g);
            continue;
        }
        ValueId v = env.name_value(s->elem_indices.empty() ? env.lower(*s->value) : env.elementwise(*s), *s);
        if (s->kind == StmtKind::Assign) {
            env.values[s->name] = v;
            fn.outputs.push_back({s->name, v});
            if (s->name == m.primary) { result = v; have_result = true; }
        } else {
            result = v;
            have_result = true;
        }
    }
    if (!have_result) result = fn.scalar(0.0);
    // A shape's distance that is an integer (D = n, n ∈ ℤ; sema allows ℤ where ℝ is asked) is a real number
    // like any other: converted here, where it leaves the module (the runtime reads a float).
    if (m.primary_type == Type::scalar() && fn.body[result].type.kind == Type::Integer) {
        Instr c;
        c.op = Op::Construct;
        c.type = Type::scalar();
        c.args = {result};
        c.span = fn.body[result].span;
        result = fn.add(std::move(c));
    }
    fn.result = result;
    ctx.module.functions[size_t(idx)] = std::move(fn);
    return idx;
}
}  // namespace

}  // namespace iqc
