// The interval extension as IR (ir/passes/IntervalExtension.h), run by the double-precision evaluator: for
// every standard-library shape and the bench's non-Lipschitz fields, the extension of the distance and of
// its gradient over random boxes holds every value sampled inside the box (soundness), is a point where the
// box is a point (tightness: the extension is not [-1e30, 1e30]), and narrows as the box shrinks.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <random>

#include "TestUtil.h"
#include "ir/Builder.h"
#include "ir/Eval.h"
#include "ir/passes/Differentiate.h"
#include "ir/passes/IntervalExtension.h"
#include "ir/passes/Stable.h"
#include "scene/Modules.h"

using namespace iqc;
namespace fs = std::filesystem;

namespace {

struct Extended {
    ir::Module m;
    int value = -1, gradient = -1;           // q -> D(q), q -> ∇D(q)
    int value_box = -1, gradient_box = -1;   // (lo, hi) -> (lo, hi) of each, as one vector
    bool jumps = false;                      // the distance has operations with jumps (widened arguments)
    std::string why;
};

// A function (lo, hi ∈ ℝ³) -> (the result's lo, then its hi) of fn's interval extension over the box.
int extension_of(ir::Module& m, int fn, std::string* why, bool* jumps = nullptr) {
    ir::Function e;
    e.name = m.functions[size_t(fn)].name + "_box";
    e.entry = true;
    ir::Builder b(m, e);
    ir::ValueId lo = b.param("lo", Type::vector(3)), hi = b.param("hi", Type::vector(3));
    ir::IntervalCode c = ir::emit_interval_extension(b, m, fn, 0, lo, hi, {lo});
    if (!c.ok) {
        *why = c.why;
        return -1;
    }
    if (jumps) *jumps = c.continuous != ir::ValueId(-1);
    const Type& t = m.functions[size_t(fn)].result_type();
    e.result = b.construct(Type::vector(2 * t.components()), {c.lo, c.hi});
    m.functions.push_back(std::move(e));
    return int(m.functions.size()) - 1;
}

// Shape module `text` at its defaults as q -> D(q), its gradient, and both extensions.
std::unique_ptr<Extended> extend_shape(const std::string& text, const std::string& name) {
    auto out = std::make_unique<Extended>();
    out->value = test::lower_shape_object(out->m, text, name);
    if (out->value < 0) return nullptr;
    ir::rewrite_unstable_forms(out->m);
    out->gradient = ir::differentiate(out->m, out->value, 0, "object_gradient", &out->why);
    if (out->gradient < 0) return out;
    out->value_box = extension_of(out->m, out->value, &out->why, &out->jumps);
    out->gradient_box = extension_of(out->m, out->gradient, &out->why);
    REQUIRE(ir::verify(out->m) == "");
    return out;
}

ir::Value vec3(double x, double y, double z) { return {Type::vector(3), {x, y, z}}; }

struct Check {
    int boxes = 0, samples = 0;
    double worst_point_width = 0;  // the widest interval at a point box
};

// Random boxes around [-2, 2]³ of widths 0.5, 0.05 and 0 (a point): every sample inside lies in the
// extension's interval (with 1e-9 of slack for rounding).
Check check_sound(const Extended& x, int fn, int box_fn, const std::string& name, uint32_t seed) {
    Check c;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-2, 2), v(0, 1);
    ir::EvalInputs in;
    for (double width : {0.5, 0.05, 0.0}) {
        for (int k = 0; k < 60; ++k) {
            double lo[3], hi[3];
            for (int i = 0; i < 3; ++i) {
                lo[i] = u(rng);
                hi[i] = lo[i] + width * v(rng);
            }
            ir::Value r = ir::evaluate(x.m, box_fn, {vec3(lo[0], lo[1], lo[2]), vec3(hi[0], hi[1], hi[2])}, in);
            size_t n = r.v.size() / 2;
            ++c.boxes;
            for (int s = 0; s < (width > 0 ? 12 : 1); ++s) {
                double p[3];
                for (int i = 0; i < 3; ++i) p[i] = lo[i] + (hi[i] - lo[i]) * (s == 0 ? 0.5 : v(rng));
                ir::Value g = ir::evaluate(x.m, fn, {vec3(p[0], p[1], p[2])}, in);
                REQUIRE(g.v.size() == n);
                for (size_t j = 0; j < n; ++j) {
                    if (!std::isfinite(g.v[j])) continue;
                    double slack = 1e-9 * (1 + std::fabs(g.v[j]));
                    INFO(name << " component " << j << " at (" << p[0] << ", " << p[1] << ", " << p[2] << ") box ["
                              << lo[0] << ", " << hi[0] << "]×[" << lo[1] << ", " << hi[1] << "]×[" << lo[2] << ", " << hi[2]
                              << "]: value " << g.v[j] << ", interval [" << r.v[j] << ", " << r.v[n + j] << "]");
                    CHECK(r.v[j] <= g.v[j] + slack);
                    CHECK(r.v[n + j] >= g.v[j] - slack);
                    if (width == 0) c.worst_point_width = std::max(c.worst_point_width, r.v[n + j] - r.v[j]);
                }
                ++c.samples;
            }
        }
    }
    return c;
}

