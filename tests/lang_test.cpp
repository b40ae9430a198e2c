// The math language end to end through the evaluator: precedence and juxtaposition as I♥LA reads them,
// names, statements in any order, built-ins, vectors and matrices.
#include <catch2/catch.hpp>
#include <cmath>

#include "TestUtil.h"
#include "scene/Modules.h"

using namespace iqc;
using namespace iqc::test;

static double eval1(const std::string& src, const std::string& out = "y",
                    const std::map<std::string, std::vector<double>>& set = {}) {
    Evaluated e = eval_module(src, set);
    INFO(e.diagnostics);
    REQUIRE(e.ok);
    return scalar_of(e, out);
}

TEST_CASE("precedence and juxtaposition follow I♥LA", "[lang]") {
    const std::string decl = "\nwhere\na ∈ ℝ\nb ∈ ℝ\nc ∈ ℝ\nx ∈ ℝ\n";
    std::map<std::string, std::vector<double>> v = {{"a", {6}}, {"b", {2}}, {"c", {3}}, {"x", {2}}};
    CHECK(eval1("y = a/bc" + decl, "y", v) == Approx(9.0));       // (a/b)c
    CHECK(eval1("y = -a2" + decl, "y", v) == Approx(-12.0));       // -(2a)
    CHECK(eval1("y = x^2c" + decl, "y", v) == Approx(12.0));       // x²c
    CHECK(eval1("y = x²c" + decl, "y", v) == Approx(12.0));
    CHECK(eval1("y = -x²" + decl, "y", v) == Approx(-4.0));        // -(x²)
    CHECK(eval1("y = a - b - c" + decl, "y", v) == Approx(1.0));   // left-associative
    CHECK(eval1("y = a b + c" + decl, "y", v) == Approx(15.0));
    CHECK(eval1("y = 2(a + b)c" + decl, "y", v) == Approx(48.0));
    CHECK(eval1("y = a * b" + decl, "y", v) == Approx(12.0));       // ASCII * (extension)
    CHECK(eval1("y = ½a" + decl, "y", v) == Approx(3.0));
    CHECK(eval1("y = x^-1" + decl, "y", v) == Approx(0.5));
    CHECK(eval1("y = x⁻¹" + decl, "y", v) == Approx(0.5));
    CHECK(eval1("y = 2e-3" + decl, "y", v) == Approx(0.002));
    CHECK(eval1("y = ac" + decl, "y", v) == Approx(18.0));         // undeclared `ac` is a·c
}

TEST_CASE("declared multi-letter names win over juxtaposition", "[lang]") {
    const std::string src = "y = ab c\nwhere\nab ∈ ℝ\nc ∈ ℝ\na ∈ ℝ\nb ∈ ℝ\n";
    CHECK(eval1(src, "y", {{"ab", {5}}, {"c", {3}}, {"a", {100}}, {"b", {100}}}) == Approx(15.0));
    // Backtick names are one name; `abc` and abc are the same when declared.
    CHECK(eval1("y = `k_d` 2\nwhere\n`k_d` ∈ ℝ\n", "y", {{"k_d", {4}}}) == Approx(8.0));
}

TEST_CASE("statements are ordered by dependency, not position", "[lang]") {
    Evaluated e = eval_module("D = ‖q‖ - t_2\nq = (‖(p_1, p_3)‖ - t_1, p_2)\nwhere\np ∈ ℝ³\nt ∈ [0,2]x[0,2] default = (0.77, 0.6)\n",
                              {{"p", {2, 0, 0}}});
    INFO(e.diagnostics);
    REQUIRE(e.ok);
    CHECK(scalar_of(e, "D") == Approx(std::hypot(2 - 0.77, 0.0) - 0.6));
    CHECK(e.text["q"] == "(1.23, 0)");
}

