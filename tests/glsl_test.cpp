// GLSL backend units: readable names that never collide with GLSL, float literals, constants, and the
// emitted code of a module.
#include <catch2/catch.hpp>

#include "TestUtil.h"
#include "glsl/Emit.h"
#include "glsl/Names.h"
#include "glsl/Validate.h"
#include "ir/Builder.h"
#include "source/Source.h"

using namespace iqc;
using namespace iqc::glsl;

namespace {

// An entry function named `name` (its GLSL name too), for a test to build with ir::Builder.
ir::Function entry_function(const char* name) {
    ir::Function f;
    f.name = name;
    f.glsl_name = name;
    f.entry = true;
    return f;
}

// The GLSL of module m's function `index` (no diagnostics expected).
std::string emit_function(const ir::Module& m, int index) {
    SourceManager sm;
    Diagnostics diags(sm);
    Namer names;
    Emitter em(m, names, diags);
    std::string code = em.function(index);
    CHECK_FALSE(diags.has_errors());
    return code;
}

std::string emit_first_function(const ir::Module& m) { return emit_function(m, 0); }

}  // namespace

TEST_CASE("math names become readable GLSL identifiers", "[glsl]") {
    CHECK(identifier("N̂") == "N_hat");
    CHECK(identifier("α") == "alpha");
    CHECK(identifier("p'") == "p_prime");
    CHECK(identifier("P_L") == "P_L");
    CHECK(identifier("x̃") == "x_tilde");
    CHECK(identifier("k_α") == "k_alpha");
    CHECK(identifier("2x") == "v2x");
    CHECK(identifier("gl_x") == "v_gl_x");
    CHECK(identifier("a__b") == "a_b");
    // the runtime's prefixes: refused with every suffix, so a user name never keeps them (the ir fuzzer
    // found `IQC_…` looping forever in Namer::unique; tests/fuzz/scene/iqc_prefixed_names.iql)
    CHECK(identifier("iqc_t") == "v_iqc_t");
    CHECK(identifier("IQC_a") == "v_IQC_a");
}

TEST_CASE("the namer avoids GLSL keywords, built-ins and names already taken", "[glsl]") {
    Namer n;
    CHECK(n.unique("length") == "length_2");
    CHECK(n.unique("in") == "in_2");
    CHECK(n.unique("x") == "x");
    CHECK(n.unique("x") == "x_2");
    Namer inner(&n);
    CHECK(inner.unique("x") == "x_3");
    CHECK(is_reserved("mainImage"));
    CHECK(is_reserved("iqc_scene"));
    CHECK(n.unique("iqc_scene") == "v_iqc_scene");
    CHECK(n.unique("IQC_FOG") == "v_IQC_FOG");
}

TEST_CASE("float literals always have a point", "[glsl]") {
    CHECK(float_literal(1) == "1.0");
    CHECK(float_literal(0.5) == "0.5");
    CHECK(float_literal(-2) == "-2.0");
    CHECK(float_literal(1e-5) == "1.0e-05");
    CHECK(float_literal(-0.0) == "0.0");
    CHECK(constant(Type::vector(3), {1, 1, 1}) == "vec3(1.0)");
    // Row-major math, column-major GLSL.
    CHECK(constant(Type::matrix(2, 2), {1, 2, 3, 4}) == "mat2(1.0, 3.0, 2.0, 4.0)");
    CHECK(type_name(Type::matrix(3, 4)) == "mat4x3");
    std::string why;
    CHECK(type_name(Type::vector(5), &why).empty());
    CHECK_THAT(why, Catch::Contains("larger than GLSL's largest vector"));
}

TEST_CASE("glslang validation accepts good shaders and rejects bad ones", "[glsl]") {
    CHECK(validate_fragment("#version 300 es\nprecision highp float;\nout vec4 c;\nvoid main() { c = vec4(1.0); }\n",
                            Profile::Es300).ok);
    auto bad = validate_fragment("#version 300 es\nprecision highp float;\nout vec4 c;\nvoid main() { c = 1; }\n",
                                 Profile::Es300);
    CHECK_FALSE(bad.ok);
    CHECK_THAT(bad.log, Catch::Contains("ERROR"));
}

