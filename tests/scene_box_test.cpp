// The scene's box (SceneIR::box, from ir/Support.h's support_box): rays are clipped to where some instance's
// distance can come within the `bound` margin (0.1 here) of 0. The box must contain every such point (else
// pixels go missing), should be near the solid's true extent (else it saves little), and must be absent
// where the compiler cannot know it; clipping must change no pixel.
#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <optional>
#include <regex>

#include "TestUtil.h"

using namespace iqc;
using namespace iqc::test;

namespace {

using Vec = std::array<double, 3>;

// The box a shader was compiled with: IQC_BOX_LO / IQC_BOX_HI (vec3(x) or vec3(x, y, z); ±1e30: unbounded).
std::optional<std::pair<Vec, Vec>> box_of(const std::string& code) {
    auto read = [&](const char* name) -> std::optional<Vec> {
        std::smatch m;
        std::regex re(std::string("const vec3 ") + name + R"( = vec3\(([^)]*)\);)");
        if (!std::regex_search(code, m, re)) return std::nullopt;
        std::vector<double> v;
        std::string s = m[1];
        for (size_t at = 0; at < s.size();) {
            size_t comma = s.find(',', at);
            v.push_back(std::stod(s.substr(at, comma - at)));
            at = comma == std::string::npos ? s.size() : comma + 1;
        }
        if (v.size() == 1) v = {v[0], v[0], v[0]};
        REQUIRE(v.size() == 3);
        return Vec{v[0], v[1], v[2]};
    };
    auto lo = read("IQC_BOX_LO"), hi = read("IQC_BOX_HI");
    CHECK(lo.has_value() == hi.has_value());
    if (!lo || !hi) return std::nullopt;
    return std::make_pair(*lo, *hi);
}

std::string bench(const std::string& name) { return std::string(IQC_SOURCE_DIR) + "/bench/" + name; }

int differ_without_box(const CompileResult& c, int W, int H);  // below

// The shader with its marches starting at the camera, not where the ray enters the box (iqc_far's t_enter).
std::string from_camera(const std::string& code) {
    const std::string start = "    t_enter = max(t_in, 0.0);";
    REQUIRE(code.find(start) != std::string::npos);
    std::string out = code;
    out.replace(out.find(start), start.size(), "    t_enter = 0.0;");
    return out;
}

// The box's level where the camera is fixed (Shadertoy; Compile.cpp box_level, SceneLower scene_box): ten hit
// tolerances (0.01 at the default 1e-3), or where wider the step cap's pixel cone on 360 rows, far / (360 ·
// focal) with focal 1/tan(30°), at the box's farthest corner from the camera (taken 5% wider, as the compiler
// does). lo and hi: the shapes' own extent.
double fixed_level(std::array<double, 3> eye, std::array<double, 3> lo, std::array<double, 3> hi) {
    double m = 0.01;
    for (int round = 0; round < 3; ++round) {
        double far = 0;
        for (int corner = 0; corner < 8; ++corner) {
            double d2 = 0;
            for (int a = 0; a < 3; ++a) d2 += std::pow(((corner >> a) & 1 ? hi[a] + m : lo[a] - m) - eye[a], 2);
            far = std::max(far, std::sqrt(d2));
        }
        double need = far / (360 / std::tan(M_PI / 6));
        if (need <= m) break;
        m = 1.05 * need;
    }
    return m;
}

const std::string kBall =
    "[modules]\nball = \"\"\"\nshape\nD = ‖p‖ - r\nwhere\np ∈ ℝ³\nr ∈ [0,3] default = 1\n\"\"\"\n"
    "ground = \"\"\"\nshape\nD = p_2 + 1\nwhere\np ∈ ℝ³\n\"\"\"\n";

}  // namespace

TEST_CASE("the scene's box: a recurrence, a height field, rotated and moved shapes, slider ranges", "[scene][box]") {
    // The box's level (Compile.cpp box_level): ten hit tolerances, or the step cap's pixel cone on 360 rows
    // where wider: t / (rows · focal), focal 1/tan(30°) at the default field of view, at max_dist, or on Shadertoy
    // (a fixed camera) at the box's farthest point from the camera (fixed_level). On slider targets the camera
    // goes anywhere, and the cone is taken at max_dist; so it is where the box is open on a side.
    auto level = [](double max_dist) { return std::max(0.01, max_dist / (360 / std::tan(M_PI / 6))); };
    const double m_uniform = level(100);  // max_dist 100 (the default): 0.16
    // Ten hit tolerances, not the `bound` margin 0.1 (the hand-written sponge's box is ±1.01: iqc's ±1.1 cost 5%
    // of its frame).
    double m = fixed_level({2.2, 1.6, -2.6}, {-1, -1, -1}, {1, 1, 1});
    CHECK(m == 0.01);
    // The Menger sponge: a recurrence of four steps (intervals carried through the loop) inside |p| <= 1.
    Compiled sponge = compile_path(bench("fractal.iq"));
    REQUIRE(sponge.result.exit_code == 0);
    auto b = box_of(sponge.result.code);
    REQUIRE(b);
    for (int a = 0; a < 3; ++a) {
        CHECK(b->first[a] <= -1 - m);
        CHECK(b->first[a] >= -1 - m - 0.01);
        CHECK(b->second[a] >= 1 + m);
        CHECK(b->second[a] <= 1 + m + 0.01);
    }
    // y = 0.6 sin(3x) sin(3z), max_dist 30: a slab below y = 0.6 + the cone at max_dist (0.048), unbounded
    // elsewhere.
    Compiled terrain = compile_path(bench("sine_terrain.iq"));
    REQUIRE(terrain.result.exit_code == 0);
    b = box_of(terrain.result.code);
    REQUIRE(b);
    CHECK(b->second[1] >= 0.6 + level(30));
    CHECK(b->second[1] <= 0.61 + level(30));
    CHECK(b->first[1] == -1e30);
    for (int a : {0, 2}) {
        CHECK(b->first[a] == -1e30);
        CHECK(b->second[a] == 1e30);
    }
    // A ground (y <= -1), a ball at x = -2, a box turned about y, and a torus (0.8, 0.25) turned by 1 radian about x
    // at x = 2: the top is the torus's, its object box (±(1.05 + m), ±(0.25 + m), ±(1.05 + m)) turned into the world.
    // The ground leaves the box open below: no farthest point, so the cone is taken at max_dist (0.16).
    Compiled few = compile_path(bench("few_shapes.iq"));
    REQUIRE(few.result.exit_code == 0);
    b = box_of(few.result.code);
    REQUIRE(b);
    double top = std::sin(1.0) * (1.05 + m_uniform) + std::cos(1.0) * (0.25 + m_uniform);
    CHECK(b->second[1] >= top);
    CHECK(b->second[1] <= top + 0.01);
    CHECK(b->first[1] == -1e30);
    // Shadertoy: the ball's radius is its value; webgl2: any value of its slider, up to 3.
    std::string scene = kBall + "[[shapes]]\ntype = \"ball\"\ntransform = \"T((0, 2, 0))\"\n";
    m = fixed_level({0, 0, -1}, {-1, 1, -1}, {1, 3, 1});  // the default camera
    Compiled constant = compile_text("box_ball.iq", scene);
    REQUIRE(constant.result.exit_code == 0);
    b = box_of(constant.result.code);
    REQUIRE(b);
    CHECK(b->first[1] <= 1 - m);
    CHECK(b->first[1] >= 1 - m - 0.01);
    CHECK(b->second[1] >= 3 + m);
    CHECK(b->second[1] <= 3 + m + 0.01);
    CompileOptions webgl2;
    webgl2.target = Target::WebGL2;
    Compiled slider = compile_path(write_temp("box_ball.iq", scene), webgl2);
    REQUIRE(slider.result.exit_code == 0);
    b = box_of(slider.result.code);
    REQUIRE(b);
    CHECK(b->first[1] <= 2 - 3 - m_uniform);
    CHECK(b->second[1] >= 2 + 3 + m_uniform);
    CHECK(b->second[1] <= 2 + 3 + m_uniform + 0.01);
    // A ball 100 units from the camera (max_dist 300): the pixel cone at its far side, 101 / (360 · focal), is
    // wider than 0.1, and the level covers it.
    Compiled far = compile_text("box_far_ball.iq", kBall + "[camera]\nposition = [0, 0, -100]\ntarget = [0, 0, 0]\n[render]\n"
                                                         "max_dist = 300\n[[shapes]]\ntype = \"ball\"\n");
    REQUIRE(far.result.exit_code == 0);
    b = box_of(far.result.code);
    REQUIRE(b);
    const double cone = (100 + 1 + 0.17) / (360 / std::tan(M_PI / 6));
    CHECK(b->second[0] >= 1 + cone);
    CHECK(b->second[0] <= 1 + 1.06 * cone + 0.01);
    CHECK(differ_without_box(far.result, 160, 360) == 0);
}

