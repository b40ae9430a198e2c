// Pass tests in IR text: each tests/passes/<pass>/<case>.ir holds an input module, the line `; expect:`, and
// the module the pass must make of it (ir::print's text). The input is parsed (ir/Parse.h), verified, given
// to the one pass its folder names, verified again, printed, and compared with the expectation.
//
// Regenerate the expectations (then review every diff as code):
//     IQC_UPDATE_GOLDEN=1 ./build/tests/iqc_tests "[passes]"
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <functional>

#include "TestUtil.h"
#include "ir/IR.h"
#include "ir/Parse.h"
#include "ir/Eval.h"
#include "ir/Pipeline.h"
#include "ir/passes/Linear.h"
#include "source/Internal.h"

using namespace iqc;
namespace fs = std::filesystem;

namespace {

const char* kExpect = "; expect:\n";

std::vector<fs::path> pass_cases() {
    std::vector<fs::path> out;
    for (auto& e : fs::recursive_directory_iterator(fs::path(IQC_SOURCE_DIR) / "tests" / "passes"))
        if (e.path().extension() == ".ir") out.push_back(e.path());
    std::sort(out.begin(), out.end());
    return out;
}

// A pass case's input module (the text before `; expect:`), parsed twice: one to keep, one for the pass.
void parse_case_twice(const fs::path& path, ir::Module& before, ir::Module& after) {
    std::string text = test::read_text(path);
    std::string input = text.substr(0, text.find(kExpect));
    std::string error;
    REQUIRE(ir::parse_module(input, before, error));
    REQUIRE(ir::parse_module(input, after, error));
}

// Each case of tests/passes/<pass>: the input module before and after that one pass (verified), with its path.
void for_each_case_through(const std::string& pass, const std::function<void(const fs::path&, const ir::Module&, const ir::Module&)>& fn) {
    for (const auto& path : pass_cases()) {
        if (path.parent_path().filename().string() != pass) continue;
        ir::Module before, after;
        parse_case_twice(path, before, after);
        ir::PipelineOptions o;
        ir::PipelineResult r;
        REQUIRE(ir::run_pass(pass, after, o, r));
        REQUIRE(ir::verify(after).empty());
        fn(path, before, after);
    }
}

// Evaluates the first function of `before` and of `after` at 200 random points (each parameter 1e-3 … 1e2 in
// size, either sign, times `scale`) in double precision and hands each pair of values to `check`; returns 200.
int compare_at_random_points(const ir::Module& before, const ir::Module& after, uint64_t seed, double scale,
                             const std::function<void(double, double, const std::vector<ir::Value>&)>& check) {
    ir::Evaluator eb(before), ea(after);
    const ir::Function& f = before.functions[0];
    uint64_t state = seed;
    auto next = [&] {
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        return double(state >> 11) / double(1ull << 53);
    };
    for (int s = 0; s < 200; ++s) {
        std::vector<ir::Value> args;
        for (const auto& p : f.params) args.push_back({p.type, {scale * (next() - 0.5) * 2 * std::pow(10.0, -3 + 5 * next())}});
        INFO("sample " << s);
        check(eb.call(0, args).v[0], ea.call(0, args).v[0], args);
    }
    return 200;
}

}  // namespace

TEST_CASE("every pass has IR-text tests", "[passes]") {
    for (const auto& p : ir::pipeline_passes()) {
        bool found = false;
        for (const auto& c : pass_cases()) found |= c.parent_path().filename() == p.name;
        INFO("tests/passes/" << p.name << "/*.ir");
        CHECK(found);
    }
}

TEST_CASE("passes on IR text: input, one pass, expected output", "[passes]") {
    bool update = std::getenv("IQC_UPDATE_GOLDEN") != nullptr;
    auto cases = pass_cases();
    REQUIRE(cases.size() >= 8);
    for (const auto& path : cases) {
        std::string text = test::read_text(path);
        size_t at = text.find(kExpect);
        INFO(path.string());
        REQUIRE(at != std::string::npos);
        std::string input = text.substr(0, at), expected = text.substr(at + std::string(kExpect).size());
        ir::Module m;
        std::string error;
        REQUIRE(ir::parse_module(input, m, error));
        INFO("input verifies: " << ir::verify(m));
        REQUIRE(ir::verify(m).empty());
        // The text form reads back as itself.
        ir::Module again;
        REQUIRE(ir::parse_module(ir::print(m), again, error));
        CHECK(ir::print(again) == ir::print(m));
        ir::PipelineOptions o;
        ir::PipelineResult r;
        std::string pass = path.parent_path().filename().string();
        if (pass == "linear") {  // an analyses' pass, not the pipeline's (ir/passes/Linear.h)
            for (auto& f : m.functions) ir::cancel_linear_terms(f);
        } else {
            REQUIRE(ir::run_pass(pass, m, o, r));
        }
        CHECK(ir::verify(m).empty());
        std::string actual = ir::print(m);
        for (const auto& w : r.range_issues) actual += "; warning: " + w.message + "\n";
        for (const auto& w : r.warnings) actual += "; warning: " + w.message + "\n";
        for (const auto& l : r.lipschitz) actual += "; lipschitz: " + l + "\n";
        for (const auto& rw : r.rewrites) actual += "; stable: " + rw.what + " in " + rw.function + "\n";
        if (update) {
            std::ofstream(path, std::ios::binary) << input << kExpect << actual;
            continue;
        }
        CHECK(actual == expected);
    }
}

