// The lighting model (docs/look.md): a shadow darkens only its own light's part of a material, ambient
// occlusion only the light-independent part; suns, sky and bounce lights; the sky-gradient background; the
// output transform; Fresnel on mirrors and glass; the scene's new keys' error paths and warnings.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "SceneRender.h"
#include "TestUtil.h"
#include "render/Render.h"

using namespace iqc;
using namespace iqc::test;
namespace fs = std::filesystem;

namespace {

// A Lambert material with an ambient term: C = C_L∘k_d max(0, L̂⋅N̂) + k_a.
const std::string kLambert = R"(
[modules]
matte = """
material
C = `C_L`∘`k_d`max(0, L̂⋅N̂) + `k_a`
L̂ = normalize(`P_L` - p)
where
p ∈ ℝ³
N̂ ∈ ℝ³
I ∈ ℝ³
`P_L` ∈ ℝ³: light position
`C_L` ∈ ℝ³: light colour
`k_d` ∈ [0,1]x[0,1]x[0,1] default = (0.6, 0.6, 0.6): diffuse colour
`k_a` ∈ [0,1]x[0,1]x[0,1] default = (0.1, 0.05, 0.02): ambient colour
"""
)";

// A ground plane y = 0 and a ball of radius 1 at height `ball_y`, seen from (0, 6, -6) looking at the
// origin: the centre pixel sees the ground at the origin, straight below the ball.
std::string ground_and_ball(const std::string& material, double ball_y, const std::string& ground_params = "",
                            const std::string& ball_params = "") {
    return "[camera]\nposition = [0, 6, -6]\ntarget = [0, 0, 0]\nfov = 40\n"
           "[[shapes]]\nname = \"ground\"\ntype = \"plane\"\nshape_params = { h = 0 }\nmaterial = \"" +
           material + "\"\n" + ground_params +
           "\n[[shapes]]\nname = \"ball\"\ntype = \"sphere\"\nmaterial = \"" + material + "\"\n" +
           "transform = \"T((0, " + std::to_string(ball_y) + ", 0))\"\n" + ball_params + "\n";
}

}  // namespace

TEST_CASE("a shadow darkens only its own light's part: the ambient term stays", "[look][render]") {
    // A light straight above the ball: the ground at the origin is in its shadow.
    std::string base = kLambert + "[render]\noutput = \"linear\"\n[[lights]]\nposition = [0, 10, 0]\n" +
                       ground_and_ball("matte", 2.5);
    render::Image lit = render_scene("shadow_off.iq", base);
    render::Image shadowed = render_scene("shadow_on.iq", base + "[effects]\nshadows = \"hard\"\n");
    const float* off = lit.pixel(48, 27);
    const float* on = shadowed.pixel(48, 27);
    // Without the shadow: ambient plus the light's full term (facing it: 0.6 + 0.1).
    CHECK(off[0] == Approx(0.7).margin(0.02));
    // In the shadow: exactly the ambient term (0.1, 0.05, 0.02), not black (before: the ambient term was
    // part of the light's term and the shadow took it too).
    CHECK(on[0] == Approx(0.1).margin(0.005));
    CHECK(on[1] == Approx(0.05).margin(0.005));
    CHECK(on[2] == Approx(0.02).margin(0.005));
    // Two lights: the ambient term is added once, not once per light.
    render::Image two = render_scene("two_lights.iq", kLambert + "[render]\noutput = \"linear\"\n"
                                                      "[[lights]]\nposition = [0, 10, 0]\ncolor = [0, 0, 0]\n"
                                                      "[[lights]]\nposition = [0, 10, 0]\ncolor = [0, 0, 0]\n" +
                                                      ground_and_ball("matte", 2.5));
    CHECK(two.pixel(48, 27)[0] == Approx(0.1).margin(0.005));
}

TEST_CASE("ambient occlusion darkens only the light-independent part", "[look][render]") {
    // The ball rests on the ground: occlusion around the contact.
    std::string lights = "[render]\noutput = \"linear\"\n[[lights]]\nposition = [3, 8, -4]\n";
    std::string no_ambient = "material_params = { k_a = [0, 0, 0] }";
    std::string scene = kLambert + lights + ground_and_ball("matte", 1.0, no_ambient, no_ambient);
    render::Image plain = render_scene("ao_off.iq", scene);
    render::Image ao = render_scene("ao_on.iq", scene + "[effects]\nao = true\n");
    // Direct light only: ambient occlusion changes nothing (before: it darkened the direct light too).
    CHECK(max_abs_diff(plain, ao) < 1e-4);
    // With an ambient term, it darkens that term near the contact.
    std::string bright = "material_params = { k_a = [0.5, 0.5, 0.5] }";
    std::string with_ambient = kLambert + lights + ground_and_ball("matte", 1.0, bright, bright);
    render::Image amb = render_scene("ao_amb_off.iq", with_ambient);
    render::Image amb_ao = render_scene("ao_amb_on.iq", with_ambient + "[effects]\nao = true\n");
    CHECK(max_abs_diff(amb, amb_ao) > 0.02);
    for (size_t i = 0; i < amb.rgba.size(); i += 4)
        CHECK(amb_ao.rgba[i] >= amb.rgba[i] - 0.5f - 1e-4f);  // never more than the ambient term (0.5) darker
}