TEST_CASE("no box where the compiler cannot know one: a tilted plane, a moving instance, a blend", "[scene][box]") {
    // A tilted ground reaches every side.
    Compiled tilted = compile_text("box_tilted.iq", kBall + "[[shapes]]\ntype = \"ground\"\ntransform = \"`R_x`(0.3)\"\n"
                                                            "[[shapes]]\ntype = \"ball\"\n");
    REQUIRE(tilted.result.exit_code == 0);
    CHECK_FALSE(box_of(tilted.result.code));
    CHECK_THAT(tilted.result.code, !Catch::Contains("iqc_far"));
    // A ball that moves with time: its box is not known at compile time.
    Compiled moving = compile_text("box_moving.iq", kBall + "[[shapes]]\ntype = \"ball\"\ntransform = \"T((0, time, 0))\"\n");
    INFO(moving.diagnostics);
    REQUIRE(moving.result.exit_code == 0);
    CHECK_FALSE(box_of(moving.result.code));
    // A smooth blend of two balls.
    Compiled blend = compile_text("box_blend.iq", kBall + "[[shapes]]\nname = \"a\"\ntype = \"ball\"\n[[shapes]]\nname = \"b\"\n"
                                                          "type = \"ball\"\ntransform = \"T((1.5, 0, 0))\"\n"
                                                          "[[blends]]\nshapes = [\"a\", \"b\"]\nradius = 0.5\n");
    INFO(blend.diagnostics);
    REQUIRE(blend.result.exit_code == 0);
    CHECK_FALSE(box_of(blend.result.code));
}

TEST_CASE("clipping rays to the box changes no pixel and saves evaluations, with every march method", "[scene][box][render]") {
    // The sponge and 100 tori as they are, and with a ball that moves with time far off screen (the scene then
    // has no box; the ball changes no distance the marches read): the same picture, more evaluations without
    // the box. Relaxed steps overshoot the box's far side (the first step from the camera of 100 tori does):
    // such a step is checked at the box's side, not taken as a miss. Marches start where the ray enters the
    // box; from there they sample other points than from the camera, and near the sponge's edges another
    // sample comes within the tolerance (4 of 14,400 pixels of its sphere tracing at 160x90, each a hit on
    // the same surface or its edge): the same picture is checked with marches from the camera.
    const int W = 160, H = 90;
    auto draw = [&](const std::string& name, const std::string& text, bool instrument, bool camera_start = false) {
        CompileOptions o;
        o.instrument = instrument;
        Compiled c = compile_path(write_temp(name, text), o);
        INFO(c.diagnostics);
        REQUIRE(c.result.exit_code == 0);
        if (camera_start) c.result.code = from_camera(c.result.code);
        render::RenderResult r = render_compiled(c.result, W, H);
        INFO(r.error);
        REQUIRE(r.ok);
        return std::make_pair(c.result.code, r);
    };
    auto evals = [&](const render::RenderResult& r) {
        double e = 0;
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x) e += r.image.pixel(x, y)[1];
        return e / (W * H);
    };
    for (const char* scene : {"fractal.iq", "instances_100.iq"})
        for (const char* march : {"sphere", "relaxed", "auto", "fixed"}) {
            std::string text = read_text(bench(scene));
            text.replace(text.find("[camera]"), 8, std::string("far = \"\"\"\nshape\nD = ‖p‖ - 1\nwhere\np ∈ ℝ³\n\"\"\"\n\n") +
                                                     "[camera]");
            std::string boxed_text = text;
            // The march method: a [render] table of its own where the scene has none, else a key in it. Fixed
            // steps are set: by default they depend on the box (its diagonal over the step cap).
            std::string keys = std::string("march = \"") + march + "\"\n" + (std::string(march) == "fixed" ? "step = 0.1\n" : "");
            size_t render = boxed_text.find("[render]\n");
            if (render == std::string::npos) boxed_text += "\n[render]\n" + keys;
            else boxed_text.insert(render + 9, keys);
            std::string unboxed_text = boxed_text + "\n[[shapes]]\ntype = \"far\"\ntransform = \"T((0, 1000 + time, 0))\"\n";
            INFO(scene << ", march " << march);
            auto [boxed_code, boxed] = draw("box_a.iq", boxed_text, false, true);
            auto [plain_code, plain] = draw("box_b.iq", unboxed_text, false);
            REQUIRE(box_of(boxed_code));
            REQUIRE_FALSE(box_of(plain_code));
            // The same hits and normals: colours within a quarter of an 8-bit level. The two shaders differ in
            // code around the scene (the moving ball, its per-pixel transform), and llvmpipe fuses multiplies and
            // adds into FMAs differently in each, so their floats may differ in the last bits (since the tilted
            // tori's maps are built from their entries: 2,000 components, by up to 1.2·10⁻⁴); a missed or added hit
            // or a different normal changes a colour by far more. Auto-relaxed steps are read off the slope of the
            // last two samples, so last bits there move a hit within the tolerance (2.7·10⁻⁴ along a ray on the
            // sponge's edge, a colour by 0.03): at most a pixel in a thousand differs by more than 10⁻³, none by
            // more than 0.1. The 100 tori's lattice fills the box, so the boxed scene function has no stand-in
            // for points far from it (no call is, from the box's entry): marched from the camera, its steps on
            // the way are the tori's distances, not the stand-in's, and hits move within the tolerance on the
            // curved tori (colours by up to 0.006 in 0.7% of the channels): there, 10⁻² stands for 10⁻³.
            const float fine = std::string(scene) == "instances_100.iq" ? 1e-2f : 1e-3f;
            int differ = 0, far_off = 0;
            float largest = 0;
            for (int y = 0; y < H; ++y)
                for (int x = 0; x < W; ++x)
                    for (int k = 0; k < 3; ++k) {
                        float e = std::fabs(boxed.image.pixel(x, y)[k] - plain.image.pixel(x, y)[k]);
                        largest = std::max(largest, e);
                        differ += e > fine;
                        far_off += e > 0.1f;
                    }
            INFO("largest difference " << largest);
            CHECK(differ <= W * H / 1000);
            CHECK(far_off == 0);
            double with_box = evals(draw("box_ai.iq", boxed_text, true).second);
            double from_box_camera = evals(draw("box_ci.iq", boxed_text, true, true).second);
            double without = evals(draw("box_bi.iq", unboxed_text, true).second);
            INFO(with_box << " evaluations per pixel with the box, " << from_box_camera << " from the camera, " << without
                          << " without");
            CHECK(with_box < from_box_camera);
            CHECK(with_box < 0.7 * without);
            // From the box's entry: the same picture but where another sample comes within the tolerance (a
            // pixel in 200 for the marches that step by the distance). Fixed steps land elsewhere along each
            // ray, and which of the sponge's holes (0.07 wide) a step of 0.3 passes over changes with where
            // they start: their picture is not checked.
            if (std::string(march) == "fixed") continue;
            auto [entry_code, entry] = draw("box_e.iq", boxed_text, false);
            int moved = 0;
            for (int y = 0; y < H; ++y)
                for (int x = 0; x < W; ++x) {
                    float e = 0;
                    for (int k = 0; k < 3; ++k) e = std::max(e, std::fabs(entry.image.pixel(x, y)[k] - boxed.image.pixel(x, y)[k]));
                    moved += e > 0.1f;
                }
            INFO(moved << " pixels differ by more than 0.1 from the march from the camera");
            CHECK(moved <= W * H / 200);
        }
}

