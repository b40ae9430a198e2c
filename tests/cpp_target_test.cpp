// The `cpp` target (issue 14): a C++17 header per bundled example, all compiled together by the system's C++
// compiler with -Wall -Wextra -Werror, and a program that checks each header's shader is byte for byte the
// webgl2 target's and its parameter table matches --meta (count, names, defaults). A title built to escape
// the raw string and the string literals must come back as written.
#include <catch2/catch.hpp>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "TestUtil.h"

using namespace iqc::test;
namespace fs = std::filesystem;

TEST_CASE("cpp target: headers of every example compile and hold the webgl2 shader and its parameters", "[cpp-target]") {
    fs::path dir = temp_dir() / "cpp_target";
    fs::remove_all(dir);
    fs::create_directories(dir);
    std::vector<fs::path> inputs;
    for (auto& e : fs::directory_iterator(fs::path(IQC_SOURCE_DIR) / "examples"))
        if ((e.path().extension() == ".iq" || e.path().extension() == ".md") && e.path().filename() != "README.md")
            inputs.push_back(e.path());
    std::sort(inputs.begin(), inputs.end());
    // A hostile title: it ends a raw string with the default delimiter, a string literal, a comment.
    std::string title = "x)iqc\" ; int injected = 1; R\"iqc( \\ \" */ ?? ☃";
    nlohmann::json t = title;
    inputs.push_back(write_temp("cpp_hostile_title.iq", "title = " + t.dump() + "\n[[shapes]]\ntype = \"sphere\"\n"));
    // 4,200 spheres with their own radius and colour: a data texture of ~280,000 base64 characters and 8,400
    // parameters. A constexpr string_view of a bare literal is measured by a loop that g++ stops past 262,144
    // steps, and clang's step limit was hit by the parameters' names from ~1,700 instances (a new user's trial):
    // every view now has its length written out.
    std::string many = "[camera]\nposition = [0, 40, -60]\ntarget = [0, 0, 0]\n[[lights]]\nposition = [-5, 8, -6]\n";
    for (int i = 0; i < 4200; ++i)
        many += fmt::format("[[shapes]]\ntype = \"sphere\"\nmaterial = \"lambert\"\nmaterial_params = {{ k_d = [{:.3f}, {:.3f}, {:.3f}] }}\n"
                            "shape_params = {{ r = {:.2f} }}\ntransform = \"T(({}, 0, {}))\"\n",
                            (i % 7) / 7.0, (i % 11) / 11.0, (i % 13) / 13.0, 0.3 + 0.01 * (i % 9), i % 70 - 35, i / 70 - 30);
    inputs.push_back(write_temp("cpp_many_members.iq", many));
    // A value below float's range (g++ -Werror stopped at `1e-50f`: "floating constant truncated to zero", a new
    // user's trial; a number written so is an error now, a product computed so is not), FLT_MAX as printed (3.4028235e38 rounds to it; it was refused), and four instances sharing a
    // shape with sequence parameters (their --meta read past the sequence: an entry per element now).
    inputs.push_back(write_temp("cpp_extreme_numbers.iq", "[modules]\nblob = \"\"\"\nshape\nD = ‖p‖ - r + 1e-30 a + 1e-30 b + "
                                                          "0.01(x_2,1 + w_1)\nwhere\np ∈ ℝ³\nr ∈ [0.05,0.5] default = 0.2\na ∈ ℝ\nb ∈ ℝ\n"
                                                          "x_i ∈ ℝ³ default = {(1, 0, 0), (0, 1, 0)}\nw_j ∈ ℝ default = {0.5, 0.25, 0.125}\n"
                                                          "\"\"\"\n[[shapes]]\ntype = \"blob\"\nshape_params = { a = \"1e-30 * 1e-30\", b = 3.4028235e38 }\n"
                                                          "transform = \"T((-2, 0, 6))\"\n"
                                                          "[[shapes]]\ntype = \"blob\"\ntransform = \"T((-1, 0, 6))\"\n"
                                                          "[[shapes]]\ntype = \"blob\"\ntransform = \"T((0, 0, 6))\"\n"
                                                          "[[shapes]]\ntype = \"blob\"\ntransform = \"T((1, 0, 6))\"\n"));
    std::string includes, checks;
    for (const auto& in : inputs) {
        std::string stem = in.stem().string();
        fs::path hpp = dir / (stem + ".hpp"), frag = dir / (stem + ".frag"), meta = dir / (stem + ".json");
        RunResult c = run_iqc(in.string() + " --target cpp -o " + hpp.string());
        INFO(stem << ": " << c.err);
        REQUIRE(c.exit_code == 0);
        RunResult w = run_iqc(in.string() + " --target webgl2 -o " + frag.string() + " --meta " + meta.string());
        REQUIRE(w.exit_code == 0);
        auto j = nlohmann::json::parse(read_text(meta));
        includes += fmt::format("#include \"{}.hpp\"\n", stem);
        std::string ns = "iqc_" + stem;
        checks += fmt::format("    ok &= same(iqc_{0}::kFragmentShader, read(dir + \"/{0}.frag\"), \"{0}\");\n", stem);
        checks += fmt::format("    ok &= expect(iqc_{}::kParameters.size() == {}, \"{} parameters\");\n", stem, j["parameters"].size(), stem);
        checks += fmt::format("    ok &= expect(iqc_{}::kTitle == {}, \"{} title\");\n", stem, nlohmann::json(j["title"].get<std::string>()).dump(), stem);
        if (j["texture"].is_object())
            checks += fmt::format("    ok &= expect(iqc_{}::kTextureBase64.size() == {}, \"{} texture\");\n", stem,
                                  j["texture"]["data"].get<std::string>().size(), stem);
        if (!j["parameters"].empty()) {
            const auto& p = j["parameters"][0];
            checks += fmt::format("    ok &= expect(iqc_{}::kParameters[0].name == {} && iqc_{}::kParameters[0].components == {}"
                                  " && iqc_{}::kParameters[0].defaults[0] == float({}), \"{} first parameter\");\n",
                                  stem, nlohmann::json(p["name"].get<std::string>()).dump(), stem, p["components"].get<int>(), stem,
                                  fmt::format("{:.9g}", p["default"][0].get<double>()), stem);
        }
    }
    std::string main_cpp = includes + R"(
#include <fstream>
#include <iostream>
#include <iterator>
#include <string>
static std::string read(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}
static bool same(std::string_view a, const std::string& b, const char* what) {
    if (a == b) return true;
    std::cerr << what << ": the header's shader differs from the webgl2 output\n";
    return false;
}
static bool expect(bool c, const char* what) {
    if (!c) std::cerr << "failed: " << what << "\n";
    return c;
}
int main(int, char** argv) {
    std::string dir = argv[1];
    bool ok = true;
)" + checks + R"(    std::cout << (ok ? "all good" : "FAILED") << "\n";
    return ok ? 0 : 1;
}
)";
    std::ofstream(dir / "main.cpp") << main_cpp;
    std::string cmd = fmt::format("cd '{0}' && c++ -std=c++17 -Wall -Wextra -Werror main.cpp -o main > build.log 2>&1 && ./main '{0}' > run.log 2>&1",
                                  dir.string());
    int status = std::system(cmd.c_str());
    INFO(read_text(dir / "build.log") << read_text(dir / "run.log"));
    CHECK(WEXITSTATUS(status) == 0);
    CHECK_THAT(read_text(dir / "run.log"), Catch::Contains("all good"));
    std::string hostile = read_text(dir / "cpp_hostile_title.hpp");
    // The title's quote is an octal escape in the literal, and the raw string's delimiter is not `iqc`.
    CHECK((hostile.find("x)iqc\\042 ; int injected") != std::string::npos));
    CHECK((hostile.find("\n    R\"iqc0(#version 300 es") != std::string::npos));
}

TEST_CASE("cpp target: the namespace is a name C++ does not reserve", "[cpp-target]") {
    // A trial: `a__b.iq` and `_x.iq` gave namespaces iqc_a__b and iqc__x (C++ reserves every identifier with a
    // double underscore). Runs of '_' are one, and none ends the name.
    for (auto [stem, ns] : {std::pair<const char*, const char*>{"a__b", "iqc_a_b"}, {"_x", "iqc_x"}, {"odd--name_", "iqc_odd_name"}}) {
        INFO(stem);
        auto in = write_temp(std::string(stem) + ".iq", "[[shapes]]\ntype = \"sphere\"\n");
        auto out = temp_dir() / (std::string(stem) + ".hpp");
        RunResult r = run_iqc(in.string() + " --target cpp -o " + out.string());
        REQUIRE(r.exit_code == 0);
        std::string text = read_text(out);
        CHECK_THAT(text, Catch::Contains(std::string("\nnamespace ") + ns + " {\n"));
        CHECK_THAT(text, Catch::Contains(std::string("}  // namespace ") + ns + "\n"));
    }
}
