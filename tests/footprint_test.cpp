// The pixel's footprint `w_P` (docs/look.md): the renderer binds it to materials that declare it — the width,
// along each world axis, of the box a pixel's cone covers on the surface — and the stdlib checker box-filters
// its pattern over it, so distant cells blend to their average instead of aliasing. Scenes whose materials do
// not read it carry none of it.
#include <catch2/catch.hpp>

#include <cmath>
#include <vector>

#include "SceneRender.h"
#include "TestUtil.h"
#include "render/Render.h"

using namespace iqc;
using namespace iqc::test;

namespace {

// A material that shows the footprint it is given, scaled by 10 (linear output).
const std::string kShowFootprint = R"(
[modules]
show = """
material
C = 10`w_P`
where
p ∈ ℝ³
N̂ ∈ ℝ³
I ∈ ℝ³
`w_P` ∈ ℝ³: the pixel's footprint
"""
[render]
output = "linear"
[[shapes]]
type = "plane"
shape_params = { h = 0 }
material = "show"
)";

// The stdlib checker (black and white cells of 0.5, lit by a white sky light alone, no ambient term) on the
// ground seen toward the horizon; `module` names a material: "checker", or a copy of it that declares the
// footprint under another name (so nothing binds it: unfiltered).
std::string checker_floor(const std::string& module) {
    return "[camera]\nposition = [0, 1, 0]\ntarget = [0, 0.75, 10]\nfov = 50\n"
           "[render]\noutput = \"linear\"\nmax_dist = 200\n"
           "[[lights]]\ntype = \"sky\"\ncolor = [1, 1, 1]\n"
           "[[shapes]]\ntype = \"plane\"\nshape_params = { h = 0 }\nmaterial = \"" + module + "\"\n"
           "material_params = { s = 0.5, c_1 = [1, 1, 1], c_2 = [0, 0, 0], k_a = [0, 0, 0] }\n";
}

}  // namespace

TEST_CASE("a material's w_P is the width of the pixel's cone on the surface along each axis", "[look][footprint][render]") {
    // The footprint of pixel (48, 27) of a 96×54 picture (fov 90: focal 1) on the ground y = 0 seen from
    // `eye` looking at the origin: the ray through the pixel's centre (iqc_look_at's basis), the cone's width
    // w = (2/54)·t at the hit, stretched by 1/|N·rd| along the view: w·sqrt(1 + rd_i²/rd_y²) for i = x, z.
    auto expected = [](double ey, double ez, double& wx, double& wz) {
        double fl = std::hypot(ey, ez), f[3] = {0, -ey / fl, -ez / fl};
        double up[3] = {0, 1, 0};
        if (std::fabs(f[1]) > 0.999) up[1] = 0, up[2] = 1;
        double r[3] = {up[1] * f[2] - up[2] * f[1], up[2] * f[0] - up[0] * f[2], up[0] * f[1] - up[1] * f[0]};
        double rl = std::hypot(r[0], r[1], r[2]);
        for (double& v : r) v /= rl;
        double u[3] = {f[1] * r[2] - f[2] * r[1], f[2] * r[0] - f[0] * r[2], f[0] * r[1] - f[1] * r[0]};
        const double ux = (2 * 48.5 - 96) / 54, uy = (2 * (54 - 27 - 0.5) - 54) / 54;  // fragCoord's y is from the bottom
        double d[3];
        for (int i = 0; i < 3; ++i) d[i] = ux * r[i] + uy * u[i] + f[i];
        double dl = std::hypot(d[0], d[1], d[2]);
        for (double& v : d) v /= dl;
        double t = ey / -d[1], w = 2.0 / 54.0 * t;
        wx = w * std::sqrt(1 + d[0] * d[0] / (d[1] * d[1]));
        wz = w * std::sqrt(1 + d[2] * d[2] / (d[1] * d[1]));
    };
    double wx, wz;
    // Straight down from height 1.
    render::Image down = render_scene("fp_down.iq", kShowFootprint + "[camera]\nposition = [0, 1, 0]\ntarget = [0, 0, 0]\nfov = 90\n");
    expected(1, 0, wx, wz);
    const float* c = down.pixel(48, 27);
    CHECK(c[0] == Approx(10 * wx).epsilon(0.002));
    CHECK(c[1] == Approx(0).margin(1e-6));  // the floor is flat along y: nothing to filter there
    CHECK(c[2] == Approx(10 * wz).epsilon(0.002));
    // At 45° from (0, 1, -1): about √2 away and stretched by about √2 along z, the direction of view.
    render::Image slant = render_scene("fp_slant.iq", kShowFootprint + "[camera]\nposition = [0, 1, -1]\ntarget = [0, 0, 0]\nfov = 90\n");
    expected(1, -1, wx, wz);
    const float* s = slant.pixel(48, 27);
    CHECK(s[0] == Approx(10 * wx).epsilon(0.002));
    CHECK(s[2] == Approx(10 * wz).epsilon(0.002));
    CHECK(s[2] / s[0] == Approx(std::sqrt(2.0)).epsilon(0.05));
    // Antialiasing: each of the 3×3 samples filters over a whole pixel (together, a two-pixel tent): the
    // average of their footprints is the pixel's.
    render::Image aa = render_scene("fp_aa.iq", kShowFootprint + "[camera]\nposition = [0, 1, 0]\ntarget = [0, 0, 0]\nfov = 90\n"
                                                                 "[effects]\nantialias = 3\n");
    expected(1, 0, wx, wz);
    CHECK(aa.pixel(48, 27)[0] == Approx(10 * wx).epsilon(0.01));
}

