#include "ir/Intervals.h"

#include <bit>
#include <cstdint>

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <map>
#include <memory>
#include <optional>

#include "sema/Builtins.h"

namespace iqc::ir {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
// The largest loop (instructions of its body × iterations) run iteration by iteration because it reads an
// array of known values (Bounds::elements): a body of 30 instructions over 500 elements (a 300-point weighted
// mean: the Lipschitz pass 0.16 → 0.57 s, 1,000 points 0.6 → 3.3 s were they run).
constexpr double kKnownLoopWork = 4096;
}

namespace iv {

Interval hull(Interval a, Interval b) { return {std::min(a.lo, b.lo), std::max(a.hi, b.hi)}; }
Interval add(Interval a, Interval b) {
    Interval r{a.lo + b.lo, a.hi + b.hi};
    if (std::isnan(r.lo)) r.lo = -kInf;
    if (std::isnan(r.hi)) r.hi = kInf;
    return r;
}
Interval neg(Interval a) { return {-a.hi, -a.lo}; }
Interval mul(Interval a, Interval b) {
    double p[4] = {a.lo * b.lo, a.lo * b.hi, a.hi * b.lo, a.hi * b.hi};
    Interval r{kInf, -kInf};
    for (double x : p) {
        if (std::isnan(x)) x = 0;  // 0·∞: the product of a zero bound with an infinite one
        r.lo = std::min(r.lo, x);
        r.hi = std::max(r.hi, x);
    }
    return r;
}
Interval sqr(Interval a) {
    double lo = contains_zero(a) ? 0 : std::min(a.lo * a.lo, a.hi * a.hi);
    return {lo, std::max(a.lo * a.lo, a.hi * a.hi)};
}
Interval div(Interval a, Interval b) {
    if (contains_zero(b)) return {};
    return mul(a, {1 / b.hi, 1 / b.lo});
}
bool contains_zero(Interval a) { return a.lo <= 0 && a.hi >= 0; }
double magnitude(Interval a) { return std::max(std::fabs(a.lo), std::fabs(a.hi)); }
std::string text(Interval a) {
    auto n = [](double x) { return std::isinf(x) ? std::string(x > 0 ? "∞" : "-∞") : fmt::format("{:.4g}", x); };
    return fmt::format("[{}, {}]", n(a.lo), n(a.hi));
}


Interval periodic(Interval a, bool is_sin) {
    if (!(a.hi - a.lo < 2 * M_PI) || std::isinf(a.lo) || std::isinf(a.hi)) return {-1, 1};
    auto fn = [&](double v) { return is_sin ? std::sin(v) : std::cos(v); };
    Interval out{std::min(fn(a.lo), fn(a.hi)), std::max(fn(a.lo), fn(a.hi))};
    double shift = is_sin ? M_PI / 2 : 0;  // sin peaks at π/2 + kπ, cos at kπ
    // At most two extrema lie in an interval shorter than 2π. Counted, not stepped by c += π: far out (|a| ≳ 1e16)
    // adding π no longer changes c, and a stepped loop never ended.
    double first = std::ceil((a.lo - shift) / M_PI) * M_PI + shift;
    for (int i = 0; i < 3; ++i) {
        double c = first + i * M_PI;
        if (c > a.hi) break;
        out.lo = std::min(out.lo, fn(c));
        out.hi = std::max(out.hi, fn(c));
    }
    return out;
}

}  // namespace iv

double Bounds::norm_from_components() const {
    if (c.size() == 1) return iv::magnitude(c[0]);  // a scalar's (most values)
    double s = 0;
    for (const auto& x : c) {
        double m = iv::magnitude(x);
        s += m * m;
    }
    double frobenius = std::sqrt(s);
    if (rows < 2 || cols < 2 || c.size() != size_t(rows * cols)) return frobenius;
    // ‖A‖₂ ≤ √(‖A‖₁ ‖A‖∞): the largest column sum times the largest row sum of |entries|.
    double col = 0, row = 0;
    for (int j = 0; j < cols; ++j) {
        double t = 0;
        for (int i = 0; i < rows; ++i) t += iv::magnitude(c[size_t(i * cols + j)]);
        col = std::max(col, t);
    }
    for (int i = 0; i < rows; ++i) {
        double t = 0;
        for (int j = 0; j < cols; ++j) t += iv::magnitude(c[size_t(i * cols + j)]);
        row = std::max(row, t);
    }
    return std::min(frobenius, std::sqrt(col * row));
}

namespace {

using namespace iv;

Bounds unknown(const Type& t) {
    Bounds b;
    b.c.assign(size_t(std::max(1, t.components())), Interval{});
    if (t.is_matrix() && t.rows > 1 && t.cols > 1) b.rows = t.rows, b.cols = t.cols;
    return b;
}

// Finishes a value: its norm is at most what its components allow.
[[gnu::always_inline]] inline Bounds finish(Bounds b) {
    b.norm = std::min(b.norm, b.norm_from_components());
    if (b.unit) b.norm = std::min(b.norm, 1.0);
    return b;
}

Interval comp(const Bounds& b, size_t k) { return b.c.size() == 1 ? b.c[0] : b.c[k]; }

Interval monotone(Interval a, double (*f)(double)) { return {f(a.lo), f(a.hi)}; }

// mod(x, m) = x − m⌊x/m⌋ for x within `a` and a period m > 0, where x/m stays within one cell: x shifted by its cell
// (rounded outwards, within [0, m]); nullopt where it crosses a cell's edge (anything in [0, m) then).
std::optional<Interval> within_period(Interval a, double m) {
    if (!(m > 0) || !std::isfinite(m) || !std::isfinite(a.lo) || !std::isfinite(a.hi)) return std::nullopt;
    const double cell = std::floor(a.lo / m);
    if (cell != std::floor(a.hi / m) || std::fabs(cell) > 1e15) return std::nullopt;
    return Interval{std::max(0.0, std::nextafter(a.lo - cell * m, -kInf)), std::min(m, std::nextafter(a.hi - cell * m, kInf))};
}

// The hull of the elements of an array of `count` elements that an index within `k` may read (`at`: At's
// rounding and clamping to the array; else an index outside the array reads nothing), into x (one element's
// components); `element(j, q)` is component q of element j. False where the index is unbounded.
template <class Get>
bool elements_read(Bounds& x, size_t count, Interval k, bool at, const Get& element) {
    const size_t n = x.c.size();
    if (n == 0 || count == 0 || !std::isfinite(k.lo) || !std::isfinite(k.hi)) return false;
    const double last = double(count - 1);
    double lo = std::ceil(k.lo), hi = std::floor(k.hi);
    if (at) lo = std::clamp(std::floor(k.lo + 0.5), 0.0, last), hi = std::clamp(std::floor(k.hi + 0.5), 0.0, last);
    if (lo < 0 || hi > last || lo > hi || hi - lo > 4096) return false;
    for (size_t q = 0; q < n; ++q) x.c[q] = {kInf, -kInf};
    double worst = 0;
    for (size_t j = size_t(lo); j <= size_t(hi); ++j) {
        double s = 0;
        for (size_t q = 0; q < n; ++q) {
            const Interval v = element(j, q);
            x.c[q] = hull(x.c[q], v);
            s += std::max(v.lo * v.lo, v.hi * v.hi);
        }
        worst = std::max(worst, std::sqrt(s));
    }
    x.norm = worst;
    x = finish(std::move(x));
    return true;
}

// An element of `array` (of type t) read by an index within `k`: from its known values (Bounds::elements) or,
// where the bounds hold every element's components (a Construct's), from those; false where neither is there.
bool element_of(Bounds& x, const Bounds& array, const Type& t, Interval k, bool at) {
    const size_t n = x.c.size();
    if (n == 0) return false;
    if (array.elements && array.elements->size() % n == 0) {
        const std::vector<double>& e = *array.elements;
        return elements_read(x, e.size() / n, k, at, [&](size_t j, size_t q) { return Interval{e[j * n + q], e[j * n + q]}; });
    }
    if (t.is_array() && t.count > 1 && array.c.size() == size_t(t.count) * n)
        return elements_read(x, size_t(t.count), k, at, [&](size_t j, size_t q) { return array.c[j * n + q]; });
    return false;
}

// The builtins builtin_bounds has a rule for, by id (one table: a chain of name comparisons per instruction was a
// tenth of an interval analysis' time).
enum class B : uint8_t { other, sin, cos, tan, tanh, sinh, cosh, smoothstep, exp, log, ln, log_2, log_10, abs, sqrt, floor, ceil, round, fract, sign, step, min, max, clamp, mix, mod, pow, length, normalize, atan, atan2, asin, acos };
B builtin_kind(int id) {
    static const std::vector<B> kinds = [] {
        constexpr std::pair<std::string_view, B> named[] = {{"sin", B::sin}, {"cos", B::cos}, {"tan", B::tan}, {"tanh", B::tanh}, {"sinh", B::sinh}, {"cosh", B::cosh}, {"smoothstep", B::smoothstep}, {"exp", B::exp}, {"log", B::log}, {"ln", B::ln}, {"log_2", B::log_2}, {"log2", B::log_2}, {"log_10", B::log_10}, {"log10", B::log_10}, {"abs", B::abs}, {"sqrt", B::sqrt}, {"floor", B::floor}, {"ceil", B::ceil}, {"round", B::round}, {"fract", B::fract}, {"sign", B::sign}, {"step", B::step}, {"min", B::min}, {"max", B::max}, {"clamp", B::clamp}, {"mix", B::mix}, {"mod", B::mod}, {"pow", B::pow}, {"length", B::length}, {"normalize", B::normalize}, {"atan", B::atan}, {"atan2", B::atan2}, {"asin", B::asin}, {"acos", B::acos}};
        std::vector<B> k(builtins().size(), B::other);
        for (size_t i = 0; i < k.size(); ++i)
            for (const auto& [name, kind] : named)
                if (name == builtins()[i].name) k[i] = kind;
        return k;
    }();
    return size_t(id) < kinds.size() ? kinds[size_t(id)] : B::other;
}

Bounds builtin_bounds(const Instr& in, const std::vector<const Bounds*>& a) {
    const B n = builtin_kind(in.aux);
    Bounds x = unknown(in.type);
    size_t comps = x.c.size();
    auto each = [&](auto fn) {
        for (size_t k = 0; k < comps; ++k) x.c[k] = fn(k);
    };
    auto arg = [&](size_t i, size_t k) { return comp(*a[i], k); };
    if (n == B::sin || n == B::cos) each([&](size_t k) { return iv::periodic(arg(0, k), n == B::sin); });
    else if (n == B::tan)
        each([&](size_t k) {
            Interval v = arg(0, k);
            return v.lo > -M_PI / 2 && v.hi < M_PI / 2 ? Interval{std::tan(v.lo), std::tan(v.hi)} : Interval{};
        });
    else if (n == B::tanh) each([&](size_t k) { return monotone(arg(0, k), [](double v) { return std::tanh(v); }); });
    else if (n == B::sinh) each([&](size_t k) { return monotone(arg(0, k), [](double v) { return std::sinh(v); }); });
    else if (n == B::cosh)
        each([&](size_t k) {
            Interval v = arg(0, k);
            double hi = std::max(std::cosh(v.lo), std::cosh(v.hi));
            return Interval{contains_zero(v) ? 1.0 : std::min(std::cosh(v.lo), std::cosh(v.hi)), hi};
        });
    else if (n == B::smoothstep)
        each([&](size_t k) {
            // Hermite's t²(3 − 2t) of t = clamp((x − e₀)/(e₁ − e₀), 0, 1): increasing in t, t monotone in x where the
            // edges are fixed (value noise's weights, a fade over a band); [0, 1] where an edge varies
            const Interval e0 = arg(0, k), e1 = arg(1, k), v = arg(2, k);
            if (e0.lo != e0.hi || e1.lo != e1.hi || e0.lo == e1.lo || !std::isfinite(e0.lo) || !std::isfinite(e1.lo))
                return Interval{0, 1};
            auto h = [&](double x) {
                const double t = std::clamp((x - e0.lo) / (e1.lo - e0.lo), 0.0, 1.0);
                return t * t * (3 - 2 * t);
            };
            if (std::isnan(v.lo) || std::isnan(v.hi)) return Interval{0, 1};
            const double a = h(v.lo), b = h(v.hi);
            return Interval{std::max(0.0, std::nextafter(std::min(a, b), -kInf)), std::min(1.0, std::nextafter(std::max(a, b), kInf))};
        });
    else if (n == B::exp) each([&](size_t k) { return monotone(arg(0, k), [](double v) { return std::exp(v); }); });
    else if (n == B::log || n == B::ln || n == B::log_2 || n == B::log_10)
        each([&](size_t k) {
            // (log₂ and log₁₀ as ln times a constant: a divisor log₂ k with k ∈ [2, 3] had no bound, K ≤ ∞, a trial's)
            const double unit = n == B::log_2 ? 1 / std::log(2.0) : n == B::log_10 ? 1 / std::log(10.0) : 1;
            Interval v = arg(0, k);
            if (v.lo <= 0) return Interval{-kInf, v.hi > 0 ? unit * std::log(v.hi) : kInf};
            const Interval l = monotone(v, [](double t) { return std::log(t); });
            return unit == 1 ? l : Interval{std::nextafter(unit * l.lo, -kInf), std::nextafter(unit * l.hi, kInf)};
        });
    else if (n == B::abs)
        each([&](size_t k) {
            Interval v = arg(0, k);
            if (v.lo >= 0) return v;
            if (v.hi <= 0) return neg(v);
            return Interval{0, std::max(-v.lo, v.hi)};
        });
    else if (n == B::sqrt)
        each([&](size_t k) {
            Interval v = arg(0, k);
            return Interval{std::sqrt(std::max(v.lo, 0.0)), std::sqrt(std::max(v.hi, 0.0))};
        });
    else if (n == B::floor)
        each([&](size_t k) { return Interval{std::floor(arg(0, k).lo), std::floor(arg(0, k).hi)}; });
    else if (n == B::ceil)
        each([&](size_t k) { return Interval{std::ceil(arg(0, k).lo), std::ceil(arg(0, k).hi)}; });
    else if (n == B::round)  // a tie goes either way (GLSL leaves it to the implementation)
        each([&](size_t k) { return Interval{std::ceil(arg(0, k).lo - 0.5), std::floor(arg(0, k).hi + 0.5)}; });
    else if (n == B::fract)  // x − ⌊x⌋: mod(x, 1) (a point box's fract is a point)
        each([&](size_t k) { return within_period(arg(0, k), 1).value_or(Interval{0, 1}); });
    else if (n == B::sign)
        each([&](size_t k) {
            Interval v = arg(0, k);
            return Interval{v.lo > 0 ? 1.0 : v.lo >= 0 ? 0.0 : -1.0, v.hi < 0 ? -1.0 : v.hi <= 0 ? 0.0 : 1.0};
        });
    else if (n == B::step)  // step(edge, x): 0 below the edge, 1 from it on
        each([&](size_t k) {
            Interval e = arg(0, k), v = arg(1, k);
            return Interval{v.lo >= e.hi ? 1.0 : 0.0, v.hi < e.lo ? 0.0 : 1.0};
        });
    else if (n == B::min || n == B::max)
        each([&](size_t k) {
            Interval u = arg(0, k), v = arg(1, k);
            return n == B::min ? Interval{std::min(u.lo, v.lo), std::min(u.hi, v.hi)} : Interval{std::max(u.lo, v.lo), std::max(u.hi, v.hi)};
        });
    else if (n == B::clamp)
        each([&](size_t k) {
            Interval v = arg(0, k), lo = arg(1, k), hi = arg(2, k);  // min(max(v, lo), hi), also where lo > hi
            return Interval{std::min(std::max(v.lo, lo.lo), hi.lo), std::min(std::max(v.hi, lo.hi), hi.hi)};
        });
    else if (n == B::mix)
        each([&](size_t k) {
            Interval u = arg(0, k), v = arg(1, k), t = arg(2, k);  // u + t(v - u)
            // A weight within [0, 1] makes a convex combination, between u and v (u + t(v - u) taken apart
            // forgets that both terms hold the same u: mix([0, 1], [0, 1], t) would be [-1, 2]).
            if (t.lo >= 0 && t.hi <= 1) return hull(u, v);
            // u + t(v − u) = mix(u, v, clamp(t, 0, 1)) + (t − clamp(t, 0, 1))(v − u): a weight a little outside [0, 1]
            // (a refined bound's, value noise's u ∈ [0, 1.06]) widens the hull by as little (else [-1.06, 2.06])
            const Interval plain = add(u, mul(t, add(v, neg(u))));
            if (!(t.hi >= 0 && t.lo <= 1)) return plain;
            const Interval out = add(hull(u, v), mul(Interval{std::min(0.0, t.lo), std::max(0.0, t.hi - 1)}, add(v, neg(u))));
            return Interval{std::max(plain.lo, out.lo), std::min(plain.hi, out.hi)};
        });
    else if (n == B::mod)
        each([&](size_t k) {
            Interval v = arg(0, k), m = arg(1, k);
            if (m.lo == m.hi)  // (a fixed modulus: a repetition's period)
                if (auto r = within_period(v, m.lo)) return *r;
            return m.lo > 0 ? Interval{0, m.hi} : m.hi < 0 ? Interval{m.lo, 0} : Interval{};
        });
    else if (n == B::pow)
        each([&](size_t k) {
            Interval b = arg(0, k), e = arg(1, k);
            if (b.lo < 0) return Interval{};
            double c[4] = {std::pow(b.lo, e.lo), std::pow(b.lo, e.hi), std::pow(b.hi, e.lo), std::pow(b.hi, e.hi)};
            Interval r{kInf, -kInf};
            for (double v : c) {
                if (std::isnan(v)) return Interval{};
                r.lo = std::min(r.lo, v);
                r.hi = std::max(r.hi, v);
            }
            if (contains_zero(b) && e.lo < 0) r.hi = kInf;
            return r;
        });
    else if (n == B::length) {
        double lo2 = 0, hi2 = 0;
        for (size_t k = 0; k < a[0]->c.size(); ++k) {
            Interval v = arg(0, k);
            Interval s = sqr(v);
            lo2 += s.lo;
            hi2 += s.hi;
        }
        x.c = {{std::sqrt(lo2), std::min(std::sqrt(hi2), a[0]->norm)}};
    } else if (n == B::normalize) {
        each([&](size_t) { return Interval{-1, 1}; });
        x.unit = true;
    } else if (n == B::atan || n == B::atan2) each([&](size_t) { return Interval{-M_PI, M_PI}; });
    else if (n == B::asin) each([&](size_t) { return Interval{-M_PI / 2, M_PI / 2}; });
    else if (n == B::acos) each([&](size_t) { return Interval{0, M_PI}; });
    // A convex combination of two vectors by one weight within [0, 1] is no longer than the longer (gradient noise's
    // blend of its corners' unit gradients: norm 1, where its components' hull says √3)
    if (n == B::mix && comps > 1 && a.size() == 3 && a[2]->c.size() == 1 && a[2]->c[0].lo >= 0 && a[2]->c[0].hi <= 1)
        x.norm = std::max(a[0]->norm, a[1]->norm);
    return x;
}

// Matrix products on intervals: (rows×inner)·(inner×cols), vectors as columns.
Bounds product(const Type& t, const Type& ta, const Type& tb, const Bounds& a, const Bounds& b) {
    Bounds x = unknown(t);
    if (ta.is_scalar() || tb.is_scalar()) {
        const Bounds& s = ta.is_scalar() ? a : b;
        const Bounds& v = ta.is_scalar() ? b : a;
        for (size_t k = 0; k < x.c.size(); ++k) x.c[k] = mul(comp(s, 0), comp(v, k));
        x.norm = magnitude(comp(s, 0)) * v.norm;
        return x;
    }
    int ar = ta.rows, ac = ta.is_matrix() ? ta.cols : 1, br = tb.rows, bc = tb.is_matrix() ? tb.cols : 1;
    if (ta.is_vector() && tb.is_matrix() && tb.rows == 1) ac = 1, br = 1;  // outer product a·bᵀ
    if (ac != br) return x;
    for (int i = 0; i < ar; ++i)
        for (int j = 0; j < bc; ++j) {
            Interval s{0, 0};
            for (int k = 0; k < ac; ++k) s = add(s, mul(a.c[size_t(i * ac + k)], b.c[size_t(k * bc + j)]));
            if (size_t(i * bc + j) < x.c.size()) x.c[size_t(i * bc + j)] = s;
        }
    x.norm = a.norm * b.norm;  // ‖AB‖_F ≤ ‖A‖_F ‖B‖_F
    return x;
}

}  // namespace

