#include "ir/ConvexBound.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "sema/Builtins.h"

namespace iqc::ir {

namespace {

// An affine value a⋅p + b, b within an interval (a value independent of p: its range over the parameters).
struct Affine {
    std::array<double, 3> a{};
    Interval b{0, 0};
};

// A convex piecewise-linear lower bound, and the value exactly where it is affine.
struct Convex {
    std::vector<AffinePiece> pieces;
    std::optional<Affine> exact;
};

bool finite(Interval x) { return std::isfinite(x.lo) && std::isfinite(x.hi); }

class Rules {
public:
    Rules(const Function& g, int query, const std::vector<Bounds>& values, size_t max_pieces)
        : g_(g), query_(query), values_(values), max_pieces_(max_pieces), depends_(g.body.size(), 0) {
        // Which values depend on the query point.
        for (size_t i = 0; i < g.body.size(); ++i) {
            const Instr& in = g.body[i];
            if (in.op == Op::Param) depends_[i] = in.aux == query;
            else
                for (ValueId a : in.args) depends_[i] |= depends_[a];
        }
    }

    // Component comp of value v (−1: a scalar) as an exactly affine value of p.
    std::optional<Affine> affine_value(ValueId v, int comp) { return affine(v, comp, 0); }
    bool depends(ValueId v) const { return depends_[v] != 0; }

    std::optional<Convex> convex(ValueId v, int depth = 0) {
        if (auto it = convex_memo_.find(v); it != convex_memo_.end()) return it->second;
        std::optional<Convex> r = convex_uncached(v, depth);
        if (r && r->pieces.size() > max_pieces_) r.reset();
        convex_memo_[v] = r;
        return r;
    }

private:
    const Function& g_;
    int query_;
    const std::vector<Bounds>& values_;
    size_t max_pieces_;
    std::vector<char> depends_;
    std::map<ValueId, std::optional<Convex>> convex_memo_;
    std::map<std::pair<ValueId, int>, std::optional<Affine>> affine_memo_;
    static constexpr int kDepth = 512;  // deeper expressions are not taken apart (the recursion's stack; a max
    // of n planes is a chain of n − 1 binary maxima)

    // Component `comp` of a value independent of p (its interval), if finite.
    std::optional<Interval> range(ValueId v, int comp) const {
        const Bounds& r = values_[v];
        size_t c = size_t(std::max(comp, 0));
        if (c >= r.c.size() || r.nan) return std::nullopt;
        Interval x = r.c[c];
        if (!finite(x)) return std::nullopt;
        return x;
    }
    // The same, where it is one number.
    std::optional<double> point(ValueId v, int comp) const {
        if (depends_[v]) return std::nullopt;
        auto x = range(v, comp);
        if (!x || x->lo != x->hi) return std::nullopt;
        return x->lo;
    }
    static Affine scaled(const Affine& x, double c) {
        Affine r;
        for (size_t k = 0; k < 3; ++k) r.a[k] = c * x.a[k];
        r.b = iv::mul({c, c}, x.b);
        return r;
    }
    static Affine sum(const Affine& x, const Affine& y, double sign) {
        Affine r;
        for (size_t k = 0; k < 3; ++k) r.a[k] = x.a[k] + sign * y.a[k];
        r.b = iv::add(x.b, sign > 0 ? y.b : iv::neg(y.b));
        return r;
    }

    std::optional<Affine> affine(ValueId v, int comp, int depth) {
        auto key = std::make_pair(v, comp);
        if (auto it = affine_memo_.find(key); it != affine_memo_.end()) return it->second;
        std::optional<Affine> r = depth > kDepth ? std::nullopt : affine_uncached(v, comp, depth + 1);
        if (r && !(finite(r->b) && std::isfinite(r->a[0] + r->a[1] + r->a[2]))) r.reset();
        affine_memo_[key] = r;
        return r;
    }

