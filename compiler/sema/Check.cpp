#include "sema/Check.h"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <functional>
#include <set>

#include "ir/IR.h"
#include "sema/Builtins.h"
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
    std::map<std::string, const Stmt*> seq_leader_;  // sequence name -> its group's leader
    std::vector<std::pair<std::string, int>> sums_;  // enclosing ∑ indices and their ranges
    int depth_ = 0;          // nesting of check() (limits::kMaxNesting)
    bool too_deep_ = false;  // reported once

    int sum_range(const Expr& body, const std::string& index);

    void collect_declarations();
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
    Type mul_type(Expr& e, const Type& a, const Type& b, bool dot);
    Type param_type(const TypeSpec& ts, const std::string& name);
    std::vector<std::string> visible_names() const;
    void undefined(const std::string& name, Span s);
    Type value_type_for_scope(const std::string& name, Type t, Expr& e, int resolved, int aux);
};

Type Checker::param_type(const TypeSpec& ts, const std::string& name) {
    int rows = ts.rows, cols = ts.cols;
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
            d_.error(ts.span, fmt::format("function parameters such as '{}' are not supported yet", name));
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
                bind_sizes(decl.type, it->second, name, span);
    for (auto& decl : m_.ast.decls) {
        for (auto& [name, span] : decl.names) {
            if (decl_spans_.count(name)) {
                auto& e = d_.error(span, fmt::format("'{}' is declared twice", name));
                Diagnostics::note(e, decl_spans_[name].second, "first declared here");
                continue;
            }
            decl_spans_[name] = {name, span};
            decls_[name] = &decl;
            if (fn_params.count(name) && !used_at_module.count(name)) continue;  // a local function's parameter
            ParamInfo p;
            p.name = name;
            p.span = span;
            p.description = decl.description;
            p.type = param_type(decl.type, name);
            if (!p.type.valid()) continue;
            int n = p.type.components();
            if (!decl.bounds.empty()) {
                p.bounded = true;
                for (auto& iv : decl.bounds) {
                    auto lo = const_eval(*iv.lo), hi = const_eval(*iv.hi);
                    if (!lo || lo->size() != 1) { d_.error(iv.lo->span, "an interval bound must be a constant number"); continue; }
                    if (!hi || hi->size() != 1) { d_.error(iv.hi->span, "an interval bound must be a constant number"); continue; }
                    if ((*lo)[0] > (*hi)[0])
                        d_.error(iv.span, fmt::format("the interval is empty: {} > {}", (*lo)[0], (*hi)[0]));
                    p.lo.push_back((*lo)[0]);
                    p.hi.push_back((*hi)[0]);
                }
                if (int(p.lo.size()) != n) continue;
            }
            if (decl.default_value) {
                auto v = const_eval(*decl.default_value);
                if (!v) {
                    d_.error(decl.default_value->span, "a default must be a constant (numbers, π, and arithmetic on them)");
                } else if (int(v->size()) != n) {
                    auto& e = d_.error(decl.default_value->span,
                                       fmt::format("the default has {} component{} but '{}' is {}", v->size(),
                                                   v->size() == 1 ? "" : "s", name, p.type.str()));
                    if (p.bounded)
                        Diagnostics::note(e, decl.type.span, fmt::format("the bounds give {} interval{}", n, n == 1 ? "" : "s"));
                } else {
                    p.value = *v;
                    p.has_default = true;
                    if (p.bounded)
                        for (int i = 0; i < n; ++i)
                            if (p.value[i] < p.lo[i] || p.value[i] > p.hi[i]) {
                                d_.error(decl.default_value->span,
                                         fmt::format("the default {} of '{}' is outside its bounds [{}, {}]", p.value[i],
                                                     name, p.lo[i], p.hi[i]));
                                break;
                            }
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
                std::vector<std::string> cands;
                for (auto& bi : builtins())
                    if (module == bi.module) cands.push_back(bi.name);
                auto& e = d_.error(span, fmt::format("module '{}' has no function '{}'", module, name));
                if (auto s = did_you_mean(name, cands)) Diagnostics::note(e, span, fmt::format("did you mean '{}'?", *s));
                return;
            }
            im.builtin = *b;
        } else {
            const CheckedModule* from = lookup_ ? lookup_(module, from_span) : nullptr;
            if (!from) {
                d_.error(from_span, fmt::format("no module named '{}' to import from", module));
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
                return;
            }
        }
        m_.imports.push_back(std::move(im));
    };
    for (const auto& s : m_.ast.stmts)
        if (s.kind == StmtKind::Import)
            for (auto& [n, sp] : s.imports) add_import(n, s.from, sp, s.from_span);
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
            if (auto it = defined.find(s.name); it != defined.end()) {
                auto& e = d_.error(s.name_span, decl_spans_.count(s.name)
                                                    ? fmt::format("'{}' is a declared parameter and cannot be assigned", s.name)
                                                    : fmt::format("'{}' is assigned twice", s.name));
                Diagnostics::note(e, it->second, "first defined here");
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
            if (!has_rec)
                d_.error(i->name_span, fmt::format("'{}' is not a sequence: define it with '{}_(k+1) = … for k ∈ 1..N'",
                                                   i->name, i->name));
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

void Checker::undefined(const std::string& name, Span s) {
    if (auto b = find_builtin(name)) {
        d_.error(s, fmt::format("'{}' needs an import: add '{} from {}'", name, name, builtin(*b).module));
        return;
    }
    auto& e = d_.error(s, fmt::format("undefined name '{}'", name));
    if (auto sug = did_you_mean(name, visible_names())) Diagnostics::note(e, s, fmt::format("did you mean '{}'?", *sug));
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
    if (n == "time" || n == "mouse") {  // reserved inputs (a declaration of the same name wins)
        e.resolved = R_Input;
        e.aux = n == "time" ? 0 : 1;
        return n == "time" ? Type::scalar() : Type::vector(2);
    }
    if (m_.find_function(n) >= 0 || std::any_of(m_.imports.begin(), m_.imports.end(), [&](auto& im) { return im.name == n; })) {
        d_.error(e.span, fmt::format("'{}' is a function: call it with arguments, as in {}(x)", n, n));
        return {};
    }
    undefined(n, e.name_span);
    return {};
}

void Checker::check_function(LocalFunction& f, Span call_site, const std::vector<Type>* args) {
    const Stmt& s = *f.stmt;
    std::vector<const Decl*> decls;
    for (size_t i = 0; i < s.params.size(); ++i) {
        const std::string& pname = s.params[i].first;
        const Decl* decl = nullptr;
        for (auto& ld : s.local_decls)
            for (auto& nm : ld.names)
                if (nm.first == pname) decl = &ld;
        if (!decl)
            if (auto it = decls_.find(pname); it != decls_.end()) decl = it->second;
        decls.push_back(decl);
        if (decl && (!decl->type.sym_rows.empty() || !decl->type.sym_cols.empty())) f.generic = true;
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
        for (size_t i = 0; i < s.params.size() && i < key.size(); ++i)
            if (decls[i]) bind_sizes(decls[i]->type, key[i], s.params[i].first, call_site);
    for (size_t i = 0; i < s.params.size(); ++i) {
        const auto& [pname, pspan] = s.params[i];
        const Decl* decl = decls[i];
        Type t;
        if (!decl) {
            d_.error(pspan, fmt::format("the parameter '{}' of '{}' has no type: add 'where {} ∈ ℝ' (or its type)", pname,
                                        s.name, pname));
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
    sizes_ = saved_sizes;
    f.checking = false;
    f.checked = true;
    if (f.generic) f.instances[key] = {f.params, f.result};
}

Type Checker::check_call(Expr& e) {
    const std::string& n = e.text;
    std::vector<Type> at;
    bool args_ok = true;
    for (auto& a : e.args) {
        at.push_back(check(*a));
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
                    assigns_.count(n) || n == "π";
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
                d_.error(e.name_span, fmt::format("'{}' needs an import: add '{} from {}'", n, n, bi.module));
                return {};
            }
        }
        e.resolved = R_Builtin;
        e.aux = *b;
        if (!args_ok) return {};
        BuiltinCheck c = check_builtin(*b, at);
        if (!c.error.empty()) {
            d_.error(c.bad_arg >= 0 ? e.args[size_t(c.bad_arg)]->span : e.span, c.error);
            return {};
        }
        return c.type;
    }
    undefined(n, e.name_span);
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
            if (a.is_scalar() && b.is_scalar()) return Type::scalar();
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
        case ExprKind::Name: t = check_name(e); break;
        case ExprKind::Call: t = check_call(e); break;
        case ExprKind::Binary: t = check_binary(e); break;
        case ExprKind::Negate: {
            Type a = check(*e.args[0]);
            if (a.valid() && !a.is_numeric()) d_.error(e.span, "a condition cannot be negated with '-'");
            else t = a.is_scalar() ? Type::scalar() : a;
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
                if (c && c->size() == 1 && (*c)[0] == -1) {
                    e.resolved = R_Inverse;
                    t = a;
                } else {
                    d_.error(e.args[1]->span, "a matrix power must be ⁻¹ (the inverse)");
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
        case ExprKind::Index: {
            if (e.args[0]->kind == ExprKind::Name && m_.find_sequence(e.args[0]->text) >= 0 &&
                !(scope_ && scope_->locals.count(e.args[0]->text))) {
                t = check_sequence_index(e);
                break;
            }
            Type a = check(*e.args[0]);
            if (!a.valid()) break;
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
                if (!c || c->size() != 1 || (*c)[0] != std::floor((*c)[0])) {
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
            if (!ok) break;
            auto range_error = [&](const IndexItem& it, int size, const char* what) {
                d_.error(it.span, fmt::format("subscript {} is out of range: {} has {} {} (subscripts start at 1)",
                                              it.value + 1, a.str(), size, what));
            };
            if (a.is_vector()) {
                if (idx.size() != 1 || idx[0] < 0) {
                    d_.error(e.span, fmt::format("a vector ({}) takes one subscript", a.str()));
                } else if (idx[0] >= a.rows) {
                    range_error(e.indices[0], a.rows, "components");
                } else {
                    t = Type::scalar();
                }
            } else if (a.is_matrix()) {
                if (idx.size() != 2) {
                    d_.error(e.span, fmt::format("a matrix ({}) takes two subscripts, as in A_2,3 or A_(2,3)", a.str()));
                } else if (idx[0] >= a.rows) {
                    range_error(e.indices[0], a.rows, "rows");
                } else if (idx[1] >= a.cols) {
                    range_error(e.indices[1], a.cols, "columns");
                } else if (idx[0] < 0 && idx[1] < 0) {
                    t = a;
                } else if (idx[0] < 0) {
                    t = Type::vector(a.rows);
                } else if (idx[1] < 0) {
                    t = Type::vector(a.cols);
                } else {
                    t = Type::scalar();
                }
            } else {
                d_.error(e.span, fmt::format("cannot subscript {}", a.str()));
            }
            break;
        }
        case ExprKind::Vector: t = check_vector_items(e); break;
        case ExprKind::Matrix: {
            // Entries may be scalars, vectors (columns) or matrices (blocks); 0, 1 and I are blocks sized
            // from their neighbours in the same block row and column.
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
            if (!ok) break;
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
            if (!ok) break;
            e.block_rows = heights;
            e.block_cols = widths;
            int64_t R = 0, C = 0;
            for (int h : heights) R += h;
            for (int w : widths) C += w;
            if (R * C > limits::kMaxComponents) {
                d_.error(e.span, fmt::format("this matrix has {}×{} entries: iqc allows at most {} per vector or matrix", R,
                                             C, limits::kMaxComponents));
                break;
            }
            t = C == 1 ? Type::vector(int(R)) : Type::matrix(int(R), int(C));
            break;
        }
        case ExprKind::Sum: {
            int n = sum_range(*e.args[0], e.text);
            if (n <= 0) {
                if (n == 0)
                    d_.error(e.span, fmt::format("cannot tell the range of ∑_{}: subscript a vector or matrix with {} in the summand",
                                                 e.text, e.text));
                break;
            }
            e.aux = n;
            sums_.push_back({e.text, n});
            Type b = check(*e.args[0]);
            sums_.pop_back();
            if (!b.valid()) break;
            if (!b.is_numeric()) d_.error(e.args[0]->span, "a sum needs numbers to add");
            else t = b.is_scalar() ? Type::scalar() : b;
            break;
        }
        case ExprKind::Norm: {
            Type a = check(*e.args[0]);
            if (!a.valid()) break;
            if (a.is_vector()) { e.resolved = R_Length; t = Type::scalar(); }
            else if (a.is_scalar()) { e.resolved = R_AbsValue; t = Type::scalar(); }
            else d_.error(e.span, fmt::format("the norm ‖·‖ of {} is not supported (vectors and scalars only)", a.str()));
            break;
        }
        case ExprKind::Abs: {
            Type a = check(*e.args[0]);
            if (!a.valid()) break;
            if (a.is_matrix()) {
                if (a.rows != a.cols) d_.error(e.span, fmt::format("the determinant |·| needs a square matrix, not {}", a.str()));
                else { e.resolved = R_Det; t = Type::scalar(); }
            } else if (a.is_numeric()) {
                e.resolved = R_AbsValue;
                t = a.is_scalar() ? Type::scalar() : a;
            }
            break;
        }
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
    for (int si : g.sequences) {
        Sequence& seq = m_.sequences[size_t(si)];
        seq.type = check(*seq.init->value);
        if (seq.type.is_scalar()) seq.type = Type::scalar();
    }
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
    bool bad = false;
    std::function<void(const Expr&)> walk = [&](const Expr& x) {
        if (x.kind == ExprKind::Index) {
            for (size_t k = 0; k < x.indices.size(); ++k) {
                const auto& it = x.indices[k];
                if (!it.expr || it.expr->kind != ExprKind::Name || it.expr->text != index) continue;
                // The size of the subscripted thing: check it (its type does not depend on the index).
                Type bt = check(const_cast<Expr&>(*x.args[0]));
                int size = 0;
                if (bt.is_vector()) size = bt.rows;
                else if (bt.is_matrix()) size = k == 0 ? bt.rows : bt.cols;
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
    return bad ? -1 : n;
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
        Type t = check(*s->value);
        if (s->kind == StmtKind::Assign && t.valid()) m_.values[s->name] = t;
    }
    for (auto& f : m_.functions) check_function(f, f.stmt->name_span);
    // Outputs the module kind requires.
    if (m_.ast.kind == ModuleKind::Shape || m_.ast.kind == ModuleKind::Material) {
        const char* out = m_.ast.kind == ModuleKind::Shape ? "D" : "C";
        m_.primary = out;
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
        if (!assigns_.count(out)) {
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
