// The bounding-volume hierarchy over a group's instances (scene/Bvh.h): world spheres contain the transformed
// `bound` balls, every node's box contains what is below it, every member is listed once, and the tree has the
// same depth everywhere with at most `branching` children per node.
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <fmt/format.h>

#include "scene/Bvh.h"
#include "ir/Parse.h"
#include "ir/Support.h"

using namespace iqc;

namespace {

struct Rng {  // deterministic, in [-1, 1)
    uint32_t h = 2463534242u;
    double operator()() {
        h ^= h << 13;
        h ^= h >> 17;
        h ^= h << 5;
        return double(h) / 2147483648.0 - 1.0;
    }
};

double dist(const std::array<double, 3>& a, const std::array<double, 3>& b) {
    return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

bool contains(const BoundingBox& outer, const BoundingBox& inner) {
    for (size_t a = 0; a < 3; ++a)
        if (inner.center[a] - inner.half[a] < outer.center[a] - outer.half[a] || inner.center[a] + inner.half[a] > outer.center[a] + outer.half[a])
            return false;
    return true;
}

// Row-major 3×3 product.
std::vector<double> mul(const std::vector<double>& a, const std::vector<double>& b) {
    std::vector<double> c(9, 0.0);
    for (int r = 0; r < 3; ++r)
        for (int k = 0; k < 3; ++k)
            for (int j = 0; j < 3; ++j) c[size_t(r * 3 + j)] += a[size_t(r * 3 + k)] * b[size_t(k * 3 + j)];
    return c;
}

}  // namespace

TEST_CASE("world_sphere contains the object-space ball under any invertible map, and is tight for similarities", "[bvh]") {
    Rng rnd;
    for (int trial = 0; trial < 200; ++trial) {
        // world -> object: a rotation about a random axis, a scale, and (every other trial) a shear.
        double a = 3 * rnd(), s = std::exp(1.5 * rnd());
        double c = std::cos(a), si = std::sin(a);
        std::vector<double> L = {c * s, -si * s, 0, si * s, c * s, 0, 0, 0, s};
        if (trial % 2) L = mul(L, {1, 0.7 * rnd(), 0, 0, 1, 0.5 * rnd(), 0.3 * rnd(), 0, 1.2 + rnd()});
        std::vector<double> o = {10 * rnd(), 10 * rnd(), 10 * rnd()};
        double R = 0.1 + std::fabs(rnd());
        BoundingSphere w = world_sphere(L, o, R);
        // Points of the object ball's surface carried to world space (p = L⁻¹(q - o), solved by Cramer's rule).
        double worst = 0;
        for (int k = 0; k < 400; ++k) {
            std::array<double, 3> q = {rnd(), rnd(), rnd()};
            double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
            for (double& x : q) x = x / n * R;
            std::array<double, 3> b = {q[0] - o[0], q[1] - o[1], q[2] - o[2]};
            auto det3 = [](const std::vector<double>& m) {
                return m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6]) + m[2] * (m[3] * m[7] - m[4] * m[6]);
            };
            double D = det3(L);
            std::array<double, 3> p;
            for (int col = 0; col < 3; ++col) {
                std::vector<double> M = L;
                for (int r = 0; r < 3; ++r) M[size_t(r * 3 + col)] = b[size_t(r)];
                p[size_t(col)] = det3(M) / D;
            }
            worst = std::max(worst, dist(p, w.center));
        }
        INFO("trial " << trial << ": farthest point " << worst << ", radius " << w.radius);
        CHECK(worst <= w.radius);
        if (trial % 2 == 0) CHECK(w.radius <= R / s * (1 + 1e-5) + 1e-5 * (std::fabs(w.center[0]) + std::fabs(w.center[1]) + std::fabs(w.center[2]) + w.radius));
    }
}