int decided(CompareKind k, Interval a, Interval b) {
    switch (k) {
        case CompareKind::Lt: return a.hi < b.lo ? 1 : a.lo >= b.hi ? 0 : -1;
        case CompareKind::Le: return a.hi <= b.lo ? 1 : a.lo > b.hi ? 0 : -1;
        case CompareKind::Gt: return a.lo > b.hi ? 1 : a.hi <= b.lo ? 0 : -1;
        case CompareKind::Ge: return a.lo >= b.hi ? 1 : a.hi < b.lo ? 0 : -1;
        case CompareKind::Eq:
            if (a.hi < b.lo || b.hi < a.lo) return 0;
            return a.lo == a.hi && b.lo == b.hi && a.lo == b.lo ? 1 : -1;
        case CompareKind::Ne: {
            int e = decided(CompareKind::Eq, a, b);
            return e < 0 ? -1 : 1 - e;
        }
    }
    return -1;
}

namespace {

// Within float's rounding of 0 (its smallest normal number): a product of small values there is 0 on the GPU.
bool holds_zero(Interval v) { return !(v.lo > 1.2e-38 || v.hi < -1.2e-38); }
bool any_of(const Bounds& b, bool (*p)(Interval)) {
    for (const Interval& v : b.c)
        if (p(v)) return true;
    return false;
}
// Past float's range (3.4e38) at some point: a finite end beyond it, or the whole interval beyond it. (An
// infinite end alone is an unbounded box's: its points are finite.)
bool overflows(const Bounds& x) {
    constexpr double kFloatMax = 3.4e38;
    for (const Interval& v : x.c)
        if ((std::isfinite(v.lo) && std::fabs(v.lo) > kFloatMax) || (std::isfinite(v.hi) && std::fabs(v.hi) > kFloatMax) ||
            v.lo > kFloatMax || v.hi < -kFloatMax || std::isnan(v.lo) || std::isnan(v.hi))
            return true;
    return false;
}

// Whether instruction `in`, whose result's intervals are `x`, may give NaN or ±∞ somewhere on the box from
// operands that are finite numbers there (IEEE 754 in 32-bit floats, as the shader computes, and GLSL's
// undefined cases): a function outside its domain (log of ≤ 0, a root of < 0, acos beyond ±1, acosh below 1,
// atanh at ±1, pow of a negative base or of 0 to a power ≤ 0, tan at a pole, smoothstep with edges not in
// order), a division by what may be 0 (in float: below its smallest normal), a singular matrix's inverse, a
// result past float's range (10^(20x), sinh(100)). An infinity counts: 0·∞ and ∞ − ∞ make NaN downstream.
// Only operations known to stay finite on finite operands are passed; any other is taken to make NaN.
bool makes_nan(const Instr& in, const std::vector<const Bounds*>& a, const Bounds& x) {
    auto below = [&](size_t i, double c, bool strict) {
        for (const Interval& v : a[i]->c)
            if (strict ? !(v.lo > c) : !(v.lo >= c)) return true;
        return false;
    };
    auto pole = [&](double offset) {  // tan/sec (offset π/2) or cot/csc (0): a multiple of π plus offset within
        for (const Interval& v : a[0]->c) {
            if (!std::isfinite(v.lo) || !std::isfinite(v.hi) || v.hi - v.lo >= M_PI) return true;
            if (std::floor((v.hi - offset) / M_PI) != std::floor((v.lo - offset) / M_PI) || std::fmod(v.lo - offset, M_PI) == 0) return true;
        }
        return false;
    };
    switch (in.op) {
        case Op::Const:
        case Op::Param:
        case Op::Copy:
        case Op::Neg:
        case Op::Transpose:
        case Op::Construct:
        case Op::Extract:
        case Op::Row:
        case Op::Column:
        case Op::Compare:
        case Op::And:
        case Op::Or:
        case Op::Select:
        case Op::If:
        case Op::Switch:
        case Op::Index:
        case Op::Element:
        case Op::At:
        case Op::Member:
        case Op::Global:
        case Op::Input: return false;
        case Op::Add:
        case Op::Sub:
        case Op::Mul:
        case Op::Hadamard:
        case Op::Dot:
        case Op::Cross:
        case Op::Det: return overflows(x);
        case Op::Div: return any_of(*a[1], holds_zero) || overflows(x);
        case Op::IntDiv:
        case Op::IntMod: return any_of(*a[1], holds_zero);
        case Op::FloorInt: return !(a[0]->c[0].lo >= -2147483648.0 && a[0]->c[0].hi < 2147483648.0);
        case Op::Builtin: {
            std::string_view n = builtin(in.aux).name;
            if (n == "abs" || n == "ceil" || n == "clamp" || n == "cos" || n == "floor" || n == "fract" || n == "length" || n == "max" ||
                n == "min" || n == "mix" || n == "round" || n == "sign" || n == "sin" || n == "step" || n == "tanh" || n == "asinh" ||
                n == "arsinh" || n == "trace" || n == "tr" || n == "vec" || n == "diag" || n == "det")
                return overflows(x);
            // Growth past float's range at finite arguments, which an unbounded box's infinite end hides: e^x
            // beyond x = 88 (a point 89 units out is within a march's reach).
            if (n == "exp" || n == "sinh" || n == "cosh") {
                for (const Interval& v : a[0]->c)
                    if (!(v.hi <= 88 && (n == "exp" || v.lo >= -88))) return true;
                return overflows(x);
            }
            if (n == "atan" || n == "arctan" || n == "atan2")
                return a.size() > 1 && any_of(*a[0], holds_zero) && any_of(*a[1], holds_zero);
            if (n == "log" || n == "ln" || n == "log_2" || n == "log_10" || n == "log2" || n == "log10") return below(0, 0, true);
            if (n == "sqrt") return below(0, 0, false);
            if (n == "pow") {
                if (below(0, 0, false) || (any_of(*a[0], holds_zero) && below(1, 0, true)) || overflows(x)) return true;
                // b^e grows past float's range at finite exponents where b > 1 and e is unbounded above (10^(20x)),
                // or b < 1 and e unbounded below; b unbounded with a bounded exponent (x²) only past reach.
                for (size_t k = 0; k < std::max(a[0]->c.size(), a[1]->c.size()); ++k) {
                    Interval b = comp(*a[0], k), e = comp(*a[1], k);
                    if ((b.hi > 1 && !std::isfinite(e.hi)) || (b.lo < 1 && !std::isfinite(e.lo))) return true;
                }
                return false;
            }
            if (n == "asin" || n == "acos" || n == "arcsin" || n == "arccos") {
                for (const Interval& v : a[0]->c)
                    if (!(v.lo >= -1 && v.hi <= 1)) return true;
                return false;
            }
            if (n == "acosh" || n == "arcosh") return below(0, 1, false);
            if (n == "atanh" || n == "artanh") {
                for (const Interval& v : a[0]->c)
                    if (!(v.lo > -1 && v.hi < 1)) return true;
                return false;
            }
            if (n == "tan" || n == "sec") return pole(M_PI / 2) || overflows(x);
            if (n == "cot" || n == "csc") return pole(0) || overflows(x);
            if (n == "mod") return a.size() > 1 && any_of(*a[1], holds_zero);
            if (n == "normalize") return std::all_of(a[0]->c.begin(), a[0]->c.end(), [](Interval v) { return holds_zero(v); });
            if (n == "smoothstep") {  // GLSL: undefined unless edge0 < edge1
                if (a.size() < 3) return true;
                for (size_t k = 0; k < std::max(a[0]->c.size(), a[1]->c.size()); ++k)
                    if (!(comp(*a[0], k).hi < comp(*a[1], k).lo)) return true;
                return false;
            }
            return true;  // inv, and anything not known to stay finite
        }
        default: return true;  // Inverse (a singular matrix), Call and Loop (their results carry it), anything new
    }
}

// The rule of one instruction's intervals (bounds_of adds whether it may be NaN).
Bounds bounds_rule(const Module& m, const Function& f, const Instr& in, const std::vector<const Bounds*>& a) {
    (void)m;
    Bounds x = unknown(in.type);
    size_t comps = x.c.size();
    auto type = [&](size_t k) -> const Type& { return f.body[in.args[k]].type; };
    switch (in.op) {
        case Op::Const:
            x.c.clear();
            for (double v : in.data) {
                // The shader holds a constant as a float: where that moves it by more than 1e-6 (16777217 is
                // 16777216, 10000000.49 is 10000000), the interval holds both: `16777217 - a` with a = 16777216
                // was boxed at radius 1 and drawn at 3, sin(100206355.14 + a) bounded a Lipschitz factor by 6e-6
                // where the shader's is 10 (a trial). Below that the box's level covers the difference.
                const double fv = double(float(v));
                x.c.push_back(in.type.kind != Type::Integer && std::fabs(fv - v) > 1e-6 ? Interval{std::min(v, fv), std::max(v, fv)}
                                                                                     : Interval{v, v});
            }
            if (x.c.empty()) x.c.push_back({0, 0});
            break;
        case Op::Copy: return *a[0];
        case Op::Add:
        case Op::Sub:
            for (size_t k = 0; k < comps; ++k) x.c[k] = add(comp(*a[0], k), in.op == Op::Add ? comp(*a[1], k) : neg(comp(*a[1], k)));
            x.norm = a[0]->norm + a[1]->norm;
            break;
        case Op::Neg:
            for (size_t k = 0; k < comps; ++k) x.c[k] = neg(comp(*a[0], k));
            x.norm = a[0]->norm;
            x.unit = a[0]->unit;
            break;
        case Op::Mul:
            if (in.args[0] == in.args[1] && !in.type.is_matrix()) {  // a square is never negative
                for (size_t k = 0; k < comps; ++k) x.c[k] = sqr(comp(*a[0], k));
                break;
            }
            x = product(in.type, type(0), type(1), *a[0], *a[1]);
            break;
        case Op::Hadamard:
            for (size_t k = 0; k < comps; ++k) x.c[k] = in.args[0] == in.args[1] ? sqr(comp(*a[0], k)) : mul(comp(*a[0], k), comp(*a[1], k));
            break;
        case Op::Div: {
            Interval d = comp(*a[1], 0);
            for (size_t k = 0; k < comps; ++k) x.c[k] = div(comp(*a[0], k), d);
            if (!contains_zero(d)) x.norm = a[0]->norm / std::min(std::fabs(d.lo), std::fabs(d.hi));
            // v / max(‖v‖, ε) and v / ‖v‖: at most a unit vector.
            const Instr& den = f.body[in.args[1]];
            auto is_length_of = [&](const Instr& l) {
                return l.op == Op::Builtin && std::string(builtin(l.aux).name) == "length" && l.args[0] == in.args[0];
            };
            bool guarded = den.op == Op::Builtin && std::string(builtin(den.aux).name) == "max" &&
                           (is_length_of(f.body[den.args[0]]) || is_length_of(f.body[den.args[1]]));
            if (in.type.is_vector() && (is_length_of(den) || guarded)) {
                x.unit = true;
                for (auto& c : x.c) c = {std::max(c.lo, -1.0), std::min(c.hi, 1.0)};
            }
            break;
        }
        case Op::Dot: {
            Interval s{0, 0};
            if (in.args[0] == in.args[1]) {
                for (size_t k = 0; k < a[0]->c.size(); ++k) s = add(s, sqr(comp(*a[0], k)));
            } else {
                for (size_t k = 0; k < a[0]->c.size(); ++k) s = add(s, mul(comp(*a[0], k), comp(*a[1], k)));
            }
            double cs = a[0]->norm * a[1]->norm;  // Cauchy–Schwarz
            x.c = {{std::max(s.lo, -cs), std::min(s.hi, cs)}};
            break;
        }
        case Op::Cross: {
            auto c = [&](size_t i, size_t j) { return add(mul(comp(*a[0], i), comp(*a[1], j)), neg(mul(comp(*a[0], j), comp(*a[1], i)))); };
            x.c = {c(1, 2), c(2, 0), c(0, 1)};
            x.norm = a[0]->norm * a[1]->norm;
            break;
        }
        case Op::Transpose: {
            const Type& t = type(0);
            if (t.is_matrix() && t.rows > 1 && t.cols > 1)
                    for (int i = 0; i < t.rows; ++i)
                    for (int j = 0; j < t.cols; ++j) x.c[size_t(j * t.rows + i)] = a[0]->c[size_t(i * t.cols + j)];
            else
                x.c = a[0]->c;
            x.norm = a[0]->norm;
            break;
        }
        case Op::Builtin: x = builtin_bounds(in, a); break;
        case Op::Construct: {
            // A vector of parts: the root of their squared norms; a matrix of rows: that bounds its Frobenius
            // norm, hence its operator norm.
            double sq = 0;
            std::vector<Interval> c;
            for (const Bounds* b : a) {
                c.insert(c.end(), b->c.begin(), b->c.end());
                sq += b->norm * b->norm;
            }
            if (c.size() == comps) {
                x.c = std::move(c);
                x.norm = std::sqrt(sq);
            }
            break;
        }
        case Op::Extract: x.c = {comp(*a[0], size_t(in.aux))}; break;
        case Op::Row: {
            int c = type(0).cols;
            x.c.assign(a[0]->c.begin() + in.aux * c, a[0]->c.begin() + (in.aux + 1) * c);
            x.norm = a[0]->norm;
            break;
        }
        case Op::Column: {
            int rows = type(0).rows, c = type(0).cols;
            x.c.clear();
            for (int k = 0; k < rows; ++k) x.c.push_back(a[0]->c[size_t(k * c + in.aux)]);
            x.norm = a[0]->norm;
            break;
        }
        case Op::Select:
        case Op::If:
        case Op::Switch: {
            if (in.op != Op::Switch && a[0]->c.size() == 1) {  // a decided condition picks its operand
                Interval c = a[0]->c[0];
                if (c.lo >= 1) return *a[1];
                if (c.hi <= 0) return *a[2];
            }
            size_t first = 1;
            x = *a[first];
            for (size_t k = first + 1; k < a.size(); ++k) {
                for (size_t c = 0; c < comps; ++c) x.c[c] = hull(comp(x, c), comp(*a[k], c));
                x.norm = std::max(x.norm, a[k]->norm);
                x.unit = x.unit && a[k]->unit;
            }
            break;
        }
        case Op::Index:  // any element: the array's bounds are per element component already
        case Op::Element:  // (a constant index: the hull holds it too; w_i ∈ ℝ over 3 weights had no bound at all)
            {  // known values, or every element's bounds: the elements the index may read
                Interval k = in.op == Op::Element ? Interval{double(in.aux), double(in.aux)} : comp(*a[1], 0);
                if (element_of(x, *a[0], type(0), k, false)) return x;
            }
            if (a[0]->c.size() == comps) {
                x = *a[0];
                x.elements = nullptr;
                return x;
            }
            break;
        case Op::At:  // an element, or a component chosen when running: the hull of what it may choose
            if (f.body[in.args[0]].type.is_array()) {
                if (a.size() == 2 && element_of(x, *a[0], type(0), comp(*a[1], 0), true)) return x;
                if (a[0]->c.size() == comps) {
                    x = *a[0];
                    x.elements = nullptr;
                    return x;
                }
            } else if (comps == 1 && !a[0]->c.empty()) {
                x.c = {a[0]->c[0]};
                for (const auto& c : a[0]->c) x.c[0] = hull(x.c[0], c);
            }
            break;
        case Op::IntDiv:
            if (comp(*a[0], 0).lo >= 0 && comp(*a[1], 0).lo > 0)
                x.c = {{std::floor(comp(*a[0], 0).lo / comp(*a[1], 0).hi), std::floor(comp(*a[0], 0).hi / comp(*a[1], 0).lo)}};
            break;
        case Op::IntMod:
            if (comp(*a[1], 0).lo > 0) x.c = {{0, comp(*a[1], 0).hi - 1}};
            break;
        case Op::FloorInt:
            x.c = {{std::floor(comp(*a[0], 0).lo), std::floor(comp(*a[0], 0).hi)}};
            break;
        case Op::Compare:
            x.c = {{0, 1}};
            if (a[0]->c.size() == 1 && a[1]->c.size() == 1) {
                int d = decided(CompareKind(in.aux), a[0]->c[0], a[1]->c[0]);
                if (d >= 0) x.c = {{double(d), double(d)}};
            }
            break;
        case Op::And:
        case Op::Or: {
            Interval u = comp(*a[0], 0), v = comp(*a[1], 0);
            x.c = {in.op == Op::And ? Interval{std::min(u.lo, v.lo), std::min(u.hi, v.hi)}
                                    : Interval{std::max(u.lo, v.lo), std::max(u.hi, v.hi)}};
            break;
        }
        default: break;  // Param, Global, Input, Call, Loop, Member: the caller's business
    }
    return finish(std::move(x));
}

}  // namespace