const char* kDisplacedTorus = R"(shape
sin from trigonometry
D = ‖q‖ - 0.35 + a sin(f p_1) sin(f p_2) sin(f p_3)
q = (‖(p_1, p_3)‖ - 1, p_2)
where
p ∈ ℝ³
a ∈ [0, 0.3] default = 0.12: displacement amplitude
f ∈ [1, 60] default = 35: displacement frequency
)";

const char* kTwistedBar = R"(shape
twist from domain
D = ‖max(|twist(p, k)| - b, 0)‖ + min(max(|twist(p, k)_1| - b_1, |twist(p, k)_2| - b_2, |twist(p, k)_3| - b_3), 0)
where
p ∈ ℝ³
k ∈ [0, 5] default = 2.2: twist, radians per unit of height
b ∈ ℝ³ default = (0.3, 1.5, 0.3): half-extents of the bar
)";

}  // namespace

TEST_CASE("interval extension of distances and gradients: sound on random boxes, exact at points", "[interval-extension]") {
    fs::path root(IQC_SOURCE_DIR);
    std::vector<std::pair<std::string, std::string>> shapes = {{"displaced_torus", kDisplacedTorus}, {"twisted_bar", kTwistedBar}};
    for (auto& e : fs::directory_iterator(root / "stdlib"))
        if (e.path().extension() == ".iql") shapes.push_back({e.path().stem().string(), test::read_text(e.path())});
    std::sort(shapes.begin() + 2, shapes.end());
    int extended = 0;
    std::vector<std::string> refused;
    uint32_t seed = 1;
    for (const auto& [name, text] : shapes) {
        auto x = extend_shape(text, name);
        if (!x) continue;  // not a shape module
        if (x->value_box < 0 || x->gradient_box < 0) {
            refused.push_back(name + ": " + x->why);
            continue;
        }
        ++extended;
        Check v = check_sound(*x, x->value, x->value_box, name + " (distance)", seed++);
        Check g = check_sound(*x, x->gradient, x->gradient_box, name + " (gradient)", seed++);
        INFO(name);
        // Functions with jumps have their arguments widened (10⁻⁵ of their magnitude): not points there.
        if (!x->jumps) {
            CHECK(v.worst_point_width < 1e-9);
            CHECK(g.worst_point_width < 1e-6);
        }
    }
    INFO(fmt::format("refused: {}", fmt::join(refused, "; ")));
    // Only recurrences (a loop: mandelbulb, menger) and what has no interval rule may be refused.
    CHECK(extended >= 40);
    for (const auto& r : refused) CHECK((r.find("a loop") != std::string::npos || r.find("no interval rule") != std::string::npos));
}

TEST_CASE("interval extension narrows with the box: the displaced torus's gradient along a ray", "[interval-extension]") {
    auto x = extend_shape(kDisplacedTorus, "displaced_torus");
    REQUIRE(x);
    REQUIRE(x->gradient_box >= 0);
    // A box of width w around (1.2, 0.4, 0.3) (away from the tube's axis, where ‖q‖ = 0): the interval's width
    // falls with w (about linearly: the gradient is smooth there).
    double last = 1e30;
    for (double w : {0.3, 0.1, 0.01, 0.001}) {
        ir::Value r = ir::evaluate(x->m, x->gradient_box, {vec3(1.2 - w, 0.4 - w, 0.3 - w), vec3(1.2 + w, 0.4 + w, 0.3 + w)});
        double width = 0;
        for (size_t j = 0; j < 3; ++j) width = std::max(width, r.v[3 + j] - r.v[j]);
        INFO("w = " << w << ": widest component " << width);
        CHECK(width < last);
        if (w <= 0.01) CHECK(width < 400 * w);  // ∂²D is at most a f² √3 ≈ 255 here
        last = width;
    }
}

