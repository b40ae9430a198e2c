#include "glsl/Emit.h"

#include <cmath>
#include <fmt/format.h>
#include <functional>
#include <set>

#include "sema/Builtins.h"

namespace iqc::glsl {

using ir::Instr;
using ir::Op;
using ir::ValueId;

std::string type_name(const Type& t, std::string* why) {
    auto fail = [&](std::string w) {
        if (why) *why = std::move(w);
        return std::string();
    };
    switch (t.kind) {
        case Type::Scalar:
        case Type::Integer: return "float";
        case Type::Bool: return "bool";
        case Type::Vector:
            if (t.rows > 4) return fail(fmt::format("{} is larger than GLSL's largest vector (vec4)", t.str()));
            return fmt::format("vec{}", t.rows);
        case Type::Matrix:
            // A row vector (1×n) is a vecN: GLSL's v * M already treats v as a row.
            if (t.rows == 1) {
                if (t.cols > 4) return fail(fmt::format("{} is larger than GLSL's largest vector (vec4)", t.str()));
                return fmt::format("vec{}", t.cols);
            }
            if (t.rows > 4 || t.cols > 4)
                return fail(fmt::format("{} is larger than GLSL's largest matrix (mat4)", t.str()));
            if (t.rows == t.cols) return fmt::format("mat{}", t.rows);
            return fmt::format("mat{}x{}", t.cols, t.rows);  // GLSL: columns x rows
        case Type::Array: {  // a sequence: vec3[4]
            std::string e = type_name(t.element(), why);
            return e.empty() ? e : fmt::format("{}[{}]", e, t.count);
        }
        default: return fail("invalid type");
    }
}

std::string float_literal(double v) {
    if (std::isnan(v)) return "(0.0 / 0.0)";
    if (std::isinf(v)) return v > 0 ? "1.0e38" : "-1.0e38";
    float f = static_cast<float>(v);
    if (f == 0.0f) f = 0.0f;  // no "-0.0"
    std::string s = fmt::format("{}", f);
    size_t e = s.find_first_of("eE");
    std::string mant = e == std::string::npos ? s : s.substr(0, e);
    std::string exp = e == std::string::npos ? "" : s.substr(e);
    if (mant.find('.') == std::string::npos) mant += ".0";
    return mant + exp;
}

std::string constant(const Type& t, const std::vector<double>& v) {
    if (t.is_scalar()) return float_literal(v[0]);
    if (t.is_array()) {
        std::vector<std::string> items;
        size_t n = size_t(t.element().components());
        for (int i = 0; i < t.count; ++i)
            items.push_back(constant(t.element(), std::vector<double>(v.begin() + long(n * size_t(i)),
                                                                      v.begin() + long(n * size_t(i + 1)))));
        return fmt::format("{}({})", type_name(t), fmt::join(items, ", "));
    }
    std::string tn = type_name(t);
    std::vector<std::string> parts;
    if (t.is_vector()) {
        bool same = true;
        for (double x : v) same &= (x == v[0]);
        if (same) return fmt::format("{}({})", tn, float_literal(v[0]));
        for (double x : v) parts.push_back(float_literal(x));
    } else {
        for (int c = 0; c < t.cols; ++c)
            for (int r = 0; r < t.rows; ++r) parts.push_back(float_literal(v[size_t(r * t.cols + c)]));
    }
    return fmt::format("{}({})", tn, fmt::join(parts, ", "));
}

const std::string& Emitter::function_name(int fn) {
    auto it = names_.find(fn);
    if (it != names_.end()) return it->second;
    const ir::Function& f = m_.functions[size_t(fn)];
    return names_[fn] = globals_.unique(f.glsl_name.empty() ? f.name : f.glsl_name);
}

std::vector<int> Emitter::closure(const std::vector<int>& roots) const {
    std::vector<int> order;
    std::set<int> seen;
    std::function<void(int)> visit = [&](int fn) {
        if (seen.count(fn)) return;
        seen.insert(fn);
        std::function<void(int)> scan = [&](int g) {
            for (const Instr& in : m_.functions[size_t(g)].body) {
                if (in.op == Op::Call) visit(in.aux);
                if (in.op == Op::Loop) scan(in.aux);  // bodies are emitted inline, their callees are not
            }
        };
        scan(fn);
        order.push_back(fn);
    };
    for (int r : roots) visit(r);
    return order;
}

namespace {

const char* kSwizzle = "xyzw";

std::string one_line(const std::string& s) {
    std::string out;
    bool space = false;
    for (char c : s) {
        if (c == '\n' || c == '\r' || c == '\t' || c == ' ') {
            space = true;
            continue;
        }
        if (space && !out.empty()) out += ' ';
        space = false;
        out += c;
    }
    return out;
}

struct FunctionEmitter {
    const ir::Module& m;
    const ir::Function& f;
    Emitter& em;
    Diagnostics& diags;
    Namer locals;
    std::vector<int> uses;
    std::vector<bool> live;
    std::vector<std::string> var;  // GLSL variable holding the value, if materialised
    std::map<ValueId, std::vector<std::string>> loop_states;  // a Loop's state variables
    bool failed = false;