namespace {

// The picture of a compiled Shadertoy shader, and the same shader with its box opened to ±1e30 on every side
// (everything else identical): the number of pixels that differ.
int differ_without_box(const CompileResult& c, int W, int H) {
    // Both march from the camera: a march from where the ray enters the box samples other points (the same
    // surfaces, other hits within the tolerance near edges), and what is tested here is that the box holds
    // every sample the hit test accepts.
    std::string boxed = from_camera(c.code);
    std::string open = std::regex_replace(boxed, std::regex(R"(const vec3 IQC_BOX_LO = vec3\([^)]*\);)"),
                                          "const vec3 IQC_BOX_LO = vec3(-1.0e30);");
    open = std::regex_replace(open, std::regex(R"(const vec3 IQC_BOX_HI = vec3\([^)]*\);)"), "const vec3 IQC_BOX_HI = vec3(1.0e30);");
    REQUIRE(open != c.code);
    render::RenderOptions o;
    o.width = W;
    o.height = H;
    render::RenderResult a = render::render_shadertoy(boxed, o), b = render::render_shadertoy(open, o);
    INFO(a.error << b.error);
    REQUIRE(a.ok);
    REQUIRE(b.ok);
    int differ = 0;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x)
            for (int k = 0; k < 3; ++k) differ += a.image.pixel(x, y)[k] != b.image.pixel(x, y)[k];
    return differ;
}

}  // namespace

// Found by a new-user trial of the box (each differed before its fix).
TEST_CASE("the box holds what the hit test accepts: a bound under a non-uniform scale, float spacing far out, "
          "the step cap's pixel cone at 360 rows",
          "[scene][box][render]") {
    // A scene compiles with a box, and draws the same at W x H with the box opened.
    auto same_without_box = [](const std::string& name, const std::string& text, int W, int H) {
        Compiled c = compile_text(name, text);
        INFO(name << "\n" << c.diagnostics);
        REQUIRE(c.result.exit_code == 0);
        REQUIRE(box_of(c.result.code));
        CHECK(differ_without_box(c.result, W, H) == 0);
    };
    // `bound` in a flattening scale: the hit test reads (|q| - R)·scale, so the object-space ball grows by the
    // margin over the scale before it is mapped (the world sphere plus the margin cut the coin's rim: 4 pixels).
    same_without_box("box_coin.iq", "[camera]\nposition = [0, 4, -6]\ntarget = [0, 0, 0]\n"
                                    "[[shapes]]\ntype = \"sphere\"\nbound = 1\ntransform = \"S((3, 0.02, 3))\"\n",
                                    160, 90);
    // A ball 200,000 units out seen through a narrow lens: there the tolerance is four float spacings, 0.19
    // units, not the hit tolerance (the box's margin of 0.1 cut its silhouette: 56 pixels).
    same_without_box("box_far.iq", "[camera]\nposition = [0, 0, 0]\ntarget = [0, 0, 1]\nfov = 0.002\n"
                                   "[render]\nmax_dist = 400000\n[[shapes]]\ntype = \"sphere\"\n"
                                   "shape_params = { r = 3 }\ntransform = \"T((0, 0, 200000))\"\n",
                                   160, 90);
    // A thin disc 40 units wide seen from its rim: rays at the picture's sides run out of steps beside it, where
    // the step cap counts a sample within the pixel's cone (t / (rows · focal)) — wider than the margin at 90
    // rows (2 pixels differ there: docs/scene.md), covered from 360 rows on. The cone reads only the height.
    same_without_box("box_disc.iq", "[modules]\ndisc = \"\"\"\nshape\nD = max(‖(p_1, p_3)‖ - r, |p_2| - h)\nwhere\n"
                                    "p ∈ ℝ³\nr ∈ [0,100] default = 40\nh ∈ [0,1] default = 0.05\n\"\"\"\n"
                                    "[camera]\nposition = [0, 1.0, -38]\ntarget = [0, 0.5, 0]\n"
                                    "[render]\nmax_dist = 100\n[[shapes]]\ntype = \"disc\"\n"
                                    "[[shapes]]\ntype = \"sphere\"\ntransform = \"T((0, 1.05, 0))\"\n",
                                    160, 360);
}

TEST_CASE("a benchmark build's box covers the largest hit tolerance the sweep gives it", "[scene][box][bench]") {
    // `iqc bench --hits 0.05,...`: the hit tolerance is a uniform, so the box is grown for the largest one (ten
    // tolerances: 0.5), not the scene's own.
    std::string scene = kBall + "[[shapes]]\ntype = \"ball\"\n";
    CompileOptions o;
    o.bench = true;
    o.bench_max_hit = 0.05;
    Compiled c = compile_path(write_temp("box_bench.iq", scene), o);
    REQUIRE(c.result.exit_code == 0);
    auto b = box_of(c.result.code);
    REQUIRE(b);
    CHECK(b->second[1] >= 1.5);
    CHECK(b->second[1] <= 1.51);
}

TEST_CASE("rotations inside a shape: a twist, a bend, a turn by a slider or a constant bound the axes they mix",
          "[scene][box]") {
    // A shape that rotates its point in a coordinate plane mixes two axes: interval arithmetic alone closes
    // neither side of x or z (c·x - s·z over x ≥ c with z unbounded). The rotated pair keeps the norm of (x, z)
    // (cos² + sin² = 1), so the box of the rotated coordinates bounds both: support_box's PlanePair.
    const double m_uniform = 100 / (360 / std::tan(M_PI / 6));  // webgl2's level (see the first test case)
    auto near = [](double got, double want) {
        INFO("got " << got << ", want " << want);
        CHECK(got >= want);
        CHECK(got <= want + 0.01);
    };
    // A scene's box (it must compile, and have one).
    auto boxed = [](const std::string& name, const std::string& text, CompileOptions o = {}) {
        Compiled c = compile_path(write_temp(name, text), o);
        INFO(c.diagnostics);
        REQUIRE(c.result.exit_code == 0);
        auto b = box_of(c.result.code);
        REQUIRE(b);
        return *b;
    };
    // The twisted box (1 x 3 x 1, `u = (c p_1 - s p_3, p_2, s p_1 + c p_3)`): its rounded corner's radius in x and
    // z, 0.5·√2 + m (the box of (u_1, u_3) is ±(0.5 + m); its far cells are split down to the corner).
    double m = fixed_level({0, 1, -5}, {-0.71, -1.5, -0.71}, {0.71, 1.5, 0.71});  // Shadertoy's fixed camera
    Compiled twisted = compile_path(bench("twisted.iq"));
    REQUIRE(twisted.result.exit_code == 0);
    auto b = box_of(twisted.result.code);
    REQUIRE(b);
    for (int a : {0, 2}) {
        near(-b->first[a], 0.5 * std::sqrt(2.0) + m);
        near(b->second[a], 0.5 * std::sqrt(2.0) + m);
    }
    near(b->second[1], 1.5 + m);
    CHECK(differ_without_box(twisted.result, 96, 54) == 0);
    // The twisted bar (the standard library's `twist` in a called function, four calls merged): the bar's
    // corner, narrower than its `bound = 1.6` sphere's box.
    m = fixed_level({0, 0.5, -4}, {-0.43, -1.5, -0.43}, {0.43, 1.5, 0.43});
    Compiled bar = compile_path(bench("twisted_bar.iq"));
    REQUIRE(bar.result.exit_code == 0);
    b = box_of(bar.result.code);
    REQUIRE(b);
    for (int a : {0, 2}) near(b->second[a], 0.3 * std::sqrt(2.0) + m);
    near(b->second[1], 1.5 + m);
    CHECK(differ_without_box(bar.result, 96, 54) == 0);
    // A slab turned about y by a matrix of a slider's angle: on webgl2 any angle in [0, 6.3], so x and z reach
    // the corner's radius |(1 + m, 0.3 + m)|.
    const std::string slab =
        "[modules]\nslab = \"\"\"\nshape\nsin, cos from trigonometry\nD = max(|v_1| - 1, |p_2| - 0.2, |v_2| - 0.3)\n"
        "v = R (p_1, p_3)\nR = [cos(θ) -sin(θ); sin(θ) cos(θ)]\nwhere\np ∈ ℝ³\nθ ∈ [0, 6.3] default = 0.7\n\"\"\"\n"
        "[[shapes]]\ntype = \"slab\"\n";
    CompileOptions webgl2;
    webgl2.target = Target::WebGL2;
    b = boxed("box_slab.iq", slab, webgl2);
    for (int a : {0, 2}) near(b->second[a], std::hypot(1 + m_uniform, 0.3 + m_uniform));
    near(b->second[1], 0.2 + m_uniform);
    // A constant turn (cos = 0.8, sin = 0.6): the rectangle ±(1 + m) x ±(0.3 + m) mapped back exactly,
    m = fixed_level({0, 0, -1}, {-0.98, -0.2, -0.84}, {0.98, 0.2, 0.84});
    // x within 0.8(1 + m) + 0.6(0.3 + m), z within 0.6(1 + m) + 0.8(0.3 + m).
    b = boxed("box_const.iq", "[modules]\nturned = \"\"\"\nshape\nD = max(|u_1| - 1, |u_2| - 0.2, |u_3| - 0.3)\n"
                                                     "u = (0.8 p_1 - 0.6 p_3, p_2, 0.6 p_1 + 0.8 p_3)\nwhere\np ∈ ℝ³\n\"\"\"\n"
                                                     "[[shapes]]\ntype = \"turned\"\n");
    near(b->second[0], 0.8 * (1 + m) + 0.6 * (0.3 + m));
    near(b->second[2], 0.6 * (1 + m) + 0.8 * (0.3 + m));
    // `bend` turns (x, y) by an angle of x itself: still a rotation, |(x, y)| ≤ |(1 + m, 0.2 + m)|.
    m = fixed_level({0, 0, -1}, {-1.02, -1.02, -0.3}, {1.02, 1.02, 0.3});
    b = boxed("box_bend.iq", "[modules]\nbent = \"\"\"\nshape\nbend from domain\n# lipschitz: 2\n"
                                                "D = max(|q_1| - 1, |q_2| - 0.2, |q_3| - 0.3)\nq = bend(p, k)\nwhere\np ∈ ℝ³\n"
                                                "k ∈ [0, 2] default = 0.5\n\"\"\"\n[[shapes]]\ntype = \"bent\"\n");
    for (int a : {0, 1}) near(b->second[a], std::hypot(1 + m, 0.2 + m));
    near(b->second[2], 0.3 + m);
    // Not a rotation: (c x - s z, c x + s z) does not keep |(x, z)|, and the rule must not apply. z is unbounded
    // (at p_2 = 0, s = 0 and z is free): it stays open. x is bounded, |2 c x| ≤ 1.3 + 2 level with c = cos(p_2) ≥
    // cos(0.2 + level): intervals close it where the half-spaces' other axes are split in turn (stop 48; before,
    // x stayed open too), around that extent.
    b = boxed("box_shear.iq", "[modules]\nsheared = \"\"\"\nshape\nsin, cos from trigonometry\n# lipschitz: 2\n"
                                                    "D = max(|u_1| - 1, |p_2| - 0.2, |u_2| - 0.3)\n"
                                                    "u = (c p_1 - s p_3, c p_1 + s p_3)\nc = cos(k p_2)\ns = sin(k p_2)\nwhere\np ∈ ℝ³\n"
                                                    "k ∈ [0, 2] default = 1\n\"\"\"\n[[shapes]]\ntype = \"sheared\"\n");
    CHECK(b->first[2] == -1e30);
    CHECK(b->second[2] == 1e30);
    const double x_most = (0.65 + m_uniform) / std::cos(0.2 + m_uniform);
    CHECK(b->second[0] >= x_most);
    CHECK(b->first[0] <= -x_most);
    CHECK(b->second[0] <= 3 * x_most);
    CHECK(b->first[0] >= -3 * x_most);
    near(b->second[1], 0.2 + m_uniform);  // an open box: the cone at max_dist
}