TEST_CASE("the IR text reader reports what it cannot read, with the line", "[passes]") {
    ir::Module m;
    std::string error;
    CHECK_FALSE(ir::parse_module("function f() -> ℝ {\n  %0 = ℝ Frobnicate %1\n  return %0\n}\n", m, error));
    CHECK(error == "line 2: unknown operation 'Frobnicate'");
    ir::Module m2;
    CHECK_FALSE(ir::parse_module("function f() -> ℝ {\n  %1 = ℝ Const 1\n}\n", m2, error));
    CHECK(error == "line 2: instructions must be numbered in order (%0 expected)");
    ir::Module m3;
    CHECK_FALSE(ir::parse_module("function f() -> ℝ {\n  %0 = ℝ Call g\n  return %0\n}\n", m3, error));
    CHECK(error == "line 2: no function named 'g'");
    ir::Module m4;
    CHECK_FALSE(ir::parse_module("function f() -> ℝ {\n  %0 = ℝ Const 1\n", m4, error));
    CHECK_THAT(error, Catch::Contains("missing '}'"));
}

TEST_CASE("every pass verifies its IR and reports a fault as an internal error naming the pass", "[passes]") {
    // A function whose result is out of range: the verifier rejects it before the first pass.
    ir::Module bad;
    std::string error;
    REQUIRE(ir::parse_module("entry function f() -> ℝ {\n  %0 = ℝ Const 1\n  return %0\n}\n", bad, error));
    bad.functions[0].result = 7;
    ir::PipelineOptions o;
    o.verify_each = true;
    CHECK_THROWS_WITH(ir::run_pipeline(bad, o), Catch::Contains("invalid IR after lowering: f: result out of range"));
    // A fault injected in each pass stops the pipeline there.
    for (const auto& p : ir::pipeline_passes()) {
        ir::Module m;
        REQUIRE(ir::parse_module("entry function f() -> ℝ {\n  %0 = ℝ Const 1\n  return %0\n}\n", m, error));
        o.inject_fault = p.name;
        INFO(p.name);
        CHECK_THROWS_AS(ir::run_pipeline(m, o), InternalError);
        CHECK_THROWS_WITH(ir::run_pipeline(m, o), Catch::StartsWith(std::string(p.name) + ": injected fault"));
    }
}

// The stable pass changes no value: each case's function, before and after the rewrite, in double precision
// at points where the unstable form is still accurate in double (exponents within ±600, angles from 1e-3).
TEST_CASE("stable rewrites give the double evaluator's values of the forms they replace", "[passes][stable]") {
    auto cases = pass_cases();
    int compared = 0;
    for (const auto& path : cases) {
        if (path.parent_path().filename() != "stable") continue;
        ir::Module before, after;
        parse_case_twice(path, before, after);
        ir::PipelineOptions o;
        ir::PipelineResult r;
        REQUIRE(ir::run_pass("stable", after, o, r));
        CHECK_FALSE(r.rewrites.empty());
        // exponents up to e^±600 in log-sum-exp
        compared += compare_at_random_points(before, after, 12345, path.filename().string().find("log_sum_exp.ir") != std::string::npos ? 6 : 1,
                                             [&](double vb, double va, const std::vector<ir::Value>&) {
            INFO(path.filename().string() << ": " << vb << " against " << va);
            if (std::isnan(vb)) CHECK(std::isnan(va));  // sqrt(x² + xy) of x² + xy < 0, in both
            else if (std::isinf(vb)) CHECK(!std::isnan(va));  // the original overflows in double: the rewrite's value, or ∞ too
            else CHECK(std::abs(va - vb) <= 1e-9 * std::max(1.0, std::abs(vb)));
        });
    }
    CHECK(compared == 10 * 200);
}

