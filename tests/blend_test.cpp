// Scene-level smooth unions (`[[blends]]`): the instances' distances joined by the polynomial smooth minimum,
// their materials mixed by its weights, analytic normals through it, and the error paths.
#include <catch2/catch.hpp>

#include <cmath>

#include "SceneRender.h"
#include "TestUtil.h"
#include "render/Render.h"

using namespace iqc;
using namespace iqc::test;

namespace {

// Two spheres side by side, red and blue (an emissive material: the colour is the material's alone),
// apart by 0.1 at their closest; `extra` adds tables.
std::string two_balls(const std::string& extra, const std::string& render = "") {
    return "[camera]\nposition = [0, 0, -5]\ntarget = [0, 0, 0]\nfov = 40\n"
           "[render]\noutput = \"linear\"\nbackground = [0, 0, 0]\n" + render +
           "[[shapes]]\nname = \"left\"\ntype = \"sphere\"\ntransform = \"T((-1.05, 0, 0))\"\nmaterial = \"emissive\"\n"
           "material_params = { k_e = [1, 0, 0], g = 0 }\n"
           "[[shapes]]\nname = \"right\"\ntype = \"sphere\"\ntransform = \"T((1.05, 0, 0))\"\nmaterial = \"emissive\"\n"
           "material_params = { k_e = [0, 0, 1], g = 0 }\n" + extra;
}

}  // namespace

TEST_CASE("a blend joins instances smoothly and mixes their materials", "[blend][render]") {
    render::Image apart = render_scene("apart.iq", two_balls(""));
    render::Image blended = render_scene("blended.iq", two_balls("[[blends]]\nshapes = [\"left\", \"right\"]\nradius = 0.5\n"));
    // Between the balls (the centre pixel): background apart, surface when blended (the neck).
    const float* gap = apart.pixel(48, 27);
    const float* neck = blended.pixel(48, 27);
    CHECK(gap[0] + gap[1] + gap[2] == Approx(0).margin(1e-3));
    CHECK(neck[0] + neck[2] > 0.9f);
    // At the neck both colours mix, half and half by symmetry (the pixel is just right of the middle); far from it each ball keeps its own.
    CHECK(neck[0] == Approx(0.5).margin(0.08));
    CHECK(neck[2] == Approx(0.5).margin(0.08));
    CHECK(blended.pixel(30, 27)[0] > 0.95f);
    CHECK(blended.pixel(66, 27)[2] > 0.95f);
    // Apart, no pixel mixes them.
    for (size_t i = 0; i < apart.rgba.size(); i += 4) CHECK_FALSE((apart.rgba[i] > 0.05f && apart.rgba[i + 2] > 0.05f));
}

TEST_CASE("a blend's analytic normals agree with finite differences", "[blend][render]") {
    // A lit blend: the shading depends on the normals, through the smooth minimum.
    auto scene = [](const char* normals) {
        return "[camera]\nposition = [0, 0, -5]\ntarget = [0, 0, 0]\nfov = 40\n[render]\nnormals = \"" + std::string(normals) +
               "\"\n[[lights]]\nposition = [-3, 4, -6]\n"
               "[[shapes]]\nname = \"a\"\ntype = \"sphere\"\ntransform = \"T((-0.8, 0, 0))\"\nmaterial = \"lambert\"\n"
               "[[shapes]]\nname = \"b\"\ntype = \"box\"\ntransform = \"T((0.8, 0.2, 0))\"\nmaterial = \"lambert\"\n"
               "[[blends]]\nshapes = [\"a\", \"b\"]\nradius = 0.6\n";
    };
    Compiled analytic = compile_text("blend_analytic.iq", scene("analytic"));
    REQUIRE(analytic.result.exit_code == 0);
    CHECK_THAT(analytic.diagnostics, !Catch::Contains("warning"));  // differentiated, no fall-back
    render::Image a = render_scene("blend_a.iq", scene("analytic"));
    render::Image t = render_scene("blend_t.iq", scene("central"));
    double diff = 0;
    for (size_t i = 0; i < a.rgba.size(); ++i) diff += std::fabs(a.rgba[i] - t.rgba[i]);
    CHECK(diff / double(a.rgba.size()) < 0.01);
}

TEST_CASE("blend error paths are located", "[blend][scene]") {
    auto err = [](const std::string& name, const std::string& blends) {
        RunResult r = run_iqc(write_temp(name, two_balls(blends)).string());
        CHECK(r.exit_code == 1);
        return r.err;
    };
    std::string unknown = err("blend_unknown.iq", "[[blends]]\nshapes = [\"left\", \"rigth\"]\n");
    CHECK_THAT(unknown, Catch::Contains("blend_unknown.iq:21:19: error: no instance is named 'rigth'"));
    CHECK_THAT(unknown, Catch::Contains("did you mean 'right'?"));
    std::string twice = err("blend_twice.iq", "[[blends]]\nshapes = [\"left\", \"right\"]\n[[blends]]\nshapes = [\"left\", \"right\"]\n");
    CHECK_THAT(twice, Catch::Contains("blend_twice.iq:23:11: error: 'left' is already blended"));
    CHECK_THAT(err("blend_one.iq", "[[blends]]\nshapes = [\"left\"]\n"),
               Catch::Contains("blend_one.iq:21:10: error: a blend joins at least two instances"));
    CHECK_THAT(err("blend_none.iq", "[[blends]]\nradius = 0.2\n"),
               Catch::Contains("blend_none.iq:20:1: error: a blend needs 'shapes'"));
    CHECK_THAT(err("blend_radius.iq", "[[blends]]\nshapes = [\"left\", \"right\"]\nradius = 0\n"),
               Catch::Contains("blend_radius.iq:22:10: error: a blend's 'radius' must be positive"));
    CHECK_THAT(err("blend_key.iq", "[[blends]]\nshapes = [\"left\", \"right\"]\nradious = 1\n"),
               Catch::Contains("error: unknown field 'radious' in [[blends]]"));
}

TEST_CASE("a blend member's bound is not used, with a located warning", "[blend][scene]") {
    std::string text = two_balls("[[blends]]\nshapes = [\"left\", \"right\"]\nradius = 0.5\n");
    text.replace(text.find("material = \"emissive\"\n"), 0, "bound = 1.5\n");
    Compiled c = compile_text("blend_bound.iq", text);
    REQUIRE(c.result.exit_code == 0);
    CHECK_THAT(c.diagnostics, Catch::Contains("blend_bound.iq:12:9: warning: `bound` is not used for 'left': it is part of a blend"));
    render::Image with = render_scene("blend_bound2.iq", text);
    render::Image without = render_scene("blend_nobound.iq", two_balls("[[blends]]\nshapes = [\"left\", \"right\"]\nradius = 0.5\n"));
    CHECK(max_abs_diff(with, without) < 1e-4);
}