TEST_CASE("a shear or nested constant rotations inside a shape bound the axes they mix",
          "[scene][box]") {
    // D = box((p_1 + 0.3·p_2, p_2, p_3), 0.3): u = p_1 + 0.3·p_2 and w = p_2 are the map [[1, 0.3], [0, 1]]; the
    // box of (u, w) is ±(0.3 + m) each, so p_1 = u - 0.3·w lies within ±1.3(0.3 + m). Paired with p_1 (which only
    // u reads), p_2 would stay unknown where the box reads it: x was open (a trial's shear, stop 39's F7). The
    // same shear as a constant matrix (`[1 0.5 0; 0 1 0; 0 0 1] p`): x within ±1.5(0.3 + m).
    auto shear = [](const std::string& q) {
        return "[modules]\nsheared = \"\"\"\nshape\n# lipschitz: 1.4\nD = ‖max(|q| - b, 0)‖ + min(max(|q_1| - b_1, |q_2| - b_2, "
               "|q_3| - b_3), 0)\nq = " + q + "\nb = (0.3, 0.3, 0.3)\nwhere\np ∈ ℝ³\n\"\"\"\n[camera]\nposition = [0, 1, -4]\n"
               "target = [0, 0.8, 0]\n[[shapes]]\ntype = \"sheared\"\n";
    };
    for (auto [q, k] : {std::pair<std::string, double>{"(p_1 + 0.3p_2, p_2, p_3)", 1.3}, {"[1 0.5 0; 0 1 0; 0 0 1] p", 1.5}}) {
        INFO(q);
        Compiled c = compile_path(write_temp("box_shear_const.iq", shear(q)));
        INFO(c.diagnostics);
        REQUIRE(c.result.exit_code == 0);
        auto b = box_of(c.result.code);
        REQUIRE(b);
        // Closed on every side, around the sheared box (the level m is under 0.02 here), and no pixel changes.
        for (int a = 0; a < 3; ++a) {
            CHECK(b->first[a] > -1e29);
            CHECK(b->second[a] < 1e29);
        }
        CHECK(b->second[0] >= k * 0.3);
        CHECK(b->second[0] <= k * 0.3 + 0.05);
        CHECK(b->second[1] >= 0.3);
        CHECK(b->second[1] <= 0.35);
        CHECK(differ_without_box(c.result, 96, 54) == 0);
    }
    // Nested rotations by constant angles, `rotate_y(rotate_y(p, 0.5), 0.3)`: the outer rotation's forms are
    // constant maps of p too (the inner one's scaled), and the outer pair is analysed (the inner pair's box,
    // rotated by intervals, left x open): the 1.2 x 0.2 rectangle turned by 0.8 rad reaches 0.6·cos 0.8 +
    // 0.1·sin 0.8 = 0.49 in x and 0.6·sin 0.8 + 0.1·cos 0.8 = 0.50 in z.
    std::string nested = "[modules]\nturned = \"\"\"\nshape\n`rotate_y` from domain\n"
                         "D = ‖max(|q| - b, 0)‖ + min(max(|q_1| - b_1, |q_2| - b_2, |q_3| - b_3), 0)\n"
                         "q = `rotate_y`(`rotate_y`(p, 0.5), 0.3)\nb = (0.6, 0.1, 0.1)\nwhere\np ∈ ℝ³\n\"\"\"\n"
                         "[camera]\nposition = [0, 1, -4]\ntarget = [0, 0, 0]\n[[shapes]]\ntype = \"turned\"\n";
    Compiled c = compile_path(write_temp("box_nested_rotation.iq", nested));
    INFO(c.diagnostics);
    REQUIRE(c.result.exit_code == 0);
    auto b = box_of(c.result.code);
    REQUIRE(b);
    CHECK(b->second[0] >= 0.6 * std::cos(0.8) + 0.1 * std::sin(0.8));
    CHECK(b->second[0] <= 0.56);
    CHECK(b->second[2] >= 0.6 * std::sin(0.8) + 0.1 * std::cos(0.8));
    CHECK(b->second[2] <= 0.56);
    CHECK(differ_without_box(c.result, 96, 54) == 0);
}

TEST_CASE("a ray that enters the box only beyond the far plane takes no step", "[scene][box][render]") {
    // A ground y ≤ 0 seen level from y = 1 with max_dist 30: the rows just below the horizon meet the box
    // (y ≤ 0.16) beyond t = 30 (they were marched to the far plane, up to 30 steps each); the picture is the
    // same with the box opened.
    const std::string scene = "[modules]\nground = \"\"\"\nshape\nD = p_2\nwhere\np ∈ ℝ³\n\"\"\"\n"
                              "[camera]\nposition = [0, 1, 0]\ntarget = [0, 1, 1]\n[render]\nmax_dist = 30\n"
                              "[[shapes]]\ntype = \"ground\"\n";
    Compiled c = compile_text("box_horizon.iq", scene);
    REQUIRE(c.result.exit_code == 0);
    REQUIRE(box_of(c.result.code));
    CHECK(differ_without_box(c.result, 160, 360) == 0);
    CompileOptions o;
    o.instrument = true;
    Compiled counted = compile_path(write_temp("box_horizon_i.iq", scene), o);
    REQUIRE(counted.result.exit_code == 0);
    const int W = 16, H = 90;
    render::RenderResult r = render_compiled(counted.result, W, H);
    INFO(r.error);
    REQUIRE(r.ok);
    // Row 45 from the top (fragCoord.y = 44.5, just below the centre): rd.y ≈ -0.0064, the ground's box at t ≈ 130.
    for (int x = 0; x < W; ++x) CHECK(r.image.pixel(x, 45)[1] == 0.0f);
    // Far below the horizon the rays do march.
    CHECK(r.image.pixel(W / 2, H - 6)[1] > 0.0f);
}