    std::optional<Affine> affine_uncached(ValueId v, int comp, int depth) {
        const Instr& in = g_.body[v];
        if (!depends_[v]) {
            auto x = range(v, comp);
            if (!x) return std::nullopt;
            return Affine{{0, 0, 0}, *x};
        }
        const bool scalar = comp < 0;
        switch (in.op) {
            case Op::Param:  // the query point itself
                if (scalar || in.type.rows != 3 || comp > 2) return std::nullopt;
                {
                    Affine e;
                    e.a[size_t(comp)] = 1;
                    return e;
                }
            case Op::Copy: return affine(in.args[0], comp, depth);
            case Op::Extract:
                if (!scalar || !g_.body[in.args[0]].type.is_vector()) return std::nullopt;
                return affine(in.args[0], in.aux, depth);
            case Op::Add:
            case Op::Sub: {
                const Type& ta = g_.body[in.args[0]].type;
                const Type& tb = g_.body[in.args[1]].type;
                if (!(ta == tb)) return std::nullopt;
                auto x = affine(in.args[0], comp, depth);
                auto y = x ? affine(in.args[1], comp, depth) : std::nullopt;
                if (!y) return std::nullopt;
                return sum(*x, *y, in.op == Op::Sub ? -1 : 1);
            }
            case Op::Neg: {
                auto x = affine(in.args[0], comp, depth);
                if (!x) return std::nullopt;
                return scaled(*x, -1);
            }
            case Op::Div: {  // x / c, c a constant
                auto c = point(in.args[1], -1);
                if (!c || *c == 0 || !g_.body[in.args[1]].type.is_scalar()) return std::nullopt;
                auto x = affine(in.args[0], comp, depth);
                if (!x) return std::nullopt;
                return scaled(*x, 1 / *c);
            }
            case Op::Mul: {
                const Instr& l = g_.body[in.args[0]];
                const Instr& rr = g_.body[in.args[1]];
                if (l.type.is_matrix() && rr.type.is_vector()) {  // M x, M constant
                    if (scalar || depends_[in.args[0]]) return std::nullopt;
                    const int cols = l.type.cols;
                    Affine acc;
                    for (int j = 0; j < cols; ++j) {
                        auto mij = point(in.args[0], comp * cols + j);
                        if (!mij) return std::nullopt;
                        if (*mij == 0) continue;
                        auto x = affine(in.args[1], j, depth);
                        if (!x) return std::nullopt;
                        acc = sum(acc, scaled(*x, *mij), 1);
                    }
                    return acc;
                }
                // A scalar constant times a scalar or a vector (either order).
                for (int k : {0, 1}) {
                    const ValueId c = in.args[size_t(k)], x = in.args[size_t(1 - k)];
                    if (!g_.body[c].type.is_scalar()) continue;
                    auto cv = point(c, -1);
                    if (!cv) continue;
                    const Type& tx = g_.body[x].type;
                    if (!(tx.is_scalar() || tx.is_vector())) return std::nullopt;
                    auto ax = affine(x, tx.is_scalar() ? -1 : comp, depth);
                    if (!ax) return std::nullopt;
                    return scaled(*ax, *cv);
                }
                return std::nullopt;
            }
            case Op::Hadamard: {
                if (scalar) return std::nullopt;
                for (int k : {0, 1}) {
                    auto c = point(in.args[size_t(k)], comp);
                    if (!c) continue;
                    auto x = affine(in.args[size_t(1 - k)], comp, depth);
                    if (!x) return std::nullopt;
                    return scaled(*x, *c);
                }
                return std::nullopt;
            }
            case Op::Dot: {
                if (!scalar) return std::nullopt;
                const int n = g_.body[in.args[0]].type.rows;
                for (int k : {0, 1}) {
                    const ValueId c = in.args[size_t(k)], x = in.args[size_t(1 - k)];
                    if (depends_[c]) continue;
                    Affine acc;
                    for (int j = 0; j < n; ++j) {
                        auto cj = point(c, j);
                        if (!cj) return std::nullopt;
                        if (*cj == 0) continue;
                        auto xj = affine(x, j, depth);
                        if (!xj) return std::nullopt;
                        acc = sum(acc, scaled(*xj, *cj), 1);
                    }
                    return acc;
                }
                return std::nullopt;
            }
            case Op::Construct: {
                if (scalar) return std::nullopt;
                int offset = 0;
                for (ValueId a : in.args) {
                    const Type& t = g_.body[a].type;
                    const int n = t.is_scalar() ? 1 : t.is_vector() ? t.rows : -1;
                    if (n < 0) return std::nullopt;
                    if (comp < offset + n) return affine(a, t.is_scalar() ? -1 : comp - offset, depth);
                    offset += n;
                }
                return std::nullopt;
            }
            default: return std::nullopt;
        }
    }