TEST_CASE("interval extension: where a floor, fract, sign or a piecewise choice may jump within the box", "[interval-extension]") {
    // The voxel sphere (‖⌊n p⌋/n + 0.5/n‖ - r, a "voxel look") is constant within a cell and jumps between cells:
    // its gradient is 0 everywhere it exists, so a gain from the gradient alone skipped the whole sphere (a new
    // user's trial). The extension says where the box holds a jump.
    const char* text = R"(shape
D = ‖⌊n p⌋/n + (0.5/n)(1, 1, 1)‖ - r + 0.1 sign(p_1 - 3) + { 0.2 if p_2 > 5
                                                             0 otherwise
where
p ∈ ℝ³
n ∈ [1, 32] default = 8: voxels per unit
r ∈ [0, 2] default = 1: radius
)";
    auto x = extend_shape(text, "jumps");
    REQUIRE(x);
    ir::Function e;
    e.name = "continuous";
    e.entry = true;
    {
        ir::Builder b(x->m, e);
        ir::ValueId lo = b.param("lo", Type::vector(3)), hi = b.param("hi", Type::vector(3));
        ir::IntervalCode c = ir::emit_interval_extension(b, x->m, x->value, 0, lo, hi, {lo});
        REQUIRE(c.ok);
        REQUIRE(c.continuous != ir::ValueId(-1));
        e.result = b.op(ir::Op::Select, {c.continuous, b.scalar(1), b.scalar(0)});
    }
    x->m.functions.push_back(std::move(e));
    int fn = int(x->m.functions.size()) - 1;
    REQUIRE(ir::verify(x->m) == "");
    auto continuous = [&](ir::Value lo, ir::Value hi) { return ir::evaluate(x->m, fn, {lo, hi}).v[0] == 1; };
    // Within one cell of 1/8 (and away from x = 3 and y = 5): continuous.
    CHECK(continuous(vec3(0.51, 0.26, 0.76), vec3(0.62, 0.37, 0.87)));
    // Across a cell's face in x, y or z: not.
    CHECK_FALSE(continuous(vec3(0.45, 0.26, 0.76), vec3(0.55, 0.37, 0.87)));
    CHECK_FALSE(continuous(vec3(0.51, 0.2, 0.76), vec3(0.62, 0.3, 0.87)));
    CHECK_FALSE(continuous(vec3(0.51, 0.26, 0.74), vec3(0.62, 0.37, 0.76)));
    // Across sign's jump at x = 3, or the piecewise choice's at y = 5 (cells of the floor held fixed).
    CHECK_FALSE(continuous(vec3(2.9, 0.26, 0.76), vec3(3.1, 0.37, 0.87)));
    CHECK_FALSE(continuous(vec3(0.51, 4.9, 0.76), vec3(0.62, 5.1, 0.87)));
    // A smooth shape has no condition at all.
    auto torus = extend_shape(kDisplacedTorus, "displaced_torus");
    ir::Function t;
    ir::Builder tb(torus->m, t);
    ir::ValueId lo = tb.param("lo", Type::vector(3)), hi = tb.param("hi", Type::vector(3));
    CHECK(ir::emit_interval_extension(tb, torus->m, torus->value, 0, lo, hi, {lo}).continuous == ir::ValueId(-1));
}

TEST_CASE("interval extension: a gradient's unit vector v/‖v‖ stays a unit vector near a box's face", "[interval-extension][segment]") {
    // ∂‖v‖/∂v = v/‖v‖. As an interval product, v's interval times 1/‖v‖'s forgets that the result has length
    // 1: just outside a box's face, max(|q| - b, 0) = (x - b_x, 0, 0) with x - b_x in [0.001, 0.01] gave
    // the normal's first component [0.1, 10] (and segment tracing took sphere-tracing steps along a twisted
    // bar). Each component is bounded as v_k/√(v_k² + R²), R the other components' length, at its ends.
    auto x = extend_shape(test::read_text(std::filesystem::path(IQC_SOURCE_DIR) / "stdlib" / "box.iql"), "box");
    REQUIRE(x);
    REQUIRE(x->gradient_box >= 0);
    // The box's half-extents are (1, 0.6, 0.8) at its defaults (stdlib/box.iql): a box over [1.001, 1.01] in x.
    ir::Value r = ir::evaluate(x->m, x->gradient_box, {vec3(1.001, -0.1, -0.2), vec3(1.01, 0.2, 0.1)});
    INFO("x in [" << r.v[0] << ", " << r.v[3] << "], y in [" << r.v[1] << ", " << r.v[4] << "], z in [" << r.v[2] << ", " << r.v[5] << "]");
    CHECK(r.v[0] > 0.9999);
    CHECK(r.v[3] < 1.0001);
    for (int k : {1, 2}) CHECK((r.v[size_t(k)] == 0 && r.v[size_t(3 + k)] == 0));
    // Over a corner region (two components positive) each component stays within [0, 1] where an interval
    // product gave up to 1/0.001.
    r = ir::evaluate(x->m, x->gradient_box, {vec3(1.001, 0.601, -0.2), vec3(1.5, 1.1, 0.1)});
    for (int k : {0, 1}) {
        CHECK(r.v[size_t(k)] >= 0);
        CHECK(r.v[size_t(3 + k)] <= 1);
        CHECK(r.v[size_t(3 + k)] > 0.99);  // still sound: (0.5, 0.001) beyond the edge points almost along x
    }
}
