// `iqc eval`: outputs in source order at full precision, --set with the language's literals, errors.
#include <catch2/catch.hpp>
#include <cmath>
#include <fmt/format.h>

#include "TestUtil.h"

using namespace iqc::test;

static const char* kTorus =
    "shape\nD = ‖q‖ - t_2\nq = (‖(p_1, p_3)‖ - t_1, p_2)\nwhere\np ∈ ℝ³\nt ∈ [0,2]x[0,2] default = (0.77, 0.6)\n";

TEST_CASE("eval prints every output in source order", "[eval]") {
    auto f = write_temp("torus.iql", kTorus);
    RunResult r = run_iqc("eval " + f.string() + " --set 'p=(2,0,0)'");
    INFO(r.err);
    CHECK(r.exit_code == 0);
    CHECK(r.out == "D = 0.63\nq = (1.23, 0)\n");
    RunResult t = run_iqc("eval " + f.string() + " --set 'p=(0, 1, 0)' --set 't=(1, 0.25)'");
    CHECK(t.out == "D = 1.1642135623730951\nq = (-1, 1)\n");
}

TEST_CASE("eval takes matrices, expressions and backticked names", "[eval]") {
    auto f = write_temp("mat.iql", "y = A v\nz = `k_d` + 1\nwhere\nA ∈ ℝ^(2×2)\nv ∈ ℝ²\n`k_d` ∈ ℝ\n");
    RunResult r = run_iqc("eval " + f.string() + " --set 'A=[1 2; 3 4]' --set 'v=(1, -1)' --set '`k_d`=π/2'");
    INFO(r.err);
    CHECK(r.exit_code == 0);
    CHECK(r.out == "y = (-1, -1)\nz = 2.5707963267948966\n");
}

TEST_CASE("a backticked name with a subscript is that name subscripted, where the joined name is declared too", "[eval]") {
    // A trial: with the sequence `ab`_i and the parameter `ab_2` both declared, `ab`_2 read ab_2 (10), not element 2
    // of ab (2): the backticks say where the name ends. Without a sequence `ab`, `ab`_2 still names ab_2.
    auto both = write_temp("backtick_sub.iql", "y = `ab`_2 + `ab_2`\nwhere\n`ab`_i ∈ ℝ default = {1, 2, 3}\n`ab_2` ∈ ℝ default = 10\n");
    RunResult r = run_iqc("eval " + both.string());
    INFO(r.err);
    CHECK(r.out == "y = 12\n");
    auto only = write_temp("backtick_sub2.iql", "y = `ab`_2\nwhere\n`ab_2` ∈ ℝ default = 10\n");
    CHECK(run_iqc("eval " + only.string()).out == "y = 10\n");
}

TEST_CASE("eval picks a module of a document and prints the bare expression as ret", "[eval]") {
    auto f = write_temp("lib.iql", "sin from trigonometry\nsin(x) + 1\nwhere\nx ∈ ℝ\n");
    RunResult r = run_iqc("eval " + f.string() + " --set x=0");
    CHECK(r.out == "ret = 1\n");
    auto doc = std::filesystem::path(IQC_SOURCE_DIR) / "examples" / "two_tori.md";
    RunResult d = run_iqc("eval " + doc.string() + " --module torus --set 'p=(2,0,0)'");
    CHECK(d.out == "D = 0.63\nq = (1.23, 0)\n");
    RunResult many = run_iqc("eval " + doc.string());
    CHECK(many.exit_code == 1);
    CHECK_THAT(many.err, Catch::Contains("defines 3 modules: choose one with --module (toon, phong, torus)"));
    // A scene of standard-library shapes defines none: located, naming them and --module.
    auto scene = write_temp("stdlib_only.iq", "title = \"t\"\n[[shapes]]\ntype = \"torus\"\n[[shapes]]\ntype = \"box\"\n");
    RunResult none = run_iqc("eval " + scene.string());
    CHECK(none.exit_code == 1);
    CHECK_THAT(none.err, Catch::Contains("stdlib_only.iq:1:1: error: '" + scene.string() + "' defines no modules: its shapes (box, "
                                         "torus) come from the standard library; choose one with --module NAME"));
    RunResult picked = run_iqc("eval " + scene.string() + " --module torus --set 'p=(1.2,0,0)'");
    CHECK(picked.exit_code == 0);
}