TEST_CASE("int(floor(x)) of a value that is already an integer is int(x)", "[glsl]") {
    // A lattice's cell range is clamp(ceil(...), 0, n - 1): the floor of it was code for the driver to compile.
    ir::Module m;
    ir::Function f = entry_function("cells");
    {
        ir::Builder b(m, f);
        ir::ValueId x = b.param("x", Type::vector(3));
        ir::ValueId cell = b.builtin("clamp", {b.builtin("ceil", {x}), b.constant(Type::vector(3), {0, 0, 0}),
                                               b.constant(Type::vector(3), {9, 9, 0})});
        ir::ValueId a = b.op(ir::Op::FloorInt, {b.op(ir::Op::Extract, {cell}, 0)});
        // Not integral: clamp's bound is not an integer, a sum is not looked into, a plain parameter.
        ir::ValueId half = b.builtin("clamp", {b.builtin("floor", {x}), b.constant(Type::vector(3), {0, 0, 0}),
                                               b.constant(Type::vector(3), {9.5, 9, 0})});
        ir::ValueId c = b.op(ir::Op::FloorInt, {b.op(ir::Op::Extract, {half}, 1)});
        ir::ValueId s = b.op(ir::Op::FloorInt, {b.op(ir::Op::Add, {b.op(ir::Op::Extract, {x}, 2), b.scalar(0.5)})});
        ir::ValueId e = b.op(ir::Op::FloorInt, {b.op(ir::Op::Extract, {x}, 1)});
        f.result = b.op(ir::Op::Add, {b.op(ir::Op::Add, {a, c}), b.op(ir::Op::Add, {s, e})});
    }
    m.functions.push_back(std::move(f));
    const std::string code = emit_first_function(m);
    INFO(code);
    CHECK_THAT(code, Catch::Contains("int(clamp(ceil(x), vec3(0.0), vec3(9.0, 9.0, 0.0)).x)"));
    CHECK_THAT(code, Catch::Contains("int(floor(clamp(floor(x), vec3(0.0), vec3(9.5, 9.0, 0.0)).y))"));
    CHECK_THAT(code, Catch::Contains("int(floor(x.z + 0.5))"));
    CHECK_THAT(code, Catch::Contains("int(floor(x.y))"));
}

TEST_CASE("an integer division by a constant is a multiplication and a shift where the dividend's range is known", "[glsl]") {
    // Builder::div_by_constant / mod_by_constant for k in [0, n): exact at every k (the double evaluator, which
    // computes IntDiv as floor), with no 32-bit overflow ((n - 1)·M < 2^31); a power of two is a shift or a mask
    // in GLSL (IntDiv/IntMod take operands >= 0), other divisors keep `/` and `%` where no multiplier fits.
    struct Case { long long d, n; bool multiplied; };
    // (7 over [0, 10^6) and 1000 over [0, 3·10^6): no multiplier that is exact there fits in 32 bits.)
    for (Case c : {Case{3, 9, true}, Case{7, 100, true}, Case{10, 100, true}, Case{10, 1000, true}, Case{13, 4096, true},
                   Case{100, 10000, true}, Case{7, 1000000, false}, Case{1000, 3000000, false}, Case{8, 50, false}, Case{1, 20, false},
                   Case{9, 5, false}}) {
        INFO(c.d << ", " << c.n);
        ir::Module m;
        ir::Function f = entry_function("divide");
        {
            ir::Builder b(m, f);
            ir::ValueId k = b.param("k", Type::integer());
            f.result = b.construct(Type::vector(2), {b.op(ir::Op::Add, {b.scalar(0), b.div_by_constant(k, c.d, c.n)}),
                                                    b.op(ir::Op::Add, {b.scalar(0), b.mod_by_constant(k, c.d, c.n)})});
        }
        for (const ir::Instr& in : f.body)  // the multiplier: no overflow in 32-bit ints over [0, n)
            if (in.op == ir::Op::Mul && in.type.kind == Type::Integer && f.body[in.args[1]].op == ir::Op::Const &&
                f.body[in.args[0]].op == ir::Op::Param)
                CHECK((c.n - 1) * (long long)f.body[in.args[1]].data[0] < (1LL << 31));
        m.functions.push_back(f);
        const long long step = std::max(1LL, c.n / 20000);
        for (long long k = 0; k < c.n; k += (k < 5000 || k > c.n - 5000) ? 1 : step) {
            ir::Value r = ir::evaluate(m, 0, {ir::Value{Type::integer(), {double(k)}}});
            if (r.v[0] != double(k / c.d) || r.v[1] != double(k % c.d)) {
                FAIL_CHECK(k << ": " << r.v[0] << ", " << r.v[1]);
                break;
            }
        }
        const std::string code = emit_first_function(m);
        INFO(code);
        if (c.d == 8) {
            CHECK_THAT(code, Catch::Contains("k >> 3"));
            CHECK_THAT(code, Catch::Contains("k & 7"));
        } else if (c.multiplied) {
            CHECK_THAT(code, Catch::Contains(">>"));
            CHECK_THAT(code, !Catch::Contains(" / ") && !Catch::Contains(" % "));
        } else if (c.d > 1) {
            CHECK_THAT(code, Catch::Contains("k / " + std::to_string(c.d)));
        }
    }
}