Bounds bounds_of(const Module& m, const Function& f, const Instr& in, const std::vector<const Bounds*>& a) {
    (void)m;
    bool operand_nan = false;
    for (const Bounds* b : a) operand_nan |= b->nan;
    Bounds x = bounds_rule(m, f, in, a);
    if (in.op == Op::Compare) {
        x.nan = false;  // a truth value: never NaN, but false for every ordered comparison of a NaN
        if (operand_nan && x.c.size() == 1) {
            if (CompareKind(in.aux) == CompareKind::Ne) x.c[0].hi = 1;
            else x.c[0].lo = 0;
        }
    } else if (in.op == Op::Copy || in.op == Op::Index ||
               ((in.op == Op::Select || in.op == Op::If) && a[0]->c.size() == 1 && (a[0]->c[0].lo >= 1 || a[0]->c[0].hi <= 0))) {
        // the operand's own (a decided choice: the one taken; its known elements too)
        if (in.op == Op::Index) x.elements = nullptr;
        return x;
    } else {
        x.nan = x.nan || operand_nan || makes_nan(in, a, x);
        // min, max and clamp of a NaN take another operand (LLVM's minnum/maxnum: llvmpipe's min(NaN, 3) is 3),
        // a value the rule above, on the NaN operand's finite interval, does not hold: min(exp(89)/exp(88.8), 3)
        // is e^0.2 by intervals and 3 in the shader (∞/∞), and a trial's ball of radius 3 was boxed at 1.23.
        if (operand_nan && in.op == Op::Builtin) {
            std::string_view n = builtin(in.aux).name;
            if (n == "min" || n == "max" || n == "clamp")
                for (size_t k = 0; k < x.c.size(); ++k)
                    for (const Bounds* b : a)
                        if (!b->c.empty()) x.c[k] = iv::hull(x.c[k], comp(*b, std::min(k, b->c.size() - 1)));
        }
    }
    x.elements = nullptr;  // (a choice between arrays, say: only copies keep an array's known values)
    x.factor = nullptr;      // (a rule's copy of an operand's: factor_refine decides)
    return x;
}

