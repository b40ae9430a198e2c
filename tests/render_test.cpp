// Tests for the headless renderer (compiler/render/Render.h) and PNG I/O (compiler/render/Png.h).
//
// Tests tagged [render] need a working EGL + OpenGL ES 3 implementation (Mesa's llvmpipe is enough);
// exclude them with `iqc_tests "~[render]"` on machines without one.
#include "render/Png.h"
#include "render/Render.h"

#include "glsl/ShadertoyWrapper.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <string>

#include <unistd.h>

using iqc::render::Image;
using iqc::render::RenderOptions;
using iqc::render::RenderResult;

namespace {

// A unique path in the temp directory, removed when the object goes out of scope.
struct TempFile {
    std::filesystem::path path;
    explicit TempFile(const std::string& stem) {
        static int counter = 0;
        path = std::filesystem::temp_directory_path() /
               (stem + "_" + std::to_string(::getpid()) + "_" + std::to_string(counter++) + ".png");
    }
    ~TempFile() {
        std::error_code ec;
        std::filesystem::remove(path, ec);
    }
};

}  // namespace

TEST_CASE("fragCoord gradient matches the formula, with row 0 at the top", "[render]") {
    const std::string shader =
        "void mainImage(out vec4 c, in vec2 f){ c = vec4(f.x/iResolution.x, f.y/iResolution.y, 0.25, 1.0); }";
    RenderOptions opts;
    opts.width = 64;
    opts.height = 32;
    RenderResult r = iqc::render::render_shadertoy(shader, opts);
    INFO(r.error);
    REQUIRE(r.ok);
    CHECK_FALSE(r.renderer.empty());
    REQUIRE(r.image.width == 64);
    REQUIRE(r.image.height == 32);
    REQUIRE(r.image.rgba.size() == 64u * 32u * 4u);
    CHECK(r.compile_ms >= 0);
    CHECK(r.frame_ms >= 0);

    // Image (x, y) with y = 0 at the top is Shadertoy fragCoord (x + 0.5, height - 1 - y + 0.5).
    const int points[][2] = {{0, 0}, {63, 0}, {0, 31}, {63, 31}, {10, 5}, {40, 20}};
    for (const auto& pt : points) {
        const int x = pt[0], y = pt[1];
        const float* p = r.image.pixel(x, y);
        INFO("pixel (" << x << ", " << y << ")");
        CHECK(p[0] == Approx((x + 0.5) / 64.0).margin(1e-3));
        CHECK(p[1] == Approx((32 - 1 - y + 0.5) / 32.0).margin(1e-3));
        CHECK(p[2] == Approx(0.25).margin(1e-3));
        CHECK(p[3] == Approx(1.0).margin(1e-3));
    }
}

TEST_CASE("a shader with a syntax error reports the compile failure", "[render]") {
    const std::string shader = "void mainImage(out vec4 c, in vec2 f){ c = vec4(1.0) }";  // missing ';'
    RenderOptions opts;
    opts.width = 8;
    opts.height = 8;
    RenderResult r = iqc::render::render_shadertoy(shader, opts);
    INFO(r.error);
    CHECK_FALSE(r.ok);
    CHECK(r.error.find("compile failed") != std::string::npos);
    CHECK(r.error.size() > std::string("fragment shader compile failed:\n").size());  // carries the info log
}

TEST_CASE("iTime is passed to the shader", "[render]") {
    const std::string shader = "void mainImage(out vec4 c, in vec2 f){ c = vec4(iTime, 0.0, 0.0, 1.0); }";
    RenderOptions opts;
    opts.width = 4;
    opts.height = 4;
    opts.time = 0.5f;
    RenderResult r = iqc::render::render_shadertoy(shader, opts);
    INFO(r.error);
    REQUIRE(r.ok);
    CHECK(r.image.pixel(0, 0)[0] == Approx(0.5).margin(1e-3));
    CHECK(r.image.pixel(3, 3)[0] == Approx(0.5).margin(1e-3));
    CHECK(r.image.pixel(2, 1)[1] == Approx(0.0).margin(1e-3));
}

TEST_CASE("Renderer renders several frames with iFrame, iMouse and unclamped floats", "[render]") {
    std::string error;
    auto renderer = iqc::render::Renderer::create(&error);
    INFO(error);
    REQUIRE(renderer);
    CHECK_FALSE(renderer->renderer_name().empty());
    CHECK_FALSE(renderer->platform_name().empty());

    const std::string source = iqc::glsl::wrap_shadertoy(
        "void mainImage(out vec4 c, in vec2 f){ c = vec4(float(iFrame), iMouse.x, iMouse.w, -2.5); }");
    for (int frame = 0; frame < 3; ++frame) {
        RenderOptions opts;
        opts.width = 16;
        opts.height = 8;
        opts.frame = frame;
        opts.mouse[0] = 7.0f + frame;
        opts.mouse[3] = -3.0f;
        RenderResult r = renderer->render(source, opts);
        INFO(r.error);
        REQUIRE(r.ok);
        const float* p = r.image.pixel(5, 5);
        CHECK(p[0] == Approx(frame));
        CHECK(p[1] == Approx(7.0 + frame));
        CHECK(p[2] == Approx(-3.0));
        // The framebuffer is floating point when available: values outside [0, 1] survive.
        if (r.renderer.find("RGBA8") == std::string::npos) CHECK(p[3] == Approx(-2.5));
    }

    RenderOptions bad;
    bad.width = 0;
    RenderResult r = renderer->render(source, bad);
    CHECK_FALSE(r.ok);
    CHECK(r.error.find("size") != std::string::npos);
}

