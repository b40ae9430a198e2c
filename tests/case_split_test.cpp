// Case splitting for interval arithmetic (ir/CaseSplit.h) on distances: for every standard-library shape the
// lowest value over the cases of a box is never above a distance sampled in it (sound) and never below one
// pass's hull (no worse), and on the octahedron, whose three cases the hull loses, it proves the half-spaces
// beyond its vertices free where one pass cannot.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>

#include "TestUtil.h"
#include "ir/CaseSplit.h"
#include "ir/Eval.h"
#include "ir/Intervals.h"
#include "ir/passes/Inline.h"

using namespace iqc;
namespace fs = std::filesystem;

namespace {

// Shape module `text` at its parameters' defaults, q -> D(q) with its calls inlined (the form case splitting
// takes apart), added to `m`: its index, or -1 for a module that is not a shape.
int flat_shape(ir::Module& m, const std::string& text, const std::string& name) {
    const int object = test::lower_shape_object(m, text, name);
    if (object < 0) return -1;
    ir::Function flat = ir::inline_calls(m, m.functions[size_t(object)]);
    flat.name = "object_flat";
    m.functions.push_back(std::move(flat));
    return int(m.functions.size()) - 1;
}

// The distance's lowest value over the box: one pass (the hull), and by case splitting.
double hull_lowest(const ir::Module& m, const ir::Function& f, const std::vector<ir::Interval>& box) {
    auto r = ir::interval_analysis(m, f, {box});
    double lo = r[f.result].c[0].lo;
    return std::isnan(lo) ? -INFINITY : lo;
}
double split_lowest(const ir::Module& m, const ir::Function& f, const std::vector<ir::Interval>& box, int passes = 64) {
    ir::CaseSplitOptions o;
    o.query_point = false;
    double worst = ir::case_split_bound(
        m, f, {box},
        [](const ir::Bounds& r) {
            double lo = r.c.empty() ? -INFINITY : r.c[0].lo;
            return std::isnan(lo) ? INFINITY : -lo;
        },
        passes, o);
    return -worst;
}

}  // namespace

TEST_CASE("case splitting on distances: sound and no worse than the hull on every standard-library shape", "[case-split]") {
    fs::path root(IQC_SOURCE_DIR);
    std::vector<fs::path> files;
    for (auto& e : fs::directory_iterator(root / "stdlib"))
        if (e.path().extension() == ".iql") files.push_back(e.path());
    std::sort(files.begin(), files.end());
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-1.5, 1.5), v(0, 1);
    int shapes = 0, tighter = 0;
    for (const auto& path : files) {
        ir::Module m;
        const int fn = flat_shape(m, test::read_text(path), path.stem().string());
        if (fn < 0) continue;
        const ir::Function* f = &m.functions[size_t(fn)];
        ++shapes;
        ir::Evaluator ev(m, {});
        bool improved = false;
        for (int k = 0; k < 40; ++k) {
            const double w = k % 2 ? 0.6 : 0.1;
            std::vector<ir::Interval> box(3);
            for (auto& c : box) {
                c.lo = u(rng);
                c.hi = c.lo + w;
            }
            const double hull = hull_lowest(m, *f, box), split = split_lowest(m, *f, box);
            INFO(path.stem().string() << " box [" << box[0].lo << ", " << box[0].hi << "] × [" << box[1].lo << ", "
                                      << box[1].hi << "] × [" << box[2].lo << ", " << box[2].hi << "]: hull " << hull
                                      << ", split " << split);
            CHECK(split >= hull);
            improved |= split > hull + 1e-9;
            double least = INFINITY;
            for (int s = 0; s < 64; ++s) {
                ir::Value q{Type::vector(3), {}};
                for (auto& c : box) q.v.push_back(c.lo + (s == 0 ? 0 : s == 1 ? 1 : v(rng)) * (c.hi - c.lo));
                least = std::min(least, ev.call(fn, {q}).v[0]);
            }
            CHECK(split <= least + 1e-9 * (1 + std::fabs(least)));
        }
        tighter += improved;
    }
    CHECK(shapes >= 40);
    CHECK(tighter >= 5);  // the shapes with piecewise choices (octahedron, pyramid, the _ab cones, ...)
}