TEST_CASE("shadowed ground lit by sky and bounce is never pure black", "[look][render]") {
    const std::string lights =
        "[render]\nbackground = { zenith = [0.2, 0.35, 0.7], horizon = [0.6, 0.7, 0.85] }\n"
        "[[lights]]\nname = \"sun\"\ndirection = [0, 1, 0]\ncolor = [1.5, 1.4, 1.2]\n"
        "[[lights]]\ntype = \"sky\"\ncolor = [0.3, 0.4, 0.6]\n"
        "[[lights]]\ntype = \"bounce\"\ncolor = [0.2, 0.15, 0.1]\n";
    const std::string pbr = "material_params = { k_d = [0.3, 0.3, 0.3] }";
    std::string scene = lights + ground_and_ball("pbr", 2.5, pbr, pbr);
    render::Image sunlit = render_scene("outdoor_noshadow.iq", scene);
    render::Image img = render_scene("outdoor.iq", scene + "[effects]\nshadows = \"soft\"\nao = true\n");
    // The sun straight above: the ground below the ball is in its shadow ...
    CHECK(img.pixel(48, 27)[0] < sunlit.pixel(48, 27)[0] - 0.2f);
    // ... and every pixel (the shadow, the ball's underside, the sky) keeps some light in every channel.
    float darkest = 1;
    for (size_t i = 0; i < img.rgba.size(); i += 4)
        for (int c = 0; c < 3; ++c) darkest = std::min(darkest, img.rgba[i + size_t(c)]);
    CHECK(darkest > 0.08f);
    // The sky is what lights the shadow: without sky and bounce lights it is much darker.
    std::string sun_only = "[[lights]]\nname = \"sun\"\ndirection = [0, 1, 0]\ncolor = [1.5, 1.4, 1.2]\n";
    render::Image dark = render_scene("sun_only.iq", sun_only + ground_and_ball("pbr", 2.5, pbr, pbr) +
                                                         "[effects]\nshadows = \"soft\"\nao = true\n");
    CHECK(dark.pixel(48, 27)[2] < img.pixel(48, 27)[2] - 0.15f);
}

TEST_CASE("a sun lights every point from one direction, a point light from its position", "[look][render]") {
    // A sun straight above lights the flat ground the same everywhere (N⋅L = 1); a point light above the
    // origin lights the ground less away from it.
    std::string matte = kLambert + "[render]\noutput = \"linear\"\n[camera]\nposition = [0, 6, -6]\ntarget = [0, 0, 0]\n"
                                   "[[shapes]]\ntype = \"plane\"\nshape_params = { h = 0 }\nmaterial = \"matte\"\n"
                                   "material_params = { k_a = [0, 0, 0] }\n";
    render::Image sun = render_scene("sun.iq", matte + "[[lights]]\ntype = \"sun\"\ndirection = [0, 2, 0]\n");
    render::Image point = render_scene("point.iq", matte + "[[lights]]\nposition = [0, 1, 0]\n");
    CHECK(sun.pixel(48, 27)[0] == Approx(0.6).margin(0.005));
    CHECK(sun.pixel(48, 50)[0] == Approx(0.6).margin(0.005));
    CHECK(point.pixel(48, 50)[0] < point.pixel(48, 27)[0] - 0.05f);
}

TEST_CASE("the background can be a sky gradient, and the output is sRGB-encoded unless linear is asked for", "[look][render]") {
    std::string cam = "[camera]\nposition = [0, 0, -5]\ntarget = [0, 0, 0]\nfov = 90\n"
                      "[[shapes]]\ntype = \"sphere\"\ntransform = \"T((0, 0, 1000))\"\n";
    render::Image grad = render_scene("grad.iq", cam + "[render]\noutput = \"linear\"\nmax_dist = 50\n"
                                                       "background = { zenith = [0, 0, 1], horizon = [1, 0, 0], ground = [0, 1, 0] }\n");
    // Looking at the horizon: the horizon's colour at the centre row; toward the zenith above, the ground below.
    CHECK(grad.pixel(48, 27)[0] > 0.8f);
    CHECK(grad.pixel(48, 0)[2] > 0.6f);
    CHECK(grad.pixel(48, 0)[0] < grad.pixel(48, 27)[0]);
    CHECK(grad.pixel(48, 53)[1] > 0.6f);
    // One colour, 0.2 linear: sRGB encodes it as 0.4845 (a TOML scene's default), linear keeps 0.2.
    std::string flat = cam + "[render]\nmax_dist = 50\nbackground = [0.2, 0.2, 0.2]\n";
    CHECK(render_scene("srgb.iq", flat).pixel(10, 10)[0] == Approx(0.4845).margin(0.004));
    CHECK(render_scene("linear.iq", flat + "output = \"linear\"\n").pixel(10, 10)[0] == Approx(0.2).margin(0.004));
    // Tone maps and exposure: ACES maps 0.2·2 to 0.4·(2.51·0.4 + 0.03)/(0.4·(2.43·0.4 + 0.59) + 0.14).
    double x = 0.4, aces = x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14);
    CHECK(render_scene("aces.iq", flat + "output = \"linear\"\ntonemap = \"aces\"\nexposure = 2\n").pixel(10, 10)[0] ==
          Approx(aces).margin(0.004));
    CHECK(render_scene("reinhard.iq", flat + "output = \"linear\"\ntonemap = \"reinhard\"\n").pixel(10, 10)[0] ==
          Approx(0.2 / 1.2).margin(0.004));
}

