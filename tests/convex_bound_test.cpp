// A convex piecewise-linear lower bound of a distance and its polytope (ir/ConvexBound.h): the standard library's
// tetrahedron, a largest of four plane distances that interval arithmetic could box on one side only, gets its
// exact box and circumradius; user-written polytopes (planes, |x|, constant matrices, scales, sums) are bounded
// and sampled outside their boxes; what is not a largest of planes (a min, a norm) gets no bound; a slab is
// bounded only across itself; a parameter's slider range takes the largest polytope.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>

#include <fmt/format.h>

#include "TestUtil.h"
#include "ir/ConvexBound.h"
#include "ir/Eval.h"
#include "ir/passes/CSE.h"
#include "ir/passes/Fold.h"
#include "ir/passes/Inline.h"

using namespace iqc;
namespace fs = std::filesystem;

namespace {

// Shape module `text` at its parameters' defaults, q -> D(q), and its flattened copy (calls inlined, constants
// folded: the form convex_lower_bound takes), both added to `m`: {object, flat}.
std::pair<int, int> shape(ir::Module& m, const std::string& text, const std::string& name) {
    const int object = test::lower_shape_object(m, text, name);
    REQUIRE(object >= 0);
    ir::Function flat = ir::inline_calls(m, m.functions[size_t(object)]);
    ir::fold_constants(m, flat);
    ir::eliminate_common_subexpressions(flat);
    flat.name = "object_flat";
    m.functions.push_back(std::move(flat));
    return {object, int(m.functions.size()) - 1};
}

std::optional<std::vector<ir::AffinePiece>> pieces_of(const ir::Module& m, int flat) {
    return ir::convex_lower_bound(m, m.functions[size_t(flat)], 0, {{}});
}

// Points of the cube of half-side `reach` outside `box` (grown by `margin`) where the distance is ≤ level: none
// for a sound box. Counts them over `n` random points.
int inside_beyond(const ir::Module& m, int object, const ir::SupportBox& box, double level, double reach, int n = 4000) {
    ir::Evaluator ev(m, {});
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-reach, reach);
    int bad = 0;
    for (int i = 0; i < n; ++i) {
        std::vector<double> p = {u(rng), u(rng), u(rng)};
        bool outside = false;
        for (size_t a = 0; a < 3; ++a) outside |= p[a] < box.lo[a] || p[a] > box.hi[a];
        if (!outside) continue;
        double d = ev.call(object, {ir::Value{Type::vector(3), p}})[0];
        if (d <= level) ++bad;
    }
    return bad;
}

}  // namespace

TEST_CASE("the tetrahedron's four planes give its exact box and circumradius", "[convex-bound][box]") {
    ir::Module m;
    auto [object, flat] = shape(m, test::read_text(fs::path(IQC_SOURCE_DIR) / "stdlib" / "tetrahedron.iql"), "tetrahedron");
    auto pieces = pieces_of(m, flat);
    REQUIRE(pieces);
    CHECK(pieces->size() == 4);
    const double r = 0.4;  // the default inradius
    ir::SupportBox box = ir::polytope_box(*pieces, 0);
    // Apex (0, 3r, 0); base vertices at y = −r, 2√2·r from the axis, one toward +z, two at x = ±√6·r.
    CHECK(box.lo[0] == Approx(-std::sqrt(6.0) * r).margin(1e-6));
    CHECK(box.hi[0] == Approx(std::sqrt(6.0) * r).margin(1e-6));
    CHECK(box.lo[1] == Approx(-r).margin(1e-6));
    CHECK(box.hi[1] == Approx(3 * r).margin(1e-6));
    CHECK(box.lo[2] == Approx(-std::sqrt(2.0) * r).margin(1e-6));
    CHECK(box.hi[2] == Approx(2 * std::sqrt(2.0) * r).margin(1e-6));
    // Rounded outward, never inward (the module's ⅓ is the float literal the shader holds, 0.33333334: its apex
    // is at 1.19999997, not 1.2).
    CHECK(box.hi[1] >= 3 * r * (1 - 1e-7));
    CHECK(box.lo[1] <= -r);
    auto radius = ir::polytope_radius(*pieces, 0);
    REQUIRE(radius);
    CHECK(*radius == Approx(3 * r).margin(1e-6));  // a regular tetrahedron's circumradius is 3 × its inradius
    CHECK(*radius >= 3 * r * (1 - 1e-7));
    CHECK(inside_beyond(m, object, box, 0, 3) == 0);
    // A level above 0 (the scene box's margin): every plane moves out by it.
    ir::SupportBox grown = ir::polytope_box(*pieces, 0.1);
    CHECK(grown.hi[1] == Approx(3 * r + 0.3).margin(1e-6));  // the apex is where three planes meet at 1/3 each
    CHECK(grown.lo[1] == Approx(-r - 0.1).margin(1e-6));
    CHECK(inside_beyond(m, object, grown, 0.1, 3) == 0);

    // The whole analysis: support_box closes every side (intervals alone closed y only) and support_radius
    // gives the circumradius (intervals alone: none).
    auto sb = ir::support_box(m, object, 0, {{}}, 0);
    REQUIRE(sb);
    for (size_t a = 0; a < 3; ++a) {
        CHECK(std::isfinite(sb->lo[a]));
        CHECK(std::isfinite(sb->hi[a]));
    }
    CHECK(sb->hi[0] == Approx(std::sqrt(6.0) * r).margin(1e-3));
    auto sr = ir::support_radius(m, object, 0, {{}});
    REQUIRE(sr);
    CHECK(*sr == Approx(3 * r).margin(1e-6));
}

