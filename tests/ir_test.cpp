// IR units: the printed form, the verifier, the evaluator's matrix helpers.
#include <catch2/catch.hpp>

#include "TestUtil.h"
#include "ir/Eval.h"
#include "ir/IR.h"
#include "ir/Parse.h"

using namespace iqc;
using namespace iqc::ir;

TEST_CASE("IR prints in a stable text form", "[ir]") {
    Module m;
    Function f;
    f.name = "len";
    f.params.push_back({"v", Type::vector(3)});
    Instr p;
    p.op = Op::Param;
    p.type = Type::vector(3);
    p.name = "v";
    ValueId v = f.add(p);
    Instr l;
    l.op = Op::Builtin;
    l.type = Type::scalar();
    l.aux = *find_builtin("length");
    l.args = {v};
    l.name = "n";
    f.result = f.add(l);
    f.outputs.push_back({"n", f.result});
    m.functions.push_back(f);
    CHECK(print(m) ==
          "function len(v: ℝ³) -> ℝ {\n"
          "  %0 = ℝ³ Param #0 v  ; v\n"
          "  %1 = ℝ Builtin length %0  ; n\n"
          "  return %1\n"
          "  output n = %1\n"
          "}\n");
    CHECK(verify(m.functions[0], m) == "");
    CHECK(format_value(evaluate(m, 0, {{Type::vector(3), {2, 3, 6}}})) == "7");
}

TEST_CASE("the verifier rejects ill-typed and out-of-order IR", "[ir]") {
    Module m;
    Function f;
    f.name = "bad";
    ValueId a = f.constant(Type::vector(3), {1, 2, 3});
    ValueId b = f.constant(Type::vector(2), {1, 2});
    Instr add;
    add.op = Op::Add;
    add.type = Type::vector(3);
    add.args = {a, b};
    f.result = f.add(add);
    m.functions.push_back(f);
    CHECK_THAT(verify(m.functions[0], m), Catch::Contains("does not match operands"));
    m.functions[0].body[2].args = {a, 5};
    CHECK_THAT(verify(m.functions[0], m), Catch::Contains("not defined before use"));
}

TEST_CASE("evaluator: inverse and determinant, singular matrices", "[ir]") {
    bool singular = true;
    std::vector<double> a = {2, 0, 0, 1, 0, 3, 0, 2, 0, 0, 4, 3, 0, 0, 0, 1};
    std::vector<double> inv = mat_inverse(a, 4, &singular);
    CHECK_FALSE(singular);
    // a · a⁻¹ = I
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) {
            double s = 0;
            for (int k = 0; k < 4; ++k) s += a[size_t(i * 4 + k)] * inv[size_t(k * 4 + j)];
            CHECK(s == Approx(i == j ? 1.0 : 0.0).margin(1e-12));
        }
    CHECK(mat_det(a, 4) == Approx(24.0));
    mat_inverse({1, 2, 2, 4}, 2, &singular);
    CHECK(singular);
}

TEST_CASE("evaluator: prepared globals are computed at their first read, again after set_global", "[ir]") {
    // The Lipschitz pass makes an evaluator per instance and calls only the shape's own function, which reads
    // no prepared global: preparing every moving instance's transform in each evaluator made n moving
    // instances n² work (2,000 moving spheres with `bound`: 88 s). An iqc_prepare that exceeds the budget
    // shows whether it ran: a function that reads no prepared global must not start it.
    const std::string text =
        "global @0 scale: ℝ prepared\n"
        "global @1 k: ℝ parameter = 2\n"
        "function iqc_prepare() -> ℝ {\n"
        "  %0 = ℝ Global @1 k\n"
        "  %1 = ℝ Mul %0, %0\n"
        "  %2 = ℝ Mul %1, %0\n"
        "  %3 = ℝ Mul %2, %0\n"
        "  %4 = ℝ Mul %3, %0\n"
        "  %5 = ℝ Mul %4, %0\n"
        "  %6 = ℝ Mul %5, %0\n"
        "  %7 = ℝ Mul %6, %0\n"
        "  return %7\n"
        "  output scale = %7\n"
        "}\n"
        "entry function shape(q: ℝ) -> ℝ {\n"
        "  %0 = ℝ Param #0 q  ; q\n"
        "  %1 = ℝ Const 1\n"
        "  %2 = ℝ Sub %0, %1\n"
        "  return %2\n"
        "}\n"
        "entry function scene(q: ℝ) -> ℝ {\n"
        "  %0 = ℝ Param #0 q  ; q\n"
        "  %1 = ℝ Global @0 scale\n"
        "  %2 = ℝ Mul %0, %1\n"
        "  return %2\n"
        "}\n";
    Module m;
    std::string error;
    REQUIRE(parse_module(text, m, error));
    REQUIRE(verify(m).empty());
    int shape = m.find("shape"), scene = m.find("scene");
    Value q{Type::scalar(), {3}};
    {
        EvalInputs tight;
        tight.max_steps = 12;  // the shape's 4 instructions fit (8 steps); iqc_prepare's 8 (16) do not
        Evaluator ev(m, tight);
        CHECK(ev.call(shape, {q}).v == std::vector<double>{2});
        CHECK_THROWS_AS(ev.call(scene, {q}), EvalLimit);
    }
    Evaluator ev(m);
    CHECK(ev.call(scene, {q}).v == std::vector<double>{3 * 256});  // k⁸ = 256
    ev.set_global(1, {3});
    CHECK(ev.call(scene, {q}).v == std::vector<double>{3 * 6561});  // 3⁸
    CHECK(ev.call(shape, {q}).v == std::vector<double>{2});
}