TEST_CASE("contrast and vignette grade the encoded colour", "[look][render]") {
    std::string flat = "[camera]\nposition = [0, 0, -5]\ntarget = [0, 0, 0]\nfov = 90\n"
                       "[[shapes]]\ntype = \"sphere\"\ntransform = \"T((0, 0, 1000))\"\n"
                       "[render]\nmax_dist = 50\nbackground = [0.2, 0.2, 0.2]\noutput = \"linear\"\n";
    // Contrast: 0.2 → 0.2²(3 - 0.4) = 0.104 at 1, halfway at 0.5; mid grey stays.
    CHECK(render_scene("contrast.iq", flat + "contrast = 1\n").pixel(10, 10)[0] == Approx(0.104).margin(0.003));
    CHECK(render_scene("contrast5.iq", flat + "contrast = 0.5\n").pixel(10, 10)[0] == Approx(0.152).margin(0.003));
    // Vignette 0.5 on a 96×54 picture: the centre keeps 0.2, the top-left pixel (x = 0.5/96, y = 0.5/54 of the
    // way across) is 0.2·(1 - 0.5·(1 - (16·x(1 - x)·y(1 - y))^¼)).
    render::Image v = render_scene("vignette.iq", flat + "vignette = 0.5\n");
    CHECK(v.pixel(48, 27)[0] == Approx(0.2).margin(0.002));
    double x = 0.5 / 96, y = 0.5 / 54, corner = 0.2 * (1 - 0.5 * (1 - std::pow(16 * x * (1 - x) * y * (1 - y), 0.25)));
    CHECK(v.pixel(0, 0)[0] == Approx(corner).margin(0.003));
    CHECK(v.pixel(95, 53)[0] == Approx(corner).margin(0.003));
    CHECK(v.pixel(0, 0)[0] < 0.13f);
    // Off by default: no code for them.
    Compiled plain = compile_text("plain_grade.iq", flat);
    CHECK(plain.result.code.find("vignette") == std::string::npos);
    CHECK(plain.result.code.find("contrast") == std::string::npos);
}

TEST_CASE("I♥IQ documents keep the thesis's linear output", "[look]") {
    Compiled doc = compile_path(std::filesystem::path(IQC_SOURCE_DIR) / "examples" / "two_tori.md");
    REQUIRE(doc.result.exit_code == 0);
    CHECK_THAT(doc.result.code, !Catch::Contains("iqc_output"));
    Compiled scene = compile_path(std::filesystem::path(IQC_SOURCE_DIR) / "examples" / "gallery.iq");
    REQUIRE(scene.result.exit_code == 0);
    CHECK_THAT(scene.result.code, Catch::Contains("1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055"));
}

TEST_CASE("glass reflects by Fresnel at grazing angles, raised by its k_r", "[look][render]") {
    // A wide glass slab seen from above; the sky is red at the zenith and black at and below the horizon, so
    // any red on the slab is reflected sky (what the slab passes on reaches the black below it).
    auto scene = [](double k_r) {
        return "[camera]\nposition = [0, 2, -4]\ntarget = [0, 0, 2]\nfov = 60\n"
               "[render]\noutput = \"linear\"\nmax_dist = 60\n"
               "background = { zenith = [1, 0, 0], horizon = [0, 0, 0], ground = [0, 0, 0] }\n"
               "[effects]\nrefraction = true\n"
               "[[lights]]\nposition = [0, 5, -5]\ncolor = [0, 0, 0]\n"
               "[[shapes]]\ntype = \"box\"\nshape_params = { b = [20, 0.05, 20] }\nmaterial = \"glass\"\n"
               "material_params = { k_r = " + std::to_string(k_r) + ", k_t = [1, 1, 1] }\n";
    };
    render::Image none = render_scene("glass0.iq", scene(0), 96, 96);
    render::Image some = render_scene("glass9.iq", scene(0.9), 96, 96);
    // Row 31 sees the slab about 7° below the horizon (Schlick: R ≈ 0.55 of a sky at √sin 7° ≈ 0.35 red),
    // row 90 about 45° below (R ≈ 0.04 of 0.84 red).
    const float grazing = none.pixel(48, 31)[0], steep = none.pixel(48, 90)[0];
    CHECK(grazing == Approx(0.19).margin(0.05));
    CHECK(steep < 0.06f);
    CHECK(grazing > steep + 0.1f);
    // k_r = 0.9 raises the reflection at every angle (before: k_r had no effect while refraction was on).
    CHECK(some.pixel(48, 90)[0] > 0.6f);
    CHECK(some.pixel(48, 31)[0] > grazing);
}