TEST_CASE("vectors, norms, dot, cross, elementwise products", "[lang]") {
    Evaluated e = eval_module(
        "n = ‖v‖\nd = v⋅w\nc = v × w\nh = v∘w\ncat = (1, u, 4)\nab = |(-1, 2, -3)|\ns = 2v\nhalf = w/2\n"
        "where\nv ∈ ℝ³ default = (1, 2, 2)\nw ∈ ℝ³ default = (0, 1, 0)\nu ∈ ℝ² default = (2, 3)\n");
    INFO(e.diagnostics);
    REQUIRE(e.ok);
    CHECK(e.text["n"] == "3");
    CHECK(e.text["d"] == "2");
    CHECK(e.text["c"] == "(-2, 0, 1)");
    CHECK(e.text["h"] == "(0, 2, 0)");
    CHECK(e.text["cat"] == "(1, 2, 3, 4)");
    CHECK(e.text["ab"] == "(1, 2, 3)");
    CHECK(e.text["s"] == "(2, 4, 4)");
    CHECK(e.text["half"] == "(0, 0.5, 0)");
}

TEST_CASE("matrices: literals on one line or many, products, transpose, inverse, determinant", "[lang]") {
    Evaluated e = eval_module(
        "A = [1 2; 3 4]\nB = [2 0\n     0 2]\nP = A B\nv = A (1, 1)\nAt = Aᵀ\nAi = A⁻¹\ndt = |A|\ne = A_2,1\n"
        "s = xᵀx\nneg = [1 -2]\n"
        "where\nx ∈ ℝ³ default = (1, 2, 3)\n");
    INFO(e.diagnostics);
    REQUIRE(e.ok);
    CHECK(e.text["A"] == "[1 2; 3 4]");
    CHECK(e.text["B"] == "[2 0; 0 2]");
    CHECK(e.text["P"] == "[2 4; 6 8]");
    CHECK(e.text["v"] == "(3, 7)");
    CHECK(e.text["At"] == "[1 3; 2 4]");
    CHECK(e.outputs["Ai"].v[0] == Approx(-2.0));
    CHECK(e.outputs["Ai"].v[3] == Approx(-0.5));
    CHECK(e.text["dt"] == "-2");
    CHECK(e.text["e"] == "3");
    CHECK(e.text["s"] == "14");
    CHECK(e.text["neg"] == "[1 -2]");  // `[1 -2]` is two entries
}

TEST_CASE("built-ins: min and max are n-ary and broadcast, floor, sqrt, imports", "[lang]") {
    Evaluated e = eval_module(
        "sin, cos from trigonometry\na = min(3, 1, 2)\nb = max(0, (-1, 2, -3))\nc = ⌊2.5⌋ + ⌈0.2⌉\nr = √9\n"
        "s = sin(π/2) + cos(0)\nl = ln(1) + exp(0)\n");
    INFO(e.diagnostics);
    REQUIRE(e.ok);
    CHECK(e.text["a"] == "1");
    CHECK(e.text["b"] == "(0, 2, 0)");
    CHECK(e.text["c"] == "3");
    CHECK(e.text["r"] == "3");
    CHECK(scalar_of(e, "s") == Approx(2.0));
    CHECK(e.text["l"] == "1");
}

TEST_CASE("local functions, piecewise definitions and the bare expression", "[lang]") {
    Evaluated e = eval_module(
        "f(x) = x² where x ∈ ℝ\ng(x) = { x if x > 0\n        -x otherwise\n"
        "y = f(3) + g(-2) + g(5)\nf(a) + 1\nwhere\nx ∈ ℝ\na ∈ ℝ default = 4\n");
    INFO(e.diagnostics);
    REQUIRE(e.ok);
    CHECK(e.text["y"] == "16");
    CHECK(e.text["ret"] == "17");
}

TEST_CASE("local functions may use module values", "[lang]") {
    Evaluated e = eval_module("y = f(2)\nf(x) = k x where x ∈ ℝ\nk = 3s\nwhere\ns ∈ ℝ default = 2\n");
    INFO(e.diagnostics);
    REQUIRE(e.ok);
    CHECK(e.text["y"] == "12");
}

