// Property tests of every shape module that exists (the standard library's, the examples', the hard
// cases'): evaluated in double precision on ≥ 10,000 point pairs, random and adversarial (the origin, the
// axes, far away, near the surface):
//   * K-Lipschitz: |D(x) − D(y)| ≤ K(1 + 1e-4)·‖x − y‖, K = 1 or the module's `# lipschitz: K` (the renderer
//     divides by K; marching relies on it);
//   * exact shapes (a module with the line `# exact`, and the reference shapes below) also have
//     |∇D| = 1 ± 1e-3 away from the medial axis (where the gradient is continuous).
#include <catch2/catch.hpp>

#include <cmath>
#include <memory>
#include <fmt/format.h>
#include <random>
#include <regex>

#include "TestUtil.h"
#include "scene/Modules.h"

using namespace iqc;
using namespace iqc::test;
namespace fs = std::filesystem;

namespace {

struct ShapeSource {
    std::string label;    // where it comes from
    std::string module;   // name
    ModuleSource source;
    bool exact = false;
};

// D at a point: one Evaluator for every call (its schedule is planned once; ir::evaluate per point planned
// it again each time: most of this test's time, 560 s under the sanitizers in CI).
struct Evaluable {
    ir::Module irm;
    int fn = -1;
    std::vector<ir::Value> args;
    int query = 0;
    std::unique_ptr<ir::Evaluator> ev;
    std::vector<const double*> arg_ptrs;
    double operator()(double x, double y, double z) {
        if (!ev) {
            ev = std::make_unique<ir::Evaluator>(irm);
            args[size_t(query)] = {Type::vector(3), {0, 0, 0}};
            for (auto& a : args) arg_ptrs.push_back(a.v.data());
        }
        std::vector<double>& q = args[size_t(query)].v;
        q[0] = x, q[1] = y, q[2] = z;
        double out = 0;
        ev->call(fn, arg_ptrs.data(), &out);
        return out;
    }
};

void check_shape(Evaluable& D, const std::string& label, bool exact, double lipschitz) {
    std::mt19937_64 rng(1234);
    std::uniform_real_distribution<double> u(-1, 1);
    auto rnd = [&](double s) { return std::array<double, 3>{s * u(rng), s * u(rng), s * u(rng)}; };
    int pairs = 0, violations = 0, grad_checked = 0, grad_bad = 0;
    double worst = 0;
    std::string example;
    auto pair_check = [&](std::array<double, 3> a, std::array<double, 3> b) {
        double da = D(a[0], a[1], a[2]), db = D(b[0], b[1], b[2]);
        double dist = std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
        if (!std::isfinite(da) || !std::isfinite(db) || dist == 0) return;
        ++pairs;
        double ratio = std::fabs(da - db) / dist;
        if (ratio > worst) worst = ratio;
        // Rounding of D itself: allow 1e-12 relative to the values' size.
        if (std::fabs(da - db) > lipschitz * (1 + 1e-4) * dist + 1e-12 * std::max({1.0, std::fabs(da), std::fabs(db)})) {
            if (violations++ == 0)
                example = fmt::format("at ({}, {}, {}) and ({}, {}, {}): |ΔD| = {} > ‖Δx‖ = {}", a[0], a[1], a[2], b[0], b[1], b[2],
                                      std::fabs(da - db), dist);
        }
    };
    const double scales[] = {0.01, 0.1, 1, 3, 10};
    for (int i = 0; i < 10000; ++i) {
        std::array<double, 3> a;
        switch (i % 10) {
            case 0: a = {0, 0, 0}; break;                                   // the origin
            case 1: a = {u(rng) * 4, 0, 0}; break;                          // axes
            case 2: a = {0, u(rng) * 4, 0}; break;
            case 3: a = {0, 0, u(rng) * 4}; break;
            case 4: a = rnd(1e4); break;                                    // far away
            default: a = rnd(4); break;
        }
        double s = scales[i % 5];
        std::array<double, 3> b = {a[0] + s * u(rng), a[1] + s * u(rng), a[2] + s * u(rng)};
        pair_check(a, b);
        // Near the surface: step a onto the zero set along the finite-difference gradient.
        if (i % 4 == 0) {
            std::array<double, 3> p = rnd(3);
            for (int k = 0; k < 20; ++k) {
                double d = D(p[0], p[1], p[2]);
                if (!std::isfinite(d) || std::fabs(d) < 1e-9) break;
                const double h = 1e-6;
                double g[3] = {(D(p[0] + h, p[1], p[2]) - D(p[0] - h, p[1], p[2])) / (2 * h),
                               (D(p[0], p[1] + h, p[2]) - D(p[0], p[1] - h, p[2])) / (2 * h),
                               (D(p[0], p[1], p[2] + h) - D(p[0], p[1], p[2] - h)) / (2 * h)};
                double l2 = g[0] * g[0] + g[1] * g[1] + g[2] * g[2];
                if (l2 < 1e-12) break;
                for (int c = 0; c < 3; ++c) p[size_t(c)] -= d * g[c] / l2;
            }
            pair_check(p, {p[0] + 1e-3 * u(rng), p[1] + 1e-3 * u(rng), p[2] + 1e-3 * u(rng)});
        }
        if (exact && i % 2 == 0) {
            // |∇D| by central differences at two step sizes; where they disagree the point is near a kink.
            std::array<double, 3> p = i % 4 == 0 ? a : rnd(3);
            auto grad = [&](double h) {
                double g[3] = {(D(p[0] + h, p[1], p[2]) - D(p[0] - h, p[1], p[2])) / (2 * h),
                               (D(p[0], p[1] + h, p[2]) - D(p[0], p[1] - h, p[2])) / (2 * h),
                               (D(p[0], p[1], p[2] + h) - D(p[0], p[1], p[2] - h)) / (2 * h)};
                return std::array<double, 3>{g[0], g[1], g[2]};
            };
            double scale = std::max(1.0, std::fabs(p[0]) + std::fabs(p[1]) + std::fabs(p[2]));
            auto g1 = grad(1e-4 * scale);
            auto g2 = grad(1e-6 * scale);
            // One-sided differences: at a kink (a medial axis, a symmetry plane inside a box) they disagree
            // with the central ones even where central differences of two sizes agree.
            double h = 1e-6 * scale, d0 = D(p[0], p[1], p[2]);
            std::array<double, 3> gf = {(D(p[0] + h, p[1], p[2]) - d0) / h, (D(p[0], p[1] + h, p[2]) - d0) / h,
                                        (D(p[0], p[1], p[2] + h) - d0) / h};
            auto dist3 = [](const std::array<double, 3>& x, const std::array<double, 3>& y) {
                return std::sqrt((x[0] - y[0]) * (x[0] - y[0]) + (x[1] - y[1]) * (x[1] - y[1]) + (x[2] - y[2]) * (x[2] - y[2]));
            };
            if (dist3(g1, g2) > 1e-4 || dist3(gf, g2) > 1e-3) continue;  // a medial axis or an edge is within reach
            ++grad_checked;
            double n = std::sqrt(g2[0] * g2[0] + g2[1] * g2[1] + g2[2] * g2[2]);
            if (std::fabs(n - 1) > 1e-3) ++grad_bad;
        }
    }
    INFO(label << ": " << pairs << " pairs, worst |ΔD|/‖Δx‖ = " << worst << (violations ? "; first violation " + example : ""));
    CHECK(pairs >= 10000);
    CHECK(violations == 0);
    if (exact) {
        INFO(grad_checked << " gradients checked, " << grad_bad << " with |∇D| off 1 by more than 1e-3");
        CHECK(grad_checked > 1000);
        CHECK(grad_bad == 0);
    }
}

// `keep` owns the scene descriptions the returned module sources point into (freed with it).
std::vector<ShapeSource> all_shapes(SourceManager& sm, Diagnostics& d, std::vector<std::unique_ptr<SceneDesc>>& keep) {
    std::vector<ShapeSource> out;
    fs::path root = IQC_SOURCE_DIR;
    auto add_file_modules = [&](const fs::path& p) {
        SceneDesc scene;
        SourceManager local;
        if (p.extension() == ".iql") {
            std::string text = read_text(p);
            FileId f = sm.add(p.string(), text);
            out.push_back({p.filename().string(), p.stem().string(), {p.stem().string(), f, {{0, uint32_t(text.size())}}, {f, 0, 1}, "file"},
                           false});  // exactness comes from the module's `# exact` pragma
            return;
        }
        keep.push_back(std::make_unique<SceneDesc>());  // kept alive: the module sources point into it
        SceneDesc* desc = keep.back().get();
        load_scene(p.string(), sm, d, *desc);
        for (const auto& m : desc->modules) {
            std::string text;
            for (auto& r : m.ranges) text += std::string(sm.text(m.file).substr(r.begin, r.end - r.begin));
            out.push_back({p.filename().string() + ":" + m.name, m.name, m, false});
        }
    };
    // (tests/hardcases/ holds deliberately bad formulas, such as an angular term with an unbounded slope.)
    for (const char* dir : {"stdlib", "examples"}) {
        std::vector<fs::path> files;
        for (auto& e : fs::directory_iterator(root / dir)) files.push_back(e.path());
        std::sort(files.begin(), files.end());
        for (auto& f : files)
            if (f.extension() == ".iql" || f.extension() == ".iq" || (f.extension() == ".md" && f.filename() != "README.md"))
                add_file_modules(f);
    }
    return out;
}

}  // namespace

