// The scene compiler and runtime: targets and their inputs, the --meta description, the uniform budget,
// march and normal methods agreeing, the camera inside a shape, time-driven transforms, lights, and the
// scene's error paths.
#include <regex>
#include <catch2/catch.hpp>

#include <cmath>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "TestUtil.h"
#include "glsl/ShadertoyWrapper.h"
#include "render/Render.h"

using namespace iqc;
using namespace iqc::test;

namespace {

const std::string kBall = "❤: ball\n```iheartla\nshape\nD = ‖p‖ - r\nwhere\np ∈ ℝ³\nr ∈ [0,3] default = 1: radius\n```\n";

render::Image render_code(const std::string& code, int w = 96, int h = 54, float time = 0) {
    render::RenderOptions o;
    o.width = w;
    o.height = h;
    o.time = time;
    auto r = render::render_shadertoy(code, o);
    INFO(r.error);
    REQUIRE(r.ok);
    return r.image;
}

int nan_pixels(const render::Image& img) {
    int n = 0;
    for (float v : img.rgba) n += !std::isfinite(v);
    return n;
}

double mean_abs_diff(const render::Image& a, const render::Image& b) {
    double s = 0;
    for (size_t i = 0; i < a.rgba.size(); i += 4)
        for (int c = 0; c < 3; ++c) s += std::fabs(a.rgba[i + size_t(c)] - b.rgba[i + size_t(c)]);
    return s / double(a.rgba.size() / 4 * 3);
}

std::string scene_with(const std::string& render_table) {
    return read_text(std::filesystem::path(IQC_SOURCE_DIR) / "golden" / "effects" / "base.iq") + "\n" + render_table;
}

}  // namespace

TEST_CASE("webgl2 and glsl330 take a uniform per parameter and describe them in --meta", "[scene]") {
    auto in = std::filesystem::path(IQC_SOURCE_DIR) / "examples" / "gallery.iq";
    auto meta = temp_dir() / "gallery.json";
    RunResult r = run_iqc(in.string() + " --target webgl2 --meta " + meta.string() + " -o " + (temp_dir() / "g.frag").string());
    INFO(r.err);
    REQUIRE(r.exit_code == 0);
    std::string code = read_text(temp_dir() / "g.frag");
    CHECK_THAT(code, Catch::StartsWith("#version 300 es"));
    CHECK_THAT(code, Catch::Contains("uniform float ball_shape_r;"));
    CHECK_THAT(code, Catch::Contains("uniform float ring_transform_theta;"));
    CHECK_THAT(code, Catch::Contains("void iqc_prepare()"));  // transforms with uniforms are inverted per pixel
    auto j = nlohmann::json::parse(read_text(meta));
    CHECK(j["target"] == "webgl2");
    bool found = false;
    for (auto& p : j["parameters"]) {
        if (p["uniform"] == "ring_transform_theta") {
            found = true;
            CHECK(p["instance"] == "ring");
            CHECK(p["role"] == "transform");
            CHECK(p["type"] == "float");
            CHECK(p["bounds"][0][0] == Approx(-3.14));
            CHECK(p["default"][0] == Approx(1.2));
            CHECK(p["description"] == "tilt");
        }
    }
    CHECK(found);
    RunResult g = run_iqc(in.string() + " --target glsl330");
    CHECK(g.exit_code == 0);
    CHECK_THAT(g.out, Catch::StartsWith("#version 330 core"));
}

TEST_CASE("past WebGL2's 224 uniform vectors, parameters go into uniform blocks", "[scene]") {
    std::string s = kBall + "```scene\n";
    for (int i = 0; i < 60; ++i)
        s += "[[shapes]]\ntype = \"ball\"\ntransform = \"\"\"T(X)⋅`R_x`(a)⋅`R_y`(b)⋅`R_z`(c)\nwhere\nX ∈ ℝ³\na, b, c ∈ ℝ\"\"\"\n";
    s += "```\n";
    auto in = write_temp("budget.md", s);
    auto meta = temp_dir() / "budget.json";
    RunResult r = run_iqc(in.string() + " --target webgl2 --meta " + meta.string());
    CHECK(r.exit_code == 0);
    CHECK_THAT(r.out, Catch::Contains("layout(std140) uniform iqc_block_0 {"));
    CHECK_THAT(read_text(meta), Catch::Contains("\"storage\": \"block\""));
    CHECK(run_iqc(in.string()).exit_code == 0);  // Shadertoy: constants
}

TEST_CASE("every march method finds the same picture", "[scene][render]") {
    // Compared in linear light: the sRGB encoding would magnify the differences of the darkest pixels.
    auto sphere = compile_text("m_sphere.iq", scene_with("[render]\nmarch = \"sphere\"\noutput = \"linear\"\n"));
    REQUIRE(sphere.result.exit_code == 0);
    render::Image ref = render_code(sphere.result.code);
    for (const char* m : {"relaxed", "auto", "fixed"}) {
        std::string extra = std::string("[render]\noutput = \"linear\"\nmarch = \"") + m + "\"\n" + (std::string(m) == "fixed" ? "max_steps = 2000\nstep = 0.01\n" : "");
        auto c = compile_text(std::string("m_") + m + ".iq", scene_with(extra));
        INFO(m << c.diagnostics);
        REQUIRE(c.result.exit_code == 0);
        render::Image img = render_code(c.result.code);
        CHECK(nan_pixels(img) == 0);
        CHECK(mean_abs_diff(img, ref) < 0.01);
    }
}

TEST_CASE("the march loop's exits are breaks, its tests after the loop choices with one return", "[scene][march]") {
    // On a GPU (an NVIDIA H200, docs/accuracy.md "On a GPU") a `return` inside the march loop cost a few shapes
    // 12% of the frame against the hand-written shader's `break`; llvmpipe's frame 3-9%. Every method's loop
    // (the body of `for (int i = 0; i < IQC_MAX_STEPS...`) holds no return.
    for (const char* m : {"sphere", "relaxed", "auto", "segment"}) {
        auto c = compile_text(std::string("exits_") + m + ".iq", scene_with(std::string("[render]\nmarch = \"") + m + "\"\n"));
        INFO(m << c.diagnostics);
        REQUIRE(c.result.exit_code == 0);
        const std::string& code = c.result.code;
        size_t f = code.find("float iqc_march(");
        REQUIRE(f != std::string::npos);
        size_t loop = code.find("for (int i = 0; i < IQC_MAX_STEPS", f);
        REQUIRE(loop != std::string::npos);
        size_t open = code.find('{', loop), close = open;
        for (int depth = 0; close < code.size(); ++close) {
            if (code[close] == '{') ++depth;
            if (code[close] == '}' && --depth == 0) break;
        }
        REQUIRE(close < code.size());
        const std::string body = code.substr(open, close - open);
        CHECK(body.find("break;") != std::string::npos);
        CHECK_FALSE(std::regex_search(body, std::regex("\\breturn\\b")));  // (the comment's "returns" is no return)
        // After the loop one return, of iqc_march_end: the hit, the far end and the step cap as choices, not early
        // returns (llvmpipe compiled those as control flow around the whole march: 100 instances' compile and 8×8
        // draw 462.9 -> 442.7 M instructions with the next check, bench/compile_count.sh).
        const std::string after = code.substr(close, code.find("\n}\n", close) - close);
        CHECK_THAT(after, Catch::Contains("return iqc_march_end(last, last_t, last_id, t > t_far, "));
        const std::regex ret("\\breturn\\b");
        CHECK(std::distance(std::sregex_iterator(after.begin(), after.end(), ret), std::sregex_iterator()) == 1);
        // Sphere tracing has no return before its loop either: a ray that misses the box fails the loop's test.
        if (std::string(m) == "sphere" || std::string(m) == "segment")
            CHECK_FALSE(std::regex_search(code.substr(f, loop - f), std::regex("\\breturn\\b")));
        const size_t cap = code.find("float iqc_at_step_cap(");
        REQUIRE(cap != std::string::npos);
        CHECK_FALSE(std::regex_search(code.substr(cap, code.find("\n}\n", cap) - cap), std::regex("\\breturn\\b[^;]*;[^}]*\\breturn")));
        // (segment tracing's own loop, not the sphere-tracing one it falls back to)
        if (std::string(m) == "segment") CHECK_THAT(body, Catch::Contains("iqc_segment_clear("));
    }
}

