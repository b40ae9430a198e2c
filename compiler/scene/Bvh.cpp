#include "scene/Bvh.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <numbers>
#include <numeric>

namespace iqc {

namespace {

using Mat3 = std::array<double, 9>;  // row-major

Mat3 inverse(const std::vector<double>& L) {
    const double a = L[0], b = L[1], c = L[2], d = L[3], e = L[4], f = L[5], g = L[6], h = L[7], i = L[8];
    const double A = e * i - f * h, B = -(d * i - f * g), C = d * h - e * g;
    const double det = a * A + b * B + c * C;
    return {A / det, -(b * i - c * h) / det, (b * f - c * e) / det,
            B / det, (a * i - c * g) / det, -(a * f - c * d) / det,
            C / det, -(a * h - b * g) / det, (a * e - b * d) / det};
}

// The largest eigenvalue of the symmetric 3×3 matrix M (Smith 1961, "Eigenvalues of a symmetric 3 × 3
// matrix"; the largest root is the well-conditioned one).
double largest_eigenvalue(const Mat3& M) {
    const double p1 = M[1] * M[1] + M[2] * M[2] + M[5] * M[5];
    const double q = (M[0] + M[4] + M[8]) / 3;
    const double p2 = (M[0] - q) * (M[0] - q) + (M[4] - q) * (M[4] - q) + (M[8] - q) * (M[8] - q) + 2 * p1;
    const double p = std::sqrt(p2 / 6);
    if (p == 0) return q;
    Mat3 B;
    for (int k = 0; k < 9; ++k) B[size_t(k)] = (M[size_t(k)] - (k % 4 == 0 ? q : 0)) / p;
    const double det = B[0] * (B[4] * B[8] - B[5] * B[7]) - B[1] * (B[3] * B[8] - B[5] * B[6]) + B[2] * (B[3] * B[7] - B[4] * B[6]);
    const double r = std::clamp(det / 2, -1.0, 1.0);
    return q + 2 * p * std::cos(std::acos(r) / 3);
}

// Rounds a radius up past float32 rounding of the centre and radius (relative to their magnitude).
double round_up(const std::array<double, 3>& c, double r) {
    double scale = r;
    for (double x : c) scale = std::max(scale, std::fabs(x));
    return r * (1 + 1e-6) + scale * 1e-6;
}

struct Builder {
    const std::vector<BoundingSphere>& members;
    int branching;
    BoundsTree tree;

    // Splits `set` into `parts` sets of at most `cap` members each, halving at the median along the widest
    // axis of the centres.
    void split(std::vector<int> set, int parts, long long cap, std::vector<std::vector<int>>& out) {
        if (parts == 1) {
            out.push_back(std::move(set));
            return;
        }
        const int left = parts / 2, right = parts - left;
        const long long n = (long long)set.size();
        long long n1 = std::llround(double(n) * left / parts);
        n1 = std::clamp(n1, std::max(0LL, n - right * cap), std::min(n, left * cap));
        std::array<double, 3> lo, hi;
        lo.fill(INFINITY);
        hi.fill(-INFINITY);
        for (int m : set)
            for (size_t a = 0; a < 3; ++a) {
                lo[a] = std::min(lo[a], members[size_t(m)].center[a]);
                hi[a] = std::max(hi[a], members[size_t(m)].center[a]);
            }
        size_t axis = 0;
        for (size_t a = 1; a < 3; ++a)
            if (hi[a] - lo[a] > hi[axis] - lo[axis]) axis = a;
        // Ties broken by the member's position: the build is deterministic.
        std::stable_sort(set.begin(), set.end(),
                         [&](int x, int y) { return members[size_t(x)].center[axis] < members[size_t(y)].center[axis]; });
        std::vector<int> a(set.begin(), set.begin() + n1), b(set.begin() + n1, set.end());
        split(std::move(a), left, cap, out);
        split(std::move(b), right, cap, out);
    }

