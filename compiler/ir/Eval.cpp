#include "ir/Eval.h"

#include <cmath>
#include <fmt/format.h>

#include "ir/Schedule.h"
#include "sema/Builtins.h"
#include "source/Internal.h"

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

// An operand: its components and type.
struct Arg {
    const double* p;
    const Type* t;
    size_t n;  // components
    double at(size_t i) const { return n == 1 ? p[0] : p[i]; }
};

// Components a value of type t occupies (a Bool is one; tuples are laid out by their loop).
size_t slots(const Type& t) { return size_t(std::max(1, t.components())); }

void run_builtin(const Instr& in, const Arg* a, double* r) {
    const BuiltinInfo& b = builtin(in.aux);
    size_t n = slots(in.type);
    switch (b.sig) {
        case Sig::Elementwise1:
            for (size_t i = 0; i < n; ++i) r[i] = b.eval1(a[0].at(i));
            return;
        case Sig::Elementwise2:
        case Sig::Nary:
            for (size_t i = 0; i < n; ++i) {
                double acc = a[0].at(i);
                for (size_t k = 1; k < in.args.size(); ++k) acc = b.eval2(acc, a[k].at(i));
                r[i] = acc;
            }
            return;
        case Sig::Clamp:
            if (std::string_view(b.name) == "smoothstep") {
                for (size_t i = 0; i < n; ++i) {
                    double e0 = a[0].at(i), e1 = a[1].at(i), x = a[2].at(i);
                    double t = std::fmin(std::fmax((x - e0) / (e1 - e0), 0.0), 1.0);
                    r[i] = t * t * (3 - 2 * t);
                }
                return;
            }
            for (size_t i = 0; i < n; ++i) r[i] = std::fmin(std::fmax(a[0].at(i), a[1].at(i)), a[2].at(i));
            return;
        case Sig::Mix:
            for (size_t i = 0; i < n; ++i) r[i] = a[0].at(i) * (1 - a[2].at(i)) + a[1].at(i) * a[2].at(i);
            return;
        case Sig::Length: {
            double s = 0;
            for (size_t i = 0; i < a[0].n; ++i) s += a[0].p[i] * a[0].p[i];
            r[0] = std::sqrt(s);
            return;
        }
        case Sig::Normalize: {
            double s = 0;
            for (size_t i = 0; i < a[0].n; ++i) s += a[0].p[i] * a[0].p[i];
            s = std::sqrt(s);
            for (size_t i = 0; i < n; ++i) r[i] = a[0].p[i] / s;
            return;
        }
        default:  // lowered to other operations (sema/Builtins.h): never an Op::Builtin
            internal_error(fmt::format("evaluator: '{}' has no built-in form", b.name));
    }
}

void multiply(const Type& t, const Arg& a, const Arg& b, double* r) {
    if (a.n == 1 || b.n == 1) {
        const Arg& s = a.n == 1 ? a : b;
        const Arg& x = a.n == 1 ? b : a;
        for (size_t i = 0; i < slots(t); ++i) r[i] = x.p[i] * s.p[0];
        return;
    }
    // General (rows×inner)·(inner×cols); vectors are columns, row vectors are 1×n.
    int ar = a.t->rows, ac = a.t->is_matrix() ? a.t->cols : 1;
    int br = b.t->rows, bc = b.t->is_matrix() ? b.t->cols : 1;
    if (ac != br) internal_error("evaluator: multiply sizes");
    for (int i = 0; i < ar; ++i)
        for (int j = 0; j < bc; ++j) {
            double s = 0;
            for (int k = 0; k < ac; ++k) s += a.p[size_t(i * ac + k)] * b.p[size_t(k * bc + j)];
            r[size_t(i * bc + j)] = s;
        }
}