TEST_CASE("every shape module is 1-Lipschitz: exact ones have a unit gradient", "[properties]") {
    SourceManager sm;
    Diagnostics d(sm);
    std::vector<std::unique_ptr<SceneDesc>> scenes;
    auto shapes = all_shapes(sm, d, scenes);
    // Reference exact shapes, in case no module claims exactness yet.
    const std::vector<std::pair<std::string, std::string>> exact_refs = {
        {"sphere", "shape\n# exact\nD = ‖p‖ - 1\nwhere\np ∈ ℝ³\n"},
        {"box", "shape\n# exact\nD = ‖(max(q_1, 0), max(q_2, 0), max(q_3, 0))‖ + min(max(q_1, q_2, q_3), 0)\nq = (|p_1|, |p_2|, |p_3|) - (0.5, 1, 0.3)\nwhere\np ∈ ℝ³\n"},
        {"torus", "shape\n# exact\nD = ‖q‖ - 0.3\nq = (‖(p_1, p_3)‖ - 1, p_2)\nwhere\np ∈ ℝ³\n"},
        {"plane", "shape\n# exact\nD = p⋅(0.6, 0.8, 0) - 0.5\nwhere\np ∈ ℝ³\n"},
    };
    for (const auto& [name, text] : exact_refs) {
        FileId f = sm.add(name + ".iql", text);
        shapes.push_back({"reference " + name, name, {name, f, {{0, uint32_t(text.size())}}, {f, 0, 1}, "test"}, true});
    }
    int tested = 0, exact = 0;
    for (const auto& s : shapes) {
        ModuleLibrary lib(sm, d, {});
        lib.add(s.source);
        const CheckedModule* m = lib.get(s.module, {});
        if (!m || m->ast.kind != ast::ModuleKind::Shape) continue;
        INFO(s.label << "\n" << d.render());
        REQUIRE(m->ok);
        Evaluable D;
        LowerContext ctx{D.irm, {}, {}};
        D.fn = lower_module(*m, s.module, s.module, ctx);
        for (size_t k = 0; k < m->params.size(); ++k) {
            D.args.push_back({m->params[k].type, m->params[k].value});
            if (m->params[k].name == "p") D.query = int(k);
        }
        // One pass over the shapes (a SECTION per shape would rerun the whole case, loading and lowering every
        // shape, once per shape: quadratic, 384 s under AddressSanitizer); check_shape says which one failed.
        check_shape(D, s.label, s.exact || m->exactness == "exact", m->lipschitz);
        ++tested;
        exact += s.exact;
    }
    CHECK(tested >= 8);
    CHECK(exact >= 4);
}
