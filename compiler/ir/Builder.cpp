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

}  // namespace iqc::ir
