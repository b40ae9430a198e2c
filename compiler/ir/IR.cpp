#include "ir/IR.h"

#include <fmt/format.h>

#include "sema/Builtins.h"

namespace iqc {

static const char* kSuperDigits[] = {"⁰", "¹", "²", "³", "⁴", "⁵", "⁶", "⁷", "⁸", "⁹"};

std::string Type::str() const {
    auto sup = [](int n) {
        std::string s;
        for (char c : std::to_string(n)) s += kSuperDigits[c - '0'];
        return s;
    };
    switch (kind) {
        case Invalid: return "<invalid>";
        case Scalar: return "ℝ";
        case Integer: return "ℤ";
        case Bool: return "condition";
        case Vector: return "ℝ" + sup(rows);
        case Matrix: return fmt::format("ℝ^({}×{})", rows, cols);
        case Tuple: return fmt::format("tuple({})", rows);
        case Array: return fmt::format("{}[{}]", element().str(), count);
    }
    return "?";
}

namespace ir {

std::string size_limit_message() {
    return fmt::format("this expands to more than {} IR instructions in one function (local functions calling each "
                       "other more than once, or sums over large ranges, unroll to that much code): write it with "
                       "fewer repetitions",
                       limits::kMaxFunctionInstructions);
}

const char* op_name(Op op) {
    switch (op) {
#define X(name, n) \
    case Op::name: return #name;
        IQC_IR_OPS(X)
#undef X
    }
    return "?";
}

int op_arity(Op op) {
    switch (op) {
#define X(name, n) \
    case Op::name: return n;
        IQC_IR_OPS(X)
#undef X
    }
    return -1;
}

ValueId Function::constant(Type t, std::vector<double> data) {
    Instr in;
    in.op = Op::Const;
    in.type = t;
    in.data = std::move(data);
    return add(std::move(in));
}

int Module::find(const std::string& name) const {
    for (size_t i = 0; i < functions.size(); ++i)
        if (functions[i].name == name) return int(i);
    return -1;
}

int Module::find_global(const std::string& name) const {
    for (size_t i = 0; i < globals.size(); ++i)
        if (globals[i].name == name) return int(i);
    return -1;
}

std::unordered_map<std::string_view, int> Module::global_index() const {
    std::unordered_map<std::string_view, int> index;
    for (size_t g = 0; g < globals.size(); ++g) index.emplace(globals[g].name, int(g));
    return index;
}

namespace {
// Whether value t of a loop body reads a state (a parameter 1 … states), directly or through other values.
bool reads_state(const Function& body, ValueId t) {
    const size_t states = body.outputs.size();
    std::vector<char> reads(size_t(t) + 1, 0);
    for (size_t i = 0; i <= t; ++i) {
        const Instr& in = body.body[i];
        reads[i] = in.op == Op::Param && in.aux >= 1 && size_t(in.aux) <= states;
        for (ValueId a : in.args) reads[i] |= reads[a];
    }
    return reads[t] != 0;
}
}  // namespace

std::optional<ValueId> accumulated_term(const Function& body, size_t j) {
    const size_t states = body.outputs.size();
    if (j >= states) return std::nullopt;
    const Instr& out = body.body[body.outputs[j].second];
    if (out.op != Op::Add || out.args.size() != 2) return std::nullopt;
    auto is_state = [&](ValueId v) { return body.body[v].op == Op::Param && size_t(body.body[v].aux) == j + 1; };
    const ValueId t = is_state(out.args[0]) ? out.args[1] : is_state(out.args[1]) ? out.args[0] : ValueId(-1);
    if (t == ValueId(-1) || reads_state(body, t)) return std::nullopt;
    return t;
}

std::optional<ValueId> selected_term(const Function& body, size_t j) {
    const size_t states = body.outputs.size();
    if (j >= states) return std::nullopt;
    const Instr& out = body.body[body.outputs[j].second];
    auto is_state = [&](ValueId v) { return body.body[v].op == Op::Param && size_t(body.body[v].aux) == j + 1; };
    ValueId t = ValueId(-1);
    if ((out.op == Op::Select || out.op == Op::If) && out.args.size() == 3)
        t = is_state(out.args[1]) ? out.args[2] : is_state(out.args[2]) ? out.args[1] : ValueId(-1);
    else if (out.op == Op::Builtin && out.args.size() == 2 &&
             (std::string_view(builtin(out.aux).name) == "max" || std::string_view(builtin(out.aux).name) == "min"))
        t = is_state(out.args[0]) ? out.args[1] : is_state(out.args[1]) ? out.args[0] : ValueId(-1);
    if (t == ValueId(-1) || reads_state(body, t)) return std::nullopt;
    return t;
}

void mark_reachable(const Module& m, int fn, std::vector<char>& seen) {
    std::vector<int> stack = {fn};
    while (!stack.empty()) {
        int f = stack.back();
        stack.pop_back();
        if (seen[size_t(f)]) continue;
        seen[size_t(f)] = 1;
        for (const Instr& in : m.functions[size_t(f)].body)
            if ((in.op == Op::Call || in.op == Op::Loop) && !seen[size_t(in.aux)]) stack.push_back(in.aux);
    }
}

Type result_type(Op op, const std::vector<Type>& a, int aux) {
    auto is_num = [](const Type& t) { return t.is_numeric(); };
    switch (op) {
        case Op::Const:
        case Op::Param:
        case Op::Call:
        case Op::Construct:
            return {};  // carried by the instruction itself
        case Op::Input:
            return aux == 0 ? Type::scalar() : aux == 1 ? Type::vector(2) : Type{};
        case Op::Loop:
        case Op::Member:
        case Op::Global:
        case Op::Switch:
            return {};  // checked against the body function, the global or the cases by the verifier
        case Op::Copy:
            return a[0];
        case Op::Index:
            return a[0].is_array() && a[1].kind == Type::Integer ? a[0].element() : Type{};
        case Op::IntDiv:
        case Op::IntMod:
            return a[0].kind == Type::Integer && a[1].kind == Type::Integer ? Type::integer() : Type{};
        case Op::FloorInt:
            return a[0].is_scalar() && a[0].kind != Type::Integer ? Type::integer() : Type{};
        case Op::Add:
        case Op::Sub:
            if (a[0].kind == Type::Integer && a[1].kind == Type::Integer) return Type::integer();
            if (a[0].is_scalar() && a[1].is_scalar()) return Type::scalar();
            return (a[0] == a[1] && is_num(a[0])) ? a[0] : Type{};
        case Op::Neg:
            return is_num(a[0]) ? (a[0].is_scalar() && a[0].kind != Type::Integer ? Type::scalar() : a[0]) : Type{};
        case Op::Mul:
            if (a[0].kind == Type::Integer && a[1].kind == Type::Integer) return Type::integer();
            if (a[0].is_scalar() && is_num(a[1])) return a[1].is_scalar() ? Type::scalar() : a[1];
            if (a[1].is_scalar() && is_num(a[0])) return a[0];
            if (a[0].is_matrix() && a[1].is_vector() && a[0].cols == a[1].rows) return Type::vector(a[0].rows);
            if (a[0].is_matrix() && a[1].is_matrix() && a[0].cols == a[1].rows) {
                if (a[1].cols == 1) return Type::vector(a[0].rows);
                if (a[0].rows == 1 && a[1].cols == 1) return Type::scalar();
                return Type::matrix(a[0].rows, a[1].cols);
            }
            if (a[0].is_vector() && a[1].is_matrix() && a[1].rows == 1)  // outer product a bᵀ
                return Type::matrix(a[0].rows, a[1].cols);
            if (a[0].is_matrix() && a[0].rows == 1 && a[1].is_vector() && a[0].cols == a[1].rows)
                return Type::scalar();
            return {};
        case Op::Div:
            return (is_num(a[0]) && a[1].is_scalar()) ? (a[0].is_scalar() ? Type::scalar() : a[0]) : Type{};
        case Op::Hadamard:
            if (a[0].is_scalar() && a[1].is_scalar()) return Type::scalar();
            return (a[0] == a[1] && is_num(a[0])) ? a[0] : Type{};
        case Op::Dot:
            return (a[0].is_vector() && a[0] == a[1]) ? Type::scalar() : Type{};
        case Op::Cross:
            return (a[0] == Type::vector(3) && a[1] == Type::vector(3)) ? a[0] : Type{};
        case Op::Transpose:
            if (a[0].is_matrix()) {
                if (a[0].rows == 1) return Type::vector(a[0].cols);
                return Type::matrix(a[0].cols, a[0].rows);
            }
            if (a[0].is_vector()) return Type::matrix(1, a[0].rows);
            if (a[0].is_scalar()) return Type::scalar();
            return {};
        case Op::Inverse:
            return (a[0].is_matrix() && a[0].rows == a[0].cols) ? a[0] : Type{};
        case Op::Det:
            return (a[0].is_matrix() && a[0].rows == a[0].cols) ? Type::scalar() : Type{};
        case Op::Builtin: {
            BuiltinCheck c = check_builtin(aux, a);
            return c.error.empty() ? c.type : Type{};
        }
        case Op::Extract:
            return (is_num(a[0]) && aux >= 0 && aux < a[0].components()) ? Type::scalar() : Type{};
        case Op::Element:
            return (a[0].is_array() && aux >= 0 && aux < a[0].count) ? a[0].element() : Type{};
        case Op::At: {
            for (size_t k = 1; k < a.size(); ++k)
                if (!a[k].is_scalar()) return {};
            if (a[0].is_array() && a.size() == 2) return a[0].element();
            if (a[0].is_vector() && a.size() == 2) return Type::scalar();
            if (a[0].is_matrix() && a.size() == 3) return Type::scalar();
            return {};
        }
        case Op::Row:
            return (a[0].is_matrix() && aux >= 0 && aux < a[0].rows) ? Type::vector(a[0].cols) : Type{};
        case Op::Column:
            return (a[0].is_matrix() && aux >= 0 && aux < a[0].cols) ? Type::vector(a[0].rows) : Type{};
        case Op::Compare:
            return (a[0].is_scalar() && a[1].is_scalar()) ? Type::boolean() : Type{};
        case Op::And:
        case Op::Or:
            return (a[0].kind == Type::Bool && a[1].kind == Type::Bool) ? Type::boolean() : Type{};
        case Op::Select:
        case Op::If:
            if (a[0].kind != Type::Bool) return {};
            if (a[1].kind == Type::Integer && a[2].kind == Type::Integer) return Type::integer();
            if (a[1].is_scalar() && a[2].is_scalar()) return Type::scalar();
            return a[1] == a[2] && a[1].valid() ? a[1] : Type{};
    }
    return {};
}

static std::string format_number(double v) { return fmt::format("{}", v); }

static std::string format_list(const std::vector<double>& v) {
    std::string s;
    for (size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + format_number(v[i]);
    return s;
}

// `∈ [0, 2]×[0, 1]` for bounded values; "" for inputs and unbounded ones.
static std::string format_bounds(const ValueBounds& b) {
    if (b.input || b.lo.empty()) return "";
    std::string s = " ∈ ";
    for (size_t i = 0; i < b.lo.size(); ++i)
        s += fmt::format("{}[{}, {}]", i ? "×" : "", format_number(b.lo[i]), format_number(b.hi[i]));
    return s;
}

static std::string instr_text(const Function& f, const Instr& in, const Module* m) {
    std::string s = fmt::format("{} {}", in.type.str(), op_name(in.op));
    switch (in.op) {
        case Op::Const: {
            s += " ";
            for (size_t i = 0; i < in.data.size(); ++i) s += (i ? ", " : "") + format_number(in.data[i]);
            break;
        }
        case Op::Param: s += fmt::format(" #{} {}", in.aux, f.params[size_t(in.aux)].name); break;
        case Op::Input: s += in.aux == 0 ? " time" : " mouse"; break;
        case Op::Loop:
            s += fmt::format(" from {} ", in.data.empty() ? 0 : in.data[0]) +
                 (m && in.aux < int(m->functions.size()) ? m->functions[size_t(in.aux)].name : fmt::format("@{}", in.aux));
            break;
        case Op::Member: s += fmt::format(" .{}", in.aux); break;
        case Op::Global:
            s += fmt::format(" @{}", in.aux);
            if (m && in.aux >= 0 && size_t(in.aux) < m->globals.size()) s += " " + m->globals[size_t(in.aux)].name;
            break;
        case Op::Switch:
            for (int k = 0; k < switch_cases(in); ++k)
                s += fmt::format(" [{}, {})", format_number(in.data[size_t(2 * k)]), format_number(in.data[size_t(2 * k + 1)]));
            break;
        case Op::Builtin: s += fmt::format(" {}", builtin(in.aux).name); break;
        case Op::Call:
            s += " " + (m && in.aux < int(m->functions.size()) ? m->functions[size_t(in.aux)].name
                                                               : fmt::format("@{}", in.aux));
            break;
        case Op::Extract:
        case Op::Element:
        case Op::Row:
        case Op::Column: s += fmt::format(" [{}]", in.aux); break;
        case Op::Compare: {
            static const char* k[] = {"eq", "ne", "lt", "le", "gt", "ge"};
            s += fmt::format(" {}", k[in.aux]);
            break;
        }
        default: break;
    }
    for (size_t i = 0; i < in.args.size(); ++i) s += fmt::format("{} %{}", i ? "," : "", in.args[i]);
    if (!in.name.empty()) s += "  ; " + in.name;
    return s;
}

std::string print(const Function& f, const Module* m) {
    std::string out = fmt::format("{}{}function {}(", f.entry ? "entry " : "", f.inline_hint ? "inline " : "", f.name);
    for (size_t i = 0; i < f.params.size(); ++i)
        out += fmt::format("{}{}: {}{}", i ? ", " : "", f.params[i].name, f.params[i].type.str(),
                           i < f.param_bounds.size() ? format_bounds(f.param_bounds[i]) : "");
    out += fmt::format(") -> {} {{\n", f.result_type().str());
    if (f.lipschitz.object_fn >= 0) {
        const LipschitzSpec& l = f.lipschitz;
        std::string fn = m && size_t(l.object_fn) < m->functions.size() ? m->functions[size_t(l.object_fn)].name
                                                                          : fmt::format("@{}", l.object_fn);
        out += fmt::format("  lipschitz {}{} ball {} group {} declared {} {} shape {}{}\n", fn, format_bounds(l.region),
                           format_number(l.ball), l.group, format_number(l.declared), l.trusted ? "trusted" : "untrusted", l.shape,
                           l.factor_global >= 0 ? fmt::format(" factor @{}", l.factor_global) : "");
    }
    for (size_t i = 0; i < f.body.size(); ++i) out += fmt::format("  %{} = {}\n", i, instr_text(f, f.body[i], m));
    out += fmt::format("  return %{}\n", f.result);
    for (const auto& [name, v] : f.outputs) out += fmt::format("  output {} = %{}\n", name, v);
    out += "}\n";
    return out;
}

std::string print(const Global& g, size_t index) {
    static const char* kinds[] = {"parameter", "constant", "prepared"};
    std::string out = fmt::format("global @{} {}: {} {}", index, g.name, g.type.str(), kinds[int(g.kind)]);
    if (g.kind != Global::Kind::Prepared) out += " = " + format_list(g.value);
    out += format_bounds(g.bounds);
    if (!g.comment.empty()) out += "  ; " + g.comment;
    return out + "\n";
}

std::string print(const Module& m) {
    std::string out = m.constant_parameters ? "constant parameters\n" : "";
    for (size_t i = 0; i < m.globals.size(); ++i) out += print(m.globals[i], i);
    for (const auto& f : m.functions) out += print(f, &m);
    return out;
}

std::string verify(const Function& f, const Module& m) {
    for (size_t i = 0; i < f.body.size(); ++i) {
        const Instr& in = f.body[i];
        auto fault = [&](const std::string& what) {
            return fmt::format("{}: %{} ({}): {}", f.name, i, op_name(in.op), what);
        };
        int arity = op_arity(in.op);
        if (arity >= 0 && int(in.args.size()) != arity) return fault("wrong operand count");
        std::vector<Type> types;
        for (ValueId a : in.args) {
            if (a >= i) return fault(fmt::format("operand %{} is not defined before use", a));
            types.push_back(f.body[a].type);
        }
        if (!in.type.valid()) return fault("invalid type");
        switch (in.op) {
            case Op::Const:
                if (int(in.data.size()) != in.type.components()) return fault("constant size does not match its type");
                break;
            case Op::Param:
                if (in.aux < 0 || size_t(in.aux) >= f.params.size() || f.params[size_t(in.aux)].type != in.type)
                    return fault("parameter index or type mismatch");
                break;
            case Op::Construct: {
                int n = 0;
                for (auto& t : types) n += t.components();
                if (n != in.type.components()) return fault("constructed components do not add up");
                break;
            }
            case Op::Loop: {
                if (in.aux < 0 || size_t(in.aux) >= m.functions.size() || in.data.size() != 1) return fault("bad loop");
                const Function& body = m.functions[size_t(in.aux)];
                size_t states = body.outputs.size();
                if (in.type != Type::tuple(int(states))) return fault("loop type does not match its body's outputs");
                // args: the last index, the initial states, the captures; body params: the index, the states, the captures.
                if (body.params.size() != in.args.size() || in.args.size() < states + 1) return fault("loop arity mismatch");
                if (!types[0].is_scalar()) return fault("loop end is not a scalar");
                for (size_t k = 1; k < in.args.size(); ++k)
                    if (body.params[k].type != types[k] && !(body.params[k].type.is_scalar() && types[k].is_scalar()))
                        return fault("loop argument type mismatch");
                break;
            }
            case Op::Member: {
                const Instr& loop = f.body[in.args[0]];
                if (loop.op != Op::Loop) return fault("member of a non-loop");
                const Function& body = m.functions[size_t(loop.aux)];
                if (in.aux < 0 || size_t(in.aux) >= body.outputs.size()) return fault("member out of range");
                Type t = body.body[body.outputs[size_t(in.aux)].second].type;
                if (t != in.type && !(t.is_scalar() && in.type.is_scalar())) return fault("member type mismatch");
                break;
            }
            case Op::Global: {
                if (in.aux < 0 || size_t(in.aux) >= m.globals.size()) return fault("no such global");
                const Global& g = m.globals[size_t(in.aux)];
                if (g.type != in.type) return fault("global type mismatch");
                if (g.kind != Global::Kind::Prepared && int(g.value.size()) != g.type.components())
                    return fault(fmt::format("global {} has {} values for its type {}", g.name, g.value.size(), g.type.str()));
                break;
            }
            case Op::Switch: {
                if (in.args.size() < 2 || in.data.size() != 2 * (in.args.size() - 2)) return fault("switch cases mismatch");
                if (types[0].kind != Type::Integer) return fault("switch selector is not ℤ");
                for (size_t k = 1; k < types.size(); ++k)
                    if (types[k] != in.type && !(types[k].is_scalar() && in.type.is_scalar())) return fault("switch case type mismatch");
                for (int k = 0; k < switch_cases(in); ++k)
                    if (!(in.data[size_t(2 * k)] < in.data[size_t(2 * k + 1)])) return fault("empty switch case");
                break;
            }
            case Op::Call: {
                if (in.aux < 0 || size_t(in.aux) >= m.functions.size()) return fault("bad callee");
                const Function& callee = m.functions[size_t(in.aux)];
                if (callee.params.size() != in.args.size()) return fault("argument count mismatch");
                for (size_t k = 0; k < types.size(); ++k)
                    if (callee.params[k].type != types[k] && !(callee.params[k].type.is_scalar() && types[k].is_scalar()))
                        return fault("argument type mismatch");
                if (callee.result_type() != in.type) return fault("result type mismatch");
                break;
            }
            default: {
                Type t = result_type(in.op, types, in.aux);
                if (t != in.type && !(t.is_scalar() && in.type.is_scalar()))
                    return fault(fmt::format("type {} does not match operands (expected {})", in.type.str(), t.str()));
            }
        }
    }
    if (!f.body.empty() && f.result >= f.body.size()) return fmt::format("{}: result out of range", f.name);
    for (const auto& [name, v] : f.outputs)
        if (v >= f.body.size()) return fmt::format("{}: output {} out of range", f.name, name);
    if (!f.param_bounds.empty() && f.param_bounds.size() != f.params.size())
        return fmt::format("{}: parameter bounds do not match the parameters", f.name);
    return "";
}

std::string verify(const Module& m) {
    for (const auto& f : m.functions)
        if (std::string fault = verify(f, m); !fault.empty()) return fault;
    return "";
}

uint64_t& analysis_work() {
    thread_local uint64_t work = 0;
    return work;
}

}  // namespace ir
}  // namespace iqc