TEST_CASE("the bounds tree lists every member once, has one depth, and nests its boxes", "[bvh]") {
    Rng rnd;
    for (int n : {1, 2, 15, 16, 17, 100, 256, 257, 1000, 4097}) {
        for (int branching : {2, 4, 16}) {
            std::vector<BoundingSphere> members(static_cast<size_t>(n));
            for (auto& m : members) {
                m.center = {20 * rnd(), 3 * rnd(), 20 * rnd()};
                m.radius = 0.2 + 0.3 * std::fabs(rnd());
            }
            if (n == 100)  // coincident centres: the median split must still make progress
                for (auto& m : members) m.center = {1, 2, 3};
            BoundsTree t = build_bounds_tree(members, branching);
            INFO(n << " members, branching " << branching);
            REQUIRE(!t.levels.empty());
            // Each member once, in leaf order.
            std::vector<int> seen(size_t(n), 0);
            for (int m : t.order) {
                REQUIRE(m >= 0);
                REQUIRE(m < n);
                ++seen[size_t(m)];
            }
            for (int v : seen) REQUIRE(v == 1);
            CHECK(t.levels[0].nodes.size() <= size_t(branching));
            size_t capacity = size_t(branching);
            for (size_t l = 1; l < t.levels.size(); ++l) capacity *= size_t(branching);
            CHECK(capacity * size_t(branching) >= size_t(n));  // no deeper than needed
            for (size_t l = 0; l < t.levels.size(); ++l) {
                const BoundsTreeLevel& L = t.levels[l];
                bool last = l + 1 == t.levels.size();
                size_t below = last ? t.order.size() : t.levels[l + 1].nodes.size();
                size_t next = 0;
                for (size_t k = 0; k < L.nodes.size(); ++k) {
                    CHECK(L.count[k] >= 1);
                    CHECK(L.count[k] <= branching);
                    CHECK(size_t(L.first[k]) == next);  // children contiguous, in order, covering the level below
                    next += size_t(L.count[k]);
                    for (int c = L.first[k]; c < L.first[k] + L.count[k]; ++c) {
                        BoundingBox child = last ? box_of(members[size_t(t.order[size_t(c)])]) : t.levels[l + 1].nodes[size_t(c)];
                        CHECK(contains(L.nodes[k], child));
                    }
                }
                CHECK(next == below);
            }
        }
    }
}

TEST_CASE("the bounds tree is deterministic", "[bvh]") {
    Rng rnd;
    std::vector<BoundingSphere> members(300);
    for (auto& m : members) m.center = {std::round(4 * rnd()), 0, std::round(4 * rnd())}, m.radius = 0.3;  // many ties
    BoundsTree a = build_bounds_tree(members, 8), b = build_bounds_tree(members, 8);
    CHECK(a.order == b.order);
    REQUIRE(a.levels.size() == b.levels.size());
    for (size_t l = 0; l < a.levels.size(); ++l) CHECK(a.levels[l].first == b.levels[l].first);
}