TEST_CASE("every normal method shades the same", "[scene][render]") {
    auto tet = compile_text("n_t.iq", scene_with(""));
    render::Image ref = render_code(tet.result.code);
    for (const char* n : {"central", "forward", "analytic"}) {
        auto c = compile_text(std::string("n_") + n + ".iq", scene_with(std::string("[render]\nnormals = \"") + n + "\"\n"));
        REQUIRE(c.result.exit_code == 0);
        render::Image img = render_code(c.result.code);
        INFO(n);
        CHECK(nan_pixels(img) == 0);
        CHECK(mean_abs_diff(img, ref) < 0.01);
    }
}

TEST_CASE("a camera inside a shape still renders: the inner wall, no NaN", "[scene][render]") {
    auto c = compile_text("inside.md", kBall + "```scene\n[camera]\nposition = [0, 0, 0]\ntarget = [0, 0, 1]\n"
                                                "[[shapes]]\ntype = \"ball\"\nshape_params = { r = 2 }\n```\n");
    REQUIRE(c.result.exit_code == 0);
    render::Image img = render_code(c.result.code);
    CHECK(nan_pixels(img) == 0);
    const float* px = img.pixel(48, 27);  // looking at the wall along +z: its normal faces us, (0, 0, -1)
    CHECK(px[0] == Approx(0.5f).margin(0.02));
    CHECK(px[2] == Approx(0.0f).margin(0.02));
}

TEST_CASE("the march tests its first sample's sign only where a march can start inside a shape", "[scene]") {
    // The inside-start test (a compare and a select in every step) is left out where the compiler proved every
    // march starts outside every shape: a fixed Shadertoy camera, no reflection or refraction rays, no input,
    // and the distance at the camera above ten hit tolerances. Everywhere else it stays.
    const std::string test = "if (i == 0 && h.x < 0.0) s = -1.0;";
    auto code = [](const std::string& name, const std::string& scene, Target target = Target::Shadertoy) {
        CompileOptions o;
        o.target = target;
        Compiled c = compile_path(write_temp(name, scene), o);
        INFO(c.diagnostics);
        REQUIRE(c.result.exit_code == 0);
        return c.result.code;
    };
    const std::string ball = kBall + "```scene\n[camera]\nposition = [0, 0, -5]\ntarget = [0, 0, 0]\n[[shapes]]\ntype = \"ball\"\n";
    CHECK_THAT(code("outside.md", ball + "```\n"), !Catch::Contains(test));
    // The camera inside the ball, or within ten tolerances of its surface.
    CHECK_THAT(code("inside.md", kBall + "```scene\n[camera]\nposition = [0, 0, 0.5]\n[[shapes]]\ntype = \"ball\"\n```\n"),
               Catch::Contains(test));
    CHECK_THAT(code("touching.md", kBall + "```scene\n[camera]\nposition = [0, 0, -1.005]\n[[shapes]]\ntype = \"ball\"\n```\n"),
               Catch::Contains(test));
    // A camera the user can move (an orbit, or uniforms on every other target), a ball that moves with time.
    CHECK_THAT(code("orbit.md", kBall + "```scene\n[camera]\nposition = [0, 0, -5]\ntarget = [0, 0, 0]\norbit = true\n"
                                        "[[shapes]]\ntype = \"ball\"\n```\n"),
               Catch::Contains(test));
    CHECK_THAT(code("uniform.md", ball + "```\n", Target::WebGL2), Catch::Contains(test));
    CHECK_THAT(code("timed.md", ball + "transform = \"T((0, 0, time))\"\n```\n"), Catch::Contains(test));
    // A noise terrain 0.03 below the camera in double precision: its hash (fract of a large sine) differs in
    // float, where the camera was inside (a new-user trial): a field with steps keeps the test.
    CHECK_THAT(code("noise.md", "```scene\n[camera]\nposition = [2.6, -0.246943, 2.7]\ntarget = [2.6, -0.246943, 7.7]\n"
                                "[render]\nmax_dist = 40\n[[shapes]]\ntype = \"terrain\"\n```\n"),
               Catch::Contains(test));
    // But a field with steps whose interval over a box around the camera stays above the level leaves it out: the
    // Menger sponge's mod-folded holes are cut from a box the camera is outside of (max(box, holes) ≥ box).
    Compiled sponge = compile_path(std::string(IQC_SOURCE_DIR) + "/bench/fractal.iq");
    REQUIRE(sponge.result.exit_code == 0);
    CHECK_THAT(sponge.result.code, Catch::Contains("mod("));
    CHECK_THAT(sponge.result.code, !Catch::Contains(test));
    // A camera outside the scene's box: every march starts where its ray enters the box, where every instance's
    // distance is above the box's level. 100 tori on a lattice (their cells' floors defeat the interval test
    // around the camera) leave the test out; with the camera inside their box, between the tori, it stays.
    const std::string tori = read_text(std::filesystem::path(IQC_SOURCE_DIR) / "bench" / "instances_100.iq");
    REQUIRE(tori.find("position = [0, 0, -14]") != std::string::npos);
    CHECK_THAT(code("tori.iq", tori), !Catch::Contains(test));
    std::string between = tori;
    between.replace(between.find("position = [0, 0, -14]"), 22, "position = [0, 0, 0.2]");
    CHECK_THAT(code("tori_between.iq", between), Catch::Contains(test));
    // Glass: a refracted ray starts inside it.
    CHECK_THAT(code("glass.md", kBall + "```scene\n[camera]\nposition = [0, 0, -5]\ntarget = [0, 0, 0]\n[effects]\nrefraction = true\n"
                                        "[[shapes]]\ntype = \"ball\"\nmaterial = \"glass\"\n```\n"),
               Catch::Contains(test));
}

