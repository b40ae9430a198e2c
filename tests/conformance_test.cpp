// The conformance suite: every tests/conformance/*.iqtest file holds cases of the language written as
// modules with their expected outputs (or expected diagnostics), derived by hand from the math, and run
// through `iqc eval`.
//
// Case format (one or more per file):
//
//   ### short case name (unique across the suite)
//   --- module
//   <module text, exactly as a .iql file>
//   --- set                    (optional) NAME=VALUE per line, passed as --set 'NAME=VALUE'
//   --- expect                 NAME = VALUE  exact text of that output line
//                              NAME ≈ VALUE  numeric match (tolerance 1e-9, relative or absolute),
//                                            for scalars, vectors and matrices alike
//   --- error                  L:C: text       stderr contains "<file>:L:C: error: text"
//                              note L:C: text  stderr contains "<file>:L:C: note: text"
//
// An expect case must exit 0, an error case 1. Outputs that are not listed are not checked.
// IQC_CONFORMANCE_FILTER=substring runs only the cases whose name contains it.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <regex>
#include <set>
#include <string>
#include <vector>

#include "Conformance.h"
#include "TestUtil.h"

using namespace iqc::test;
using namespace iqc::test::conformance;
namespace fs = std::filesystem;

namespace {
std::string shell_quote(const std::string& s) {
    std::string q = "'";
    for (char c : s) {
        if (c == '\'')
            q += "'\\''";
        else
            q += c;
    }
    return q + "'";
}

std::string file_stem_for(const std::string& name) {
    std::string s;
    for (unsigned char c : name) s += std::isalnum(c) ? char(c) : '_';
    return "conf_" + s;
}

// A value written as text: its numbers and the punctuation around them (whitespace dropped).
struct Shape {
    std::vector<double> numbers;
    std::string skeleton;
    bool ok = true;
};

Shape numeric_shape(const std::string& text) {
    static const std::regex number(R"(^[-+]?(?:inf|nan|(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?))");
    Shape s;
    size_t i = 0;
    bool expect_value = true;  // a sign starts a number only where a value may begin
    while (i < text.size()) {
        char c = text[i];
        if (c == ' ' || c == '\t') {
            ++i;
            expect_value = true;
            continue;
        }
        std::smatch m;
        std::string rest = text.substr(i);
        bool signed_start = (c == '-' || c == '+');
        if ((!signed_start || expect_value) && std::regex_search(rest, m, number) && m.position(0) == 0 &&
            m.length(0) > 0 && !(signed_start && m.length(0) == 1)) {
            std::string tok = m.str(0);
            s.numbers.push_back(std::strtod(tok.c_str(), nullptr));
            s.skeleton += '#';
            i += size_t(m.length(0));
            expect_value = false;
            continue;
        }
        if (std::string("()[],;").find(c) == std::string::npos) s.ok = false;
        s.skeleton += c;
        ++i;
        expect_value = true;
    }
    return s;
}

bool numbers_close(double a, double b) {
    if (std::isnan(a) || std::isnan(b)) return std::isnan(a) && std::isnan(b);
    if (a == b) return true;
    double tol = 1e-9 * std::max({1.0, std::fabs(a), std::fabs(b)});
    return std::fabs(a - b) <= tol;
}

// Splits "NAME = VALUE" / "NAME ≈ VALUE" at the first " = " or " ≈ ".
bool split_expect(const std::string& line, std::string& name, std::string& op, std::string& value) {
    size_t eq = line.find(" = ");
    size_t ap = line.find(" ≈ ");
    size_t at = std::min(eq, ap);
    if (at == std::string::npos) return false;
    name = trim(line.substr(0, at));
    if (at == eq) {
        op = "=";
        value = trim(line.substr(at + 3));
    } else {
        op = "≈";
        value = trim(line.substr(at + std::string(" ≈ ").size()));
    }
    return true;
}

// Runs one case; returns an empty string when it passes, else a one-line reason.
std::string run_case(const ConformanceCase& c, RunResult& r) {
    auto path = write_temp(file_stem_for(c.name) + ".iql", c.module);
    std::string args = "eval " + shell_quote(path.string());
    for (auto& s : c.sets) args += " --set " + shell_quote(s);
    r = run_iqc(args);
    std::string fname = path.filename().string();

    if (c.has_expect) {
        if (r.exit_code != 0) {
            std::string first = split_lines(r.err).empty() ? "" : split_lines(r.err)[0];
            return "exit code " + std::to_string(r.exit_code) + " (expected 0): " + first;
        }
        std::map<std::string, std::string> outs;
        for (auto& l : split_lines(r.out)) {
            size_t at = l.find(" = ");
            if (at != std::string::npos) outs[l.substr(0, at)] = trim(l.substr(at + 3));
        }
        for (auto& e : c.expects) {
            std::string name, op, value;
            if (!split_expect(e, name, op, value)) return "malformed expect line: " + e;
            auto it = outs.find(name);
            if (it == outs.end()) return "no output named '" + name + "' (expected " + e + ")";
            const std::string& got = it->second;
            if (op == "=") {
                if (got != value) return "expected '" + name + " = " + value + "', got '" + name + " = " + got + "'";
            } else {
                Shape want = numeric_shape(value), have = numeric_shape(got);
                bool same = want.ok && have.ok && want.skeleton == have.skeleton &&
                            want.numbers.size() == have.numbers.size();
                for (size_t i = 0; same && i < want.numbers.size(); ++i)
                    same = numbers_close(want.numbers[i], have.numbers[i]);
                if (!same) return "expected '" + name + " ≈ " + value + "', got '" + name + " = " + got + "'";
            }
        }
        return "";
    }

    // An error case.
    if (r.exit_code != 1) return "exit code " + std::to_string(r.exit_code) + " (expected 1 with diagnostics)";
    static const std::regex loc(R"(^(note\s+)?(\d+):(\d+):\s?(.*)$)");
    for (auto& e : c.errors) {
        std::smatch m;
        if (!std::regex_match(e, m, loc)) return "malformed error line: " + e;
        std::string kind = m[1].matched ? "note" : "error";
        std::string want = fname + ":" + m[2].str() + ":" + m[3].str() + ": " + kind + ": " + m[4].str();
        if (r.err.find(want) == std::string::npos) {
            std::string first = split_lines(r.err).empty() ? "(no diagnostics)" : split_lines(r.err)[0];
            return "missing '" + want + "'; first diagnostic: " + first;
        }
    }
    return "";
}

}  // namespace