// Found by a new-user trial: `fixed` stepped max_dist / max_steps by default (156 units for a camera 12,000
// units away, max_dist 20,000), through a box 2.8 wide, and drew nothing. Marches start and end at the box,
// so the default step is its diagonal over the step cap where that is shorter.
TEST_CASE("fixed steps by default cover the scene's box, not max_dist, over the step cap", "[scene][box][render]") {
    const std::string far = "[camera]\nposition = [10000, 3000, -8000]\ntarget = [0, 0, 0]\nfov = 0.02\n[render]\nmarch = \"MARCH\"\n"
                            "max_dist = 20000\n[[shapes]]\ntype = \"torus\"\ntransform = \"`R_x`(0.7)\"\n[[shapes]]\ntype = \"sphere\"\n"
                            "transform = \"T((1.3, 0, 0))\"\nshape_params = { r = 0.3 }\n";
    auto draw = [&](const std::string& march) {
        std::string text = far;
        text.replace(text.find("MARCH"), 5, march);
        Compiled c = compile_text("fixed_far_" + march + ".iq", text);
        INFO(c.diagnostics);
        REQUIRE(c.result.exit_code == 0);
        render::RenderResult r = render_compiled(c.result, 96, 54);
        INFO(r.error);
        REQUIRE(r.ok);
        return std::make_pair(c.result.code, r);
    };
    auto [fixed_code, fixed] = draw("fixed");
    auto [sphere_code, sphere] = draw("sphere");
    auto b = box_of(fixed_code);
    REQUIRE(b);
    double d2 = 0;
    for (int k = 0; k < 3; ++k) d2 += std::pow(b->second[k] - b->first[k], 2);
    std::smatch m;
    REQUIRE(std::regex_search(fixed_code, m, std::regex(R"(const float IQC_FIXED_STEP = ([0-9.e+-]+);)")));
    CHECK(std::stod(m[1]) == Approx(std::sqrt(d2) / 128).epsilon(1e-4));  // the default step cap
    int drawn = 0, differ = 0;
    const float* bg = sphere.image.pixel(0, 0);
    for (int y = 0; y < 54; ++y)
        for (int x = 0; x < 96; ++x) {
            const float *a = fixed.image.pixel(x, y), *s = sphere.image.pixel(x, y);
            drawn += std::fabs(s[0] - bg[0]) + std::fabs(s[1] - bg[1]) + std::fabs(s[2] - bg[2]) > 0.05f;
            differ += std::fabs(a[0] - s[0]) + std::fabs(a[1] - s[1]) + std::fabs(a[2] - s[2]) > 0.1f;
        }
    INFO(drawn << " pixels show the shapes (sphere tracing), " << differ << " differ with fixed steps");
    CHECK(drawn > 150);
    CHECK(differ < drawn / 20);
}

// Found by new-user trials (stops 44, 45): `fixed`'s default step (max_dist, or the box's diagonal, over the step
// cap) passed through walls and panels thinner than a step without a sample inside, and drew nothing. Steps from
// each ray's own way through the box drew them but made every missing ray take all max_steps samples (15x a pipe
// scene's evaluations for the same picture): the compiler finds the thinnest instance (its shape's box by
// interval arithmetic, its transform's scale) and says which step would see it.
TEST_CASE("fixed steps longer than the thinnest instance are a located warning with the step that sees it", "[scene][box][render]") {
    const std::string modules = "[modules]\nwall = \"\"\"\nshape\nD = |p_1| - 0.1\nwhere\np ∈ ℝ³\n\"\"\"\n"
                                "ball = \"\"\"\nshape\nD = ‖p‖ - 1\nwhere\np ∈ ℝ³\n\"\"\"\n";
    auto scene = [&](const std::string& render, const std::string& type, const std::string& transform) {
        return modules + "[camera]\nposition = [-6, 1.2, 1]\ntarget = [3, 0.3, 0.5]\n[render]\nmax_dist = 60\n" + render +
               "\n[[shapes]]\ntype = \"" + type + "\"\ntransform = \"" + transform + "\"\n";
    };
    // The wall 0.2 thick at steps of 60 / 128: the warning at its `type`, with half its thickness as the step.
    Compiled thin = compile_text("fixed_thin.iq", scene("march = \"fixed\"", "wall", "T((3, 0.3, 0.5))"));
    REQUIRE(thin.result.exit_code == 0);
    CHECK_THAT(thin.diagnostics, Catch::Contains("fixed_thin.iq:21:8: warning: `march = \"fixed\"` steps 0.46875 by default "
                                                 "(max_dist 60 / max_steps 128), longer than the thickness of 'wall_1' (0.20"));
    CHECK_THAT(thin.diagnostics, Catch::Contains("Set `step` under [render] to at most 0.1 (and max_steps to 600 to reach as far)"));
    CHECK_THAT(thin.diagnostics, Catch::Contains("  type = \"wall\"\n         ^~~~~~"));
    // What it says holds: with the step it gives the wall is drawn as sphere tracing draws it; without, it is not.
    auto draw = [&](const std::string& render) {
        Compiled c = compile_text("fixed_thin_draw.iq", scene(render, "wall", "T((3, 0.3, 0.5))"));
        REQUIRE(c.result.exit_code == 0);
        render::RenderResult r = render_compiled(c.result, 96, 54);
        REQUIRE(r.ok);
        return r;
    };
    render::RenderResult sphere = draw("march = \"sphere\""), coarse = draw("march = \"fixed\""),
                         fine = draw("march = \"fixed\"\nstep = 0.1\nmax_steps = 600");
    int differ_coarse = 0, differ_fine = 0;
    for (int y = 0; y < 54; ++y)
        for (int x = 0; x < 96; ++x) {
            const float *s = sphere.image.pixel(x, y), *c = coarse.image.pixel(x, y), *f = fine.image.pixel(x, y);
            differ_coarse += std::fabs(c[0] - s[0]) + std::fabs(c[1] - s[1]) + std::fabs(c[2] - s[2]) > 0.1f;
            differ_fine += std::fabs(f[0] - s[0]) + std::fabs(f[1] - s[1]) + std::fabs(f[2] - s[2]) > 0.1f;
        }
    INFO(differ_coarse << " pixels differ from sphere tracing at the default step, " << differ_fine << " at the warning's");
    CHECK(differ_coarse > 96 * 54 / 2);
    CHECK(differ_fine <= 96 * 54 / 100);
    // Thickness in the shape's own space times the transform's scale: the wall turned by π/6 and scaled by 3 is
    // 0.6 thick (its world box is not thin on any axis): warned at steps of 60 / 64, not at 60 / 128 (a step
    // shorter than a slab's thickness samples it on every ray).
    Compiled turned = compile_text("fixed_turned.iq", scene("march = \"fixed\"\nmax_steps = 64", "wall", "`R_y`(π/6)⋅S((3, 3, 3))"));
    REQUIRE(turned.result.exit_code == 0);
    CHECK_THAT(turned.diagnostics, Catch::Contains("longer than the thickness of 'wall_1' (0.60"));
    CHECK_THAT(turned.diagnostics, Catch::Contains("to at most 0.3 (and max_steps to 200 to reach as far)"));
    Compiled fits = compile_text("fixed_fits.iq", scene("march = \"fixed\"", "wall", "`R_y`(π/6)⋅S((3, 3, 3))"));
    CHECK(fits.diagnostics.find("thickness") == std::string::npos);  // 60 / 128 = 0.47
    // No warning: a step the scene sets, another march, a shape thicker than two steps (a ball 2 across).
    for (const auto& [render, type] : std::vector<std::pair<std::string, std::string>>{
             {"march = \"fixed\"\nstep = 0.3", "wall"}, {"march = \"sphere\"", "wall"}, {"march = \"fixed\"", "ball"}}) {
        Compiled quiet = compile_text("fixed_quiet.iq", scene(render, type, "T((3, 0.3, 0.5))"));
        INFO(render << " " << type << "\n" << quiet.diagnostics);
        REQUIRE(quiet.result.exit_code == 0);
        CHECK(quiet.diagnostics.find("warning") == std::string::npos);
    }
    // Thin parts whose box is not thin (stop 45's trial): a shell 0.04 thick has a box 2 across; its depth (the
    // distance's lowest value inside it, by interval branch and bound) gives its thickness. On a ground (an open
    // box: steps of 60 / 128).
    const std::string ground = "[[shapes]]\ntype = \"floor\"\n";
    const std::string more = "floor = \"\"\"\nshape\nD = p_2 + 2\nwhere\np ∈ ℝ³\n\"\"\"\n"
                             "shell = \"\"\"\nshape\nD = |‖p‖ - 1| - 0.02\nwhere\np ∈ ℝ³\n\"\"\"\n"
                             "plate = \"\"\"\nshape\nD = max(|p_1| - 0.01, |p_2| - 0.5, |p_3| - 0.5)\nwhere\np ∈ ℝ³\n\"\"\"\n";
    auto with_ground = [&](const std::string& type, const std::string& transform) {
        std::string text = scene("march = \"fixed\"", type, transform) + ground;
        text.insert(text.find("[camera]"), more);
        return text;
    };
    Compiled shell = compile_text("fixed_shell.iq", with_ground("shell", "T((3, 0.3, 0.5))"));
    REQUIRE(shell.result.exit_code == 0);
    CHECK_THAT(shell.diagnostics, Catch::Contains("longer than the thickness of 'shell_1' (0.04"));
    // A plate 0.02 thick stretched 80 times across its thin side is a block 1.6 thick: no warning; unstretched,
    // and turned by time (taken at time 0), it is warned.
    Compiled stretched = compile_text("fixed_stretched.iq", with_ground("plate", "S((80, 1, 1))"));
    REQUIRE(stretched.result.exit_code == 0);
    CHECK(stretched.diagnostics.find("thickness") == std::string::npos);
    Compiled plate = compile_text("fixed_plate.iq", with_ground("plate", "`R_y`(time)"));
    INFO(plate.diagnostics);
    REQUIRE(plate.result.exit_code == 0);
    CHECK_THAT(plate.diagnostics, Catch::Contains("longer than the thickness of 'plate_1' (0.02"));
    // A relative hit tolerance (0.01 per unit of distance): the hit test sees the plate 20 units away 0.02 + 2·0.2
    // thick, and steps of 60 / 256 sample it on every ray (a trial's false alarm); with 0.01 absolute, warned.
    for (const char* mode : {"relative", "absolute"}) {
        std::string text = with_ground("plate", "T((0, 0, 20))⋅`R_y`(0.3)");
        text.insert(text.find("max_dist = 60"), std::string("hit_mode = \"") + mode + "\"\nhit = 0.01\nmax_steps = 256\n");
        text.replace(text.find("position = [-6, 1.2, 1]"), 23, "position = [0, 1, -1]");
        Compiled c = compile_text("fixed_relative.iq", text);
        INFO(mode << "\n" << c.diagnostics);
        REQUIRE(c.result.exit_code == 0);
        CHECK((c.diagnostics.find("longer than the thickness of 'plate_1'") != std::string::npos) == (std::string(mode) == "absolute"));
    }
    // A step that would need more than max_steps' limit to reach max_dist says so.
    std::string far_text = scene("march = \"fixed\"", "wall", "T((3, 0.3, 0.5))");
    far_text.replace(far_text.find("max_dist = 60"), 13, "max_dist = 20000");
    Compiled far = compile_text("fixed_far.iq", far_text);
    REQUIRE(far.result.exit_code == 0);
    CHECK_THAT(far.diagnostics, Catch::Contains("to reach as far it would take 200000 steps, over max_steps' limit of 100000: "
                                                "a smaller max_dist, or `march = \"sphere\"`"));
}