TEST_CASE("user-written polytopes: planes, |x|, constant matrices, scales and sums are bounded soundly",
          "[convex-bound][box]") {
    struct Case {
        const char* name;
        const char* d;
        std::array<double, 3> lo, hi;  // the expected box at level 0
        double radius;                 // the farthest vertex's distance from the origin
    };
    const Case cases[] = {
        // A block from |x| and a wedge's two planes.
        {"wedge", "D = max(|p_1| - 1, |p_2| - 0.5, p_3 - 2, -p_3)", {-1, -0.5, 0}, {1, 0.5, 2}, std::sqrt(1 + 0.25 + 4)},
        // The same scaled (a Lipschitz factor written out) and offset by a constant.
        {"scaled", "D = 0.5 max(|p_1| - 1, |p_2| - 0.5, p_3 - 2, -p_3) / 2 + 0", {-1, -0.5, 0}, {1, 0.5, 2}, std::sqrt(1 + 0.25 + 4)},
        // One face written 10⁶ times steeper than the others (a trial's bar: every vertex on that face was
        // dropped as singular, and the radius was the near face's, 0.71).
        {"steep", "D = max(1000000(p_1 - 2), -p_1 - 0.1, |p_2| - 0.5, |p_3| - 0.5)", {-0.1, -0.5, -0.5}, {2, 0.5, 0.5},
         std::sqrt(4 + 0.25 + 0.25)},
        {"shallow", "D = max((p_1 - 2)/1000, -p_1 - 0.1, |p_2| - 0.5, |p_3| - 0.5)", {-0.1, -0.5, -0.5}, {2, 0.5, 0.5},
         std::sqrt(4 + 0.25 + 0.25)},
        // An octahedron as the largest of |x|+|y|+|z|'s planes, written as a dot product with constants.
        {"diamond", "D = (max(p⋅(1,1,1), p⋅(-1,1,1), p⋅(1,-1,1), p⋅(1,1,-1), p⋅(-1,-1,1), p⋅(-1,1,-1), p⋅(1,-1,-1), "
                    "p⋅(-1,-1,-1)) - 1)/√3",
         {-1, -1, -1}, {1, 1, 1}, 1},
        // A cube turned by a constant rotation about z (45°): its extent in x and y is √2.
        {"turned", "D = max(|q_1|, |q_2|, |q_3|) - 1\nq = [0.7071067811865476 0.7071067811865476 0; -0.7071067811865476 "
                   "0.7071067811865476 0; 0 0 1] p",
         {-std::sqrt(2.0), -std::sqrt(2.0), -1}, {std::sqrt(2.0), std::sqrt(2.0), 1}, std::sqrt(3.0)},
        // A sum of two bounds: each pair of their planes summed.
        {"sum", "D = max(|p_1|, |p_2|) + |p_3| - 1", {-1, -1, -1}, {1, 1, 1}, std::sqrt(2.0)},
    };
    for (const Case& c : cases) {
        INFO(c.name << ": " << c.d);
        ir::Module m;
        std::string text = std::string("shape\n") + c.d + "\nwhere\np ∈ ℝ³\n";
        auto [object, flat] = shape(m, text, c.name);
        auto pieces = pieces_of(m, flat);
        REQUIRE(pieces);
        ir::SupportBox box = ir::polytope_box(*pieces, 0);
        for (size_t a = 0; a < 3; ++a) {
            CHECK(box.lo[a] == Approx(c.lo[a]).margin(1e-6));
            CHECK(box.hi[a] == Approx(c.hi[a]).margin(1e-6));
        }
        CHECK(inside_beyond(m, object, box, 0, 4) == 0);
        auto radius = ir::polytope_radius(*pieces, 0);
        REQUIRE(radius);
        CHECK(*radius == Approx(c.radius).margin(1e-6));
        CHECK(*radius >= c.radius);
        ir::SupportBox ball{{-*radius, -*radius, -*radius}, {*radius, *radius, *radius}};
        CHECK(inside_beyond(m, object, ball, 0, 4) == 0);
    }
}

