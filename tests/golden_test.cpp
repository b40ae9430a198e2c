// Golden tests: every example and every input under golden/ compiles, for every target, to exactly the
// expected shader, byte for byte, and the expected file itself passes glslang (Shadertoy's wrapper for
// shadertoy; ES 3.00 for webgl2; core 3.30 for glsl330; for the examples also Vulkan GLSL 4.50 to SPIR-V and
// SPIRV-Tools for spirv, whose golden is the Vulkan GLSL the module is compiled from, glslang's HLSL front
// end for hlsl, and Tint in Dawn for Node for wgsl: tests/browser/wgsl-validate.mjs).
//
// Inputs: examples/<name>.{md,iq}  ->  golden/examples/<name>.<target>.expected
//         golden/<area>/<name>.{md,iq,iql} -> golden/<area>/<name>.<target>.expected
// (golden/effects/ holds one scene per effect and its effect-off twin; tests/effects_test.cpp checks that
// the twin contains none of the effect's code.)
// Regenerate (then review every diff as code):  IQC_UPDATE_GOLDEN=1 ./build/tests/iqc_tests "[golden]"
//                                          or:  scripts/update-goldens.sh
#include <catch2/catch.hpp>
#include <cstdlib>

#include "TestUtil.h"
#include "glsl/ShadertoyWrapper.h"
#include "glsl/Spirv.h"
#include "glsl/Validate.h"

using namespace iqc;
using namespace iqc::test;
namespace fs = std::filesystem;

namespace {

struct GoldenCase {
    fs::path input, expected;
    Target target;
};

const Target kTargets[] = {Target::Shadertoy, Target::WebGL2, Target::GLSL330};

std::vector<GoldenCase> golden_cases() {
    std::vector<GoldenCase> cases;
    fs::path root = IQC_SOURCE_DIR;
    auto is_input = [](const fs::path& p) {
        auto e = p.extension();
        return e == ".md" || e == ".iq" || e == ".iql";
    };
    auto add = [&](const fs::path& input, const fs::path& dir, bool engines) {
        for (Target t : kTargets)
            cases.push_back({input, dir / (input.stem().string() + "." + target_name(t) + ".expected"), t});
        if (engines)  // the SPIR-V target's Vulkan GLSL (the module is its compilation) and the HLSL
            for (Target t : {Target::SPIRV, Target::HLSL, Target::WGSL})
                cases.push_back({input, dir / (input.stem().string() + "." + target_name(t) + ".expected"), t});
    };
    for (auto& e : fs::directory_iterator(root / "examples"))
        if (is_input(e.path()) && e.path().filename() != "README.md") add(e.path(), root / "golden" / "examples", true);
    for (auto& area : fs::directory_iterator(root / "golden")) {
        if (!area.is_directory()) continue;
        for (auto& e : fs::directory_iterator(area.path()))
            if (is_input(e.path())) add(e.path(), area.path(), false);
    }
    std::sort(cases.begin(), cases.end(), [](auto& a, auto& b) { return a.expected < b.expected; });
    return cases;
}

// Runs a shell command; its standard output and error in `out`; true when it exits 0.
bool capture(const std::string& cmd, std::string& out) {
    FILE* p = popen((cmd + " 2>&1").c_str(), "r");
    if (!p) return false;
    char buf[4096];
    size_t n;
    while ((n = fread(buf, 1, sizeof buf, p)) > 0) out.append(buf, n);
    return pclose(p) == 0;
}

std::string unified_diff(const fs::path& expected, const std::string& actual) {
    auto tmp = write_temp("actual.frag", actual);
    std::string out;
    capture("diff -u '" + expected.string() + "' '" + tmp.string() + "'", out);
    return out;
}

}  // namespace

TEST_CASE("golden: every example compiles to its expected shader", "[golden]") {
    bool update = std::getenv("IQC_UPDATE_GOLDEN") != nullptr;
    auto cases = golden_cases();
    REQUIRE(cases.size() >= 12);
    for (const auto& c : cases) {
        SECTION(c.expected.filename().string()) {
            CompileOptions opts;
            opts.target = c.target;
            Compiled r = compile_path(c.input, opts);
            INFO(c.input.string() << "\n" << r.diagnostics << r.result.internal);
            REQUIRE(r.result.exit_code == 0);
            // Paths in the output are file names only, so goldens do not depend on where the repo is.
            if (update) {
                fs::create_directories(c.expected.parent_path());
                std::ofstream(c.expected, std::ios::binary) << r.result.code;
            }
            REQUIRE(fs::exists(c.expected));
            std::string expected = read_text(c.expected);
            INFO("golden mismatch; the diff (expected -> actual):\n" << unified_diff(c.expected, r.result.code));
            CHECK(r.result.code == expected);
            glsl::ValidationResult v;
            switch (c.target) {
                case Target::Shadertoy: v = glsl::validate_fragment(glsl::wrap_shadertoy(expected), glsl::Profile::Es300); break;
                case Target::WebGL2:
                case Target::ThreeJS: v = glsl::validate_fragment(expected, glsl::Profile::Es300); break;
                case Target::GLSL330: v = glsl::validate_fragment(expected, glsl::Profile::Core330); break;
                case Target::SPIRV: {
                    glsl::SpirvResult spv = glsl::compile_vulkan_fragment(expected);
                    v.ok = spv.ok && spv.words == r.result.spirv;  // the module is the golden's compilation
                    v.log = spv.log;
                    break;
                }
                case Target::HLSL: v = glsl::validate_hlsl_fragment(expected); break;
                case Target::WGSL: {
                    // Tint (Dawn for Node, tests/browser/wgsl-validate.mjs): no WGSL compiler runs in-process
                    v.ok = capture("node '" + (fs::path(IQC_SOURCE_DIR) / "tests/browser/wgsl-validate.mjs").string() + "' '" +
                                       c.expected.string() + "'", v.log) &&
                           v.log.rfind("ok ", 0) == 0;
                    break;
                }
            }
            INFO(v.log);
            CHECK(v.ok);
        }
    }
}

TEST_CASE("golden: output is deterministic", "[golden]") {
    auto cases = golden_cases();
    REQUIRE(!cases.empty());
    Compiled a = compile_path(cases[0].input, {});
    Compiled b = compile_path(cases[0].input, {});
    CHECK(a.result.code == b.result.code);
}
