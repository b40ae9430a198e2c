#include "sema/Check.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fmt/format.h>
#include <functional>
#include <set>

#include "ir/IR.h"
#include "sema/Builtins.h"
#include "sema/Hints.h"
#include "source/Limits.h"

namespace iqc {

using namespace ast;

int CheckedModule::find_param(const std::string& n) const {
    for (size_t i = 0; i < params.size(); ++i)
        if (params[i].name == n) return int(i);
    return -1;
}

int CheckedModule::find_sequence(const std::string& n) const {
    for (size_t i = 0; i < sequences.size(); ++i)
        if (sequences[i].name == n) return int(i);
    return -1;
}

int CheckedModule::find_function(const std::string& n) const {
    for (size_t i = 0; i < functions.size(); ++i)
        if (functions[i].stmt->name == n) return int(i);
    return -1;
}

std::optional<std::string> did_you_mean(const std::string& name, const std::vector<std::string>& candidates) {
    // Edit distance with adjacent transpositions (optimal string alignment), over code points.
    auto points = [](const std::string& s) {
        std::vector<char32_t> v;
        for (size_t i = 0; i < s.size();) v.push_back(utf8::decode(s, i));
        return v;
    };
    auto dist = [](const std::vector<char32_t>& a, const std::vector<char32_t>& b) {
        std::vector<std::vector<size_t>> d(a.size() + 1, std::vector<size_t>(b.size() + 1));
        for (size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
        for (size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
        for (size_t i = 1; i <= a.size(); ++i)
            for (size_t j = 1; j <= b.size(); ++j) {
                d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1)});
                if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
            }
        return d[a.size()][b.size()];
    };
    auto n = points(name);
    if (n.size() < 3) return std::nullopt;  // one- and two-letter names: any suggestion would be noise
    std::optional<std::string> best;
    size_t best_d = std::max<size_t>(1, n.size() / 3) + 1;
    for (const auto& c : candidates) {
        if (c == name) continue;
        size_t d = dist(n, points(c));
        if (d < best_d) { best_d = d; best = c; }
    }
    return best;
}

std::optional<std::vector<double>> const_eval(const Expr& e) {
    auto scalar = [](std::optional<std::vector<double>> v) -> std::optional<double> {
        if (v && v->size() == 1) return (*v)[0];
        return std::nullopt;
    };
    switch (e.kind) {
        case ExprKind::Number: return std::vector<double>{e.number};
        case ExprKind::Name:
            if (e.text == "π") return std::vector<double>{M_PI};
            return std::nullopt;
        case ExprKind::Negate: {
            auto v = const_eval(*e.args[0]);
            if (!v) return std::nullopt;
            for (auto& x : *v) x = -x;
            return v;
        }
        case ExprKind::Matrix: {  // [1 0; 0 1]: numbers only, row-major
            std::vector<double> out;
            for (const auto& row : e.rows)
                for (const auto& a : row) {
                    auto v = const_eval(*a);
                    if (!v || v->size() != 1 || row.size() != e.rows[0].size()) return std::nullopt;
                    out.push_back((*v)[0]);
                }
            return out;
        }
        case ExprKind::Vector: {
            std::vector<double> out;
            for (const auto& a : e.args) {
                auto v = const_eval(*a);
                if (!v) return std::nullopt;
                out.insert(out.end(), v->begin(), v->end());
            }
            return out;
        }
        case ExprKind::Binary: {
            auto a = const_eval(*e.args[0]);
            auto b = const_eval(*e.args[1]);
            if (!a || !b) return std::nullopt;
            if (b->size() == 1 && e.op != BinOp::Add && e.op != BinOp::Sub) {
                std::vector<double> out = *a;
                for (auto& x : out) {
                    if (e.op == BinOp::Div) x /= (*b)[0];
                    else x *= (*b)[0];
                }
                return out;
            }
            if (a->size() == 1 && (e.op == BinOp::Juxtapose || e.op == BinOp::Star || e.op == BinOp::Dot)) {
                std::vector<double> out = *b;
                for (auto& x : out) x *= (*a)[0];
                return out;
            }
            if (a->size() != b->size()) return std::nullopt;
            std::vector<double> out = *a;
            for (size_t i = 0; i < out.size(); ++i) {
                if (e.op == BinOp::Add) out[i] += (*b)[i];
                else if (e.op == BinOp::Sub) out[i] -= (*b)[i];
                else return std::nullopt;
            }
            return out;
        }
        case ExprKind::Power: {
            auto a = scalar(const_eval(*e.args[0]));
            auto b = scalar(const_eval(*e.args[1]));
            if (!a || !b) return std::nullopt;
            return std::vector<double>{std::pow(*a, *b)};
        }
        default: return std::nullopt;
    }
}

namespace {

using limits::kFloatMax;

// Why a parameter's value cannot reach a shader as written ("" when it can): not a number, infinite, beyond
// the 32-bit floats, or for ℤ not an integer of 32 bits (a shader's int).
std::string unrepresentable(const std::vector<double>& v, bool integer) {
    for (double x : v) {
        if (std::isnan(x)) return "is not a number (0/0, √-1, …)";
        if (!limits::fits_float(x))
            return fmt::format("is {}, outside the range of 32-bit floats (at most about 3.4e38)", x);
        if (integer && (x != std::floor(x) || !limits::is_int32(x)))
            return fmt::format("is {}, not a 32-bit integer (a shader's int: -2147483648 … 2147483647)", x);
    }
    return "";
}

// Free names an expression refers to (syntactically), excluding `bound` ones.
void collect_names(const Expr& e, std::vector<const Expr*>& out) {
    if (e.kind == ExprKind::Name || e.kind == ExprKind::Call) out.push_back(&e);
    for (const auto& a : e.args) collect_names(*a, out);
    for (const auto& r : e.rows)
        for (const auto& a : r) collect_names(*a, out);
    for (const auto& i : e.indices)
        if (i.expr) collect_names(*i.expr, out);
    if (e.otherwise) collect_names(*e.otherwise, out);
}

class Checker {
public:
    Checker(CheckedModule& m, const ModuleLookup& lookup, const CheckOptions& opts, Diagnostics& d)
        : m_(m), lookup_(lookup), opts_(opts), d_(d) {}
    void run();

private:
    CheckedModule& m_;
    const ModuleLookup& lookup_;
    const CheckOptions& opts_;
    // A constant expression's value: folded here where it can be, else by the evaluator (CheckOptions::constant).
    std::optional<std::vector<double>> constant(const Expr& e) const {
        if (auto v = const_eval(e)) return v;
        return opts_.constant ? opts_.constant(e) : std::nullopt;
    }
    Diagnostics& d_;
    std::map<std::string, const Stmt*> assigns_;
    std::map<std::string, Decl*> decls_;
    std::map<std::string, std::pair<std::string, Span>> decl_spans_;
    struct Scope {
        LocalFunction* fn;
        std::map<std::string, int> locals;
    };
    Scope* scope_ = nullptr;
    std::map<std::string, int> sizes_;  // symbolic sizes bound at this point (ℝ^n)
    // Binds the symbols of `ts` from a value's type; false (and an error at `where`) on a conflict.
    bool bind_sizes(const TypeSpec& ts, const Type& t, const std::string& name, Span where);
    const LoopGroup* loop_ = nullptr;  // the recurrence group whose bodies are being checked
    // The group whose first elements are being checked, and which of its sequences: a first element may read
    // the first elements of the group's earlier sequences only (the others are not known yet).
    const LoopGroup* init_group_ = nullptr;
    size_t init_at_ = 0;
    std::map<std::string, const Stmt*> seq_leader_;  // sequence name -> its group's leader
    std::vector<std::pair<std::string, int>> sums_;  // enclosing ∑ indices and their ranges
    int depth_ = 0;          // nesting of check() (limits::kMaxNesting)
    bool too_deep_ = false;  // reported once

    int sum_range(const Expr& body, const std::string& index);