TEST_CASE("eval errors: unknown parameter, wrong size, bad value, invalid module", "[eval]") {
    auto f = write_temp("torus2.iql", kTorus);
    RunResult a = run_iqc("eval " + f.string() + " --set 'pp=(1,2,3)'");
    CHECK(a.exit_code == 1);
    CHECK_THAT(a.err, Catch::Contains("--set pp:1:1: error: the module has no parameter 'pp' (its parameters: p, t)\n  (1,2,3)\n  ^~~~~~~"));
    RunResult b = run_iqc("eval " + f.string() + " --set 'p=(1,2)'");
    CHECK(b.exit_code == 1);
    CHECK_THAT(b.err, Catch::Contains("--set p:1:1: error: 'p' is ℝ³, but the value is ℝ²\n  (1,2)\n  ^~~~~"));
    RunResult c = run_iqc("eval " + f.string() + " --set 'p=(1,,2)'");
    CHECK(c.exit_code == 1);
    CHECK_THAT(c.err, Catch::Contains("--set p:1:4: error: expected an expression, found ','"));
    // A value and then more (a trial's `p=(1,2,3);t=2`): an error at the extra statement, not silently dropped.
    RunResult more = run_iqc("eval " + f.string() + " --set 'p=(1,2,3);t=(1,2)'");
    CHECK(more.exit_code == 1);
    CHECK_THAT(more.err, Catch::Contains("--set p:1:9: error: the value of '--set p' must be one expression; this is more"));
    CHECK_THAT(more.err, Catch::Contains("  (1,2,3);t=(1,2)\n          ^"));
    // A declaration as the value (a trial's `r=x ∈ ℝ` crashed: no statement at all): a located error.
    for (const char* decl : {"p=x ∈ ℝ", "p=x, y ∈ ℝ", "p=v ∈ ℝ³ default = (1, 2, 3)"}) {
        RunResult d = run_iqc("eval " + f.string() + " --set '" + decl + "'");
        INFO(decl << "\n" << d.err);
        CHECK(d.exit_code == 1);
        CHECK_THAT(d.err, Catch::Contains("--set p:1:1: error: the value of '--set p' must be an expression"));
        CHECK_THAT(d.err, Catch::Contains("not a declaration"));
    }
    RunResult u = run_iqc("eval " + f.string() + " --set novalue");
    CHECK(u.exit_code == 2);
    auto bad = write_temp("bad.iql", "y = x +\n");
    RunResult e = run_iqc("eval " + bad.string());
    CHECK(e.exit_code == 1);
    CHECK_THAT(e.err, Catch::Contains("bad.iql:1:8: error: expected an expression, found the end of the line"));
}

TEST_CASE("eval binds symbolic sizes from --set values and checks integers", "[eval]") {
    auto f = write_temp("sym.iql", "y = ‖v‖ + f(w)\nf(x) = ∑_i x_i where x ∈ ℝ^m\nwhere\nv ∈ ℝ^n\nw ∈ ℝ^n\n");
    RunResult r = run_iqc("eval " + f.string() + " --set 'v=(3, 4)' --set 'w=(1, 2)'");
    INFO(r.err);
    CHECK(r.out == "y = 8\n");
    RunResult bad = run_iqc("eval " + f.string() + " --set 'v=(3, 4)' --set 'w=(1, 2, 3)'");
    CHECK(bad.exit_code == 1);
    CHECK_THAT(bad.err, Catch::Contains("sym.iql:5:1: error: the size n is 3 for 'w' but 2 elsewhere"));
    RunResult unknown = run_iqc("eval " + f.string());
    CHECK(unknown.exit_code == 1);
    CHECK_THAT(unknown.err, Catch::Contains("sym.iql:4:5: error: the size n of 'v' is not known"));
    auto g = write_temp("int.iql", "x_1 = 0\nx_(i+1) = x_i + i for i ∈ 1..N\ny = x_(N+1)\nwhere\nN ∈ ℤ\n");
    CHECK(run_iqc("eval " + g.string() + " --set N=4").out == "x_(N+1) = 10\ny = 10\n");
    RunResult frac = run_iqc("eval " + g.string() + " --set N=2.5");
    CHECK(frac.exit_code == 1);
    CHECK_THAT(frac.err, Catch::Contains("--set N:1:1: error: 'N' is ℤ, but the value 2.5 is not a whole number"));
}