    // Adds the nodes of `set` at `level` (each covering at most branching^(depth - level) members), their
    // subtrees below; returns the boxes of the nodes added.
    std::vector<BoundingBox> build(const std::vector<int>& set, size_t level, size_t depth) {
        long long cap = 1;
        for (size_t l = level + 1; l < depth; ++l) cap *= branching;  // members under one child node
        const int parts = int((set.size() + size_t(cap) * branching - 1) / (size_t(cap) * branching));
        std::vector<std::vector<int>> nodes;
        split(set, parts, cap * branching, nodes);
        std::vector<BoundingBox> boxes;
        BoundsTreeLevel& L = tree.levels[level];
        for (const auto& node : nodes) {
            std::vector<BoundingBox> below;
            int first;
            if (level + 1 == depth) {  // children are members
                first = int(tree.order.size());
                for (int m : node) {
                    tree.order.push_back(m);
                    below.push_back(box_of(members[size_t(m)]));
                }
            } else {
                // The children's nodes are appended to the next level together (deeper recursion only
                // appends to deeper levels), so they are [first, first + count) there.
                first = int(tree.levels[level + 1].nodes.size());
                below = build(node, level + 1, depth);
            }
            BoundingBox b = enclosing_box(below);
            L.nodes.push_back(b);
            L.first.push_back(first);
            L.count.push_back(int(below.size()));
            boxes.push_back(b);
        }
        return boxes;
    }
};

}  // namespace

BoundingSphere world_sphere(const std::vector<double>& L, const std::vector<double>& o, double R) {
    const Mat3 A = inverse(L);  // object -> world, linear part
    BoundingSphere s;
    for (size_t r = 0; r < 3; ++r) s.center[r] = -(A[r * 3] * o[0] + A[r * 3 + 1] * o[1] + A[r * 3 + 2] * o[2]);
    Mat3 AtA{};
    double frobenius2 = 0;
    for (size_t r = 0; r < 3; ++r)
        for (size_t c = 0; c < 3; ++c) {
            for (size_t k = 0; k < 3; ++k) AtA[r * 3 + c] += A[k * 3 + r] * A[k * 3 + c];
            frobenius2 += A[r * 3 + c] * A[r * 3 + c];
        }
    // σ_max(A)² ≤ ‖A‖_F²; the closed form rounded up, never past that bound.
    const double sigma2 = std::min(frobenius2, largest_eigenvalue(AtA) * (1 + 1e-9));
    s.radius = round_up(s.center, R * std::sqrt(sigma2));
    return s;
}

BoundingBox box_of(const BoundingSphere& s) {
    BoundingBox b;
    b.center = s.center;
    b.half = {s.radius, s.radius, s.radius};
    return b;
}

BoundingBox enclosing_box(const std::vector<BoundingBox>& boxes) {
    std::array<double, 3> lo, hi;
    lo.fill(INFINITY);
    hi.fill(-INFINITY);
    for (const auto& b : boxes)
        for (size_t a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], b.center[a] - b.half[a]);
            hi[a] = std::max(hi[a], b.center[a] + b.half[a]);
        }
    BoundingBox out;
    for (size_t a = 0; a < 3; ++a) {
        out.center[a] = (lo[a] + hi[a]) / 2;
        out.half[a] = round_up(out.center, (hi[a] - lo[a]) / 2);
    }
    return out;
}

BoundsTree build_bounds_tree(const std::vector<BoundingSphere>& members, int branching) {
    Builder b{members, std::max(2, branching), {}};
    if (members.empty()) return {};
    // Levels of nodes: a node of the last level holds at most `branching` members, one a level up at most
    // branching² ..., and the top level has at most `branching` nodes.
    size_t depth = 1;
    for (long long span = (long long)b.branching * b.branching; span < (long long)members.size(); span *= b.branching) ++depth;
    b.tree.levels.resize(depth);
    std::vector<int> all(members.size());
    std::iota(all.begin(), all.end(), 0);
    b.build(all, 0, depth);
    return std::move(b.tree);
}

