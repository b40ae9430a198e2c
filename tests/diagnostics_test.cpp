// Every error path of the language front end: the message, its location (file:line:col), the source
// line and the caret. Several errors are reported in one run where recovery makes sense.
#include <catch2/catch.hpp>

#include "TestUtil.h"

using namespace iqc;
using namespace iqc::test;

static std::string errors_of(const std::string& src) {
    Evaluated e = eval_module(src);
    REQUIRE_FALSE(e.ok);
    return e.diagnostics;
}

TEST_CASE("diagnostics show the location, the line and a caret under the span", "[diag]") {
    std::string d = errors_of("D = ‖q‖ - s\nwhere\nq ∈ ℝ³\n");
    CHECK(d == "test.iql:1:11: error: undefined name 's'\n"
               "  D = ‖q‖ - s\n"
               "            ^\n");
}

TEST_CASE("type errors name both sides with their types", "[diag]") {
    CHECK_THAT(errors_of("y = a + b\nwhere\na ∈ ℝ³\nb ∈ ℝ⁴\n"),
               Catch::Contains("test.iql:1:5: error: cannot add ℝ³ and ℝ⁴"));
    CHECK_THAT(errors_of("y = A b\nwhere\nA ∈ ℝ^(3×3)\nb ∈ ℝ²\n"),
               Catch::Contains("test.iql:1:5: error: cannot multiply ℝ^(3×3) by ℝ²: the inner sizes differ"));
    CHECK_THAT(errors_of("y = a b\nwhere\na ∈ ℝ³\nb ∈ ℝ³\n"),
               Catch::Contains("test.iql:1:5: error: cannot multiply ℝ³ by ℝ³: use ⋅ for the dot product"));
    CHECK_THAT(errors_of("y = a / b\nwhere\na ∈ ℝ\nb ∈ ℝ³\n"),
               Catch::Contains("test.iql:1:9: error: cannot divide by ℝ³: '/' needs a scalar divisor"));
    CHECK_THAT(errors_of("y = v_4\nwhere\nv ∈ ℝ³\n"),
               Catch::Contains("test.iql:1:7: error: subscript 4 is out of range: ℝ³ has 3 components"));
}

TEST_CASE("declaration errors", "[diag]") {
    CHECK_THAT(errors_of("y = t_1\nwhere\nt ∈ [0,2]x[0,2] default = (1, 2, 3)\n"),
               Catch::Contains("test.iql:3:27: error: the default has 3 components but 't' is ℝ²"));
    CHECK_THAT(errors_of("y = t\nwhere\nt ∈ [0,1] default = 2\n"),
               Catch::Contains("test.iql:3:21: error: the default 2 of 't' is outside its bounds [0, 1]"));
    CHECK_THAT(errors_of("y = t\nwhere\nt ∈ [2,1]\n"), Catch::Contains("test.iql:3:5: error: the interval is empty"));
}

TEST_CASE("names assigned twice, cycles and recursion", "[diag]") {
    std::string d = errors_of("a = 1\nb = 2\na = 3\n");
    CHECK_THAT(d, Catch::Contains("test.iql:3:1: error: 'a' is assigned twice"));
    CHECK_THAT(d, Catch::Contains("test.iql:1:1: note: first defined here"));
    CHECK_THAT(errors_of("a = b + 1\nb = c\nc = a\n"), Catch::Contains("test.iql:1:1: error: dependency cycle: a → b → c → a"));
    CHECK_THAT(errors_of("f(x) = f(x) + 1 where x ∈ ℝ\ny = f(1)\n"),
               Catch::Contains("error: 'f' calls itself: recursion is not supported"));
}

TEST_CASE("did-you-mean and missing imports", "[diag]") {
    std::string d2 = errors_of("y = raduis2\nwhere\nradius ∈ ℝ\n");
    CHECK_THAT(d2, Catch::Contains("error: undefined name"));
    CHECK_THAT(errors_of("y = `radiu` + 1\nwhere\n`radius` ∈ ℝ\n"),
               Catch::Contains("test.iql:1:5: note: did you mean 'radius'?"));
    CHECK_THAT(errors_of("y = sin(1)\n"), Catch::Contains("test.iql:1:5: error: 'sin' needs an import: add 'sin from trigonometry'"));
    CHECK_THAT(errors_of("sinus from trigonometry\ny = 1\n"),
               Catch::Contains("test.iql:1:1: error: module 'trigonometry' has no function 'sinus'"));
    // A built-in name imported: said so (a trial wrote `e, ln from trigonometry`).
    const std::string ln = errors_of("e, ln from trigonometry\ny = ln(e)\n");
    CHECK_THAT(ln, Catch::Contains("test.iql:1:4: error: module 'trigonometry' has no function 'ln'"));
    CHECK_THAT(ln, Catch::Contains("test.iql:1:4: note: 'ln' is built in: use it without an import"));
}