TEST_CASE("the stdlib checker blends distant cells to their average instead of aliasing", "[look][footprint][render]") {
    // The unfiltered reference: the stdlib checker with its footprint parameter renamed, which nothing binds.
    std::string copy = read_text(std::string(IQC_SOURCE_DIR) + "/stdlib/checker.iql");
    for (size_t at; (at = copy.find("`w_P`")) != std::string::npos;) copy.replace(at, 5, "`w_Q`");
    render::Image filtered = render_scene("fp_checker.iq", checker_floor("checker"), 160, 90);
    render::Image aliased = render_scene("fp_aliased.iq", "[modules]\nraw = \"\"\"\n" + copy + "\"\"\"\n" + checker_floor("raw"), 160, 90);
    // The horizon is at row 43 (of 90, top first); rows 44-52 see the ground from 200 to 10 units away,
    // where a pixel covers several cells along the view.
    auto band = [](const render::Image& im, int y0, int y1, double& mean, double& jump, double& extreme) {
        double sum = 0, jumps = 0, ext = 0;
        int n = 0, nj = 0;
        for (int y = y0; y < y1; ++y)
            for (int x = 0; x < im.width; ++x) {
                double v = im.pixel(x, y)[1];
                sum += v;
                ext += v < 0.1 || v > 0.9;
                ++n;
                if (x > 0) jumps += std::fabs(v - im.pixel(x - 1, y)[1]), ++nj;
            }
        mean = sum / n, jump = jumps / nj, extreme = ext / n;
    };
    double fm, fj, fe, am, aj, ae;
    band(filtered, 44, 53, fm, fj, fe);
    band(aliased, 44, 53, am, aj, ae);
    INFO("filtered mean " << fm << " jump " << fj << " extreme " << fe << "; unfiltered " << am << " " << aj << " " << ae);
    CHECK(fm == Approx(0.5).margin(0.05));  // the cells' average
    CHECK(fe < 0.05);                        // hardly a pixel all black or all white there
    CHECK(ae > 0.5);                         // unfiltered: each pixel picks one cell
    CHECK(fj < 0.3 * aj);                    // neighbours differ far less
    // Near the camera (the bottom rows: cells many pixels wide) the checks stay crisp: only the pixels on a
    // cell's edge are in between, and the average is the unfiltered one's.
    band(filtered, 80, 90, fm, fj, fe);
    band(aliased, 80, 90, am, aj, ae);
    CHECK(fe > 0.75);
    CHECK(fm == Approx(am).margin(0.03));
}

TEST_CASE("a scene whose materials do not read w_P carries no footprint", "[look][footprint]") {
    Compiled plain = compile_text("fp_plain.iq", "[[shapes]]\ntype = \"sphere\"\nmaterial = \"phong\"\n[[lights]]\nposition = [2, 3, -2]\n");
    REQUIRE(plain.result.exit_code == 0);
    CHECK(plain.result.code.find("iqc_footprint") == std::string::npos);
    CHECK(plain.result.code.find("iqc_pixel_cone") == std::string::npos);
    Compiled checker = compile_text("fp_checker2.iq", checker_floor("checker"));
    REQUIRE(checker.result.exit_code == 0);
    CHECK(checker.result.code.find("iqc_footprint(") != std::string::npos);
    // w_P is the renderer's: --meta lists no slider of it.
    CHECK(checker.result.meta.find("w_P") == std::string::npos);
}