TEST_CASE("eval: sequences and function parameters from --set, and their errors", "[eval]") {
    auto seq = write_temp("seq.iql", "s = ∑_i x_i\nf = x_2\nwhere\nx_i ∈ ℝ²\n");
    RunResult a = run_iqc("eval " + seq.string() + " --set 'x={(1, 2), (3, 4), (5, 6)}'");
    INFO(a.err);
    CHECK(a.exit_code == 0);
    CHECK(a.out == "s = (9, 12)\nf = (3, 4)\n");
    RunResult wrong = run_iqc("eval " + seq.string() + " --set 'x={1, 2}'");
    CHECK(wrong.exit_code == 1);
    CHECK_THAT(wrong.err, Catch::Contains("--set x:1:1: error: 'x' is ℝ²[2], but the value is ℝ[2]"));
    // A sequence whose default is too large for iqc's sizes.
    std::string zeros = "(0";
    for (int i = 1; i < 4096; ++i) zeros += ", 0";
    zeros += ")";
    auto big = write_temp("big.iql", "y = x_1_1\nwhere\nx_i ∈ ℝ^4096 default = {" + zeros + ", " + zeros + "}\n");
    RunResult b = run_iqc("eval " + big.string());
    CHECK(b.exit_code == 1);
    CHECK_THAT(b.err, Catch::Contains("big.iql:3:1: error: the sequence 'x' would have 8192 components: iqc allows at most 4096"));
    // f(x)=… defines a function parameter; its arity and result type are checked where it is written.
    auto fn = write_temp("fn.iql", "y = f(x, v)\nwhere\nf: ℝ, ℝ² → ℝ²\nx ∈ ℝ\nv ∈ ℝ²\n");
    RunResult ok = run_iqc("eval " + fn.string() + " --set 'f(s, w)=s w' --set x=3 --set 'v=(1, 2)'");
    INFO(ok.err);
    CHECK(ok.out == "y = (3, 6)\n");
    RunResult arity = run_iqc("eval " + fn.string() + " --set 'f(s)=s' --set x=3 --set 'v=(1, 2)'");
    CHECK(arity.exit_code == 1);
    CHECK_THAT(arity.err, Catch::Contains("--set f(s):1:1: error: 'f' takes 2 arguments (its declaration: ℝ, ℝ² → ℝ²), but "
                                          "the definition has 1"));
    RunResult result = run_iqc("eval " + fn.string() + " --set 'f(s, w)=s' --set x=3 --set 'v=(1, 2)'");
    CHECK(result.exit_code == 1);
    CHECK_THAT(result.err, Catch::Contains("--set f(s, w):1:11: error: 'f' is declared to give ℝ², but its definition gives ℝ"));
    RunResult not_def = run_iqc("eval " + fn.string() + " --set 'f(s, w)' --set x=3 --set 'v=(1, 2)'");
    CHECK(not_def.exit_code == 2);  // NAME=VALUE is a usage error
    RunResult broken = run_iqc("eval " + fn.string() + " --set 'f(s, w)=)' --set x=3 --set 'v=(1, 2)'");
    CHECK(broken.exit_code == 1);
    CHECK_THAT(broken.err, Catch::Contains("--set f(s, w):1:11: error: expected an expression, found ')'"));
}