// A pure operation on operand values (no frames: everything but Param, Global, Input, Call, Loop, Member,
// Index, If, Switch, Copy).
void run_op(const Instr& in, const Arg* a, double* r) {
    size_t n = slots(in.type);
    // ℤ arithmetic as a shader's 32-bit int: the low 32 bits of the exact result (GLSL ES 3.00 §4.1.3: "they will
    // wrap to yield the low-order 32 bits"). A trial: k·k at k = 100,000 was 10¹⁰ here and 1,410,065,408 in the
    // shader. Operands are int32 values, so their exact sums and products fit an int64.
    if (in.type.kind == Type::Integer && (in.op == Op::Add || in.op == Op::Sub || in.op == Op::Mul || in.op == Op::Neg)) {
        auto i64 = [](double x) { return std::isfinite(x) && std::fabs(x) < 9.2e18 ? int64_t(x) : int64_t(0); };
        const int64_t x = i64(a[0].at(0)), y = in.op == Op::Neg ? 0 : i64(a[1].at(0));
        const int64_t exact = in.op == Op::Add ? x + y : in.op == Op::Sub ? x - y : in.op == Op::Mul ? x * y : -x;
        r[0] = double(int32_t(uint32_t(uint64_t(exact))));
        return;
    }
    auto each2 = [&](auto f) {
        for (size_t i = 0; i < n; ++i) r[i] = f(a[0].at(i), a[1].at(i));
    };
    switch (in.op) {
        case Op::Const:
            for (size_t i = 0; i < n; ++i) r[i] = in.data[i];
            return;
        case Op::Add: return each2([](double x, double y) { return x + y; });
        case Op::Sub: return each2([](double x, double y) { return x - y; });
        case Op::IntDiv: return each2([](double x, double y) { return std::floor(x / y); });
        case Op::IntMod: return each2([](double x, double y) { return x - y * std::floor(x / y); });
        case Op::FloorInt:
            r[0] = std::floor(a[0].at(0));
            return;
        case Op::Hadamard: return each2([](double x, double y) { return x * y; });
        case Op::Div: return each2([](double x, double y) { return x / y; });
        case Op::Neg:
            for (size_t i = 0; i < n; ++i) r[i] = -a[0].p[i];
            return;
        case Op::Mul: return multiply(in.type, a[0], a[1], r);
        case Op::Dot: {
            double s = 0;
            for (size_t k = 0; k < a[0].n; ++k) s += a[0].p[k] * a[1].p[k];
            r[0] = s;
            return;
        }
        case Op::Cross: {
            const double *x = a[0].p, *y = a[1].p;
            r[0] = x[1] * y[2] - x[2] * y[1];
            r[1] = x[2] * y[0] - x[0] * y[2];
            r[2] = x[0] * y[1] - x[1] * y[0];
            return;
        }
        case Op::Transpose: {
            const Type& at = *a[0].t;
            if (!at.is_matrix()) {
                for (size_t i = 0; i < n; ++i) r[i] = a[0].p[i];
                return;
            }
            for (int i = 0; i < at.rows; ++i)
                for (int j = 0; j < at.cols; ++j) r[size_t(j * at.rows + i)] = a[0].p[size_t(i * at.cols + j)];
            return;
        }
        case Op::Inverse: {
            std::vector<double> inv = mat_inverse(std::vector<double>(a[0].p, a[0].p + a[0].n), a[0].t->rows, nullptr);
            for (size_t i = 0; i < n; ++i) r[i] = inv[i];
            return;
        }
        case Op::Det: r[0] = mat_det(std::vector<double>(a[0].p, a[0].p + a[0].n), a[0].t->rows); return;
        case Op::Builtin: return run_builtin(in, a, r);
        case Op::Construct: {
            size_t k = 0;
            for (size_t j = 0; j < in.args.size(); ++j)
                for (size_t c = 0; c < a[j].n; ++c) r[k++] = a[j].p[c];
            return;
        }
        case Op::Extract: r[0] = a[0].p[in.aux]; return;
        case Op::Element:
            for (size_t i = 0; i < n; ++i) r[i] = a[0].p[size_t(in.aux) * n + i];
            return;
        case Op::At: {
            // Indices are rounded and clamped to the range (a shader cannot stop; GLSL does the same).
            const Type& t = *a[0].t;
            auto index = [&](size_t k, int count) {
                double x = std::floor(a[k].p[0] + 0.5);
                return size_t(std::isnan(x) ? 0 : std::min(std::max(x, 0.0), double(count - 1)));
            };
            if (t.is_array()) {
                size_t i = index(1, t.count);
                for (size_t c = 0; c < n; ++c) r[c] = a[0].p[i * n + c];
            } else if (t.is_vector()) {
                r[0] = a[0].p[index(1, t.rows)];
            } else {
                r[0] = a[0].p[index(1, t.rows) * size_t(t.cols) + index(2, t.cols)];
            }
            return;
        }
        case Op::Row: {
            int c = a[0].t->cols;
            for (int k = 0; k < c; ++k) r[k] = a[0].p[in.aux * c + k];
            return;
        }
        case Op::Column: {
            int rows = a[0].t->rows, c = a[0].t->cols;
            for (int k = 0; k < rows; ++k) r[k] = a[0].p[k * c + in.aux];
            return;
        }
        case Op::Compare: {
            double x = a[0].p[0], y = a[1].p[0];
            bool b = false;
            switch (CompareKind(in.aux)) {
                case CompareKind::Eq: b = x == y; break;
                case CompareKind::Ne: b = x != y; break;
                case CompareKind::Lt: b = x < y; break;
                case CompareKind::Le: b = x <= y; break;
                case CompareKind::Gt: b = x > y; break;
                case CompareKind::Ge: b = x >= y; break;
            }
            r[0] = b ? 1.0 : 0.0;
            return;
        }
        case Op::And: r[0] = (a[0].p[0] != 0 && a[1].p[0] != 0) ? 1.0 : 0.0; return;
        case Op::Or: r[0] = (a[0].p[0] != 0 || a[1].p[0] != 0) ? 1.0 : 0.0; return;
        case Op::Select: {
            const Arg& x = a[0].p[0] != 0 ? a[1] : a[2];
            for (size_t i = 0; i < n; ++i) r[i] = x.at(i);
            return;
        }
        default: internal_error(fmt::format("evaluator: {} is not a pure operation", op_name(in.op)));
    }
}