TEST_CASE("syntax errors are located and recovery reports several per run", "[diag]") {
    // Inside parentheses and norms an expression may go on over several lines, so an unclosed one is
    // reported where the next statement begins, with a note where it opened.
    std::string d = errors_of("a = (1 + 2\nb = 3 +\nc = ‖x\nd = 4\ne = 4 $ 5\nf = 2 +\nwhere\nx ∈ ℝ³\n");
    CHECK_THAT(d, Catch::Contains("test.iql:2:3: error: expected ')', found '='"));
    CHECK_THAT(d, Catch::Contains("test.iql:1:5: note: opened here"));
    CHECK_THAT(d, Catch::Contains("test.iql:4:3: error: expected '‖' to close the norm, found '='"));
    CHECK_THAT(d, Catch::Contains("test.iql:3:5: note: opened here"));
    CHECK_THAT(d, Catch::Contains("test.iql:5:7: error: unexpected character '$'"));
    CHECK_THAT(d, Catch::Contains("test.iql:7:1: error: unexpected keyword 'where' in an expression"));
}

TEST_CASE("a module whose every statement is wrong reports each error and does not crash", "[diag]") {
    std::string d = errors_of("a = b\nc = (1, 2) + (1, 2, 3)\nd = q_9\ne = f(1)\nwhere\nq ∈ ℝ²\n");
    CHECK_THAT(d, Catch::Contains("1:5: error: undefined name 'b'"));
    CHECK_THAT(d, Catch::Contains("2:5: error: cannot add ℝ² and ℝ³"));
    CHECK_THAT(d, Catch::Contains("3:7: error: subscript 9 is out of range"));
    CHECK_THAT(d, Catch::Contains("4:5: error: undefined name 'f'"));
}

TEST_CASE("type errors carry notes at the declarations involved", "[diag]") {
    std::string d = errors_of("y = a + q\nq = (1, 2)\nwhere\na ∈ ℝ³\n");
    CHECK_THAT(d, Catch::Contains("test.iql:1:5: error: cannot add ℝ³ and ℝ²"));
    CHECK_THAT(d, Catch::Contains("test.iql:4:1: note: 'a' is declared here as ℝ³"));
    CHECK_THAT(d, Catch::Contains("test.iql:2:1: note: 'q' is defined here as ℝ²"));
}

TEST_CASE("GLSL's size limit is a located error", "[diag]") {
    Compiled c = compile_text("five.md", "❤: blob\n```iheartla\nshape\nv = (p, 1, 2)\nD = ‖v‖ - 1\nwhere\np ∈ ℝ³\n```\n"
                                         "```scene\n[[shapes]]\ntype = \"blob\"\n```\n");
    CHECK(c.result.exit_code == 1);
    CHECK_THAT(c.diagnostics, Catch::Contains("five.md:4:1: error: cannot generate GLSL: ℝ⁵ is larger than GLSL's largest vector (vec4)"));
    // a parameter GLSL cannot hold: at its declaration (it was at the file's start; a wgsl trial)
    Compiled p = compile_text("ten.iq", "[modules]\nbig = \"\"\"\nshape\nD = ‖p‖ - 0.5 - 0.01w_7\nwhere\np ∈ ℝ³\n"
                                        "w ∈ ℝ^10 default = (1,2,3,4,5,6,7,8,9,10)\n\"\"\"\n[[shapes]]\ntype = \"big\"\n");
    CHECK(p.result.exit_code == 1);
    CHECK_THAT(p.diagnostics, Catch::Contains("ten.iq:7:1: error: cannot generate GLSL: ℝ¹⁰ is larger than GLSL's largest vector (vec4)"));
    CHECK_THAT(p.diagnostics, Catch::Contains("  w ∈ ℝ^10 default"));
}