TEST_CASE("light and background error paths are located", "[look][scene]") {
    auto err = [](const std::string& name, const std::string& text) {
        RunResult r = run_iqc(write_temp(name, "[[shapes]]\ntype = \"sphere\"\n" + text).string());
        CHECK(r.exit_code == 1);
        return r.err;
    };
    CHECK_THAT(err("sun.iq", "[[lights]]\ntype = \"sun\"\n"), Catch::Contains("sun.iq:3:1: error: this sun has no 'direction'"));
    CHECK_THAT(err("pointdir.iq", "[[lights]]\nposition = [0, 1, 0]\ndirection = [0, 1, 0]\n"),
               Catch::Contains("pointdir.iq:5:13: error: a point light has no 'direction' (did you mean type = \"sun\"?)"));
    CHECK_THAT(err("skypos.iq", "[[lights]]\ntype = \"sky\"\nposition = [0, 1, 0]\n"),
               Catch::Contains("skypos.iq:5:12: error: a sky light has no 'position'"));
    CHECK_THAT(err("skydir.iq", "[[lights]]\ntype = \"sky\"\ndirection = [0, 1, 0]\n"),
               Catch::Contains("skydir.iq:5:13: error: a sky light has no 'direction'"));
    CHECK_THAT(err("zero.iq", "[[lights]]\ndirection = [0, 0, 0]\n"),
               Catch::Contains("zero.iq:4:13: error: a light's 'direction' cannot be the zero vector"));
    std::string kind = err("kind.iq", "[[lights]]\ntype = \"skye\"\n");
    CHECK_THAT(kind, Catch::Contains("kind.iq:4:8: error: unknown light type 'skye': choose one of point, sun, sky, bounce"));
    CHECK_THAT(kind, Catch::Contains("did you mean 'sky'?"));
    CHECK_THAT(err("grad.iq", "[render]\nbackground = { zenith = [0, 0, 1] }\n"),
               Catch::Contains("grad.iq:4:14: error: a sky-gradient 'background' needs 'zenith' and 'horizon' colours"));
    CHECK_THAT(err("gradkey.iq", "[render]\nbackground = { zenith = [0, 0, 1], horizon = [1, 1, 1], groud = [0, 0, 0] }\n"),
               Catch::Contains("error: unknown field 'groud' in 'background'"));
    CHECK_THAT(err("out.iq", "[render]\noutput = \"gamma\"\n"),
               Catch::Contains("out.iq:4:10: error: unknown output encoding 'gamma': choose one of srgb, linear"));
    CHECK_THAT(err("tone.iq", "[render]\ntonemap = \"filmic\"\n"),
               Catch::Contains("error: unknown tone map 'filmic': choose one of none, reinhard, aces"));
    CHECK_THAT(err("exp.iq", "[render]\nexposure = 0\n"), Catch::Contains("exp.iq:4:12: error: 'exposure' must be positive"));
    CHECK_THAT(err("vig.iq", "[render]\nvignette = 1.5\n"), Catch::Contains("vig.iq:4:12: error: 'vignette' must be in [0, 1]"));
    CHECK_THAT(err("con.iq", "[render]\ncontrast = -0.1\n"), Catch::Contains("con.iq:4:12: error: 'contrast' must be in [0, 1]"));
    CHECK_THAT(err("vigs.iq", "[render]\nvignette = \"yes\"\n"), Catch::Contains("vigs.iq:4:12: error:"));
}

TEST_CASE("sky and bounce lights no material reads are a located warning, and --meta lists every light", "[look][scene]") {
    std::string text = "[[shapes]]\ntype = \"sphere\"\nmaterial = \"phong\"\n"
                       "[[lights]]\nname = \"key\"\ndirection = [1, 1, 0]\n"
                       "[[lights]]\nname = \"fill\"\ntype = \"sky\"\ncolor = [0.2, 0.3, 0.5]\n";
    Compiled c = compile_text("idle_sky.iq", text);
    REQUIRE(c.result.exit_code == 0);
    CHECK_THAT(c.diagnostics, Catch::Contains("idle_sky.iq:7:1: warning: the sky light 'fill' has no effect: no material has an "
                                              "ambient light colour `C_A`"));
    // With pbr it binds: no warning; the meta lists the sun's direction and the sky's colour.
    std::string pbr = text;
    pbr.replace(pbr.find("phong"), 5, "pbr");
    fs::path in = write_temp("bound_sky.iq", pbr);
    fs::path meta = temp_dir() / "bound_sky.json";
    RunResult r = run_iqc(in.string() + " --target webgl2 -o " + (temp_dir() / "bound_sky.frag").string() + " --meta " + meta.string());
    REQUIRE(r.exit_code == 0);
    CHECK_THAT(r.err, !Catch::Contains("has no effect"));
    auto j = nlohmann::json::parse(read_text(meta));
    REQUIRE(j["lights"].size() == 2);
    CHECK(j["lights"][0]["name"] == "key");
    CHECK(j["lights"][0]["type"] == "sun");
    CHECK(j["lights"][0]["direction"] == "key_direction");
    CHECK(j["lights"][1]["type"] == "sky");
    CHECK(j["lights"][1]["color"] == "fill_color");
    CHECK_THAT(read_text(temp_dir() / "bound_sky.frag"), Catch::Contains("uniform vec3 key_direction;"));
}

TEST_CASE("the stdlib pbr material has no NaN where the light is behind the eye", "[look][render]") {
    // V̂ = L̂: the Fresnel term's (1 - V̂⋅Ĥ)⁵ with V̂⋅Ĥ rounded just past 1 was pow of a negative base (NaN).
    std::string scene = "[camera]\nposition = [0, 1.5, -5]\ntarget = [0, 0, 0]\n[[lights]]\nposition = [0, 1.5, -5]\n"
                        "[[shapes]]\ntype = \"plane\"\nmaterial = \"pbr\"\n[[shapes]]\ntype = \"sphere\"\nmaterial = \"pbr\"\n";
    render::Image img = render_scene("pbr_eye_light.iq", scene, 160, 90);
    int nan = 0;
    for (float v : img.rgba) nan += !std::isfinite(v);
    CHECK(nan == 0);
    Compiled c = compile_text("pbr_eye_light2.iq", scene);
    CHECK_THAT(c.result.code, !Catch::Contains(", 5.0)"));  // (1 - v)⁵ multiplied out, not pow(…, 5.0)
}