TEST_CASE("a division by a constant is emitted as a multiplication by its reciprocal", "[scene][glsl]") {
    // llvmpipe keeps x / c a division (several times a multiplication's latency); the Lipschitz factor divides
    // every step's distance.
    Compiled c = compile_text("third.md", "❤: third\n```iheartla\nshape\nD = ‖p‖/3 - r\nwhere\np ∈ ℝ³\nr ∈ [0,3] default = 1\n```\n"
                                          "```scene\n[[shapes]]\ntype = \"third\"\n```\n");
    REQUIRE(c.result.exit_code == 0);
    CHECK_THAT(c.result.code, Catch::Contains("length(p) * 0.33333334"));
    CHECK_THAT(c.result.code, !Catch::Contains("length(p) / 3.0"));
}

TEST_CASE("a transform must be affine at every moment and slider value", "[scene]") {
    // The shader inverts a transform as an affine map and never reads its last row. Checked at the parameters'
    // values only, [1 0 0 0; 0 1 0 0; 0 0 1 0; time 0 0 1] (affine at time 0) was accepted and drew as if
    // time were 0 (a new user's trial, stop 38); so was a slider that makes the row (s, 0, 0, 1) at s ≠ 0.
    auto scene = [](const std::string& transform) {
        return "[[shapes]]\ntype = \"sphere\"\ntransform = \"\"\"" + transform + "\"\"\"\n";
    };
    Compiled fixed = compile_text("fixed_projective.iq", scene("[1 0 0 0; 0 1 0 0; 0 0 1 0; 0.5 0 0 1]"));
    CHECK(fixed.result.exit_code == 1);
    CHECK_THAT(fixed.diagnostics, Catch::Contains("fixed_projective.iq:3:16: error: the transform's last row is (0.5, 0, 0, 1), not (0, 0, 0, 1)"));
    Compiled timed = compile_text("timed_projective.iq", scene("[1 0 0 0; 0 1 0 0; 0 0 1 0; time 0 0 1]"));
    CHECK(timed.result.exit_code == 1);
    CHECK_THAT(timed.diagnostics, Catch::Contains("timed_projective.iq:3:16: error: the transform's last row is (0.37, 0, 0, 1) at "
                                                  "time = 0.37, mouse = (0.13, 0.91), not (0, 0, 0, 1)"));
    CHECK_THAT(timed.diagnostics, Catch::Contains("at every moment and slider value"));
    std::string slider = scene("[1 0 0 0; 0 1 0 0; 0 0 1 0; s 0 0 1]\nwhere\ns ∈ [-1, 1] default = 0");
    for (Target target : {Target::Shadertoy, Target::WebGL2}) {
        CompileOptions o;
        o.target = target;
        Compiled c = compile_path(write_temp("slider_projective_" + std::to_string(int(target)) + ".iq", slider), o);
        INFO(int(target));
        CHECK(c.result.exit_code == 1);
        CHECK_THAT(c.diagnostics, Catch::Contains(":3:16: error: the transform's last row is (-1, 0, 0, 1) at s = -1, not (0, 0, 0, 1)"));
    }
    // Affine at every moment: accepted.
    Compiled moving = compile_text("moving_affine.iq", scene("T((time, 0, 0))⋅`R_y`(time)⋅S((1 + time, 1, 1))"));
    CHECK(moving.result.exit_code == 0);
}

TEST_CASE("a transform that uses time is evaluated per pixel, even on Shadertoy", "[scene][render]") {
    auto c = compile_text("timed.md", kBall + "```scene\n[[shapes]]\ntype = \"ball\"\ntransform = \"T((time, 0, 5))\"\n"
                                               "shape_params = { r = 0.5 }\n```\n");
    REQUIRE(c.result.exit_code == 0);
    CHECK_THAT(c.result.code, Catch::Contains("void iqc_prepare()"));
    CHECK_THAT(c.result.code, Catch::Contains("iTime"));
    render::Image at0 = render_code(c.result.code, 96, 54, 0.0f);
    render::Image at1 = render_code(c.result.code, 96, 54, 1.0f);
    // The ball moves right: the centre pixel is lit at t = 0 and background at t = 1.
    CHECK(at0.pixel(48, 27)[0] != at1.pixel(48, 27)[0]);
}

TEST_CASE("global lights bind to P_L and C_L: each light adds its term", "[scene][render]") {
    std::string mat =
        "❤: lambert\n```iheartla\nmaterial\nC = `C_L`max(0, L̂⋅N̂)\nL̂ = (`P_L` - p)/‖`P_L` - p‖\nwhere\np ∈ ℝ³\nN̂ ∈ ℝ³\nI ∈ ℝ³\n"
        "`P_L` ∈ ℝ³\n`C_L` ∈ ℝ³\n```\n";
    auto one = compile_text("one_light.md", kBall + mat + "```scene\n[[lights]]\nposition = [0, 0, -10]\ncolor = [0.5, 0, 0]\n"
                                                          "[[shapes]]\ntype = \"ball\"\nmaterial = \"lambert\"\ntransform = \"T((0,0,5))\"\n```\n");
    auto two = compile_text("two_lights.md", kBall + mat + "```scene\n[[lights]]\nposition = [0, 0, -10]\ncolor = [0.5, 0, 0]\n"
                                                           "[[lights]]\nposition = [0, 0, -10]\ncolor = [0, 0.25, 0]\n"
                                                           "[[shapes]]\ntype = \"ball\"\nmaterial = \"lambert\"\ntransform = \"T((0,0,5))\"\n```\n");
    REQUIRE(one.result.exit_code == 0);
    REQUIRE(two.result.exit_code == 0);
    // The material is called once per light with that light's position and colour as P_L and C_L.
    CHECK_THAT(one.result.code, Catch::Contains("lambert(p, N, eye, P_L, C_L)"));
    CHECK_THAT(one.result.code, Catch::Contains("if (l == 0) position = light_1_position;"));
    CHECK_THAT(one.result.code, Catch::Contains("if (l == 0) colour = light_1_color;"));
    render::Image ia = render_code(one.result.code), ib = render_code(two.result.code);
    const float* a = ia.pixel(48, 27);
    const float* b = ib.pixel(48, 27);
    CHECK(a[0] == Approx(0.5f).margin(0.01));  // facing the light: max(0, L̂⋅N̂) = 1
    CHECK(b[1] == Approx(0.25f).margin(0.01));
}

TEST_CASE("scene error paths are located", "[scene]") {
    RunResult m = run_iqc(write_temp("march.iq", scene_with("[render]\nmarch = \"spere\"\n")).string());
    CHECK(m.exit_code == 1);
    CHECK_THAT(m.err, Catch::Contains("error: unknown march method 'spere': choose one of fixed, sphere, relaxed, auto"));
    CHECK_THAT(m.err, Catch::Contains("note: did you mean 'sphere'?"));
    RunResult n = run_iqc(write_temp("normals.iq", scene_with("[render]\nnormals = \"analytical\"\n")).string());
    CHECK(n.exit_code == 1);
    CHECK_THAT(n.err, Catch::Contains("error: unknown normals method 'analytical'"));
    CHECK_THAT(n.err, Catch::Contains("did you mean 'analytic'?"));
    RunResult e = run_iqc(write_temp("effects.iq", scene_with("[effects]\nshadow = \"soft\"\nao = 1\n")).string());
    CHECK(e.exit_code == 1);
    CHECK_THAT(e.err, Catch::Contains("error: unknown field 'shadow' in [effects]"));
    CHECK_THAT(e.err, Catch::Contains("did you mean 'shadows'?"));
    CHECK_THAT(e.err, Catch::Contains("error: 'ao' must be true or false, not an integer"));
    RunResult l = run_iqc(write_temp("light.iq", scene_with("[[lights]]\ncolor = [1, 1]\n")).string());
    CHECK(l.exit_code == 1);
    CHECK_THAT(l.err, Catch::Contains("error: this [[lights]] entry has no 'position'"));
    CHECK_THAT(l.err, Catch::Contains("error: 'color' must have 3 components, not 2"));
}