// The IR of a sphere of radius r, a torus (R, r) and a box of half-sides b, and a plane (unbounded), and more
// (the extent and depth tests below).
const char* const kShapesIr = R"(function ball(p: ℝ³, r: ℝ) -> ℝ {
  %0 = ℝ³ Param #0 p  ; p
  %1 = ℝ Param #1 r  ; r
  %2 = ℝ Builtin length %0
  %3 = ℝ Sub %2, %1
  return %3
}
function torus(p: ℝ³, t: ℝ²) -> ℝ {
  %0 = ℝ³ Param #0 p  ; p
  %1 = ℝ² Param #1 t  ; t
  %2 = ℝ Extract [0] %0
  %3 = ℝ Extract [2] %0
  %4 = ℝ² Construct %2, %3
  %5 = ℝ Builtin length %4
  %6 = ℝ Extract [0] %1
  %7 = ℝ Sub %5, %6
  %8 = ℝ Extract [1] %0
  %9 = ℝ² Construct %7, %8
  %10 = ℝ Builtin length %9
  %11 = ℝ Extract [1] %1
  %12 = ℝ Sub %10, %11
  return %12
}
function plane(p: ℝ³) -> ℝ {
  %0 = ℝ³ Param #0 p  ; p
  %1 = ℝ Extract [1] %0
  %2 = ℝ Const 1
  %3 = ℝ Add %1, %2
  return %3
}
function two_balls(p: ℝ³, c: ℝ³) -> ℝ {
  %0 = ℝ³ Param #0 p  ; p
  %1 = ℝ³ Param #1 c  ; c
  %2 = ℝ Builtin length %0
  %3 = ℝ Const 300
  %4 = ℝ Sub %2, %3
  %5 = ℝ³ Sub %0, %1
  %6 = ℝ Builtin length %5
  %7 = ℝ Sub %6, %3
  %8 = ℝ Builtin min %4, %7
  return %8
}
function ball_and_far_plane(p: ℝ³, c: ℝ) -> ℝ {
  %0 = ℝ³ Param #0 p  ; p
  %1 = ℝ Param #1 c  ; c
  %2 = ℝ Extract [1] %0
  %3 = ℝ Add %2, %1
  %4 = ℝ Builtin length %0
  %5 = ℝ Const 1
  %6 = ℝ Sub %4, %5
  %7 = ℝ Builtin min %6, %3
  return %7
}
)";

TEST_CASE("a shape's extent by interval arithmetic: a ball that contains the solid, tight to a few percent", "[bvh]") {
    const std::string text = kShapesIr;
    ir::Module m;
    std::string error;
    INFO(error);
    REQUIRE(ir::parse_module(text, m, error));
    using V = std::vector<std::vector<ir::Interval>>;
    auto ball = ir::support_radius(m, 0, 0, V{{}, {{1, 1}}});
    REQUIRE(ball);
    CHECK(*ball >= 1.0);
    CHECK(*ball <= 1.1);
    // A slider's range: the radius that holds for every value of it.
    auto ranged = ir::support_radius(m, 0, 0, V{{}, {{0.5, 2}}});
    REQUIRE(ranged);
    CHECK(*ranged >= 2.0);
    CHECK(*ranged <= 2.2);
    auto torus = ir::support_radius(m, 1, 0, V{{}, {{0.3, 0.3}, {0.08, 0.08}}});
    REQUIRE(torus);
    CHECK(*torus >= 0.38);
    CHECK(*torus <= 0.38 * 1.15);
    CHECK_FALSE(ir::support_radius(m, 2, 0, V{{}}));  // a plane: the solid reaches the search cube's faces
    CHECK_FALSE(ir::support_radius(m, 0, 0, V{{}, {{-INFINITY, INFINITY}}}));  // an unbounded radius
    // A negative radius: no point where the distance can be ≤ 0, nothing to bound.
    CHECK_FALSE(ir::support_radius(m, 0, 0, V{{}, {{-1, -1}}}));
    // Parts beyond the search cube (half-side 1024) are not cut off (a trial's model in millimetres: a second
    // ball 2000 units away was dropped from the radius, and drawn nowhere): no radius. Near, both balls count.
    CHECK_FALSE(ir::support_radius(m, 3, 0, V{{}, {{2000, 2000}, {0, 0}, {0, 0}}}));
    auto near = ir::support_radius(m, 3, 0, V{{}, {{600, 600}, {0, 0}, {0, 0}}});
    REQUIRE(near);
    CHECK(*near >= 900);
    CHECK_FALSE(ir::support_radius(m, 4, 0, V{{}, {{1e4, 1e4}}}));  // a ball and a plane 10⁴ below it
    // The answer does not depend on the order of evaluation: the same twice.
    CHECK(ir::support_radius(m, 1, 0, V{{}, {{0.3, 0.3}, {0.08, 0.08}}}) == torus);
}