InstanceLattice find_instance_lattice(const std::vector<BoundingSphere>& members) {
    InstanceLattice L;
    const size_t N = members.size();
    if (N < 2) return {};
    double extent = 0;
    for (size_t a = 0; a < 3; ++a) {
        double lo = INFINITY, hi = -INFINITY;
        for (const auto& m : members) lo = std::min(lo, m.center[a]), hi = std::max(hi, m.center[a]);
        extent = std::max({extent, hi - lo, std::fabs(lo), std::fabs(hi)});
    }
    // Per axis: centres within a thousandth of the largest gap between neighbouring coordinates (about the spacing)
    // of their cell's are on the lattice (positions written rounded, thirds to 4 decimals); L.deviation says how far.
    std::array<double, 3> tols;
    for (size_t a = 0; a < 3; ++a) {
        std::vector<double> v;
        for (const auto& m : members) v.push_back(m.center[a]);
        std::sort(v.begin(), v.end());
        double gap = 0;
        for (size_t i = 1; i < v.size(); ++i) gap = std::max(gap, v[i] - v[i - 1]);
        const double tol = tols[a] = std::max(1e-6 * std::max(extent, 1e-6), 1e-3 * gap);
        std::vector<double> distinct = {v[0]};
        for (double x : v)
            if (x - distinct.back() > tol) distinct.push_back(x);
        // A coordinate that is 0 but for rounding (a centre mapped through a rotation: −2.2e−16) is 0: else the
        // scene function subtracts it from p at every evaluation (x − c is not x for a constant c ≠ 0).
        L.origin[a] = std::fabs(distinct.front()) <= 1e-3 * tol ? 0.0 : distinct.front();
        L.n[a] = int(distinct.size());
        if (distinct.size() > 1) {
            L.spacing[a] = (distinct.back() - distinct.front()) / double(distinct.size() - 1);
            if (!(L.spacing[a] > 4 * tol)) return {};
            for (size_t j = 0; j < distinct.size(); ++j)
                if (std::fabs(distinct[j] - (L.origin[a] + double(j) * L.spacing[a])) > tol) return {};
        }
    }
    const size_t cells = size_t(L.n[0]) * size_t(L.n[1]) * size_t(L.n[2]);
    if (cells < N || cells > 2 * N) return {};
    // Each member's cell; every cell once (N members in N cells, none twice).
    std::vector<long long> member_of(cells, -1);
    std::vector<std::array<long long, 3>> cell(N);
    for (size_t k = 0; k < N; ++k) {
        size_t flat = 0, mul = 1;
        for (size_t a = 0; a < 3; ++a) {
            const double u = (members[k].center[a] - L.origin[a]) / L.spacing[a];
            const double r = std::round(u);
            const double off = std::fabs(members[k].center[a] - (L.origin[a] + r * L.spacing[a]));
            if (off > tols[a] || r < 0 || r >= L.n[a]) return {};
            L.deviation = std::max(L.deviation, off);
            cell[k][a] = (long long)r;
            flat += size_t(r) * mul;
            mul *= size_t(L.n[a]);
        }
        if (member_of[flat] >= 0) return {};
        member_of[flat] = (long long)k;
        L.radius = std::max(L.radius, members[k].radius);
    }
    // k = base + Σ stride_a · cell_a: base from cell (0, 0, 0), each stride from the next cell along its axis.
    L.base = member_of[0];
    L.members = (long long)N;
    if (L.base < 0) return {};
    for (size_t a = 0, mul = 1; a < 3; mul *= size_t(L.n[a]), ++a) {
        if (L.n[a] > 1 && member_of[mul] < 0) return {};
        L.stride[a] = L.n[a] > 1 ? member_of[mul] - L.base : 0;
    }
    auto affine = [&](size_t i, size_t j, size_t l) {
        return L.base + L.stride[0] * (long long)i + L.stride[1] * (long long)j + L.stride[2] * (long long)l;
    };
    for (size_t k = 0; k < N; ++k)
        if (affine(size_t(cell[k][0]), size_t(cell[k][1]), size_t(cell[k][2])) != (long long)k) return {};
    if (cells == N) return L;
    // Empty cells: outside [0, N), with the cell one step back along the axis of the largest stride filled.
    int axis = 0;
    for (int a = 1; a < 3; ++a)
        if (std::llabs(L.stride[size_t(a)]) > std::llabs(L.stride[size_t(axis)])) axis = a;
    L.back_axis = axis;
    const size_t step = axis == 0 ? 1 : axis == 1 ? size_t(L.n[0]) : size_t(L.n[0]) * size_t(L.n[1]);
    for (size_t l = 0, flat = 0; l < size_t(L.n[2]); ++l)
        for (size_t j = 0; j < size_t(L.n[1]); ++j)
            for (size_t i = 0; i < size_t(L.n[0]); ++i, ++flat) {
                if (member_of[flat] >= 0) continue;
                const long long k = affine(i, j, l);
                if (k >= 0 && k < (long long)N) return {};
                const size_t at[3] = {i, j, l};
                if (at[axis] == 0 || member_of[flat - step] < 0) return {};
            }
    return L;
}

}  // namespace iqc