namespace {
// The Menger sponge of examples/menger.iq (soft shadows on a floor), with or without `bound`.
std::string menger_scene(const std::string& bound_line) {
    std::string text = read_text(std::filesystem::path(IQC_SOURCE_DIR) / "examples" / "menger.iq");
    size_t at = text.find("type = \"menger\"\n");
    REQUIRE(at != std::string::npos);
    size_t line_end = text.find('\n', at) + 1;
    std::string out = text.substr(0, line_end) + bound_line;
    std::string rest = text.substr(line_end);
    if (rest.rfind("bound = ", 0) == 0) rest = rest.substr(rest.find('\n') + 1);  // the example's own bound
    return out + rest;
}
double mean_channel(const render::Image& img, int c) {
    double s = 0;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) s += img.pixel(x, y)[c];
    return s / double(img.width * img.height);
}
}  // namespace

TEST_CASE("`bound` skips the shape outside its bounding sphere: same picture, same geometry, fewer evaluations",
          "[scene][render]") {
    auto plain = compile_text("bound_off.iq", menger_scene(""));
    auto bounded = compile_text("bound_on.iq", menger_scene("bound = 1.74\n"));
    INFO(plain.diagnostics << bounded.diagnostics);
    REQUIRE(plain.result.exit_code == 0);
    REQUIRE(bounded.result.exit_code == 0);
    // The shape is evaluated only near its bounding sphere: a lazy branch in the scene function.
    CHECK_THAT(bounded.result.code, Catch::Contains("float bound = length(q) - sponge_bound;"));
    CHECK_THAT(bounded.result.code, Catch::Contains("if (bound > 0.1) {\n        sponge = bound;\n    } else {\n        sponge = menger("));
    CHECK_THAT(plain.result.code, !Catch::Contains("float bound"));
    render::Image a = render_code(plain.result.code), b = render_code(bounded.result.code);
    CHECK(nan_pixels(b) == 0);
    // Soft shadows read the distance's value (a penumbra): they march the scene without bound spheres, so
    // the picture is the plain one (issue 12: the bound darkened the shadow into a disc with bands).
    CHECK_THAT(bounded.result.code, Catch::Contains("vec2 h = iqc_scene_unbounded(p);"));
    CHECK_THAT(plain.result.code, !Catch::Contains("iqc_scene_unbounded"));
    CHECK(mean_abs_diff(a, b) < 0.002);
    {
        auto hard = [](std::string t) { return t.replace(t.find("shadows = \"soft\""), 16, "shadows = \"hard\""); };
        auto ph = compile_text("bound_off_h.iq", hard(menger_scene("")));
        auto bh = compile_text("bound_on_h.iq", hard(menger_scene("bound = 1.74\n")));
        REQUIRE(ph.result.exit_code == 0);
        REQUIRE(bh.result.exit_code == 0);
        CHECK(mean_abs_diff(render_code(ph.result.code), render_code(bh.result.code)) < 0.002);
    }
    // The double-precision model: the same hits at the same depths.
    const SceneModel &ma = *plain.result.model, &mb = *bounded.result.model;
    int hits = 0;
    for (int y = 1; y < 36; y += 4)
        for (int x = 1; x < 64; x += 4) {
            std::array<double, 3> ro, rd;
            ma.ray(x, y, 64, 36, ro, rd);
            int ia, ib;
            double ta = ma.trace(ro, rd, &ia), tb = mb.trace(ro, rd, &ib);
            INFO(x << "," << y);
            CHECK(ia == ib);
            if (ta >= 0 && tb >= 0) {
                CHECK(tb == Approx(ta).margin(1e-6));
                ++hits;
            }
        }
    CHECK(hits > 50);
    // Far from the sponge, the bound's distance (a lower bound); near it, the shape's.
    CHECK(mb.distance({0, 5, 0}) == Approx(5 - 1.74).margin(1e-12));
    CHECK(mb.distance({0, 1.7, 0}) == Approx(ma.distance({0, 1.7, 0})).margin(1e-12));
    // Instrumented builds: the scene is evaluated about as often, the sponge far less.
    CompileOptions io;
    io.instrument = true;
    auto ip = compile_path(write_temp("bound_off_i.iq", menger_scene("")), io);
    auto ib = compile_path(write_temp("bound_on_i.iq", menger_scene("bound = 1.74\n")), io);
    REQUIRE(ip.result.exit_code == 0);
    REQUIRE(ib.result.exit_code == 0);
    render::Image sp = render_code(ip.result.code), sb = render_code(ib.result.code);
    double shape_plain = mean_channel(sp, 3), shape_bound = mean_channel(sb, 3);
    double evals_plain = mean_channel(sp, 1);
    INFO("shape evaluations per pixel: " << shape_plain << " without bound, " << shape_bound << " with");
    // Two instances, both evaluated at every step of a march; a normal's taps (4 per hit pixel, counted as
    // evaluations) evaluate the hit instance only.
    CHECK(shape_plain <= 2 * evals_plain + 1e-6);
    CHECK(shape_plain >= 1.9 * evals_plain);
    CHECK(shape_bound < 0.8 * shape_plain);
}

TEST_CASE("`bound` must be a positive number, reported at the value", "[scene]") {
    const std::string head = "[[shapes]]\ntype = \"sphere\"\n";
    auto zero = compile_text("bound_zero.iq", head + "bound = 0\n");
    CHECK(zero.result.exit_code != 0);
    CHECK_THAT(zero.diagnostics, Catch::Contains("bound_zero.iq:3:9: error: 'bound' (a bounding sphere radius) must be "
                                                 "positive, not 0\n  bound = 0\n          ^"));
    auto neg = compile_text("bound_neg.iq", head + "bound = -1.5\n");
    CHECK_THAT(neg.diagnostics, Catch::Contains("bound_neg.iq:3:9: error: 'bound' (a bounding sphere radius) must be positive, not -1.5"));
    auto text = compile_text("bound_text.iq", head + "bound = \"big\"\n");
    CHECK(text.result.exit_code != 0);
    CHECK_THAT(text.diagnostics, Catch::Contains("bound_text.iq:3:9: error: 'bound' must be a number, not a string"));
}