    std::optional<Convex> convex_uncached(ValueId v, int depth) {
        const Instr& in = g_.body[v];
        if (depth > kDepth || !in.type.is_scalar()) return std::nullopt;
        if (auto x = affine(v, -1, depth)) return Convex{{AffinePiece{x->a, x->b.lo}}, x};
        auto add_pieces = [&](const Convex& x, const Convex& y) -> std::optional<Convex> {
            if (x.pieces.size() * y.pieces.size() > max_pieces_) return std::nullopt;
            Convex r;
            for (const AffinePiece& s : x.pieces)
                for (const AffinePiece& t : y.pieces)
                    r.pieces.push_back({{s.a[0] + t.a[0], s.a[1] + t.a[1], s.a[2] + t.a[2]}, s.b + t.b});
            return r;
        };
        switch (in.op) {
            case Op::Copy: return convex(in.args[0], depth + 1);
            case Op::Builtin: {
                const std::string_view name = builtin(in.aux).name;
                if (name == "max") {  // max(x, y, …) ≥ each operand's bound
                    Convex r;
                    for (ValueId a : in.args) {
                        auto x = convex(a, depth + 1);
                        if (!x) return std::nullopt;
                        r.pieces.insert(r.pieces.end(), x->pieces.begin(), x->pieces.end());
                        if (r.pieces.size() > max_pieces_) return std::nullopt;
                    }
                    return r;
                }
                if (name == "abs" && in.args.size() == 1) {  // |x| = max(x, −x) of an affine x
                    auto x = affine(in.args[0], -1, depth + 1);
                    if (!x) return std::nullopt;
                    return Convex{{AffinePiece{x->a, x->b.lo}, AffinePiece{{-x->a[0], -x->a[1], -x->a[2]}, -x->b.hi}}, {}};
                }
                return std::nullopt;
            }
            case Op::Add: {
                auto x = convex(in.args[0], depth + 1);
                auto y = x ? convex(in.args[1], depth + 1) : std::nullopt;
                if (!y) return std::nullopt;
                return add_pieces(*x, *y);
            }
            case Op::Sub: {  // x − y of an affine y
                auto x = convex(in.args[0], depth + 1);
                auto y = x ? affine(in.args[1], -1, depth + 1) : std::nullopt;
                if (!y) return std::nullopt;
                Affine ny = scaled(*y, -1);
                return add_pieces(*x, Convex{{AffinePiece{ny.a, ny.b.lo}}, ny});
            }
            case Op::Mul:
            case Op::Div: {  // a positive constant times a bound (or a bound over one)
                const bool div = in.op == Op::Div;
                for (int k : div ? std::vector<int>{1} : std::vector<int>{0, 1}) {
                    const ValueId c = in.args[size_t(k)], x = in.args[size_t(1 - k)];
                    auto cv = g_.body[c].type.is_scalar() ? point(c, -1) : std::nullopt;
                    if (!cv || !(*cv > 0)) continue;
                    auto bx = convex(x, depth + 1);
                    if (!bx) return std::nullopt;
                    const double s = div ? 1 / *cv : *cv;
                    Convex r;
                    for (AffinePiece q : bx->pieces) {
                        for (double& a : q.a) a *= s;
                        q.b *= s;
                        r.pieces.push_back(q);
                    }
                    return r;
                }
                return std::nullopt;
            }
            default: return std::nullopt;
        }
    }
};

// Solves the 3×3 system M x = r (rows of M), nothing where it is near singular.
std::optional<std::array<double, 3>> solve3(const std::array<std::array<double, 3>, 3>& M, const std::array<double, 3>& r) {
    auto det = [](const std::array<std::array<double, 3>, 3>& A) {
        return A[0][0] * (A[1][1] * A[2][2] - A[1][2] * A[2][1]) - A[0][1] * (A[1][0] * A[2][2] - A[1][2] * A[2][0]) +
               A[0][2] * (A[1][0] * A[2][1] - A[1][1] * A[2][0]);
    };
    double scale = 0;
    for (const auto& row : M)
        for (double x : row) scale = std::max(scale, std::fabs(x));
    const double d = det(M);
    if (!(std::fabs(d) > 1e-12 * scale * scale * scale) || scale == 0) return std::nullopt;
    std::array<double, 3> x{};
    for (size_t c = 0; c < 3; ++c) {
        auto A = M;
        for (size_t i = 0; i < 3; ++i) A[i][c] = r[i];
        x[c] = det(A) / d;
    }
    return x;
}

// Rounded away from zero in the direction of `up` (a side's plane, a radius): a margin for the rounding of
// the solves.
double outward(double x, bool up) {
    const double margin = 1e-9 * std::max(1.0, std::fabs(x));
    return up ? x + margin : x - margin;
}

// The pieces as constraints aᵢ⋅p + bᵢ ≤ level with unit normals: (aᵢ⋅p + bᵢ − level)/‖aᵢ‖ ≤ 0, the same
// polytope, so that a plane written 10⁶ times steeper than the others (a scale that leaves the shape as it
// is) does not make every solve that involves it look singular (a trial's bar lost its far face's vertices
// and got a radius of 0.71 for 2.12). A piece with no normal is a constant: `empty` when it is above the level
// (nothing is ≤ level), else no constraint.
std::vector<AffinePiece> unit_constraints(const std::vector<AffinePiece>& P, double level, bool& empty) {
    std::vector<AffinePiece> out;
    empty = false;
    for (const AffinePiece& q : P) {
        const double n = std::sqrt(q.a[0] * q.a[0] + q.a[1] * q.a[1] + q.a[2] * q.a[2]);
        if (!(n > 0)) {
            empty |= q.b > level;
            continue;
        }
        out.push_back({{q.a[0] / n, q.a[1] / n, q.a[2] / n}, (q.b - level) / n});
    }
    return out;
}

}  // namespace

std::optional<std::vector<AffinePiece>> convex_lower_bound(const Module& m, const Function& g, int query,
                                                           std::vector<std::vector<Interval>> params, size_t max_pieces) {
    if (query < 0 || size_t(query) >= params.size() || size_t(query) >= g.params.size()) return std::nullopt;
    if (!g.body[g.result].type.is_scalar()) return std::nullopt;
    const Type& qt = g.params[size_t(query)].type;
    if (!qt.is_vector() || qt.rows != 3) return std::nullopt;
    params[size_t(query)].assign(3, Interval{});
    // The ranges of the values that do not depend on p (those that do are not read).
    long work = 200000;
    std::vector<Bounds> values = interval_analysis(m, g, params, {}, 0, &work);
    if (values.size() != g.body.size()) return std::nullopt;
    Rules rules(g, query, values, max_pieces);
    auto r = rules.convex(g.result);
    if (!r || r->pieces.empty()) return std::nullopt;
    for (const AffinePiece& q : r->pieces)
        if (!std::isfinite(q.b + q.a[0] + q.a[1] + q.a[2])) return std::nullopt;
    return r->pieces;
}

std::vector<AffineMap> affine_maps(const Module& m, const Function& g, int query, std::vector<std::vector<Interval>> params) {
    std::vector<AffineMap> out;
    if (query < 0 || size_t(query) >= params.size() || size_t(query) >= g.params.size()) return out;
    params[size_t(query)].assign(3, Interval{});
    long work = 200000;
    std::vector<Bounds> values = interval_analysis(m, g, params, {}, 0, &work);
    if (values.size() != g.body.size()) return out;
    Rules rules(g, query, values, 1);
    for (size_t i = 0; i < g.body.size(); ++i) {
        const Instr& in = g.body[i];
        if (!in.type.is_vector() || in.type.rows != 3 || !rules.depends(ValueId(i)) || in.op == Op::Param) continue;
        AffineMap map;
        map.value = ValueId(i);
        bool ok = true, mixing = false;
        for (int k = 0; k < 3 && ok; ++k) {
            auto x = rules.affine_value(ValueId(i), k);
            if (!x || x->b.lo != x->b.hi) {
                ok = false;
                break;
            }
            map.A[size_t(k)] = x->a;
            map.b[size_t(k)] = x->b.lo;
            int nonzero = 0;
            for (double a : x->a) nonzero += a != 0;
            mixing |= nonzero >= 2;
        }
        if (!ok || !mixing) continue;
        // A⁻¹ column by column (A e_j = ... solved for each unit vector).
        bool invertible = true;
        for (size_t j = 0; j < 3 && invertible; ++j) {
            std::array<double, 3> e{};
            e[j] = 1;
            auto col = solve3(map.A, e);
            if (!col) invertible = false;
            else
                for (size_t r = 0; r < 3; ++r) map.inverse[r][j] = (*col)[r];
        }
        if (invertible) out.push_back(map);
    }
    return out;
}

SupportBox polytope_box(const std::vector<AffinePiece>& pieces, double level_in) {
    SupportBox out;
    out.lo.fill(-INFINITY);
    out.hi.fill(INFINITY);
    bool empty = false;
    const std::vector<AffinePiece> P = unit_constraints(pieces, level_in, empty);
    const double level = 0;
    const size_t n = P.size();
    for (size_t k = 0; k < 3; ++k) {
        const size_t u = (k + 1) % 3, w = (k + 2) % 3;
        for (double s : {1.0, -1.0}) {
            double best = INFINITY;
            // A convex combination λ of the pieces listed (weights as given): its plane, where it is s·c·e_k.
            auto consider = [&](const size_t* idx, const double* lambda, size_t count) {
                double c = 0, ru = 0, rw = 0, b = 0, mag = 0;
                for (size_t t = 0; t < count; ++t) {
                    if (lambda[t] < 0) return;
                    const AffinePiece& q = P[idx[t]];
                    c += lambda[t] * q.a[k];
                    ru += lambda[t] * q.a[u];
                    rw += lambda[t] * q.a[w];
                    b += lambda[t] * q.b;
                    mag += lambda[t] * (std::fabs(q.a[0]) + std::fabs(q.a[1]) + std::fabs(q.a[2]));
                }
                c *= s;
                if (!(c > 1e-9 * mag) || std::fabs(ru) > 1e-12 * mag || std::fabs(rw) > 1e-12 * mag) return;
                best = std::min(best, (level - b) / c);
            };
            for (size_t i = 0; i < n; ++i) {
                const double one = 1;
                consider(&i, &one, 1);
                for (size_t j = i + 1; j < n; ++j) {
                    // λ_i = t, λ_j = 1 − t: t·(a_i − a_j) + a_j = 0 on the two other axes.
                    const AffinePiece &x = P[i], &y = P[j];
                    const double du = x.a[u] - y.a[u], dw = x.a[w] - y.a[w];
                    const double t = std::fabs(du) >= std::fabs(dw) ? (du != 0 ? -y.a[u] / du : NAN) : -y.a[w] / dw;
                    if (std::isfinite(t) && t >= 0 && t <= 1) {
                        size_t idx[2] = {i, j};
                        double lambda[2] = {t, 1 - t};
                        consider(idx, lambda, 2);
                    }
                    for (size_t l = j + 1; l < n; ++l) {
                        const AffinePiece& z = P[l];
                        auto lambda = solve3({{{x.a[u], y.a[u], z.a[u]}, {x.a[w], y.a[w], z.a[w]}, {1, 1, 1}}}, {0, 0, 1});
                        if (!lambda) continue;
                        size_t idx[3] = {i, j, l};
                        consider(idx, lambda->data(), 3);
                    }
                }
            }
            if (std::isfinite(best)) {
                if (s > 0) out.hi[k] = outward(best, true);
                else out.lo[k] = outward(-best, false);
            }
        }
    }
    return out;
}

std::optional<double> polytope_radius(const std::vector<AffinePiece>& pieces, double level) {
    if (pieces.size() > 128) return std::nullopt;
    SupportBox box = polytope_box(pieces, level);
    double corner = 0;
    for (size_t k = 0; k < 3; ++k) {
        if (!std::isfinite(box.lo[k]) || !std::isfinite(box.hi[k])) return std::nullopt;
        corner += std::pow(std::max(std::fabs(box.lo[k]), std::fabs(box.hi[k])), 2);
    }
    corner = outward(std::sqrt(corner), true);  // the box's farthest corner: sound whatever the vertices
    bool empty = false;
    const std::vector<AffinePiece> P = unit_constraints(pieces, level, empty);
    if (empty) return std::nullopt;
    // The vertices: every three planes whose unit normals are independent. Three that are nearly dependent
    // (|det| between rounding's 1e-14 and 1e-6) meet at a point the solve cannot place well: the box's corner then.
    double radius = -1;
    const size_t n = P.size();
    for (size_t i = 0; i < n; ++i)
        for (size_t j = i + 1; j < n; ++j)
            for (size_t l = j + 1; l < n; ++l) {
                const std::array<std::array<double, 3>, 3> M = {P[i].a, P[j].a, P[l].a};
                const double det = M[0][0] * (M[1][1] * M[2][2] - M[1][2] * M[2][1]) -
                                   M[0][1] * (M[1][0] * M[2][2] - M[1][2] * M[2][0]) +
                                   M[0][2] * (M[1][0] * M[2][1] - M[1][1] * M[2][0]);
                if (std::fabs(det) <= 1e-14) continue;  // dependent: no vertex (parallel planes, a line)
                if (std::fabs(det) <= 1e-6) return corner;
                auto p = solve3(M, {-P[i].b, -P[j].b, -P[l].b});
                if (!p) return corner;
                const double norm = std::sqrt((*p)[0] * (*p)[0] + (*p)[1] * (*p)[1] + (*p)[2] * (*p)[2]);
                bool inside = true;
                for (const AffinePiece& q : P) {
                    const double at = q.a[0] * (*p)[0] + q.a[1] * (*p)[1] + q.a[2] * (*p)[2] + q.b;
                    if (at > 1e-9 * (1 + std::fabs(q.b) + norm)) {
                        inside = false;
                        break;
                    }
                }
                if (inside) radius = std::max(radius, norm);
            }
    // A bounded polytope that is not empty has a vertex, and one as far along each axis as the box's side.
    double extent = 0;
    for (size_t k = 0; k < 3; ++k) extent = std::max({extent, std::fabs(box.lo[k]), std::fabs(box.hi[k])});
    if (radius < 0 || radius < extent * (1 - 1e-6) - 1e-9) return corner;
    return std::min(corner, outward(radius, true));
}

}  // namespace iqc::ir
