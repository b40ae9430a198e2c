// Analytic gradients (ir/passes/Differentiate) against central differences of the double-precision
// evaluator: the angle between them, over random points and points near each surface.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>

#include "TestUtil.h"
#include "ir/passes/Differentiate.h"
#include "scene/Modules.h"

using namespace iqc;
using namespace iqc::test;

namespace {

struct Angles {
    std::vector<double> deg;
    double median() { std::sort(deg.begin(), deg.end()); return deg[deg.size() / 2]; }
    double p99() { std::sort(deg.begin(), deg.end()); return deg[size_t(double(deg.size() - 1) * 0.99)]; }
};

// Differentiates a shape module and compares its gradient with central differences (h = 1e-6) at n points.
Angles gradient_angles(const std::string& src, int n, double box = 2.0) {
    SourceManager sm;
    Diagnostics d(sm);
    FileId f = sm.add("shape.iql", src);
    ModuleSource ms{"shape", f, {{0, uint32_t(src.size())}}, {f, 0, 1}, "test"};
    ModuleLibrary lib(sm, d, {});
    auto m = lib.parse_check(ms, "shape", false);
    INFO(d.render());
    REQUIRE(m->ok);
    ir::Module irm;
    LowerContext ctx{irm, {}, {}};
    int fn = lower_module(*m, "shape", "shape", ctx);
    std::string why;
    int g = ir::differentiate(irm, fn, 0, "shape_gradient", &why);
    INFO(why);
    REQUIRE(g >= 0);
    REQUIRE(ir::verify(irm.functions[size_t(g)], irm) == "");
    std::vector<ir::Value> args;
    for (const auto& p : m->params) args.push_back({p.type, p.value});
    auto D = [&](double x, double y, double z) {
        args[0] = {Type::vector(3), {x, y, z}};
        return ir::evaluate(irm, fn, args).v[0];
    };
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-box, box);
    Angles a;
    const double h = 1e-6;
    for (int i = 0; i < n; ++i) {
        double x = u(rng), y = u(rng), z = u(rng);
        // Every other point is moved close to the surface along the gradient (damped Newton steps: landing
        // exactly on an edge of a box would compare a subgradient with the differences' average).
        if (i % 2)
            for (int k = 0; k < 4; ++k) {
                args[0] = {Type::vector(3), {x, y, z}};
                auto gv = ir::evaluate(irm, g, args).v;
                double dd = D(x, y, z), l2 = gv[0] * gv[0] + gv[1] * gv[1] + gv[2] * gv[2];
                if (l2 < 1e-20) break;
                x -= 0.9 * dd * gv[0] / l2, y -= 0.9 * dd * gv[1] / l2, z -= 0.9 * dd * gv[2] / l2;
            }
        args[0] = {Type::vector(3), {x, y, z}};
        auto ga = ir::evaluate(irm, g, args).v;
        double fd[3] = {(D(x + h, y, z) - D(x - h, y, z)) / (2 * h), (D(x, y + h, z) - D(x, y - h, z)) / (2 * h),
                        (D(x, y, z + h) - D(x, y, z - h)) / (2 * h)};
        double la = std::sqrt(ga[0] * ga[0] + ga[1] * ga[1] + ga[2] * ga[2]);
        double lf = std::sqrt(fd[0] * fd[0] + fd[1] * fd[1] + fd[2] * fd[2]);
        if (la < 1e-9 || lf < 1e-9) continue;  // on a medial axis: no direction to compare
        double c = (ga[0] * fd[0] + ga[1] * fd[1] + ga[2] * fd[2]) / (la * lf);
        a.deg.push_back(std::acos(std::clamp(c, -1.0, 1.0)) * 180.0 / M_PI);
    }
    INFO("shape: " << src);
    REQUIRE(a.deg.size() > size_t(n * 8 / 10));
    return a;
}

}  // namespace