namespace {

// Monomial factors (Factored) ------------------------------------------------------------------------------------
constexpr char kSummed = 1, kSymbol = 2;  // IntervalScratch::marks
constexpr size_t kMaxSymbols = 4;
using Powers = std::vector<std::pair<ValueId, int>>;

// Whether bounds are exactly 0 (every component: a loop state's first value, say).
bool is_zero(const Bounds& b) {
    return !b.c.empty() && std::all_of(b.c.begin(), b.c.end(), [](Interval c) { return c.lo == 0 && c.hi == 0; });
}

// The bounds of 1: a symbol s is s¹ · 1.
const Bounds& one_bounds() {
    static const Bounds one = [] {
        Bounds b;
        b.c = {Interval{1, 1}};
        b.norm = 1;
        return b;
    }();
    return one;
}

// The marks of `f`'s values (IntervalScratch::marks): bit kSummed, an operand of an Add of its type; bit kSymbol, a
// scalar Param or Global that a Div divides by, itself or through products, quotients and negations (2k, k/2, -k), or that a loop
// captures. One more entry past the values: whether any is a symbol.
std::vector<char> value_marks(const Function& f) {
    std::vector<char> marks(f.body.size(), 0), divided(f.body.size(), 0);
    for (const Instr& u : f.body) {
        if (u.op == Op::Add)
            for (ValueId a : u.args)
                if (f.body[a].type == u.type) marks[a] |= kSummed;
        if (u.op == Op::Div && u.args.size() == 2 && f.body[u.args[1]].type.is_scalar()) divided[u.args[1]] = 1;
        // (a loop's captured scalars: its body may divide by them, and its states' factors name them)
        if (u.op == Op::Loop)
            for (size_t a = 1; a < u.args.size(); ++a)
                if (f.body[u.args[a]].type.is_scalar()) divided[u.args[a]] = 1;
    }
    for (size_t i = f.body.size(); i-- > 0;) {
        if (!divided[i]) continue;
        const Instr& u = f.body[i];
        if (u.op == Op::Mul || u.op == Op::Neg || u.op == Op::Copy)
            for (ValueId a : u.args)
                if (f.body[a].type.is_scalar()) divided[a] = 1;
        if (u.op == Op::Div && f.body[u.args[0]].type.is_scalar()) divided[u.args[0]] = 1;  // (k/2)
        if ((u.op == Op::Param || u.op == Op::Global) && u.type.is_scalar()) marks[i] |= kSymbol;
    }
    marks.push_back(char(std::any_of(marks.begin(), marks.end(), [](char c) { return c & kSymbol; })));  // (one past: any)
    return marks;
}

// Whether value x is a constant whose every component is v.
bool is_const(const Function& f, ValueId x, double v) {
    const Instr& in = f.body[x];
    if (in.op != Op::Const || in.data.empty()) return false;
    for (double d : in.data)
        if (d != v) return false;
    return true;
}

// What an operand brings to a product or a sum: its factor's powers and cofactor; or, a symbol, s¹ · 1; or itself
// (no powers). `zero`: a constant 0, which is any monomial times 0.
struct FactorView {
    const Powers* powers = nullptr;  // a factor's (null: none, or a symbol's own)
    Powers own;                      // a symbol's s¹ (where `symbol`: no pointer to it, the view is copied)
    bool symbol = false;
    const Bounds* co = nullptr;
    bool zero = false;
    const Powers& get() const {
        static const Powers none;
        return symbol ? own : powers ? *powers : none;
    }
};

FactorView factor_view(const Function& f, const std::vector<Bounds>& r, const std::vector<char>& marks, ValueId v) {
    FactorView view;
    const Bounds& b = r[v];
    if (b.factor) {
        view.powers = &b.factor->powers;
        view.co = &b.factor->co;
        return view;
    }
    view.co = &b;
    if ((marks[v] & kSymbol) && b.c.size() == 1 && !b.nan && b.c[0].lo < b.c[0].hi && (b.c[0].lo > 0 || b.c[0].hi < 0) &&
        std::isfinite(b.c[0].lo) && std::isfinite(b.c[0].hi)) {
        view.own = {{v, 1}};
        view.symbol = true;
        view.co = &one_bounds();
        return view;
    }
    view.zero = is_const(f, v, 0);
    return view;
}

// a·b (sign 1) or a/b (sign -1) of two monomials, into out; false past kMaxSymbols symbols.
bool combine(const Powers& a, const Powers& b, int sign, Powers& out) {
    out.clear();
    size_t i = 0, j = 0;
    while (i < a.size() || j < b.size()) {
        if (j == b.size() || (i < a.size() && a[i].first < b[j].first)) out.push_back(a[i++]);
        else if (i == a.size() || b[j].first < a[i].first) out.push_back({b[j].first, sign * b[j].second}), ++j;
        else {
            const int p = a[i].second + sign * b[j].second;
            if (p != 0) out.push_back({a[i].first, p});
            ++i, ++j;
        }
    }
    return out.size() <= kMaxSymbols;
}

// A factor owned by the scratch (IntervalScratch::factors).
const Factored* new_factor(IntervalScratch& scratch, Powers powers, Bounds co) {
    if (scratch.factors_used == scratch.factors.size()) scratch.factors.push_back(std::make_unique<Factored>());
    Factored& f = *scratch.factors[scratch.factors_used++];
    f.powers = std::move(powers);
    f.co = std::move(co);
    return &f;
}

// The range of the monomial Π s^p over the symbols' bounds in r (each a scalar interval without 0: factor_view's
// symbols); unbounded where a symbol's bounds are not one such interval. Each symbol appears once: interval
// products are tight per symbol and sound across them.
Interval monomial_range(const Powers& powers, const std::vector<Bounds>& r) {
    Interval m{1, 1};
    for (const auto& [id, power] : powers) {
        const Bounds& b = r[id];
        if (b.c.size() != 1 || b.nan || contains_zero(b.c[0])) return Interval{-kInf, kInf};
        Interval sp{1, 1};
        for (int k = 0; k < std::abs(power); ++k) sp = mul(sp, b.c[0]);
        m = mul(m, power < 0 ? div(Interval{1, 1}, sp) : sp);
    }
    return m;
}

// Records that x is Π s^p · (a value within co): a factor, and x within the monomial's range times co (k²‖p‖/k with
// k ∈ [0.25, 3]: k · ‖p‖, within 3, where x's own intervals give 9/0.25 = 36); where every symbol cancelled, x within co.
void settle(IntervalScratch& scratch, Bounds& x, Powers powers, Bounds co, const std::vector<Bounds>& r) {
    co.factor = nullptr;
    co.elements = nullptr;
    co = finish(std::move(co));
    Bounds within;
    const Bounds* clip = &co;
    if (!powers.empty()) {
        const Interval mono = monomial_range(powers, r);
        if (std::isfinite(mono.lo) && std::isfinite(mono.hi) && co.c.size() == x.c.size()) {
            within.c = co.c;
            for (size_t k = 0; k < co.c.size(); ++k) within.c[k] = mul(mono, co.c[k]);
            within.norm = std::max(std::fabs(mono.lo), std::fabs(mono.hi)) * co.norm;
            clip = &within;
        } else {
            clip = nullptr;
        }
        x.factor = new_factor(scratch, std::move(powers), std::move(co));
    }
    if (!clip || clip->c.size() != x.c.size()) return;
    for (size_t k = 0; k < x.c.size(); ++k) {
        const Interval t{std::max(x.c[k].lo, clip->c[k].lo), std::min(x.c[k].hi, clip->c[k].hi)};
        if (t.lo <= t.hi) x.c[k] = t;  // (rounding: never empty)
    }
    if (!std::isnan(clip->norm)) x.norm = std::min(x.norm, clip->norm);
}

// The monomial factor of instruction i from its operands' (Factored): a product's powers add, a quotient's
// subtract, and a sum, a choice, a negation or a part keep what all their operands share. The cofactor's bounds are
// the instruction's rule on the operands' cofactors; where the powers cancel, they bound the value itself.
void factor_refine(IntervalScratch& scratch, const Module& m, const Function& f, std::vector<Bounds>& r,
                   const std::vector<char>& marks, size_t i, std::vector<const Bounds*>& cos) {
    const Instr& in = f.body[i];
    Bounds& x = r[i];
    if (in.type.is_array() || in.op == Op::Copy) return;  // (a copy: its operand's, bounds_of kept it)
    switch (in.op) {
        case Op::Mul:
        case Op::Hadamard:
        case Op::Dot:
        case Op::Cross:
        case Op::Div: {
            if (in.args.size() != 2) return;
            const FactorView a = factor_view(f, r, marks, in.args[0]), b = factor_view(f, r, marks, in.args[1]);
            if (a.get().empty() && b.get().empty()) return;
            Powers p;
            if (!combine(a.get(), b.get(), in.op == Op::Div ? -1 : 1, p)) return;
            Bounds co;
            if (in.op == Op::Div) {  // (the rule's own: its unit vectors v/‖v‖ are read from the code, not the cofactor)
                co = unknown(in.type);
                const Interval d = comp(*b.co, 0);
                for (size_t k = 0; k < co.c.size(); ++k) co.c[k] = div(comp(*a.co, k), d);
                if (!contains_zero(d)) co.norm = a.co->norm / std::min(std::fabs(d.lo), std::fabs(d.hi));
            } else {
                cos.assign({a.co, b.co});
                co = bounds_rule(m, f, in, cos);
            }
            settle(scratch, x, std::move(p), std::move(co), r);
            return;
        }
        case Op::Add:
        case Op::Sub:
        case Op::Neg:
        case Op::Construct:
        case Op::Extract:
        case Op::Row:
        case Op::Column:
        case Op::Transpose:
        case Op::Select:
        case Op::If:
        case Op::Switch: {
            const size_t first = in.op == Op::Select || in.op == Op::If || in.op == Op::Switch ? 1 : 0;
            if (first == 1 && in.op != Op::Switch && r[in.args[0]].c.size() == 1 &&
                (r[in.args[0]].c[0].lo >= 1 || r[in.args[0]].c[0].hi <= 0))
                return;  // (a decided choice: the operand's, bounds_of kept it)
            Powers p;
            cos.clear();
            std::vector<FactorView> views;
            views.reserve(in.args.size());
            for (size_t k = 0; k < in.args.size(); ++k) {
                if (k < first) {
                    cos.push_back(&r[in.args[k]]);
                    continue;
                }
                views.push_back(factor_view(f, r, marks, in.args[k]));
                const FactorView& v = views.back();
                if (v.zero) continue;
                if (v.get().empty() || (!p.empty() && p != v.get())) return;
                p = v.get();
            }
            if (p.empty()) return;
            for (const FactorView& v : views) cos.push_back(v.co);
            settle(scratch, x, std::move(p), bounds_rule(m, f, in, cos), r);
            return;
        }
        default: return;
    }
}

// Convex combinations (a rule interval arithmetic cannot see: it bounds each weight a_j/D on its own).
// X = (Σ_j a_j w_j)/D with every a_j ≥ 0 and D ≥ Σ_j a_j (D that sum, or max(that sum, …)) is Σ_j λ_j w_j with λ_j ≥ 0,
// Σ λ_j ≤ 1: within the hull of 0 and the w_j, its norm at most the largest ‖w_j‖. And c + X where every w_j is
// v_j − c is (1 − Σλ) c + Σ λ_j v_j: within the hull of c and the v_j. Such are the gradients of a weighted mean
// ∑_i w_i t_i/∑_j w_j (Σ w_i ∇t_i/Σ w_j) and of a log-sum-exp in its stable form m + log(max(Σ_i e^(x_i − m), 1))
// (∇m + Σ e_i(∇x_i − ∇m)/max(S, 1)): a smooth minimum of 40 distances had no bound (K ≤ ∞; a trial's, stop 52),
// it is 1. The forms are written by the differentiator: ÷D, ·(1/D), a sum of terms each ÷D, a choice of that or 0.
// A rolled sum's convex numerator (analyse's Loop rule records it): state j accumulates a·w where state k
// accumulates a ≥ 0, both from 0 (j) and from at least 0 (k); `w` bounds w over every iteration, and where w is
// v − c with c a value the loop captures, `v` bounds v and `shift` is the captured value (in the caller).
struct LoopConvex {
    int j = -1, k = -1;
    Bounds w, v;
    ValueId shift = ValueId(-1);
};
using LoopConvexMap = std::map<size_t, std::vector<LoopConvex>>;

struct ConvexForm {
    std::vector<const Bounds*> w;   // the combined values' bounds
    // Where every combined value is v_j − c for one c: c and the v_j's bounds.
    ValueId shift = ValueId(-1);
    std::vector<const Bounds*> v;
    // Σ_j a_j w_j/(c·Σ_j a_j) with c > 0 (a weighted mean over half the weights' sum: c = ½), and sums that read each
    // weight up to m times ((∑_i w_i t_i + ∑_i w_i s_i)/∑_j w_j: two combinations): within m·hull(0, w_j)/c. (A trial,
    // stop 52: both derived 10× the truth on targets with sliders, where the weights' sum is no constant.)
    Interval scale{1, 1};
    int multiplicity = 1;
};

// The leaves of the sum tree at `x` (Add of one type; at most `limit` leaves), into out; false past the limit.
bool sum_leaves(const Function& f, ValueId x, std::vector<ValueId>& out, size_t limit) {
    const Instr& in = f.body[x];
    if (in.op == Op::Add && in.args.size() == 2 && f.body[in.args[0]].type == in.type && f.body[in.args[1]].type == in.type)
        return sum_leaves(f, in.args[0], out, limit) && sum_leaves(f, in.args[1], out, limit);
    if (out.size() >= limit) return false;
    out.push_back(x);
    return true;
}

// x as (numerator, divisor): n/d, (1/d)·n, n·(1/d).
bool quotient(const Function& f, ValueId x, ValueId& n, ValueId& d) {
    const Instr& in = f.body[x];
    if (in.op == Op::Div && in.args.size() == 2 && f.body[in.args[1]].type.is_scalar()) {
        n = in.args[0], d = in.args[1];
        return true;
    }
    if (in.op == Op::Mul && in.args.size() == 2)
        for (int k = 0; k < 2; ++k) {
            const Instr& r = f.body[in.args[size_t(k)]];
            if (r.op == Op::Div && r.type.is_scalar() && is_const(f, r.args[0], 1)) {
                n = in.args[size_t(1 - k)], d = r.args[1];
                return true;
            }
        }
    return false;
}

std::optional<ConvexForm> convex_form(const Function& f, const std::vector<Bounds>& r, const LoopConvexMap& loops, ValueId x) {
    constexpr size_t kLimit = 4096;
    std::vector<ValueId> terms;
    ValueId n = 0, d = 0;
    if (quotient(f, x, n, d)) {
        // A choice of the sum or 0 (the stable log-sum-exp's derivative where its sum is below 1).
        const Instr& ni = f.body[n];
        if (ni.op == Op::Select && ni.args.size() == 3) {
            if (is_const(f, ni.args[2], 0)) n = ni.args[1];
            else if (is_const(f, ni.args[1], 0)) n = ni.args[2];
        }
        if (!sum_leaves(f, n, terms, kLimit)) return std::nullopt;
    } else {
        // Σ_j (a_j w_j)/D: each term over the same D. A summand at hand that is no quotient ends it before the whole
        // tree is walked: every Add of an unrolled sum of 4,096 terms asks (it walked its whole subtree, quadratic).
        const Instr& xi = f.body[x];
        if (xi.op != Op::Add) return std::nullopt;
        for (ValueId a : xi.args) {
            ValueId qn = 0, qd = 0;
            if (f.body[a].op != Op::Add && !quotient(f, a, qn, qd)) return std::nullopt;
        }
        std::vector<ValueId> quotients;
        if (!sum_leaves(f, x, quotients, kLimit) || quotients.size() < 2) return std::nullopt;
        for (ValueId q : quotients) {
            ValueId qn = 0, qd = 0;
            if (!quotient(f, q, qn, qd) || (!terms.empty() && qd != d)) return std::nullopt;
            d = qd;
            terms.push_back(qn);
        }
    }
    if (terms.empty()) return std::nullopt;
    // D ≥ Σ a_j: the sum itself or a max with it; or c times that, c > 0.
    std::vector<ValueId> weights;
    ConvexForm form;
    {
        const Instr& mi = f.body[d];
        if (mi.op == Op::Mul && mi.args.size() == 2 && mi.type.is_scalar())
            for (int k = 0; k < 2; ++k) {
                const Bounds& c = r[mi.args[size_t(k)]];
                if (c.c.size() == 1 && c.c[0].lo > 0 && std::isfinite(c.c[0].hi) && !c.nan && f.body[mi.args[size_t(1 - k)]].op == Op::Add) {
                    form.scale = c.c[0];
                    d = mi.args[size_t(1 - k)];
                    break;
                }
            }
    }
    const Instr& di = f.body[d];
    if (di.op == Op::Builtin && std::string_view(builtin(di.aux).name) == "max" && di.args.size() == 2) {
        bool found = false;
        for (ValueId a : di.args) {
            weights.clear();
            if (sum_leaves(f, a, weights, kLimit) && weights.size() >= terms.size()) {
                found = true;
                break;
            }
        }
        if (!found) return std::nullopt;
    } else if (!sum_leaves(f, d, weights, kLimit)) {
        return std::nullopt;
    }
    for (ValueId a : weights)
        if (r[a].c.size() != 1 || !(r[a].c[0].lo >= 0)) return std::nullopt;
    // A rolled sum: ∑_i a_i w_i / ∑_i a_i from one loop.
    if (terms.size() == 1 && weights.size() == 1 && f.body[terms[0]].op == Op::Member && f.body[weights[0]].op == Op::Member &&
        f.body[terms[0]].args[0] == f.body[weights[0]].args[0]) {
        auto it = loops.find(f.body[terms[0]].args[0]);
        if (it == loops.end()) return std::nullopt;
        for (const LoopConvex& lc : it->second)
            if (lc.j == f.body[terms[0]].aux && lc.k == f.body[weights[0]].aux) {
                form.w.push_back(&lc.w);
                if (form.scale.lo == 1 && form.scale.hi == 1) {  // (c + X needs Σ λ ≤ 1)
                    form.shift = lc.shift;
                    if (lc.shift != ValueId(-1)) form.v.push_back(&lc.v);
                }
                return form;
            }
        return std::nullopt;
    }
    std::sort(weights.begin(), weights.end());
    std::vector<int> uses(weights.size(), 0);  // (how many terms read each weight)
    bool shifted = true;
    auto add_term = [&](ValueId w) {
        form.w.push_back(&r[w]);
        const Instr& wi = f.body[w];
        const bool sub = wi.op == Op::Sub && wi.args.size() == 2 && (form.v.empty() || wi.args[1] == form.shift);
        shifted = shifted && sub;
        if (shifted) {
            form.shift = wi.args[1];
            form.v.push_back(&r[wi.args[0]]);
        }
    };
    for (ValueId t : terms) {
        const Instr& ti = f.body[t];
        if (ti.op == Op::Member) {
            // A rolled sum's convex numerator beside other terms (its state j), over its denominator's state k among the
            // weights (a ring of 32 blobs and a core under one log-sum-exp: K ≤ ∞ on webgl2, a trial's, stop 54).
            auto it = loops.find(ti.args[0]);
            bool matched = false;
            for (size_t q = 0; it != loops.end() && q < it->second.size() && !matched; ++q) {
                const LoopConvex& lc = it->second[q];
                if (lc.j != int(ti.aux)) continue;
                auto at = std::find_if(weights.begin(), weights.end(), [&](ValueId a) {
                    return f.body[a].op == Op::Member && f.body[a].args[0] == ti.args[0] && int(f.body[a].aux) == lc.k;
                });
                if (at == weights.end()) continue;
                ++uses[size_t(at - weights.begin())];
                form.w.push_back(&lc.w);
                const bool same = lc.shift != ValueId(-1) && (form.v.empty() || lc.shift == form.shift);
                shifted = shifted && same;
                if (shifted) {
                    form.shift = lc.shift;
                    form.v.push_back(&lc.v);
                }
                matched = true;
            }
            if (!matched) return std::nullopt;
            continue;
        }
        if (ti.op != Op::Mul || ti.args.size() != 2) return std::nullopt;
        bool matched = false;
        for (int k = 0; k < 2 && !matched; ++k) {
            const ValueId a = ti.args[size_t(k)];
            auto at = std::lower_bound(weights.begin(), weights.end(), a);
            if (at == weights.end() || *at != a || !f.body[a].type.is_scalar()) continue;
            ++uses[size_t(at - weights.begin())];
            const ValueId w = ti.args[size_t(1 - k)];
            add_term(w);
            matched = true;
        }
        // w·(e·v) over a weight written w·e (a weighted log-sum-exp's ∑_i w_i e_i(∇x_i − ∇m)).
        for (int k = 0; k < 2 && !matched; ++k) {
            const ValueId s = ti.args[size_t(k)];
            const Instr& inner = f.body[ti.args[size_t(1 - k)]];
            if (!f.body[s].type.is_scalar() || inner.op != Op::Mul || inner.args.size() != 2) continue;
            for (int q = 0; q < 2 && !matched; ++q) {
                const ValueId e = inner.args[size_t(q)];
                if (!f.body[e].type.is_scalar()) continue;
                auto leaf = std::find_if(weights.begin(), weights.end(), [&](ValueId a) {
                    const Instr& ai = f.body[a];
                    return ai.op == Op::Mul && ai.args.size() == 2 &&
                           ((ai.args[0] == s && ai.args[1] == e) || (ai.args[0] == e && ai.args[1] == s));
                });
                if (leaf == weights.end()) continue;
                ++uses[size_t(leaf - weights.begin())];
                add_term(inner.args[size_t(1 - q)]);
                matched = true;
            }
        }
        if (!matched) return std::nullopt;
    }
    form.multiplicity = uses.empty() ? 1 : std::max(1, *std::max_element(uses.begin(), uses.end()));
    if (!shifted || form.multiplicity > 1 || form.scale.lo != 1 || form.scale.hi != 1) {  // (c + X needs Σ λ ≤ 1)
        form.shift = ValueId(-1);
        form.v.clear();
    }
    return form;
}

// Bounds of a convex combination of `parts` (with 0 where `with_zero`): their components' hull, their largest norm.
void convex_bounds(Bounds& x, const std::vector<const Bounds*>& parts, bool with_zero, int multiplicity = 1,
                   Interval scale = {1, 1}) {
    const size_t n = x.c.size();
    IntervalVec hullv(n, Interval{with_zero ? 0.0 : kInf, with_zero ? 0.0 : -kInf});
    double norm = 0;
    for (const Bounds* p : parts) {
        if (p->c.size() != n && p->c.size() != 1) return;
        for (size_t k = 0; k < n; ++k) hullv[k] = hull(hullv[k], comp(*p, k));
        norm = std::max(norm, p->norm);
    }
    if (multiplicity != 1 || scale.lo != 1 || scale.hi != 1) {  // m·hull/c (with_zero: the hull holds 0)
        for (size_t k = 0; k < n; ++k) hullv[k] = div(mul(Interval{double(multiplicity), double(multiplicity)}, hullv[k]), scale);
        norm = multiplicity * norm / scale.lo;
    }
    for (size_t k = 0; k < n; ++k) x.c[k] = {std::max(x.c[k].lo, hullv[k].lo), std::min(x.c[k].hi, hullv[k].hi)};
    x.norm = std::min(x.norm, norm);
    for (size_t k = 0; k < n; ++k)
        if (!(x.c[k].lo <= x.c[k].hi)) x.c[k] = hullv[k];  // (rounding: never empty)
}

// convex_bounds on the parts' cofactors, where every part but zeros has a factor with the same powers: x's factor.
void convex_factor(IntervalScratch& scratch, Bounds& x, const Type& t, const std::vector<const Bounds*>& parts, bool with_zero,
                   const std::vector<Bounds>& r) {
    const Powers* p = nullptr;
    std::vector<const Bounds*> cos;
    for (const Bounds* b : parts) {
        if (!b->factor || (p && *p != b->factor->powers)) return;
        p = &b->factor->powers;
        cos.push_back(&b->factor->co);
    }
    if (!p) return;
    Bounds co = unknown(t);
    convex_bounds(co, cos, with_zero);
    settle(scratch, x, *p, std::move(co), r);
}

// Tightens r[i] where instruction i is a convex combination, or a shift plus one (ConvexForm).
// A two-term log-sum-exp's derivative in its stable form, max(x, y) + log(1 + e^(-|x − y|)):
// (x ≥ y ? A : B) + (1/(1 + E))·(E·(−sign(x − y)·(A − B))), E = e^(...) ≥ 0 — (1 − λ)A + λB where x ≥ y and
// (1 − λ)B + λA elsewhere, λ = E/(1 + E) ∈ [0, 1): within the hull of A and B (A, B: ∇x, ∇y). Two nested smooth
// minima derived K ≤ 3 where it is 1 (a trial's, stop 52). The arms, or nothing.
std::optional<std::pair<ValueId, ValueId>> two_term_lse(const Function& f, const std::vector<Bounds>& r, ValueId s, ValueId t) {
    auto is = [&](ValueId v, Op op) { return f.body[v].op == op && !f.body[v].args.empty(); };
    auto builtin_is = [&](ValueId v, std::string_view name) {
        return f.body[v].op == Op::Builtin && builtin(f.body[v].aux).name == name && f.body[v].args.size() == 1;
    };
    const Instr& si = f.body[s];
    if (si.op != Op::Select || si.args.size() != 3) return std::nullopt;
    const Instr& ci = f.body[si.args[0]];
    if (ci.op != Op::Compare || CompareKind(ci.aux) != CompareKind::Ge || ci.args.size() != 2) return std::nullopt;
    const ValueId A = si.args[1], B = si.args[2], x = ci.args[0], y = ci.args[1];
    // t = (1/(1 + E))·u (either order), u = E·v (either order)
    const Instr& ti = f.body[t];
    if (ti.op != Op::Mul || ti.args.size() != 2) return std::nullopt;
    for (int k = 0; k < 2; ++k) {
        const ValueId q = ti.args[size_t(k)], u = ti.args[size_t(1 - k)];
        if (!is(q, Op::Div) || !is_const(f, f.body[q].args[0], 1) || !is(f.body[q].args[1], Op::Add)) continue;
        const Instr& den = f.body[f.body[q].args[1]];
        ValueId E = ValueId(-1);
        for (int j = 0; j < 2; ++j)
            if (is_const(f, den.args[size_t(j)], 1)) E = den.args[size_t(1 - j)];
        if (E == ValueId(-1) || !(r[E].c.size() == 1 && r[E].c[0].lo >= 0) || !is(u, Op::Mul)) continue;
        const Instr& ui = f.body[u];
        ValueId v = ValueId(-1);
        for (int j = 0; j < 2; ++j)
            if (ui.args[size_t(j)] == E) v = ui.args[size_t(1 - j)];
        // v = −(sign(x − y)·(A − B))
        if (v == ValueId(-1) || !is(v, Op::Neg) || !is(f.body[v].args[0], Op::Mul)) continue;
        const Instr& mi = f.body[f.body[v].args[0]];
        for (int j = 0; j < 2; ++j) {
            const ValueId sg = mi.args[size_t(j)], diff = mi.args[size_t(1 - j)];
            if (!builtin_is(sg, "sign") || !is(f.body[sg].args[0], Op::Sub) || !is(diff, Op::Sub)) continue;
            const Instr& d = f.body[f.body[sg].args[0]];
            const Instr& ab = f.body[diff];
            if (d.args[0] == x && d.args[1] == y && ab.args[0] == A && ab.args[1] == B) return std::make_pair(A, B);
        }
    }
    return std::nullopt;
}

void convex_refine(IntervalScratch& scratch, const Function& f, std::vector<Bounds>& r, const LoopConvexMap& loops, size_t i) {
    const Instr& in = f.body[i];
    if (in.op == Op::Add && in.args.size() == 2) {
        for (int k = 0; k < 2; ++k)
            if (auto arms = two_term_lse(f, r, in.args[size_t(k)], in.args[size_t(1 - k)])) {
                const std::vector<const Bounds*> parts = {&r[arms->first], &r[arms->second]};
                convex_bounds(r[i], parts, false);
                convex_factor(scratch, r[i], in.type, parts, false, r);
                return;
            }
        for (int k = 0; k < 2; ++k) {
            const ValueId c = in.args[size_t(k)], xv = in.args[size_t(1 - k)];
            const Instr& xi = f.body[xv];
            if (xi.op != Op::Div && xi.op != Op::Mul && xi.op != Op::Add) continue;
            auto form = convex_form(f, r, loops, xv);
            if (!form || form->shift != c || form->v.size() != form->w.size()) continue;
            std::vector<const Bounds*> parts = {&r[c]};
            parts.insert(parts.end(), form->v.begin(), form->v.end());
            convex_bounds(r[i], parts, false);
            convex_factor(scratch, r[i], in.type, parts, false, r);
            return;
        }
    }
    if (in.op != Op::Div && in.op != Op::Mul && in.op != Op::Add) return;
    if (auto form = convex_form(f, r, loops, ValueId(i))) {
        convex_bounds(r[i], form->w, true, form->multiplicity, form->scale);
        if (form->multiplicity == 1 && form->scale.lo == 1 && form->scale.hi == 1) convex_factor(scratch, r[i], in.type, form->w, true, r);
    }
}

// Univariate refinement ------------------------------------------------------------------------------------------
// The dependency problem: interval arithmetic takes each operand's interval as independent of the others', so a value
// that reads one varying component more than once is bounded loosely. Value noise's weight u = f²(3 − 2f) of
// f = fract(x) ∈ [0, 1] was [0, 1]·[0, 1]·[1, 3] = [0, 3], its derivative 2f(3 − 2f) − 2f² [-2, 6] where it is
// [0, 1.5]: a displacement by value noise derived K 51.6 where its slope is at most 2.1 (a new user's trial76, N1: a
// terrain's rays stopped short at the step cap). A component that depends on one periodic value alone (its source:
// f's component; sin of a hash) and reads it more than once is bounded where it leaves that
// dependence (its value read by something that depends on more) by evaluating its cone — the instructions between
// the source and it, one component each — on pieces of the source's interval: the hull over the pieces encloses it
// (every point of the box puts the source in some piece, and the cone reads nothing else that varies), and is
// intersected with the plain bound. 8 equal pieces, then 8 bisections of the piece with the highest (or lowest)
// end: an extremum inside the interval, as u′'s at f = ½, is found to within ~1/64 of the interval.
constexpr size_t kMaxConeSteps = 40;  // a longer cone is not refined (its bound stays the plain one)
constexpr int kEqualPieces = 8, kBisections = 8;
constexpr int64_t kConstSource = -1;
int64_t component_id(ValueId v, size_t k) { return (int64_t(v) << 20) | int64_t(k); }
ValueId id_value(int64_t id) { return ValueId(id >> 20); }
size_t id_component(int64_t id) { return size_t(id & ((1 << 20) - 1)); }

struct ConeOperand {
    int32_t step;  // ≥ 0: an earlier step's value; -1: the piece of the source; -2: component `comp` of value `v` (constant)
    ValueId v;
    uint32_t comp;
};
struct ConeStep {
    Instr scalar;  // the instruction, one component of it (a Builtin's id, a scalar type)
    std::array<ConeOperand, 3> operands;
    uint8_t count = 0;
};
struct Refinement {
    uint32_t comp;         // the component of the instruction refined
    ValueId source;        // the source: component `source_comp` of value `source`
    uint32_t source_comp;
    std::vector<ConeStep> steps;  // the cone, in order (the last is the refined component)
};
}  // namespace

