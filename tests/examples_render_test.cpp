// The examples, rendered by a Shadertoy-style harness (EGL + llvmpipe): the shapes appear where the
// transforms put them, lit by the materials as written.
#include <catch2/catch.hpp>
#include <cmath>

#include "TestUtil.h"
#include "render/Render.h"

using namespace iqc;
using namespace iqc::test;

namespace {

render::Image render_file(const std::filesystem::path& p, int w = 160, int h = 90) {
    Compiled c = compile_path(p);
    INFO(c.diagnostics << c.result.internal);
    REQUIRE(c.result.exit_code == 0);
    render::RenderOptions o;
    o.width = w;
    o.height = h;
    render::RenderResult r = render::render_shadertoy(c.result.code, o);
    INFO(r.error);
    REQUIRE(r.ok);
    return r.image;
}

render::Image render_text(const std::string& name, const std::string& text) {
    return render_file(write_temp(name, text));
}

int nan_pixels(const render::Image& img) {
    int n = 0;
    for (float v : img.rgba) n += !std::isfinite(v);
    return n;
}

bool is_background(const float* px) {
    return std::fabs(px[0] - 0.05f) < 1e-3f && std::fabs(px[1] - 0.05f) < 1e-3f && std::fabs(px[2] - 0.08f) < 1e-3f;
}

std::filesystem::path example(const char* name) { return std::filesystem::path(IQC_SOURCE_DIR) / "examples" / name; }

}  // namespace

TEST_CASE("two tori: a diffuse blue torus on the left, a red toon torus on the right", "[render][examples]") {
    render::Image img = render_file(example("two_tori.md"));
    CHECK(nan_pixels(img) == 0);
    CHECK(is_background(img.pixel(2, 2)));
    CHECK(is_background(img.pixel(80, 85)));
    // Find the lit pixels of each half.
    int blue = 0, red = 0;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) {
            const float* p = img.pixel(x, y);
            if (is_background(p)) continue;
            if (x < img.width / 2 && p[2] > p[0] && p[2] > 0.2f) ++blue;
            if (x > img.width / 2 && p[0] > p[2] && p[0] > 0.2f && p[1] < 0.01f) ++red;
        }
    CHECK(blue > 200);
    CHECK(red > 200);
    // The toon material quantises light into few levels: count distinct reds on the right.
    std::set<int> levels;
    for (int y = 0; y < img.height; ++y)
        for (int x = img.width / 2; x < img.width; ++x) {
            const float* p = img.pixel(x, y);
            if (!is_background(p) && p[0] > 0.01f) levels.insert(int(std::lround(p[0] * 1000)));
        }
    CHECK(levels.size() <= 4);
}

TEST_CASE("every example renders with no NaN and shows its shapes", "[render][examples]") {
    for (const char* name : {"two_tori.md", "box_frames.md", "full_phong.md", "simple_phong.md", "gallery.iq"}) {
        SECTION(name) {
            render::Image img = render_file(example(name));
            CHECK(nan_pixels(img) == 0);
            // The top-left corner is background in every example: count pixels that differ from it.
            const float* bg = img.pixel(0, 0);
            int lit = 0;
            for (int y = 0; y < img.height; ++y)
                for (int x = 0; x < img.width; ++x) {
                    const float* p = img.pixel(x, y);
                    lit += std::fabs(p[0] - bg[0]) + std::fabs(p[1] - bg[1]) + std::fabs(p[2] - bg[2]) > 1e-3f;
                }
            CHECK(lit > 300);
        }
    }
}

TEST_CASE("full Phong: the sphere at (0, 0, 5) fills the centre with the specular highlight toward the light", "[render][examples]") {
    render::Image img = render_file(example("full_phong.md"));
    const float* c = img.pixel(80, 45);
    CHECK_FALSE(is_background(c));
    CHECK(c[2] > c[0]);  // blue material
    // The light is up and to the left: that side is brighter than the opposite one.
    CHECK(img.pixel(65, 30)[2] > img.pixel(95, 60)[2]);
}

TEST_CASE("a material with no free parameter shows its colour, not white", "[render]") {
    render::Image img = render_text("plain.md",
                                    "❤: ball\n```iheartla\nshape\nD = ‖p‖ - 1\nwhere\np ∈ ℝ³\n```\n"
                                    "❤: green\n```iheartla\nmaterial\nC = (0.2, 0.8, 0.3)\nwhere\np ∈ ℝ³\nN̂ ∈ ℝ³\nI ∈ ℝ³\n```\n"
                                    "```scene\n[[shapes]]\ntype = \"ball\"\nmaterial = \"green\"\ntransform = \"T((0, 0, 4))\"\n```\n");
    const float* c = img.pixel(80, 45);
    CHECK(c[0] == Approx(0.2f).margin(1e-4));
    CHECK(c[1] == Approx(0.8f).margin(1e-4));
    CHECK(c[2] == Approx(0.3f).margin(1e-4));
}

TEST_CASE("without a material the default shades by the normal", "[render]") {
    render::Image img = render_text("nomat.md", "❤: ball\n```iheartla\nshape\nD = ‖p‖ - 1\nwhere\np ∈ ℝ³\n```\n"
                                                "```scene\n[[shapes]]\ntype = \"ball\"\ntransform = \"T((0, 0, 4))\"\n```\n");
    const float* c = img.pixel(80, 45);  // facing the camera: N ≈ (0, 0, -1) -> colour (0.5, 0.5, 0)
    CHECK(c[0] == Approx(0.5f).margin(0.02));
    CHECK(c[1] == Approx(0.5f).margin(0.02));
    CHECK(c[2] == Approx(0.0f).margin(0.02));
}