TEST_CASE("an open scene box costs one analysis per shape, not one per round", "[scene][box]") {
    // With the camera known, the box's level is found in rounds from the hit tolerance up; a shape without a
    // box (a ground plane) leaves it open, and then only the last round's boxes (at the widest level) are kept.
    // The first round stops at the first open shape and analyses shapes a quick test finds open first: here the
    // ground (listed last), then the ball and the ground once each at the widest level. Every round in full was
    // 4 analyses here, and half of lowering examples/christmas_tree.iq and examples/menger.iq.
    const std::string scene = kBall + "[camera]\nposition = [0, 1, -6]\ntarget = [0, 0, 0]\n"
                                      "[[shapes]]\ntype = \"ball\"\n[[shapes]]\ntype = \"ground\"\n";
    std::filesystem::path path = write_temp("box_rounds.iq", scene);
    RunResult r = run_iqc(path.string() + " --dump-ir -o " + (temp_dir() / "box_rounds.frag").string());
    INFO(r.err.substr(0, 2000));
    REQUIRE(r.exit_code == 0);
    CHECK_THAT(r.err, Catch::Contains("; scene box: open (3 analyses of shapes' boxes)"));
    // A closed box: the ball alone, in as many rounds as its level needs (two here: the tolerance, then the
    // pixel cone at its farthest corner).
    RunResult closed = run_iqc(write_temp("box_closed.iq", kBall + "[camera]\nposition = [0, 1, -6]\ntarget = [0, 0, 0]\n"
                                                                   "[[shapes]]\ntype = \"ball\"\n").string() +
                               " --dump-ir -o " + (temp_dir() / "box_closed.frag").string());
    REQUIRE(closed.exit_code == 0);
    CHECK_THAT(closed.err, Catch::Contains("; scene box: closed (2 analyses of shapes' boxes)"));
}

// iqc_far tests the slabs of the axes where the box is bounded only (Compile.cpp BOX_SLABS): on an open axis every
// ray lies within the slab, and the test cost a ground plane's scene 3% of llvmpipe's compile. Each shader draws
// the same picture, bit for bit, as the same shader with the three-axis slab test in its place.
TEST_CASE("the box's slab test takes only the axes where the box is bounded", "[scene][box][render]") {
    const std::string three_axes = "    vec3 m = 1.0 / rd;\n"
                                   "    vec3 a = (IQC_BOX_LO - ro) * m, b = (IQC_BOX_HI - ro) * m;\n"
                                   "    vec3 n = min(a, b), f = max(a, b);\n"
                                   "    float t_in = max(max(n.x, n.y), n.z), t_out = min(min(min(f.x, f.y), f.z), IQC_MAX_DIST);\n";
    struct Case {
        const char* what;
        const char* distance;  // the one shape's D
        const char* slabs;     // what iqc_far's first line divides by
    };
    const Case cases[] = {
        {"a ball: every axis", "‖p‖ - 1", "vec3 m = 1.0 / rd;"},
        {"a ground plane and a ball: y alone", "min(p_2 + 1, ‖p‖ - 1)", "float m = 1.0 / rd.y;"},
        {"a column along y: x and z", "‖(p_1, p_3)‖ - 0.5", "vec2 m = 1.0 / rd.xz;"},
        {"a rod along x: y and z", "‖(p_2, p_3)‖ - 0.3", "vec2 m = 1.0 / rd.yz;"},
        {"a wall across x: x alone", "|p_1| - 0.2", "float m = 1.0 / rd.x;"},
    };
    for (const Case& c : cases) {
        INFO(c.what);
        const std::string scene = std::string("[modules]\nthing = \"\"\"\nshape\nD = ") + c.distance +
                                  "\nwhere\np ∈ ℝ³\n\"\"\"\n[camera]\nposition = [1.5, 2, -4]\ntarget = [0, 0, 0]\n"
                                  "[[shapes]]\ntype = \"thing\"\n";
        Compiled compiled = compile_text("box_slabs.iq", scene);
        INFO(compiled.diagnostics);
        REQUIRE(compiled.result.exit_code == 0);
        const std::string& code = compiled.result.code;
        REQUIRE(box_of(code));
        size_t at = code.find("float iqc_far(vec3 ro, vec3 rd, out float t_enter) {\n");
        REQUIRE(at != std::string::npos);
        at = code.find('\n', at) + 1;
        CHECK(code.compare(at, 4 + std::string(c.slabs).size(), std::string("    ") + c.slabs) == 0);
        size_t end = code.find("    t_enter = max(t_in, 0.0);", at);
        REQUIRE(end != std::string::npos);
        std::string general = code;
        general.replace(at, end - at, three_axes);
        render::RenderOptions o;
        o.width = 96;
        o.height = 54;
        render::RenderResult mine = render::render_shadertoy(code, o), theirs = render::render_shadertoy(general, o);
        INFO(mine.error << theirs.error);
        REQUIRE(mine.ok);
        REQUIRE(theirs.ok);
        int differ = 0, other = 0;
        for (int y = 0; y < 54; ++y)
            for (int x = 0; x < 96; ++x) {
                for (int k = 0; k < 3; ++k) differ += mine.image.pixel(x, y)[k] != theirs.image.pixel(x, y)[k];
                other += mine.image.pixel(x, y)[0] != mine.image.pixel(0, 0)[0];
            }
        CHECK(differ == 0);
        CHECK(other > 0);  // the picture is not one colour: the shape is in it
    }
}