TEST_CASE("a scene whose lights are all sky or bounce has no direct light", "[look][render]") {
    // The material's light terms are left out: its P_L and C_L defaults are not a hidden, unshadowed light.
    std::string base = "[render]\noutput = \"linear\"\n[camera]\nposition = [0, 6, -6]\ntarget = [0, 0, 0]\n"
                       "[[shapes]]\ntype = \"plane\"\nshape_params = { h = 0 }\nmaterial = \"pbr\"\n"
                       "material_params = { k_d = [0.5, 0.5, 0.5], rho = 1 }\n[[lights]]\ntype = \"sky\"\ncolor = [0.4, 0.4, 0.4]\n";
    render::Image sky = render_scene("sky_only.iq", base);
    render::Image dark_sun = render_scene("sky_dark_sun.iq", base + "[[lights]]\ndirection = [0, 1, 0]\ncolor = [0, 0, 0]\n");
    CHECK(max_abs_diff(sky, dark_sun) < 1e-4);
    Compiled c = compile_text("sky_only2.iq", base);
    CHECK_THAT(c.result.code, !Catch::Contains("material_P_L"));
}

TEST_CASE("a colour that scales or multiplies a sum still splits into light and ambient terms", "[look][render]") {
    // C = 0.5(C_L∘k_d max(0, L̂⋅N̂) + k_a): in the shadow, exactly 0.5·k_a.
    std::string half = R"(
[modules]
half = """
material
C = 0.5(`C_L`∘`k_d`max(0, L̂⋅N̂) + `k_a`)
L̂ = normalize(`P_L` - p)
where
p ∈ ℝ³
N̂ ∈ ℝ³
I ∈ ℝ³
`P_L` ∈ ℝ³: light position
`C_L` ∈ ℝ³: light colour
`k_d` ∈ [0,1]x[0,1]x[0,1] default = (0.6, 0.6, 0.6): diffuse colour
`k_a` ∈ [0,1]x[0,1]x[0,1] default = (0.2, 0.1, 0.04): ambient colour
"""
)";
    render::Image img = render_scene("half.iq", half + "[render]\noutput = \"linear\"\n[effects]\nshadows = \"hard\"\n"
                                                       "[[lights]]\nposition = [0, 10, 0]\n" + ground_and_ball("half", 2.5));
    CHECK(img.pixel(48, 27)[0] == Approx(0.1).margin(0.005));
    CHECK(img.pixel(48, 27)[1] == Approx(0.05).margin(0.005));
}

TEST_CASE("a ray that uses up its bounces sees the background beyond, not black", "[look][render]") {
    // Two glass balls in a row (η = 1: no bending) before a white background; with no reflections the ray has
    // two bounces, used up inside the second ball.
    std::string scene = "[camera]\nposition = [0, 0, -6]\ntarget = [0, 0, 0]\nfov = 30\n"
                        "[render]\noutput = \"linear\"\nbackground = [1, 1, 1]\n[effects]\nrefraction = true\n"
                        "[[shapes]]\ntype = \"sphere\"\nmaterial = \"glass\"\nmaterial_params = { k_t = [1, 1, 1], eta = 1, k_r = 0 }\n"
                        "[[shapes]]\ntype = \"sphere\"\ntransform = \"T((0, 0, 3))\"\nmaterial = \"glass\"\n"
                        "material_params = { k_t = [1, 1, 1], eta = 1, k_r = 0 }\n";
    render::Image img = render_scene("glass_row.iq", scene);
    CHECK(img.pixel(48, 27)[0] > 0.9f);
}

TEST_CASE("a sky background shows each sun as a disc with a glow", "[look][render]") {
    std::string scene = "[camera]\nposition = [0, 0, -5]\ntarget = [0, 0, 0]\nfov = 60\n"
                        "[render]\noutput = \"linear\"\nbackground = { zenith = [0.1, 0.1, 0.2], horizon = [0.2, 0.2, 0.2] }\n"
                        "[[lights]]\ndirection = [0, 0, 1]\ncolor = [1, 0.8, 0.6]\n"
                        "[[shapes]]\ntype = \"sphere\"\ntransform = \"T((0, 100, 0))\"\nmaterial = \"lambert\"\n";
    render::Image img = render_scene("sun_disc.iq", scene, 97, 55);
    // The centre pixel (an odd size: its ray is the axis) looks straight at the sun: its disc, brighter than
    // 1 before the clamp.
    CHECK(img.pixel(48, 27)[0] > 0.99f);
    // Away from it, the sky plus a glow that fades with the angle.
    CHECK(img.pixel(60, 27)[0] > img.pixel(90, 27)[0]);
    CHECK(img.pixel(90, 27)[0] < 0.5f);
    // Without a sun (a point light), the sky is the gradient alone.
    std::string point = scene;
    point.replace(point.find("direction = [0, 0, 1]"), 21, "position = [0, 0, 10]");
    CHECK(render_scene("no_sun_disc.iq", point, 97, 55).pixel(48, 27)[0] == Approx(0.2).margin(0.01));
}

