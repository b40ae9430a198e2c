// Rendering a scene written in a test: compiled for Shadertoy from a temporary file and drawn on the
// headless renderer (llvmpipe), failing the test on a compile or render error; and the largest difference
// of two pictures. Shared by the lighting-model and blend tests.
#pragma once

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <string>

#include "TestUtil.h"
#include "render/Render.h"

namespace iqc::test {

// `text` written as `name` (its extension says .iq, .md or .iql), compiled and drawn at w×h.
inline render::Image render_scene(const std::string& name, const std::string& text, int w = 96, int h = 54) {
    Compiled c = compile_text(name, text);
    INFO(name << "\n" << c.diagnostics);
    REQUIRE(c.result.exit_code == 0);
    render::RenderOptions o;
    o.width = w;
    o.height = h;
    auto r = render::render_shadertoy(c.result.code, o);
    INFO(r.error);
    REQUIRE(r.ok);
    return r.image;
}

// The largest difference of any channel of any pixel (the pictures have one size).
inline double max_abs_diff(const render::Image& a, const render::Image& b) {
    double m = 0;
    for (size_t i = 0; i < a.rgba.size(); ++i) m = std::max(m, double(std::fabs(a.rgba[i] - b.rgba[i])));
    return m;
}

}  // namespace iqc::test