    FunctionEmitter(const ir::Module& mod, const ir::Function& fn, Emitter& e, Diagnostics& d, const Namer& globals)
        : m(mod), f(fn), em(e), diags(d), locals(&globals) {}

    std::string type_of(const Type& t, Span span) {
        std::string why;
        std::string n = type_name(t, &why);
        if (n.empty() && !failed) {
            diags.error(span, fmt::format("cannot generate GLSL: {}", why));
            failed = true;
        }
        return n.empty() ? "float" : n;
    }

    // Whether the value is simple enough to repeat rather than give a variable.
    bool trivial(ValueId v) const {
        const Instr& in = f.body[v];
        return in.op == Op::Param || in.op == Op::Input || in.op == Op::Member ||
               (in.op == Op::Const && in.type.is_scalar());
    }

    // A value used more than once gets a variable when recomputing it would cost real work (a call, a
    // square root, ...) or repeat long text; cheap ones such as `P_L - p` stay inline for readability
    // (the driver's own CSE removes the repeat).
    bool worth_a_variable(ValueId v) {
        const Instr& in = f.body[v];
        switch (in.op) {
            case Op::Call: case Op::Inverse: case Op::Det: case Op::Dot: case Op::Cross: case Op::Select:
                return true;
            case Op::Builtin: {
                std::string n = builtin(in.aux).name;
                if (n != "abs" && n != "min" && n != "max" && n != "floor" && n != "ceil" && n != "sign") return true;
                break;
            }
            default: break;
        }
        return expr(v).size() > 40;
    }

    std::string operand(ValueId v) {  // an operand inside a larger expression: parenthesised if compound
        std::string s = expr(v);
        const Instr& in = f.body[v];
        if (!var[v].empty()) return s;
        switch (in.op) {
            case Op::Add: case Op::Sub: case Op::Mul: case Op::Div: case Op::Hadamard: case Op::Compare:
            case Op::And: case Op::Or: case Op::Select: case Op::Neg:
                return "(" + s + ")";
            case Op::Const:
                if (in.type.is_scalar() && in.data[0] < 0) return "(" + s + ")";
                return s;
            default: return s;
        }
    }

    // A value as something `.x` or `[i]` may follow.
    std::string postfix_base(ValueId v) {
        std::string s = expr(v);
        const Instr& in = f.body[v];
        if (!var[v].empty() || in.op == Op::Param || in.op == Op::Builtin || in.op == Op::Call || in.op == Op::Construct ||
            in.op == Op::Dot || in.op == Op::Cross || in.op == Op::Transpose || in.op == Op::Inverse ||
            in.op == Op::Element || in.op == Op::At)
            return s;
        return "(" + s + ")";
    }