TEST_CASE("a turn by a multiple of π/2 keeps the axes it bounds: rounding's coefficients do not open the box", "[scene][box][render]") {
    // cos(π/2) is 6·10⁻¹⁷ in double: R_y(π/2) mixes a wall's unbounded object z into world x by that much. Over the
    // world float32 tells apart it moves the wall by less than 10⁻⁸, which the box takes as a margin; before, the
    // wall's world box was open on every axis and the scene had no box (stop 43's trial: R_z(π) on a column).
    struct Case {
        const char* what;
        const char* distance;
        const char* transform;
        std::array<bool, 3> bounded;  // the world axes the box bounds
        int axis;                     // one of them, with its half-width `half` around 0
        double half;
    };
    const Case cases[] = {
        {"a wall across x turned by R_y(π/2): across z", "|p_1| - 0.2", "`R_y`(π/2)", {false, false, true}, 2, 0.2},
        {"a wall across x turned by R_z(π): across x", "|p_1| - 0.2", "`R_z`(π)", {true, false, false}, 0, 0.2},
        {"a column along y turned by R_z(π): x and z", "‖(p_1, p_3)‖ - 0.5", "`R_z`(π)", {true, false, true}, 0, 0.5},
        {"a column along y turned by R_x(π/2): along z, x and y bounded", "‖(p_1, p_3)‖ - 0.5", "`R_x`(π/2)", {true, true, false}, 1, 0.5},
        {"a rod along x turned by R_y(-π/2)⋅R_z(π): along z", "‖(p_2, p_3)‖ - 0.3", "`R_y`(-π/2)⋅`R_z`(π)", {true, true, false}, 0, 0.3},
    };
    for (const Case& c : cases) {
        INFO(c.what);
        const std::string scene = std::string("[modules]\nthing = \"\"\"\nshape\nD = ") + c.distance +
                                  "\nwhere\np ∈ ℝ³\n\"\"\"\n[camera]\nposition = [1.5, 2, -4]\ntarget = [0, 0, 0]\n"
                                  "[[shapes]]\ntype = \"thing\"\ntransform = \"" + c.transform + "\"\n";
        Compiled compiled = compile_text("box_turned.iq", scene);
        INFO(compiled.diagnostics);
        REQUIRE(compiled.result.exit_code == 0);
        auto b = box_of(compiled.result.code);
        REQUIRE(b);
        for (int a = 0; a < 3; ++a) {
            INFO("axis " << a);
            CHECK((b->first[a] > -1e29) == c.bounded[a]);
            CHECK((b->second[a] < 1e29) == c.bounded[a]);
        }
        // Around the shape by the level, not more: the box is open on a side, so the step cap's pixel cone at
        // max_dist (100 / (360 · focal), focal 1/tan(30°): 0.16).
        const double m = 100 / (360 / std::tan(M_PI / 6));
        CHECK(b->first[c.axis] <= -c.half - m);
        CHECK(b->first[c.axis] >= -c.half - m - 0.01);
        CHECK(b->second[c.axis] >= c.half + m);
        CHECK(b->second[c.axis] <= c.half + m + 0.01);
        // At 360 rows, the step cap's pixel cone the level is taken at (at 90 rows, four times wider, the cone
        // at the wall's far end reaches past the box with or without the turn).
        CHECK(differ_without_box(compiled.result, 160, 360) == 0);
    }
    // A real tilt stays open: R_y(10⁻⁶) moves the wall 0.1 at z = 10⁵, inside max_dist's reach.
    Compiled tilted = compile_text("box_tilted.iq", "[modules]\nthing = \"\"\"\nshape\nD = |p_1| - 0.2\nwhere\np ∈ ℝ³\n\"\"\"\n"
                                                    "[[shapes]]\ntype = \"thing\"\ntransform = \"`R_y`(0.000001)\"\n");
    REQUIRE(tilted.result.exit_code == 0);
    CHECK_FALSE(box_of(tilted.result.code));
}

TEST_CASE("piecewise shapes are boxed case by case: the octahedron's box is its vertices', the pyramid's is closed",
          "[scene][box]") {
    // The octahedron's distance picks one of three permutations of |p|; one pass of intervals takes their hull
    // and proves no half-space free, so the box was open on every side (every ray marched from the camera).
    // Case splitting (ir/CaseSplit.h) proves each side within the hit test's band of its vertex at distance s.
    const std::string camera = "[camera]\nposition = [0, 1, -5]\ntarget = [0, 0, 0]\n";
    Compiled oct = compile_path(write_temp("box_octahedron.iq", camera + "[[shapes]]\ntype = \"octahedron\"\n"));
    REQUIRE(oct.result.exit_code == 0);
    auto b = box_of(oct.result.code);
    REQUIRE(b);
    const double m = fixed_level({0, 1, -5}, {-1, -1, -1}, {1, 1, 1});
    for (int a = 0; a < 3; ++a) {
        INFO("axis " << a << ": [" << b->first[a] << ", " << b->second[a] << "], level " << m);
        CHECK(b->second[a] >= 1 + m);
        CHECK(b->second[a] <= 1 + m + 0.02);
        CHECK(b->first[a] <= -1 - m);
        CHECK(b->first[a] >= -1 - m - 0.02);
    }
    // The pyramid (by default a square base of side 1.4 at y = -0.6, its apex at y = 0.6): its cases close the
    // sides along x and z, which were open.
    Compiled pyr = compile_path(write_temp("box_pyramid.iq", camera + "[[shapes]]\ntype = \"pyramid\"\n"));
    REQUIRE(pyr.result.exit_code == 0);
    b = box_of(pyr.result.code);
    REQUIRE(b);
    const double extent[3] = {0.7, 0.6, 0.7};
    const double mp = fixed_level({0, 1, -5}, {-0.7, -0.6, -0.7}, {0.7, 0.6, 0.7});
    for (int a = 0; a < 3; ++a) {
        INFO("axis " << a << ": [" << b->first[a] << ", " << b->second[a] << "], level " << mp);
        CHECK(b->second[a] >= extent[a] + mp);
        CHECK(b->second[a] <= extent[a] + mp + 0.03);
        CHECK(b->first[a] <= -extent[a] - mp);
        CHECK(b->first[a] >= -extent[a] - mp - 0.03);
    }
}

TEST_CASE("constants the shader holds in float: a call's argument and a parameter are boxed as the shader computes them",
          "[scene][box]") {
    // A trial: `R_z`(10000000.49) inside a module, folded in double after inlining, turned the bar by 183°; the
    // shader passes the float 10000000 to R_z and draws it at 155°, and the box cut it (570 pixels). A parameter
    // default 10000000.49 is the float constant 10000000 on Shadertoy: sin of it differs by 0.48.
    const std::string camera = "[camera]\nposition = [0, 1, -6]\ntarget = [0, 0, 0]\n";
    auto module = [](const std::string& angle) {
        return "[modules]\nbar = \"\"\"\nshape\n`R_z` from transformations\nh = `R_z`(" + angle +
               ") (p, 1)\nq = (h_1, h_2, h_3)\nd = |q| - (1.5, 0.15, 0.15)\nD = ‖max(d, 0)‖ + min(max(d_1, d_2, d_3), 0)\n"
               "where\np ∈ ℝ³\n\"\"\"\n";
    };
    Compiled written = compile_path(write_temp("box_big_angle.iq", module("10000000.49") + camera + "[[shapes]]\ntype = \"bar\"\n"));
    Compiled as_float = compile_path(write_temp("box_float_angle.iq", module("10000000") + camera + "[[shapes]]\ntype = \"bar\"\n"));
    REQUIRE(written.result.exit_code == 0);
    REQUIRE(as_float.result.exit_code == 0);
    CHECK_THAT(written.result.code, Catch::Contains("R_z(10000000.0)"));  // what the shader computes
    auto a = box_of(written.result.code), b = box_of(as_float.result.code);
    REQUIRE(a);
    REQUIRE(b);
    for (int k = 0; k < 3; ++k) {
        INFO("axis " << k);
        CHECK(a->first[k] <= b->first[k]);
        CHECK(a->second[k] >= b->second[k]);
    }
    // The float angle's bar reaches y = ±(1.5 |sin 155°| + 0.15 |cos 155°|) = ±0.77 (the double angle's ±0.24).
    CHECK(a->second[1] >= 0.77);
    CHECK(differ_without_box(written.result, 96, 54) == 0);

    const std::string ball = "[modules]\nball = \"\"\"\nshape\nsin from trigonometry\nD = ‖p‖ - (1 + sin(a))\nwhere\np ∈ ℝ³\n"
                             "a ∈ ℝ default = 10000000.49\n\"\"\"\n";
    Compiled c = compile_path(write_temp("box_big_parameter.iq", ball + camera + "[[shapes]]\ntype = \"ball\"\n"));
    REQUIRE(c.result.exit_code == 0);
    auto bb = box_of(c.result.code);
    REQUIRE(bb);
    const double r = 1 + std::sin(double(float(10000000.49)));  // 1.42: the shader's radius
    for (int k = 0; k < 3; ++k) {
        CHECK(bb->second[k] >= r);
        CHECK(bb->first[k] <= -r);
    }
    CHECK(differ_without_box(c.result, 96, 54) == 0);
}