TEST_CASE("bounded parameters: defaults, midpoints, vector bounds", "[lang]") {
    SourceManager sm;
    Diagnostics d(sm);
    std::string src = "y = a + b_1\nwhere\na ∈ [0,4]: a slider\nb ∈ [0,1]x[2,4]×[-1,1] default = (0.5, 3, 0)\nc ∈ ℝ\n";
    FileId f = sm.add("t.iql", src);
    ast::Module m = parse_module(sm, f, {{0, uint32_t(src.size())}}, "t", {}, d);
    auto cm = check_module(std::move(m), nullptr, {}, d);
    INFO(d.render());
    REQUIRE(!d.has_errors());
    REQUIRE(cm->params.size() == 3);
    CHECK(cm->params[0].value == std::vector<double>{2.0});  // midpoint
    CHECK(cm->params[0].description == "a slider");
    CHECK(cm->params[1].type == Type::vector(3));
    CHECK(cm->params[1].lo == std::vector<double>{0, 2, -1});
    CHECK(cm->params[1].value == std::vector<double>{0.5, 3, 0});
    CHECK(cm->params[2].value == std::vector<double>{0.0});  // unbounded: 0
}

TEST_CASE("sums run over the size of what their index subscripts", "[lang]") {
    Evaluated e = eval_module("s = ∑_i v_i w_i\nn = ∑_i v_i² + 1\ntr = ∑_i A_i,i\nall = ∑_i ∑_j A_i,j\n"
                              "where\nv ∈ ℝ³ default = (1, 2, 3)\nw ∈ ℝ³ default = (4, 5, 6)\nA ∈ ℝ^(2×2)\n",
                              {{"A", {1, 2, 3, 4}}});
    INFO(e.diagnostics);
    REQUIRE(e.ok);
    CHECK(e.text["s"] == "32");
    CHECK(e.text["n"] == "15");  // (∑ v_i²) + 1
    CHECK(e.text["tr"] == "5");
    CHECK(e.text["all"] == "10");
    Evaluated bad = eval_module("s = ∑_i v_i w_i\nwhere\nv ∈ ℝ³\nw ∈ ℝ²\n");
    CHECK_FALSE(bad.ok);
    CHECK_THAT(bad.diagnostics, Catch::Contains("test.iql:1:15: error: ∑_i runs over 2 here but over 3 elsewhere in the sum"));
}

TEST_CASE("block matrices size 0, 1 and I from their neighbours", "[lang]") {
    Evaluated e = eval_module("M = [R 0; 0 1]\nH = [I v; 0 1]\nC = [v w]\nZ = [0 v]\n"
                              "where\nv ∈ ℝ³ default = (1, 2, 3)\nw ∈ ℝ³ default = (4, 5, 6)\nR ∈ ℝ^(2×2)\n",
                              {{"R", {1, 2, 3, 4}}});
    INFO(e.diagnostics);
    REQUIRE(e.ok);
    CHECK(e.text["M"] == "[1 2 0; 3 4 0; 0 0 1]");
    CHECK(e.text["H"] == "[1 0 0 1; 0 1 0 2; 0 0 1 3; 0 0 0 1]");
    CHECK(e.text["C"] == "[1 4; 2 5; 3 6]");
    CHECK(e.text["Z"] == "[0 1; 0 2; 0 3]");
    Evaluated bad = eval_module("M = [R v]\nwhere\nv ∈ ℝ³\nR ∈ ℝ^(2×2)\n");
    CHECK_FALSE(bad.ok);
    CHECK_THAT(bad.diagnostics, Catch::Contains("test.iql:1:8: error: this block has 3 rows but the blocks beside it have 2"));
}

TEST_CASE("the reserved inputs time and mouse", "[lang]") {
    Evaluated e = eval_module("y = 2time + mouse_1\n");
    INFO(e.diagnostics);
    REQUIRE(e.ok);
    CHECK(e.text["y"] == "0");
    // A declaration of the same name wins.
    Evaluated d = eval_module("y = time\nwhere\ntime ∈ ℝ default = 3\n");
    REQUIRE(d.ok);
    CHECK(d.text["y"] == "3");
}

