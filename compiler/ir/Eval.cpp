#include "ir/Eval.h"

#include <cmath>
#include <fmt/format.h>
#include <stdexcept>

#include "sema/Builtins.h"

namespace iqc::ir {

std::vector<double> mat_inverse(const std::vector<double>& a, int n, bool* singular) {
    // Gauss-Jordan elimination with partial pivoting.
    std::vector<double> m = a, inv(size_t(n * n), 0.0);
    for (int i = 0; i < n; ++i) inv[size_t(i * n + i)] = 1.0;
    double scale = 0;
    for (double x : a) scale = std::max(scale, std::fabs(x));
    if (singular) *singular = false;
    for (int c = 0; c < n; ++c) {
        int p = c;
        for (int r = c + 1; r < n; ++r)
            if (std::fabs(m[size_t(r * n + c)]) > std::fabs(m[size_t(p * n + c)])) p = r;
        double pv = m[size_t(p * n + c)];
        if (std::fabs(pv) <= 1e-12 * std::max(scale, 1e-300)) {
            if (singular) *singular = true;
            return std::vector<double>(size_t(n * n), NAN);
        }
        if (p != c)
            for (int k = 0; k < n; ++k) {
                std::swap(m[size_t(p * n + k)], m[size_t(c * n + k)]);
                std::swap(inv[size_t(p * n + k)], inv[size_t(c * n + k)]);
            }
        for (int k = 0; k < n; ++k) {
            m[size_t(c * n + k)] /= pv;
            inv[size_t(c * n + k)] /= pv;
        }
        for (int r = 0; r < n; ++r) {
            if (r == c) continue;
            double f = m[size_t(r * n + c)];
            if (f == 0) continue;
            for (int k = 0; k < n; ++k) {
                m[size_t(r * n + k)] -= f * m[size_t(c * n + k)];
                inv[size_t(r * n + k)] -= f * inv[size_t(c * n + k)];
            }
        }
    }
    return inv;
}

double mat_det(const std::vector<double>& a, int n) {
    std::vector<double> m = a;
    double det = 1;
    for (int c = 0; c < n; ++c) {
        int p = c;
        for (int r = c + 1; r < n; ++r)
            if (std::fabs(m[size_t(r * n + c)]) > std::fabs(m[size_t(p * n + c)])) p = r;
        if (m[size_t(p * n + c)] == 0) return 0;
        if (p != c) {
            for (int k = 0; k < n; ++k) std::swap(m[size_t(p * n + k)], m[size_t(c * n + k)]);
            det = -det;
        }
        det *= m[size_t(c * n + c)];
        for (int r = c + 1; r < n; ++r) {
            double f = m[size_t(r * n + c)] / m[size_t(c * n + c)];
            for (int k = c; k < n; ++k) m[size_t(r * n + k)] -= f * m[size_t(c * n + k)];
        }
    }
    return det;
}

namespace {

Value scalar(double x) { return {Type::scalar(), {x}}; }

Value elementwise(const Type& t, const Value& a, const Value& b, double (*f)(double, double)) {
    Value r{t, std::vector<double>(size_t(t.components()))};
    for (size_t i = 0; i < r.v.size(); ++i)
        r.v[i] = f(a.v.size() == 1 ? a.v[0] : a.v[i], b.v.size() == 1 ? b.v[0] : b.v[i]);
    return r;
}

Value multiply(const Type& t, const Value& a, const Value& b) {
    if (a.v.size() == 1 || b.v.size() == 1) {
        const Value& s = a.v.size() == 1 ? a : b;
        const Value& x = a.v.size() == 1 ? b : a;
        Value r{t, x.v};
        for (auto& c : r.v) c *= s.v[0];
        return r;
    }
    // General (rows×inner)·(inner×cols); vectors are columns, row vectors are 1×n.
    int ar = a.type.is_matrix() ? a.type.rows : a.type.rows;
    int ac = a.type.is_matrix() ? a.type.cols : 1;
    int bc = b.type.is_matrix() ? b.type.cols : 1;
    int br = b.type.is_matrix() ? b.type.rows : b.type.rows;
    if (ac != br) throw std::logic_error("evaluator: multiply sizes");
    Value r{t, std::vector<double>(size_t(ar * bc), 0.0)};
    for (int i = 0; i < ar; ++i)
        for (int j = 0; j < bc; ++j) {
            double s = 0;
            for (int k = 0; k < ac; ++k) s += a.v[size_t(i * ac + k)] * b.v[size_t(k * bc + j)];
            r.v[size_t(i * bc + j)] = s;
        }
    return r;
}

Value run_builtin(const Instr& in, const std::vector<const Value*>& a) {
    const BuiltinInfo& b = builtin(in.aux);
    const Type& t = in.type;
    Value r{t, std::vector<double>(size_t(t.components()))};
    auto at = [](const Value* v, size_t i) { return v->v.size() == 1 ? v->v[0] : v->v[i]; };
    switch (b.sig) {
        case Sig::Elementwise1:
            for (size_t i = 0; i < r.v.size(); ++i) r.v[i] = b.eval1(a[0]->v[i]);
            return r;
        case Sig::Elementwise2:
        case Sig::Nary: {
            for (size_t i = 0; i < r.v.size(); ++i) {
                double acc = at(a[0], i);
                for (size_t k = 1; k < a.size(); ++k) acc = b.eval2(acc, at(a[k], i));
                r.v[i] = acc;
            }
            return r;
        }
        case Sig::Clamp:
            if (std::string(b.name) == "smoothstep") {
                for (size_t i = 0; i < r.v.size(); ++i) {
                    double e0 = at(a[0], i), e1 = at(a[1], i), x = at(a[2], i);
                    double t = std::fmin(std::fmax((x - e0) / (e1 - e0), 0.0), 1.0);
                    r.v[i] = t * t * (3 - 2 * t);
                }
                return r;
            }
            for (size_t i = 0; i < r.v.size(); ++i) r.v[i] = std::fmin(std::fmax(at(a[0], i), at(a[1], i)), at(a[2], i));
            return r;
        case Sig::Mix:
            for (size_t i = 0; i < r.v.size(); ++i) r.v[i] = at(a[0], i) * (1 - at(a[2], i)) + at(a[1], i) * at(a[2], i);
            return r;
        case Sig::Length: {
            double s = 0;
            for (double x : a[0]->v) s += x * x;
            r.v[0] = std::sqrt(s);
            return r;
        }
        case Sig::Normalize: {
            double s = 0;
            for (double x : a[0]->v) s += x * x;
            s = std::sqrt(s);
            for (size_t i = 0; i < r.v.size(); ++i) r.v[i] = a[0]->v[i] / s;
            return r;
        }
        default:  // lowered to other operations (sema/Builtins.h): never an Op::Builtin
            throw std::logic_error(std::string("evaluator: '") + b.name + "' has no built-in form");
    }
    return r;
}

}  // namespace

Value eval_instr(const Module& m, const Function& f, const Instr& in, const std::vector<const Value*>& a,
                 const std::vector<Value>& args, const EvalInputs& inputs) {
    Value r;
    r.type = in.type;
    switch (in.op) {
        case Op::Const: r.v = in.data; break;
        case Op::Param: r.v = args.at(size_t(in.aux)).v; break;
        case Op::Input:
            if (in.aux == 0) r.v = {inputs.time};
            else r.v = {inputs.mouse[0], inputs.mouse[1]};
            break;
        case Op::Copy: r.v = a[0]->v; break;
        case Op::Add: r = elementwise(in.type, *a[0], *a[1], [](double x, double y) { return x + y; }); break;
        case Op::Sub: r = elementwise(in.type, *a[0], *a[1], [](double x, double y) { return x - y; }); break;
        case Op::Hadamard: r = elementwise(in.type, *a[0], *a[1], [](double x, double y) { return x * y; }); break;
        case Op::Div: r = elementwise(in.type, *a[0], *a[1], [](double x, double y) { return x / y; }); break;
        case Op::Neg:
            r.v = a[0]->v;
            for (auto& x : r.v) x = -x;
            break;
        case Op::Mul: r = multiply(in.type, *a[0], *a[1]); break;
        case Op::Dot: {
            double s = 0;
            for (size_t k = 0; k < a[0]->v.size(); ++k) s += a[0]->v[k] * a[1]->v[k];
            r.v = {s};
            break;
        }
        case Op::Cross: {
            const auto& x = a[0]->v;
            const auto& y = a[1]->v;
            r.v = {x[1] * y[2] - x[2] * y[1], x[2] * y[0] - x[0] * y[2], x[0] * y[1] - x[1] * y[0]};
            break;
        }
        case Op::Transpose: {
            const Type& at = a[0]->type;
            if (at.is_vector()) { r.v = a[0]->v; break; }
            r.v.resize(a[0]->v.size());
            for (int i2 = 0; i2 < at.rows; ++i2)
                for (int j = 0; j < at.cols; ++j) r.v[size_t(j * at.rows + i2)] = a[0]->v[size_t(i2 * at.cols + j)];
            break;
        }
        case Op::Inverse: r.v = mat_inverse(a[0]->v, a[0]->type.rows, nullptr); break;
        case Op::Det: r.v = {mat_det(a[0]->v, a[0]->type.rows)}; break;
        case Op::Builtin: r = run_builtin(in, a); break;
        case Op::Construct:
            for (auto* x : a) r.v.insert(r.v.end(), x->v.begin(), x->v.end());
            break;
        case Op::Extract: r.v = {a[0]->v[size_t(in.aux)]}; break;
        case Op::Element: {
            size_t n = size_t(in.type.components());
            r.v.assign(a[0]->v.begin() + long(n * size_t(in.aux)), a[0]->v.begin() + long(n * size_t(in.aux + 1)));
            break;
        }
        case Op::At: {
            // Indices are rounded and clamped to the range (a shader cannot stop; GLSL does the same).
            const Type& t = a[0]->type;
            auto index = [&](size_t k, int n) {
                double x = std::floor(a[k]->v[0] + 0.5);
                return size_t(std::isnan(x) ? 0 : std::min(std::max(x, 0.0), double(n - 1)));
            };
            if (t.is_array()) {
                size_t n = size_t(in.type.components()), i = index(1, t.count);
                r.v.assign(a[0]->v.begin() + long(n * i), a[0]->v.begin() + long(n * (i + 1)));
            } else if (t.is_vector()) {
                r.v = {a[0]->v[index(1, t.rows)]};
            } else {
                r.v = {a[0]->v[index(1, t.rows) * size_t(t.cols) + index(2, t.cols)]};
            }
            break;
        }
        case Op::Row: {
            int c = a[0]->type.cols;
            r.v.assign(a[0]->v.begin() + in.aux * c, a[0]->v.begin() + (in.aux + 1) * c);
            break;
        }
        case Op::Column: {
            int rows = a[0]->type.rows, c = a[0]->type.cols;
            for (int k = 0; k < rows; ++k) r.v.push_back(a[0]->v[size_t(k * c + in.aux)]);
            break;
        }
        case Op::Compare: {
            double x = a[0]->v[0], y = a[1]->v[0];
            bool b = false;
            switch (CompareKind(in.aux)) {
                case CompareKind::Eq: b = x == y; break;
                case CompareKind::Ne: b = x != y; break;
                case CompareKind::Lt: b = x < y; break;
                case CompareKind::Le: b = x <= y; break;
                case CompareKind::Gt: b = x > y; break;
                case CompareKind::Ge: b = x >= y; break;
            }
            r.v = {b ? 1.0 : 0.0};
            break;
        }
        case Op::And: r.v = {(a[0]->v[0] != 0 && a[1]->v[0] != 0) ? 1.0 : 0.0}; break;
        case Op::Or: r.v = {(a[0]->v[0] != 0 || a[1]->v[0] != 0) ? 1.0 : 0.0}; break;
        case Op::Select: r.v = a[0]->v[0] != 0 ? a[1]->v : a[2]->v; break;
        case Op::Loop: {
            const Function& body = m.functions[size_t(in.aux)];
            size_t states = body.outputs.size();
            std::vector<Value> bargs(a.size());
            for (size_t k = 1; k < a.size(); ++k) bargs[k] = *a[k];
            double hi = std::floor(a[0]->v[0] + 0.5);
            for (double k = in.data[0]; k <= hi; k += 1) {
                bargs[0] = {Type::integer(), {k}};
                auto res = evaluate_all(m, in.aux, bargs, inputs);
                for (size_t j = 0; j < states; ++j) bargs[j + 1] = res[body.outputs[j].second];
            }
            r.v.clear();
            for (size_t j = 0; j < states; ++j) r.v.insert(r.v.end(), bargs[j + 1].v.begin(), bargs[j + 1].v.end());
            break;
        }
        case Op::Member: {
            const Instr& loop = f.body[in.args[0]];
            const Function& body = m.functions[size_t(loop.aux)];
            size_t off = 0;
            for (int j = 0; j < in.aux; ++j) off += size_t(body.body[body.outputs[size_t(j)].second].type.components());
            r.v.assign(a[0]->v.begin() + long(off), a[0]->v.begin() + long(off) + in.type.components());
            break;
        }
        case Op::Call: {
            std::vector<Value> cargs;
            for (auto* x : a) cargs.push_back(*x);
            r = evaluate(m, in.aux, cargs, inputs);
            break;
        }
    }
    r.type = in.type;
    return r;
}

std::vector<Value> evaluate_all(const Module& m, int fn, const std::vector<Value>& args, const EvalInputs& inputs) {
    const Function& f = m.functions[size_t(fn)];
    std::vector<Value> vals(f.body.size());
    for (size_t i = 0; i < f.body.size(); ++i) {
        const Instr& in = f.body[i];
        std::vector<const Value*> a;
        for (ValueId id : in.args) a.push_back(&vals[id]);
        vals[i] = eval_instr(m, f, in, a, args, inputs);
    }
    return vals;
}

Value evaluate(const Module& m, int fn, const std::vector<Value>& args, const EvalInputs& inputs) {
    auto all = evaluate_all(m, fn, args, inputs);
    return all[m.functions[size_t(fn)].result];
}

std::string format_value(const Value& v) {
    auto num = [](double x) { return fmt::format("{}", x); };
    if (v.type.is_vector()) {
        std::string s = "(";
        for (size_t i = 0; i < v.v.size(); ++i) s += (i ? ", " : "") + num(v.v[i]);
        return s + ")";
    }
    if (v.type.is_matrix()) {
        std::string s = "[";
        for (int r = 0; r < v.type.rows; ++r) {
            if (r) s += "; ";
            for (int c = 0; c < v.type.cols; ++c) s += (c ? " " : "") + num(v.v[size_t(r * v.type.cols + c)]);
        }
        return s + "]";
    }
    if (v.type.is_array()) {  // a sequence: {x_1, x_2, ...}
        std::string s = "{";
        size_t n = size_t(v.type.element().components());
        for (int i = 0; i < v.type.count; ++i) {
            Value e{v.type.element(), std::vector<double>(v.v.begin() + long(n * size_t(i)), v.v.begin() + long(n * size_t(i + 1)))};
            s += (i ? ", " : "") + format_value(e);
        }
        return s + "}";
    }
    if (v.type.kind == Type::Bool) return v.v[0] != 0 ? "true" : "false";
    return num(v.v.empty() ? NAN : v.v[0]);
}

}  // namespace iqc::ir