TEST_CASE("analytic gradients agree with central differences of the evaluator", "[differentiate]") {
    const char* shapes[] = {
        // sphere, torus, box, box frame (min/max/abs), capsule-like (clamp), a smooth union (mix, exp),
        // twisted (sin/cos of p), a piecewise field, and a normalize/cross/dot mixture.
        "shape\nD = ‖p‖ - r\nwhere\np ∈ ℝ³\nr ∈ ℝ default = 1\n",
        "shape\nD = ‖q‖ - t_2\nq = (‖(p_1, p_3)‖ - t_1, p_2)\nwhere\np ∈ ℝ³\nt ∈ ℝ² default = (0.8, 0.3)\n",
        "shape\nD = ‖(max(q_1, 0), max(q_2, 0), max(q_3, 0))‖ + min(max(q_1, q_2, q_3), 0)\nq = (|p_1|, |p_2|, |p_3|) - b\n"
        "where\np ∈ ℝ³\nb ∈ ℝ³ default = (0.5, 0.7, 0.3)\n",
        "shape\nD = min(‖(max(0, `p'`_1), max(0, q_2), max(0, q_3))‖ + min(max(`p'`_1, q_2, q_3),0), ‖(max(0, q_1), "
        "max(0, `p'`_2), max(0, q_3))‖ + min(max(q_1, `p'`_2, q_3),0), ‖(max(0, q_1), max(0, q_2), max(0, `p'`_3))‖ + "
        "min(max(q_1, q_2, `p'`_3),0))\n`p'` = (|p_1|, |p_2|, |p_3|) - b\nq = (|`p'`_1 + e| - e, |`p'`_2 + e| - e, "
        "|`p'`_3 + e| - e)\nwhere\np ∈ ℝ³\nb ∈ ℝ³ default = (1, 1, 1)\ne ∈ ℝ default = 0.1\n",
        "shape\nD = ‖p - (0, h, 0)‖ - r\nh = clamp(p_2, 0, 1)\nwhere\np ∈ ℝ³\nr ∈ ℝ default = 0.3\n",
        "shape\nD = -ln(exp(-k a) + exp(-k b))/k\na = ‖p‖ - 1\nb = ‖p - (1, 0, 0)‖ - 0.6\nwhere\np ∈ ℝ³\nk ∈ ℝ default = 8\n",
        "shape\nsin, cos from trigonometry\nD = ‖(c q_1 - s q_3, q_2, s q_1 + c q_3)‖ - 1\nc = cos(0.5p_2)\ns = sin(0.5p_2)\n"
        "q = p\nwhere\np ∈ ℝ³\n",
        "shape\nD = { ‖p‖ - 1 if p_2 > 0\n    ‖p - (0, -0.5, 0)‖ - 0.8 otherwise\nwhere\np ∈ ℝ³\n",
        "shape\nD = n⋅p - 0.2 + 0.1(p × (0, 0, 1))⋅(1, 1, 0)\nn = normalize(a)\nwhere\np ∈ ℝ³\na ∈ ℝ³ default = (1, 2, 2)\n",
        // Quilez's elongation: the query point clamped per component (a clamp of vectors, with scalar and
        // vector bounds).
        "shape\nD = ‖(‖(q_1, q_3)‖ - 0.6, q_2)‖ - 0.2\nq = p - clamp(p, -h, h)\nwhere\np ∈ ℝ³\nh ∈ ℝ³ default = (0.8, 0, 0.3)\n",
        "shape\nD = ‖p - clamp(p, -0.5, 0.5)‖ - 0.2\nwhere\np ∈ ℝ³\n",
        // clamp with lo > hi (min(max(x, lo), hi) = hi) and mod with a varying modulus (∂x - ⌊x/y⌋∂y): both
        // were wrong (a soundness trial).
        "shape\nD = clamp(-5, 2 + 0.1p_1, 3p_2) + 0.2p_3\nwhere\np ∈ ℝ³\n",
        "shape\nD = 6mod(2.5 + 0.1p_1, 1 + 0.1p_2) + 0.1p_3\nwhere\np ∈ ℝ³\n",
        // Recurrences (the tangent rule for the IR's loop): a fold, a scale carried as a state, and a state
        // updated by a piecewise step (the loop's body has lazy arms).
        "shape\nq_1 = p\nq_(k+1) = (|q_k_1|, |q_k_2|, |q_k_3|) - 0.4(1, 1, 1) for k ∈ 1..3\nD = ‖q_4‖ - 0.3\nwhere\np ∈ ℝ³\n",
        "shape\nsin from trigonometry\nz_1 = p\ns_1 = 1\nz_(k+1) = 1.3z_k + 0.2(sin(2z_k_2), sin(2z_k_3), sin(2z_k_1)) for k ∈ 1..4\n"
        "s_(k+1) = 1.3s_k for k ∈ 1..4\nD = (‖z_5‖ - 1)/s_5\nwhere\np ∈ ℝ³\n",
        "shape\nw_1 = p\nw_(k+1) = { w_k if ‖w_k‖ > 3\n            w_k + 0.3(w_k_2, w_k_3, w_k_1) otherwise for k ∈ 1..3\nD = ‖w_4‖ - 1\nwhere\np ∈ ℝ³\n",
    };
    const char* weights[] = {
        // mix with a weight per component: a constant broadcast (0.3 of mix(p, 2p, 0.3)) and one that varies
        // with p (a new user's trial, stop 39: "mix with a vector weight" had no rule)
        "shape\nD = ‖mix(p, 2p, 0.3)‖ - 0.5\nwhere\np ∈ ℝ³\n",
        "shape\nD = ‖mix(p, (1, 2, 0.5), w)‖ - 0.5\nw = (0.3, 0.5 + 0.1p_1, 0.2p_3)\nwhere\np ∈ ℝ³\n",
    };
    for (const char* s : weights) {
        Angles a = gradient_angles(s, 400);
        INFO(s << "\nmedian " << a.median() << "°, p99 " << a.p99() << "°");
        CHECK(a.median() <= 0.01);
    }
    for (const char* s : shapes) {
        Angles a = gradient_angles(s, 400);
        INFO(s << "\nmedian " << a.median() << "°, p99 " << a.p99() << "°");
        CHECK(a.median() <= 0.01);
    }
}