    std::string expr(ValueId v) {
        if (!var[v].empty()) return var[v];
        const Instr& in = f.body[v];
        auto a = [&](size_t i) { return operand(in.args[i]); };
        auto plain = [&](size_t i) { return expr(in.args[i]); };
        switch (in.op) {
            case Op::Const: return constant(in.type, in.data);
            case Op::Param: return var[v];
            case Op::Input: return in.aux == 0 ? "iTime" : "(iMouse.xy / iResolution.xy)";
            case Op::Member: return loop_states.at(in.args[0]).at(size_t(in.aux));
            case Op::Loop: return "/* loop */";
            case Op::Copy: return plain(0);
            case Op::Add: return a(0) + " + " + a(1);
            case Op::Sub: return a(0) + " - " + a(1);
            case Op::Mul: {
                const Type& lt = f.body[in.args[0]].type;
                const Type& rt = f.body[in.args[1]].type;
                bool lrow = lt.is_matrix() && lt.rows == 1, rrow = rt.is_matrix() && rt.rows == 1;
                if (lrow && rt.is_vector()) return fmt::format("dot({}, {})", plain(0), plain(1));  // row · column
                if (lt.is_vector() && rrow) return fmt::format("outerProduct({}, {})", plain(0), plain(1));
                return a(0) + " * " + a(1);
            }
            case Op::Div: return a(0) + " / " + a(1);
            case Op::Neg: return "-" + a(0);
            case Op::Hadamard:
                if (in.type.is_matrix() && in.type.rows > 1) return fmt::format("matrixCompMult({}, {})", plain(0), plain(1));
                return a(0) + " * " + a(1);
            case Op::Dot: return fmt::format("dot({}, {})", plain(0), plain(1));
            case Op::Cross: return fmt::format("cross({}, {})", plain(0), plain(1));
            case Op::Transpose: {
                const Type& at = f.body[in.args[0]].type;
                if (at.is_vector() || (at.is_matrix() && at.rows == 1)) return expr(in.args[0]);  // column <-> row: the same vecN
                // The transpose of a matrix built from rows is the matrix with them as columns.
                const Instr& src = f.body[in.args[0]];
                if (var[in.args[0]].empty() && src.op == Op::Construct && at.is_matrix() && int(src.args.size()) == at.rows) {
                    bool rows = true;
                    for (ValueId a : src.args) rows &= f.body[a].type == Type::vector(at.cols);
                    if (rows) {
                        std::vector<std::string> cols;
                        for (ValueId a : src.args) cols.push_back(expr(a));
                        return fmt::format("{}({})", type_of(in.type, in.span), fmt::join(cols, ", "));
                    }
                }
                return fmt::format("transpose({})", plain(0));
            }
            case Op::Inverse: return fmt::format("inverse({})", plain(0));
            case Op::Det: return fmt::format("determinant({})", plain(0));
            case Op::Builtin: {
                std::vector<std::string> args;
                for (size_t i = 0; i < in.args.size(); ++i) args.push_back(plain(i));
                // A template such as `1.0 / tan(#)`: # is the (parenthesised) argument.
                std::string spelling = builtin(in.aux).glsl;
                if (size_t at = spelling.find('#'); at != std::string::npos) return spelling.replace(at, 1, a(0));
                return fmt::format("{}({})", spelling, fmt::join(args, ", "));
            }
            case Op::Construct: {
                std::string tn = type_of(in.type, in.span);
                // vec3(x, x, x) -> vec3(x)
                bool same = in.args.size() > 1;
                for (ValueId x : in.args) same &= (x == in.args[0]);
                if (same && f.body[in.args[0]].type.is_scalar() && in.type.is_vector())
                    return fmt::format("{}({})", tn, plain(0));
                // (p_1, p_3) -> p.xz
                if (in.type.is_vector()) {
                    bool swz = true;
                    ValueId src = 0;
                    std::string sel;
                    for (size_t i = 0; i < in.args.size() && swz; ++i) {
                        const Instr& x = f.body[in.args[i]];
                        if (x.op != Op::Extract || !f.body[x.args[0]].type.is_vector() || !var[in.args[i]].empty()) {
                            swz = false;
                            break;
                        }
                        if (i == 0) src = x.args[0];
                        else if (x.args[0] != src) swz = false;
                        sel += kSwizzle[x.aux];
                    }
                    if (swz) return postfix_base(src) + "." + sel;
                }
                std::vector<std::string> args;
                if (in.type.is_matrix() && in.type.rows > 1) {
                    bool rows = true;
                    for (ValueId a : in.args) rows &= f.body[a].type == Type::vector(in.type.cols);
                    if (rows && int(in.args.size()) == in.type.rows && in.type.cols > 1) {
                        // Whole rows: a matrix with them as columns, transposed.
                        for (size_t i = 0; i < in.args.size(); ++i) args.push_back(plain(i));
                        Type cols_as_rows = Type::matrix(in.type.cols, in.type.rows);
                        return fmt::format("transpose({}({}))", type_of(cols_as_rows, in.span), fmt::join(args, ", "));
                    }
                    // Row-major components (scalars, or vectors' components) -> GLSL's column-major constructor.
                    std::vector<std::string> comps;
                    for (size_t i = 0; i < in.args.size(); ++i) {
                        const Type& t = f.body[in.args[i]].type;
                        if (t.is_scalar()) comps.push_back(plain(i));
                        else
                            for (int k = 0; k < t.components(); ++k) comps.push_back(postfix_base(in.args[i]) + "." + kSwizzle[k]);
                    }
                    for (int c = 0; c < in.type.cols; ++c)
                        for (int r = 0; r < in.type.rows; ++r) args.push_back(comps[size_t(r * in.type.cols + c)]);
                } else {
                    for (size_t i = 0; i < in.args.size(); ++i) args.push_back(plain(i));
                }
                return fmt::format("{}({})", tn, fmt::join(args, ", "));
            }
            case Op::Extract: {
                const Type& st = f.body[in.args[0]].type;
                if (st.is_vector() || (st.is_matrix() && st.rows == 1)) return postfix_base(in.args[0]) + "." + kSwizzle[in.aux];
                return fmt::format("{}[{}][{}]", postfix_base(in.args[0]), in.aux % st.cols, in.aux / st.cols);
            }
            case Op::Column: return fmt::format("{}[{}]", postfix_base(in.args[0]), in.aux);
            case Op::Element: return fmt::format("{}[{}]", postfix_base(in.args[0]), in.aux);
            case Op::At: {  // indices rounded and clamped, as the evaluator does
                const Type& st = f.body[in.args[0]].type;
                auto index = [&](size_t k, int n) {
                    return fmt::format("clamp(int(floor({} + 0.5)), 0, {})", expr(in.args[k]), n - 1);
                };
                if (st.is_matrix())  // GLSL indexes columns first
                    return fmt::format("{}[{}][{}]", postfix_base(in.args[0]), index(2, st.cols), index(1, st.rows));
                return fmt::format("{}[{}]", postfix_base(in.args[0]), index(1, st.is_array() ? st.count : st.rows));
            }
            case Op::Row: {
                const Type& st = f.body[in.args[0]].type;
                if (st.rows == 1) return expr(in.args[0]);
                std::vector<std::string> parts;
                std::string base = postfix_base(in.args[0]);
                for (int c = 0; c < st.cols; ++c) parts.push_back(fmt::format("{}[{}][{}]", base, c, in.aux));
                return fmt::format("{}({})", type_of(in.type, in.span), fmt::join(parts, ", "));
            }
            case Op::Compare: {
                static const char* ops[] = {"==", "!=", "<", "<=", ">", ">="};
                return fmt::format("{} {} {}", a(0), ops[in.aux], a(1));
            }
            case Op::And: return a(0) + " && " + a(1);
            case Op::Or: return a(0) + " || " + a(1);
            case Op::Select: return fmt::format("{} ? {} : {}", a(0), a(1), a(2));
            case Op::Call: {
                std::vector<std::string> args;
                for (size_t i = 0; i < in.args.size(); ++i) args.push_back(plain(i));
                return fmt::format("{}({})", em.function_name(in.aux), fmt::join(args, ", "));
            }
        }
        return "0.0";
    }

