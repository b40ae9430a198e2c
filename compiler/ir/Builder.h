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

// One value a loop over a group's members tests (members_within): component `component` of global `global` (a per-member
// table: of its element k at member k; any other global, the same for every member: its flat component) against an interval per tier
// [lo[t], hi[t]] (the ends as given: the shader compares its uniforms, floats, with these numbers).
struct MemberTest {
    int global = -1;
    int component = 0;
    std::vector<double> lo, hi;  // per tier
};

// The index of `m`'s iqc_prepare function (names::kPrepare), made empty where there is none.
int prepare_function(Module& m);

// Appends to `m`'s function `prep` (iqc_prepare, made where -1: its index returned in `prep`) a loop over the members
// k = 0..members-1, its body a new function `body_name` whose states (one per tier, named state_names[t], each ℝ: 1 at
// the start) stay 1 while every test holds at member k; returns the states after the loop, values of `prep`. Once per
// pixel, where a group's bounds hold only while every member's sliders are within some intervals (the Lipschitz pass's
// hull of the members' values, the scene box's window around their defaults).
std::vector<ValueId> members_within(Module& m, int& prep, const std::string& body_name, size_t members,
                                    const std::vector<MemberTest>& tests, const std::vector<std::string>& state_names);

}  // namespace iqc::ir
