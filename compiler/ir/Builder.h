// The IR builder: appends typed instructions to a function. Every instruction's type comes from the one
// set of typing rules (ir::result_type), and an ill-typed request is an internal error, so what a builder
// makes always verifies.
#pragma once

#include <string>
#include <tuple>
#include <vector>

#include "ir/IR.h"

namespace iqc::ir {

class Builder {
public:
    Builder(const Module& m, Function& f) : m_(m), f_(f) {}
    Function& function() { return f_; }
    const Type& type(ValueId v) const { return f_.body[v].type; }

    ValueId param(const std::string& name, const Type& t, ValueBounds bounds = {});
    ValueId constant(const Type& t, std::vector<double> data);
    ValueId scalar(double x) { return constant(Type::scalar(), {x}); }
    ValueId integer(long long n) { return constant(Type::integer(), {double(n)}); }
    // Any operation typed by ir::result_type (Add, Mul, Dot, Extract (aux), Compare (aux), Select, ...).
    ValueId op(Op op, std::vector<ValueId> args, int aux = 0);
    ValueId builtin(const char* name, std::vector<ValueId> args);
    ValueId compare(CompareKind k, ValueId a, ValueId b) { return op(Op::Compare, {a, b}, int(k)); }
    ValueId construct(const Type& t, std::vector<ValueId> parts);
    ValueId global(int g);
    ValueId call(int fn, std::vector<ValueId> args);
    // A lazy choice: only the chosen operand is computed.
    ValueId if_(ValueId cond, ValueId a, ValueId b) { return op(Op::If, {cond, a, b}); }
    // Lazy: the case whose [lo, hi) holds the selector, else the default. Adjacent cases with the same value
    // become one.
    ValueId switch_(ValueId selector, ValueId fallback, std::vector<std::tuple<long long, long long, ValueId>> cases);
    // Gives v a name (and the statement as written, for the emitted comment): a copy when v already has one.
    ValueId named(ValueId v, const std::string& name, const std::string& source = "");

private:
    const Module& m_;
    Function& f_;
    ValueId add(Instr in);
};

}  // namespace iqc::ir