TEST_CASE("overrides may be numbers or vectors or a matrix's rows or constant expressions", "[scene]") {
    const std::string head = "[modules]\nsq = \"\"\"\nshape\nD = ‖A p‖ - r\nwhere\np ∈ ℝ³\nA ∈ ℝ^(3×3)\nr ∈ [0, 3] default = 1\n\"\"\"\n";
    auto ok = compile_text("overrides.iq", head + "[[shapes]]\ntype = \"sq\"\nshape_params = { r = \"√2/2\", A = [[1, 0, 0], [0, 2, 0], [0, 0, 1]] }\n"
                                                  "[[shapes]]\ntype = \"sq\"\nshape_params = { A = \"[1 0 0; 0 3 0; 0 0 1]\" }\n");
    INFO(ok.diagnostics);
    REQUIRE(ok.result.exit_code == 0);
    CHECK_THAT(ok.result.code, Catch::Contains("const mat3 sq_1_shape_A = mat3(1.0, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 1.0);"));
    CHECK_THAT(ok.result.code, Catch::Contains("const float sq_1_shape_r = 0.70710677;"));
    CHECK_THAT(ok.result.code, Catch::Contains("const mat3 sq_2_shape_A = mat3(1.0, 0.0, 0.0, 0.0, 3.0, 0.0, 0.0, 0.0, 1.0);"));
    auto rows = compile_text("override_rows.iq", head + "[[shapes]]\ntype = \"sq\"\nshape_params = { A = [[1, 0], [0, 2]] }\n");
    CHECK(rows.result.exit_code == 1);
    CHECK_THAT(rows.diagnostics, Catch::Contains("override_rows.iq:12:18: error: 'A' is ℝ^(3×3) but the value is 2 rows of 2"));
    auto ragged = compile_text("override_ragged.iq", head + "[[shapes]]\ntype = \"sq\"\nshape_params = { A = [[1, 0, 0], [0, 2]] }\n");
    CHECK_THAT(ragged.diagnostics, Catch::Contains("override_ragged.iq:12:34: error: the rows of 'A' must have one length: this one "
                                                   "has 2, the first 3"));
    auto text = compile_text("override_text.iq", head + "[[shapes]]\ntype = \"sq\"\nshape_params = { r = \"two\" }\n");
    CHECK_THAT(text.diagnostics, Catch::Contains("override_text.iq:12:22: error: 'r' must be a number, an array, or a constant "
                                                 "expression such as \"√2\"; this string is not one"));
}

TEST_CASE("a ℤ parameter stays an integer: an int uniform and int in --meta and the same picture", "[scene][render]") {
    const std::string scene =
        "[modules]\nfolded = \"\"\"\nshape\nq_1 = p\nq_(k+1) = (|q_k_1|, |q_k_2|, |q_k_3|) - 0.3(1, 1, 1) for k ∈ 1..n\n"
        "D = ‖q_(n+1)‖ - 0.3\nwhere\np ∈ ℝ³\nn ∈ ℤ default = 3: folds\n\"\"\"\n[[shapes]]\ntype = \"folded\"\n";
    auto path = write_temp("int_param.iq", scene);
    CompileOptions o;
    o.target = Target::WebGL2;
    Compiled w = compile_path(path, o);
    INFO(w.diagnostics);
    REQUIRE(w.result.exit_code == 0);
    CHECK_THAT(w.result.code, Catch::Contains("uniform int folded_1_shape_n;  // n ∈ ℤ: folds (default 3)"));
    CHECK_THAT(w.result.code, Catch::Contains("float folded(vec3 p, int n) {"));
    auto meta = nlohmann::json::parse(w.result.meta);
    bool found = false;
    for (const auto& p : meta["parameters"])
        if (p["name"] == "n") {
            found = true;
            CHECK(p["type"] == "int");
            CHECK(p["default"][0] == 3);
        }
    CHECK(found);
    REQUIRE(w.result.inputs.uniforms.size() == 1);
    CHECK(w.result.inputs.uniforms[0].integer);
    Compiled s = compile_path(path);
    REQUIRE(s.result.exit_code == 0);
    CHECK_THAT(s.result.code, Catch::Contains("const int folded_1_shape_n = 3;"));
    auto a = render_compiled(s.result, 96, 54), b = render_compiled(w.result, 96, 54);
    REQUIRE(a.ok);
    REQUIRE(b.ok);
    CHECK(mean_abs_diff(a.image, b.image) < 1e-4);
}

TEST_CASE("a shape whose distance is an integer (D ∈ ℤ) is a real distance for every target", "[scene][render]") {
    // Found by a new-user trial: `D = n` with n ∈ ℤ passed the type check (ℤ where ℝ is asked) and the
    // shape function returned an int where the runtime reads a float: glslang rejected the shader (exit 3, an
    // internal error) for every target. The distance is converted where it leaves the module.
    const std::string scene = "[modules]\nfar = \"\"\"\nshape\nD = n⋅n\nwhere\np ∈ ℝ³\nn ∈ ℤ default = 2\n\"\"\"\n"
                              "[[shapes]]\ntype = \"far\"\n";
    auto path = write_temp("int_distance.iq", scene);
    for (Target t : {Target::Shadertoy, Target::WebGL2, Target::GLSL330, Target::SPIRV, Target::HLSL, Target::ThreeJS, Target::WGSL}) {
        CompileOptions o;
        o.target = t;
        Compiled c = compile_path(path, o);
        INFO(int(t) << "\n" << c.diagnostics << c.result.internal);
        CHECK(c.result.exit_code == 0);
    }
    // The field is 4 everywhere: nothing to hit, every pixel background (id -1).
    CompileOptions g;
    g.ids = true;
    Compiled c = compile_path(path, g);
    REQUIRE(c.result.exit_code == 0);
    CHECK_THAT(c.result.code, Catch::Contains("return float(D);"));
    render::RenderResult r = render_compiled(c.result, 9, 9);
    REQUIRE(r.ok);
    CHECK(r.image.pixel(4, 4)[1] == -1);
}

TEST_CASE("an effect nothing in the scene can show is a located warning", "[scene]") {
    // Shadows without lights, reflections and refraction without a material that has k_r, k_t (issue 12).
    Compiled c = compile_text("idle_effects.iq", "[effects]\nshadows = \"soft\"\nreflections = 2\nrefraction = true\n"
                                                 "[[shapes]]\ntype = \"sphere\"\n");
    REQUIRE(c.result.exit_code == 0);
    CHECK_THAT(c.diagnostics, Catch::Contains("idle_effects.iq:2:11: warning: shadows have no effect: the scene has no point light or sun"));
    CHECK_THAT(c.diagnostics, Catch::Contains("idle_effects.iq:3:15: warning: reflections have no effect: no material has a reflectivity `k_r`"));
    CHECK_THAT(c.diagnostics, Catch::Contains("idle_effects.iq:4:14: warning: refraction has no effect"));
    // Lights, but no material reads P_L: still nothing to shadow.
    Compiled u = compile_text("unlit.iq", "[effects]\nshadows = \"hard\"\n[[lights]]\nposition = [1, 2, 3]\n[[shapes]]\ntype = \"sphere\"\n");
    REQUIRE(u.result.exit_code == 0);
    CHECK_THAT(u.diagnostics, Catch::Contains("unlit.iq:2:11: warning: shadows have no effect: no material is lit by the lights"));
    // A lit scene with shadows: no such warning.
    Compiled lit = compile_text("lit.iq", "[effects]\nshadows = \"hard\"\n[[lights]]\nposition = [1, 2, 3]\n[[shapes]]\ntype = \"sphere\"\n"
                                          "material = \"lambert\"\n");
    REQUIRE(lit.result.exit_code == 0);
    CHECK_THAT(lit.diagnostics, !Catch::Contains("have no effect"));
}