TEST_CASE("PNG round trip within 1/255", "[png]") {
    Image img;
    img.width = 5;
    img.height = 3;
    img.rgba.resize(5 * 3 * 4);
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) {
            float* p = img.pixel(x, y);
            p[0] = x / 4.0f;
            p[1] = y / 2.0f;
            p[2] = 0.3f + 0.01f * float(x * y);
            p[3] = 1.0f - 0.1f * float(x);
        }

    SECTION("RGBA keeps alpha") {
        TempFile file("iqc_png_rgba");
        std::string error;
        REQUIRE(iqc::render::write_png(file.path.string(), img, &error, /*keep_alpha=*/true));
        Image back;
        REQUIRE(iqc::render::read_png(file.path.string(), back, &error));
        REQUIRE(back.width == img.width);
        REQUIRE(back.height == img.height);
        for (size_t i = 0; i < img.rgba.size(); ++i) CHECK(back.rgba[i] == Approx(img.rgba[i]).margin(1.0 / 255.0));
    }

    SECTION("RGB (default) reads back with alpha 1") {
        TempFile file("iqc_png_rgb");
        std::string error;
        REQUIRE(iqc::render::write_png(file.path.string(), img, &error));
        Image back;
        REQUIRE(iqc::render::read_png(file.path.string(), back, &error));
        REQUIRE(back.width == img.width);
        REQUIRE(back.height == img.height);
        for (int y = 0; y < img.height; ++y)
            for (int x = 0; x < img.width; ++x)
                for (int c = 0; c < 4; ++c) {
                    const float expected = c == 3 ? 1.0f : img.pixel(x, y)[c];
                    CHECK(back.pixel(x, y)[c] == Approx(expected).margin(1.0 / 255.0));
                }
    }
}

TEST_CASE("PNG output clamps, rounds, shows NaN as magenta and is deterministic", "[png]") {
    Image img;
    img.width = 4;
    img.height = 1;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    img.rgba = {-1.0f, 2.0f, 0.5f, 1.0f,            // clamped; 0.5 -> 128
                nan, 0.0f, 0.0f, 1.0f,              // NaN -> magenta
                1.0f / 255.0f, 0.0f, 1.0f, 1.0f,    // exact byte values survive
                std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity(), 0.0f, 1.0f};
    TempFile a("iqc_png_det_a"), b("iqc_png_det_b");
    std::string error;
    REQUIRE(iqc::render::write_png(a.path.string(), img, &error));
    REQUIRE(iqc::render::write_png(b.path.string(), img, &error));
    Image back;
    REQUIRE(iqc::render::read_png(a.path.string(), back, &error));
    auto byte = [&](int x, int c) { return std::lround(back.pixel(x, 0)[c] * 255.0f); };
    CHECK(byte(0, 0) == 0);
    CHECK(byte(0, 1) == 255);
    CHECK(byte(0, 2) == 128);
    CHECK(byte(1, 0) == 255);
    CHECK(byte(1, 1) == 0);
    CHECK(byte(1, 2) == 255);
    CHECK(byte(2, 0) == 1);
    CHECK(byte(3, 0) == 255);
    CHECK(byte(3, 1) == 0);

    CHECK(std::filesystem::file_size(a.path) == std::filesystem::file_size(b.path));
    std::FILE* fa = std::fopen(a.path.string().c_str(), "rb");
    std::FILE* fb = std::fopen(b.path.string().c_str(), "rb");
    REQUIRE(fa);
    REQUIRE(fb);
    bool same = true;
    for (int ca = 0, cb = 0; ca != EOF || cb != EOF;) {
        ca = std::fgetc(fa);
        cb = std::fgetc(fb);
        if (ca != cb) {
            same = false;
            break;
        }
    }
    std::fclose(fa);
    std::fclose(fb);
    CHECK(same);
}

TEST_CASE("PNG errors are reported, not thrown", "[png]") {
    std::string error;
    Image img;
    CHECK_FALSE(iqc::render::read_png("/nonexistent/dir/x.png", img, &error));
    CHECK_FALSE(error.empty());

    TempFile notpng("iqc_png_bad");
    {
        std::FILE* f = std::fopen(notpng.path.string().c_str(), "wb");
        REQUIRE(f);
        std::fputs("this is not a png file", f);
        std::fclose(f);
    }
    error.clear();
    CHECK_FALSE(iqc::render::read_png(notpng.path.string(), img, &error));
    CHECK(error.find("not a PNG") != std::string::npos);

    // A truncated file fails inside libpng (its longjmp error path).
    TempFile truncated("iqc_png_trunc");
    {
        Image img2;
        img2.width = 32;
        img2.height = 32;
        img2.rgba.assign(32 * 32 * 4, 0.5f);
        for (size_t i = 0; i < img2.rgba.size(); i += 7) img2.rgba[i] = float(i % 13) / 13.0f;  // not all alike
        REQUIRE(iqc::render::write_png(truncated.path.string(), img2, &error));
        const auto size = std::filesystem::file_size(truncated.path);
        std::filesystem::resize_file(truncated.path, size / 2);
    }
    error.clear();
    Image untouched;
    untouched.width = 3;
    CHECK_FALSE(iqc::render::read_png(truncated.path.string(), untouched, &error));
    CHECK(error.find("libpng") != std::string::npos);
    CHECK(untouched.width == 3);  // left unchanged on failure

    error.clear();
    CHECK_FALSE(iqc::render::write_png("/tmp/x.png", Image{}, &error));  // empty image
    CHECK_FALSE(error.empty());
}
