// The typed IR: what folding, dead-code removal, differentiation, range analysis, the double-precision
// evaluator and the GLSL backend all work on.
//
// A Module holds Functions. A Function's body is a list of instructions in SSA form: each instruction
// defines one value (its index in the body) from earlier values. Instructions keep the source name and
// span of the statement that defined them, so the backend can emit readable code (`float D = ...; // D = ‖q‖
// - t_2`) and diagnostics can point at the math. `print()` gives a stable text form for tests and
// `--dump-ir`; `verify()` checks types and SSA order.
//
// Matrices are stored row-major in constants and evaluator values (as they are written in math).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "sema/Type.h"
#include "source/Source.h"

namespace iqc::ir {

// The one list of instruction kinds (X-macro): name, operand count (-1: variable).
#define IQC_IR_OPS(X)                                                                    \
    X(Const, 0)       /* data: components */                                             \
    X(Param, 0)       /* aux: parameter index */                                         \
    X(Copy, 1)        /* a named alias of another value */                               \
    X(Add, 2)                                                                            \
    X(Sub, 2)                                                                            \
    X(Mul, 2)         /* scalar·x, x·scalar, matrix·vector, matrix·matrix, vector·row */ \
    X(Div, 2)         /* x / scalar */                                                   \
    X(Neg, 1)                                                                            \
    X(Hadamard, 2)    /* elementwise product */                                          \
    X(Dot, 2)                                                                            \
    X(Cross, 2)                                                                          \
    X(Transpose, 1)                                                                      \
    X(Inverse, 1)                                                                        \
    X(Det, 1)                                                                            \
    X(Builtin, -1)    /* aux: Builtin id (sema/Builtins.h) */                            \
    X(Construct, -1)  /* concatenation of scalars/vectors into a vector or (row-major) matrix */ \
    X(Extract, 1)     /* aux: flat component index (row-major) */                        \
    X(Row, 1)         /* aux: row index of a matrix, as a vector */                      \
    X(Column, 1)      /* aux: column index of a matrix, as a vector */                   \
    X(Compare, 2)     /* aux: CompareKind */                                             \
    X(And, 2)                                                                            \
    X(Or, 2)                                                                             \
    X(Select, 3)      /* cond ? a : b */                                                 \
    X(Call, -1)       /* aux: callee function index */                                  \
    X(Input, 0)       /* aux: 0 time (ℝ, seconds), 1 mouse (ℝ², [0,1]² of the view) */  \
    X(Loop, -1)       /* aux: body function; data: {lo}; args: hi, initial states, captures */    \
    X(Member, 1)      /* aux: which result of a Loop */                                  \
    X(Element, 1)     /* aux: 0-based index of an array's element */                    \
    X(At, -1)         /* args: an array, vector or matrix, then 0-based indices (values, \
                         rounded; clamped to the range): a[i], v[i], M[i][j] */

enum class Op : uint8_t {
#define X(name, n) name,
    IQC_IR_OPS(X)
#undef X
};

const char* op_name(Op op);
int op_arity(Op op);

enum class CompareKind : uint8_t { Eq, Ne, Lt, Le, Gt, Ge };

using ValueId = uint32_t;

struct Instr {
    Op op = Op::Const;
    Type type;
    std::vector<ValueId> args;
    std::vector<double> data;  // Const components
    int aux = 0;
    std::string name;          // source name when this value is a named statement ("" otherwise)
    std::string source;        // the statement as written (for comments), on named values
    Span span;
};

struct FunctionParam {
    std::string name;
    Type type;
};

struct Function {
    std::string name;                  // qualified: "torus", "transformations.T", "scene.box_frame_1.transform"
    std::string glsl_name;             // preferred GLSL spelling (the backend still makes it unique)
    std::vector<FunctionParam> params;
    std::vector<Instr> body;
    ValueId result = 0;                // the primary output (D, C, or the bare expression)
    std::vector<std::pair<std::string, ValueId>> outputs;  // every assigned name, in source order
    Type result_type() const { return body.empty() ? Type{} : body[result].type; }

    ValueId add(Instr in) {
        body.push_back(std::move(in));
        return ValueId(body.size() - 1);
    }
    ValueId constant(Type t, std::vector<double> data);
    ValueId scalar(double v) { return constant(Type::scalar(), {v}); }
};

struct Module {
    std::vector<Function> functions;
    int find(const std::string& name) const;
};

// Stable text form, e.g. `%3: ℝ = sub %1, %2  ; D`.
std::string print(const Function& f, const Module* m = nullptr);
std::string print(const Module& m);

// Checks operand counts, SSA order and types; returns "" when valid, else a description of the first fault.
std::string verify(const Function& f, const Module& m);

// A Loop runs its body function for k = lo..hi (lo in data; operands: hi, the initial states, the captured
// outer values): the body's parameters are (k, the states, the captured outer values) and its outputs
// are the next states, in order. The Loop's value is the tuple of final
// states; Member picks one. Bodies are functions of the module that are never called on their own.
//
// The result type of `op` applied to operands of the given types, or Invalid (the rules the verifier,
// the lowering and the folder share).
Type result_type(Op op, const std::vector<Type>& args, int aux);

}  // namespace iqc::ir
