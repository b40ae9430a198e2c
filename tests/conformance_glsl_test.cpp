// The conformance suite through emitted GLSL: every expect case's module is lowered, its outputs computed
// by a probe shader on the headless renderer (llvmpipe, or a GPU), and compared with the double-precision
// evaluator within single-precision tolerance. Outputs GLSL cannot hold (larger than vec4/mat4, row
// vectors) are counted and reported, not compared.
#include <catch2/catch.hpp>

#include <cmath>
#include <fmt/format.h>

#include "Conformance.h"
#include "TestUtil.h"
#include "glsl/Probe.h"
#include "glsl/ShadertoyWrapper.h"
#include "glsl/Validate.h"
#include "render/Render.h"
#include "scene/Modules.h"

using namespace iqc;
using namespace iqc::test;
using namespace iqc::test::conformance;

TEST_CASE("conformance suite through emitted GLSL agrees with the evaluator", "[conformance][render]") {
    std::vector<std::string> problems;
    auto cases = load_suite(problems);
    REQUIRE(problems.empty());
    std::string err;
    auto renderer = render::Renderer::create(&err);
    REQUIRE(renderer);
    int compared = 0, outputs_compared = 0, not_representable = 0;
    std::vector<std::string> skipped_modules;  // modules with values GLSL cannot hold
    std::vector<std::string> failures;
    for (const auto& c : cases) {
        if (!c.has_expect) continue;
        SourceManager sm;
        Diagnostics d(sm);
        FileId f = sm.add(c.name + ".iql", c.module);
        ModuleSource src;
        src.name = "m";
        src.file = f;
        src.ranges = {{0, uint32_t(c.module.size())}};
        src.where = {f, 0, 1};
        ModuleLibrary lib(sm, d, {});
        // --set values: evaluate them as the CLI does (they may bind symbolic sizes).
        std::map<std::string, Type> given_types;
        std::map<std::string, ir::Value> given;
        bool ok = true;
        for (const auto& s : c.sets) {
            size_t eq = s.find('=');
            std::string n = trim(s.substr(0, eq)), text = s.substr(eq + 1);
            if (n.size() > 2 && n.front() == '`') n = n.substr(1, n.size() - 2);
            FileId vf = sm.add("value", text);
            ModuleSource vs{"value", vf, {{0, uint32_t(text.size())}}, {vf, 0, 1}, "value"};
            auto vm = lib.parse_check(vs, "value", false);
            if (!vm->ok || !vm->ret) { ok = false; break; }
            ir::Module vir;
            LowerContext vctx{vir, {}, {}};
            ir::Value v = ir::evaluate(vir, lower_module(*vm, "value", "value", vctx), {});
            given[n] = v;
            given_types[n] = v.type;
        }
        if (!ok) continue;
        auto m = lib.parse_check(src, "m", false, given_types);
        INFO(c.name << "\n" << d.render());
        REQUIRE(m->ok);
        ir::Module irm;
        LowerContext ctx{irm, {}, {}};
        int fn = lower_module(*m, "m", "m", ctx);
        std::vector<ir::Value> args;
        for (const auto& p : m->params) {
            auto it = given.find(p.name);
            args.push_back({p.type, it != given.end() ? it->second.v : p.value});
        }
        auto all = ir::evaluate_all(irm, fn, args);
        glsl::Probe probe = glsl::make_probe(irm, fn, args, d);
        if (d.has_errors()) {
            // Only GLSL's size limits may stop the backend (vectors over 4 components, row vectors).
            std::string text = d.render();
            INFO(text);
            CHECK_THAT(text, Catch::Contains("cannot generate GLSL"));
            skipped_modules.push_back(c.name);
            continue;
        }
        auto v = glsl::validate_fragment(glsl::wrap_shadertoy(probe.code), glsl::Profile::Es300);
        INFO(c.name << "\n" << probe.code << "\n" << v.log);
        REQUIRE(v.ok);
        render::RenderOptions ro;
        ro.width = probe.pixels;
        ro.height = 1;
        auto r = renderer->render(glsl::wrap_shadertoy(probe.code), ro);
        REQUIRE(r.ok);
        ++compared;
        const ir::Function& F = irm.functions[size_t(fn)];
        for (size_t j = 0; j < probe.outputs.size(); ++j) {
            const auto& po = probe.outputs[j];
            if (po.first_pixel < 0) {
                ++not_representable;
                continue;
            }
            const ir::Value& ref = all[F.outputs[j].second];
            for (int k = 0; k < po.type.components(); ++k) {
                double want = ref.v[size_t(k)];
                double got = r.image.pixel(po.first_pixel + k, 0)[0];
                ++outputs_compared;
                // Single precision with the GPU's approximate transcendentals: 5e-4 of the value's magnitude
                // (floor 1 near 0). The worst seen on llvmpipe is acos(0.3), off by 1.6e-4.
                double tol = 5e-4 * std::max(1.0, std::fabs(want));
                bool same = std::isfinite(want) ? std::fabs(got - want) <= tol : !std::isfinite(got) || std::isnan(want);
                if (!same)
                    failures.push_back(fmt::format("{} ({}:{}): {}[{}] GLSL {} vs evaluator {}", c.name, c.file, c.line,
                                                   po.name, k, got, want));
            }
        }
    }
    INFO(fmt::format("{} modules, {} components compared; {} outputs not representable in GLSL", compared,
                     outputs_compared, not_representable));
    for (const auto& f : failures) FAIL_CHECK(f);
    CHECK(compared >= 200);
    CHECK(skipped_modules.size() <= 10);
    WARN(fmt::format("conformance through GLSL: {} modules, {} components compared, {} outputs GLSL cannot hold, "
                     "{} modules GLSL cannot hold ({})",
                     compared, outputs_compared, not_representable, skipped_modules.size(), fmt::join(skipped_modules, "; ")));
}
