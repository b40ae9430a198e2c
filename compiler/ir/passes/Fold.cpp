#include "ir/passes/Fold.h"

#include <cmath>

#include "ir/Eval.h"

namespace iqc::ir {

namespace {

bool is_const(const Function& f, ValueId v) { return f.body[v].op == Op::Const; }

bool all_equal(const Function& f, ValueId v, double x) {
    if (!is_const(f, v)) return false;
    for (double c : f.body[v].data)
        if (c != x) return false;
    return true;
}

bool is_identity(const Function& f, ValueId v) {
    const Instr& in = f.body[v];
    if (in.op != Op::Const || !in.type.is_matrix() || in.type.rows != in.type.cols) return false;
    for (int r = 0; r < in.type.rows; ++r)
        for (int c = 0; c < in.type.cols; ++c)
            if (in.data[size_t(r * in.type.cols + c)] != (r == c ? 1.0 : 0.0)) return false;
    return true;
}

bool foldable(Op op) {
    switch (op) {
        case Op::Const: case Op::Param: case Op::Input: case Op::Call: case Op::Loop: case Op::Member:
        case Op::Global: case Op::Index: case Op::If: case Op::Switch: case Op::Copy:
            return false;
        default: return true;
    }
}

// Replaces `in` by a constant of its type, keeping its name, source and span.
void make_constant(Instr& in, Type t, std::vector<double> data) {
    std::string name = std::move(in.name), source = std::move(in.source);
    Span span = in.span;
    in = Instr{};
    in.op = Op::Const;
    in.type = t;
    in.data = std::move(data);
    in.name = std::move(name);
    in.source = std::move(source);
    in.span = span;
}

}  // namespace

int fold_constants(const Module& m, Function& f) {
    std::vector<ValueId> remap(f.body.size());
    int changed = 0;
    for (size_t i = 0; i < f.body.size(); ++i) {
        remap[i] = ValueId(i);
        Instr& in = f.body[i];
        for (ValueId& a : in.args) a = remap[a];
        // A constant element of a constant global (a fact of the scene, not a slider) is its value. Whole
        // constant globals stay: they are named in the output.
        if (in.op == Op::Index && f.body[in.args[0]].op == Op::Global && is_const(f, in.args[1])) {
            const Global& g = m.globals[size_t(f.body[in.args[0]].aux)];
            size_t n = size_t(std::max(1, in.type.components())), k = size_t(f.body[in.args[1]].data[0]);
            if (g.kind == Global::Kind::Constant && (k + 1) * n <= g.value.size()) {
                make_constant(in, in.type, std::vector<double>(g.value.begin() + long(k * n), g.value.begin() + long((k + 1) * n)));
                ++changed;
            }
            continue;
        }
        if (!foldable(in.op) || in.type.kind == Type::Tuple) {
            // A lazy choice with a constant condition or selector is the chosen operand.
            if (in.name.empty() && in.op == Op::If && is_const(f, in.args[0])) {
                remap[i] = in.args[f.body[in.args[0]].data[0] != 0 ? 1 : 2];
                ++changed;
            } else if (in.name.empty() && in.op == Op::Switch && is_const(f, in.args[0])) {
                double sel = f.body[in.args[0]].data[0];
                size_t arm = 1;
                for (int k = 0; k < switch_cases(in); ++k)
                    if (sel >= in.data[size_t(2 * k)] && sel < in.data[size_t(2 * k + 1)]) arm = size_t(2 + k);
                remap[i] = in.args[arm];
                ++changed;
            }
            continue;
        }
        bool consts = !in.args.empty();
        for (ValueId a : in.args) consts &= is_const(f, a);
        if (consts) {
            std::vector<Value> vals;
            for (ValueId a : in.args) vals.push_back({f.body[a].type, f.body[a].data});
            std::vector<const Value*> ptrs;
            for (auto& v : vals) ptrs.push_back(&v);
            Value r = eval_instr(m, f, in, ptrs);
            // A NaN or ∞ stays an operation: the range pass guards it (pow(-2, 0.5), 1/0, ln 0) with the
            // meaning the shader and the evaluator share, and says so; a constant NaN would reach the output.
            bool finite = true;
            for (double x : r.v) finite &= std::isfinite(x);
            if (!finite) continue;
            make_constant(in, in.type, r.v);
            ++changed;
            continue;
        }
        if (!in.name.empty()) continue;  // named statements keep their own instruction
        auto redirect = [&](ValueId to) {
            remap[i] = to;
            ++changed;
        };
        switch (in.op) {
            case Op::Mul:
                // (-1)·x = -x
                if (all_equal(f, in.args[0], -1.0) && f.body[in.args[0]].type.is_scalar() && f.body[in.args[1]].type == in.type &&
                    in.type.kind != Type::Integer) {
                    in.op = Op::Neg;
                    in.args = {in.args[1]};
                    ++changed;
                    break;
                }
                if (is_identity(f, in.args[0]) && f.body[in.args[1]].type == in.type) redirect(in.args[1]);
                else if (is_identity(f, in.args[1]) && f.body[in.args[0]].type == in.type) redirect(in.args[0]);
                else if (all_equal(f, in.args[0], 1.0) && f.body[in.args[0]].type.is_scalar() && f.body[in.args[1]].type == in.type)
                    redirect(in.args[1]);
                else if (all_equal(f, in.args[1], 1.0) && f.body[in.args[1]].type.is_scalar() && f.body[in.args[0]].type == in.type)
                    redirect(in.args[0]);
                break;
            case Op::Hadamard:
                // x ⊙ (1, 1, 1) = x (a lattice's spacing of 1 scaling its cell)
                if (all_equal(f, in.args[0], 1.0) && f.body[in.args[1]].type == in.type) redirect(in.args[1]);
                else if (all_equal(f, in.args[1], 1.0) && f.body[in.args[0]].type == in.type) redirect(in.args[0]);
                break;
            case Op::Add:
                if (all_equal(f, in.args[0], 0.0) && f.body[in.args[1]].type == in.type) redirect(in.args[1]);
                else if (all_equal(f, in.args[1], 0.0) && f.body[in.args[0]].type == in.type) redirect(in.args[0]);
                else if (f.body[in.args[1]].op == Op::Neg && f.body[in.args[1]].type == in.type) {  // a + (-b) = a - b
                    in.op = Op::Sub;
                    in.args[1] = f.body[in.args[1]].args[0];
                    ++changed;
                }
                break;
            case Op::Sub:
                if (all_equal(f, in.args[1], 0.0) && f.body[in.args[0]].type == in.type) redirect(in.args[0]);
                break;
            case Op::Div:  // x/1 (a blend divided by its members' largest Lipschitz factor, 1)
                if (all_equal(f, in.args[1], 1.0) && f.body[in.args[1]].type.is_scalar() && f.body[in.args[0]].type == in.type)
                    redirect(in.args[0]);
                break;
            case Op::Transpose:
                if (is_identity(f, in.args[0])) redirect(in.args[0]);
                break;
            default: break;
        }
    }
    f.result = remap[f.result];
    for (auto& [name, v] : f.outputs) v = remap[v];
    return changed;
}

}  // namespace iqc::ir