TEST_CASE("imports from module files beside the input, and import cycles", "[diag]") {
    write_temp("helpers.iql", "sq(x) = x² where x ∈ ℝ\n");
    auto user = write_temp("user.iql", "sq from helpers\ny = sq(3)\n");
    RunResult r = run_iqc("eval " + user.string());
    INFO(r.err);
    CHECK(r.out == "y = 9\n");
    write_temp("cyc_a.iql", "g from cyc_b\nf(x) = x where x ∈ ℝ\n");
    write_temp("cyc_b.iql", "f from cyc_a\ng(x) = x where x ∈ ℝ\n");
    auto top = write_temp("cyc_top.iql", "f from cyc_a\ny = f(1)\n");
    RunResult c = run_iqc("eval " + top.string());
    CHECK(c.exit_code == 1);
    CHECK_THAT(c.err, Catch::Contains("cyc_b.iql:1:8: error: module 'cyc_a' imports itself (an import cycle)"));
}

TEST_CASE("a multi-letter function definition without backticks says how to write it", "[diag]") {
    std::string d = errors_of("smooth_union(a, b) = min(a, b) where a ∈ ℝ, b ∈ ℝ\nx = 1\n");
    CHECK_THAT(d, Catch::Contains("test.iql:1:20: error: unexpected '=' after the end of the statement\n"
                                  "  smooth_union(a, b) = min(a, b) where a ∈ ℝ, b ∈ ℝ\n"
                                  "                     ^\n"));
    CHECK_THAT(d, Catch::Contains("test.iql:1:1: note: 'smooth_union' reads as a product of one-letter names; to "
                                  "define a function with this name, write it in backticks: `smooth_union`(…) = …\n"
                                  "  smooth_union(a, b) = min(a, b) where a ∈ ℝ, b ∈ ℝ\n"
                                  "  ^~~~~~~~~~~~\n"));
    // A one-letter function followed by '=' elsewhere is not given the hint.
    CHECK_THAT(errors_of("y = 1 = 2\n"), !Catch::Contains("backticks"));
}

TEST_CASE("a literal outside the 32-bit float range is a located error", "[diag]") {
    // 1e-50 is 0 in a shader: max(‖q‖, 1e-50) would guard nothing (issue 12).
    CHECK(errors_of("D = ‖q‖/max(‖q‖, 1e-50)\nwhere\nq ∈ ℝ³\n") ==
          "test.iql:1:18: error: the number 1e-50 is below the smallest normal 32-bit float (about 1.2e-38), which shaders "
          "compute in: it would be 0 there (a guard such as max(x, 1e-30) works)\n"
          "  D = ‖q‖/max(‖q‖, 1e-50)\n"
          "                   ^~~~~\n");
    CHECK_THAT(errors_of("y = 2x + 1e39\nwhere\nx ∈ ℝ\n"),
               Catch::Contains("test.iql:1:10: error: the number 1e39 is outside the range of 32-bit floats (at most about 3.4e38)"));
    // The ends of the range are fine.
    Evaluated ok = eval_module("y = 1e-30 + 3e38 - 3e38\n");
    CHECK(ok.ok);
}

TEST_CASE("π cannot be declared or assigned", "[diag]") {
    // A trial: `π = 3` (and `π ∈ ℝ`) were accepted, and every π after them was 3.
    CHECK(errors_of("π = 3\ny = π\n") == "test.iql:1:1: error: 'π' is the constant 3.14159…: it cannot be assigned; choose another name\n"
                                           "  π = 3\n  ^\n");
    CHECK_THAT(errors_of("y = π x\nwhere\nπ ∈ ℝ\nx ∈ ℝ\n"),
               Catch::Contains("test.iql:3:1: error: 'π' is the constant 3.14159…: it cannot be declared; choose another name"));
}