TEST_CASE("defaults and bounds may be any constant expression, evaluated by the evaluator", "[eval]") {
    auto f = write_temp("defaults.iql", "y = r + s\nwhere\nr ∈ [0, 2] default = √2\ns ∈ [0, sin(π/2)] default = cos(π/3)\n");
    RunResult r = run_iqc("eval " + f.string());
    INFO(r.err);
    CHECK(r.exit_code == 0);
    auto value = [](const std::string& out) { return out.rfind("y = ", 0) == 0 ? std::stod(out.substr(4)) : NAN; };
    CHECK(value(r.out) == Approx(std::sqrt(2.0) + 0.5).epsilon(1e-15));
    RunResult s = run_iqc("eval " + f.string() + " --set 'r=√3/2'");
    CHECK(value(s.out) == Approx(std::sqrt(3.0) / 2 + 0.5).epsilon(1e-15));
    auto bad = write_temp("bad_default.iql", "y = r\nwhere\nr ∈ [0, 2] default = q + 1\n");
    RunResult b = run_iqc("eval " + bad.string());
    CHECK(b.exit_code == 1);
    CHECK_THAT(b.err, Catch::Contains("bad_default.iql:3:22: error: a default must be a constant (numbers, π, and arithmetic and "
                                      "functions of them, such as √2 or sin(π/8))\n  r ∈ [0, 2] default = q + 1\n"
                                      "                       ^~~~~"));
    // Bounds are checked in the shader's 32-bit floats: 0.1 + 0.2 (0.30000000000000004 in doubles) is within
    // [0, 0.3], 0.30001 is not (a second trial of this stop's fixes).
    RunResult sum = run_iqc("eval " + write_temp("float_bound.iql", "y = r\nwhere\nr ∈ [0, 0.3] default = 0.1 + 0.2\n").string());
    CHECK(sum.exit_code == 0);
    RunResult past_float = run_iqc("eval " + write_temp("past_bound.iql", "y = r\nwhere\nr ∈ [0, 0.3] default = 0.30001\n").string());
    CHECK(past_float.exit_code == 1);
    CHECK_THAT(past_float.err, Catch::Contains("past_bound.iql:3:24: error: the default 0.30001 of 'r' is outside its bounds [0, 0.3]"));
    // A value past the sliders is evaluated and warned, as a scene's override is (it was silent).
    RunResult past = run_iqc("eval " + f.string() + " --set r=5");
    CHECK(past.exit_code == 0);
    CHECK(value(past.out) == Approx(5.5));
    CHECK_THAT(past.err, Catch::Contains("--set r:1:1: warning: the value 5 of 'r' is outside its slider bounds [0, 2]"));
    // time and the mouse are inputs, not constants: they were evaluated as 0 (a new user's trial).
    auto t = write_temp("time_default.iql", "y = r\nwhere\nr ∈ [0, 2] default = 1 + time\n");
    RunResult tr = run_iqc("eval " + t.string());
    CHECK(tr.exit_code == 1);
    CHECK_THAT(tr.err, Catch::Contains("time_default.iql:3:22: error: a default must be a constant"));
    auto m = write_temp("mouse_bound.iql", "y = r\nwhere\nr ∈ [0, mouse_1] default = 0\n");
    RunResult mr = run_iqc("eval " + m.string());
    CHECK(mr.exit_code == 1);
    CHECK_THAT(mr.err, Catch::Contains("mouse_bound.iql:3:9: error: an interval bound must be a constant number"));
    RunResult sr = run_iqc("eval " + f.string() + " --set 'r=0.5 + time'");
    CHECK(sr.exit_code == 1);
    CHECK_THAT(sr.err, Catch::Contains("error: the value of '--set r' must be a constant: it reads time, which changes while the "
                                       "shader runs"));
    auto scene = write_temp("time_override.iq", "[[shapes]]\ntype = \"sphere\"\nshape_params = { r = \"0.5 + 0.1 sin(time)\" }\n");
    RunResult or_ = run_iqc(scene.string() + " -o -");
    CHECK(or_.exit_code == 1);
    CHECK_THAT(or_.err, Catch::Contains("time_override.iq:3:22: error: 'r' must be a number, an array, or a constant expression"));
    CHECK_THAT(or_.err, Catch::Contains("it reads time"));
}

TEST_CASE("eval means what the shader computes: guarded values, not NaN", "[eval]") {
    auto f = write_temp("acos.iql", "acos from trigonometry\ny = acos(x)\nwhere\nx ∈ [0, 2] default = 1.5\n");
    RunResult r = run_iqc("eval " + f.string());
    CHECK(r.exit_code == 0);
    CHECK(r.out == "y = 0\n");  // acos(clamp(1.5, -1, 1)), as the emitted GLSL
    CHECK_THAT(r.err, Catch::Contains("acos.iql:2:1: warning: acos of a value outside [-1, 1]: with the parameters' bounds it "
                                      "ranges over [0, 2]"));
    // ℤ arithmetic wraps as a shader's 32-bit int does (a trial: k·k at k = 100,000 was 10¹⁰ in eval, 1,410,065,408
    // in the shader: 10¹⁰ mod 2³²); −k is a real number (as in the shader: -float(k)), so it does not wrap.
    auto ints = write_temp("int_wrap.iql", "y = k k\nz = -k\nwhere\nk ∈ ℤ\n");
    RunResult w = run_iqc("eval " + ints.string() + " --set k=100000");
    INFO(w.err);
    CHECK(w.out == fmt::format("y = {}\nz = -100000\n", int64_t(10000000000LL % 4294967296LL)));
    CHECK(run_iqc("eval " + ints.string() + " --set k=-2147483648").out == "y = 0\nz = 2147483648\n");
}