    // Marks what `roots` need (liveness) and counts uses.
    void analyze(const std::vector<ValueId>& roots) {
        size_t n = f.body.size();
        uses.assign(n, 0);
        live.assign(n, false);
        var.assign(n, "");
        for (ValueId r : roots) {
            live[r] = true;
            uses[r]++;
        }
        for (size_t i = n; i-- > 0;) {
            if (!live[i]) continue;
            for (ValueId a : f.body[i].args) {
                live[a] = true;
                uses[a]++;
            }
        }
    }

    // One statement per live named value, shared costly value and loop; `skip` is left as an expression.
    std::string statements(const std::string& indent, ValueId skip) {
        std::string out;
        for (size_t i = 0; i < f.body.size(); ++i) {
            const Instr& in = f.body[i];
            if (!live[i] || in.op == Op::Param || in.op == Op::Member) continue;
            if (in.op == Op::Loop) {
                out += loop(ValueId(i), indent);
                continue;
            }
            bool named = !in.name.empty();
            bool shared = uses[i] > 1 && !trivial(ValueId(i)) && worth_a_variable(ValueId(i));
            if (i == skip && !named) continue;
            if (!named && !shared) continue;
            if (in.op == Op::Construct && !named && in.type.is_vector()) {
                // A shared broadcast such as vec3(x) is cheap: keep it inline.
                bool same = true;
                for (ValueId x : in.args) same &= x == in.args[0];
                if (same) continue;
            }
            out += materialize(ValueId(i), named ? in.name : "tmp", indent, named ? in.source : "");
        }
        return out;
    }