TEST_CASE("a recurrence's first element cannot read itself, the result or a later sequence", "[diag]") {
    // Found by the ir fuzzer (tests/fuzz/ir/first_element_reads_itself.iql): these lowered to a missing value,
    // an internal error (exit 3).
    CHECK_THAT(errors_of("y = d_2\nd_1 = min(d_1, 0) + 1\nd_(k+1) = d_k + 1 for k ∈ 1..1\n"),
               Catch::Contains("test.iql:2:11: error: 'd_1' cannot read d_1: a first element cannot read itself or the recurrence's result"));
    CHECK_THAT(errors_of("y = d_2\nd_1 = d_2 + 1\nd_(k+1) = d_k + 1 for k ∈ 1..1\n"),
               Catch::Contains("test.iql:2:7: error: 'd_1' cannot read a later element"));
    CHECK_THAT(errors_of("y = d_2 + e_2\nd_1 = e_1\ne_1 = 1\nd_(k+1) = d_k + 1 for k ∈ 1..1\ne_(k+1) = e_k + 1 for k ∈ 1..1\n"),
               Catch::Contains("test.iql:2:7: error: 'd_1' cannot read e_1: first elements are computed in the order of the "
                               "recurrences, and e's comes after d's; write e's recurrence first"));
    // In that order it is fine.
    Evaluated ok = eval_module("y = d_2 + e_2\ne_1 = 1\nd_1 = e_1 + 1\ne_(k+1) = e_k + 1 for k ∈ 1..1\nd_(k+1) = d_k + 1 for k ∈ 1..1\n");
    INFO(ok.diagnostics);
    CHECK(ok.ok);
}

TEST_CASE("an error in a module written as a TOML string with escapes points at the file's own line and column", "[diag]") {
    // A new user's trial: `blob = "shape\nD = ‖p‖ - q\n…"` was reported at line 3 of a file whose line 3 is empty,
    // quoting a line the file does not have; a line-ending backslash and \u escapes shifted lines and columns too.
    struct Case {
        const char* name;
        std::string scene, expected;
    };
    const std::vector<Case> cases = {
        {"escaped.iq", "[modules]\nblob = \"shape\\nD = ‖p‖ - q\\nwhere\\np ∈ ℝ³\\n\"\n\n[[shapes]]\ntype = \"blob\"\n",
         "escaped.iq:2:26: error: undefined name 'q'\n  blob = \"shape\\nD = ‖p‖ - q\\nwhere\\np ∈ ℝ³\\n\"\n                           ^\n"},
        {"continued.iq", "[modules]\nblob = \"\"\"\nshape\nD = ‖p‖ - \\\n  r + `zz`\nwhere\np ∈ ℝ³\nr ∈ [0,1] default = 0.5\n\"\"\"\n"
                         "[[shapes]]\ntype = \"blob\"\n",
         "continued.iq:5:7: error: undefined name 'zz'\n    r + `zz`\n        ^~~~\n"},
        {"unicode_escape.iq", "[[shapes]]\ntype = \"sphere\"\ntransform = \"\\u0054((1, 0, `zz`))\"\n",
         "unicode_escape.iq:3:28: error: undefined name 'zz'\n  transform = \"\\u0054((1, 0, `zz`))\"\n                             ^~~~\n"},
    };
    for (const auto& c : cases) {
        INFO(c.name);
        Compiled r = compile_text(c.name, c.scene);
        CHECK(r.result.exit_code == 1);
        INFO(r.diagnostics);
        CHECK(r.diagnostics.find(c.expected) != std::string::npos);
    }
}

TEST_CASE("the caret under a line indented with tabs keeps the tabs", "[diag]") {
    // A trial: a module indented with tabs got its caret columns to the left of the name (spaces only, where a
    // terminal widens each tab to its next stop).
    CHECK(errors_of("y = x +\tzz\nwhere\nx ∈ ℝ\n").find("  y = x +\tzz\n         \t^") != std::string::npos);
}

TEST_CASE("a declaration with a subscript digit says how to name the parameter", "[diag]") {
    // A trial: `x₁ ∈ ℝ` got "expected '∈' in the declaration, found subscript" (x₁ is component 1 of x).
    CHECK_THAT(errors_of("y = x_1\nwhere\nx₁ ∈ ℝ default = 2\n"),
               Catch::Contains("test.iql:3:1: error: 'x₁' is a component of x, not a name: to declare a parameter named x_1, "
                               "write x_1 (and use it as x_1)\n  x₁ ∈ ℝ default = 2\n  ^~\n"));
}

