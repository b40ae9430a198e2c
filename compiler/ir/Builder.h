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
    // k div d and k mod d (ℤ) for k known to lie in [0, n) (d ≥ 1, n ≥ 1), by multiplication and a division by a
    // power of two, which the GLSL backend writes as a shift: ⌊k/d⌋ = ⌊k·M/2^s⌋ with M = ⌈2^s/d⌉ for the
    // smallest s where (n - 1)·(M·d - 2^s) < 2^s, a sufficient condition (Granlund & Montgomery 1994, "Division
    // by invariant integers using multiplication"), and (n - 1)·M < 2^31 (no overflow in 32-bit ints). Where no
    // such s ≤ 30 exists, a plain IntDiv/IntMod. Why: SIMD CPUs (llvmpipe) scalarise an integer division by a
    // constant that is not a power of two (100 tilted tori read by k mod 7: frame +8%; by the product: -4%).
    ValueId div_by_constant(ValueId k, long long d, long long n);
    ValueId mod_by_constant(ValueId k, long long d, long long n);

private:
    const Module& m_;
    Function& f_;
    ValueId add(Instr in);
};

}  // namespace iqc::ir