TEST_CASE("a shape's depth by interval branch and bound: a bound of the largest ball inside, within 10%", "[bvh]") {
    // A ball (depth its radius), a shell 0.04 thick (depth 0.02: its box is 2 across), a torus's tube (0.1), and a
    // function positive everywhere (no depth).
    const std::string text = std::string(kShapesIr) + R"(function shell(p: ℝ³) -> ℝ {
  %0 = ℝ³ Param #0 p  ; p
  %1 = ℝ Builtin length %0
  %2 = ℝ Const 1
  %3 = ℝ Sub %1, %2
  %4 = ℝ Builtin abs %3
  %5 = ℝ Const 0.02
  %6 = ℝ Sub %4, %5
  return %6
}
)";
    ir::Module m;
    std::string error;
    INFO(error);
    REQUIRE(ir::parse_module(text, m, error));
    using V = std::vector<std::vector<ir::Interval>>;
    const std::array<double, 3> lo{-1.1, -1.1, -1.1}, hi{1.1, 1.1, 1.1};
    auto ball = ir::deepest_bound(m, 0, 0, V{{}, {{0.7, 0.7}}}, lo, hi);
    REQUIRE(ball);
    CHECK(*ball >= 0.7);
    CHECK(*ball <= 0.7 * 1.1);
    auto shell = ir::deepest_bound(m, m.find("shell"), 0, V{{}}, lo, hi);
    REQUIRE(shell);
    CHECK(*shell >= 0.02);
    CHECK(*shell <= 0.022);
    auto tube = ir::deepest_bound(m, m.find("torus"), 0, V{{}, {{0.5, 0.5}, {0.1, 0.1}}}, lo, hi);
    REQUIRE(tube);
    CHECK(*tube >= 0.1);
    CHECK(*tube <= 0.11);
    auto none = ir::deepest_bound(m, 0, 0, V{{}, {{-1, -1}}}, lo, hi);  // ‖p‖ + 1: never inside
    REQUIRE(none);
    CHECK(*none == 0);
    // An unbounded box, or one the distance cannot bound: nothing.
    CHECK_FALSE(ir::deepest_bound(m, 0, 0, V{{}, {{0.7, 0.7}}}, {-INFINITY, -1, -1}, hi));
    CHECK_FALSE(ir::deepest_bound(m, 0, 0, V{{}, {{-INFINITY, INFINITY}}}, lo, hi));
}

