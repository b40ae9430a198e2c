// The pixel's footprint `w_P` (docs/look.md): the renderer binds it to materials that declare it — the width,
// along each world axis, of the box a pixel's cone covers on the surface — and the stdlib checker box-filters
// its pattern over it, so distant cells blend to their average instead of aliasing. Scenes whose materials do
// not read it carry none of it.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

#include "SceneRender.h"
#include "TestUtil.h"
#include "render/Render.h"

using namespace iqc;
using namespace iqc::test;

namespace {

// A material that shows the footprint it is given, scaled by 2.5 (linear output).
const std::string kShowFootprint = R"(
[modules]
show = """
material
C = 2.5`w_P`
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
    // `eye` looking at the origin: the ray through the pixel's centre (iqc_look_at's basis), the filter cone's
    // width w = k·(2/54)/|(uv, 1)|·t at the hit (k pixels: 2 without antialiasing, 1 per sample with it),
    // stretched by 1/|N·rd| along the view: w·sqrt(1 + rd_i²/rd_y²) for i = x, z.
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
        double t = ey / -d[1], w = 2 * 2.0 / 54.0 / std::sqrt(ux * ux + uy * uy + 1) * t;
        wx = w * std::sqrt(1 + d[0] * d[0] / (d[1] * d[1]));
        wz = w * std::sqrt(1 + d[2] * d[2] / (d[1] * d[1]));
    };
    double wx, wz;
    // Straight down from height 1.
    render::Image down = render_scene("fp_down.iq", kShowFootprint + "[camera]\nposition = [0, 1, 0]\ntarget = [0, 0, 0]\nfov = 90\n");
    expected(1, 0, wx, wz);
    const float* c = down.pixel(48, 27);
    CHECK(c[0] == Approx(2.5 * wx).epsilon(0.002));
    CHECK(c[1] == Approx(0).margin(1e-6));  // the floor is flat along y: nothing to filter there
    CHECK(c[2] == Approx(2.5 * wz).epsilon(0.002));
    // At 45° from (0, 1, -1): about √2 away and stretched by about √2 along z, the direction of view.
    render::Image slant = render_scene("fp_slant.iq", kShowFootprint + "[camera]\nposition = [0, 1, -1]\ntarget = [0, 0, 0]\nfov = 90\n");
    expected(1, -1, wx, wz);
    const float* s = slant.pixel(48, 27);
    CHECK(s[0] == Approx(2.5 * wx).epsilon(0.002));
    CHECK(s[2] == Approx(2.5 * wz).epsilon(0.002));
    CHECK(s[2] / s[0] == Approx(std::sqrt(2.0)).epsilon(0.05));
    // Antialiasing: each of the 3×3 samples filters over one pixel (together, a two-pixel tent): the
    // average of their footprints is half the two-pixel filter's.
    render::Image aa = render_scene("fp_aa.iq", kShowFootprint + "[camera]\nposition = [0, 1, 0]\ntarget = [0, 0, 0]\nfov = 90\n"
                                                                 "[effects]\nantialias = 3\n");
    expected(1, 0, wx, wz);
    CHECK(aa.pixel(48, 27)[0] == Approx(2.5 * wx / 2).epsilon(0.01));
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
    CHECK(fe > 0.5);
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

TEST_CASE("the stdlib checker stays exact far from the origin and on a floor lying on a cell boundary", "[look][footprint]") {
    const std::string checker = read_text(std::string(IQC_SOURCE_DIR) + "/stdlib/checker.iql");
    auto t_at = [&](std::vector<double> p, std::vector<double> w, double s) {
        Evaluated e = eval_module(checker, {{"p", p}, {"N̂", {0, 1, 0}}, {"w_P", w}, {"s", {s}}});
        INFO(e.diagnostics);
        REQUIRE(e.ok);
        return scalar_of(e, "t");
    };
    // 5,000 units out, a footprint of a thousandth of a cell: the difference of the triangle wave would be float
    // rounding (banding inside the cells); the cell's own colour is taken, 0 or 1.
    for (double x : {5000.2, 5000.6, 10000.3}) {
        double t = t_at({x, 0.5, 0.5}, {0.00075, 0, 0.00075}, 0.75);
        CHECK(std::min(std::fabs(t), std::fabs(t - 1)) < 1e-6);
    }
    // A floor at y = -1 (a cell boundary for s = 0.05) hit within the default tolerance above or below: the
    // same cell (the inward offset, 0.002 at least, exceeds the tolerance; a hundredth of 0.05 did not).
    CHECK(t_at({0.12, -1 + 0.0008, 0.31}, {0, 0, 0}, 0.05) == t_at({0.12, -1 - 0.0008, 0.31}, {0, 0, 0}, 0.05));
    // Filtering still averages: a footprint of two cells around a cell edge gives the mean.
    CHECK(t_at({0.75, 0.5, 0.5}, {1.5, 0, 0}, 0.75) == Approx(0.5).margin(1e-9));
}

TEST_CASE("w_P is the renderer's: a scene cannot set it, and another type of w_P is warned about", "[look][footprint][scene]") {
    std::string floor = "[[shapes]]\ntype = \"plane\"\nmaterial = \"checker\"\n";
    RunResult set = run_iqc(write_temp("fp_set.iq", floor + "material_params = { w_P = [5, 5, 5] }\n").string());
    CHECK(set.exit_code == 1);
    CHECK_THAT(set.err, Catch::Contains("fp_set.iq:4:21: error: 'w_P' is bound by the renderer and cannot be set"));
    std::string scalar = "[modules]\nm = \"\"\"\nmaterial\nC = (1, 1, 1)`w_P`\nwhere\np ∈ ℝ³\nN̂ ∈ ℝ³\nI ∈ ℝ³\n`w_P` ∈ ℝ\n\"\"\"\n"
                         "[[shapes]]\ntype = \"sphere\"\nmaterial = \"m\"\n";
    RunResult warn = run_iqc(write_temp("fp_scalar.iq", scalar).string() + " -o " + (temp_dir() / "fp_scalar.frag").string());
    CHECK(warn.exit_code == 0);
    CHECK_THAT(warn.err, Catch::Contains("fp_scalar.iq:13:12: warning: material 'm' has a parameter 'w_P' of type ℝ"));
}

TEST_CASE("the filtered checker has no banding inside its cells far from the origin", "[look][footprint][render]") {
    // 5,000 units out, 0.25 above the floor (a new user's trial): in float, the triangle wave's difference over a
    // footprint just past the old threshold of 0.001 cells was rounding, and banded the cells (0.80-0.86 in a
    // cell of 0.831).
    std::string copy = read_text(std::string(IQC_SOURCE_DIR) + "/stdlib/checker.iql");
    for (size_t at; (at = copy.find("`w_P`")) != std::string::npos;) copy.replace(at, 5, "`w_Q`");
    auto scene = [](const std::string& material) {
        return "[camera]\nposition = [5000.3, 0.25, 5000.2]\ntarget = [5001.3, -0.05, 5001.5]\nfov = 60\n"
               "[render]\nmax_dist = 50\noutput = \"linear\"\nbackground = [0.6, 0.7, 0.85]\n"
               "[[lights]]\ntype = \"sun\"\ndirection = [0.3, 1, -0.2]\n"
               "[[shapes]]\ntype = \"plane\"\nmaterial = \"" + material + "\"\nmaterial_params = { s = 1 }\n";
    };
    render::Image filtered = render_scene("fp_far.iq", scene("checker"), 160, 90);
    render::Image plain = render_scene("fp_far_raw.iq", "[modules]\nraw = \"\"\"\n" + copy + "\"\"\"\n" + scene("raw"), 160, 90);
    // Inside the cells near the camera (the unfiltered picture flat over a pixel's 5×5 neighbourhood) both agree.
    double worst = 0;
    int inside = 0;
    for (int y = 50; y < 88; ++y)
        for (int x = 2; x < 158; ++x) {
            float lo = 1e9f, hi = -1e9f;
            for (int dy = -2; dy <= 2; ++dy)
                for (int dx = -2; dx <= 2; ++dx) {
                    float v = plain.pixel(x + dx, y + dy)[1];
                    lo = std::min(lo, v), hi = std::max(hi, v);
                }
            if (hi - lo > 1e-4f) continue;
            ++inside;
            worst = std::max(worst, double(std::fabs(filtered.pixel(x, y)[1] - plain.pixel(x, y)[1])));
        }
    INFO("largest difference inside the cells " << worst << " over " << inside << " pixels");
    CHECK(inside > 1000);
    CHECK(worst < 0.003);  // 0.0017 here; 0.005 with the old fixed threshold of 0.001 cells
}