TEST_CASE("conformance suite", "[conformance]") {
    std::vector<std::string> problems;
    std::vector<ConformanceCase> cases = load_suite(problems);

    // The suite files themselves are well formed and the case names are unique.
    for (auto& p : problems) {
        INFO(p);
        CHECK(false);
    }
    std::set<std::string> names;
    for (auto& c : cases) {
        INFO("duplicate case name: " << c.name << " (" << c.file << ":" << c.line << ")");
        CHECK(names.insert(c.name).second);
    }
    CHECK(cases.size() >= 600);  // issue 13: the suite covers the language at this size

    const char* filter = std::getenv("IQC_CONFORMANCE_FILTER");
    int failed = 0, run = 0;
    std::string summary;
    for (auto& c : cases) {
        if (filter && *filter && c.name.find(filter) == std::string::npos) continue;
        ++run;
        RunResult r;
        std::string reason = run_case(c, r);
        INFO("case: " << c.name << "  (" << c.file << ":" << c.line << ")");
        INFO("module:\n" << c.module);
        INFO("reason: " << reason);
        INFO("iqc stdout:\n" << r.out);
        INFO("iqc stderr:\n" << r.err);
        CHECK(reason.empty());
        if (!reason.empty()) {
            ++failed;
            summary += "  [" + c.file + "] " + c.name + ": " + reason + "\n";
        }
    }
    if (failed) WARN("conformance: " << failed << " of " << run << " cases failed:\n" << summary);
}