TEST_CASE("a switch's default is the initial value only where it is safe to compute for every selector", "[glsl]") {
    // A group's table read at id - 1 as the default of a switch on the id (cases 7 and 8: two instances of their
    // own) would be read at 6 and 7, past the table's 6 entries, if it were computed first: it is guarded by the
    // cases' complement. A default that reads a table at a constant index stays the initial value.
    ir::Module m;
    ir::Global g;
    g.name = "t";
    g.type = Type::array(Type::vector(2), 6);
    g.value.assign(12, 0.5);
    m.globals.push_back(g);
    ir::Function f = entry_function("pick");
    {
        ir::Builder b(m, f);
        ir::ValueId id = b.param("id", Type::integer());
        ir::ValueId t = b.global(0);
        ir::ValueId read = b.op(ir::Op::Index, {t, b.op(ir::Op::Sub, {id, b.integer(1)})});
        ir::ValueId a = b.constant(Type::vector(2), {1, 2}), c = b.constant(Type::vector(2), {3, 4});
        ir::ValueId guarded = b.switch_(id, read, {{7, 8, a}, {8, 9, c}});
        ir::ValueId plain = b.switch_(id, b.op(ir::Op::Index, {t, b.integer(2)}), {{7, 8, a}, {8, 9, c}});
        f.result = b.op(ir::Op::Add, {guarded, plain});
    }
    m.functions.push_back(std::move(f));
    const std::string code = emit_first_function(m);
    INFO(code);
    CHECK_THAT(code, Catch::Contains("if (!((id == 7) || (id == 8))) {"));
    CHECK_THAT(code, !Catch::Contains("= t[id - 1];\n    if (id == 7)"));
    CHECK_THAT(code, Catch::Contains("vec2 tmp_2 = t[2];"));
}

TEST_CASE("the instances' distances a dispatch selects are computed in statements before the select", "[glsl]") {
    // GLSL's ?: computes only the chosen operand: `id == 0 ? ball(p) : ball(2p)` is a branch around each inlined
    // body in the driver, where the IR's Select computes both (IfConvert's dispatch of instances' distances, in
    // iqc_distance_of). A call elsewhere in that function stays inline, and so does a select's call in another
    // function (a piecewise bound its author wrote: `{ f(p) if ‖p‖ < 2; ... }`).
    ir::Module m;
    ir::Function ball;
    ball.name = ball.glsl_name = "ball";
    {
        ir::Builder b(m, ball);
        ir::ValueId p = b.param("p", Type::vector(3));
        ball.result = b.op(ir::Op::Sub, {b.builtin("length", {p}), b.scalar(1)});
    }
    m.functions.push_back(std::move(ball));
    ir::Function f = entry_function(ir::names::kDistanceOf);
    {
        ir::Builder b(m, f);
        ir::ValueId p = b.param("p", Type::vector(3));
        ir::ValueId id = b.param("id", Type::integer());
        // The far operand: a call scaled (the scale of an instance's distance).
        ir::ValueId near = b.call(0, {p}), far = b.op(ir::Op::Mul, {b.call(0, {b.op(ir::Op::Mul, {b.scalar(2), p})}), b.scalar(0.5)});
        ir::ValueId chosen = b.op(ir::Op::Select, {b.compare(ir::CompareKind::Eq, id, b.integer(0)), near, far});
        f.result = b.op(ir::Op::Add, {chosen, b.call(0, {b.op(ir::Op::Neg, {p})})});
    }
    m.functions.push_back(std::move(f));
    const std::string code = emit_function(m, 1);
    INFO(code);
    CHECK_THAT(code, Catch::Contains("    float tmp = ball(p);\n    float tmp_2 = ball(2.0 * p) * 0.5;\n"));
    CHECK_THAT(code, Catch::Contains("((id == 0) ? tmp : tmp_2) + ball(-p)"));
    // The same select in another function: the calls inline in ?:.
    ir::Function g = entry_function("pick");
    {
        ir::Builder b(m, g);
        ir::ValueId p = b.param("p", Type::vector(3));
        ir::ValueId c = b.compare(ir::CompareKind::Lt, b.builtin("length", {p}), b.scalar(2));
        g.result = b.op(ir::Op::Select, {c, b.call(0, {p}), b.op(ir::Op::Sub, {b.builtin("length", {p}), b.scalar(1)})});
    }
    m.functions.push_back(std::move(g));
    const std::string other = emit_function(m, 2);
    INFO(other);
    CHECK_THAT(other, Catch::Contains("? ball(p) :"));
}

TEST_CASE("an integer constant read as a float is a float literal", "[glsl]") {
    // A lattice one cell deep in z: the cell (i, j, 0) was vec3(float(i), float(j), float(0)).
    ir::Module m;
    ir::Function f = entry_function("cell");
    {
        ir::Builder b(m, f);
        ir::ValueId i = b.param("i", Type::integer());
        ir::ValueId x = b.param("x", Type::scalar());
        ir::ValueId c = b.construct(Type::vector(3), {i, b.integer(3), b.integer(0)});
        ir::ValueId d = b.op(ir::Op::Sub, {x, b.integer(-2)});
        f.result = b.op(ir::Op::Add, {b.op(ir::Op::Extract, {c}, 2), d});
    }
    m.functions.push_back(std::move(f));
    const std::string code = emit_first_function(m);
    INFO(code);
    CHECK_THAT(code, Catch::Contains("vec3(float(i), 3.0, 0.0)"));
    CHECK_THAT(code, Catch::Contains("x - (-2.0)"));
    CHECK_THAT(code, !Catch::Contains("float(0)"));
}