TEST_CASE("an override whose constant expression leaves the 32-bit float range is a located error", "[scene]") {
    // Found by a new-user trial: "(3e38, 3e38)*10" was accepted and clamped to 1e38 in the shader.
    Compiled c = compile_text("override_range.iq", "[[shapes]]\ntype = \"torus\"\nshape_params = { t = \"(3e38, 3e38)*10\" }\n");
    CHECK(c.result.exit_code == 1);
    CHECK_THAT(c.diagnostics, Catch::Contains("override_range.iq:3:22: error: 't' must be a number, an array, or a constant "
                                              "expression such as \"√2\"; this string is not one: the value of 't' is outside "
                                              "the range of 32-bit floats"));
}

TEST_CASE("the default step cap grows by the factor steps are shortened by: a box made thin by a scale draws as the thin box",
          "[scene][render][march]") {
    // A new user's trial: S((0.05, 1, 1)) multiplies a box's distance by 0.05, 20 times too small above and beside
    // it; rays passing near it ran out of the 128 steps and showed the background, a funnel through the ground
    // behind it (a twisted plate with K = 23.8 lost its top the same way, a terrain's ridges got dotted lines).
    auto scene = [](const std::string& box, const std::string& render) {
        return "[camera]\nposition = [0, 3, -7]\ntarget = [0, 0, 0]\n" + render +
               "[[shapes]]\ntype = \"plane\"\n[[shapes]]\ntype = \"box\"\n" + box;
    };
    auto scaled = compile_text("thin_scaled.iq", scene("transform = \"S((0.05, 1, 1))\"\n", ""));
    INFO(scaled.diagnostics);
    REQUIRE(scaled.result.exit_code == 0);
    CHECK_THAT(scaled.result.code, Catch::Contains("const int IQC_MAX_STEPS = 2048;  // max_steps 128 × 16: steps are up to that much "
                                                   "shorter than the distance to a surface here"));
    auto thin = compile_text("thin_params.iq", scene("shape_params = { b = [0.05, 0.6, 0.8] }\n", ""));
    REQUIRE(thin.result.exit_code == 0);
    CHECK_THAT(thin.result.code, Catch::Contains("const int IQC_MAX_STEPS = 128;\n"));
    // a step cap the scene sets is kept
    auto capped = compile_text("thin_capped.iq", scene("transform = \"S((0.05, 1, 1))\"\n", "[render]\nmax_steps = 128\n"));
    REQUIRE(capped.result.exit_code == 0);
    CHECK_THAT(capped.result.code, Catch::Contains("const int IQC_MAX_STEPS = 128;\n"));
    const int W = 320, H = 180;
    render::Image a = render_code(scaled.result.code, W, H), b = render_code(thin.result.code, W, H),
                  c = render_code(capped.result.code, W, H);
    auto differing = [&](const render::Image& x, const render::Image& y) {
        int n = 0;
        for (size_t i = 0; i < x.rgba.size(); i += 4) {
            float d = 0;
            for (int k = 0; k < 3; ++k) d = std::max(d, std::fabs(x.rgba[i + size_t(k)] - y.rgba[i + size_t(k)]));
            n += d > 3.0f / 255;
        }
        return n;
    };
    int grown = differing(a, b), kept = differing(c, b);
    INFO("differing pixels: grown cap " << grown << ", 128 steps " << kept);
    CHECK(grown <= W * H / 200);
    CHECK(kept > 4 * grown + 40);

    // A transform that moves or has sliders is sized as thin as it gets at the sampled moments and slider ends, not
    // at time 0 or the slider's default (a trial: S((0.55 + 0.5 sin(time), 1, 1)) kept a cap for 0.55, and at time
    // 10.1, a width of 0.24, the funnel came back; a slider S((s, 1, 1)) with s ∈ [0.05, 1] kept 128 on webgl2).
    auto moving = compile_text("thin_moving.iq", scene("transform = \"\"\"\nS((0.55 + 0.5 sin(time), 1, 1))\nwhere\nsin from "
                                                       "trigonometry\n\"\"\"\n", ""));
    INFO(moving.diagnostics);
    REQUIRE(moving.result.exit_code == 0);
    CHECK_THAT(moving.result.code, Catch::Contains("const int IQC_MAX_STEPS = 2048;"));
    CompileOptions web;
    web.target = Target::WebGL2;
    Compiled slider = compile_path(write_temp("thin_slider.iq", scene("transform = \"\"\"\nS((s, 1, 1))\nwhere\ns ∈ [0.05, 1] "
                                                                     "default = 1\n\"\"\"\n", "")), web);
    INFO(slider.diagnostics);
    REQUIRE(slider.result.exit_code == 0);
    CHECK_THAT(slider.result.code, Catch::Contains("const int IQC_MAX_STEPS = 2048;"));
    // At time 10.1 the moving box draws as the box scaled by its width then, 0.55 + 0.5 sin(10.1).
    auto still = compile_text("thin_still.iq", scene(fmt::format("transform = \"S(({:.9f}, 1, 1))\"\n", 0.55 + 0.5 * std::sin(10.1)), ""));
    REQUIRE(still.result.exit_code == 0);
    render::Image m = render_code(moving.result.code, W, H, 10.1f), st = render_code(still.result.code, W, H);
    INFO("moving box at 10.1 s against the still box: " << differing(m, st) << " pixels differ");
    CHECK(differing(m, st) <= W * H / 200);
}

TEST_CASE("fixed steps divide the reach by the step budget as set, not as grown for shortened steps", "[scene][march]") {
    // A trial: the grown cap (427 for S((0.3, 1, 1))) made `fixed`'s default step 3.3x shorter, and its cost per ray
    // 3.3x higher, though a fixed march takes no step by a distance. The step is the box's diagonal over 128.
    Compiled c = compile_text("fixed_scaled.iq", "[render]\nmarch = \"fixed\"\n[[shapes]]\ntype = \"box\"\ntransform = \"S((0.3, 1, 1))\"\n");
    REQUIRE(c.result.exit_code == 0);
    CHECK_THAT(c.result.code, Catch::Contains("const int IQC_MAX_STEPS = 427;"));  // (shadows are sphere-traced: grown)
    std::smatch lo, hi, step;
    const std::string& code = c.result.code;
    REQUIRE(std::regex_search(code, lo, std::regex(R"(IQC_BOX_LO = vec3\(([-0-9.e]+), ([-0-9.e]+), ([-0-9.e]+)\))")));
    REQUIRE(std::regex_search(code, hi, std::regex(R"(IQC_BOX_HI = vec3\(([-0-9.e]+), ([-0-9.e]+), ([-0-9.e]+)\))")));
    REQUIRE(std::regex_search(code, step, std::regex(R"(IQC_FIXED_STEP = ([0-9.e-]+);)")));
    double d2 = 0;
    for (int k = 1; k <= 3; ++k) d2 += std::pow(std::stod(hi[k]) - std::stod(lo[k]), 2);
    CHECK(std::stod(step[1]) == Approx(std::sqrt(d2) / 128).epsilon(1e-5));
}