// The components of a Loop's tuple: each state's size, from the body's outputs.
size_t loop_slots(const Module& m, const Instr& in) {
    const Function& body = m.functions[size_t(in.aux)];
    size_t n = 0;
    for (const auto& [name, v] : body.outputs) n += slots(body.body[v].type);
    return n;
}

int switch_arm(const Instr& in, double selector) {
    for (int k = 0; k < switch_cases(in); ++k)
        if (selector >= in.data[size_t(2 * k)] && selector < in.data[size_t(2 * k + 1)]) return 2 + k;
    return 1;
}

}  // namespace

struct Evaluator::Plan {
    Schedule sched;
    std::vector<size_t> offset;  // per instruction, into the frame
    std::vector<size_t> size;
    size_t frame = 0;
};

// One activation of a function: where each value's components are.
// Its storage is the evaluator's buffer for its depth of calls (Evaluator::frames_), reused from call to call:
// the Lipschitz pass's samples and jump search call one function thousands of times, and two fresh vectors
// per call (and per callee) were most of that under AddressSanitizer.
struct Frame {
    Evaluator& ev;
    const Module& m;
    const Function& f;
    const Evaluator::Plan& plan;
    const double* const* args;
    Evaluator::FrameBuffers& buffers;
    std::vector<double>& data;
    std::vector<const double*>& at;

    Frame(Evaluator& e, int fn, const double* const* a)
        : ev(e), m(e.m_), f(e.m_.functions[size_t(fn)]), plan(e.plan(fn)), args(a), buffers(e.frame_buffers()),
          data(buffers.data), at(buffers.at) {
        data.assign(plan.frame, 0.0);
        at.assign(f.body.size(), nullptr);
    }
    ~Frame() { --ev.depth_; }
    Frame(const Frame&) = delete;
    Frame& operator=(const Frame&) = delete;

    Arg arg(ValueId v) const { return {at[v], &f.body[v].type, plan.size[v]}; }
    double* slot(ValueId v) { return data.data() + plan.offset[v]; }

    void run_region(int r) {
        for (ValueId i : plan.sched.regions[size_t(r)].instrs) run(i);
    }

    void run(ValueId i) {
        const Instr& in = f.body[i];
        // A step per instruction and per component it computes; reading a parameter, a global, an array's element
        // or a loop's result only points at it (a rolled ∑'s body reads its captured arrays every iteration: counted
        // by size, 500 × 500 terms took 250 million steps and hit the limit, where unrolled they took 1.3 million).
        const bool alias = in.op == Op::Param || in.op == Op::Global || in.op == Op::Copy || in.op == Op::Index || in.op == Op::Member;
        ev.steps_ += alias ? 1 : 1 + plan.size[i];
        if (ev.steps_ > ev.inputs_.max_steps) throw EvalLimit{in.span};
        switch (in.op) {
            case Op::Param: at[i] = args[in.aux]; return;
            case Op::Global: at[i] = ev.read_global(in.aux).data(); return;
            case Op::Copy: at[i] = at[in.args[0]]; return;
            case Op::Index: {
                double k = at[in.args[1]][0];
                int count = f.body[in.args[0]].type.count;
                if (!(k >= 0 && k < count)) internal_error(fmt::format("evaluator: index {} outside an array of {}", k, count));
                at[i] = at[in.args[0]] + size_t(k) * plan.size[i];
                return;
            }
            case Op::Input: {
                double* r = slot(i);
                if (in.aux == 0) r[0] = ev.inputs_.time;
                else r[0] = ev.inputs_.mouse[0], r[1] = ev.inputs_.mouse[1];
                at[i] = r;
                return;
            }
            case Op::If:
            case Op::Switch: {
                int arm = in.op == Op::If ? (at[in.args[0]][0] != 0 ? 1 : 2) : switch_arm(in, at[in.args[0]][0]);
                run_region(plan.sched.arms[i][size_t(arm)]);
                at[i] = at[in.args[size_t(arm)]];
                return;
            }
            case Op::Call: {
                const double* few[8];
                std::vector<const double*> many;
                const double** a = few;
                if (in.args.size() > 8) {
                    many.resize(in.args.size());
                    a = many.data();
                }
                for (size_t k = 0; k < in.args.size(); ++k) a[k] = at[in.args[k]];
                double* r = slot(i);
                ev.call(in.aux, a, r);
                at[i] = r;
                return;
            }
            case Op::Loop: run_loop(i); return;
            case Op::Member: {
                const Instr& loop = f.body[in.args[0]];
                const Function& body = m.functions[size_t(loop.aux)];
                size_t off = 0;
                for (int j = 0; j < in.aux; ++j) off += slots(body.body[body.outputs[size_t(j)].second].type);
                at[i] = at[in.args[0]] + off;
                return;
            }
            default: {
                Arg a[8];
                std::vector<Arg> many;
                Arg* ap = a;
                if (in.args.size() > 8) {
                    many.resize(in.args.size());
                    ap = many.data();
                }
                for (size_t k = 0; k < in.args.size(); ++k) ap[k] = arg(in.args[k]);
                double* r = slot(i);
                run_op(in, ap, r);
                at[i] = r;
            }
        }
    }