TEST_CASE("recurrences: sequences defined by a first element and a step, run as one loop", "[lang]") {
    Evaluated e = eval_module("z_1 = 1\nz_(k+1) = 2z_k + k for k ∈ 1..4\ns_1 = (0, 0)\ns_(k+1) = s_k + (1, z_k) for k ∈ 1..4\n"
                              "w = z_5 + c\nwhere\nc ∈ ℝ default = 100\n");
    INFO(e.diagnostics);
    REQUIRE(e.ok);
    CHECK(e.text["z_5"] == "42");
    CHECK(e.text["s_5"] == "(4, 31)");  // s uses z_k before z steps
    CHECK(e.text["w"] == "142");
    // Value times a parenthesised list: s(1, 1, 1) is s·(1, 1, 1).
    Evaluated f = eval_module("q_1 = p\nq_(k+1) = (|q_k_1|, |q_k_2|, |q_k_3|) - s(1, 1, 1)/k for k ∈ 1..3\nD = ‖q_4‖\n"
                              "where\np ∈ ℝ³ default = (0.5, 0.2, 0.1)\ns ∈ ℝ default = 0.4\n");
    INFO(f.diagnostics);
    REQUIRE(f.ok);
    CHECK(f.outputs["q_4"].v[0] == Approx(-0.1 / 3));
    CHECK(f.outputs["q_4"].v[1] == Approx(-0.4 / 3));
}

TEST_CASE("recurrence errors", "[lang]") {
    auto err = [](const std::string& src) {
        Evaluated e = eval_module(src);
        REQUIRE_FALSE(e.ok);
        return e.diagnostics;
    };
    CHECK_THAT(err("z_(k+1) = z_k + 1 for k ∈ 1..3\ny = z_4\n"),
               Catch::Contains("test.iql:1:1: error: the sequence 'z' has no first element: add 'z_1 = …'"));
    CHECK_THAT(err("z_1 = 0\nz_(k+1) = z_k + 1 for k ∈ 1..3\ny = z_3\n"),
               Catch::Contains("test.iql:3:7: error: only the first and the last elements of 'z' exist outside its recurrence: z_1 and z_4"));
    CHECK_THAT(err("z_1 = 0\nz_(k+1) = z_4 + 1 for k ∈ 1..3\ny = z_4\n"),
               Catch::Contains("test.iql:2:13: error: z_4 is the result of this recurrence and cannot be used inside it"));
    CHECK_THAT(err("z_1 = 0\nz_(k+2) = z_k for k ∈ 1..3\ny = z_4\n"),
               Catch::Contains("test.iql:2:3: error: a recurrence defines the next element: write z_(k+1) = … for k ∈ …"));
    CHECK_THAT(err("z_1 = 0\nz_(k+1) = (z_k, 1) for k ∈ 1..3\ny = z_4\n"),
               Catch::Contains("test.iql:2:11: error: the recurrence gives ℝ² but 'z' starts as ℝ"));
    CHECK_THAT(err("z_1 = 0\nz_(k+1) = z_k for k ∈ 3..1\ny = z_4\n"), Catch::Contains("error: the range 3..1 is empty"));
}

TEST_CASE("a recurrence whose step is a piecewise definition over two lines", "[lang]") {
    Evaluated e = eval_module("g(x, y) = x y_1 where x ∈ ℝ, y ∈ ℝ³\nq = g(2, (3, 4, 5))\nz_1 = c\n"
                              "z_(k+1) = { z_k if ‖z_k‖ > 2\n    z_k∘z_k + c otherwise for k ∈ 1..5\nw = z_6\n"
                              "where\nc ∈ ℝ² default = (0.5, 0.5)\n");
    INFO(e.diagnostics);
    REQUIRE(e.ok);
    CHECK(e.text["q"] == "6");
    CHECK(e.text["w"] == "(1.62890625, 1.62890625)");  // escaped after three steps, then held
}

TEST_CASE("a function parameter's given module must define the function", "[lang]") {
    SourceManager sm;
    Diagnostics d(sm);
    std::string src = "y = f(1)\nwhere\nf: ℝ → ℝ\n", given = "g(t) = t\n";
    FileId f = sm.add("m.iql", src), gf = sm.add("given", given);
    ModuleLibrary lib(sm, d, {});
    auto def = lib.parse_function({"value", gf, {{0, uint32_t(given.size())}}, {gf, 0, 1}, "value"});
    auto m = lib.parse_check({"m", f, {{0, uint32_t(src.size())}}, {f, 0, 1}, "test"}, "m", false, {}, {{"f", def}});
    CHECK_FALSE(m->ok);
    CHECK(d.render() == "m.iql:3:1: error: the value given for the function 'f' must define it: f(x) = …\n"
                        "  f: ℝ → ℝ\n  ^\n");
}