struct UnivariatePlan {
    std::vector<std::vector<Refinement>> at;  // per instruction (empty: nothing to refine; most)
    bool any = false;
};

namespace {

// Whether instruction `in` is evaluated component by component (each result component k reads component k of each
// operand, or component 0 of a scalar operand): sums, elementwise products, scalar multiples, elementwise built-ins.
bool elementwise(const Function& f, const Instr& in) {
    const Type::Kind kind = in.type.kind;
    if (kind != Type::Scalar && kind != Type::Vector && kind != Type::Matrix) return false;
    const size_t n = size_t(in.type.components());
    for (ValueId a : in.args) {
        const Type& t = f.body[a].type;
        if (t.kind != Type::Scalar && t.kind != Type::Vector && t.kind != Type::Matrix) return false;
        if (size_t(t.components()) != n && t.components() != 1) return false;
    }
    switch (in.op) {
        case Op::Add:
        case Op::Sub:
        case Op::Hadamard:
        case Op::Neg:
        case Op::Div:
        case Op::Copy: return true;
        case Op::Mul:
            return in.args.size() == 2 && (f.body[in.args[0]].type.components() == 1 || f.body[in.args[1]].type.components() == 1);
        case Op::Builtin:
            switch (builtin_kind(in.aux)) {
                case B::other:
                case B::length:
                case B::normalize: return false;
                default: return in.args.size() <= 3;
            }
        default: return false;
    }
}

// The operand component (value, component) that component k of instruction `in` reads through operand j, where the
// instruction moves components (Extract, Row, Column, Construct) or works component by component; false otherwise.
bool operand_component(const Function& f, const Instr& in, size_t k, size_t j, ValueId& v, size_t& c) {
    const size_t n = size_t(std::max(1, in.type.components()));
    switch (in.op) {
        case Op::Extract:
            if (j != 0) return false;
            v = in.args[0], c = size_t(in.aux);
            return c < size_t(f.body[v].type.components());
        case Op::Row: {
            const Type& t = f.body[in.args[0]].type;
            if (j != 0 || !t.is_matrix()) return false;
            v = in.args[0], c = size_t(in.aux) * size_t(t.cols) + k;
            return true;
        }
        case Op::Column: {
            const Type& t = f.body[in.args[0]].type;
            if (j != 0 || !t.is_matrix()) return false;
            v = in.args[0], c = k * size_t(t.cols) + size_t(in.aux);
            return true;
        }
        case Op::Construct: {
            size_t total = 0;
            for (ValueId a : in.args) {
                const Type& t = f.body[a].type;
                if (t.kind != Type::Scalar && t.kind != Type::Vector && t.kind != Type::Matrix) return false;
                total += size_t(t.components());
            }
            if (in.args.size() == 1 && total == 1) {  // a broadcast scalar
                v = in.args[0], c = 0;
                return j == 0;
            }
            if (total != n) return false;
            size_t start = 0;
            for (size_t a = 0; a < in.args.size(); ++a) {
                const size_t m = size_t(f.body[in.args[a]].type.components());
                if (k < start + m) {
                    if (a != j) return false;
                    v = in.args[a], c = k - start;
                    return true;
                }
                start += m;
            }
            return false;
        }
        default:
            if (!elementwise(f, in) || j >= in.args.size()) return false;
            v = in.args[j], c = f.body[v].type.components() == 1 ? 0 : k;
            return true;
    }
}

// Which operands component k of `in` reads (Construct, Extract, Row and Column read one; the others all).
size_t operand_count(const Instr& in) {
    return in.op == Op::Extract || in.op == Op::Row || in.op == Op::Column ? 1 : in.args.size();
}

// The plan of `f`'s refinements. Per component: its leaf (kConstSource, or the component of which it is a function
// alone: a Param's, or a value that reads more than one leaf), its immediate dominator on the way to the leaf (every
// path from it down to the leaf passes there: for a read of one operand, that operand; for reads of several, their
// nearest common dominator) and whether it reads a component more than once (a merge). An exit (a component read by
// something of another leaf, or the result) below which a merge lies is refined over the dominator of its first merge
// (the first below it on its chain of single reads): value noise's u = f·f·(3 − 2f) over f = fract(x), not over x,
// whose interval spans many lattice cells. Only periodic values are sources (see `periodic` below).
UnivariatePlan univariate_plan(const Function& f) {
    UnivariatePlan plan;
    const size_t n = f.body.size();
    std::vector<size_t> offset(n + 1, 0);
    for (size_t i = 0; i < n; ++i) offset[i + 1] = offset[i] + size_t(std::max(1, f.body[i].type.components()));
    const size_t total = offset[n];
    std::vector<int64_t> leaf(total), idom(total, -1);
    std::vector<int32_t> depth(total, 0);
    std::vector<uint8_t> reads(total, 0);   // non-constant operand components read (2 at most counted)
    std::vector<char> repeated(total, 0);   // a merge at or below it, on its leaf's
    std::vector<char> traced(n, 0);
    std::vector<char> point(n, 0);  // whether the value reads the query point
    auto index = [&](int64_t id) { return offset[id_value(id)] + id_component(id); };
    // The nearest common dominator of two components of one leaf (-1 past 64 steps: then none is looked for).
    auto common = [&](int64_t x, int64_t y) -> int64_t {
        for (int steps = 0; x != y; ++steps) {
            if (steps > 64 || x < 0 || y < 0) return -1;
            if (depth[index(x)] >= depth[index(y)]) x = idom[index(x)];
            else y = idom[index(y)];
        }
        return x;
    };
    for (size_t i = 0; i < n; ++i) {
        const Instr& in = f.body[i];
        const size_t comps = offset[i + 1] - offset[i];
        // Constants, and whatever does not read the query point (parameter 0): a slider, time, a group member's
        // parameters from its table. They are read at their intervals in a cone (an enclosure whatever they are: the
        // source's pieces stand for every read of the source). A noise's frequency f in fract(f x) made f x a value of
        // two leaves: a terrain derived 9.6 where f was a slider in [0.49, 0.51], 2.96 where the literal 0.5, and a
        // group of 20 fbm balls, each its own frequency, 43 (trial77).
        bool varies = in.op == Op::Param && in.aux == 0;
        for (ValueId a : in.args) varies = varies || (a < n && point[a]);
        point[i] = varies;
        if (!varies) {
            for (size_t k = 0; k < comps; ++k) leaf[offset[i] + k] = kConstSource;
            traced[i] = 1;
            continue;
        }
        bool moves = in.op == Op::Extract || in.op == Op::Row || in.op == Op::Column || in.op == Op::Construct;
        traced[i] = (moves || elementwise(f, in)) && !in.args.empty();
        for (size_t k = 0; k < comps; ++k) {
            const size_t x = offset[i] + k;
            int64_t s = kConstSource, dom = -1;
            int count = 0, matched = 0;
            bool ok = traced[i], rep = false, single = true;
            size_t used = operand_count(in);
            for (size_t j = 0; ok && j < used; ++j) {
                ValueId v;
                size_t c;
                if (!operand_component(f, in, k, j, v, c)) {
                    if (in.op == Op::Construct) continue;  // (another operand's component)
                    ok = false;
                    break;
                }
                ++matched;
                const size_t y = offset[v] + c;
                if (leaf[y] == kConstSource) continue;
                if (s == kConstSource) s = leaf[y];
                else if (s != leaf[y]) single = false;
                const int64_t id = component_id(v, c);
                dom = count == 0 ? id : single ? common(dom, id) : -1;
                ++count;
                rep = rep || repeated[y];
            }
            if (ok && single && matched > 0 && (s == kConstSource || dom >= 0)) {
                leaf[x] = s;
                if (s != kConstSource) {
                    idom[x] = dom;
                    depth[x] = depth[index(dom)] + 1;
                    reads[x] = uint8_t(std::min(count, 2));
                    repeated[x] = rep || count >= 2;
                }
            } else {
                leaf[x] = component_id(ValueId(i), k);  // a leaf of its own
            }
        }
    }
    // Exits: components of one leaf, with a merge below, read by something of another leaf (or the result).
    std::vector<char> exit(total, 0);
    auto mark = [&](ValueId v, size_t c) {
        const size_t x = offset[v] + c;
        if (repeated[x] && leaf[x] != kConstSource && leaf[x] != component_id(v, c)) exit[x] = 1;
    };
    for (size_t i = 0; i < n; ++i) {
        const Instr& in = f.body[i];
        if (!traced[i]) {
            for (ValueId a : in.args)
                if (a < n)
                    for (size_t c = 0; c < offset[a + 1] - offset[a]; ++c) mark(a, c);
            continue;
        }
        for (size_t k = 0; k < offset[i + 1] - offset[i]; ++k) {
            size_t used = operand_count(in);
            for (size_t j = 0; j < used; ++j) {
                ValueId v;
                size_t c;
                if (operand_component(f, in, k, j, v, c) && leaf[offset[i] + k] != leaf[offset[v] + c]) mark(v, c);
            }
        }
    }
    if (f.result < n)
        for (size_t c = 0; c < offset[f.result + 1] - offset[f.result]; ++c) mark(f.result, c);
    for (const auto& [name, v] : f.outputs)
        if (v < n)
            for (size_t c = 0; c < offset[v + 1] - offset[v]; ++c) mark(v, c);
    // Whether a component is a periodic function's value (fract, mod, sin, cos; moved by Extract, Row, Column,
    // Construct or Copy): an interval that does not shrink with the box, where pieces of it are the only way to a
    // tighter bound (a source that follows the box, h of a blend, is bounded as well by smaller boxes: refining it
    // too took a slider blend's compile 0.39 → 0.93 s for the same K).
    auto periodic = [&](int64_t id) {
        for (int steps = 0; id >= 0 && steps < 16; ++steps) {
            const ValueId v = id_value(id);
            const size_t c = id_component(id);
            const Instr& in = f.body[v];
            if (in.op == Op::Builtin) {
                const B kind = builtin_kind(in.aux);
                return kind == B::fract || kind == B::mod || kind == B::sin || kind == B::cos;
            }
            if (in.op != Op::Extract && in.op != Op::Row && in.op != Op::Column && in.op != Op::Construct && in.op != Op::Copy)
                return false;
            ValueId a = 0;
            size_t ac = 0;
            bool found = false;
            for (size_t j = 0; j < in.args.size() && !found; ++j) found = operand_component(f, in, c, j, a, ac);
            if (!found) return false;
            id = component_id(a, ac);
        }
        return false;
    };
    // Each exit's source: the nearest periodic value that dominates its first merge (the first below it on its chain
    // of single reads).
    std::vector<int64_t> source_of(total, -1);
    for (size_t i = 0; i < n; ++i)
        for (size_t k = 0; k < offset[i + 1] - offset[i]; ++k) {
            const size_t x = offset[i] + k;
            if (!exit[x]) continue;
            int64_t at = component_id(ValueId(i), k);
            for (int steps = 0; at >= 0 && reads[index(at)] == 1 && steps < 64; ++steps) at = idom[index(at)];
            if (at < 0 || reads[index(at)] < 2) continue;
            int64_t s = idom[index(at)];
            for (int steps = 0; s >= 0 && !periodic(s) && steps < 64; ++steps) s = idom[index(s)];
            if (s >= 0 && periodic(s)) source_of[x] = s;
        }
    // Each exit's cone, depth first from it (operands before their users), down to its source.
    plan.at.resize(n);
    std::vector<int32_t> step_of(total, -1);
    std::vector<size_t> touched;
    for (size_t i = 0; i < n; ++i)
        for (size_t k = 0; k < offset[i + 1] - offset[i]; ++k) {
            const int64_t s = source_of[offset[i] + k];
            if (!exit[offset[i] + k] || s < 0) continue;
            const int64_t lf = leaf[offset[i] + k];
            Refinement ref;
            ref.comp = uint32_t(k);
            ref.source = id_value(s);
            ref.source_comp = uint32_t(id_component(s));
            bool fits = true;
            std::vector<std::pair<size_t, size_t>> stack = {{i, k}};
            while (!stack.empty() && fits) {
                auto [v, c] = stack.back();
                const size_t x = offset[v] + c;
                if (step_of[x] >= 0) {
                    stack.pop_back();
                    continue;
                }
                const Instr& in = f.body[v];
                bool ready = true;
                ConeStep step;
                step.scalar.op = in.op;
                step.scalar.aux = in.aux;
                step.scalar.type = Type::scalar();
                size_t used = operand_count(in);
                for (size_t j = 0; j < used; ++j) {
                    ValueId a;
                    size_t ac;
                    if (!operand_component(f, in, c, j, a, ac)) continue;
                    ConeOperand o{-2, a, uint32_t(ac)};
                    if (component_id(a, ac) == s) o.step = -1;
                    else if (leaf[offset[a] + ac] == lf && lf != kConstSource) {
                        if (step_of[offset[a] + ac] < 0) {
                            stack.push_back({a, ac});
                            ready = false;
                            continue;
                        }
                        o.step = step_of[offset[a] + ac];
                    }
                    if (step.count < 3) step.operands[step.count++] = o;
                    else fits = false;
                }
                if (!ready) continue;
                stack.pop_back();
                if (ref.steps.size() >= kMaxConeSteps) {
                    fits = false;
                    break;
                }
                step_of[x] = int32_t(ref.steps.size());
                touched.push_back(x);
                ref.steps.push_back(std::move(step));
            }
            for (size_t x : touched) step_of[x] = -1;
            touched.clear();
            if (fits && !ref.steps.empty()) {
                plan.at[i].push_back(std::move(ref));
                plan.any = true;
            }
        }
    return plan;
}

// One component of a cone step from its operands' intervals.
Interval cone_step(const ConeStep& s, const Interval* in) {
    switch (s.scalar.op) {
        case Op::Add: return s.count == 2 ? add(in[0], in[1]) : Interval{};
        case Op::Sub: return s.count == 2 ? add(in[0], neg(in[1])) : Interval{};
        case Op::Mul:
        case Op::Hadamard:
            if (s.count != 2) return {};
            return s.operands[0].step == s.operands[1].step && s.operands[0].step != -2 ? sqr(in[0]) : mul(in[0], in[1]);
        case Op::Div: return s.count == 2 ? div(in[0], in[1]) : Interval{};
        case Op::Neg: return s.count == 1 ? neg(in[0]) : Interval{};
        case Op::Copy:
        case Op::Extract:
        case Op::Row:
        case Op::Column:
        case Op::Construct: return s.count == 1 ? in[0] : Interval{};
        case Op::Builtin: {
            Bounds b[3];
            thread_local std::vector<const Bounds*> a;  // (builtin_bounds' operands: one buffer for every step)
            a.clear();
            for (size_t j = 0; j < s.count; ++j) {
                b[j].c = {in[j]};
                a.push_back(&b[j]);
            }
            Bounds x = builtin_bounds(s.scalar, a);
            return x.c.size() == 1 ? x.c[0] : Interval{};
        }
        default: return {};
    }
}

// The cone of `ref` over a piece of its source's interval.
Interval cone_over(const Refinement& ref, const std::vector<Bounds>& r, Interval piece, std::vector<Interval>& values) {
    values.resize(ref.steps.size());
    analysis_work() += kIntervalWork * ref.steps.size();  // (each step as an instruction of the analysis)
    for (size_t t = 0; t < ref.steps.size(); ++t) {
        const ConeStep& s = ref.steps[t];
        Interval in[3];
        for (size_t j = 0; j < s.count; ++j) {
            const ConeOperand& o = s.operands[j];
            // (a constant operand without that component's bounds, none the analysis keeps: unbounded)
            in[j] = o.step >= 0                                           ? values[size_t(o.step)]
                    : o.step == -1                                        ? piece
                    : r[o.v].c.size() == 1 || o.comp < r[o.v].c.size() ? comp(r[o.v], o.comp)
                                                                          : Interval{};
        }
        values[t] = cone_step(s, in);
    }
    return values.back();
}

// Refines instruction i's components by its plan (UnivariatePlan): each bound on pieces of its source, intersected.
void univariate_refine(const UnivariatePlan& plan, std::vector<Bounds>& r, size_t i) {
    Bounds& x = r[i];
    if (x.nan) return;  // (min and max of a NaN take the other operand: the cone's intervals would not say so)
    bool changed = false;
    std::vector<Interval> values;
    for (const Refinement& ref : plan.at[i]) {
        if (ref.comp >= x.c.size() || r[ref.source].nan || r[ref.source].c.empty()) continue;
        const Interval s = comp(r[ref.source], ref.source_comp);
        if (!(s.hi > s.lo) || !std::isfinite(s.lo) || !std::isfinite(s.hi)) continue;
        struct Piece {
            Interval s, v;
        };
        std::array<Piece, kEqualPieces + kBisections> pieces;
        size_t count = 0;
        Interval hull_of{kInf, -kInf};
        bool bounded = true;
        for (int p = 0; p < kEqualPieces && bounded; ++p) {
            Interval part{s.lo + (s.hi - s.lo) * p / kEqualPieces, p + 1 == kEqualPieces ? s.hi : s.lo + (s.hi - s.lo) * (p + 1) / kEqualPieces};
            Interval v = cone_over(ref, r, part, values);
            bounded = !std::isnan(v.lo) && !std::isnan(v.hi) && std::isfinite(v.lo) && std::isfinite(v.hi);
            pieces[count++] = {part, v};
        }
        if (!bounded) continue;
        for (int b = 0; b < kBisections; ++b) {
            // the piece holding the highest end (even steps) or the lowest (odd): halved, the half that holds it
            // replaced and the other added
            size_t w = 0;
            for (size_t p = 1; p < count; ++p)
                if (b % 2 == 0 ? pieces[p].v.hi > pieces[w].v.hi : pieces[p].v.lo < pieces[w].v.lo) w = p;
            const Interval part = pieces[w].s;
            const double mid = 0.5 * (part.lo + part.hi);
            if (!(mid > part.lo && mid < part.hi) || count >= pieces.size()) break;
            Interval left{part.lo, mid}, right{mid, part.hi};
            Interval vl = cone_over(ref, r, left, values), vr = cone_over(ref, r, right, values);
            if (!std::isfinite(vl.lo) || !std::isfinite(vl.hi) || !std::isfinite(vr.lo) || !std::isfinite(vr.hi)) break;
            pieces[w] = {left, vl};
            pieces[count++] = {right, vr};
        }
        for (size_t p = 0; p < count; ++p) hull_of = hull(hull_of, pieces[p].v);
        Interval& c = x.c[ref.comp];
        const Interval both{std::max(c.lo, hull_of.lo), std::min(c.hi, hull_of.hi)};
        if (both.lo <= both.hi && (both.lo > c.lo || both.hi < c.hi)) {
            c = both;
            changed = true;
        }
    }
    if (changed) x = finish(std::move(x));
}

template <class Params>
void analyse(std::vector<Bounds>& r, IntervalScratch& scratch, const Module& m, const Function& f, const Params& params,
             const IntervalHook& hook, int loop_trips, long* work) {
    r.resize(f.body.size());
    if (scratch.depth == 0) scratch.factors_used = 0;  // (a new analysis: the last one's factors are not read again)
    std::map<size_t, std::vector<Bounds>> loop_states;  // a Loop's final states (read by Member)
    LoopConvexMap loop_convex;                            // a Loop's convex numerators (LoopConvex)
    auto [marked, fresh] = scratch.marks.try_emplace({&f, f.body.size()});
    if (fresh) marked->second = value_marks(f);
    const std::vector<char>& marks = marked->second;
    auto [planned, unplanned] = scratch.univariate.try_emplace({&f, f.body.size()});
    if (unplanned) planned->second = std::make_shared<const UnivariatePlan>(univariate_plan(f));
    const UnivariatePlan& plan = *planned->second;
    // Whether a value may have a factor: a symbol here, or one the caller passes (a loop body's Param).
    bool factors = marks.back() != 0;
    if (scratch.depth > 0 && static_cast<const void*>(&params) == scratch.args[scratch.depth - 1].get())
        for (char c : *scratch.symbols[scratch.depth - 1]) factors = factors || c;
    std::vector<const Bounds*> a;                        // an instruction's operands (one buffer for all)
    // A callee's (or loop body's) values, in the buffer of the next depth.
    auto call = [&](int fn, const std::vector<IntervalVec>& args) -> std::vector<Bounds>& {
        const size_t d = scratch.depth;
        struct Depth {
            size_t& depth;
            explicit Depth(size_t& d) : depth(d) { ++depth; }
            ~Depth() { --depth; }
        } deeper(scratch.depth);
        std::vector<Bounds>& values = *scratch.values[d];
        analyse(values, scratch, m, m.functions[size_t(fn)], args, {}, loop_trips, work);
        return values;
    };
    auto args_buffer = [&]() -> std::vector<IntervalVec>& {
        const size_t d = scratch.depth;
        while (scratch.values.size() <= d) {
            scratch.values.push_back(std::make_unique<std::vector<Bounds>>());
            scratch.args.push_back(std::make_unique<std::vector<IntervalVec>>());
            scratch.elements.push_back(std::make_unique<std::vector<const std::vector<double>*>>());
            scratch.symbols.push_back(std::make_unique<std::vector<char>>());
        }
        scratch.args[d]->clear();
        scratch.elements[d]->clear();
        scratch.symbols[d]->clear();
        return *scratch.args[d];
    };
    // An argument's known array elements (Bounds::elements), and whether it is a symbol of Bounds::factor (a loop
    // body's Param then is one, its factors mapped back by the Loop rule), at the position of its intervals in
    // args_buffer().
    auto pass_elements = [&](const Bounds& b, bool symbol = false) {
        std::vector<const std::vector<double>*>& e = *scratch.elements[scratch.depth];
        std::vector<char>& sy = *scratch.symbols[scratch.depth];
        e.resize(scratch.args[scratch.depth]->size(), nullptr);
        sy.resize(scratch.args[scratch.depth]->size(), 0);
        if (!e.empty()) e.back() = b.elements;
        if (!sy.empty()) sy.back() = symbol ? 1 : 0;
    };
    for (size_t i = 0; i < f.body.size(); ++i) {
        if (i > 0 && hook && !hook(i - 1, r)) {
            for (size_t j = i; j < f.body.size(); ++j) r[j] = Bounds{};  // not analysed (the buffer may hold old values)
            return;
        }
        const Instr& in = f.body[i];
        analysis_work() += kIntervalWork;
        if (work && --*work < 0) {  // the budget is spent: this value and the rest are unbounded
            for (size_t j = i; j < f.body.size(); ++j) {
                r[j] = f.body[j].op == Op::Loop ? Bounds{} : unknown(f.body[j].type);
                r[j].nan = true;  // anything
            }
            return;
        }
        if (in.op == Op::Param) {
            // (an array's bounds are its elements' hull: per component of one element, as a Global's)
            // An array comes as every element's components (a Construct's) or as one element's, their hull (a
            // Global's): arrays passed on by a call were unknown in the second form.
            const bool one_element = in.type.is_array() && size_t(in.aux) < params.size() &&
                                     params[size_t(in.aux)].size() != size_t(std::max(1, in.type.components()));
            r[i] = unknown(one_element ? in.type.element() : in.type);
            if (size_t(in.aux) < params.size() && params[size_t(in.aux)].size() == r[i].c.size()) {
                const auto& p = params[size_t(in.aux)];
                for (size_t k = 0; k < p.size(); ++k) r[i].c[k] = p[k];
            }
            r[i] = finish(std::move(r[i]));
            // A callee's (or loop body's) argument: an array's known values come with it.
            if (scratch.depth > 0 && static_cast<const void*>(&params) == scratch.args[scratch.depth - 1].get()) {
                const auto& known = *scratch.elements[scratch.depth - 1];
                if (in.type.is_array() && size_t(in.aux) < known.size()) r[i].elements = known[size_t(in.aux)];
                const auto& symbol = *scratch.symbols[scratch.depth - 1];
                if (size_t(in.aux) < symbol.size() && symbol[size_t(in.aux)] && r[i].c.size() == 1)
                    r[i].factor = new_factor(scratch, {{ValueId(i), 1}}, one_bounds());
            }
            continue;
        }
        if (in.op == Op::Global) {
            const Global& g = m.globals[size_t(in.aux)];
            Type e = g.type.is_array() ? g.type.element() : g.type;
            Bounds b = unknown(e);
            size_t n = b.c.size();
            const bool fixed = g.kind == Global::Kind::Constant || (g.kind == Global::Kind::Parameter && m.constant_parameters);
            if (g.kind != Global::Kind::Prepared) {
                bool slider = g.kind == Global::Kind::Parameter && !m.constant_parameters;
                // A group's per-member parameters (an array) are their values' hull where parameters are constants
                // (four blobs in a group, each with its own amplitude, had no bound at all: a trial's, stop 39), and
                // their sliders' hull elsewhere.
                if (slider && !g.bounds.lo.empty() && g.bounds.lo.size() % n == 0 && g.bounds.hi.size() == g.bounds.lo.size()) {
                    for (size_t k = 0; k < n; ++k) b.c[k] = {kInf, -kInf};
                    for (size_t j = 0; j < g.bounds.lo.size(); ++j) b.c[j % n] = hull(b.c[j % n], {g.bounds.lo[j], g.bounds.hi[j]});
                } else if (fixed && !g.value.empty() && g.value.size() % n == 0) {
                    for (size_t k = 0; k < n; ++k) b.c[k] = {kInf, -kInf};
                    for (size_t j = 0; j < g.value.size(); ++j) b.c[j % n] = hull(b.c[j % n], {g.value[j], g.value[j]});
                } else if (!g.value.empty() && !g.type.is_array()) {  // a parameter without bounds: its value
                    for (size_t k = 0; k < n; ++k) b.c[k] = {g.value[k], g.value[k]};
                }
            }
            if (!g.type.is_array()) b = finish(std::move(b));
            else {
                // An element's norm: the largest over the elements (constants), else from the components.
                double worst = 0;
                if (fixed)
                    for (size_t e0 = 0; e0 + n <= g.value.size(); e0 += n) {
                        double s = 0;
                        for (size_t k = 0; k < n; ++k) s += g.value[e0 + k] * g.value[e0 + k];
                        worst = std::max(worst, std::sqrt(s));
                    }
                b = finish(std::move(b));
                if (fixed) b.norm = std::min(b.norm, worst);
                if (fixed && g.kind != Global::Kind::Prepared && !g.value.empty() && g.value.size() % n == 0) b.elements = &g.value;
            }
            r[i] = std::move(b);
            continue;
        }
        if (in.op == Op::Call) {
            std::vector<IntervalVec>& args = args_buffer();
            bool nan = false;  // (the callee sees intervals only: an argument that may be NaN makes its result so)
            for (ValueId x : in.args) {
                args.push_back(r[x].c);
                pass_elements(r[x]);
                nan |= r[x].nan;
                // A function the backend keeps receives its real arguments in float: a constant 10000000.49
                // as 10000000 (the hull holds both, and what a building block inlined and folded in double sees).
                const Type& t = f.body[x].type;
                if (t.kind != Type::Integer && t.elem != Type::Integer)
                    for (Interval& c : args.back()) {
                        const double lo = double(float(c.lo)), hi = double(float(c.hi));
                        if (lo < c.lo) c.lo = lo;
                        if (hi > c.hi) c.hi = hi;
                    }
            }
            r[i] = call(in.aux, args)[m.functions[size_t(in.aux)].result];
            r[i].nan |= nan;
            r[i].factor = nullptr;  // (the callee's symbols)
            continue;
        }
        if (in.op == Op::Loop) {
            // The body once per iteration, on the states' bounds so far: k = lo..hi for a constant hi.
            const Function& body = m.functions[size_t(in.aux)];
            size_t states = body.outputs.size();
            std::vector<Bounds> s;
            const Interval hi = r[in.args[0]].c.empty() ? Interval{} : r[in.args[0]].c[0];
            double first = in.data.empty() ? 0 : in.data[0];
            double last = std::floor(hi.lo + 0.5);
            // A loop reading an array whose values are known (a constant-weighted ∑_i w_i t_i over 300 weights)
            // runs too, where that is cheap: each iteration reads its own element, where one analysis of the body
            // over every index reads their hull (∑_i w_i t_i/∑_j w_j: K ≤ 11 where it is 1).
            // A loop whose every argument is a point or a known array (∑_j w_j: nothing of the box) is run once
            // per search (IntervalScratch::known_loops) and may be larger.
            bool reads_known = false, fixed = true;
            for (size_t c = states + 1; c < in.args.size(); ++c) reads_known |= r[in.args[c]].elements != nullptr;
            for (size_t c = 1; c < in.args.size(); ++c) {
                const Bounds& b = r[in.args[c]];
                if (b.elements || b.nan) continue;
                for (const Interval& v : b.c) fixed = fixed && v.lo == v.hi;
            }
            const double trips = last - first + 1;
            const double work_allowed = fixed ? kKnownLoopWork * 16 : kKnownLoopWork;
            const int limit = std::max(loop_trips, reads_known && double(body.body.size()) * trips <= work_allowed ? int(trips) : 0);
            bool run = limit > 0 && hi.lo == hi.hi && std::isfinite(hi.lo) && trips <= limit && in.args.size() >= states + 1;
            std::vector<uint64_t> key;
            if (run && reads_known) {
                key = {uint64_t(reinterpret_cast<uintptr_t>(&m)), uint64_t(in.aux), std::bit_cast<uint64_t>(first),
                       std::bit_cast<uint64_t>(last)};
                for (size_t c = 1; c < in.args.size(); ++c) {
                    const Bounds& b = r[in.args[c]];
                    key.push_back(uint64_t(reinterpret_cast<uintptr_t>(b.elements)) * 2 + (b.nan ? 1 : 0));
                    for (const Interval& v : b.c) key.insert(key.end(), {std::bit_cast<uint64_t>(v.lo), std::bit_cast<uint64_t>(v.hi)});
                }
                auto known = scratch.known_loops.find(key);
                if (known != scratch.known_loops.end()) {
                    loop_states[i] = known->second;
                    r[i] = Bounds{};
                    continue;
                }
            }
            for (size_t j = 0; j < states; ++j) s.push_back(run ? r[in.args[j + 1]] : unknown(body.body[body.outputs[j].second].type));
            // NaN in a state or an argument, or made by the body in any iteration, may reach every state.
            bool nan = !run;
            for (size_t c = 1; c < in.args.size(); ++c) nan |= r[in.args[c]].nan;
            for (double k = first; run && k <= last; k += 1) {
                std::vector<IntervalVec>& args = args_buffer();
                args.push_back({{k, k}});
                for (size_t j = 0; j < states; ++j) args.push_back(s[j].c);
                for (size_t c = states + 1; c < in.args.size(); ++c) {
                    args.push_back(r[in.args[c]].c);
                    pass_elements(r[in.args[c]]);
                }
                const std::vector<Bounds>& v = call(in.aux, args);
                for (size_t j = 0; j < states; ++j) {
                    s[j] = v[body.outputs[j].second];
                    nan |= s[j].nan;
                }
            }
            if (!run && hi.lo == hi.hi && std::isfinite(hi.lo) && last >= first && in.args.size() >= states + 1) {
                // An accumulation (a rolled ∑: each state s_j ← s_j + t_j, no t_j reading a state): t_j once,
                // with k over [first, last], and s_j = s_j(0) + n·t_j for the n iterations (sound: each term
                // lies in t_j's bounds, whatever k).
                // A state that keeps one of itself and a term (a rolled max and its derivative: selected_term) ends
                // within the hull of its first value and the term's bounds.
                std::vector<ValueId> term(states, ValueId(-1));
                std::vector<char> selected(states, 0);
                bool accumulates = true;
                for (size_t j = 0; j < states && accumulates; ++j) {
                    auto t = accumulated_term(body, j);
                    if (!t) {
                        t = selected_term(body, j);
                        selected[j] = t.has_value();
                    }
                    accumulates = t.has_value();
                    if (t) term[j] = *t;
                }
                if (accumulates) {
                    std::vector<IntervalVec>& args = args_buffer();
                    args.push_back({{first, last}});
                    for (size_t j = 0; j < states; ++j) args.push_back(r[in.args[j + 1]].c);
                    for (size_t c = states + 1; c < in.args.size(); ++c) {
                        args.push_back(r[in.args[c]].c);
                        // (a scalar that is no point and leaves out 0: a symbol in the body, whatever it is here — k,
                        // m² or 2k — and mapped back to this function's factors by caller_factor)
                        const Bounds& x = r[in.args[c]];
                        const bool symbol = x.c.size() == 1 && !x.nan && x.c[0].lo < x.c[0].hi && (x.c[0].lo > 0 || x.c[0].hi < 0) &&
                                            std::isfinite(x.c[0].lo) && std::isfinite(x.c[0].hi) && f.body[in.args[c]].type.is_scalar();
                        pass_elements(x, symbol);
                    }
                    const std::vector<Bounds>& v = call(in.aux, args);
                    const double n = last - first + 1;
                    // A body value's factor in this function's symbols (the values the loop captures), into out.
                    // A body value's factor in this function's symbols, into (out, co): each captured symbol is the
                    // value captured, which may have a factor of its own here (m² for k: m's square times its cofactor).
                    auto caller_factor = [&](const Bounds& b, Powers& out, Bounds& co) {
                        out.clear();
                        if (!b.factor) return false;
                        co = b.factor->co;
                        for (const auto& [id, power] : b.factor->powers) {
                            const Instr& pi = body.body[id];
                            if (pi.op != Op::Param || size_t(pi.aux) <= states || size_t(pi.aux) >= in.args.size()) return false;
                            const ValueId x = in.args[size_t(pi.aux)];
                            const FactorView view = factor_view(f, r, marks, x);
                            Powers own = {{x, 1}};
                            const Powers& px = view.get().empty() || view.symbol ? own : view.get();
                            const Interval cx = view.get().empty() || view.symbol ? Interval{1, 1} : comp(*view.co, 0);
                            for (int q = 0; q < std::abs(power); ++q) {
                                Powers next;
                                if (!combine(out, px, power > 0 ? 1 : -1, next)) return false;
                                out = std::move(next);
                                for (Interval& c : co.c) c = power > 0 ? mul(c, cx) : div(c, cx);
                                co.norm = power > 0 ? co.norm * magnitude(cx)
                                                    : (contains_zero(cx) ? kInf : co.norm / std::min(std::fabs(cx.lo), std::fabs(cx.hi)));
                            }
                        }
                        return true;
                    };
                    // A state's factor: its first value's (or 0) and the term's, with the term's powers; the cofactor
                    // init + n·t (an accumulation) or the hull of both (a choice).
                    auto state_factor = [&](Bounds& sj, const Bounds& init, const Bounds& t, bool chosen) {
                        Powers p;
                        Bounds co;
                        if (!caller_factor(t, p, co)) return;
                        const Bounds* init_co = init.factor && init.factor->powers == p ? &init.factor->co : nullptr;
                        if (!init_co && !is_zero(init)) return;
                        for (size_t q = 0; q < co.c.size(); ++q) {
                            const Interval i0 = init_co ? comp(*init_co, q) : Interval{0, 0};
                            co.c[q] = chosen ? hull(i0, co.c[q]) : Interval{i0.lo + n * co.c[q].lo, i0.hi + n * co.c[q].hi};
                            if (std::isnan(co.c[q].lo) || std::isnan(co.c[q].hi)) return;
                        }
                        const double n0 = init_co ? init_co->norm : 0.0;
                        co.norm = chosen ? std::max(n0, co.norm) : n0 + n * co.norm;
                        co.unit = false;
                        settle(scratch, sj, std::move(p), std::move(co), r);
                    };
                    // A LoopConvex part's factor, in this function's symbols.
                    auto part_factor = [&](Bounds& b) {
                        Powers p;
                        Bounds co;
                        if (!caller_factor(b, p, co)) b.factor = nullptr;
                        else if (p.empty()) b.factor = nullptr;  // (cancelled: the intervals stand)
                        else b.factor = new_factor(scratch, std::move(p), std::move(co));
                    };
                    nan = false;
                    for (size_t c = 1; c < in.args.size(); ++c) nan |= r[in.args[c]].nan;
                    for (size_t j = 0; j < states; ++j) {
                        const Bounds& init = r[in.args[j + 1]];
                        const Bounds& t = v[term[j]];
                        if (init.c.size() != t.c.size()) continue;  // (s stays unknown)
                        if (selected[j]) {
                            s[j] = init;
                            s[j].elements = nullptr;
                            s[j].unit = init.unit && t.unit;
                            s[j].norm = std::max(init.norm, t.norm);
                            for (size_t q = 0; q < t.c.size(); ++q) s[j].c[q] = hull(init.c[q], t.c[q]);
                            s[j] = finish(std::move(s[j]));
                            s[j].factor = nullptr;
                            state_factor(s[j], init, t, true);
                            nan |= t.nan;
                            continue;
                        }
                        s[j] = init;
                        s[j].unit = false;
                        s[j].norm = init.norm + n * t.norm;  // ‖s + Σ t‖ ≤ ‖s‖ + n·max ‖t‖
                        for (size_t q = 0; q < t.c.size(); ++q) {
                            s[j].c[q].lo = init.c[q].lo + n * t.c[q].lo;
                            s[j].c[q].hi = init.c[q].hi + n * t.c[q].hi;
                            if (std::isnan(s[j].c[q].lo) || std::isnan(s[j].c[q].hi)) s[j].c[q] = Interval{};
                        }
                        s[j] = finish(std::move(s[j]));
                        s[j].factor = nullptr;
                        state_factor(s[j], init, t, false);
                        nan |= t.nan;
                    }
                    // Convex numerators: state j accumulates a·w where state k accumulates a ≥ 0 (LoopConvex).
                    std::vector<LoopConvex> found;
                    // (the factors of a product taken apart, scalars commuting: a weighted term's derivative is
                    // w·(e·g) where its term is e·w, a·g once reassociated; a trial's weighted log-sum-exp of 32
                    // points had no bound, K ≤ ∞, where 31 unrolled got 1)
                    auto factors = [&](ValueId x, std::vector<ValueId>& out) {
                        std::vector<ValueId> todo = {x};
                        while (!todo.empty() && out.size() < 8) {
                            const ValueId y = todo.back();
                            todo.pop_back();
                            const Instr& yi = body.body[y];
                            if (yi.op == Op::Mul && yi.args.size() == 2 &&
                                (body.body[yi.args[0]].type.is_scalar() || body.body[yi.args[1]].type.is_scalar())) {
                                todo.push_back(yi.args[0]);
                                todo.push_back(yi.args[1]);
                            } else {
                                out.push_back(y);
                            }
                        }
                        std::sort(out.begin(), out.end());
                        return todo.empty();
                    };
                    for (size_t j = 0; j < states; ++j) {
                        if (selected[j]) continue;
                        const Instr& tj = body.body[term[j]];
                        const Bounds& init_j = r[in.args[j + 1]];
                        if (tj.op != Op::Mul || tj.args.size() != 2 || !is_zero(init_j)) continue;
                        std::vector<ValueId> fj;
                        if (!factors(term[j], fj)) continue;
                        for (size_t k = 0; k < states; ++k) {
                            if (k == j || selected[k]) continue;
                            const ValueId a = term[k];
                            const Bounds& init_k = r[in.args[k + 1]];
                            if (v[a].c.size() != 1 || !(v[a].c[0].lo >= 0) || init_k.c.size() != 1 || !(init_k.c[0].lo >= 0)) continue;
                            // term j = a·w: a one of its operands, or a's factors and one more among its factors
                            ValueId rest = ValueId(-1);
                            for (int side = 0; side < 2 && rest == ValueId(-1); ++side)
                                if (tj.args[size_t(side)] == a) rest = tj.args[size_t(1 - side)];
                            if (rest == ValueId(-1)) {
                                std::vector<ValueId> fk, left;
                                if (!factors(a, fk) || fk.size() + 1 != fj.size()) continue;
                                std::set_difference(fj.begin(), fj.end(), fk.begin(), fk.end(), std::back_inserter(left));
                                if (left.size() != 1) continue;
                                rest = left[0];
                            }
                            {
                                LoopConvex lc;
                                lc.j = int(j), lc.k = int(k);
                                const ValueId w = rest;
                                lc.w = v[w];
                                part_factor(lc.w);
                                const Instr& wi = body.body[w];
                                if (wi.op == Op::Sub && wi.args.size() == 2) {
                                    const Instr& c = body.body[wi.args[1]];
                                    // (a captured value: a parameter after k and the states)
                                    if (c.op == Op::Param && size_t(c.aux) > states && size_t(c.aux) < in.args.size()) {
                                        lc.shift = in.args[size_t(c.aux)];
                                        lc.v = v[wi.args[0]];
                                        part_factor(lc.v);
                                    }
                                }
                                found.push_back(std::move(lc));
                            }
                        }
                    }
                    if (!found.empty()) loop_convex[i] = std::move(found);
                }
            }
            for (Bounds& b : s) {
                b.nan |= nan;
                if (run) b.factor = nullptr;  // (the body's symbols; the accumulation's are this function's)
            }
            if (!key.empty()) {
                if (scratch.known_loops.size() >= 256) scratch.known_loops.clear();
                scratch.known_loops.emplace(std::move(key), s);
            }
            loop_states[i] = std::move(s);
            r[i] = Bounds{};
            continue;
        }
        if (in.op == Op::Member) {
            auto it = loop_states.find(in.args[0]);
            if (it != loop_states.end() && size_t(in.aux) < it->second.size()) {
                r[i] = it->second[size_t(in.aux)];  // (a factor there is in this function's symbols)
            } else {
                r[i] = unknown(in.type);
                r[i].nan = true;
            }
            continue;
        }
        a.clear();
        for (ValueId x : in.args) a.push_back(&r[x]);
        r[i] = bounds_of(m, f, in, a);
        bool factored = false;  // (most values: no operand is a symbol or has a factor, and this is all they cost)
        if (factors)
            for (ValueId x : in.args)
                factored = factored || r[x].factor || ((marks[x] & kSymbol) && r[x].c.size() == 1 && r[x].c[0].lo < r[x].c[0].hi);
        if (factored) factor_refine(scratch, m, f, r, marks, i, a);
        if ((in.op == Op::Div || in.op == Op::Mul || in.op == Op::Add) && !in.type.is_matrix() && !(marks[i] & kSummed))
            convex_refine(scratch, f, r, loop_convex, i);
        if (plan.any && !plan.at[i].empty()) univariate_refine(plan, r, i);
    }
    if (!f.body.empty() && hook) hook(f.body.size() - 1, r);
}

}  // namespace

std::vector<Bounds> interval_analysis(const Module& m, int fn, const std::vector<std::vector<Interval>>& params,
                                      const IntervalHook& hook, int loop_trips, long* work) {
    return interval_analysis(m, m.functions[size_t(fn)], params, hook, loop_trips, work);
}

std::vector<Bounds> interval_analysis(const Module& m, const Function& f, const std::vector<std::vector<Interval>>& params,
                                      const IntervalHook& hook, int loop_trips, long* work) {
    std::vector<Bounds> r;
    IntervalScratch scratch;
    analyse(r, scratch, m, f, params, hook, loop_trips, work);
    return r;
}

void interval_analysis(IntervalScratch& scratch, std::vector<Bounds>& r, const Module& m, const Function& f,
                       const std::vector<std::vector<Interval>>& params, const IntervalHook& hook, int loop_trips, long* work) {
    scratch.depth = 0;
    analyse(r, scratch, m, f, params, hook, loop_trips, work);
}

}  // namespace iqc::ir