TEST_CASE("soft shadows of a scene a thousand times smaller darken only what hard shadows darken", "[scene][render][effects]") {
    // A new user's trial: the penumbra's h / t was read at t ≥ 1e-4 (an absolute floor) while a scene a thousandth
    // of the size, with hit 1e-7, samples at t < 1e-4: every lit surface darkened (the floor 169 -> 70 of 255).
    auto scene = [](const char* shadows) {
        return fmt::format(
            "[camera]\nposition = [0, 0.002, -0.005]\ntarget = [0, 0, 0]\n[render]\nmax_dist = 0.1\nhit = 1e-7\noutput = \"linear\"\n"
            "[effects]\nshadows = \"{}\"\n[[lights]]\ndirection = [-0.5, 0.7, -0.4]\n"
            "[[shapes]]\ntype = \"plane\"\nmaterial = \"lambert\"\nshape_params = {{ h = 0.001 }}\n"
            "[[shapes]]\ntype = \"torus\"\nmaterial = \"lambert\"\ntransform = \"S((0.001, 0.001, 0.001))⋅T((-1.5, 0, 0))⋅`R_x`(1.2)\"\n"
            "[[shapes]]\ntype = \"sphere\"\nmaterial = \"lambert\"\ntransform = \"S((0.001, 0.001, 0.001))⋅T((0, 0.2, 1.5))\"\n"
            "shape_params = {{ r = 0.7 }}\n",
            shadows);
    };
    auto soft = compile_text("tiny_soft.iq", scene("soft")), hard = compile_text("tiny_hard.iq", scene("hard"));
    INFO(soft.diagnostics);
    REQUIRE(soft.result.exit_code == 0);
    REQUIRE(hard.result.exit_code == 0);
    const int W = 160, H = 90;
    render::Image s = render_code(soft.result.code, W, H), h = render_code(hard.result.code, W, H);
    CHECK(nan_pixels(s) == 0);
    int darker = 0, lit = 0;
    for (size_t i = 0; i < s.rgba.size(); i += 4) {
        float ls = s.rgba[i] + s.rgba[i + 1] + s.rgba[i + 2], lh = h.rgba[i] + h.rgba[i + 1] + h.rgba[i + 2];
        lit += lh > 0.05f;
        darker += lh > 0.05f && ls < 0.8f * lh;
    }
    INFO("lit pixels " << lit << ", of them darker with soft shadows " << darker);
    CHECK(lit > W * H / 4);
    CHECK(darker < lit / 50);
}

