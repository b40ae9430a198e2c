// The conformance suite's case files (tests/conformance/*.iqtest): format and loader, shared by the
// runner through `iqc eval` (conformance_test.cpp) and the runner through emitted GLSL
// (conformance_glsl_test.cpp). See conformance_test.cpp for the format.
#pragma once

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include "TestUtil.h"

namespace iqc::test::conformance {

namespace fs = std::filesystem;


struct ConformanceCase {
    std::string file;  // file name, e.g. 01_precedence.iqtest
    int line = 0;      // line of the ### header
    std::string name;
    std::string module;
    std::vector<std::string> sets;
    std::vector<std::string> expects;
    std::vector<std::string> errors;
    bool has_expect = false, has_error = false, has_module = false;
};

inline std::vector<std::string> split_lines(const std::string& text) {
    std::vector<std::string> lines;
    std::string cur;
    for (char c : text) {
        if (c == '\n') {
            lines.push_back(cur);
            cur.clear();
        } else {
            cur += c;
        }
    }
    if (!cur.empty()) lines.push_back(cur);
    for (auto& l : lines)
        if (!l.empty() && l.back() == '\r') l.pop_back();
    return lines;
}

inline std::string trim(const std::string& s) {
    size_t b = s.find_first_not_of(" \t");
    if (b == std::string::npos) return "";
    size_t e = s.find_last_not_of(" \t");
    return s.substr(b, e - b + 1);
}

inline bool starts_with(const std::string& s, const std::string& p) { return s.compare(0, p.size(), p) == 0; }

// Parses one .iqtest file; structural problems of the file itself are reported in `problems`.
inline std::vector<ConformanceCase> parse_iqtest(const fs::path& path, std::vector<std::string>& problems) {
    std::vector<ConformanceCase> cases;
    auto lines = split_lines(read_text(path));
    std::string file = path.filename().string();
    std::string section;
    std::vector<std::string> module_lines;
    auto finish_module = [&] {
        if (cases.empty()) return;
        while (!module_lines.empty() && trim(module_lines.back()).empty()) module_lines.pop_back();
        std::string text;
        for (auto& l : module_lines) text += l + "\n";
        if (!module_lines.empty()) cases.back().module = text;
        module_lines.clear();
    };
    for (size_t i = 0; i < lines.size(); ++i) {
        const std::string& l = lines[i];
        if (starts_with(l, "### ")) {
            finish_module();
            ConformanceCase c;
            c.file = file;
            c.line = int(i + 1);
            c.name = trim(l.substr(4));
            cases.push_back(c);
            section.clear();
            continue;
        }
        if (starts_with(l, "--- ")) {
            std::string s = trim(l.substr(4));
            if (s != "module" && s != "set" && s != "expect" && s != "error") {
                problems.push_back(file + ":" + std::to_string(i + 1) + ": unknown section '" + s + "'");
                continue;
            }
            if (cases.empty()) {
                problems.push_back(file + ":" + std::to_string(i + 1) + ": section before the first ### case");
                continue;
            }
            finish_module();
            section = s;
            if (s == "module") cases.back().has_module = true;
            if (s == "expect") cases.back().has_expect = true;
            if (s == "error") cases.back().has_error = true;
            continue;
        }
        if (cases.empty()) {
            if (!trim(l).empty()) problems.push_back(file + ":" + std::to_string(i + 1) + ": text before the first ### case");
            continue;
        }
        ConformanceCase& c = cases.back();
        if (section == "module") {
            module_lines.push_back(l);
        } else if (trim(l).empty()) {
            continue;
        } else if (section == "set") {
            c.sets.push_back(trim(l));
        } else if (section == "expect") {
            c.expects.push_back(trim(l));
        } else if (section == "error") {
            c.errors.push_back(trim(l));
        } else {
            problems.push_back(file + ":" + std::to_string(i + 1) + ": text outside a section");
        }
    }
    finish_module();
    for (auto& c : cases) {
        std::string where = file + ":" + std::to_string(c.line) + " (" + c.name + ")";
        if (!c.has_module || c.module.empty()) problems.push_back(where + ": no module");
        if (c.has_expect == c.has_error) problems.push_back(where + ": needs exactly one of --- expect and --- error");
        if (c.has_expect && c.expects.empty()) problems.push_back(where + ": empty --- expect");
        if (c.has_error && c.errors.empty()) problems.push_back(where + ": empty --- error");
    }
    return cases;
}

inline std::vector<ConformanceCase> load_suite(std::vector<std::string>& problems) {
    fs::path dir = fs::path(IQC_SOURCE_DIR) / "tests" / "conformance";
    std::vector<fs::path> files;
    if (fs::is_directory(dir))
        for (auto& e : fs::directory_iterator(dir))
            if (e.path().extension() == ".iqtest") files.push_back(e.path());
    std::sort(files.begin(), files.end());
    std::vector<ConformanceCase> all;
    for (auto& f : files) {
        auto cs = parse_iqtest(f, problems);
        all.insert(all.end(), cs.begin(), cs.end());
    }
    return all;
}

}  // namespace iqc::test::conformance