    // k = lo..hi: the body's parameters are (k, the states, the captures), its outputs the next states.
    void run_loop(ValueId i) {
        const Instr& in = f.body[i];
        const Function& body = m.functions[size_t(in.aux)];
        size_t states = body.outputs.size();
        double* r = slot(i);
        std::vector<size_t> off(states + 1, 0);
        for (size_t j = 0; j < states; ++j) {
            size_t n = slots(body.body[body.outputs[j].second].type);
            off[j + 1] = off[j] + n;
            const double* init = at[in.args[j + 1]];
            std::copy(init, init + n, r + off[j]);
        }
        std::vector<double> next(off[states]);
        double k = 0;
        std::vector<const double*> a(in.args.size());
        a[0] = &k;
        for (size_t j = 0; j < states; ++j) a[j + 1] = r + off[j];
        for (size_t c = states + 1; c < in.args.size(); ++c) a[c] = at[in.args[c]];
        double hi = std::floor(at[in.args[0]][0] + 0.5);
        // Refused before it starts when its iterations alone exceed what is left of the budget (so a huge
        // range never starts, and k += 1 never has to count past 2^53).
        double trips = hi - in.data[0] + 1;
        double left = double(ev.inputs_.max_steps - std::min(ev.inputs_.max_steps, ev.steps_));
        if (trips > 0 && trips * double(body.body.size() + 1) > left) throw EvalLimit{in.span};
        Frame bf(ev, in.aux, a.data());  // one frame for every iteration: each run overwrites its values
        for (k = in.data[0]; k <= hi; k += 1) {
            bf.run_region(0);
            for (size_t j = 0; j < states; ++j) {
                const double* v = bf.at[body.outputs[j].second];
                std::copy(v, v + (off[j + 1] - off[j]), next.data() + off[j]);
            }
            std::copy(next.begin(), next.end(), r);
        }
        at[i] = r;
    }
};

Evaluator::Evaluator(const Module& m, const EvalInputs& inputs) : m_(m), inputs_(inputs) {
    for (const auto& g : m.globals) globals_.push_back(g.kind == Global::Kind::Prepared ? std::vector<double>(slots(g.type), 0.0) : g.value);
    plans_.resize(m.functions.size());
}

Evaluator::~Evaluator() = default;

const Evaluator::Plan& Evaluator::plan(int fn) const {
    if (fn < 0 || size_t(fn) >= m_.functions.size()) internal_error(fmt::format("evaluator: no function #{}", fn));
    auto& p = plans_[size_t(fn)];
    if (p) return *p;
    const Function& f = m_.functions[size_t(fn)];
    p = std::make_unique<Plan>();
    p->sched = schedule(f);
    p->offset.resize(f.body.size());
    p->size.resize(f.body.size());
    for (size_t i = 0; i < f.body.size(); ++i) {
        const Instr& in = f.body[i];
        p->size[i] = in.op == Op::Loop ? loop_slots(m_, in) : slots(in.type);
        p->offset[i] = p->frame;
        p->frame += p->size[i];
    }
    return *p;
}

