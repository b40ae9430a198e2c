#include "ir/Lower.h"

#include <cmath>
#include <functional>
#include <fmt/format.h>

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
    // Sequences: final and first values (module level); in a recurrence body, the parent environment,
    // the loop index and current states, and outer values captured as extra body parameters.
    std::map<int, ValueId> seq_first, seq_last;
    Env* parent = nullptr;
    ValueId loop_index = 0;
    std::map<int, ValueId> seq_current;
    std::map<ValueId, ValueId> captured;  // parent value -> body parameter
    std::vector<ValueId> capture_args;    // parent values, in parameter order

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
    int sum_range(const Expr& body, const std::string& index) {
        int n = 0;
        std::function<void(const Expr&)> walk = [&](const Expr& x) {
            if (x.kind == ExprKind::Index && x.resolved == R_None)
                for (size_t k = 0; k < x.indices.size(); ++k) {
                    const auto& it = x.indices[k];
                    if (!it.expr || it.expr->kind != ExprKind::Name || it.expr->text != index) continue;
                    const Type& t = type_of(lower(*x.args[0]));
                    if (t.is_vector()) n = t.rows;
                    else if (t.is_matrix()) n = k == 0 ? t.rows : t.cols;
                }
            for (const auto& a : x.args) walk(*a);
            for (const auto& r : x.rows)
                for (const auto& a : r) walk(*a);
            if (x.otherwise) walk(*x.otherwise);
        };
        walk(body);
        return n;
    }

    ValueId power(ValueId base, const Expr& ex, Span span) {
        auto c = const_eval(ex);
        if (c && c->size() == 1 && std::fabs((*c)[0]) <= 4 && (*c)[0] == std::floor((*c)[0])) {
            int n = int((*c)[0]);
            if (n == 0) return f.scalar(1.0);
            ValueId r = base;
            for (int i = 1; i < std::abs(n); ++i) r = emit(Op::Mul, Type::scalar(), {r, base}, 0, span);
            if (n < 0) r = emit(Op::Div, Type::scalar(), {f.scalar(1.0), r}, 0, span);
            return r;
        }
        ValueId e = lower(ex);
        return builtin("pow", {base, e}, span);
    }

    ValueId builtin(const char* name, std::vector<ValueId> args, Span span) {
        int id = *find_builtin(name);
        const BuiltinInfo& b = iqc::builtin(id);
        if (b.sig == Sig::Nary && args.size() > 2) {
            ValueId acc = builtin(name, {args[0], args[1]}, span);
            for (size_t i = 2; i < args.size(); ++i) acc = builtin(name, {acc, args[i]}, span);
            return acc;
        }
        Type t;
        if (b.sig == Sig::Elementwise2 || b.sig == Sig::Nary || b.sig == Sig::Clamp || b.sig == Sig::Mix) {
            Type common = Type::scalar();
            for (ValueId a : args)
                if (type_of(a).is_vector()) common = type_of(a);
            if (common.is_vector())
                for (auto& a : args) a = broadcast(a, common);
        }
        std::vector<Type> ts;
        for (ValueId a : args) ts.push_back(type_of(a));
        t = check_builtin(id, ts).type;
        return emit(Op::Builtin, t, std::move(args), id, span);
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
                    case R_LoopIndex: return loop_index;
                    case R_Param: return params[size_t(e.aux)];
                    case R_Value: return values.at(e.text);
                    case R_Local: return locals[size_t(e.aux)];
                    case R_Capture: return captures[size_t(e.aux)];
                    case R_Pi: return f.scalar(M_PI);
                    case R_Input: return emit(Op::Input, e.aux == 0 ? Type::scalar() : Type::vector(2), {}, e.aux, e.span);
                    case R_SumIndex: return f.scalar(double(sum_index.at(e.text) + 1));
                    default: internal_error("lowering: unresolved name " + e.text);
                }
            case ExprKind::Call: {
                if (e.resolved == R_Scale) return mul(lower(*e.args[0]), lower(*e.args[1]), e.span);
                std::vector<ValueId> args;
                for (auto& a : e.args) args.push_back(lower(*a));
                if (e.resolved == R_Builtin) return builtin(iqc::builtin(e.aux).name, std::move(args), e.span);
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
                ValueId base = lower(*e.args[0]);
                if (type_of(base).is_matrix()) return emit(Op::Inverse, type_of(base), {base}, 0, e.span);
                return power(base, *e.args[1], e.span);
            }
            case ExprKind::Transpose: {
                ValueId a = lower(*e.args[0]);
                if (type_of(a).is_scalar()) return a;
                return emit(Op::Transpose, ir::result_type(Op::Transpose, {type_of(a)}, 0), {a}, 0, e.span);
            }
            case ExprKind::Index: {
                if (e.resolved == R_SeqCurrent) return seq_current.at(e.aux);
                if (e.resolved == R_SeqFirst || e.resolved == R_SeqLast) {
                    if (parent) return capture(parent->lower(e));
                    return (e.resolved == R_SeqFirst ? seq_first : seq_last).at(e.aux);
                }
                ValueId a = lower(*e.args[0]);
                const Type& t = type_of(a);
                auto index = [&](size_t k) {
                    const IndexItem& it = e.indices[k];
                    return it.value == -2 ? sum_index.at(it.expr->text) : it.value;
                };
                if (t.is_vector()) return emit(Op::Extract, Type::scalar(), {a}, index(0), e.span);
                int r = index(0), c = index(1);
                if (r < 0 && c < 0) return a;
                if (r < 0) return emit(Op::Column, Type::vector(t.rows), {a}, c, e.span);
                if (c < 0) return emit(Op::Row, Type::vector(t.cols), {a}, r, e.span);
                return emit(Op::Extract, Type::scalar(), {a}, r * t.cols + c, e.span);
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
            case ExprKind::Matrix: {
                // Element by element, row-major, from the blocks (sized by the checker).
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
            case ExprKind::Sum: {
                // Unrolled: the range is a vector's or matrix's size, known when checking.
                ValueId acc = ValueId(-1);
                int n = sum_range(*e.args[0], e.text);
                for (int k = 0; k < n; ++k) {
                    sum_index[e.text] = k;
                    ValueId term = lower(*e.args[0]);
                    acc = acc == ValueId(-1) ? term : op2(Op::Add, acc, term, e.span);
                }
                sum_index.erase(e.text);
                return acc;
            }
            case ExprKind::Norm:
            case ExprKind::Abs: {
                ValueId a = lower(*e.args[0]);
                if (type_of(a).is_matrix()) return emit(Op::Det, Type::scalar(), {a}, 0, e.span);
                return builtin(e.kind == ExprKind::Norm && type_of(a).is_vector() ? "length" : "abs", {a}, e.span);
            }
            case ExprKind::Floor: return builtin("floor", {lower(*e.args[0])}, e.span);
            case ExprKind::Ceil: return builtin("ceil", {lower(*e.args[0])}, e.span);
            case ExprKind::Sqrt: return builtin("sqrt", {lower(*e.args[0])}, e.span);
            case ExprKind::Compare: {
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
            case ExprKind::Logic: {
                ValueId a = lower(*e.args[0]);
                ValueId b = lower(*e.args[1]);
                return emit(e.op == BinOp::And ? Op::And : Op::Or, Type::boolean(), {a, b}, 0, e.span);
            }
            case ExprKind::Piecewise: {
                // Cases are tried in order: the first true condition wins.
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

ValueId add_param(ir::Function& f, const std::string& name, Type t);

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

ValueId add_param(ir::Function& f, const std::string& name, Type t) {
    f.params.push_back({name, t});
    Instr in;
    in.op = Op::Param;
    in.type = t;
    in.aux = int(f.params.size() - 1);
    in.name = name;
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
    int idx = lower_module(m, m.ast.name, m.ast.name, ctx);
    ctx.modules[&m] = idx;
    return idx;
}

int lower_module(const CheckedModule& m, const std::string& name, const std::string& glsl_name, LowerContext& ctx) {
    ir::Function fn;
    fn.name = name;
    fn.glsl_name = glsl_name;
    int idx = int(ctx.module.functions.size());
    ctx.module.functions.emplace_back();
    Env env{m, ctx, fn};
    for (auto& p : m.params) env.params.push_back(add_param(fn, p.name, p.type));
    fn.param_bounds = parameter_bounds(m);
    ValueId result = 0;
    bool have_result = false;
    for (const Stmt* s : m.order) {
        if (s->kind == StmtKind::Recurrence) {
            for (const auto& g : m.groups)
                if (g.leader == s) env.lower_group(g);
            continue;
        }
        ValueId v = env.name_value(env.lower(*s->value), *s);
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
    fn.result = result;
    ctx.module.functions[size_t(idx)] = std::move(fn);
    return idx;
}

}  // namespace iqc