TEST_CASE("a glowing instance lights the rays that pass near it, not those behind an occluder", "[look][render]") {
    // A ball of radius 0.5 at the origin glowing red (radius 0.2) on a black background, from (0, 0, -5), fov 90.
    std::string ball = "[camera]\nposition = [0, 0, -5]\ntarget = [0, 0, 0]\nfov = 90\n"
                       "[render]\noutput = \"linear\"\nbackground = [0, 0, 0]\n"
                       "[[shapes]]\nname = \"ball\"\ntype = \"sphere\"\nshape_params = { r = 0.5 }\n"
                       "material = \"emissive\"\nmaterial_params = { k_e = [0, 0, 0] }\n";
    render::Image glow = render_scene("glow.iq", ball + "glow = [1, 0, 0]\nglow_radius = 0.2\n");
    // Pixel (51, 27) of 96×54: its ray passes the ball's surface at d = 5|uv|/sqrt(1 + |uv|²) - 0.5 and
    // gathers exp(-d / 0.2) of red (the nearest sample of the closest approach is within a few per cent).
    const double u = (2 * 51.5 - 96) / 54.0, v = (2 * 26.5 - 54) / 54.0;
    const double d = 5 * std::hypot(u, v) / std::sqrt(1 + u * u + v * v) - 0.5;
    CHECK(glow.pixel(51, 27)[0] == Approx(std::exp(-d / 0.2)).epsilon(0.05));
    CHECK(glow.pixel(51, 27)[1] == Approx(0).margin(1e-6));
    // Farther out it fades; at the corner almost nothing.
    CHECK(glow.pixel(60, 27)[0] < glow.pixel(51, 27)[0]);
    CHECK(glow.pixel(0, 0)[0] < 1e-3f);
    // A wall in front of the ball: the primary ray ends there, and gathers no glow from behind it.
    render::Image hidden = render_scene("glow_hidden.iq", ball + "glow = [1, 0, 0]\nglow_radius = 0.2\n"
                                        "[[shapes]]\ntype = \"box\"\nshape_params = { b = [3, 3, 0.1] }\ntransform = \"T((0, 0, -2))\"\n"
                                        "material = \"emissive\"\nmaterial_params = { k_e = [0, 0, 0] }\n");
    CHECK(hidden.pixel(51, 27)[0] < 1e-3f);
    // Without glow nothing of it is in the shader.
    Compiled plain = compile_text("no_glow.iq", ball);
    REQUIRE(plain.result.exit_code == 0);
    CHECK(plain.result.code.find("iqc_glow") == std::string::npos);
}

TEST_CASE("a night sky can have stars above the horizon", "[look][render]") {
    std::string sky = "[camera]\nposition = [0, 0, 0]\ntarget = [0, 0.5, 1]\nfov = 90\n"
                      "[[shapes]]\ntype = \"sphere\"\ntransform = \"T((0, 0, 1000))\"\n"
                      "[render]\noutput = \"linear\"\nmax_dist = 50\n";
    auto bright = [](const render::Image& im, int y0, int y1) {
        int n = 0;
        for (int y = y0; y < y1; ++y)
            for (int x = 0; x < im.width; ++x) n += im.pixel(x, y)[0] > 0.05f;
        return n;
    };
    render::Image stars = render_scene("stars.iq", sky + "background = { zenith = [0, 0, 0], horizon = [0, 0, 0], stars = 1 }\n", 192, 108);
    render::Image none = render_scene("nostars.iq", sky + "background = { zenith = [0, 0, 0], horizon = [0, 0, 0] }\n", 192, 108);
    CHECK(bright(stars, 0, 40) > 5);     // well above the horizon
    CHECK(bright(none, 0, 108) == 0);
    CHECK(bright(stars, 80, 108) == 0);  // below the horizon (row ~75): none
    Compiled plain = compile_text("nostars2.iq", sky + "background = { zenith = [0, 0, 0], horizon = [0, 0, 0] }\n");
    CHECK(plain.result.code.find("iqc_stars") == std::string::npos);
}

TEST_CASE("glow and stars error paths are located", "[look][scene]") {
    auto err = [](const std::string& name, const std::string& text) {
        RunResult r = run_iqc(write_temp(name, "[[shapes]]\ntype = \"sphere\"\n" + text).string());
        CHECK(r.exit_code == 1);
        return r.err;
    };
    CHECK_THAT(err("glowneg.iq", "glow = [1, -1, 0]\n"), Catch::Contains("glowneg.iq:3:8: error: 'glow' is a colour: its components cannot be negative"));
    CHECK_THAT(err("glowr.iq", "glow = [1, 1, 0]\nglow_radius = 0\n"), Catch::Contains("glowr.iq:4:15: error: 'glow_radius' must be positive, not 0"));
    CHECK_THAT(err("glowr2.iq", "glow_radius = 0.5\n"), Catch::Contains("glowr2.iq:3:15: error: 'glow_radius' without 'glow'"));
    CHECK_THAT(err("glow2.iq", "glow = [1, 1]\n"), Catch::Contains("glow2.iq:3:8: error:"));
    CHECK_THAT(err("stars.iq", "[render]\nbackground = { zenith = [0, 0, 1], horizon = [1, 1, 1], stars = 2 }\n"),
               Catch::Contains("stars.iq:4:65: error: 'stars' (how many stars) must be in [0, 1]"));
}