TEST_CASE("analytic normals through recurrences: the loop carries each state's tangent", "[differentiate]") {
    // Fractals (a fold, the Menger sponge) had no analytic normal: the gradient stopped at the IR's loop and the
    // runtime fell back to tetrahedron differences, with a warning. The loop's tangent rule makes a loop of
    // the states and their tangents (forward mode).
    Compiled a = compile_text("folded_analytic.md",
                              "❤: folded\n```iheartla\nshape\nq_1 = p\nq_(k+1) = (|q_k_1|, |q_k_2|, |q_k_3|) - 0.4(1, 1, 1) for k ∈ 1..3\n"
                              "D = ‖q_4‖ - 0.3\nwhere\np ∈ ℝ³\n```\n```scene\n[render]\nnormals = \"analytic\"\n[[shapes]]\ntype = \"folded\"\n```\n");
    REQUIRE(a.result.exit_code == 0);
    CHECK_THAT(a.diagnostics, !Catch::Contains("no analytic normal here"));
    CHECK_THAT(a.result.code, Catch::Contains("vec3 iqc_gradient(vec3 p, int id) {"));
    CHECK_THAT(a.result.code, Catch::Contains("mat3 d_q = "));  // the tangent state
    Compiled menger = compile_text("menger_analytic.iq", "[render]\nnormals = \"analytic\"\n[[shapes]]\ntype = \"menger\"\n");
    REQUIRE(menger.result.exit_code == 0);
    CHECK_THAT(menger.diagnostics, !Catch::Contains("no analytic normal here"));
    const SceneModel& model = *a.result.model;
    int id = -1;
    model.distance({0, 0, 0}, &id);
    CHECK(id == 0);
}