TEST_CASE("a sequence parameter's override takes its elements as rows, of the module's length or another", "[scene]") {
    // A new user's trial: x = [[…], […]] for x_i ∈ ℝ³ was "'x' is ℝ³[3] but the value is 3 rows of 3" (only the string
    // form was taken), and 5 points where the module's default has 3 said "has 15 components".
    auto scene = [](const std::string& value) {
        return "[modules]\nchain = \"\"\"\nshape\nD = ‖p - x_1‖ + ‖p - x_3‖ - 1\nwhere\np ∈ ℝ³\nx_i ∈ ℝ³ default = {(0, 0, 0), (1, 0, 0), "
               "(2, 0, 0)}\n\"\"\"\n[[shapes]]\ntype = \"chain\"\nshape_params = { x = " + value + " }\n";
    };
    Compiled rows = compile_text("seq_rows.iq", scene("[[-1, 0, 0], [0, 0.5, 0], [1, 0, 0]]"));
    Compiled text = compile_text("seq_text.iq", scene("\"{(-1, 0, 0), (0, 0.5, 0), (1, 0, 0)}\""));
    INFO(rows.diagnostics);
    REQUIRE(rows.result.exit_code == 0);
    REQUIRE(text.result.exit_code == 0);
    auto body = [](const std::string& code) { return code.substr(code.find("// ---- parameters")); };
    CHECK(body(rows.result.code) == body(text.result.code));
    CHECK_THAT(rows.result.code, Catch::Contains("vec3(-1.0, 0.0, 0.0)"));
    // Another length (stop 52; it was "an instance keeps the module's length"): the instance gets the module checked for
    // 5 points, a function of its own (chain_x5), and every target compiles it. Instances of either length share theirs.
    const std::string two = "\n[[shapes]]\ntype = \"chain\"\ntransform = \"T((0, 2, 0))\"\n[[shapes]]\ntype = \"chain\"\n"
                            "transform = \"T((0, -2, 0))\"\nshape_params = { x = \"{(0, 0, 0), (0, 1, 0), (0, 2, 0), (0, 3, 0), (0, 4, 0)}\" }\n";
    for (Target t : {Target::Shadertoy, Target::WebGL2, Target::WGSL}) {
        CompileOptions o;
        o.target = t;
        Compiled longer = compile_path(write_temp("seq_long.iq", scene("[[-1, 0, 0], [0, 0.5, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]]") + two), o);
        INFO(longer.diagnostics);
        REQUIRE(longer.result.exit_code == 0);
        if (t == Target::WGSL) continue;
        CHECK_THAT(longer.result.code, Catch::Contains("float chain_x5("));
        CHECK_THAT(longer.result.code, Catch::Contains("float chain("));
        if (t == Target::Shadertoy) CHECK_THAT(longer.result.code, Catch::Contains("vec3 x[5]"));
    }
    // The distances: D = ‖p - x_1‖ + ‖p - x_3‖ - 1 reads the first and third of the instance's own points: five points
    // whose first and third are those of three give the same field (the double-precision model runs the emitted IR);
    // five whose third differs do not.
    Compiled five = compile_text("seq_five.iq", scene("[[-1, 0, 0], [0, 0.5, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]]"));
    Compiled other = compile_text("seq_other.iq", scene("[[-1, 0, 0], [0, 0.5, 0], [2, 0, 0], [2, 0, 0], [3, 0, 0]]"));
    REQUIRE(five.result.exit_code == 0);
    REQUIRE(other.result.exit_code == 0);
    REQUIRE(rows.result.model);
    REQUIRE(five.result.model);
    REQUIRE(other.result.model);
    for (std::array<double, 3> at : {std::array<double, 3>{0, 1, 0}, {0.3, -0.2, 0.5}, {2, 2, 2}}) {
        CHECK(five.result.model->distance(at) == Approx(rows.result.model->distance(at)).epsilon(1e-12));
        CHECK(std::fabs(other.result.model->distance(at) - rows.result.model->distance(at)) > 1e-3);
    }
    // A value whose components are not whole elements is still an error.
    Compiled ragged = compile_text("seq_ragged.iq", scene("\"{(1, 0, 0), (2, 0)}\""));
    CHECK(ragged.result.exit_code == 1);
    // Two sequences of one index given different lengths: one error, at the override (a trial's were two or three,
    // located in the module, and said the default's length was the only one allowed). Past the size limit: one too.
    auto pair = [](const std::string& values) {
        return "[modules]\nblob = \"\"\"\nshape\nD = -log(∑_i exp(-8(‖p - x_i‖ - r_i)))/8\nwhere\np ∈ ℝ³\n"
               "x_i ∈ ℝ³ default = {(0, 0, 0), (1, 0, 0), (2, 0, 0)}\nr_i ∈ [0.05, 1] default = {0.3, 0.2, 0.25}\n\"\"\"\n"
               "[[shapes]]\ntype = \"blob\"\nshape_params = { " + values + " }\n";
    };
    Compiled five_three = compile_text("seq_pair.iq", pair("x = [[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0], [4, 0, 0]]"));
    CHECK(five_three.result.exit_code == 1);
    CHECK_THAT(five_three.diagnostics, Catch::EndsWith("seq_pair.iq:12:18: error: 'x' has 5 elements here, but 'r' has 3 (its "
                                                       "default): sequences indexed by i have one length; give 'r' 5 elements too\n"
                                                       "  shape_params = { x = [[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0], [4, 0, 0]] }\n"
                                                       "                   ^\n"));
    Compiled both = compile_text("seq_pair.iq", pair("x = [[0, 0, 0], [1, 0, 0]], r = [0.3]"));
    CHECK(both.result.exit_code == 1);
    CHECK_THAT(both.diagnostics, Catch::Contains("seq_pair.iq:12:46: error: 'r' has 1 element here, but 'x' has 2 here: "
                                                 "sequences indexed by i have one length; give both one length"));
    CHECK(count_of(both.diagnostics, "error:") == 1);
    // (r set to its default's length: set here all the same)
    Compiled kept = compile_text("seq_pair.iq", pair("x = [[0, 0, 0], [1, 0, 0]], r = [0.3, 0.2, 0.25]"));
    CHECK(kept.result.exit_code == 1);
    CHECK_THAT(kept.diagnostics, Catch::Contains("'x' has 2 elements here, but 'r' has 3 here: sequences indexed by i have one "
                                                 "length; give both one length"));
    Compiled fine = compile_text("seq_pair.iq", pair("x = [[0, 0, 0], [1, 0, 0]], r = [0.3, 0.4]"));
    CHECK(fine.result.exit_code == 0);
    // (its bounds in the shader's comment: one element's, not 2 × 1 intervals in a row)
    CHECK_THAT(fine.result.code, Catch::Contains("// r_i ∈ [0.05, 1]\n"));
    // An element outside the module's bounds (warned) widens its slider's: --meta and the HTML page's slider hold the
    // instance's value, and the analyses cover it (a trial's r = 1.5 over [0.05, 1] was a slider that stopped at 1).
    CompileOptions web;
    web.target = Target::WebGL2;
    Compiled wide = compile_path(write_temp("seq_wide.iq", pair("x = [[0, 0, 0], [1, 0, 0]], r = [0.3, 1.5]")), web);
    REQUIRE(wide.result.exit_code == 0);
    CHECK_THAT(wide.diagnostics, Catch::Contains("warning: the value 1.5 of 'r' is outside its slider bounds [0.05, 1]"));
    const auto meta = nlohmann::json::parse(wide.result.meta);
    int seen = 0;
    for (const auto& q : meta["parameters"]) {
        if (q["name"] != "r_1" && q["name"] != "r_2") continue;
        ++seen;
        CHECK(q["bounds"][0][0].get<double>() == 0.05);
        CHECK(q["bounds"][0][1].get<double>() == (q["name"] == "r_1" ? 1.0 : 1.5));
    }
    CHECK(seen == 2);
    std::string many;
    for (int k = 0; k < 1400; ++k) many += fmt::format("{}[{}, 0, 0]", k ? ", " : "", k);
    Compiled huge = compile_text("seq_huge.iq", pair("x = [" + many + "]"));
    CHECK(huge.result.exit_code == 1);
    CHECK_THAT(huge.diagnostics, Catch::Contains("seq_huge.iq:12:18: error: 'x' would have 1400 elements (4200 components): "
                                                   "iqc allows at most 4096 components in a sequence"));
    CHECK(count_of(huge.diagnostics, "error:") == 1);
}

TEST_CASE("a blend's shape does not depend on its members' Lipschitz factors", "[scene]") {
    // A trial (stop 52): a blend smooth-unioned its members' distances divided by their Lipschitz factors, so a factor K
    // made the blend radius K times larger: two balls 0.4 apart with radius 0.3 stayed apart under `# lipschitz: 1` and
    // merged under 4 (1,236 pixels), and a point cloud's factor (1 on Shadertoy, up to 12 on webgl2) changed its blend.
    // The blend takes the members' own distances and is divided by their largest factor.
    auto scene = [](double k1, double k2) {
        return fmt::format("[modules]\nball = \"\"\"\nshape\n# lipschitz: {}\nD = ‖p‖ - 0.6\nwhere\np ∈ ℝ³\n\"\"\"\n"
                           "ball2 = \"\"\"\nshape\n# lipschitz: {}\nD = ‖p‖ - 0.6\nwhere\np ∈ ℝ³\n\"\"\"\n"
                           "[camera]\nposition = [0, 0, -5]\ntarget = [0, 0, 0]\n"
                           "[[shapes]]\nname = \"a\"\ntype = \"ball\"\ntransform = \"T((-0.8, 0, 0))\"\n"
                           "[[shapes]]\nname = \"b\"\ntype = \"ball2\"\ntransform = \"T((0.8, 0, 0))\"\n"
                           "[[blends]]\nshapes = [\"a\", \"b\"]\nradius = 0.3\n", k1, k2);
    };
    Compiled one = compile_text("blend_k1.iq", scene(1, 1)), four = compile_text("blend_k4.iq", scene(4, 4)),
             mixed = compile_text("blend_k23.iq", scene(2, 3));
    REQUIRE(one.result.exit_code == 0);
    REQUIRE(four.result.exit_code == 0);
    REQUIRE(mixed.result.exit_code == 0);
    REQUIRE(one.result.model);
    REQUIRE(four.result.model);
    REQUIRE(mixed.result.model);
    // The distance between the balls (the blend's gap) and beside them: the factors only scale it.
    for (std::array<double, 3> at : {std::array<double, 3>{0, 0, 0}, {0, 0.3, 0}, {-0.8, 0.9, 0}, {1.5, 0, -1}}) {
        const double d = one.result.model->distance(at);
        CHECK(four.result.model->distance(at) * 4 == Approx(d).epsilon(1e-9));
        CHECK(mixed.result.model->distance(at) * 3 == Approx(d).epsilon(1e-9));
    }
    CHECK(one.result.model->distance({0, 0, 0}) > 0);  // (the gap stays open: 0.4 is wider than the blend bridges)
    CHECK_THAT(one.result.code, !Catch::Contains("_lipschitz"));  // factors of 1 fold away
    CHECK_THAT(mixed.result.code, Catch::Contains("max(a_lipschitz, b_lipschitz)"));
}