// If-conversion changes no value: tests/passes/select's entry functions, before and after, evaluated in double
// precision at random points for every id from 0 to 14, agree exactly (the evaluator runs only a lazy choice's chosen arm, and a select's operands all).
// iqc_distance_of is called with instances' ids only (the cases of its dispatch): its default, which the converted
// dispatch drops, is compared nowhere else.
TEST_CASE("selects made of lazy choices give the values they replace", "[passes][select]") {
    int compared = 0;
    for_each_case_through("select", [&](const fs::path& path, const ir::Module& before, const ir::Module& after) {
        ir::Evaluator eb(before), ea(after);
        uint64_t state = 99;
        auto next = [&] {
            state = state * 6364136223846793005ull + 1442695040888963407ull;
            return double(state >> 11) / double(1ull << 53);
        };
        for (size_t fi = 0; fi < before.functions.size(); ++fi) {
            const ir::Function& f = before.functions[fi];
            if (!f.entry) continue;
            const ir::Instr& res = f.body[f.result];
            auto instance = [&](int id) {
                if (f.name != ir::names::kDistanceOf || res.op != ir::Op::Switch) return true;
                for (int k = 0; k < ir::switch_cases(res); ++k)
                    if (id >= res.data[size_t(2 * k)] && id < res.data[size_t(2 * k + 1)]) return true;
                return false;
            };
            for (int id = 0; id < 15; ++id)
                for (int s = 0; s < 8 && instance(id); ++s) {
                    std::vector<ir::Value> args;
                    for (const auto& p : f.params)
                        args.push_back(p.type.kind == Type::Integer ? ir::Value{p.type, {double(id)}}
                                                                    : ir::Value{p.type, {4 * next() - 2, 4 * next() - 2, 4 * next() - 2}});
                    INFO(path.filename().string() << " " << f.name << " id " << id);
                    CHECK(eb.call(int(fi), args).v == ea.call(int(fi), args).v);
                    ++compared;
                }
        }
    });
    CHECK(compared >= 4 * 15 * 8);
}

// Cancelling linear terms changes no value beyond rounding: tests/passes/linear's functions, before and after,
// in double precision at random points (each parameter 1e-3 … 1e2 in size, either sign).
TEST_CASE("cancelled linear terms give the values of the forms they replace", "[passes][linear]") {
    int compared = 0;
    for (const auto& path : pass_cases()) {
        if (path.parent_path().filename() != "linear") continue;
        ir::Module before, after;
        parse_case_twice(path, before, after);
        int rewritten = 0;
        for (auto& f : after.functions) rewritten += ir::cancel_linear_terms(f);
        CHECK(rewritten > 0);
        REQUIRE(ir::verify(after).empty());
        compared += compare_at_random_points(before, after, 777, 1, [&](double vb, double va, const std::vector<ir::Value>& args) {
            INFO(path.filename().string() << ": " << vb << " against " << va);
            CHECK(std::abs(va - vb) <= 1e-12 * std::max(1.0, std::abs(args[0].v[0]) + std::abs(args[1].v[0])));
        });
    }
    CHECK(compared >= 200);
}

// Binding array arguments changes no value: tests/passes/arrays' entry functions, before and after, evaluated in
// double precision at random points, agree exactly (the copies read the same global the argument was).
TEST_CASE("calls of copies that read global arrays in place give the values of the calls they replace", "[passes][arrays]") {
    int compared = 0;
    for_each_case_through("arrays", [&](const fs::path& path, const ir::Module& before, const ir::Module& after) {
        CHECK(after.functions.size() > before.functions.size());  // copies were made
        ir::Evaluator eb(before), ea(after);
        uint64_t state = 7;
        auto next = [&] {
            state = state * 6364136223846793005ull + 1442695040888963407ull;
            return double(state >> 11) / double(1ull << 53);
        };
        for (size_t fi = 0; fi < before.functions.size(); ++fi) {
            const ir::Function& f = before.functions[fi];
            if (!f.entry) continue;
            for (int s = 0; s < 50; ++s) {
                std::vector<ir::Value> args;
                for (const auto& p : f.params) args.push_back(ir::Value{p.type, {8 * next() - 4, 8 * next() - 4, 8 * next() - 4}});
                INFO(path.filename().string() << " " << f.name);
                CHECK(eb.call(int(fi), args).v == ea.call(int(fi), args).v);
                ++compared;
            }
        }
    });
    CHECK(compared >= 50);
}
