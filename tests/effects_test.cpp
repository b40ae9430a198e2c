// "Simulate only what the scene calls for": for each effect, golden/effects/<effect>.iq turns it on in
// the scene golden/effects/base.iq, whose output must contain none of the effect's code. The checks read
// the golden files (which golden_test.cpp keeps equal to the compiler's output) for every target.
#include <catch2/catch.hpp>

#include "TestUtil.h"

using namespace iqc;
using namespace iqc::test;
namespace fs = std::filesystem;

namespace {

// Code that exists only when the effect is on.
const std::vector<std::pair<std::string, std::vector<std::string>>> kEffects = {
    {"shadows_hard", {"float iqc_shadow(", "c_l *= iqc_shadow(p, N, P_L);"}},
    {"shadows_soft", {"float iqc_shadow(", "IQC_SHADOW_K", "sqrt(max(h * h - y * y, 0.0))"}},
    {"ao", {"float iqc_ao(", "c *= iqc_ao(p, N);"}},
    {"fog", {"IQC_FOG", "exp(-IQC_FOG * t)"}},
    {"reflections", {"vec3 iqc_reflectivity(", "IQC_BOUNCES", "reflect(rd, N)"}},
    {"refraction", {"vec4 iqc_transmission(", "refract(", "IQC_BOUNCES"}},
    {"antialias", {"IQC_AA"}},
    {"debug_normals", {"return 0.5 + 0.5 * N;\n"}},
    {"debug_steps", {"float(steps) / float(IQC_MAX_STEPS)"}},
    {"debug_depth", {"1.0 - t / IQC_MAX_DIST"}},
    {"orbit_camera", {"iMouse.x > 0.0", "yaw"}},
    {"march_fixed", {"IQC_FIXED_STEP", "bisection"}},
    {"march_relaxed", {"IQC_RELAXATION", "Keinert"}},
    {"march_auto", {"Bán & Valasek", "step_len = d * (1.0 + g * (1.0 + m) / (1.0 - m))"}},
    {"normals_central", {"Normal by central differences"}},
    {"normals_forward", {"Normal by forward differences"}},
    {"normals_analytic", {"derived by iqc (forward-mode differentiation)", "vec3 iqc_gradient(vec3 p, int id) {",
                          "if (id == 1) g = p / max(length(p), 1.0e-30);", "int taps = dot(g, g) < 1.0e-24 ? 4 : 0;"}},
    {"hit_relative", {"IQC_HIT * max(t, 1.0e-3)"}},
};

std::string golden(const std::string& name, const char* target) {
    return read_text(fs::path(IQC_SOURCE_DIR) / "golden" / "effects" / (name + "." + target + ".expected"));
}

}  // namespace

TEST_CASE("each effect's code appears only when the scene asks for it", "[effects][golden]") {
    for (const char* target : {"shadertoy", "webgl2", "glsl330"}) {
        std::string base = golden("base", target);
        REQUIRE(!base.empty());
        for (const auto& [effect, markers] : kEffects) {
            std::string on = golden(effect, target);
            INFO(effect << " (" << target << ")");
            REQUIRE(!on.empty());
            for (const auto& m : markers) {
                // The mouse orbit is the Shadertoy shader's: the uniform targets take the host's camera (the html
                // page orbits it), so there the orbit scene's shader has none of it either.
                if (effect == "orbit_camera" && std::string(target) != "shadertoy") CHECK_THAT(on, !Catch::Contains(m));
                else CHECK_THAT(on, Catch::Contains(m));
                CHECK_THAT(base, !Catch::Contains(m));
            }
        }
        // The base scene marches by sphere tracing and takes tetrahedron normals.
        CHECK_THAT(base, Catch::Contains("Sphere tracing (Hart 1996)"));
        CHECK_THAT(base, Catch::Contains("tetrahedron finite differences"));
        CHECK_THAT(base, !Catch::Contains("Normal by central differences"));
    }
}

TEST_CASE("unused modules and unused outputs cost nothing", "[effects]") {
    std::string base = golden("base", "shadertoy");
    // golden/effects/base.iq defines a module `unused` that no instance uses.
    CHECK_THAT(base, !Catch::Contains("unused"));
    // A statement the distance does not need is not emitted.
    Compiled c = compile_text("extra.md", "❤: blob\n```iheartla\nshape\nD = ‖p‖ - 1\nwaste = ‖p‖³ + 17\nwhere\np ∈ ℝ³\n```\n"
                                          "```scene\n[[shapes]]\ntype = \"blob\"\n```\n");
    REQUIRE(c.result.exit_code == 0);
    CHECK_THAT(c.result.code, !Catch::Contains("waste"));
    CHECK_THAT(c.result.code, !Catch::Contains("17.0"));
}