TEST_CASE("a number outside float's range is one error: the declaration it is in stays declared", "[eval]") {
    // A trial: a default of 1e-46 was followed by "undefined name 'a'" at every use of a.
    for (const char* n : {"1e-46", "1e39"}) {
        INFO(n);
        auto f = write_temp("range_default.iql", std::string("y = 2a + 1\nwhere\na ∈ ℝ default = ") + n + "\n");
        RunResult r = run_iqc("eval " + f.string());
        CHECK(r.exit_code == 1);
        CHECK_THAT(r.err, Catch::Contains("range_default.iql:3:17: error: the number"));
        CHECK_THAT(r.err, !Catch::Contains("undefined name"));
        size_t errors = 0;
        for (size_t at = 0; (at = r.err.find("error:", at)) != std::string::npos; ++at) ++errors;
        CHECK(errors == 1);
    }
}

TEST_CASE("one range rule for numbers: a module's literal, a scene's number and a scene's string alike", "[eval]") {
    // A trial: 3.4028235e38 (FLT_MAX as printed, which rounds to it) was a number in a scene but an error as a
    // module's literal and as a scene string; 1e-50 was an error as a literal and as a string ("1e-50") but
    // silently 0 as a scene number. A value fits where it rounds to a finite float and is 0 or not below the
    // smallest normal float.
    auto lit = [](const char* v) {
        return run_iqc("eval " + write_temp("range_literal.iql", std::string("y = x + ") + v + "\nwhere\nx ∈ [0, " + v + "]\n").string() +
                       " --set x=0");
    };
    CHECK(lit("3.4028235e38").exit_code == 0);
    RunResult over = lit("3.5e38");
    CHECK(over.exit_code == 1);
    CHECK_THAT(over.err, Catch::Contains("range_literal.iql:1:9: error: the number 3.5e38 is outside the range of 32-bit floats"));
    auto scene = [](const std::string& v) {
        return run_iqc(write_temp("range_scene.iq", "[[shapes]]\ntype = \"sphere\"\nshape_params = { r = " + v + " }\n").string() +
                       " -o " + (temp_dir() / "range_scene.frag").string());
    };
    for (const char* v : {"3.4028235e38", "\"3.4028235e38\""}) {
        INFO(v);
        RunResult r = scene(v);
        CHECK(r.exit_code == 0);
        CHECK_THAT(r.err, Catch::Contains("outside its slider bounds"));  // (a warning: the slider goes to 3)
    }
    RunResult tiny = scene("1e-50"), tiny_string = scene("\"1e-50\"");
    CHECK(tiny.exit_code == 1);
    CHECK_THAT(tiny.err, Catch::Contains("range_scene.iq:3:22: error: 'r' is 1e-50, below the smallest normal 32-bit float"));
    CHECK(tiny_string.exit_code == 1);
    CHECK_THAT(tiny_string.err, Catch::Contains("range_scene.iq:3:22: error: 'r' must be a number, an array, or a constant expression"));
    CHECK_THAT(tiny_string.err, Catch::Contains("below the smallest normal 32-bit float"));
    RunResult huge = scene("3.5e38");
    CHECK(huge.exit_code == 1);
    CHECK_THAT(huge.err, Catch::Contains("range_scene.iq:3:22: error: 'r' must be a finite number within the range of 32-bit floats"));
}