TEST_CASE("case splitting proves the octahedron's far half-spaces free, where the hull of its three cases cannot",
          "[case-split]") {
    ir::Module m;
    const int fn = flat_shape(m, test::read_text(fs::path(IQC_SOURCE_DIR) / "stdlib" / "octahedron.iql"), "octahedron");
    REQUIRE(fn >= 0);
    const ir::Function* f = &m.functions[size_t(fn)];
    // Beyond x = 2 (the vertices at distance 1), the other axes unbounded: the distance there is at least
    // (2 − 1)/√3 (the face planes'), but the hull of q's permutations of |p| lets ‖(q₁, q₂ − s + k, q₃ − k)‖ reach 0.
    std::vector<ir::Interval> beyond = {{2, INFINITY}, {-INFINITY, INFINITY}, {-INFINITY, INFINITY}};
    CHECK(hull_lowest(m, *f, beyond) <= 0);
    CHECK(split_lowest(m, *f, beyond) > 0.5);
    // A box around a vertex: the cases give a positive bound near the true distance, the hull does not.
    std::vector<ir::Interval> corner = {{1.2, 1.3}, {-0.1, 0.1}, {-0.1, 0.1}};
    CHECK(hull_lowest(m, *f, corner) <= 0);
    const double split = split_lowest(m, *f, corner);
    CHECK(split > 0);
    CHECK(split <= 0.2);  // the distance at (1.2, 0, 0) is 0.2
    // Too few passes to reach the cases: the hull's value, no more.
    CHECK(split_lowest(m, *f, beyond, 1) == hull_lowest(m, *f, beyond));
    // A target reached: the search stops with a value at least the target (here: the box is inside).
    ir::CaseSplitOptions o;
    o.query_point = false;
    o.target = 0;
    int left = 0;
    double r = ir::case_split_bound(
        m, *f, {{{-0.1, 0.1}, {-0.1, 0.1}, {-0.1, 0.1}}}, [](const ir::Bounds& b) { return -b.c[0].lo; }, 64, o, &left);
    CHECK(r >= 0);
    CHECK(left >= 60);  // one pass and a stop, not all 64
}

TEST_CASE("case splitting keeps the case a NaN takes: a comparison of a logarithm is false both ways below 0",
          "[case-split]") {
    // l = log(p₂) is NaN below y = 0, where l > 0 and l ≤ 0 are both false and the `otherwise` ball at
    // (0, −1.5, 0) is drawn. Taking "l > 0 false" for "l ≤ 0" dropped that ball from the scene's box (a trial:
    // the box's floor at y = 0.19, the ball gone), and likewise for 0/0.
    const std::string text = "shape\nl = log(p_2)\n"
                             "D = { ‖p - (0, 2, 0)‖ - 0.5 if l > 0\n"
                             "      ‖p - (1, 0.5, 0)‖ - 0.3 if l ≤ 0\n"
                             "      ‖p - (0, -1.5, 0)‖ - 0.5 otherwise\n"
                             "where\np ∈ ℝ³\n";
    ir::Module m;
    const int fn = flat_shape(m, text, "nan_pick");
    REQUIRE(fn >= 0);
    const ir::Function* f = &m.functions[size_t(fn)];
    // Around the ball below: its centre's distance is −0.5.
    std::vector<ir::Interval> below = {{-0.2, 0.2}, {-1.7, -1.3}, {-0.2, 0.2}};
    CHECK(split_lowest(m, *f, below) <= -0.5);
    CHECK(hull_lowest(m, *f, below) <= -0.5);
    // Where y > 0 the logarithm is a number, and the cases still prove what they can: above y = 3 nothing.
    std::vector<ir::Interval> above = {{-INFINITY, INFINITY}, {3, INFINITY}, {-INFINITY, INFINITY}};
    CHECK(split_lowest(m, *f, above) > 0);
    // The scene: its box reaches below the lower ball.
    const std::string scene = "[modules]\nnan_pick = \"\"\"\n" + text +
                              "\"\"\"\n[camera]\nposition = [0.5, 0.5, -7]\ntarget = [0, 0, 0]\n[[shapes]]\ntype = \"nan_pick\"\n";
    test::Compiled c = test::compile_text("nan_pick.iq", scene);
    INFO(c.diagnostics);
    REQUIRE(c.result.exit_code == 0);
    const std::string lo = "const vec3 IQC_BOX_LO = vec3(";
    size_t at = c.result.code.find(lo);
    REQUIRE(at != std::string::npos);
    std::string v = c.result.code.substr(at + lo.size());
    CHECK(std::stod(v.substr(v.find(',') + 1)) <= -2.0);
}