TEST_CASE("a failed sequence declaration is said once", "[diag]") {
    // A trial: a local function's parameter declared as a sequence typed `a` as ℝ³ and its `a_i` as a component
    // ("cannot subtract ℝ from ℝ³" at p - a_i).
    std::string d = errors_of("y = f(x_1)\nwhere\np ∈ ℝ³\nx_i ∈ ℝ³ default = {(1, 0, 0), (0, 1, 0)}\n"
                              "f(a) = ∑_i ‖p - a_i‖ where a_i ∈ ℝ³\n");
    CHECK(d == "test.iql:5:3: error: the parameter 'a' of 'f' is declared as a sequence (a_i ∈ …): a local function's "
               "parameters are single values; read the module's sequence in the function instead (f() = ∑_i … x_i …)\n"
               "  f(a) = ∑_i ‖p - a_i‖ where a_i ∈ ℝ³\n    ^\n");
    // Passing it the module's sequence is not a second error (it was: "'x' is a sequence", listed first), nor
    // where the parameter takes the module's declaration of a sequence of its name.
    CHECK(errors_of("y = f(x)\nwhere\np ∈ ℝ³\nx_i ∈ ℝ³ default = {(1, 0, 0), (0, 1, 0)}\n"
                    "f(a) = ∑_i ‖p - a_i‖ where a_i ∈ ℝ³\n") == d);
    CHECK_THAT(errors_of("y = f(x)\nf(a) = ∑_i ‖p - a_i‖\nwhere\np ∈ ℝ³\nx_i ∈ ℝ³ default = {(1, 0, 0)}\n"
                         "a_i ∈ ℝ³ default = {(1, 0, 0)}\n"),
               Catch::StartsWith("test.iql:2:3: error: the parameter 'a' of 'f' is declared as a sequence") &&
                   !Catch::Contains("'x' is a sequence"));
    // (A sequence may have bounds since stop 52, each element's: tests/conformance/22_sequences.iqtest.)
}

TEST_CASE("an empty sequence's declaration is one error", "[diag]") {
    // A trial (stop 52): `w_i ∈ ℝ default = {}` added "undefined name 'w'" at each use after the real error.
    auto f = write_temp("empty_seq.iql", "shape\nD = ‖p‖ - 1 + ∑_i w_i\nwhere\np ∈ ℝ³\nw_i ∈ ℝ default = {}\n");
    RunResult r = run_iqc(f.string() + " -o /dev/null");
    CHECK(r.exit_code == 1);
    CHECK_THAT(r.err, Catch::Contains("empty_seq.iql:5:19: error: '{}' is an empty sequence: a sequence has at least one element"));
    CHECK_THAT(r.err, !Catch::Contains("undefined name"));
}

TEST_CASE("the same error at the same place is said once", "[diag]") {
    // A trial: `a(sin(r), 0, 0)` (a product or a call: the checker tries both readings) said "'sin' needs an
    // import" twice, "2 errors".
    auto f = write_temp("twice.iql", "shape\nc = a(sin(r), 0, 0)\nD = c_1\nwhere\np ∈ ℝ³\na ∈ ℝ\nr ∈ ℝ\n");
    RunResult r = run_iqc(f.string() + " -o /dev/null");
    CHECK(r.exit_code == 1);
    CHECK_THAT(r.err, Catch::Contains("twice.iql:2:7: error: 'sin' needs an import: add 'sin from trigonometry'"));
    size_t first = r.err.find("needs an import");
    CHECK(r.err.find("needs an import", first + 1) == std::string::npos);
    CHECK_THAT(r.err, !Catch::Contains("2 errors"));
}

TEST_CASE("an empty sequence {} says so", "[diag]") {
    // A trial: `--set 'x={}'` said "a piecewise definition needs at least one 'if' case".
    CHECK(errors_of("y = {}\n") == "test.iql:1:5: error: '{}' is an empty sequence: a sequence has at least one element, as in {1, 2}\n"
                                   "  y = {}\n      ^~\n");
    auto f = write_temp("empty_set.iql", "y = ∑_i x_i\nwhere\nx_i ∈ ℝ default = {1, 2}\n");
    RunResult r = run_iqc("eval " + f.string() + " --set 'x={}'");
    CHECK(r.exit_code == 1);
    CHECK_THAT(r.err, Catch::Contains("--set x:1:1: error: '{}' is an empty sequence"));
}