TEST_CASE("fog_mode exp2 keeps the near scene clearer than exp", "[look][render]") {
    // A black wall 5 units away in white fog of density 0.1: exp gives 1 - e^-0.5, exp2 1 - e^-0.25.
    std::string wall = "[camera]\nposition = [0, 0, -5]\ntarget = [0, 0, 0]\nfov = 40\n"
                       "[render]\noutput = \"linear\"\nbackground = [1, 1, 1]\n"
                       "[[shapes]]\ntype = \"box\"\nshape_params = { b = [10, 10, 0.01] }\n"
                       "material = \"emissive\"\nmaterial_params = { k_e = [0, 0, 0] }\n"
                       "[effects]\nfog = 0.1\nfog_color = [1, 1, 1]\n";
    CHECK(render_scene("fog_exp.iq", wall).pixel(48, 27)[0] == Approx(1 - std::exp(-0.5)).margin(0.005));
    CHECK(render_scene("fog_exp2.iq", wall + "fog_mode = \"exp2\"\n").pixel(48, 27)[0] == Approx(1 - std::exp(-0.25)).margin(0.005));
    RunResult bad = run_iqc(write_temp("fog_bad.iq", wall + "fog_mode = \"linear\"\n").string());
    CHECK(bad.exit_code == 1);
    CHECK_THAT(bad.err, Catch::Contains("fog_bad.iq:16:12: error: unknown fog mode 'linear': choose one of exp, exp2"));
}

TEST_CASE("a mirror shows a point light as a glint, unless something is in the way", "[look][render]") {
    // A perfect mirror floor (k_r = 1: its own colour counts for nothing) under a light at (0, 4, 0); from
    // (0, 2, -2) the light's image (0, -4, 0) is seen through the floor at (0, 0, -4/3), the centre pixel.
    std::string scene = "[camera]\nposition = [0, 2, -2]\ntarget = [0, 0, -1.3333333]\nfov = 40\n"
                        "[render]\noutput = \"linear\"\nbackground = [0, 0, 0]\nmax_dist = 40\n"
                        "[effects]\nreflections = 1\n"
                        "[[lights]]\nposition = [0, 4, 0]\ncolor = [1, 1, 1]\n"
                        "[[shapes]]\ntype = \"plane\"\nshape_params = { h = 0 }\nmaterial = \"mirror\"\n"
                        "material_params = { k_r = 1, k_d = [0, 0, 0] }\n";
    render::Image glint = render_scene("glint.iq", scene);
    CHECK(glint.pixel(48, 27)[0] > 0.95f);  // 3 × the light's colour, clamped
    CHECK(glint.pixel(48, 2)[0] < 0.05f);   // 18° away from the light's image: nothing
    // A dark ball on the reflected ray, between the floor and the light: no glint.
    render::Image blocked = render_scene("glint_blocked.iq", scene + "[[shapes]]\ntype = \"sphere\"\nshape_params = { r = 0.3 }\n"
                                                                     "transform = \"T((0, 2, -0.6666667))\"\nmaterial = \"emissive\"\n"
                                                                     "material_params = { k_e = [0, 0, 0] }\n");
    CHECK(blocked.pixel(48, 27)[0] < 0.02f);
}

