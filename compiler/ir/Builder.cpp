#include "ir/Builder.h"

#include <fmt/format.h>

#include "sema/Builtins.h"
#include "source/Internal.h"

namespace iqc::ir {

ValueId Builder::add(Instr in) {
    if (!in.type.valid()) internal_error(fmt::format("IR builder: {} of these operand types has no type", op_name(in.op)));
    return f_.add(std::move(in));
}

ValueId Builder::param(const std::string& name, const Type& t, ValueBounds bounds) {
    if (!f_.param_bounds.empty() || !bounds.input) f_.param_bounds.resize(f_.params.size());
    f_.params.push_back({name, t});
    if (!f_.param_bounds.empty()) f_.param_bounds.push_back(std::move(bounds));
    Instr in;
    in.op = Op::Param;
    in.type = t;
    in.aux = int(f_.params.size() - 1);
    in.name = name;
    return add(std::move(in));
}

ValueId Builder::constant(const Type& t, std::vector<double> data) {
    if (int(data.size()) != std::max(1, t.components())) internal_error("IR builder: constant size does not match its type");
    return f_.constant(t, std::move(data));
}

ValueId Builder::op(Op o, std::vector<ValueId> args, int aux) {
    std::vector<Type> ts;
    for (ValueId a : args) ts.push_back(type(a));
    Instr in;
    in.op = o;
    in.type = result_type(o, ts, aux);
    in.args = std::move(args);
    in.aux = aux;
    return add(std::move(in));
}

ValueId Builder::builtin(const char* name, std::vector<ValueId> args) {
    auto id = find_builtin(name);
    if (!id) internal_error(fmt::format("IR builder: no built-in '{}'", name));
    return op(Op::Builtin, std::move(args), *id);
}

ValueId Builder::construct(const Type& t, std::vector<ValueId> parts) {
    int n = 0;
    for (ValueId p : parts) n += type(p).components();
    if (n != t.components()) internal_error("IR builder: constructed components do not add up");
    Instr in;
    in.op = Op::Construct;
    in.type = t;
    in.args = std::move(parts);
    return add(std::move(in));
}

ValueId Builder::global(int g) {
    Instr in;
    in.op = Op::Global;
    in.type = m_.globals.at(size_t(g)).type;
    in.aux = g;
    return add(std::move(in));
}

ValueId Builder::call(int fn, std::vector<ValueId> args) {
    const Function& callee = m_.functions.at(size_t(fn));
    if (callee.params.size() != args.size()) internal_error("IR builder: call of " + callee.name + " with the wrong argument count");
    Instr in;
    in.op = Op::Call;
    in.type = callee.result_type();
    in.args = std::move(args);
    in.aux = fn;
    return add(std::move(in));
}

ValueId Builder::switch_(ValueId selector, ValueId fallback, std::vector<std::tuple<long long, long long, ValueId>> cases) {
    Instr in;
    in.op = Op::Switch;
    in.type = type(fallback);
    in.args = {selector, fallback};
    for (const auto& [lo, hi, v] : cases) {
        if (!in.data.empty() && in.args.back() == v && in.data.back() == double(lo)) {
            in.data.back() = double(hi);
            continue;
        }
        if (type(v) != in.type && !(type(v).is_scalar() && in.type.is_scalar())) internal_error("IR builder: switch case type mismatch");
        in.args.push_back(v);
        in.data.push_back(double(lo));
        in.data.push_back(double(hi));
    }
    if (in.args.size() == 2) return fallback;
    return add(std::move(in));
}

ValueId Builder::named(ValueId v, const std::string& name, const std::string& source) {
    if (f_.body[v].op == Op::Param || !f_.body[v].name.empty() || f_.body[v].op == Op::Const) {
        Instr cp;
        cp.op = Op::Copy;
        cp.type = type(v);
        cp.args = {v};
        v = add(std::move(cp));
    }
    f_.body[v].name = name;
    f_.body[v].source = source;
    return v;
}

namespace {

// The multiplier and shift of div_by_constant, or {0, 0} where there are none.
std::pair<long long, int> division_magic(long long d, long long n) {
    for (int s = 0; s <= 30; ++s) {
        const long long two_s = 1LL << s;
        if (two_s < d) continue;
        const long long M = (two_s + d - 1) / d, e = M * d - two_s;
        if ((n - 1) * e < two_s && (n - 1) * M < (1LL << 31)) return {M, s};
    }
    return {0, 0};
}

}  // namespace

ValueId Builder::div_by_constant(ValueId k, long long d, long long n) {
    if (d == 1) return k;
    if ((d & (d - 1)) == 0 || n <= d) {
        // A power of two is a shift already; below d the quotient is 0 (kept as the division: k may be a
        // value the caller did not bound, such as a stand-in lane's index).
        return op(Op::IntDiv, {k, integer(d)});
    }
    auto [M, s] = division_magic(d, n);
    if (M == 0) return op(Op::IntDiv, {k, integer(d)});
    return op(Op::IntDiv, {op(Op::Mul, {k, integer(M)}), integer(1LL << s)});
}

ValueId Builder::mod_by_constant(ValueId k, long long d, long long n) {
    if (d == 1) return integer(0);
    if ((d & (d - 1)) == 0 || n <= d) return op(Op::IntMod, {k, integer(d)});
    auto [M, s] = division_magic(d, n);
    if (M == 0) return op(Op::IntMod, {k, integer(d)});
    return op(Op::Sub, {k, op(Op::Mul, {op(Op::IntDiv, {op(Op::Mul, {k, integer(M)}), integer(1LL << s)}), integer(d)})});
}

int prepare_function(Module& m) {
    if (int f = m.find(names::kPrepare); f >= 0) return f;
    Function f;
    f.name = f.glsl_name = names::kPrepare;
    m.functions.push_back(std::move(f));
    return int(m.functions.size() - 1);
}

std::vector<ValueId> members_within(Module& m, int& prep, const std::string& body_name, size_t members,
                                    const std::vector<MemberTest>& tests, const std::vector<std::string>& state_names) {
    const size_t tiers = state_names.size();
    {
        Function body;
        body.name = body.glsl_name = body_name;
        Builder b(m, body);
        const ValueId k = b.param("k", Type::integer());
        std::vector<ValueId> state, value;
        for (const std::string& n : state_names) state.push_back(b.param(n, Type::scalar()));
        for (const MemberTest& t : tests) {
            const Global& g = m.globals[size_t(t.global)];
            ValueId v = b.global(t.global);
            int c = t.component;
            if (g.type.is_array()) {  // (member k's element of a table; else a sequence's element, by the flat component)
                const int n = g.type.element().components();
                v = b.op(Op::Index, {v, g.per_member ? k : b.integer(c / n)});
                if (!g.per_member) c %= n;
            }
            if (!(g.type.is_array() ? g.type.element() : g.type).is_scalar()) v = b.op(Op::Extract, {v}, c);
            value.push_back(v);
        }
        for (size_t tier = 0; tier < tiers; ++tier) {
            ValueId all = ValueId(-1);
            for (size_t j = 0; j < tests.size(); ++j) {
                const ValueId in = b.op(Op::And, {b.compare(CompareKind::Ge, value[j], b.scalar(tests[j].lo[tier])),
                                                  b.compare(CompareKind::Le, value[j], b.scalar(tests[j].hi[tier]))});
                all = all == ValueId(-1) ? in : b.op(Op::And, {all, in});
            }
            body.outputs.push_back({state_names[tier], all == ValueId(-1) ? state[tier] : b.op(Op::Select, {all, state[tier], b.scalar(0)})});
        }
        body.result = body.outputs[0].second;
        m.functions.push_back(std::move(body));
    }
    const int fn = int(m.functions.size() - 1);
    if (prep < 0) prep = prepare_function(m);
    Function& pf = m.functions[size_t(prep)];
    Builder b(m, pf);
    Instr loop;
    loop.op = Op::Loop;
    loop.type = Type::tuple(int(tiers));
    loop.args = {b.integer((long long)members - 1)};
    for (size_t t = 0; t < tiers; ++t) loop.args.push_back(b.scalar(1));
    loop.aux = fn;
    loop.data = {0};
    const ValueId lv = pf.add(std::move(loop));
    std::vector<ValueId> out;
    for (size_t t = 0; t < tiers; ++t) {
        Instr mem;
        mem.op = Op::Member;
        mem.type = Type::scalar();
        mem.args = {lv};
        mem.aux = int(t);
        out.push_back(pf.add(std::move(mem)));
    }
    return out;
}

}  // namespace iqc::ir