TEST_CASE("find_instance_lattice: full and partly filled lattices in any member order, none for other layouts", "[bvh][lattice]") {
    // Members listed x fastest, then z, then y (bench/rings.sh's order), spacing (1, 0.5, 1), radius 0.4.
    auto rings = [](int n, int side) {
        std::vector<BoundingSphere> s;
        for (int i = 0; i < n; ++i)
            s.push_back({{double(i % side) - side / 2.0, (i / (side * side)) * 0.5 - 0.7, double((i / side) % side) - side / 2.0}, 0.4});
        return s;
    };
    // k = base + Σ stride·cell for every member, each cell's centre = origin + cell·spacing.
    auto check = [](const std::vector<BoundingSphere>& s, const InstanceLattice& L) {
        for (size_t k = 0; k < s.size(); ++k) {
            std::array<long long, 3> c{};
            for (size_t a = 0; a < 3; ++a) {
                c[a] = std::llround((s[k].center[a] - L.origin[a]) / L.spacing[a]);
                CHECK(c[a] >= 0);
                CHECK(c[a] < L.n[a]);
                CHECK(std::fabs(L.origin[a] + double(c[a]) * L.spacing[a] - s[k].center[a]) < 1e-9);
            }
            CHECK(L.base + L.stride[0] * c[0] + L.stride[1] * c[1] + L.stride[2] * c[2] == (long long)k);
        }
    };
    InstanceLattice full = find_instance_lattice(rings(1000, 10));
    REQUIRE(full.found());
    CHECK(full.n == std::array<int, 3>{10, 10, 10});
    CHECK(full.spacing[1] == Approx(0.5));
    CHECK(full.stride == std::array<long long, 3>{1, 100, 10});
    CHECK(full.back_axis == -1);
    CHECK(full.radius == 0.4);
    check(rings(1000, 10), full);
    // 3,000 rings on 18 × 18 cells a layer: ten layers, the last one with 84 members.
    InstanceLattice partial = find_instance_lattice(rings(3000, 18));
    REQUIRE(partial.found());
    CHECK(partial.n == std::array<int, 3>{18, 10, 18});
    CHECK(partial.back_axis == 1);  // y: one layer down is filled
    CHECK(partial.members == 3000);
    check(rings(3000, 18), partial);
    // Reversed order: negative strides.
    std::vector<BoundingSphere> rev = rings(100, 10);
    std::reverse(rev.begin(), rev.end());
    InstanceLattice r = find_instance_lattice(rev);
    REQUIRE(r.found());
    CHECK(r.stride[0] == -1);
    check(rev, r);
    // A plane of tori (bench/instances_100.iq): one cell thick along z.
    std::vector<BoundingSphere> plane;
    for (int k = 0; k < 100; ++k) plane.push_back({{k % 10 - 4.5, k / 10 - 4.5, 0}, 0.4});
    InstanceLattice p = find_instance_lattice(plane);
    REQUIRE(p.found());
    CHECK(p.n == std::array<int, 3>{10, 10, 1});
    CHECK(p.stride[2] == 0);
    check(plane, p);
    // Its centres mapped through the tori's tilts come out at z = ±2.2·10⁻¹⁶: the origin is 0 there, not the
    // rounding (the scene function subtracted it from p at every evaluation), and a real offset stays.
    std::vector<BoundingSphere> rounding = plane;
    for (int k = 0; k < 100; ++k) rounding[size_t(k)].center[2] = k % 3 ? -2.220446e-16 : 1.1e-16;
    InstanceLattice z0 = find_instance_lattice(rounding);
    REQUIRE(z0.found());
    CHECK(z0.origin[2] == 0.0);
    CHECK(z0.origin[0] == -4.5);
    std::vector<BoundingSphere> lifted = plane;
    for (auto& m : lifted) m.center[2] = 0.25;
    CHECK(find_instance_lattice(lifted).origin[2] == 0.25);
    // Not lattices: jittered centres, two members in one cell, an order not affine in the cells (a serpentine),
    // most cells empty, an empty cell inside the filled range.
    std::vector<BoundingSphere> jitter = rings(100, 10);
    jitter[37].center[0] += 0.01;
    CHECK_FALSE(find_instance_lattice(jitter).found());
    // Within 10⁻³ of the spacing (positions written rounded): a lattice, with how far the centres stray.
    std::vector<BoundingSphere> rounded = rings(100, 10);
    rounded[37].center[0] += 0.0004;
    InstanceLattice near = find_instance_lattice(rounded);
    REQUIRE(near.found());
    CHECK(near.deviation == Approx(0.0004).margin(1e-9));
    CHECK(full.deviation == 0);
    std::vector<BoundingSphere> twice = rings(100, 10);
    twice[5] = twice[6];
    CHECK_FALSE(find_instance_lattice(twice).found());
    std::vector<BoundingSphere> snake = rings(100, 10);
    for (int k = 0; k < 100; ++k)
        if ((k / 10) % 2) snake[size_t(k)].center[0] = double(9 - k % 10) - 5;
    CHECK_FALSE(find_instance_lattice(snake).found());
    std::vector<BoundingSphere> sparse = {{{0, 0, 0}, 0.4}, {{1, 0, 1}, 0.4}, {{2, 0, 2}, 0.4}, {{3, 0, 3}, 0.4}};  // a diagonal
    CHECK_FALSE(find_instance_lattice(sparse).found());
    std::vector<BoundingSphere> hole = rings(100, 10);
    hole.erase(hole.begin() + 50);  // the rest renumbered: k no longer affine
    CHECK_FALSE(find_instance_lattice(hole).found());
    CHECK_FALSE(find_instance_lattice({{{0, 0, 0}, 1}}).found());
}