const std::vector<double>& Evaluator::read_global(int g) {
    if (!prepared_ && m_.globals[size_t(g)].kind == Global::Kind::Prepared) prepare();
    return globals_[size_t(g)];
}

void Evaluator::prepare() {
    prepared_ = true;  // first: iqc_prepare's own reads of globals must not start it again
    int fn = m_.find(names::kPrepare);
    if (fn < 0) return;
    const Function& f = m_.functions[size_t(fn)];
    const auto index = m_.global_index();
    uint64_t caller = steps_;  // the work of the call that read a prepared global goes on after this
    steps_ = 0;
    Frame fr(*this, fn, nullptr);
    try {
        fr.run_region(0);
    } catch (...) {
        prepared_ = false;  // not prepared: the next read tries again (and meets the same limit)
        throw;
    }
    steps_ = caller;
    for (const auto& [name, v] : f.outputs) {
        auto g = index.find(name);
        if (g == index.end()) internal_error("evaluator: iqc_prepare computes '" + name + "', which is no global");
        globals_[size_t(g->second)].assign(fr.at[v], fr.at[v] + fr.plan.size[v]);
    }
}

void Evaluator::set_global(int g, std::vector<double> value) {
    if (g < 0 || size_t(g) >= globals_.size() || value.size() != globals_[size_t(g)].size())
        internal_error(fmt::format("evaluator: bad value for global #{}", g));
    globals_[size_t(g)] = std::move(value);
    prepared_ = false;
}

Evaluator::FrameBuffers& Evaluator::frame_buffers() {
    while (frames_.size() <= depth_) frames_.push_back(std::make_unique<FrameBuffers>());
    return *frames_[depth_++];
}

namespace {
// Adds a call's steps to the thread's analysis work meter however the call ends (EvalLimit included).
struct Metered {
    const uint64_t& steps;
    ~Metered() { analysis_work() += steps; }
};
}  // namespace

void Evaluator::call(int fn, const double* const* args, double* out) {
    steps_ = 0;
    Metered meter{steps_};
    Frame fr(*this, fn, args);
    fr.run_region(0);
    work_ += steps_;
    const Function& f = m_.functions[size_t(fn)];
    if (f.body.empty()) return;
    const double* r = fr.at[f.result];
    std::copy(r, r + fr.plan.size[f.result], out);
}

namespace {
std::vector<const double*> arg_pointers(const Function& f, const std::vector<Value>& args) {
    if (args.size() != f.params.size())
        internal_error(fmt::format("evaluator: {} takes {} arguments, not {}", f.name, f.params.size(), args.size()));
    std::vector<const double*> a;
    for (size_t k = 0; k < args.size(); ++k) {
        if (int(args[k].v.size()) != std::max(1, f.params[k].type.components()))
            internal_error(fmt::format("evaluator: argument {} of {} has the wrong size", f.params[k].name, f.name));
        a.push_back(args[k].v.data());
    }
    return a;
}
}  // namespace

Value Evaluator::call(int fn, const std::vector<Value>& args) {
    const Function& f = m_.functions[size_t(fn)];
    auto a = arg_pointers(f, args);
    Value r{f.result_type(), std::vector<double>(slots(f.result_type()))};
    call(fn, a.data(), r.v.data());
    return r;
}

std::vector<Value> Evaluator::call_all(int fn, const std::vector<Value>& args) {
    const Function& f = m_.functions[size_t(fn)];
    auto a = arg_pointers(f, args);
    steps_ = 0;
    Metered meter{steps_};
    Frame fr(*this, fn, a.data());
    fr.run_region(0);
    work_ += steps_;
    std::vector<Value> out(f.body.size());
    for (size_t i = 0; i < f.body.size(); ++i) {
        if (!fr.at[i] || f.body[i].op == Op::Loop) continue;
        out[i].type = f.body[i].type;
        out[i].v.assign(fr.at[i], fr.at[i] + fr.plan.size[i]);
    }
    return out;
}

std::vector<Value> evaluate_all(const Module& m, int fn, const std::vector<Value>& args, const EvalInputs& in) {
    Evaluator ev(m, in);
    return ev.call_all(fn, args);
}

Value evaluate(const Module& m, int fn, const std::vector<Value>& args, const EvalInputs& in) {
    Evaluator ev(m, in);
    return ev.call(fn, args);
}

Value eval_instr(const Module& m, const Function& f, const Instr& in, const std::vector<const Value*>& a) {
    (void)m;
    (void)f;
    std::vector<Arg> args;
    for (const Value* v : a) args.push_back({v->v.data(), &v->type, v->v.size()});
    Value r{in.type, std::vector<double>(slots(in.type))};
    run_op(in, args.data(), r.v.data());
    return r;
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