    std::string materialize(ValueId v, const std::string& name, const std::string& indent, const std::string& source) {
        const Instr& in = f.body[v];
        std::string value = expr(v);
        std::string vn = locals.unique(name);
        std::string out = fmt::format("{}{} {} = {};", indent, type_of(in.type, in.span), vn, value);
        if (!source.empty()) out += " // " + one_line(source);
        var[v] = vn;
        return out + "\n";
    }

    // A recurrence: its states as variables, then a for loop computing the next states.
    std::string loop(ValueId v, const std::string& indent) {
        const Instr& in = f.body[v];
        const ir::Function& body = m.functions[size_t(in.aux)];
        size_t states = body.outputs.size();
        std::string out;
        // Captured values are read every iteration: give costly ones a variable first.
        for (size_t k = states + 1; k < in.args.size(); ++k) {
            ValueId a = in.args[k];
            if (var[a].empty() && !trivial(a) && f.body[a].op != Op::Member) out += materialize(a, "tmp", indent, "");
        }
        std::vector<std::string> names;
        for (size_t j = 0; j < states; ++j) {
            const Type& t = body.params[j + 1].type;
            std::string n = locals.unique(body.outputs[j].first);
            out += fmt::format("{}{} {} = {};\n", indent, type_of(t, in.span), n, expr(in.args[j + 1]));
            names.push_back(n);
        }
        loop_states[v] = names;
        std::string k = locals.unique(body.params[0].name);
        const Instr& hi = f.body[in.args[0]];
        std::string hi_text = hi.op == Op::Const ? std::to_string(int(hi.data[0])) : "int(" + expr(in.args[0]) + ")";
        out += fmt::format("{}for (int {} = {}; {} <= {}; {}++) {{  // {}\n", indent, k, int(in.data[0]), k, hi_text, k,
                           one_line(in.source));
        FunctionEmitter be(m, body, em, diags, locals);
        std::vector<ValueId> roots;
        for (auto& o : body.outputs) roots.push_back(o.second);
        be.analyze(roots);
        for (size_t p = 0; p < body.body.size(); ++p) {
            const Instr& pi = body.body[p];
            if (pi.op != Op::Param) continue;
            if (pi.aux == 0) be.var[p] = "float(" + k + ")";
            else if (size_t(pi.aux) <= states) be.var[p] = names[size_t(pi.aux) - 1];
            else be.var[p] = operand(in.args[size_t(pi.aux)]);
        }
        std::string inner = indent + "    ";
        out += be.statements(inner, ValueId(-1));
        if (states == 1) {
            out += fmt::format("{}{} = {};\n", inner, names[0], be.expr(body.outputs[0].second));
        } else {
            std::vector<std::string> next;
            for (size_t j = 0; j < states; ++j) {
                ValueId o = body.outputs[j].second;
                next.push_back(be.locals.unique(names[j] + "_next"));
                out += fmt::format("{}{} {} = {}; // {}\n", inner, type_of(body.body[o].type, in.span), next[j], be.expr(o),
                                   one_line(body.body[o].source));
            }
            for (size_t j = 0; j < states; ++j) out += fmt::format("{}{} = {};\n", inner, names[j], next[j]);
        }
        out += indent + "}\n";
        return out;
    }

    std::string run(const std::string& name, const std::string& comment) {
        size_t n = f.body.size();
        analyze({f.result});
        std::string out;
        if (!comment.empty()) out += "// " + comment + "\n";
        std::vector<std::string> params;
        for (size_t i = 0; i < f.params.size(); ++i) {
            std::string pn = locals.unique(f.params[i].name);
            params.push_back(fmt::format("{} {}", type_of(f.params[i].type, {}), pn));
            for (size_t k = 0; k < n; ++k)
                if (f.body[k].op == Op::Param && f.body[k].aux == int(i)) var[k] = pn;
        }
        out += fmt::format("{} {}({}) {{\n", type_of(f.result_type(), {}), name, fmt::join(params, ", "));
        out += statements("    ", f.result);
        const Instr& r = f.body[f.result];
        std::string rv = expr(f.result);
        out += fmt::format("    return {};", rv);
        if (r.name.empty() && !r.source.empty()) out += " // " + one_line(r.source);
        out += "\n}\n";
        return out;
    }
};

}  // namespace

std::string Emitter::function(int fn, const std::string& comment) {
    const std::string& name = function_name(fn);
    FunctionEmitter fe(m_, m_.functions[size_t(fn)], *this, diags_, globals_);
    return fe.run(name, comment);
}

}  // namespace iqc::glsl