TEST_CASE("numbers are analysed as the float literals the shader holds, and min of a NaN takes the other operand",
          "[scene][box]") {
    // A trial (every one a shape cut by its box, or a shell the march stepped over): a number written in the
    // math was analysed at its double value while the shader holds the float literal (16777217 is 16777216 there).
    const std::string camera = "[camera]\nposition = [0, 1, -9]\ntarget = [0, 0, 0]\n";
    struct Case {
        const char* name;
        const char* module;
        double radius;  // the shader's: the box must reach it
    };
    const Case cases[] = {
        {"parameter", "D = ‖p‖ - 3 + 2(16777217 - a)\nwhere\np ∈ ℝ³\na ∈ ℝ default = 16777216\n", 3},
        {"piecewise", "D = { ‖p‖ - 1 if a < 16777217\n      ‖p‖ - 3 otherwise\nwhere\np ∈ ℝ³\na ∈ ℝ default = 16777216\n", 3},
        {"local", "f(x) = 16777217 - x where x ∈ ℝ\nD = ‖p‖ - 3 + 2f(16777216)\nwhere\np ∈ ℝ³\n", 3},
        {"sine", "sin from trigonometry\nD = ‖p‖ - (1 + sin(10000000.49 + a))\nwhere\np ∈ ℝ³\na ∈ ℝ default = 0\n",
         1 + std::sin(double(float(10000000.49)))},
        // exp(89) and exp(88.8) overflow float: ∞/∞ is NaN, and llvmpipe's min(NaN, 3) is 3 (intervals gave e^0.2).
        {"overflow", "D = ‖p‖ - min(exp(a)/exp(a - 0.2), 3)\nwhere\np ∈ ℝ³\na ∈ ℝ default = 89\n", 3},
    };
    for (const Case& c : cases) {
        INFO(c.name);
        Compiled r = compile_path(write_temp(std::string("box_float_") + c.name + ".iq",
                                             "[modules]\nball = \"\"\"\nshape\n" + std::string(c.module) + "\"\"\"\n" + camera +
                                                 "[[shapes]]\ntype = \"ball\"\n"));
        INFO(r.diagnostics);
        REQUIRE(r.result.exit_code == 0);
        auto b = box_of(r.result.code);
        REQUIRE(b);
        for (int k = 0; k < 3; ++k) {
            CHECK(b->second[k] >= c.radius);
            CHECK(b->first[k] <= -c.radius);
        }
        CHECK(differ_without_box(r.result, 96, 54) == 0);
    }
    // A polytope whose face offset comes from a local function's literal: the flattened copy (convex bounds, case
    // splitting, rotations) folded 16777217 − 16777216 to 1 in double and boxed x at ±1; the shader's is 0 (±2).
    Compiled poly = compile_path(write_temp(
        "box_float_polytope.iq", "[modules]\npoly = \"\"\"\nshape\nf(x) = 16777217 - x where x ∈ ℝ\nD = max(|p_1| + f(16777216) - 2, "
                                 "|p_2| - 1, |p_3| - 1)\nwhere\np ∈ ℝ³\n\"\"\"\n" + camera + "[[shapes]]\ntype = \"poly\"\n"));
    REQUIRE(poly.result.exit_code == 0);
    auto pb = box_of(poly.result.code);
    REQUIRE(pb);
    CHECK(pb->second[0] >= 2);
    CHECK(pb->first[0] <= -2);
    CHECK(differ_without_box(poly.result, 96, 54) == 0);
    // The Lipschitz factor of a field scaled by 5 + 5 sin(100206355.14): 6e-6 in double, so no divisor was
    // written, where the shader's float argument gives a factor of 10 and the march stepped over the shell.
    Compiled shell = compile_path(write_temp(
        "lipschitz_float_shell.iq", "[modules]\nshell = \"\"\"\nshape\nsin from trigonometry\nD = (|‖p‖ - 1| - 0.05)(5 + "
                                    "5sin(100206355.14 + a))\nwhere\np ∈ ℝ³\na ∈ ℝ default = 0\n\"\"\"\n" +
                                        camera + "[[shapes]]\ntype = \"shell\"\n"));
    REQUIRE(shell.result.exit_code == 0);
    std::smatch k;
    REQUIRE(std::regex_search(shell.result.code, k, std::regex(R"(shell_1_lipschitz = ([0-9.e+]+);)")));
    CHECK(std::stod(k[1]) >= 9.99);
}

TEST_CASE("folded prisms and cones are boxed on every side: the half-space proofs split the other axes too",
          "[scene][box]") {
    // A proof that a half-space x ≥ c holds no point within the level splits its boxes at their widest side. A
    // half-space's own axis is unbounded, and split along it alone its far half is a half-space again: the other
    // axes were never narrowed. The hexagonal and octagonal prisms fold |p| by a reflection, p − 2 min(k⋅p, 0) k,
    // whose intervals prove nothing unless y is bounded; the cones' distance picks between two candidates by
    // the sign of a cross product. All four were open along x (the cones along z too): every ray marched from
    // the camera. Where every analysis leaves a side open, its search runs again with the unbounded sides split
    // in turn.
    const std::string camera = "[camera]\nposition = [0, 1, -5]\ntarget = [0, 0, 0]\n";
    struct Case {
        const char* type;
        std::array<double, 3> lo, hi;  // the solid's extent at the module's defaults
        double slack;                  // how far past extent + level the box may reach (this stop's boxes: within it)
    };
    const double hex = 0.7 * 2 / std::sqrt(3.0), cone = 1.6 * std::tan(0.45);
    const Case cases[] = {
        // (the folds' boxes stay loose in x: the fold's two terms share a⋅k, which intervals take apart; 0.89
        // and 1.09 for 0.82 and 0.81 at this stop)
        {"hex_prism", {-hex, -0.7, -0.6}, {hex, 0.7, 0.6}, 0.15},
        {"octagon_prism", {-0.8, -0.8, -0.4}, {0.8, 0.8, 0.4}, 0.4},
        {"cone", {-cone, -0.8, -cone}, {cone, 0.8, cone}, 0.25},  // (0.93 for 0.78 in x and z, 0.96 for 0.8 in y)
        {"round_cone", {-0.6, -1.2, -0.6}, {0.6, 0.85, 0.6}, 0.03},
    };
    for (const Case& c : cases) {
        Compiled out = compile_path(write_temp(std::string("box_") + c.type + ".iq",
                                               camera + "[[shapes]]\ntype = \"" + c.type + "\"\n"));
        REQUIRE(out.result.exit_code == 0);
        auto b = box_of(out.result.code);
        REQUIRE(b);
        const double m = fixed_level({0, 1, -5}, c.lo, c.hi);
        for (int a = 0; a < 3; ++a) {
            INFO(c.type << " axis " << a << ": [" << b->first[a] << ", " << b->second[a] << "], level " << m);
            CHECK(b->second[a] >= c.hi[a] + m);
            CHECK(b->second[a] <= c.hi[a] + m + c.slack);
            CHECK(b->first[a] <= c.lo[a] - m);
            CHECK(b->first[a] >= c.lo[a] - m - c.slack);
        }
    }
}