TEST_CASE("what is not a largest of planes gets no polytope: a slab is bounded across itself only", "[convex-bound]") {
    for (const char* d : {"D = min(‖p‖ - 1, p_2)", "D = ‖p‖ - 1", "D = max(p_1 p_2, p_3)", "D = -max(p_1, p_2)",
                          "D = max(p_1, p_2) - max(p_2, p_3)", "D = max(|p_1|, p_2) * p_3"}) {
        INFO(d);
        ir::Module m;
        auto [object, flat] = shape(m, std::string("shape\n") + d + "\nwhere\np ∈ ℝ³\n", "notconvex");
        (void)object;
        CHECK_FALSE(pieces_of(m, flat));
    }
    ir::Module m;
    auto [object, flat] = shape(m, "shape\nD = |p_2| - 1\nwhere\np ∈ ℝ³\n", "slab");
    auto pieces = pieces_of(m, flat);
    REQUIRE(pieces);
    ir::SupportBox box = ir::polytope_box(*pieces, 0);
    CHECK(box.lo[1] == Approx(-1).margin(1e-6));
    CHECK(box.hi[1] == Approx(1).margin(1e-6));
    for (size_t a : {size_t(0), size_t(2)}) {
        CHECK(std::isinf(box.lo[a]));
        CHECK(std::isinf(box.hi[a]));
    }
    CHECK_FALSE(ir::polytope_radius(*pieces, 0));  // unbounded: no ball holds it
    CHECK(inside_beyond(m, object, box, 0, 5) == 0);
}

TEST_CASE("a parameter's range takes the largest polytope it allows", "[convex-bound]") {
    ir::Module m;
    auto [object, flat] = shape(m, test::read_text(fs::path(IQC_SOURCE_DIR) / "stdlib" / "tetrahedron.iql"), "tetrahedron");
    (void)object;
    // The object's own parameters are constants; the module's function takes r as its second parameter.
    const int fn = m.find("tetrahedron");
    REQUIRE(fn >= 0);
    ir::Function g = m.functions[size_t(fn)];
    ir::fold_constants(m, g);
    auto pieces = ir::convex_lower_bound(m, g, 0, {{}, {{0.2, 0.6}}});
    REQUIRE(pieces);
    auto radius = ir::polytope_radius(*pieces, 0);
    REQUIRE(radius);
    CHECK(*radius == Approx(3 * 0.6).margin(1e-6));
    // A range with no end: no finite plane.
    CHECK_FALSE(ir::convex_lower_bound(m, g, 0, {{}, {{0.2, INFINITY}}}));
    (void)flat;
}

TEST_CASE("a polytope of 100 planes (a chain of 99 maxima) is bounded soundly", "[convex-bound]") {
    // Unit normals spread over the sphere (a Fibonacci lattice), each plane at distance 1: the polytope holds the
    // unit ball and lies within 1/cos of the largest angle between neighbouring normals.
    std::string d = "D = max(";
    const int n = 100;
    for (int i = 0; i < n; ++i) {
        const double z = 1 - (2 * i + 1.0) / n, r = std::sqrt(1 - z * z), phi = i * M_PI * (3 - std::sqrt(5.0));
        d += fmt::format("{}p⋅({:.17g}, {:.17g}, {:.17g}) - 1", i ? ", " : "", r * std::cos(phi), r * std::sin(phi), z);
    }
    d += ")";
    ir::Module m;
    auto [object, flat] = shape(m, "shape\n" + d + "\nwhere\np ∈ ℝ³\n", "ball100");
    auto pieces = pieces_of(m, flat);
    REQUIRE(pieces);
    CHECK(pieces->size() == size_t(n));
    ir::SupportBox box = ir::polytope_box(*pieces, 0);
    for (size_t a = 0; a < 3; ++a) {
        CHECK(box.lo[a] <= -1);
        CHECK(box.hi[a] >= 1);
        CHECK(box.hi[a] < 1.5);
    }
    CHECK(inside_beyond(m, object, box, 0, 2) == 0);
    auto radius = ir::polytope_radius(*pieces, 0);
    REQUIRE(radius);
    CHECK(*radius >= 1);
    CHECK(*radius < 1.5);
    ir::SupportBox ball{{-*radius, -*radius, -*radius}, {*radius, *radius, *radius}};
    CHECK(inside_beyond(m, object, ball, 0, 2, 20000) == 0);
}