TEST_CASE("a sum over a long sequence is a loop: its values are the sum's, conditions, indices, nesting and "
          "recurrences included",
          "[eval]") {
    // ∑ over 32 or more elements of a sequence lowers to a Loop (Mesa compiled an unrolled sum of 100 lengths of
    // uniform-array elements in 2.5 s, a loop in 0.17 s). The values: the sums computed here term by term.
    const int n = 40;
    std::string xs, ys;
    for (int k = 1; k <= n; ++k) {
        xs += fmt::format("{}{}", k > 1 ? ", " : "", k);
        ys += fmt::format("{}({}, {}, {})", k > 1 ? ", " : "", k, 2 * k, 3 * k);
    }
    auto f = write_temp("long_sums.iql", "a = ∑_i x_i\nb = ∑_i i x_i\nc = ∑_(i for x_i > 20) x_i\nd = ∑_i y_i,2\ne = ∑_i ∑_j y_i,j\n"
                                         "g = ∑_i ∑_k x_i x_k\nh = ∑_i f(x_i)\nu = ∑_i y_i\nz_1 = 0\nz_(k+1) = z_k + k ∑_i x_i for k ∈ 1..3\n"
                                         "where\nx_i ∈ ℝ default = {" + xs + "}\ny_i ∈ ℝ³ default = {" + ys + "}\nf(t) = t² where t ∈ ℝ\n");
    double a = 0, b = 0, c = 0, g = 0, h = 0;
    for (int k = 1; k <= n; ++k) {
        a += k, b += k * k, h += k * k;
        if (k > 20) c += k;
        for (int q = 1; q <= n; ++q) g += k * q;
    }
    RunResult r = run_iqc("eval " + f.string());
    INFO(r.err);
    REQUIRE(r.exit_code == 0);
    CHECK(r.out == fmt::format("a = {}\nb = {}\nc = {}\nd = {}\ne = {}\ng = {}\nh = {}\nu = ({}, {}, {})\nz_4 = {}\n", a, b, c, 2 * a,
                               6 * a, g, h, a, 2 * a, 3 * a, (1 + 2 + 3) * a));
    // Nested loops over two sequences of 500: 250,000 terms within eval's step limit (a new user's trial: reading a
    // captured array counted its 500 components every iteration, 250 million steps, and eval stopped).
    std::string ws, us;
    double sw = 0, su = 0;
    for (int k = 0; k < 500; ++k) {
        ws += fmt::format("{}{}", k ? ", " : "", k % 7 + 1);
        us += fmt::format("{}{}", k ? ", " : "", k % 5 + 1);
        sw += k % 7 + 1, su += k % 5 + 1;
    }
    auto nested = write_temp("nested_500.iql", "n = ∑_i ∑_j w_i u_j\nwhere\nw_i ∈ ℝ default = {" + ws + "}\nu_j ∈ ℝ default = {" + us + "}\n");
    RunResult nr = run_iqc("eval " + nested.string());
    INFO(nr.err);
    CHECK(nr.out == fmt::format("n = {}\n", sw * su));
    // ... and a loop in the IR and in the shader (a module shown alone on a uniform target).
    auto shape = write_temp("long_sum_shape.iql", "shape\nD = ‖p‖ - ∑_i ‖x_i‖/400\nwhere\np ∈ ℝ³\nx_i ∈ ℝ³ default = {" + ys + "}\n");
    RunResult s = run_iqc(shape.string() + " --target webgl2 --dump-ir=after-lower -o " + (temp_dir() / "long_sum.frag").string());
    INFO(s.err);
    REQUIRE(s.exit_code == 0);
    CHECK_THAT(s.err, Catch::Contains("Loop from 0 "));
    std::string code = read_text(temp_dir() / "long_sum.frag");
    CHECK_THAT(code, Catch::Contains("for (int "));
    CHECK_THAT(code, !Catch::Contains("x[39]"));
    // A sum inside a rolled sum's term that reads nothing of its index is computed once, before the loop (a trial:
    // ∑_i w_i x_i / ∑_j w_j over 100 points was 101 loops; its frame 33 s on webgl2), also where it reuses the
    // letter (∑_i w_i x_i / ∑_i w_i). Nested sums that read both indices are one loop (the inner sum unrolled
    // in it: llvmpipe's 65,535 loop iterations per invocation), the values as before.
    auto count_loops = [](const std::string& text) {
        size_t n = 0;
        for (size_t at = text.find("Loop from"); at != std::string::npos; at = text.find("Loop from", at + 1)) ++n;
        return n;
    };
    std::string weights;
    for (int k = 1; k <= n; ++k) weights += fmt::format("{}{}", k > 1 ? ", " : "", k);
    for (const char* c : {"c = ∑_i w_i y_i / ∑_j w_j", "c = ∑_i w_i y_i / ∑_i w_i"}) {
        INFO(c);
        auto centre = write_temp("centre.iql", std::string("shape\nD = ‖p - c‖ - 0.5\n") + c + "\nwhere\np ∈ ℝ³\ny_i ∈ ℝ³ default = {" + ys +
                                                   "}\nw_i ∈ ℝ default = {" + weights + "}\n");
        RunResult d = run_iqc(centre.string() + " --target webgl2 --dump-ir=after-lower -o /dev/null");
        REQUIRE(d.exit_code == 0);
        CHECK(count_loops(d.err) == 2);
        double sw = 0, sx = 0;
        for (int k = 1; k <= n; ++k) sw += k, sx += double(k) * k;
        RunResult v = run_iqc("eval " + centre.string() + " --set 'p=(0,0,0)'");
        size_t at = v.out.find("c = (");
        REQUIRE(at != std::string::npos);
        double c1 = 0, c2 = 0, c3 = 0;
        REQUIRE(std::sscanf(v.out.c_str() + at, "c = (%lf, %lf, %lf)", &c1, &c2, &c3) == 3);
        CHECK(c1 == Approx(sx / sw).epsilon(1e-12));
        CHECK(c2 == Approx(2 * sx / sw).epsilon(1e-12));
        CHECK(c3 == Approx(3 * sx / sw).epsilon(1e-12));
    }
    auto pairs = write_temp("pairs.iql", "shape\nD = ‖p‖ - 1 + s/1e9\ns = ∑_i ∑_j ‖y_i - y_j‖\nwhere\np ∈ ℝ³\ny_i ∈ ℝ³ default = {" + ys + "}\n");
    RunResult pd = run_iqc(pairs.string() + " --target webgl2 --dump-ir=after-lower -o /dev/null");
    REQUIRE(pd.exit_code == 0);
    CHECK(count_loops(pd.err) == 1);
    double pair_sum = 0;
    for (int a = 1; a <= n; ++a)
        for (int b = 1; b <= n; ++b) pair_sum += std::abs(a - b) * std::sqrt(14.0);
    // A sum over a sequence the module computes element-wise is a loop whose term reads the element's expression
    // with the loop's index (a loop over the array built where y is defined kept it built whole per evaluation:
    // 12 s a frame on webgl2, a trial; then it stayed unrolled), also where the definition uses another letter and
    // where the term reads a component of the element.
    double elem_sum = 0, second = 0;
    for (int k = 1; k <= n; ++k) {
        elem_sum += std::sqrt(std::pow(2.0 * k + 1, 2) + std::pow(4.0 * k, 2) + std::pow(6.0 * k, 2));
        second += 4.0 * k;
    }
    for (const char* def : {"y_i = 2x_i + (1, 0, 0)", "y_j = 2x_j + (1, 0, 0)"}) {
        INFO(def);
        auto elem = write_temp("elementwise.iql", std::string("shape\nD = ‖p‖ - 1 + s/1e9 + t/1e9\n") + def +
                                                      "\ns = ∑_i ‖y_i‖\nt = ∑_i y_i,2\nwhere\np ∈ ℝ³\nx_i ∈ ℝ³ default = {" + ys + "}\n");
        RunResult ed = run_iqc(elem.string() + " --target webgl2 --dump-ir=after-lower -o " + (temp_dir() / "elem.frag").string());
        REQUIRE(ed.exit_code == 0);
        CHECK(count_loops(ed.err) == 2);
        CHECK_THAT(read_text(temp_dir() / "elem.frag"), !Catch::Contains("vec3[" + std::to_string(n) + "]("));  // no array built
        RunResult ev = run_iqc("eval " + elem.string() + " --set 'p=(0,0,0)'");
        INFO(ev.out);
        REQUIRE(ev.out.find("s = ") != std::string::npos);
        CHECK(std::stod(ev.out.substr(ev.out.find("s = ") + 4)) == Approx(elem_sum).epsilon(1e-12));
        REQUIRE(ev.out.find("t = ") != std::string::npos);
        CHECK(std::stod(ev.out.substr(ev.out.find("t = ") + 4)) == Approx(second).epsilon(1e-12));
    }
    // Inside a recurrence, a sum over such a sequence: the recurrence captured the whole array to learn the sum's
    // range, and then had no derivative (a trial: "cannot differentiate it"); the range comes from the definition.
    {
        std::string pts;
        for (int k = 1; k <= 40; ++k) pts += fmt::format("{}({}, 0, 0)", k > 1 ? ", " : "", 0.01 * k);
        auto rec = write_temp("elem_rec.iql", "shape\ny_i = x_i - p\ns_1 = 0\ns_(k+1) = s_k + ∑_i exp(-k‖y_i‖²) / 40   for k ∈ 1..3\n"
                                              "D = ‖p‖ - 0.5 - 0.1 s_4\nwhere\np ∈ ℝ³\nx_i ∈ ℝ³ default = {" + pts + "}\n");
        for (const char* target : {"webgl2", "shadertoy"}) {
            INFO(target);
            RunResult c = run_iqc(rec.string() + " --target " + target + " -o /dev/null");
            REQUIRE(c.exit_code == 0);
            CHECK_THAT(c.err, !Catch::Contains("cannot differentiate"));
        }
    }
    // An element-wise definition of numbers (u_i = w_i²) is a vector, and GLSL has none past 4 components: a sum over
    // it read the vector (a trial: "ℝ⁴⁰ is larger than GLSL's largest vector", exit 1, where eval ran); each term
    // reads its element's expression now, rolled (40) or unrolled (10).
    for (int count : {10, 40}) {
        std::string ws;
        double squares = 0;
        for (int k = 1; k <= count; ++k) ws += fmt::format("{}{}", k > 1 ? ", " : "", 0.1 * k), squares += 0.01 * k * k;
        auto scalar = write_temp("elem_scalar.iql", "shape\nu_i = w_i²\ns = ∑_i u_i\nD = ‖p‖ - 0.01s\nwhere\np ∈ ℝ³\n"
                                                    "w_i ∈ ℝ default = {" + ws + "}\n");
        for (const char* target : {"webgl2", "shadertoy"}) {
            INFO(count << " " << target);
            RunResult c = run_iqc(scalar.string() + " --target " + target + " -o /dev/null");
            INFO(c.err);
            CHECK(c.exit_code == 0);
        }
        RunResult v = run_iqc("eval " + scalar.string() + " --set 'p=(0,0,0)'");
        REQUIRE(v.out.find("s = ") != std::string::npos);
        CHECK(std::stod(v.out.substr(v.out.find("s = ") + 4)) == Approx(squares).epsilon(1e-12));
    }
    // An element-wise sequence that reads p (y_i = x_i - p): its rolled sum is a loop on every target, and the
    // Lipschitz pass's derivative takes each element's own (a trial: the array's derivative was a 3×3 matrix of
    // 96 rows, a heap overflow when folded: exit 134 on webgl2). Unrolled (31) and rolled (40) alike.
    for (int count : {31, 40}) {
        std::string pts;
        for (int k = 1; k <= count; ++k) pts += fmt::format("{}({}, 0, 0)", k > 1 ? ", " : "", 0.01 * k);
        auto moving = write_temp("elem_p.iql", "shape\ny_i = x_i - p\nD = ∑_i ‖y_i‖/" + std::to_string(count) + " - 1\nwhere\np ∈ ℝ³\n"
                                               "x_i ∈ ℝ³ default = {" + pts + "}\n");
        for (const char* target : {"webgl2", "shadertoy"}) {
            INFO(count << " " << target);
            RunResult c = run_iqc(moving.string() + " --target " + target + " --dump-ir -o /dev/null");
            REQUIRE(c.exit_code == 0);
            CHECK_THAT(c.err, Catch::Contains("K ≤ 1 derived"));
        }
    }
    RunResult pv = run_iqc("eval " + pairs.string() + " --set 'p=(0,0,0)'");
    INFO(pv.out);
    REQUIRE(pv.out.find("s = ") != std::string::npos);
    CHECK(std::abs(std::stod(pv.out.substr(pv.out.find("s = ") + 4)) - pair_sum) < 1e-9 * pair_sum);
}
