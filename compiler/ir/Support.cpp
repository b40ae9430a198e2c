#include "ir/Support.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <queue>

namespace iqc::ir {

namespace {

struct Box {
    std::array<double, 3> lo, hi;
};

}  // namespace

std::optional<double> support_radius(const Module& m, int fn, int query, std::vector<std::vector<Interval>> params,
                                      double reach, int budget) {
    if (fn < 0 || size_t(fn) >= m.functions.size() || query < 0 || size_t(query) >= params.size()) return std::nullopt;
    const Function& f = m.functions[size_t(fn)];
    if (!f.body[f.result].type.is_scalar()) return std::nullopt;
    // The distance's lowest value over a box.
    auto lowest = [&](const Box& b) {
        params[size_t(query)] = {{b.lo[0], b.hi[0]}, {b.lo[1], b.hi[1]}, {b.lo[2], b.hi[2]}};
        std::vector<Bounds> v = interval_analysis(m, fn, params);
        const Bounds& r = v[f.result];
        double lo = r.c.empty() ? -INFINITY : r.c[0].lo;
        return std::isnan(lo) ? -INFINITY : lo;
    };
    // One pass: the boxes of `domain`, split `depth` times where they may hold the solid; false when one
    // touching the domain's boundary does (when `open`), or the budget runs out.
    auto pass = [&](const Box& domain, int depth, bool open, std::vector<Box>& kept) {
        std::vector<std::pair<Box, int>> stack = {{domain, 0}};
        kept.clear();
        while (!stack.empty()) {
            auto [b, level] = stack.back();
            stack.pop_back();
            if (--budget < 0) return false;
            if (lowest(b) > 0) continue;
            if (level == depth) {
                if (open)
                    for (int c = 0; c < 3; ++c)
                        if (b.lo[size_t(c)] <= domain.lo[size_t(c)] || b.hi[size_t(c)] >= domain.hi[size_t(c)]) return false;
                kept.push_back(b);
                continue;
            }
            for (int o = 0; o < 8; ++o) {
                Box c;
                for (size_t a = 0; a < 3; ++a) {
                    double mid = 0.5 * (b.lo[a] + b.hi[a]);
                    bool upper = (o >> a) & 1;
                    c.lo[a] = upper ? mid : b.lo[a];
                    c.hi[a] = upper ? b.hi[a] : mid;
                }
                stack.push_back({c, level + 1});
            }
        }
        return true;
    };
    Box domain{{-reach, -reach, -reach}, {reach, reach, reach}};
    std::vector<Box> kept;
    // Coarse: the solid must stay off the boundary of the big cube (levels of 1/64 of it).
    if (!pass(domain, 6, true, kept)) return std::nullopt;
    if (kept.empty()) return std::nullopt;  // nothing where the distance can be ≤ 0: no solid to bound
    // Nor beyond the cube: each of the six half-spaces past a face (the other axes unbounded) must be free, or a
    // part of the solid farther than `reach` (a model in millimetres scaled to metres) would be cut off.
    for (size_t a = 0; a < 3; ++a)
        for (int side : {-1, 1}) {
            Box slab{{-INFINITY, -INFINITY, -INFINITY}, {INFINITY, INFINITY, INFINITY}};
            if (side > 0) slab.lo[a] = reach;
            else slab.hi[a] = -reach;
            if (--budget < 0 || !(lowest(slab) > 0)) return std::nullopt;
        }
    // Fine: the hull of what is left, widened by half a cell, split again (four times: each cell is 1/8 of the
    // last hull, which shrinks to the solid's).
    for (int round = 0; round < 4; ++round) {
        Box hull{{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}};
        double cell = 0;
        for (const Box& b : kept)
            for (size_t a = 0; a < 3; ++a) {
                hull.lo[a] = std::min(hull.lo[a], b.lo[a]);
                hull.hi[a] = std::max(hull.hi[a], b.hi[a]);
                cell = std::max(cell, b.hi[a] - b.lo[a]);
            }
        for (size_t a = 0; a < 3; ++a) {
            hull.lo[a] -= 0.5 * cell;
            hull.hi[a] += 0.5 * cell;
        }
        std::vector<Box> finer;
        if (!pass(hull, 3, false, finer)) break;  // keep the coarser answer
        kept = std::move(finer);
    }
    // The radius: the farthest corner of a box left, refined where it is decided (best first: the box with the
    // farthest corner is split until it is small against the radius, or the budget ends).
    auto far_corner = [](const Box& b) {
        double s = 0;
        for (size_t a = 0; a < 3; ++a) s += std::pow(std::max(std::fabs(b.lo[a]), std::fabs(b.hi[a])), 2);
        return std::sqrt(s);
    };
    auto size = [](const Box& b) { return std::max({b.hi[0] - b.lo[0], b.hi[1] - b.lo[1], b.hi[2] - b.lo[2]}); };
    auto farther = [&](const Box& a, const Box& b) { return far_corner(a) < far_corner(b); };
    std::priority_queue<Box, std::vector<Box>, decltype(farther)> queue(farther, std::move(kept));
    double r = 0;
    while (!queue.empty()) {
        Box b = queue.top();
        if (size(b) <= 0.002 * far_corner(b) || budget < 8) {
            r = far_corner(b);
            break;
        }
        queue.pop();
        for (int o = 0; o < 8; ++o) {
            Box c;
            for (size_t a = 0; a < 3; ++a) {
                double mid = 0.5 * (b.lo[a] + b.hi[a]);
                bool upper = (o >> a) & 1;
                c.lo[a] = upper ? mid : b.lo[a];
                c.hi[a] = upper ? b.hi[a] : mid;
            }
            --budget;
            if (lowest(c) <= 0) queue.push(c);
        }
    }
    return std::nextafter(r * (1 + 1e-9), INFINITY);
}

std::optional<SupportBox> support_box(const Module& m, int fn, int query, std::vector<std::vector<Interval>> params,
                                      double level, int per_proof, int loop_trips, long work) {
    if (fn < 0 || size_t(fn) >= m.functions.size() || query < 0 || size_t(query) >= params.size()) return std::nullopt;
    const Function& f = m.functions[size_t(fn)];
    const Type& rt = f.body[f.result].type;
    if (!rt.is_scalar() && !rt.is_vector()) return std::nullopt;  // a scene's (distance, id): the first component
    // The distance's interval over a box (its first component; [-∞, ∞] where unknown or NaN).
    auto range = [&](const Box& b) {
        params[size_t(query)] = {{b.lo[0], b.hi[0]}, {b.lo[1], b.hi[1]}, {b.lo[2], b.hi[2]}};
        std::vector<Bounds> v = interval_analysis(m, fn, params, {}, loop_trips, &work);
        const Bounds& r = v[f.result];
        Interval x = r.c.empty() ? Interval{} : r.c[0];
        if (std::isnan(x.lo)) x.lo = -INFINITY;
        if (std::isnan(x.hi)) x.hi = INFINITY;
        return x;
    };
    // A point inside an interval, and its halves (an unbounded side grows geometrically).
    auto centre = [](double lo, double hi) {
        if (std::isinf(lo) && std::isinf(hi)) return 0.0;
        if (std::isinf(hi)) return lo + std::max(1.0, std::fabs(lo));
        if (std::isinf(lo)) return hi - std::max(1.0, std::fabs(hi));
        return 0.5 * (lo + hi);
    };
    // Whether no point of `b` has a distance ≤ level (false: not proven, or a point found that has).
    auto free_of = [&](const Box& start) {
        std::vector<Box> stack = {start};
        int left = per_proof;
        while (!stack.empty()) {
            if (work <= 0) return false;
            Box b = stack.back();
            stack.pop_back();
            if (range(b).lo > level) continue;
            if (--left < 0) return false;
            Box c;
            for (size_t a = 0; a < 3; ++a) c.lo[a] = c.hi[a] = centre(b.lo[a], b.hi[a]);
            if (range(c).hi <= level) return false;
            // Split the widest side (an unbounded one first) at its centre.
            size_t w = 0;
            double widest = -1;
            for (size_t a = 0; a < 3; ++a) {
                double len = b.hi[a] - b.lo[a];
                if (len > widest) widest = len, w = a;
            }
            if (!(widest > 0)) return false;
            Box lo = b, hi = b;
            lo.hi[w] = hi.lo[w] = c.lo[w];
            stack.push_back(lo);
            stack.push_back(hi);
        }
        return true;
    };
    constexpr double R = 1048576.0;  // 2^20: beyond this, a side is unbounded
    SupportBox out;
    bool any = false;
    // One side's edge: the nearest plane c (along axis a, from below or above) beyond which nothing is ≤ level;
    // ±∞ where the half-space beyond R is not proven free.
    auto edge_of = [&](size_t a, bool upper) {
        // The half-space beyond the plane c on this side.
        auto beyond = [&](double c) {
            Box b{{-INFINITY, -INFINITY, -INFINITY}, {INFINITY, INFINITY, INFINITY}};
            if (upper) b.lo[a] = c;
            else b.hi[a] = c;
            return free_of(b);
        };
        const double sgn = upper ? 1 : -1;
        if (!beyond(sgn * R)) return sgn * INFINITY;
        // A plane that is not proven (in) and one that is (out): planes ±1, ±2, ±4, … from 0 outward (or
        // inward, where the half-space beyond 0 is already free), then bisection to 1e-3 of the scale.
        double in = NAN, out_c = NAN;
        if (beyond(0)) {
            out_c = 0;
            for (double c = 1; c <= R && std::isnan(in); c *= 2) (beyond(-sgn * c) ? out_c : in) = -sgn * c;
            if (std::isnan(in)) return -sgn * R;  // free on both sides: nothing is ≤ level anywhere
        } else {
            in = 0;
            // Planes out to 1,024 units (a shape's own space rarely reaches further; beyond, the side stays at
            // R rather than spending the budget on proofs that keep failing, as over fbm noise).
            for (double c = 1; c <= 1024 && std::isnan(out_c); c *= 2) (beyond(sgn * c) ? out_c : in) = sgn * c;
            if (std::isnan(out_c)) return sgn * R;
        }
        while (std::fabs(out_c - in) > 1e-3 * std::max(1.0, std::fabs(out_c))) {
            double mid = 0.5 * (in + out_c);
            (beyond(mid) ? out_c : in) = mid;
        }
        return out_c;
    };
    // Each side gets its share of the budget (an open side spends all of it on trying).
    const long share = work / 6;
    long left = work;
    for (size_t a = 0; a < 3; ++a)
        for (bool upper : {false, true}) {
            work = std::min(left, share);
            const long given = work;
            double e = edge_of(a, upper);
            left -= given - work;
            (upper ? out.hi[a] : out.lo[a]) = e;
            any |= std::isfinite(e);
        }
    if (!any) return std::nullopt;
    return out;
}

}  // namespace iqc::ir