TEST_CASE("a box turned inside its module by a constant rotation gets a box and a radius", "[convex-bound][box]") {
    // q = R p mixes every axis: over a half-space beyond any plane each component of R p is unbounded, so
    // intervals proved no side (no scene box, no derived bound: 100 of them evaluated 93 shapes per scene
    // evaluation). Analysed over boxes of q and mapped back through R⁻¹ = Rᵀ.
    const double R[3][3] = {{0.8775825618903728, 0, 0.479425538604203},
                            {0.2298488470659301, 0.8775825618903728, -0.4207354924039483},
                            {-0.4207354924039483, 0.479425538604203, 0.7701511529340699}};
    const double h[3] = {1, 0.5, 0.25};
    std::string text = fmt::format(
        "shape\nq = |[{} {} {}; {} {} {}; {} {} {}] (p - (0.5, 0, 0))| - ({}, {}, {})\nD = ‖max(q, 0)‖ + min(max(q_1, q_2, q_3), 0)\n"
        "where\np ∈ ℝ³\n",
        R[0][0], R[0][1], R[0][2], R[1][0], R[1][1], R[1][2], R[2][0], R[2][1], R[2][2], h[0], h[1], h[2]);
    ir::Module m;
    auto [object, flat] = shape(m, text, "turned_box");
    (void)flat;
    CHECK_FALSE(pieces_of(m, flat));  // not a largest of planes: the norm
    auto box = ir::support_box(m, object, 0, {{}}, 0);
    REQUIRE(box);
    for (size_t k = 0; k < 3; ++k) {
        // The exact extent: the centre's coordinate ± Σ_j |R_jk| h_j (p = Rᵀ q + c).
        double e = 0;
        for (size_t j = 0; j < 3; ++j) e += std::fabs(R[j][k]) * h[j];
        const double c = k == 0 ? 0.5 : 0;
        CHECK(box->lo[k] <= c - e);
        CHECK(box->hi[k] >= c + e);
        CHECK(box->lo[k] >= c - e - 0.01);
        CHECK(box->hi[k] <= c + e + 0.01);
    }
    CHECK(inside_beyond(m, object, *box, 0, 3) == 0);
    auto radius = ir::support_radius(m, object, 0, {{}});
    REQUIRE(radius);
    // The farthest corner: ‖Rᵀ(±h) + c‖, at most ‖h‖ + 0.5.
    CHECK(*radius >= std::sqrt(1 + 0.25 + 0.0625));
    CHECK(*radius <= std::sqrt(1 + 0.25 + 0.0625) + 0.5 + 0.01);
    ir::SupportBox ball{{-*radius, -*radius, -*radius}, {*radius, *radius, *radius}};
    CHECK(inside_beyond(m, object, ball, 0, 3) == 0);
}