    void collect_declarations();
    void declare_sequence(const Decl& decl, const std::string& name, Span span, const std::string& index);
    // A declaration's intervals `∈ [a,b]x[c,d]` into lo and hi (one per interval; a bad one is reported and left out).
    void interval_bounds(const Decl& decl, const std::string& name, std::vector<double>& lo, std::vector<double>& hi);
    void bind_function(const Decl& decl, const std::string& name, Span span);
    const Decl* param_decl(const LocalFunction& f, size_t i) const;
    std::set<std::string> unbound_functions_;  // function parameters without a definition, and sequences whose
                                               // declaration failed (already reported: not undefined at each use)
    std::map<std::string, int> seq_lengths_;  // a sequence index letter -> the length of its sequences
    void collect_imports();
    void collect_statements();
    void order_statements();
    void collect_sequences(const std::vector<const Stmt*>& inits, const std::vector<const Stmt*>& recs);
    void check_group(const LoopGroup& g);
    Type check_sequence_index(Expr& e);
    Type check_vector_items(Expr& e);
    void note_operands(Diagnostic& d, const Expr& e);
    std::vector<const Expr*> statement_values(const Stmt& s) const;
    void check_function(LocalFunction& f, Span call_site, const std::vector<Type>* args = nullptr);
    Type check(Expr& e);       // with the depth limit and the size limit
    Type check_kind(Expr& e);  // by the expression's kind
    Type check_name(Expr& e);
    Type check_call(Expr& e);
    Type check_binary(Expr& e);
    Type check_norm(Expr& e);
    Type check_block(Expr& e);
    Type check_matrix_literal(Expr& e);
    Type check_index(Expr& e);
    Type check_sequence_literal(Expr& e);
    Type check_elementwise(const Stmt& s);
    bool zero_based(const Expr& x) const;
    // Whether a sum, difference or product of two scalars is a whole number: a ℤ value with another, or
    // with a whole-number literal (b + 1, 2k).
    static bool integer_result(const Expr& e, const Type& a, const Type& b) {
        auto whole = [](const Expr& x, const Type& t) {
            return t.kind == Type::Integer || (x.kind == ExprKind::Number && x.number == std::floor(x.number) &&
                                               std::fabs(x.number) < 1e9);
        };
        return (a.kind == Type::Integer || b.kind == Type::Integer) && whole(*e.args[0], a) && whole(*e.args[1], b);
    }
    bool allow_sequence_ = false;               // the Name being checked is subscripted (x_1): it may be a sequence
    std::set<std::string> zero_based_values_;   // assigned ℤ values that count from 0 (c = b + 1, b ∈ ℤ index)
    // Whether the module (or the local function being checked) gives `name` a meaning of its own.
    bool defines(const std::string& name) const {
        return m_.find_param(name) >= 0 || assigns_.count(name) || decls_.count(name) ||
               (scope_ && scope_->locals.count(name)) || m_.find_sequence(name) >= 0;
    }
    Type check_inner(Expr& e);
    Type check_matrix_product(Expr& e, const Type& a, const Type& b);
    Type mul_type(Expr& e, const Type& a, const Type& b, bool dot);
    Type param_type(const TypeSpec& ts, const std::string& name);
    std::optional<int> computed_size(const Expr& x, const std::string& name);
    std::vector<std::string> visible_names() const;
    void undefined(const Expr& e);
    std::set<std::string> failed_imports_;  // names whose import was reported (their uses are not reported again)
    bool library_import(Span s, const std::string& name);
    std::optional<std::string> library_suggestion(const std::string& name);
    std::set<std::pair<uint32_t, uint32_t>> reported_words_;  // split words already reported (file, offset)
    // The built-in id of a constant imported by this name (e from trigonometry), or -1.
    int imported_constant(const std::string& name) const {
        for (const auto& im : m_.imports)
            if (im.name == name && im.builtin >= 0 && builtin(im.builtin).sig == Sig::Constant) return im.builtin;
        return -1;
    }
    Type value_type_for_scope(const std::string& name, Type t, Expr& e, int resolved, int aux);
};

// A size written as arithmetic on size symbols (ℝ^((p+1)×k)), once the symbols are bound.
std::optional<int> Checker::computed_size(const Expr& x, const std::string& name) {
    std::function<std::optional<double>(const Expr&)> eval = [&](const Expr& e) -> std::optional<double> {
        if (e.kind == ExprKind::Number) return e.number;
        if (e.kind == ExprKind::Name) {
            auto it = sizes_.find(e.text);
            if (it == sizes_.end()) {
                d_.error(e.span, fmt::format("the size {} of '{}' is not known: it must be a size of another declaration, "
                                             "such as n in v ∈ ℝ^n", e.text, name));
                return std::nullopt;
            }
            return double(it->second);
        }
        if (e.kind != ExprKind::Binary) return std::nullopt;
        auto a = eval(*e.args[0]);
        if (!a) return std::nullopt;
        auto b = eval(*e.args[1]);
        if (!b) return std::nullopt;
        switch (e.op) {
            case BinOp::Add: return *a + *b;
            case BinOp::Sub: return *a - *b;
            case BinOp::Div: return *b == 0 ? std::optional<double>() : *a / *b;
            default: return *a * *b;
        }
    };
    auto v = eval(x);
    if (!v) return std::nullopt;
    if (!(*v >= 1) || *v != std::floor(*v) || *v > limits::kMaxComponents) {
        d_.error(x.span, fmt::format("the size of '{}' must be a whole number ≥ 1, but it is {}", name, *v));
        return std::nullopt;
    }
    return int(*v);
}

Type Checker::param_type(const TypeSpec& ts, const std::string& name) {
    int rows = ts.rows, cols = ts.cols;
    for (auto [ex, dim] : {std::pair<const ExprPtr*, int*>{&ts.rows_expr, &rows}, {&ts.cols_expr, &cols}}) {
        if (!*ex) continue;
        auto n = computed_size(**ex, name);
        if (!n) return {};
        *dim = *n;
    }
    for (auto [sym, dim] : {std::pair<const std::string*, int*>{&ts.sym_rows, &rows}, {&ts.sym_cols, &cols}}) {
        if (sym->empty()) continue;
        auto it = sizes_.find(*sym);
        if (it == sizes_.end()) {
            d_.error(ts.span, fmt::format("the size {} of '{}' is not known: write the size, or give '{}' a value of "
                                          "its size (iqc eval --set {}=…)", *sym, name, name, name));
            return {};
        }
        *dim = it->second;
    }
    if (int64_t(rows) * (ts.kind == TypeSpec::Matrix ? cols : 1) > limits::kMaxComponents) {
        d_.error(ts.span, fmt::format("'{}' would have {}×{} components: iqc allows at most {} per vector or matrix", name,
                                      rows, cols, limits::kMaxComponents));
        return {};
    }
    switch (ts.kind) {
        case TypeSpec::Scalar: return Type::scalar();
        case TypeSpec::Integer: return Type::integer();
        case TypeSpec::Vector: return Type::vector(rows);
        case TypeSpec::Matrix:
            if (cols == 1) return Type::vector(rows);
            return Type::matrix(rows, cols);
        case TypeSpec::Function:
            d_.error(ts.span, fmt::format("'{}' is a function: a local function's parameters are values (define the "
                                          "function in the module and call it by name)", name));
            return {};
    }
    return {};
}

bool Checker::bind_sizes(const TypeSpec& ts, const Type& t, const std::string& name, Span where) {
    auto bind = [&](const std::string& sym, int value) {
        if (sym.empty()) return true;
        auto [it, fresh] = sizes_.emplace(sym, value);
        if (!fresh && it->second != value) {
            d_.error(where, fmt::format("the size {} is {} for '{}' but {} elsewhere", sym, value, name, it->second));
            return false;
        }
        return true;
    };
    if (ts.kind == TypeSpec::Vector) return bind(ts.sym_rows, t.is_vector() ? t.rows : 1);
    if (ts.kind == TypeSpec::Matrix) {
        int r = t.is_matrix() ? t.rows : t.is_vector() ? t.rows : 1;
        int c = t.is_matrix() ? t.cols : 1;
        return bind(ts.sym_rows, r) && bind(ts.sym_cols, c);
    }
    return true;
}

void Checker::collect_declarations() {
    // Names used at module level (outside local function bodies), to tell module parameters from
    // declarations that only give a local function's parameter its type.
    std::set<std::string> used_at_module;
    std::set<std::string> fn_params;
    for (const auto& s : m_.ast.stmts) {
        if (s.kind == StmtKind::Assign || s.kind == StmtKind::Return || s.kind == StmtKind::SeqInit ||
            s.kind == StmtKind::Recurrence) {
            std::vector<const Expr*> names;
            collect_names(*s.value, names);
            for (auto* n : names) used_at_module.insert(n->text);
        } else if (s.kind == StmtKind::Function) {
            for (auto& p : s.params) {
                bool local = false;
                for (auto& ld : s.local_decls)
                    for (auto& n : ld.names) local |= n.first == p.first;
                if (!local) fn_params.insert(p.first);
            }
            // A function body may capture module parameters.
            std::vector<const Expr*> names;
            collect_names(*s.value, names);
            std::set<std::string> own;
            for (auto& p : s.params) own.insert(p.first);
            for (auto* n : names)
                if (!own.count(n->text)) used_at_module.insert(n->text);
        }
    }
    // Sizes given from outside (a value set for a parameter declared ℝ^n) bind their symbols first.
    for (auto& decl : m_.ast.decls)
        for (auto& [name, span] : decl.names)
            if (auto it = opts_.given_types.find(name);
                it != opts_.given_types.end() && (!decl.type.sym_rows.empty() || !decl.type.sym_cols.empty()))
                bind_sizes(decl.type, it->second.is_array() ? it->second.element() : it->second, name, span);
    for (auto& decl : m_.ast.decls) {
        for (size_t ni = 0; ni < decl.names.size(); ++ni) {
            auto& [name, span] = decl.names[ni];
            if (name == "π") {  // (a trial: `π ∈ ℝ` and `π = 3` were accepted, and every π after them was 3)
                d_.error(span, "'π' is the constant 3.14159…: it cannot be declared; choose another name");
                continue;
            }
            if (decl_spans_.count(name)) {
                auto& e = d_.error(span, fmt::format("'{}' is declared twice", name));
                Diagnostics::note(e, decl_spans_[name].second, "first declared here");
                continue;
            }
            decl_spans_[name] = {name, span};
            decls_[name] = &decl;
            if (ni < decl.indices.size() && !decl.indices[ni].empty()) {  // x_i ∈ ℝ³
                declare_sequence(decl, name, span, decl.indices[ni]);
                continue;
            }
            if (fn_params.count(name) && !used_at_module.count(name)) continue;  // a local function's parameter
            if (decl.type.kind == TypeSpec::Function) {  // f: ℝ → ℝ, bound to a definition given from outside
                bind_function(decl, name, span);
                continue;
            }
            ParamInfo p;
            p.name = name;
            p.span = span;
            p.description = decl.description;
            // A description is a slider's label and a comment per instance: a megabyte of it, copied into every
            // instance, would make gigabytes of shader.
            if (p.description.size() > 1000) {
                d_.error(span, fmt::format("the description of '{}' has {} bytes: at most 1000", name, p.description.size()));
                p.description.resize(0);
            }
            p.zero_based = decl.zero_based;
            p.type = param_type(decl.type, name);
            if (!p.type.valid()) continue;
            int n = p.type.components();
            if (!decl.bounds.empty()) {
                p.bounded = true;
                interval_bounds(decl, name, p.lo, p.hi);
                if (int(p.lo.size()) != n) continue;
            }
            if (decl.default_value) {
                auto v = constant(*decl.default_value);
                if (!v) {
                    d_.error(decl.default_value->span, "a default must be a constant (numbers, π, and arithmetic and functions "
                                                       "of them, such as √2 or sin(π/8))");
                } else if (int(v->size()) != n) {
                    auto& e = d_.error(decl.default_value->span,
                                       fmt::format("the default has {} component{} but '{}' is {}", v->size(),
                                                   v->size() == 1 ? "" : "s", name, p.type.str()));
                    if (p.bounded)
                        Diagnostics::note(e, decl.type.span, fmt::format("the bounds give {} interval{}", n, n == 1 ? "" : "s"));
                } else if (std::string why = unrepresentable(*v, p.type.kind == Type::Integer); !why.empty()) {
                    d_.error(decl.default_value->span, fmt::format("the default of '{}' {}", name, why));
                } else {
                    p.value = *v;
                    p.has_default = true;
                    if (int i = p.outside_bounds(p.value); i >= 0)
                        d_.error(decl.default_value->span, fmt::format("the default {} of '{}' is outside its bounds [{}, {}]",
                                                                       p.value[size_t(i)], name, p.lo[size_t(i)], p.hi[size_t(i)]));
                }
            }
            if (p.value.empty()) {
                p.value.assign(size_t(n), 0.0);
                if (p.bounded)
                    for (int i = 0; i < n; ++i) p.value[i] = 0.5 * (p.lo[i] + p.hi[i]);
            }
            m_.params.push_back(std::move(p));
        }
    }
}

void Checker::interval_bounds(const Decl& decl, const std::string& name, std::vector<double>& lo_out, std::vector<double>& hi_out) {
    for (auto& iv : decl.bounds) {
        auto lo = constant(*iv.lo), hi = constant(*iv.hi);
        if (!lo || lo->size() != 1) { d_.error(iv.lo->span, "an interval bound must be a constant number"); continue; }
        if (!hi || hi->size() != 1) { d_.error(iv.hi->span, "an interval bound must be a constant number"); continue; }
        if (!limits::fits_float((*lo)[0]) || !limits::fits_float((*hi)[0])) {
            d_.error(iv.span, fmt::format("an interval bound must be a finite 32-bit float, not [{}, {}] (leave "
                                          "'{}' unbounded: '{} ∈ ℝ')", (*lo)[0], (*hi)[0], name, name));
            continue;
        }
        if ((*lo)[0] > (*hi)[0])
            d_.error(iv.span, fmt::format("the interval is empty: {} > {}", (*lo)[0], (*hi)[0]));
        lo_out.push_back((*lo)[0]);
        hi_out.push_back((*hi)[0]);
    }
}

// x_i ∈ ℝ³: a sequence parameter. Its length comes from its value (iqc eval --set 'x={…}') or its default
// {…}; sequences indexed by one letter have one length (I♥LA: the index ranges over them all). Bounds
// (`w_i ∈ [0.1, 1]`, `x_i ∈ [-1,1]x[-1,1]x[-1,1]`) hold for every element: each element's sliders, and what range
// analysis and the Lipschitz bounds assume of the elements on targets with uniforms.
void Checker::declare_sequence(const Decl& decl, const std::string& name, Span span, const std::string& index) {
    unbound_functions_.insert(name);  // until it is declared below
    Type elem = param_type(decl.type, name);
    if (!elem.valid()) return;
    if (elem.is_scalar()) elem = Type::scalar();
    std::vector<double> elo, ehi;
    if (!decl.bounds.empty()) {
        const size_t errors = d_.error_count();
        interval_bounds(decl, name, elo, ehi);
        if (d_.error_count() != errors) return;
        if (int(elo.size()) != elem.components()) {
            d_.error(Span::join(decl.bounds.front().span, decl.bounds.back().span),
                     fmt::format("the bounds of the sequence '{}' give {} interval{}, but its elements are {}", name, elo.size(),
                                 elo.size() == 1 ? "" : "s", elem.str()));
            return;
        }
    }
    ParamInfo p;
    p.name = name;
    p.span = span;
    p.description = decl.description;
    p.seq_index = index;
    int count = 0;
    if (auto it = opts_.given_types.find(name); it != opts_.given_types.end() && it->second.is_array()) {
        count = it->second.count;
    } else if (decl.default_value && decl.default_value->kind == ExprKind::Sequence) {
        count = int(decl.default_value->args.size());
        if (count == 0) return;  // `{}`: the parser said so (its uses stay quiet: unbound_functions_)
        for (const auto& item : decl.default_value->args) {
            auto v = constant(*item);  // (√2/2 too, as a scalar default: a trial's)
            if (!v || int(v->size()) != elem.components()) {
                d_.error(item->span, fmt::format("each element of '{}' must be a constant {}", name, elem.str()));
                return;
            }
            // (0/0 reached the shader as 0.0/0.0: NaN at every pixel, a trial's; a scalar default said so already)
            if (std::string why = unrepresentable(*v, elem.kind == Type::Integer); !why.empty()) {
                d_.error(item->span, fmt::format("element {} of the default of '{}' {}", p.value.size() / size_t(std::max(1, elem.components())) + 1,
                                                 name, why));
                return;
            }
            p.value.insert(p.value.end(), v->begin(), v->end());
        }
        p.has_default = true;
    } else if (decl.default_value) {
        d_.error(decl.default_value->span, fmt::format("the default of the sequence '{}' lists its elements: {{x_1, x_2, …}}", name));
        return;
    } else {
        d_.error(span, fmt::format("the length of the sequence '{}' is not known: give its elements as a default "
                                   "({}_{} ∈ {} default = {{…}}) or a value (iqc eval --set '{}={{…}}')", name, name, index,
                                   elem.str(), name));
        return;
    }
    if (auto [it, fresh] = seq_lengths_.emplace(index, count); !fresh && it->second != count) {
        d_.error(span, fmt::format("'{}' has {} elements but another sequence indexed by {} has {}", name, count, index,
                                   it->second));
        return;
    }
    if (int64_t(count) * elem.components() > limits::kMaxComponents) {
        d_.error(span, fmt::format("the sequence '{}' would have {} components: iqc allows at most {}", name,
                                   int64_t(count) * elem.components(), limits::kMaxComponents));
        return;
    }
    p.type = Type::array(elem, count);
    if (!elo.empty()) {
        p.bounded = true;
        for (int e = 0; e < count; ++e) {
            p.lo.insert(p.lo.end(), elo.begin(), elo.end());
            p.hi.insert(p.hi.end(), ehi.begin(), ehi.end());
        }
    }
    if (p.value.empty()) {
        p.value.assign(size_t(p.type.components()), 0.0);
        for (size_t k = 0; k < p.value.size() && p.bounded; ++k) p.value[k] = 0.5 * (p.lo[k] + p.hi[k]);
    } else if (int i = p.outside_bounds(p.value); i >= 0) {
        const int nc = std::max(1, elem.components());
        d_.error(decl.default_value ? decl.default_value->args[size_t(i / nc)]->span : span,
                 fmt::format("element {} of the default of '{}' is outside its bounds: {} is not in [{}, {}]", i / nc + 1, name,
                             p.value[size_t(i)], p.lo[size_t(i)], p.hi[size_t(i)]));
        return;
    }
    m_.params.push_back(std::move(p));
    unbound_functions_.erase(name);
}

// A function parameter of the module: its definition comes from outside (iqc eval --set 'f(x)=…'), typed
// by the declaration; calls to it are calls of that definition.
void Checker::bind_function(const Decl& decl, const std::string& name, Span span) {
    auto it = opts_.given_functions.find(name);
    if (it == opts_.given_functions.end() || !it->second) {
        unbound_functions_.insert(name);
        d_.error(span, fmt::format("'{}' is a function parameter: give its definition, e.g. iqc eval --set '{}(x)=…' "
                                   "(a shader needs it defined in the module: {}(x) = … where x ∈ …)", name, name, name));
        return;
    }
    const ast::Module& given = *it->second;
    const Stmt* def = nullptr;
    for (const auto& st : given.stmts)
        if (st.kind == StmtKind::Function && st.name == name) def = &st;
    unbound_functions_.insert(name);  // until bound below: its errors are reported here, not at each call
    if (!def) {
        d_.error(span, fmt::format("the value given for the function '{}' must define it: {}(x) = …", name, name));
        return;
    }
    if (def->params.size() != decl.type.params.size()) {
        d_.error(def->name_span, fmt::format("'{}' takes {} argument{} (its declaration: {}), but the definition has {}", name,
                                             decl.type.params.size(), decl.type.params.size() == 1 ? "" : "s",
                                             d_.sources().slice(decl.type.span), def->params.size()));
        return;
    }
    unbound_functions_.erase(name);
    m_.bound_functions.push_back(it->second);
    LocalFunction f;
    f.stmt = def;
    f.declared = &decl.type;
    m_.functions.push_back(std::move(f));
}

void Checker::collect_imports() {
    auto add_import = [&](const std::string& name, const std::string& module, Span span, Span from_span) {
        for (auto& im : m_.imports)
            if (im.name == name) return;  // importing a name twice is harmless
        ImportedFunction im;
        im.name = name;
        im.module = module;
        im.span = span;
        if (is_builtin_module(module)) {
            auto b = find_builtin(name);
            if (!b || module != builtin(*b).module) {
                std::vector<std::string> cands = builtin_module_names(module);
                auto& e = d_.error(span, fmt::format("module '{}' has no function '{}'", module, name));
                // (a name every module has without an import: `e, ln from trigonometry` after e's own error, a trial's)
                if (b && std::string_view(builtin(*b).module).empty())
                    Diagnostics::note(e, span, fmt::format("'{}' is built in: use it without an import", name));
                else if (auto s = did_you_mean(name, cands)) Diagnostics::note(e, span, fmt::format("did you mean '{}'?", *s));
                failed_imports_.insert(name);
                return;
            }
            im.builtin = *b;
        } else {
            const CheckedModule* from = lookup_ ? lookup_(module, from_span) : nullptr;
            if (!from) {
                auto& e = d_.error(from_span, fmt::format("no module named '{}' to import from", module));
                std::vector<std::string> modules = library_module_names();  // (`from nosie`: a trial's, stop 58)
                modules.insert(modules.end(), builtin_modules().begin(), builtin_modules().end());
                if (auto s = did_you_mean(module, modules)) Diagnostics::note(e, from_span, fmt::format("did you mean '{}'?", *s));
                failed_imports_.insert(name);
                return;
            }
            im.from = from;
            im.function = from->find_function(name);
            if (im.function < 0 && name == module &&
                (from->ast.kind != ModuleKind::Library || from->ret != nullptr)) {
                im.whole_module = true;
            } else if (im.function < 0) {
                std::vector<std::string> cands;
                for (auto& f : from->functions) cands.push_back(f.stmt->name);
                auto& e = d_.error(span, fmt::format("module '{}' defines no function '{}'", module, name));
                if (auto s = did_you_mean(name, cands)) Diagnostics::note(e, span, fmt::format("did you mean '{}'?", *s));
                else if (!cands.empty() && cands.size() <= 24) {
                    // (`perlin from noise`: what the module has instead; a trial's, stop 58)
                    std::string list;
                    for (const std::string& c : cands)
                        if (c.find('_') == std::string::npos || c.rfind('_') + 1 < c.size())
                            list += (list.empty() ? "" : ", ") + import_spelling(c);
                    Diagnostics::note(e, span, fmt::format("'{}' defines {}", module, list));
                }
                failed_imports_.insert(name);
                return;
            }
        }
        m_.imports.push_back(std::move(im));
    };
    for (const auto& s : m_.ast.stmts)
        if (s.kind == StmtKind::Import)
            for (auto& [n, sp] : s.imports) add_import(n, s.from, sp, s.from_span);
    // A name imported and defined here too: which one a call meant was the local one's, silently (`fbm from noise`
    // beside `fbm(x) = x_1`: a trial's, stop 58).
    for (const auto& s : m_.ast.stmts) {
        if (s.kind != StmtKind::Assign && s.kind != StmtKind::Function) continue;
        for (const ImportedFunction& im : m_.imports)
            if (im.name == s.name) {
                auto& e = d_.error(s.name_span, fmt::format("'{}' is imported from '{}' and defined here too: rename this one, or "
                                                            "remove the import",
                                                            s.name, im.module));
                Diagnostics::note(e, im.span, fmt::format("'{}' is imported here", s.name));
            }
    }
    for (auto& [n, mod] : opts_.implicit_imports) {
        bool defined = decl_spans_.count(n) > 0;
        for (const auto& s : m_.ast.stmts)
            if ((s.kind == StmtKind::Assign || s.kind == StmtKind::Function) && s.name == n) defined = true;
        if (!defined) add_import(n, mod, m_.ast.span, m_.ast.span);
    }
}

void Checker::collect_statements() {
    std::map<std::string, Span> defined;
    for (auto& [n, s] : decl_spans_) defined[n] = s.second;
    std::vector<const Stmt*> inits, recs;
    for (const auto& s : m_.ast.stmts) {
        if (s.kind == StmtKind::SeqInit) inits.push_back(&s);
        if (s.kind == StmtKind::Recurrence) recs.push_back(&s);
    }
    for (const auto* r : recs) defined.emplace(r->name, r->name_span);
    for (const auto& s : m_.ast.stmts) {
        if (s.kind == StmtKind::Assign || s.kind == StmtKind::Function) {
            if (s.name == "π") {
                d_.error(s.name_span, "'π' is the constant 3.14159…: it cannot be assigned; choose another name");
                continue;
            }
            if (auto it = defined.find(s.name); it != defined.end()) {
                auto& e = d_.error(s.name_span, decl_spans_.count(s.name)
                                                    ? fmt::format("'{}' is a declared parameter and cannot be assigned", s.name)
                                                    : fmt::format("'{}' is assigned twice", s.name));
                Diagnostics::note(e, it->second, "first defined here");
                if (!s.elem_indices.empty())
                    Diagnostics::note(e, s.name_span, "an element-wise definition defines the whole of its name; changing "
                                                      "some entries of a value defined elsewhere is not supported");
                continue;
            }
            defined[s.name] = s.name_span;
            if (s.kind == StmtKind::Assign) {
                assigns_[s.name] = &s;
            } else {
                LocalFunction f;
                f.stmt = &s;
                m_.functions.push_back(std::move(f));
            }
        } else if (s.kind == StmtKind::Return) {
            if (m_.ret) {
                auto& e = d_.error(s.span, "a module can have only one bare expression (its value)");
                Diagnostics::note(e, m_.ret->span, "the first one is here");
                continue;
            }
            m_.ret = &s;
        }
    }
    collect_sequences(inits, recs);
}

// Ends of a recurrence's range: GLSL loops count in 32-bit ints (z_(hi+1) must exist too).
constexpr int kMaxRangeEnd = 1'000'000'000;

void Checker::collect_sequences(const std::vector<const Stmt*>& inits, const std::vector<const Stmt*>& recs) {
    auto const_int = [&](const Expr& x, const char* what) -> std::optional<int> {
        auto v = const_eval(x);
        if (!v || v->size() != 1 || (*v)[0] != std::floor((*v)[0])) {
            d_.error(x.span, fmt::format("the {} of a recurrence's range must be a whole number", what));
            return std::nullopt;
        }
        auto k = limits::checked_int((*v)[0], -kMaxRangeEnd, kMaxRangeEnd);
        if (!k) d_.error(x.span, fmt::format("the {} of a recurrence's range must be within ±{}", what, kMaxRangeEnd));
        return k;
    };
    for (const Stmt* r : recs) {
        if (m_.find_sequence(r->name) >= 0) {
            auto& e = d_.error(r->name_span, fmt::format("the sequence '{}' has two recurrences", r->name));
            Diagnostics::note(e, m_.sequences[size_t(m_.find_sequence(r->name))].rec->name_span, "the first one is here");
            continue;
        }
        // The left side must be the next element: z_(k+1).
        const Expr& ix = *r->index;
        bool next = ix.kind == ExprKind::Binary && ix.op == BinOp::Add && ix.args[0]->kind == ExprKind::Name &&
                    ix.args[0]->text == r->loop_var && ix.args[1]->kind == ExprKind::Number && ix.args[1]->number == 1;
        if (!next) {
            d_.error(ix.span, fmt::format("a recurrence defines the next element: write {}_({}+1) = … for {} ∈ …", r->name,
                                          r->loop_var, r->loop_var));
            continue;
        }
        auto lo = const_int(*r->range_lo, "start");
        std::optional<int> hi;
        std::string hi_name;
        if (r->range_hi->kind == ExprKind::Name && !const_eval(*r->range_hi)) {
            hi_name = r->range_hi->text;  // a ℤ parameter: checked with the group
            hi = 0;
        } else {
            hi = const_int(*r->range_hi, "end");
        }
        if (!lo || !hi) continue;
        if (hi_name.empty() && *hi < *lo) {
            d_.error(Span::join(r->range_lo->span, r->range_hi->span), fmt::format("the range {}..{} is empty", *lo, *hi));
            continue;
        }
        const Stmt* init = nullptr;
        for (const Stmt* i : inits)
            if (i->name == r->name) init = i;
        if (!init) {
            d_.error(r->name_span, fmt::format("the sequence '{}' has no first element: add '{}_{} = …'", r->name, r->name, *lo));
            continue;
        }
        auto first = const_eval(*init->index);
        if (!first || first->size() != 1 || (*first)[0] != *lo) {
            d_.error(init->index->span, fmt::format("the recurrence for '{}' starts at {}, so its first element is {}_{}",
                                                    r->name, *lo, r->name, *lo));
            continue;
        }
        Sequence seq;
        seq.name = r->name;
        seq.init = init;
        seq.rec = r;
        int gi = -1;
        for (size_t g = 0; g < m_.groups.size(); ++g)
            if (m_.groups[g].var == r->loop_var && m_.groups[g].lo == *lo && m_.groups[g].hi == *hi &&
                m_.groups[g].hi_name == hi_name)
                gi = int(g);
        if (gi < 0) {
            LoopGroup g;
            g.var = r->loop_var;
            g.lo = *lo;
            g.hi = *hi;
            g.hi_name = hi_name;
            g.leader = r;
            m_.groups.push_back(g);
            gi = int(m_.groups.size() - 1);
        }
        seq.group = gi;
        m_.groups[size_t(gi)].sequences.push_back(int(m_.sequences.size()));
        m_.sequences.push_back(seq);
        seq_leader_[r->name] = m_.groups[size_t(gi)].leader;
    }
    for (const Stmt* i : inits)
        if (m_.find_sequence(i->name) < 0 && !seq_leader_.count(i->name)) {
            bool has_rec = std::any_of(recs.begin(), recs.end(), [&](const Stmt* r) { return r->name == i->name; });
            if (!has_rec) {
                // (a trial's, stop 56: `k_1 = 0.1` meant a value named k_1, and the words offered only a recurrence)
                const std::string sub = i->index && (i->index->kind == ExprKind::Number || i->index->kind == ExprKind::Name)
                                            ? i->index->text
                                            : "1";
                d_.error(i->name_span, fmt::format("'{0}_{1} = …' starts a sequence '{0}', but no recurrence continues it "
                                                   "('{0}_(n+1) = … for n ∈ 1..N'); to name one value {0}_{1}, write the "
                                                   "name in backticks: `{0}_{1}` = …",
                                                   i->name, sub));
            }
        }
}

std::vector<const Expr*> Checker::statement_values(const Stmt& s) const {
    if (s.kind != StmtKind::Recurrence) return {s.value.get()};
    std::vector<const Expr*> v;
    for (const auto& g : m_.groups)
        if (g.leader == &s)
            for (int si : g.sequences) {
                v.push_back(m_.sequences[size_t(si)].init->value.get());
                v.push_back(m_.sequences[size_t(si)].rec->value.get());
            }
    return v;
}

void Checker::order_statements() {
    // Depth-first topological sort in source order; reports the first cycle.
    std::map<const Stmt*, int> state;  // 0 new, 1 visiting, 2 done
    std::vector<const Stmt*> stack;
    auto node_of = [&](const std::string& n) -> const Stmt* {
        if (auto it = assigns_.find(n); it != assigns_.end()) return it->second;
        if (auto it = seq_leader_.find(n); it != seq_leader_.end()) return it->second;
        return nullptr;
    };
    // Dependencies by name (sorted: the order statements come out in is deterministic).
    std::function<std::set<std::string_view>(const Stmt&)> deps_of = [&](const Stmt& s) {
        std::vector<const Expr*> names;
        for (const Expr* v : statement_values(s)) collect_names(*v, names);
        std::set<std::string_view> deps;
        std::set<std::string_view> seen_fn;
        // Names used through local functions count too.
        for (size_t i = 0; i < names.size(); ++i) {
            const std::string& n = names[i]->text;
            // A recurrence group's own sequences are not dependencies of the group; anything else, the
            // statement itself included (a = a + 1), is.
            if (const Stmt* dep = node_of(n); dep && !(s.kind == StmtKind::Recurrence && dep == &s)) deps.insert(n);
            int fi = m_.find_function(n);
            if (fi >= 0 && !seen_fn.count(n)) {
                seen_fn.insert(n);
                const Stmt& fs = *m_.functions[size_t(fi)].stmt;
                std::vector<const Expr*> inner;
                collect_names(*fs.value, inner);
                for (auto* in : inner) {
                    bool own = false;
                    for (auto& p : fs.params) own |= p.first == in->text;
                    if (!own) names.push_back(in);
                }
            }
        }
        return deps;
    };
    bool reported = false;
    // Depth-first with an explicit stack of frames: 50,000 statements written in reverse order are a
    // 50,000-deep chain, too deep for recursion.
    struct Frame {
        const Stmt* s;
        std::vector<const Stmt*> deps;
        size_t next = 0;
    };
    std::vector<Frame> frames;
    auto enter = [&](const Stmt* s) {
        if (state[s] == 2) return;
        if (state[s] == 1) {
            if (reported) return;
            reported = true;
            auto it = std::find(stack.begin(), stack.end(), s);
            const long kShown = 12;  // a long cycle is shown by its first and last names
            long length = long(stack.end() - it);
            std::string cycle;
            for (auto j = it; j != stack.end(); ++j) {
                long k = long(j - it);
                if (k < kShown - 1 || k == length - 1) cycle += (*j)->name + " → ";
                else if (k == kShown - 1) cycle += fmt::format("… ({} more) → ", length - kShown);
            }
            cycle += s->name;
            auto& e = d_.error(s->name_span, fmt::format("dependency cycle: {}", cycle));
            for (auto j = it + 1; j != stack.end() && j - it < kShown; ++j)
                Diagnostics::note(e, (*j)->name_span, fmt::format("'{}' is defined here", (*j)->name));
            return;
        }
        state[s] = 1;
        stack.push_back(s);
        Frame f{s, {}};
        for (const auto& dep : deps_of(*s)) f.deps.push_back(node_of(std::string(dep)));
        frames.push_back(std::move(f));
    };
    auto visit = [&](const Stmt* root) {
        enter(root);
        while (!frames.empty()) {
            Frame& f = frames.back();
            if (f.next < f.deps.size()) {
                enter(f.deps[f.next++]);  // may grow `frames`: `f` is not used after this
                continue;
            }
            state[f.s] = 2;
            m_.order.push_back(f.s);
            stack.pop_back();
            frames.pop_back();
        }
    };
    for (const auto& s : m_.ast.stmts) {
        if (s.kind == StmtKind::Assign && assigns_.count(s.name) && assigns_[s.name] == &s) visit(&s);
        if (s.kind == StmtKind::Recurrence && seq_leader_.count(s.name) && seq_leader_[s.name] == &s) visit(&s);
    }
    if (m_.ret) {
        for (const auto& dep : deps_of(*m_.ret)) visit(node_of(std::string(dep)));
        m_.order.push_back(m_.ret);
    }
    if (reported) m_.order.clear();
}

std::vector<std::string> Checker::visible_names() const {
    std::vector<std::string> v;
    for (auto& p : m_.params) v.push_back(p.name);
    for (auto& [n, s] : assigns_) v.push_back(n);
    for (auto& f : m_.functions) v.push_back(f.stmt->name);
    for (auto& im : m_.imports) v.push_back(im.name);
    if (scope_)
        for (auto& [n, i] : scope_->locals) v.push_back(n);
    for (auto& b : builtins()) v.push_back(b.name);
    return v;
}

// A standard-library function used without its import (fbm(p) without `fbm from noise` was "names are one letter,
// so 'fbm' reads as f·b·m", a trial's): the import to add, at `s`. False where no library module defines `name`.
bool Checker::library_import(Span s, const std::string& name) {
    const std::vector<std::string> modules = library_modules_of(name);
    if (modules.empty()) return false;
    const std::string spelled = import_spelling(name);
    std::string also;
    for (size_t k = 1; k < modules.size(); ++k) also += fmt::format("{}'{} from {}'", k == 1 ? " (or " : ", ", spelled, modules[k]);
    d_.error(s, fmt::format("'{}' needs an import: add '{} from {}'{}", name, spelled, modules[0], also.empty() ? "" : also + ")"));
    return true;
}

// "did you mean 'value_noise' (add '`value_noise` from noise')?" for a misspelled standard-library function that is
// not imported either (`valu_noise`, `fmb`: "undefined name" alone, or "declare `fmb`"; a trial's, stop 58).
std::optional<std::string> Checker::library_suggestion(const std::string& name) {
    std::string lower = name;  // (FBM: fbm)
    for (char& c : lower) c = char(std::tolower(static_cast<unsigned char>(c)));
    std::optional<std::string> sug = lower != name && !library_modules_of(lower).empty() ? std::optional<std::string>(lower)
                                                                                          : did_you_mean(name, library_function_names());
    if (!sug) return std::nullopt;
    const std::vector<std::string> modules = library_modules_of(*sug);
    if (modules.empty()) return std::nullopt;
    return fmt::format("did you mean '{}' (add '{} from {}')?", *sug, import_spelling(*sug), modules[0]);
}

void Checker::undefined(const Expr& e) {
    const std::string& name = e.text;
    if (unbound_functions_.count(name)) return;  // reported at its declaration
    if (failed_imports_.count(name)) return;     // reported at its import
    if (e.word_span.end > e.word_span.begin && failed_imports_.count(std::string(d_.sources().slice(e.word_span)))) return;
    // Past the diagnostics that are shown, only the count matters: no suggestions (did_you_mean scans every
    // name: 10,000 undefined names against 10,000 defined ones would take a minute).
    if (d_.error_count() >= Diagnostics::kMaxKept) {
        d_.error(e.name_span, fmt::format("undefined name '{}'", name));
        return;
    }
    Span s = e.name_span;
    if (e.word_span.end > e.word_span.begin) {
        // A letter of a longer word (`dot` is d·o·t): report the word once, as written, with a hint.
        if (!reported_words_.insert({e.word_span.file, e.word_span.begin}).second) return;
        std::string word(d_.sources().slice(e.word_span));
        if (auto b = find_builtin(word); b && *builtin(*b).module) {
            d_.error(e.word_span, fmt::format("'{}' needs an import: add '{} from {}'", word, word, builtin(*b).module));
            return;
        }
        if (library_import(e.word_span, word)) return;
        auto& err = d_.error(e.word_span, fmt::format("undefined name '{}'", word));
        // A name of several letters that is defined, written without its backticks (`smooth_union` imported, then
        // written smooth_union: "undefined name 'smooth'" and 'union'; a trial's, stop 56).
        std::string longest;
        const std::string_view rest = d_.sources().text(e.word_span.file).substr(e.word_span.begin);
        for (const std::string& n : visible_names())
            if (n.size() > word.size() && n.size() > longest.size() && rest.substr(0, n.size()) == n) longest = n;
        if (!longest.empty()) {
            // (the words after the first within it, `union`, are the same mistake: not said again)
            for (uint32_t at = e.word_span.begin + 1; at < e.word_span.begin + uint32_t(longest.size()); ++at)
                reported_words_.insert({e.word_span.file, at});
            Diagnostics::note(err, e.word_span, fmt::format("'{0}' is one name: write it in backticks, `{0}`", longest));
        } else if (auto hint = word_hint(word)) {
            Diagnostics::note(err, e.word_span, *hint);
        } else if (auto sug = did_you_mean(word, visible_names())) {  // (sinn(x), smoothstpe(…): a trial's, stop 56)
            Diagnostics::note(err, e.word_span, fmt::format("did you mean '{}'?", *sug));
        } else if (auto lib = library_suggestion(word)) {  // (fmb(p), not imported: a trial's, stop 58)
            Diagnostics::note(err, e.word_span, *lib);
        } else {
            Diagnostics::note(err, e.word_span,
                              fmt::format("names are one letter, so '{}' reads as {}: declare `{}` to use it as one name, "
                                          "or write {}", word, spell_letters(word, "·"), word, spell_letters(word, " ")));
        }
        return;
    }
    if (auto b = find_builtin(name)) {
        if (*builtin(*b).module)
            d_.error(s, fmt::format("'{}' needs an import: add '{} from {}'", name, name, builtin(*b).module));
        else
            d_.error(s, fmt::format("'{}' is a function: call it with arguments, as in {}(x)", name, name));
        return;
    }
    if (library_import(s, name)) return;
    auto& err = d_.error(s, fmt::format("undefined name '{}'", name));
    if (auto sug = did_you_mean(name, visible_names())) Diagnostics::note(err, s, fmt::format("did you mean '{}'?", *sug));
    else if (auto hint = word_hint(name)) Diagnostics::note(err, s, *hint);
    else if (auto lib = library_suggestion(name)) Diagnostics::note(err, s, *lib);
}

Type Checker::value_type_for_scope(const std::string& name, Type t, Expr& e, int resolved, int aux) {
    if (!scope_) {
        e.resolved = resolved;
        e.aux = aux;
        return t;
    }
    // Inside a local function: a module value or parameter becomes a capture.
    auto& caps = scope_->fn->captures;
    for (size_t i = 0; i < caps.size(); ++i)
        if (caps[i].first == name) {
            e.resolved = R_Capture;
            e.aux = int(i);
            return t;
        }
    caps.push_back({name, t});
    e.resolved = R_Capture;
    e.aux = int(caps.size() - 1);
    return t;
}

Type Checker::check_name(Expr& e) {
    const std::string& n = e.text;
    for (auto it = sums_.rbegin(); it != sums_.rend(); ++it)
        if (it->first == n) {
            e.resolved = R_SumIndex;
            return Type::integer();
        }
    if (scope_) {
        if (auto it = scope_->locals.find(n); it != scope_->locals.end()) {
            e.resolved = R_Local;
            e.aux = it->second;
            return scope_->fn->params[size_t(it->second)].second;
        }
    }
    if (loop_ && n == loop_->var) {
        e.resolved = R_LoopIndex;
        return Type::integer();
    }
    if (int pi = m_.find_param(n); pi >= 0) return value_type_for_scope(n, m_.params[size_t(pi)].type, e, R_Param, pi);
    if (m_.find_sequence(n) >= 0) {
        const auto& g = m_.groups[size_t(m_.sequences[size_t(m_.find_sequence(n))].group)];
        d_.error(e.span, fmt::format("'{}' is a sequence: use an element such as {}_{} or {}_{}", n, n, g.lo, n, g.last()));
        return {};
    }
    if (auto it = m_.values.find(n); it != m_.values.end()) return value_type_for_scope(n, it->second, e, R_Value, 0);
    if (assigns_.count(n)) return {};  // defined, but its own statement failed to check: already reported
    if (n == "π") {
        e.resolved = R_Pi;
        return Type::scalar();
    }
    if (int b = imported_constant(n); b >= 0) {
        e.resolved = R_Constant;
        e.aux = b;
        return Type::scalar();
    }
    if (n == "time" || n == "mouse") {  // reserved inputs (a declaration of the same name wins)
        e.resolved = R_Input;
        e.aux = n == "time" ? 0 : 1;
        return n == "time" ? Type::scalar() : Type::vector(2);
    }
    if (m_.find_function(n) >= 0 || std::any_of(m_.imports.begin(), m_.imports.end(), [&](auto& im) { return im.name == n; })) {
        // (the first letters of a longer word, `sinn(x)` read as sin·n·n: the word is what was written)
        if (e.word_span.end > e.word_span.begin) {
            undefined(e);
            return {};
        }
        d_.error(e.span, fmt::format("'{}' is a function: call it with arguments, as in {}(x)", n, n));
        return {};
    }
    undefined(e);
    return {};
}

// The index letter of `name` where `decl` declares it a sequence (x_i ∈ ℝ³: "i"), else "".
static std::string sequence_index(const Decl& decl, const std::string& name) {
    for (size_t k = 0; k < decl.names.size() && k < decl.indices.size(); ++k)
        if (decl.names[k].first == name) return decl.indices[k];
    return "";
}

// The declaration of parameter i of a local function: its own `where`, else the module's (none for a function
// parameter of the module, typed by its declared signature).
const Decl* Checker::param_decl(const LocalFunction& f, size_t i) const {
    const Stmt& s = *f.stmt;
    const std::string& pname = s.params[i].first;
    const Decl* decl = nullptr;
    for (auto& ld : s.local_decls)
        for (auto& nm : ld.names)
            if (nm.first == pname) decl = &ld;
    if (!decl && !f.declared)
        if (auto it = decls_.find(pname); it != decls_.end()) decl = it->second;
    return decl;
}

void Checker::check_function(LocalFunction& f, Span call_site, const std::vector<Type>* args) {
    const Stmt& s = *f.stmt;
    std::vector<const Decl*> decls;
    for (size_t i = 0; i < s.params.size(); ++i) {
        const Decl* decl = param_decl(f, i);
        decls.push_back(decl);
        // A parameter of a symbolic size (x ∈ ℝ^n, or f: ℝ^(k×k) → ℝ) makes the function generic.
        const TypeSpec* spec = decl ? &decl->type : f.declared ? &f.declared->params[i] : nullptr;
        if (spec && (!spec->sym_rows.empty() || !spec->sym_cols.empty())) f.generic = true;
    }
    std::vector<Type> key;
    if (f.generic) {
        if (!args) return;  // checked at each use, with the sizes of its arguments
        for (const Type& t : *args) key.push_back(t.is_scalar() ? Type::scalar() : t);
        if (auto it = f.instances.find(key); it != f.instances.end()) {
            f.params = it->second.first;
            f.result = it->second.second;
            return;
        }
    } else if (f.checked) {
        return;
    }
    if (f.checking) {
        d_.error(call_site, fmt::format("'{}' calls itself: recursion is not supported (use an iteration)", f.stmt->name));
        return;
    }
    f.checking = true;
    Scope scope{&f, {}};
    f.params.clear();
    auto saved_sizes = sizes_;
    if (f.generic)
        for (size_t i = 0; i < s.params.size() && i < key.size(); ++i) {
            if (decls[i]) bind_sizes(decls[i]->type, key[i], s.params[i].first, call_site);
            else if (f.declared) bind_sizes(f.declared->params[i], key[i], s.params[i].first, call_site);
        }
    for (size_t i = 0; i < s.params.size(); ++i) {
        const auto& [pname, pspan] = s.params[i];
        const Decl* decl = decls[i];
        Type t;
        if (!decl && f.declared) {
            t = param_type(f.declared->params[i], pname);
        } else if (!decl) {
            d_.error(pspan, fmt::format("the parameter '{}' of '{}' has no type: add 'where {} ∈ ℝ' (or its type)", pname,
                                        s.name, pname));
        } else if (std::string index = sequence_index(*decl, pname); !index.empty()) {
            // I♥LA passes sequences to functions; iqc's local functions take single values (its ∑ over a sequence
            // needs the sequence's length where the sum is written). Said at the declaration; the parameter
            // stays untyped, so its uses say nothing more (`p - a_i` said ℝ³ minus ℝ).
            d_.error(pspan, fmt::format("the parameter '{}' of '{}' is declared as a sequence ({}_{} ∈ …): a local "
                                        "function's parameters are single values; read the module's sequence in the "
                                        "function instead ({}() = ∑_{} … x_{} …)", pname, s.name, pname, index, s.name,
                                        index, index));
        } else if (!decl->bounds.empty()) {
            t = Type::vector(int(decl->bounds.size()));
        } else {
            t = param_type(decl->type, pname);
        }
        scope.locals[pname] = int(i);
        f.params.push_back({pname, t});
    }
    Scope* saved = scope_;
    scope_ = &scope;
    f.result = check(*s.value);
    scope_ = saved;
    if (f.declared && f.result.valid()) {
        Type want = param_type(*f.declared->result, s.name);
        if (want.valid() && want != f.result && !(want.is_scalar() && f.result.is_scalar()))
            d_.error(s.value->span, fmt::format("'{}' is declared to give {}, but its definition gives {}", s.name, want.str(),
                                                f.result.str()));
    }
    sizes_ = saved_sizes;
    f.checking = false;
    f.checked = true;
    if (f.generic) f.instances[key] = {f.params, f.result};
}

Type Checker::check_call(Expr& e) {
    const std::string& n = e.text;
    std::vector<Type> at;
    bool args_ok = true;
    // A local function whose parameter is declared as a sequence: that is the error (check_function), said at the
    // declaration; a sequence passed to it is not another one.
    const int local = m_.find_function(n);
    for (size_t k = 0; k < e.args.size(); ++k) {
        auto& a = e.args[k];
        bool seq_param = false;
        if (local >= 0 && a->kind == ExprKind::Name && k < m_.functions[size_t(local)].stmt->params.size())
            if (const Decl* d = param_decl(m_.functions[size_t(local)], k))
                seq_param = !sequence_index(*d, m_.functions[size_t(local)].stmt->params[k].first).empty();
        allow_sequence_ = seq_param;
        at.push_back(check(*a));
        allow_sequence_ = false;
        if (seq_param && at.back().is_array()) at.back() = {};  // (the call is not checked further)
        args_ok &= at.back().valid();
    }
    auto check_args = [&](const std::vector<Type>& params, const std::string& fname) -> bool {
        if (params.size() != at.size()) {
            d_.error(e.span, fmt::format("'{}' takes {} argument{}, but {} {} given", fname, params.size(),
                                         params.size() == 1 ? "" : "s", at.size(), at.size() == 1 ? "is" : "are"));
            return false;
        }
        for (size_t i = 0; i < at.size(); ++i) {
            if (!params[i].valid() || !at[i].valid()) continue;
            if (params[i] != at[i] && !(params[i].is_scalar() && at[i].is_scalar())) {
                d_.error(e.args[i]->span, fmt::format("argument {} of '{}' must be {}, but it is {}", i + 1, fname,
                                                      params[i].str(), at[i].str()));
                return false;
            }
        }
        return true;
    };
    // A value followed by a parenthesis is a product: a(b + c).
    bool is_value = (scope_ && scope_->locals.count(n)) || m_.find_param(n) >= 0 || m_.values.count(n) ||
                    assigns_.count(n) || n == "π" || imported_constant(n) >= 0;
    if (is_value && e.args.empty()) {
        d_.error(e.span, fmt::format("'{}' is a value, not a function: '{}()' has nothing to multiply it by", n, n));
        return {};
    }
    if (is_value) {
        Expr name_expr(ExprKind::Name, e.name_span);
        name_expr.text = n;
        name_expr.name_span = e.name_span;
        Type vt = check_name(name_expr);
        e.resolved = R_Scale;
        // Keep the value's resolution for lowering in a Name node inserted as the first argument.
        auto callee = std::make_unique<Expr>(ExprKind::Name, e.name_span);
        callee->text = n;
        callee->name_span = e.name_span;
        callee->resolved = name_expr.resolved;
        callee->aux = name_expr.aux;
        callee->type = vt;
        if (e.args.size() != 1) {
            // s(1, 2, 3) is s times the vector (1, 2, 3).
            Span vs = Span::join(e.args.front()->span, e.args.back()->span);
            auto vec = std::make_unique<Expr>(ExprKind::Vector, vs);
            vec->args = std::move(e.args);
            e.args.clear();
            vec->type = check_vector_items(*vec);
            e.args.push_back(std::move(vec));
        }
        Expr& arg = *e.args[0];
        e.args.insert(e.args.begin(), std::move(callee));
        if (!vt.valid() || !arg.type.valid()) return {};
        Type t = mul_type(e, vt, arg.type, false);
        e.resolved = R_Scale;  // mul_type marks products; lowering needs to know this call is one
        return t;
    }
    if (int fi = m_.find_function(n); fi >= 0) {
        LocalFunction& f = m_.functions[size_t(fi)];
        if (!args_ok) return {};
        check_function(f, e.name_span, &at);
        e.resolved = R_LocalFn;
        e.aux = fi;
        std::vector<Type> pt;
        for (auto& p : f.params) pt.push_back(p.second);
        if (!check_args(pt, n) || !args_ok) return {};
        // Calls from inside another local function need that function to capture what the callee captures.
        if (scope_)
            for (auto& c : f.captures) {
                bool have = false;
                for (auto& mine : scope_->fn->captures) have |= mine.first == c.first;
                if (!have) scope_->fn->captures.push_back(c);
            }
        return f.result;
    }
    for (size_t ii = 0; ii < m_.imports.size(); ++ii) {
        const ImportedFunction& im = m_.imports[ii];
        if (im.name != n) continue;
        if (im.builtin >= 0) break;  // handled below as a built-in
        if (im.whole_module) {
            e.resolved = R_ImportModule;
            e.aux = int(ii);
            std::vector<Type> pt;
            for (const auto& p : im.from->params) pt.push_back(p.type);
            if (!check_args(pt, n) || !args_ok) return {};
            if (!im.from->ok || !im.from->primary_type.valid()) return {};
            return im.from->primary_type;
        }
        const LocalFunction& f = im.from->functions[size_t(im.function)];
        if (f.generic) {
            d_.error(e.name_span, fmt::format("'{}' from '{}' has symbolic sizes (ℝ^n): such functions can only be used in "
                                              "their own module for now", n, im.module));
            return {};
        }
        e.resolved = R_ImportFn;
        e.aux = int(ii);
        std::vector<Type> pt;
        for (auto& p : f.params) pt.push_back(p.second);
        if (!check_args(pt, n) || !args_ok) return {};
        return f.result;
    }
    if (auto b = find_builtin(n)) {
        const BuiltinInfo& bi = builtin(*b);
        if (*bi.module) {
            bool imported = false;
            for (auto& im : m_.imports) imported |= im.builtin == *b;
            if (!imported) {
                if (e.word_span.end > e.word_span.begin) undefined(e);  // the last letter of a word: `translate(v)`
                else d_.error(e.name_span, fmt::format("'{}' needs an import: add '{} from {}'", n, n, bi.module));
                return {};
            }
        }
        e.resolved = R_Builtin;
        e.aux = *b;
        if (!args_ok) return {};
        BuiltinCheck c = check_builtin(*b, at, n);
        if (!c.error.empty()) {
            d_.error(c.bad_arg >= 0 ? e.args[size_t(c.bad_arg)]->span : e.span, c.error);
            return {};
        }
        return c.type;
    }
    undefined(e);
    return {};
}

// Adds a note at the declaration or definition of each operand that is a plain name, with its type.
void Checker::note_operands(Diagnostic& d, const Expr& e) {
    for (const auto& a : e.args) {
        const Expr* x = a.get();
        if (x->kind != ExprKind::Name || !x->type.valid()) continue;
        if (x->resolved == R_Param || (x->resolved == R_Capture && m_.find_param(x->text) >= 0)) {
            const ParamInfo& p = m_.params[size_t(m_.find_param(x->text))];
            Diagnostics::note(d, p.span, fmt::format("'{}' is declared here as {}", p.name, p.type.str()));
        } else if (x->resolved == R_Value || x->resolved == R_Capture) {
            if (auto it = assigns_.find(x->text); it != assigns_.end())
                Diagnostics::note(d, it->second->name_span, fmt::format("'{}' is defined here as {}", x->text, x->type.str()));
        }
    }
}

Type Checker::mul_type(Expr& e, const Type& a, const Type& b, bool dot) {
    e.resolved = R_Mul;
    if (a.is_scalar() && b.is_scalar() && integer_result(e, a, b)) return Type::integer();
    if (a.is_scalar()) return b.is_scalar() ? Type::scalar() : b;
    if (b.is_scalar()) return a;
    if (a.is_vector() && b.is_vector()) {
        if (dot && a == b) {
            e.resolved = R_DotProduct;
            return Type::scalar();
        }
        if (dot) {
            note_operands(d_.error(e.span, fmt::format("cannot take the dot product of {} and {}: the sizes differ", a.str(), b.str())), e);
            return {};
        }
        note_operands(d_.error(e.span, fmt::format("cannot multiply {} by {}: use ⋅ for the dot product, ∘ for the elementwise "
                                     "product, or ᵀ for a matrix product",
                                     a.str(), b.str())), e);
        return {};
    }
    Type t = ir::result_type(ir::Op::Mul, {a, b}, 0);
    if (!t.valid()) {
        note_operands(d_.error(e.span, fmt::format("cannot multiply {} by {}: the inner sizes differ", a.str(), b.str())), e);
        return {};
    }
    return t;
}

Type Checker::check_binary(Expr& e) {
    Type a = check(*e.args[0]);
    Type b = check(*e.args[1]);
    if (!a.valid() || !b.valid()) return {};
    auto numeric = [&](const Type& t, const Expr& x) {
        if (!t.is_numeric()) {
            d_.error(x.span, fmt::format("a {} cannot be used in arithmetic", t.str()));
            return false;
        }
        return true;
    };
    switch (e.op) {
        case BinOp::Add:
        case BinOp::Sub:
            if (!numeric(a, *e.args[0]) || !numeric(b, *e.args[1])) return {};
            if (a.is_scalar() && b.is_scalar())  // ℤ ± ℤ stays ℤ (it may be a subscript: a_(b+1))
                return integer_result(e, a, b) ? Type::integer() : Type::scalar();
            if (a != b) {
                if (e.op == BinOp::Add) note_operands(d_.error(e.span, fmt::format("cannot add {} and {}", a.str(), b.str())), e);
                else note_operands(d_.error(e.span, fmt::format("cannot subtract {} from {}", b.str(), a.str())), e);
                return {};
            }
            return a;
        case BinOp::Juxtapose:
        case BinOp::Star:
        case BinOp::Dot:
            if (!numeric(a, *e.args[0]) || !numeric(b, *e.args[1])) return {};
            return mul_type(e, a, b, e.op == BinOp::Dot);
        case BinOp::Div:
            if (!numeric(a, *e.args[0]) || !numeric(b, *e.args[1])) return {};
            if (!b.is_scalar()) {
                note_operands(d_.error(e.args[1]->span, fmt::format("cannot divide by {}: '/' needs a scalar divisor", b.str())), e);
                return {};
            }
            return a.is_scalar() ? Type::scalar() : a;
        case BinOp::Hadamard:
            if (!numeric(a, *e.args[0]) || !numeric(b, *e.args[1])) return {};
            if (a.is_scalar() && b.is_scalar()) return Type::scalar();
            if (a != b) {
                note_operands(d_.error(e.span, fmt::format("the elementwise product ∘ needs equal sizes, not {} and {}", a.str(), b.str())), e);
                return {};
            }
            return a;
        case BinOp::Solve:
        case BinOp::Kronecker:
        case BinOp::Frobenius:
            return check_matrix_product(e, a, b);
        case BinOp::PlusMinus:
            d_.error(e.span, "'±' can only be used in a condition, where x = a ± b means x = a + b or x = a - b");
            return {};
        case BinOp::Cross:
            if (a != Type::vector(3) || b != Type::vector(3)) {
                note_operands(d_.error(e.span, fmt::format("the cross product × needs two ℝ³ vectors, not {} and {}", a.str(), b.str())), e);
                return {};
            }
            return a;
        default: break;
    }
    return {};
}

// A \ b (solve), A ⊗ B (Kronecker) and A : B (Frobenius), with I♥LA's type rules.
Type Checker::check_matrix_product(Expr& e, const Type& a, const Type& b) {
    auto fail = [&](std::string msg) {
        note_operands(d_.error(e.span, std::move(msg)), e);
        return Type{};
    };
    auto shaped = [](const Type& t) { return t.is_vector() || t.is_matrix(); };
    switch (e.op) {
        case BinOp::Solve:
            if (!a.is_matrix() || a.rows != a.cols)
                return fail(fmt::format("A \\ b needs a square matrix A on the left, not {}", a.str()));
            if (!shaped(b)) return fail(fmt::format("A \\ b needs a vector or a matrix b on the right, not {}", b.str()));
            if (b.rows != a.rows)
                return fail(fmt::format("cannot solve {} \\ {}: the rows differ ({} and {})", a.str(), b.str(), a.rows, b.rows));
            return b;
        case BinOp::Kronecker: {
            if (!shaped(a) || !shaped(b))
                return fail(fmt::format("the Kronecker product ⊗ needs vectors or matrices, not {} and {}", a.str(), b.str()));
            int rows = a.rows * b.rows, cols = (a.is_matrix() ? a.cols : 1) * (b.is_matrix() ? b.cols : 1);
            return cols == 1 ? Type::vector(rows) : Type::matrix(rows, cols);
        }
        default:  // Frobenius
            if (!shaped(a) || !shaped(b) || a != b)
                return fail(fmt::format("the Frobenius product A : B needs two vectors or matrices of one size, not {} and {}",
                                        a.str(), b.str()));
            return Type::scalar();
    }
}

// Sized blocks: 0_m,n (zeros), 1_n and 𝟙_m,n (ones), I_n (the identity, unless the module defines I).
// A size is a whole number or a size symbol bound by a declaration (v ∈ ℝ^n).
Type Checker::check_block(Expr& e) {
    bool identity = e.kind == ExprKind::Index;
    std::vector<int> dims;
    for (auto& it : e.indices) {
        if (!it.expr) {
            d_.error(it.span, "a block's size cannot be *");
            return {};
        }
        if (it.expr->kind == ExprKind::Name) {
            auto s = sizes_.find(it.expr->text);
            if (s == sizes_.end()) {
                d_.error(it.span, fmt::format("the size '{}' is not known: a block's size is a whole number or a size "
                                              "symbol such as n in v ∈ ℝ^n", it.expr->text));
                return {};
            }
            dims.push_back(s->second);
            continue;
        }
        auto c = const_eval(*it.expr);
        if (!c || c->size() != 1 || !((*c)[0] >= 1) || (*c)[0] != std::floor((*c)[0]) || (*c)[0] > limits::kMaxComponents) {
            d_.error(it.span, "a block's size must be a whole number ≥ 1");
            return {};
        }
        dims.push_back(int((*c)[0]));
    }
    if (identity && dims.size() != 1) {
        d_.error(e.span, "the identity I_n takes one size (it is n×n)");
        return {};
    }
    int rows = dims[0], cols = identity ? dims[0] : dims.size() > 1 ? dims[1] : 1;
    e.resolved = identity ? R_BlockIdentity : e.text == "0" ? R_BlockZero : R_BlockOnes;
    e.block_rows = {rows};
    e.block_cols = {cols};
    if (cols == 1) return Type::vector(rows);
    return Type::matrix(rows, cols);
}

// ‖x‖ and |x|, with I♥LA's subscripts: ‖v‖_1, ‖v‖_2, ‖v‖_∞, ‖v‖_p, ‖v‖_M; ‖A‖ and ‖A‖_F are Frobenius.
Type Checker::check_norm(Expr& e) {
    Type a = check(*e.args[0]);
    if (!a.valid()) return {};
    bool sub = e.args.size() > 1 || !e.text.empty();
    Span where = e.span;
    if (e.kind == ExprKind::Abs) {
        if (a.is_matrix()) {
            if (a.rows != a.cols) {
                d_.error(where, fmt::format("the determinant |·| needs a square matrix, not {}", a.str()));
                return {};
            }
            e.resolved = R_Det;
            return Type::scalar();
        }
        if (!a.is_numeric()) return {};
        if (sub && !a.is_scalar()) {
            d_.error(where, "a norm with a subscript is written with double bars, as in ‖v‖_1 (|v| is elementwise)");
            return {};
        }
        e.resolved = R_AbsValue;
        return a.is_scalar() ? Type::scalar() : a;
    }
    if (a.is_scalar()) {
        e.resolved = R_AbsValue;
        return Type::scalar();
    }
    if (a.is_matrix()) {
        if (e.text == "*") {  // the sum of the singular values: closed forms up to three of them
            if (std::min(a.rows, a.cols) > 3) {
                d_.error(where, fmt::format("the nuclear norm ‖A‖_* is supported for matrices with at most 3 rows or 3 "
                                            "columns, not {}", a.str()));
                return {};
            }
            e.resolved = R_Nuclear;
            return Type::scalar();
        }
        if (e.args.size() > 1 || (!e.text.empty() && e.text != "F")) {
            d_.error(where, fmt::format("the norm of a matrix ({}) is ‖A‖ or ‖A‖_F (Frobenius)", a.str()));
            return {};
        }
        e.resolved = R_Frobenius;
        return Type::scalar();
    }
    if (!a.is_vector()) return {};
    if (e.text == "F" || e.text == "*") {
        d_.error(where, fmt::format("‖·‖_{} is a norm of matrices; for a vector write ‖v‖, ‖v‖_1, ‖v‖_∞ or ‖v‖_p", e.text));
        return {};
    }
    e.resolved = e.text == "∞" ? R_NormMax : R_Length;
    if (e.args.size() > 1) {
        Type p = check(*e.args[1]);
        if (!p.valid()) return {};
        auto c = const_eval(*e.args[1]);
        if (p.is_matrix()) {
            if (p.rows != p.cols || p.rows != a.rows) {
                d_.error(e.args[1]->span, fmt::format("the matrix of ‖v‖_M must be {}×{} for v ∈ {}, not {}", a.rows, a.rows,
                                                      a.str(), p.str()));
                return {};
            }
            e.resolved = R_NormMatrix;
        } else if (!p.is_scalar()) {
            d_.error(e.args[1]->span, fmt::format("the subscript of a norm is a number p ≥ 1 or a matrix, not {}", p.str()));
            return {};
        } else if (c && c->size() == 1 && (*c)[0] == 0) {
            e.resolved = R_Norm0;  // ‖v‖_0: how many components are not 0 (I♥LA, after numpy)
        } else {
            e.resolved = c && (*c)[0] == 2 ? R_Length : c && (*c)[0] == 1 ? R_Norm1 : R_NormP;
        }
    }
    return Type::scalar();
}

// ⟨u, v⟩ (or <u, v>): the dot product of two vectors of one size; ⟨u, v⟩_M = vᵀ M u.
Type Checker::check_inner(Expr& e) {
    Type a = check(*e.args[0]);
    Type b = check(*e.args[1]);
    Type m = e.args.size() > 2 ? check(*e.args[2]) : Type::scalar();
    if (!a.valid() || !b.valid() || !m.valid()) return {};
    if (!a.is_vector() || a != b) {
        note_operands(d_.error(e.span, fmt::format("the inner product ⟨u, v⟩ needs two vectors of one size, not {} and {}",
                                                   a.str(), b.str())), e);
        return {};
    }
    if (e.args.size() > 2 && (!m.is_matrix() || m.rows != a.rows || m.cols != a.rows)) {
        d_.error(e.args[2]->span, fmt::format("the matrix of ⟨u, v⟩_M must be {}×{} for vectors in {}, not {}", a.rows,
                                              a.rows, a.str(), m.str()));
        return {};
    }
    return Type::scalar();
}

Type Checker::check(Expr& e) {
    limits::DepthGuard depth(depth_);
    if (!depth.enter()) {
        // The parser bounds one expression's depth; local functions calling local functions add up.
        if (!too_deep_) d_.error(e.span, fmt::format("expressions and the local functions they call nest deeper than {} "
                                                     "levels here", limits::kMaxNesting));
        too_deep_ = true;
        return {};
    }
    Type t = check_kind(e);
    if (t.valid() && t.components() > limits::kMaxComponents) {
        d_.error(e.span, fmt::format("this value has {} components: iqc allows at most {} per vector or matrix",
                                     t.components(), limits::kMaxComponents));
        t = {};
    }
    e.type = t;
    return t;
}

Type Checker::check_kind(Expr& e) {
    Type t;
    switch (e.kind) {
        case ExprKind::Number: t = Type::scalar(); break;
        case ExprKind::Name:
            t = check_name(e);
            if (t.is_array() && !allow_sequence_) {
                d_.error(e.span, fmt::format("'{}' is a sequence: use an element, such as {}_1, or {}_i inside ∑_i", e.text,
                                             e.text, e.text));
                t = {};
            }
            break;
        case ExprKind::Call: t = check_call(e); break;
        case ExprKind::Binary: t = check_binary(e); break;
        case ExprKind::Negate: {
            Type a = check(*e.args[0]);
            if (a.valid() && !a.is_numeric()) d_.error(e.span, "a condition cannot be negated with '-'");
            else t = a.kind == Type::Integer ? a : a.is_scalar() ? Type::scalar() : a;
            break;
        }
        case ExprKind::Power: {
            Type a = check(*e.args[0]);
            // a(3)² with a value a is a·(3)², not (a·3)²: the power belongs to the parenthesis.
            if (e.args[0]->kind == ExprKind::Call && e.args[0]->resolved == R_Scale) {
                ExprPtr call = std::move(e.args[0]);
                ExprPtr exponent = std::move(e.args[1]);
                auto power = std::make_unique<Expr>(ExprKind::Power, Span::join(call->args[1]->span, exponent->span));
                power->args.push_back(std::move(call->args[1]));
                power->args.push_back(std::move(exponent));
                e.kind = ExprKind::Binary;
                e.op = BinOp::Juxtapose;
                e.args.clear();
                e.args.push_back(std::move(call->args[0]));
                e.args.push_back(std::move(power));
                t = check(e);
                break;
            }
            Type b = check(*e.args[1]);
            if (!a.valid() || !b.valid()) break;
            if (a.is_scalar() && b.is_scalar()) {
                e.resolved = R_Pow;
                t = Type::scalar();
            } else if (a.is_matrix() && a.rows == a.cols && b.is_scalar()) {
                auto c = const_eval(*e.args[1]);
                if (c && c->size() == 1 && (*c)[0] == std::floor((*c)[0]) && std::fabs((*c)[0]) <= 1024) {
                    e.resolved = (*c)[0] == -1 ? R_Inverse : R_MatPow;
                    e.aux = int((*c)[0]);
                    t = a;
                } else {
                    d_.error(e.args[1]->span, "a matrix power must be a whole number such as A², A^3 or A⁻¹");
                }
            } else if (a.is_matrix()) {
                d_.error(e.span, fmt::format("only square matrices have powers, not {}", a.str()));
            } else if (!b.is_scalar()) {
                d_.error(e.args[1]->span, fmt::format("an exponent must be a scalar, not {}", b.str()));
            } else {
                d_.error(e.span, fmt::format("cannot raise {} to a power: use ‖v‖² for a squared length, or ∘ for "
                                             "elementwise products", a.str()));
            }
            break;
        }
        case ExprKind::Transpose: {
            Type a = check(*e.args[0]);
            if (a.valid()) t = ir::result_type(ir::Op::Transpose, {a}, 0);
            break;
        }
        case ExprKind::Block: t = check_block(e); break;
        case ExprKind::Index: t = check_index(e); break;
        case ExprKind::Sequence: t = check_sequence_literal(e); break;
        case ExprKind::Vector: t = check_vector_items(e); break;
        case ExprKind::Matrix: t = check_matrix_literal(e); break;
        case ExprKind::Sum: {
            int n = sum_range(*e.args[0], e.text);
            // ∑_(i for w_i > 0.5) 1/w_(i+1): the condition subscripts a sequence with the index itself (a trial's: the
            // summand's i + 1 alone did not say the range, and the error said to subscript with i).
            if (n == 0 && e.args.size() > 1) n = sum_range(*e.args[1], e.text);
            if (n <= 0) {
                if (n == 0)
                    d_.error(e.span, fmt::format("cannot tell the range of ∑_{}: subscript a vector or matrix with {} in the summand",
                                                 e.text, e.text));
                break;
            }
            e.aux = n;
            sums_.push_back({e.text, n});
            Type b = check(*e.args[0]);
            if (e.args.size() > 1) {  // ∑_(j for condition)
                Type c = check(*e.args[1]);
                if (c.valid() && c.kind != Type::Bool) d_.error(e.args[1]->span, "expected a condition such as j ≠ i");
            }
            sums_.pop_back();
            if (!b.valid()) break;
            if (!b.is_numeric()) d_.error(e.args[0]->span, "a sum needs numbers to add");
            else t = b.is_scalar() ? Type::scalar() : b;
            break;
        }
        case ExprKind::Norm:
        case ExprKind::Abs: t = check_norm(e); break;
        case ExprKind::Inner: t = check_inner(e); break;
        case ExprKind::Floor:
        case ExprKind::Ceil:
        case ExprKind::Sqrt: {
            Type a = check(*e.args[0]);
            if (!a.valid()) break;
            if (a.is_scalar() || a.is_vector()) t = a.is_scalar() ? Type::scalar() : a;
            else d_.error(e.span, fmt::format("{} needs a scalar or a vector, not {}",
                                              e.kind == ExprKind::Sqrt ? "√" : e.kind == ExprKind::Floor ? "⌊⌋" : "⌈⌉", a.str()));
            break;
        }
        case ExprKind::Compare: {
            Type a = check(*e.args[0]);
            Type b = check(*e.args[1]);
            if (!a.valid() || !b.valid()) break;
            if (!a.is_scalar() || !b.is_scalar())
                d_.error(e.span, fmt::format("a comparison needs two scalars, not {} and {}", a.str(), b.str()));
            else t = Type::boolean();
            break;
        }
        case ExprKind::Logic: {
            Type a = check(*e.args[0]);
            Type b = check(*e.args[1]);
            if (a.valid() && b.valid()) t = Type::boolean();
            break;
        }
        case ExprKind::Piecewise: {
            Type common;
            bool ok = true;
            auto unify = [&](Expr& v) {
                Type vt = check(v);
                if (!vt.valid()) { ok = false; return; }
                if (!common.valid()) common = vt.is_scalar() ? Type::scalar() : vt;
                else if (!(common.is_scalar() && vt.is_scalar()) && common != vt) {
                    d_.error(v.span, fmt::format("the cases of a piecewise definition must have one type: {} and {}",
                                                 common.str(), vt.str()));
                    ok = false;
                }
            };
            for (auto& c : e.rows) {
                unify(*c[0]);
                Type ct = check(*c[1]);
                if (ct.valid() && ct.kind != Type::Bool) {
                    d_.error(c[1]->span, "expected a condition such as x > 0");
                    ok = false;
                }
            }
            if (e.otherwise) unify(*e.otherwise);
            if (ok) t = common;
            break;
        }
    }
    return t;
}

// A subscripted value: p_1 (a component), A_2,3 / A_2,* / A_*,1 (an entry, a row, a column), x_1 or x_i (an
// element of a sequence, then optionally its component: x_i,2). A subscript is a whole number, an enclosing
// ∑'s index, or a ℤ value known only when running (a_b, b ∈ ℤ; counted from 0 for `ℤ index`).
Type Checker::check_index(Expr& e) {
    if (e.args[0]->kind == ExprKind::Name && e.args[0]->text == "I" && !defines("I")) return check_block(e);  // I_n
    if (e.args[0]->kind == ExprKind::Name && m_.find_sequence(e.args[0]->text) >= 0 &&
        !(scope_ && scope_->locals.count(e.args[0]->text)))
        return check_sequence_index(e);
    allow_sequence_ = e.args[0]->kind == ExprKind::Name;
    Type a = check(*e.args[0]);
    allow_sequence_ = false;
    if (!a.valid()) return {};
    // A subscripted scalar is most often a name meant whole (k_0, r_1 beside a slider k or r): say so, with
    // where to declare it, before any subscript's own checks (a trial's `k_0` read "subscript 0 is out of range").
    if (a.is_scalar() && e.args[0]->kind == ExprKind::Name) {
        const std::string& x = e.args[0]->text;
        // (the subscript as written: a word such as r_big too, whose letters would each be reported undefined)
        std::string sub;
        uint32_t sub_at = 0;
        if (e.indices.size() == 1 && e.indices[0].expr && e.indices[0].expr->kind == ExprKind::Number) {
            sub = e.indices[0].expr->text;
        } else if (std::all_of(e.indices.begin(), e.indices.end(), [](const IndexItem& it) {
                       return it.expr && (it.expr->kind == ExprKind::Name || it.expr->kind == ExprKind::Number);
                   })) {  // the letters after the underscore, as written (r_big reads as r_b,i then g: a matrix's entry)
            const std::string_view text = d_.sources().text(e.args[0]->span.file);
            sub_at = e.args[0]->span.end;
            if (sub_at < text.size() && text[sub_at] == '_') ++sub_at;
            for (uint32_t at = sub_at; at < text.size() && std::isalnum(static_cast<unsigned char>(text[at])); ++at) sub += text[at];
            for (uint32_t at = sub_at; at < sub_at + sub.size(); ++at) reported_words_.insert({e.args[0]->span.file, at});
        }
        const bool simple = !sub.empty();
        std::string message = fmt::format("cannot subscript '{}': it is {}, with no components or elements", x, a.str());
        if (simple) {  // (in backticks: `k_i ∈ ℝ` would declare a sequence k, `k_1 = …` start one)
            const std::string whole = x + "_" + sub;
            message += fmt::format("; to use a value of its own named {0}, write the name in backticks and declare it in "
                                   "`where` (`{0}` ∈ ℝ) or define it (`{0}` = …)",
                                   whole);
        }
        auto& err = d_.error(e.span, message);
        if (int pi = m_.find_param(x); pi >= 0)
            Diagnostics::note(err, m_.params[size_t(pi)].span, fmt::format("'{}' is declared here", x));
        return {};
    }
    if (a.is_scalar()) {  // (p_1_2: a component subscripted again; a trial's, stop 56, read "cannot subscript ℝ")
        d_.error(e.span, fmt::format("cannot subscript '{}': it is {}, with no components or elements (a matrix's entry is "
                                     "A_1,2)",
                                     std::string(d_.sources().slice(e.args[0]->span)), a.str()));
        return {};
    }
    std::vector<int> idx;
    bool ok = true;
    for (auto& it : e.indices) {
        if (!it.expr) {
            it.value = -1;
            idx.push_back(-1);
            continue;
        }
        if (it.expr->kind == ExprKind::Name &&
            std::any_of(sums_.begin(), sums_.end(), [&](auto& s) { return s.first == it.expr->text; })) {
            check(*it.expr);
            it.value = -2;  // bound by the enclosing ∑ (its range fits: see sum_range)
            idx.push_back(0);
            continue;
        }
        auto c = const_eval(*it.expr);
        if (!c && a.is_array() && &it == &e.indices[0] && it.expr->kind == ExprKind::Name && !defines(it.expr->text) &&
            !m_.values.count(it.expr->text) && !assigns_.count(it.expr->text) && it.expr->text != "π") {
            const std::string& x = e.args[0]->text;
            auto& err = d_.error(it.span, fmt::format("the index '{}' of {}_{} is not bound: use {}_{} inside ∑_{} or an "
                                                      "element-wise definition (y_{} = …), or an element such as {}_1",
                                                      it.expr->text, x, it.expr->text, x, it.expr->text, it.expr->text,
                                                      it.expr->text, x));
            if (int pi = m_.find_param(x); pi >= 0)
                Diagnostics::note(err, m_.params[size_t(pi)].span,
                                  fmt::format("{}_{} declares the sequence {}; to name one parameter {}_{}, write `{}_{}`", x,
                                              m_.params[size_t(pi)].seq_index, x, x, it.expr->text, x, it.expr->text));
            ok = false;
            continue;
        }
        if (!c) {
            Type it_type = check(*it.expr);
            if (it_type.kind == Type::Integer) {  // known when running: a_b with b ∈ ℤ
                it.value = -3;
                it.zero_based = zero_based(*it.expr);
                idx.push_back(0);
                continue;
            }
            if (it_type.valid())
                d_.error(it.span, fmt::format("a subscript must be a whole number (p_1) or a ℤ value (p_k with k ∈ ℤ), not {}",
                                              it_type.str()));
            ok = false;
            continue;
        }
        if (c->size() != 1 || (*c)[0] != std::floor((*c)[0])) {
            d_.error(it.span, "a subscript must be a whole number such as p_1 (or * for a whole row or column)");
            ok = false;
            continue;
        }
        if (!((*c)[0] >= 1)) {
            d_.error(it.span, fmt::format("subscript {} is out of range: subscripts start at 1", (*c)[0]));
            ok = false;
            continue;
        }
        if ((*c)[0] > limits::kMaxComponents) {
            d_.error(it.span, fmt::format("subscript {} is out of range: {} has fewer components", (*c)[0], a.str()));
            ok = false;
            continue;
        }
        it.value = int((*c)[0]) - 1;
        idx.push_back(it.value);
    }
    if (!ok) return {};
    size_t first = 0;
    Type base = a;
    if (a.is_array()) {  // a sequence: its first subscript picks the element
        if (idx[0] == -1) {
            d_.error(e.indices[0].span, fmt::format("an element of the sequence '{}' is chosen by a subscript, not *", e.args[0]->text));
            return {};
        }
        if (e.indices[0].value >= a.count) {
            d_.error(e.indices[0].span, fmt::format("subscript {} is out of range: the sequence '{}' has {} elements (subscripts "
                                                    "start at 1)", e.indices[0].value + 1, e.args[0]->text, a.count));
            return {};
        }
        if (e.indices.size() == 1) return a.element();
        base = a.element();
        first = 1;
    }
    size_t n = e.indices.size() - first;
    auto value = [&](size_t k) { return idx[first + k]; };
    auto dynamic = [&](size_t k) { return e.indices[first + k].value == -3; };
    auto range_error = [&](size_t k, int size, const char* what) {
        d_.error(e.indices[first + k].span, fmt::format("subscript {} is out of range: {} has {} {} (subscripts start at 1)",
                                                        e.indices[first + k].value + 1, base.str(), size, what));
    };
    if (base.is_vector()) {
        if (first > 0 && n != 1)  // (x_1,2,3 on a sequence of vectors: a trial's, stop 56)
            d_.error(e.span, fmt::format("an element of the sequence '{}' is {}: it takes one more subscript, for a component "
                                         "({}_1,2), not {}",
                                         e.args[0]->text, base.str(), e.args[0]->text, n));
        else if (n != 1 || value(0) < 0) d_.error(e.span, fmt::format("a vector ({}) takes one subscript", base.str()));
        else if (value(0) >= base.rows) range_error(0, base.rows, "components");
        else return Type::scalar();
        return {};
    }
    if (base.is_matrix()) {
        if (n != 2) {
            d_.error(e.span, fmt::format("a matrix ({}) takes two subscripts, as in A_2,3 or A_(2,3)", base.str()));
        } else if (value(0) >= base.rows) {
            range_error(0, base.rows, "rows");
        } else if (value(1) >= base.cols) {
            range_error(1, base.cols, "columns");
        } else if ((dynamic(0) || dynamic(1)) && (value(0) < 0 || value(1) < 0)) {
            d_.error(e.span, "a row or a column (A_k,*) is chosen by a whole number, not a ℤ value known only when running");
        } else if (value(0) < 0 && value(1) < 0) {
            return base;
        } else if (value(0) < 0) {
            return Type::vector(base.rows);
        } else if (value(1) < 0) {
            return Type::vector(base.cols);
        } else {
            return Type::scalar();
        }
        return {};
    }
    d_.error(e.span, fmt::format("cannot subscript {}", base.str()));
    return {};
}

// [a b; c d]: entries may be scalars, vectors (columns) or matrices (blocks); 0, 1 and I are blocks sized
// from their neighbours in the same block row and column.
Type Checker::check_matrix_literal(Expr& e) {
    size_t ncols = e.rows[0].size();
    bool ok = true;
    size_t nrows = e.rows.size();
    std::vector<std::vector<std::pair<int, int>>> size(nrows);
    for (size_t r = 0; r < nrows; ++r) {
        auto& row = e.rows[r];
        if (row.size() != ncols) {
            d_.error(Span::join(row.front()->span, row.back()->span),
                     fmt::format("this row has {} entr{} but the first row has {}", row.size(),
                                 row.size() == 1 ? "y" : "ies", ncols));
            ok = false;
        }
        for (auto& item : row) {
            bool declared_I = m_.find_param("I") >= 0 || assigns_.count("I") || (scope_ && scope_->locals.count("I"));
            if (item->kind == ExprKind::Number && (item->number == 0 || item->number == 1)) {
                item->resolved = item->number == 0 ? R_BlockZero : R_BlockOnes;
                item->type = Type::scalar();
                size[r].push_back({-1, -1});
                continue;
            }
            if (item->kind == ExprKind::Name && item->text == "I" && !declared_I) {
                item->resolved = R_BlockIdentity;
                size[r].push_back({-1, -1});
                continue;
            }
            Type it = check(*item);
            if (!it.valid()) { ok = false; size[r].push_back({1, 1}); continue; }
            if (it.is_scalar()) size[r].push_back({1, 1});
            else if (it.is_vector()) size[r].push_back({it.rows, 1});
            else if (it.is_matrix()) size[r].push_back({it.rows, it.cols});
            else { d_.error(item->span, fmt::format("a matrix entry cannot be a {}", it.str())); ok = false; size[r].push_back({1, 1}); }
        }
    }
    if (!ok) return {};
    std::vector<int> heights(nrows, -1), widths(ncols, -1);
    for (size_t r = 0; r < nrows; ++r)
        for (size_t c = 0; c < ncols; ++c) {
            auto [h, w] = size[r][c];
            if (h >= 0) {
                if (heights[r] >= 0 && heights[r] != h) {
                    d_.error(e.rows[r][c]->span, fmt::format("this block has {} rows but the blocks beside it have {}", h, heights[r]));
                    ok = false;
                }
                heights[r] = h;
            }
            if (w >= 0) {
                if (widths[c] >= 0 && widths[c] != w) {
                    d_.error(e.rows[r][c]->span, fmt::format("this block has {} columns but the blocks above or below it have {}", w, widths[c]));
                    ok = false;
                }
                widths[c] = w;
            }
        }
    // I is square: it can size its row from its column and the other way round.
    for (int pass = 0; pass < 2; ++pass)
        for (size_t r = 0; r < nrows; ++r)
            for (size_t c = 0; c < ncols; ++c)
                if (e.rows[r][c]->resolved == R_BlockIdentity) {
                    if (heights[r] < 0 && widths[c] >= 0) heights[r] = widths[c];
                    if (widths[c] < 0 && heights[r] >= 0) widths[c] = heights[r];
                }
    for (auto& h : heights) if (h < 0) h = 1;
    for (auto& w : widths) if (w < 0) w = 1;
    for (size_t r = 0; r < nrows; ++r)
        for (size_t c = 0; c < ncols; ++c)
            if (e.rows[r][c]->resolved == R_BlockIdentity && heights[r] != widths[c]) {
                d_.error(e.rows[r][c]->span, fmt::format("I must be square here, but its place is {}×{}", heights[r], widths[c]));
                ok = false;
            }
    if (!ok) return {};
    e.block_rows = heights;
    e.block_cols = widths;
    int64_t R = 0, C = 0;
    for (int h : heights) R += h;
    for (int w : widths) C += w;
    if (R * C > limits::kMaxComponents) {
        d_.error(e.span, fmt::format("this matrix has {}×{} entries: iqc allows at most {} per vector or matrix", R,
                                     C, limits::kMaxComponents));
        return {};
    }
    return C == 1 ? Type::vector(int(R)) : Type::matrix(int(R), int(C));
}

// {a, b, c}: a sequence of values of one type.
Type Checker::check_sequence_literal(Expr& e) {
    Type elem;
    for (auto& item : e.args) {
        Type t = check(*item);
        if (!t.valid()) return {};
        if (t.is_scalar()) t = Type::scalar();
        if (!t.is_numeric()) {
            d_.error(item->span, fmt::format("a sequence's elements are numbers, vectors or matrices, not {}", t.str()));
            return {};
        }
        if (elem.valid() && elem != t) {
            d_.error(item->span, fmt::format("the elements of a sequence must have one type: {} and {}", elem.str(), t.str()));
            return {};
        }
        elem = t;
    }
    return Type::array(elem, int(e.args.size()));
}

// Whether a ℤ subscript counts from 0: an I♥LA `ℤ index` (b ∈ ℤ index), or one plus or minus a count
// (b + 1); the difference of two indices is a count again.
bool Checker::zero_based(const Expr& x) const {
    switch (x.kind) {
        case ExprKind::Name:
            if (int pi = m_.find_param(x.text); pi >= 0 && (x.resolved == R_Param || x.resolved == R_Capture))
                return m_.params[size_t(pi)].zero_based;
            return x.resolved == R_Value && zero_based_values_.count(x.text);
        case ExprKind::Binary:
            if (x.op == BinOp::Add) return zero_based(*x.args[0]) != zero_based(*x.args[1]);
            if (x.op == BinOp::Sub) return zero_based(*x.args[0]) && !zero_based(*x.args[1]);
            return false;
        default: return false;
    }
}

// An element-wise definition: q_i = p_i² (a vector, or a sequence when the elements are vectors or
// matrices), B_ij = A_ij A_ij (a matrix), D_ii = v_i (a diagonal matrix). Each index runs over the size of
// what it subscripts on the right side.
Type Checker::check_elementwise(const Stmt& s) {
    std::vector<int> ranges;
    for (const auto& [letter, span] : s.elem_indices) {
        int n = sum_range(*s.value, letter);
        if (n == 0)
            d_.error(span, fmt::format("cannot tell the range of {}: subscript a vector, a matrix or a sequence with {} on "
                                       "the right side", letter, letter));
        if (n <= 0) return {};
        ranges.push_back(n);
    }
    size_t pushed = 0;
    for (size_t k = 0; k < ranges.size(); ++k)
        if (k == 0 || s.elem_indices[k].first != s.elem_indices[0].first) sums_.push_back({s.elem_indices[k].first, ranges[k]}), ++pushed;
    Type b = check(*s.value);
    sums_.resize(sums_.size() - pushed);
    if (!b.valid()) return {};
    if (!b.is_numeric()) {
        d_.error(s.value->span, "an element-wise definition needs numbers");
        return {};
    }
    Type t;
    if (ranges.size() == 1) {
        t = b.is_scalar() ? Type::vector(ranges[0]) : Type::array(b, ranges[0]);
    } else if (!b.is_scalar()) {
        d_.error(s.value->span, fmt::format("the entries of the matrix {} must be numbers, not {}", s.name, b.str()));
        return {};
    } else {
        t = ranges[1] == 1 ? Type::vector(ranges[0]) : Type::matrix(ranges[0], ranges[1]);
    }
    if (t.components() > limits::kMaxComponents) {
        d_.error(s.name_span, fmt::format("'{}' would have {} components: iqc allows at most {} per vector or matrix", s.name,
                                          t.components(), limits::kMaxComponents));
        return {};
    }
    return t;
}

// (a, b, ...): scalars and vectors concatenated. The items were already checked when they carry a type.
Type Checker::check_vector_items(Expr& e) {
    int64_t n = 0;
    bool ok = true;
    for (auto& a : e.args) {
        Type at = a->type.valid() ? a->type : check(*a);
        if (!at.valid()) { ok = false; continue; }
        if (at.is_scalar()) n += 1;
        else if (at.is_vector()) n += at.rows;
        else {
            d_.error(a->span, fmt::format("a vector's items must be scalars or vectors, not {}", at.str()));
            ok = false;
        }
    }
    if (!ok) return {};
    if (n > limits::kMaxComponents) {
        d_.error(e.span, fmt::format("this vector has {} components: iqc allows at most {}", n, limits::kMaxComponents));
        return {};
    }
    return Type::vector(int(n));
}

void Checker::check_group(const LoopGroup& g) {
    if (!g.hi_name.empty()) {
        Type t = check(*g.leader->range_hi);
        if (t.valid() && t.kind != Type::Integer)
            d_.error(g.leader->range_hi->span, fmt::format("the end of a recurrence's range must be a whole number or a "
                                                           "ℤ parameter, but '{}' is {}", g.hi_name, t.str()));
    }
    init_group_ = &g;
    for (size_t k = 0; k < g.sequences.size(); ++k) {
        Sequence& seq = m_.sequences[size_t(g.sequences[k])];
        init_at_ = k;
        seq.type = check(*seq.init->value);
        if (seq.type.is_scalar()) seq.type = Type::scalar();
    }
    init_group_ = nullptr;
    loop_ = &g;
    for (int si : g.sequences) {
        Sequence& seq = m_.sequences[size_t(si)];
        Type t = check(*seq.rec->value);
        if (!t.valid() || !seq.type.valid()) continue;
        if (!(t.is_scalar() && seq.type.is_scalar()) && t != seq.type)
            d_.error(seq.rec->value->span, fmt::format("the recurrence gives {} but '{}' starts as {}", t.str(), seq.name,
                                                       seq.type.str()));
    }
    loop_ = nullptr;
}

// z_k (inside the recurrence), z_1 (the first element) or z_(N+1) (the last).
Type Checker::check_sequence_index(Expr& e) {
    int si = m_.find_sequence(e.args[0]->text);
    const Sequence& seq = m_.sequences[size_t(si)];
    const LoopGroup& g = m_.groups[size_t(seq.group)];
    e.aux = si;
    if (e.indices.size() != 1 || !e.indices[0].expr) {
        d_.error(e.span, fmt::format("a sequence element takes one subscript, as in {}_{}", seq.name, g.lo));
        return {};
    }
    const Expr& ix = *e.indices[0].expr;
    // Inside the group's first elements: only the earlier sequences' first elements exist yet (d_1 = d_1 + 1,
    // or a first element reading the recurrence's result, would be its own cause).
    if (init_group_ == &g) {
        size_t at = size_t(std::find(g.sequences.begin(), g.sequences.end(), si) - g.sequences.begin());
        auto c0 = const_eval(ix);
        bool first = c0 && c0->size() == 1 && (*c0)[0] == g.lo;
        const Sequence& cur = m_.sequences[size_t(g.sequences[init_at_])];
        if (!first || at == init_at_) {
            d_.error(e.span, fmt::format("'{}_{}' cannot read {}: a first element cannot read itself or the recurrence's "
                                         "result", cur.name, g.lo, first ? seq.name + "_" + std::to_string(g.lo) : "a later element"));
            return {};
        }
        if (at > init_at_) {
            d_.error(e.span, fmt::format("'{}_{}' cannot read {}_{}: first elements are computed in the order of the "
                                         "recurrences, and {}'s comes after {}'s; write {}'s recurrence first",
                                         cur.name, g.lo, seq.name, g.lo, seq.name, cur.name, seq.name));
            return {};
        }
    }
    // A local function's body cannot read a module's sequence (its elements are not among the values a
    // local function captures): pass the element as an argument.
    if (scope_ && scope_->fn && loop_ != &g) {
        d_.error(e.span, fmt::format("the local function '{}' cannot read the sequence '{}': pass the element as an "
                                     "argument, e.g. {}(…, {}_{})", scope_->fn->stmt->name, seq.name, scope_->fn->stmt->name,
                                     seq.name, g.hi_name.empty() ? std::to_string(int(g.hi) + 1) : g.hi_name + "+1"));
        return {};
    }
    if (loop_ == &g && ix.kind == ExprKind::Name && ix.text == g.var) {
        e.resolved = R_SeqCurrent;
        return seq.type;
    }
    auto c = const_eval(ix);
    if (c && c->size() == 1 && (*c)[0] == g.lo) {
        e.resolved = R_SeqFirst;
        return seq.type;
    }
    bool last = g.hi_name.empty() ? (c && c->size() == 1 && (*c)[0] == g.hi + 1)
                                  : (ix.kind == ExprKind::Binary && ix.op == BinOp::Add && ix.args[0]->kind == ExprKind::Name &&
                                     ix.args[0]->text == g.hi_name && ix.args[1]->kind == ExprKind::Number &&
                                     ix.args[1]->number == 1);
    if (last) {
        if (loop_ == &g) {
            d_.error(e.indices[0].span, fmt::format("{}_{} is the result of this recurrence and cannot be used inside it",
                                                    seq.name, g.last()));
            return {};
        }
        e.resolved = R_SeqLast;
        return seq.type;
    }
    if (loop_ == &g)
        d_.error(e.indices[0].span, fmt::format("inside its recurrence, '{}' can be used as {}_{} (the current element) or "
                                                "{}_{} (the first)", seq.name, seq.name, g.var, seq.name, g.lo));
    else
        d_.error(e.indices[0].span, fmt::format("only the first and the last elements of '{}' exist outside its recurrence: "
                                                "{}_{} and {}_{}", seq.name, seq.name, g.lo, seq.name, g.last()));
    return {};
}

// The range of a ∑ index: the size of what it subscripts (every use must agree). 0 when unused,
// -1 after reporting a disagreement.
int Checker::sum_range(const Expr& body, const std::string& index) {
    int n = 0;
    bool bad = false, reported = false;
    std::function<void(const Expr&)> walk = [&](const Expr& x) {
        if (x.kind == ExprKind::Index) {
            for (size_t k = 0; k < x.indices.size(); ++k) {
                const auto& it = x.indices[k];
                if (!it.expr || it.expr->kind != ExprKind::Name || it.expr->text != index) continue;
                // The size of the subscripted thing: check it (its type does not depend on the index).
                allow_sequence_ = x.args[0]->kind == ExprKind::Name;
                Type bt = check(const_cast<Expr&>(*x.args[0]));
                allow_sequence_ = false;
                if (!bt.valid()) {  // an error already said (a sequence whose declaration failed): not again here
                    reported = true;
                    continue;
                }
                size_t pos = k;
                if (bt.is_array() && k > 0) bt = bt.element(), pos = k - 1;  // x_i,j: a component of an element
                int size = 0;
                if (bt.is_array()) size = bt.count;
                else if (bt.is_vector()) size = bt.rows;
                else if (bt.is_matrix()) size = pos == 0 ? bt.rows : bt.cols;
                if (size == 0) continue;
                if (n && n != size && !bad) {
                    d_.error(it.span, fmt::format("∑_{} runs over {} here but over {} elsewhere in the sum", index, size, n));
                    bad = true;
                }
                n = size;
            }
        }
        for (const auto& a : x.args) walk(*a);
        for (const auto& r : x.rows)
            for (const auto& a : r) walk(*a);
        if (x.otherwise) walk(*x.otherwise);
    };
    walk(body);
    return bad || (n == 0 && reported) ? -1 : n;
}

void Checker::run() {
    collect_declarations();
    collect_imports();
    collect_statements();
    order_statements();
    // Statements in dependency order; a local function is checked at its first call (its captured values
    // are typed by then), and uncalled ones afterwards.
    for (const Stmt* s : m_.order) {
        if (s->kind == StmtKind::Recurrence) {
            for (const auto& g : m_.groups)
                if (g.leader == s) check_group(g);
            continue;
        }
        Type t = s->elem_indices.empty() ? check(*s->value) : check_elementwise(*s);
        if (s->kind == StmtKind::Assign && t.valid()) {
            m_.values[s->name] = t;
            if (t.kind == Type::Integer && zero_based(*s->value)) zero_based_values_.insert(s->name);
        }
    }
    for (auto& f : m_.functions) check_function(f, f.stmt->name_span);
    // Outputs the module kind requires.
    if (m_.ast.kind == ModuleKind::Shape || m_.ast.kind == ModuleKind::Material) {
        const char* out = m_.ast.kind == ModuleKind::Shape ? "D" : "C";
        m_.primary = out;
        // A shape's value is D and a material's is C: a bare expression would be computed and never used.
        if (m_.ret)
            d_.error(m_.ret->span, fmt::format("a {} has no bare value: its value is what it assigns to '{}' (write {} = …)",
                                               m_.ast.kind == ModuleKind::Shape ? "shape" : "material", out, out));
        // The renderer binds a shape's query point and a material's surface point, normal and eye: by their
        // conventional names where the module uses them, otherwise the first parameters not yet bound, in
        // order. They must be ℝ³. These are the only rules (CheckedModule::roles; the scene compiler uses them).
        bool shape = m_.ast.kind == ModuleKind::Shape;
        std::vector<std::vector<std::string>> names = {{"p"}};
        std::vector<const char*> what = {shape ? "the query point" : "the surface point"};
        if (!shape) {
            names.push_back({"N̂", "N", "n̂", "n"});
            names.push_back({"I", "eye", "E"});
            what.push_back("the unit normal");
            what.push_back("the eye position");
        }
        m_.roles.assign(names.size(), -1);
        for (size_t r = 0; r < names.size(); ++r)
            for (const auto& n : names[r])
                if (m_.roles[r] < 0) m_.roles[r] = m_.find_param(n);
        for (size_t r = 0, next = 0; r < names.size(); ++r) {
            if (m_.roles[r] >= 0) continue;
            auto taken = [&](size_t k) { return std::find(m_.roles.begin(), m_.roles.end(), int(k)) != m_.roles.end(); };
            while (next < m_.params.size() && taken(next)) ++next;
            if (next < m_.params.size()) m_.roles[r] = int(next++);
        }
        for (size_t r = 0; r < names.size(); ++r) {
            int pi = m_.roles[r];
            if (pi < 0) {
                d_.error(m_.ast.span, fmt::format("{} '{}' needs {} as a parameter", shape ? "shape" : "material", m_.ast.name,
                                                  what[r]));
            } else if (m_.params[size_t(pi)].type != Type::vector(3)) {
                d_.error(m_.params[size_t(pi)].span, fmt::format("'{}' is {} ({}) and must be ℝ³", m_.params[size_t(pi)].name,
                                                                  what[r], m_.params[size_t(pi)].type.str()));
            }
        }
        if (!assigns_.count(out) && std::find(m_.ast.dropped.begin(), m_.ast.dropped.end(), out) != m_.ast.dropped.end()) {
            // (its statement failed to parse: reported there)
        } else if (!assigns_.count(out)) {
            d_.error(m_.ast.span, fmt::format("{} '{}' does not assign '{}' ({})", m_.ast.kind == ModuleKind::Shape ? "shape" : "material",
                                              m_.ast.name, out,
                                              m_.ast.kind == ModuleKind::Shape ? "its signed distance" : "its RGB colour"));
        } else if (m_.values.count(out)) {
            Type t = m_.values[out];
            Type want = m_.ast.kind == ModuleKind::Shape ? Type::scalar() : Type::vector(3);
            if (t != want && !(want.is_scalar() && t.is_scalar()))
                d_.error(assigns_[out]->name_span, fmt::format("'{}' must be {}, but it is {}", out, want.str(), t.str()));
            m_.primary_type = want;
        }
    } else if (m_.ret) {
        m_.primary_type = m_.ret->value->type;
    }
}

}  // namespace

std::string ParamInfo::outside_bounds_message(const std::vector<double>& v, int i, const std::string& as) const {
    return fmt::format("the value {} of '{}' is outside its slider bounds [{}, {}]", v[size_t(i)], as, lo[size_t(i)], hi[size_t(i)]);
}

std::unique_ptr<CheckedModule> check_module(ast::Module module, const ModuleLookup& lookup, const CheckOptions& opts,
                                            Diagnostics& diags) {
    auto m = std::make_unique<CheckedModule>();
    m->ast = std::move(module);
    size_t before = diags.error_count();
    Checker c(*m, lookup, opts, diags);
    c.run();
    m->ok = diags.error_count() == before;
    return m;
}

}  // namespace iqc