TEST_CASE("glows: the field's own distance, not a bound sphere's or a Lipschitz-divided one, and many glows are one loop", "[look][render]") {
    // The glowing ball of the first glow test, its distance written so that iqc divides it by a Lipschitz
    // factor (2‖p‖ - 1 has gradient 2: the field value is twice the distance) and with a bound sphere of 3.
    std::string base = "[camera]\nposition = [0, 0, -5]\ntarget = [0, 0, 0]\nfov = 90\n"
                       "[render]\noutput = \"linear\"\nbackground = [0, 0, 0]\n";
    std::string plain = base + "[[shapes]]\ntype = \"sphere\"\nshape_params = { r = 0.5 }\nmaterial = \"emissive\"\n"
                               "material_params = { k_e = [0, 0, 0] }\nglow = [1, 0, 0]\nglow_radius = 0.2\n";
    std::string bounded = plain + "bound = 3\n";
    const double u = (2 * 51.5 - 96) / 54.0, v = (2 * 26.5 - 54) / 54.0;
    const double d = 5 * std::hypot(u, v) / std::sqrt(1 + u * u + v * v) - 0.5;
    render::Image a = render_scene("glow_plain.iq", plain);
    render::Image b = render_scene("glow_bound.iq", bounded);
    CHECK(a.pixel(51, 27)[0] == Approx(std::exp(-d / 0.2)).epsilon(0.05));
    CHECK(b.pixel(51, 27)[0] == Approx(a.pixel(51, 27)[0]).epsilon(0.01));
    // At the bound sphere's silhouette (3 units from the centre, pixel column 48 + 54·0.63/2): no ring.
    CHECK(b.pixel(65, 27)[0] == Approx(a.pixel(65, 27)[0]).margin(0.003));
    std::string twice = "[modules]\nball2 = \"\"\"\nshape\n# lipschitz: 2\nD = 2‖p‖ - 1\nwhere\np ∈ ℝ³\n\"\"\"\n" + base +
                        "[[shapes]]\ntype = \"ball2\"\nmaterial = \"emissive\"\nmaterial_params = { k_e = [0, 0, 0] }\n"
                        "glow = [1, 0, 0]\nglow_radius = 0.4\n";  // the field is twice the distance: twice the radius
    CHECK(render_scene("glow_lips.iq", twice).pixel(51, 27)[0] == Approx(std::exp(-d / 0.2)).epsilon(0.05));
    // A floor under a glowing ball: the glow on the floor falls off smoothly (sampled where the ray ends).
    std::string lamp = "[camera]\nposition = [0, 3, -4]\ntarget = [0, 0, 0]\nfov = 60\n"
                       "[render]\noutput = \"linear\"\nbackground = [0, 0, 0]\n"
                       "[[shapes]]\ntype = \"plane\"\nshape_params = { h = 0 }\nmaterial = \"emissive\"\nmaterial_params = { k_e = [0, 0, 0] }\n"
                       "[[shapes]]\ntype = \"sphere\"\nshape_params = { r = 0.3 }\ntransform = \"T((0, 0.5, 0))\"\nmaterial = \"emissive\"\n"
                       "material_params = { k_e = [0, 0, 0] }\nglow = [1, 1, 1]\nglow_radius = 0.5\n";
    render::Image floor = render_scene("glow_floor.iq", lamp, 96, 54);
    double worst = 0;
    for (int y = 40; y < 53; ++y) worst = std::max(worst, double(std::fabs(floor.pixel(20, y)[0] - floor.pixel(20, y + 1)[0])));
    CHECK(worst < 0.02);  // neighbouring rows of the floor differ little (the half-step samples banded by 0.06)
    // 30 glowing balls: one loop over a table, not 30 marches in the code.
    std::string many = base;
    for (int i = 0; i < 30; ++i)
        many += "[[shapes]]\ntype = \"sphere\"\nshape_params = { r = 0.1 }\ntransform = \"T((" + std::to_string(i % 6 - 2.5) + ", " +
                std::to_string(i / 6 - 2.0) + ", 0))\"\nglow = [0.2, 0.1, 0]\n";
    Compiled c = compile_text("glow_many.iq", many);
    REQUIRE(c.result.exit_code == 0);
    size_t calls = 0;
    for (size_t at = 0; (at = c.result.code.find("iqc_glow(", at)) != std::string::npos; ++at) ++calls;
    CHECK(calls == 2);  // its definition and the one call in the loop
    CHECK_THAT(c.result.code, Catch::Contains("const int IQC_GLOWS = 30;"));
    RunResult big = run_iqc(write_temp("glow_big.iq", "[[shapes]]\ntype = \"sphere\"\nglow = [1, 1, 2000]\n").string());
    CHECK(big.exit_code == 1);
    CHECK_THAT(big.err, Catch::Contains("glow_big.iq:3:8: error: 'glow' components above 1000 overflow the tone map"));
}

TEST_CASE("iqc render --stats draws glowing instances with bound, alone, in a group and unbounded beside them", "[look][render][stats]") {
    // Found by a trial: the instrumented shader (--stats) read the shapes-evaluated count from the distance without
    // the bound sphere (which glows march), a float: glslang rejected it and iqc exited 3.
    std::string base = "[camera]\nposition = [0, 1, -6]\ntarget = [0, 0, 0]\n[[lights]]\nposition = [-5, 8, -6]\n";
    std::string one = base + "[[shapes]]\ntype = \"sphere\"\nmaterial = \"lambert\"\nglow = [0.6, 0.4, 0.1]\nbound = 1.1\n";
    std::string group = base + "[[shapes]]\ntype = \"plane\"\nshape_params = { h = 1 }\n";
    for (int i = 0; i < 6; ++i)
        group += fmt::format("[[shapes]]\ntype = \"sphere\"\nshape_params = {{ r = 0.3 }}\ntransform = \"T(({}, 0, 0))\"\nglow = [0.2, 0.1, 0]\n"
                             "bound = 0.35\n", i - 2.5);
    for (const auto& [name, text] : {std::pair{"stats_glow_one.iq", one}, std::pair{"stats_glow_group.iq", group}}) {
        auto path = write_temp(name, text);
        RunResult r = run_iqc("render " + path.string() + " --size 48x27 --stats -o " + (temp_dir() / "stats_glow.png").string());
        INFO(name << "\n" << r.err);
        CHECK(r.exit_code == 0);
        CHECK_THAT(r.out + r.err, Catch::Contains("shape_evals_per_eval"));
    }
}

TEST_CASE("fog thickens along a reflected ray's whole path", "[look][render]") {
    // A mirror 20 units away in white fog: what it shows (a black sky) is as fogged as the mirror.
    std::string scene = "[camera]\nposition = [0, 0, -20]\ntarget = [0, 0, 0]\nfov = 20\n"
                        "[render]\noutput = \"linear\"\nbackground = [0, 0, 0]\nmax_dist = 100\n"
                        "[effects]\nreflections = 1\nfog = 0.05\nfog_color = [1, 1, 1]\n"
                        "[[lights]]\nposition = [0, 50, -50]\ncolor = [0, 0, 0]\n"
                        "[[shapes]]\ntype = \"box\"\nshape_params = { b = [3, 3, 0.1] }\nmaterial = \"mirror\"\n"
                        "material_params = { k_r = 1, k_d = [0, 0, 0] }\n";
    // The centre ray meets the mirror 19.9 away, comes straight back and leaves the scene: the sky it shows is
    // 19.9 units of fog away at least (1 - e^-0.995 = 0.63); before, only the mirror's own colour was fogged.
    float c = render_scene("fog_mirror.iq", scene).pixel(48, 27)[0];
    CHECK(c > 0.6f);
    CHECK(c < 0.66f);
}