TEST_CASE("a union of parts turned differently, or beside an unturned ball, is boxed part by part", "[convex-bound][box]") {
    // A trial: min(box(M p), box(N (p − c))) and min(box(M p), ball) got no box: the rotated analysis of the whole
    // leaves the other part's coordinates unbounded. The points of a union are those of some operand: the hull of
    // the operands' boxes, each by the analysis that closes it.
    const double M[3][3] = {{0.7648421872844885, 0.2508701838500143, 0.5933637833613874},
                            {0.0, 0.9210609940028851, -0.3894183423086505},
                            {-0.644217687237691, 0.2978435767000479, 0.7044663052755917}};
    const double N[3][3] = {{0.39806804630419473, -0.8912073600614354, -0.21746556482323487},
                            {0.7821080382182704, 0.4535961214255773, -0.42726756860548354},
                            {0.479425538604203, 0.0, 0.8775825618903728}};
    auto matrix = [](const double A[3][3]) {
        return fmt::format("[{} {} {}; {} {} {}; {} {} {}]", A[0][0], A[0][1], A[0][2], A[1][0], A[1][1], A[1][2], A[2][0],
                           A[2][1], A[2][2]);
    };
    const std::string box_fn =
        "box(x, b) = ‖max(|x| - b, 0)‖ + min(max((|x| - b)_1, (|x| - b)_2, (|x| - b)_3), 0) where x ∈ ℝ³, b ∈ ℝ³\n";
    // The extent along k of a box of half-sizes h turned by A (p = Aᵀ q + c), centred at c.
    auto extent = [](const double A[3][3], const std::array<double, 3>& h, size_t k) {
        double e = 0;
        for (size_t j = 0; j < 3; ++j) e += std::fabs(A[j][k]) * h[j];
        return e;
    };
    const std::array<double, 3> h1 = {1, 0.2, 0.3}, h2 = {0.2, 0.9, 0.2}, c2 = {0.5, 0.5, 0};
    {
        ir::Module m;
        auto [object, flat] = shape(m,
                                    "shape\n" + box_fn + "D = min(box(" + matrix(M) + " p, (1, 0.2, 0.3)), box(" + matrix(N) +
                                        " (p - (0.5, 0.5, 0)), (0.2, 0.9, 0.2)))\nwhere\np ∈ ℝ³\n",
                                    "union2");
        (void)flat;
        auto box = ir::support_box(m, object, 0, {{}}, 0);
        REQUIRE(box);
        for (size_t k = 0; k < 3; ++k) {
            const double lo = std::min(-extent(M, h1, k), c2[k] - extent(N, h2, k));
            const double hi = std::max(extent(M, h1, k), c2[k] + extent(N, h2, k));
            INFO("axis " << k << ": [" << box->lo[k] << ", " << box->hi[k] << "] for [" << lo << ", " << hi << "]");
            CHECK(box->lo[k] <= lo);
            CHECK(box->hi[k] >= hi);
            CHECK(box->lo[k] >= lo - 0.01);
            CHECK(box->hi[k] <= hi + 0.01);
        }
        CHECK(inside_beyond(m, object, *box, 0, 3) == 0);
    }
    {
        ir::Module m;
        auto [object, flat] = shape(m,
                                    "shape\n" + box_fn + "D = min(box(" + matrix(M) + " p, (1, 0.2, 0.3)), ‖p - (2, 0, 0)‖ - 0.5)\n"
                                                         "where\np ∈ ℝ³\n",
                                    "mixed");
        (void)flat;
        auto box = ir::support_box(m, object, 0, {{}}, 0);
        REQUIRE(box);
        CHECK(box->hi[0] >= 2.5);
        CHECK(box->hi[0] <= 2.51);
        for (size_t k = 1; k < 3; ++k) {
            CHECK(box->hi[k] >= std::max(extent(M, h1, k), 0.5));
            CHECK(box->lo[k] <= -std::max(extent(M, h1, k), 0.5));
        }
        CHECK(inside_beyond(m, object, *box, 0, 4) == 0);
    }
    // Through a rounding or a scale of the union (a trial): k·min(…) + c is ≤ 0 where the union is ≤ −c/k.
    for (const char* outer : {"min({}, {}) - 0.3", "0.5 min({}, {}) - 0.15", "(min({}, {}) - 0.6)/2 + 0.15"}) {
        INFO(outer);
        ir::Module m;
        const std::string d = fmt::format(fmt::runtime(outer), "box(" + matrix(M) + " p, (1, 0.2, 0.3))", "‖p - (2, 0, 0)‖ - 0.5");
        auto [object, flat] = shape(m, "shape\n" + box_fn + "D = " + d + "\nwhere\np ∈ ℝ³\n", "rounded");
        (void)flat;
        auto box = ir::support_box(m, object, 0, {{}}, 0);
        REQUIRE(box);
        CHECK(box->hi[0] >= 2.8);  // the ball's side, 0.3 further
        CHECK(box->hi[0] <= 2.82);
        for (size_t k = 0; k < 3; ++k) {
            CHECK(std::isfinite(box->lo[k]));
            CHECK(std::isfinite(box->hi[k]));
        }
        CHECK(inside_beyond(m, object, *box, 0, 4) == 0);
    }
}
