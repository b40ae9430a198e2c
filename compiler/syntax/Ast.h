// Abstract syntax of one module of the math language.
//
// The parser produces it; the checker (sema/) annotates each expression with its type. Nodes own their
// children. Names are stored as written (without backticks); spans point into the source for diagnostics.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "sema/Type.h"
#include "source/Source.h"

namespace iqc::ast {

enum class ExprKind {
    Number,     // number
    Name,       // name (a variable, parameter, constant such as π)
    Call,       // name(args): a function call, or a name times a parenthesised value (decided by sema)
    Binary,     // op, args[0], args[1]
    Negate,     // -args[0]
    Power,      // args[0] ^ args[1]  (also superscripts; ᵀ is Transpose)
    Transpose,  // args[0]ᵀ
    Index,      // args[0] subscripted by indices (1-based; `*` is a whole row/column)
    Vector,     // (a, b, ...) — concatenation of scalars and vectors
    Matrix,     // [a b; c d]
    Norm,       // ‖args[0]‖, with a subscript: text "∞", "*" or "F", or args[1] (‖v‖_1, ‖v‖_p, ‖v‖_M)
    Abs,        // |args[0]|
    Floor,      // ⌊args[0]⌋
    Ceil,       // ⌈args[0]⌉
    Sqrt,       // √args[0]
    Compare,    // args[0] op args[1]  (=, ≠, <, ≤, >, ≥) — only in piecewise conditions
    Logic,      // and / or
    Piecewise,  // cases: values[i] if conds[i]; otherwise
    Sum,        // ∑_text args[0]: a sum over the index `text` (range from the sizes it subscripts)
    Inner,      // ⟨args[0], args[1]⟩ (or <a, b>), with a subscript args[2]: ⟨u, v⟩_M = vᵀ M u
    Block,      // a sized block: text "0" (zeros) or "1" (ones, also 𝟙); indices: its sizes (0_2,3, 1_n, 𝟙₃)
    Sequence,   // {a, b, c}: a sequence literal (an iqc extension, for values and defaults of x_i ∈ ℝ³)
};

enum class BinOp {
    Add, Sub,
    Juxtapose,  // a b, 2x
    Star,       // a * b (extension)
    Dot,        // a ⋅ b: dot product of two equal-size vectors, otherwise multiplication
    Div,        // a / b, a ÷ b
    Hadamard,   // a ∘ b
    Cross,      // a × b
    Solve,      // A \ b: the x with A x = b
    Kronecker,  // A ⊗ B
    Frobenius,  // A : B, the sum of the elementwise products
    PlusMinus,  // a ± b, only in conditions: x = a ± b is x = a + b or x = a - b
    Eq, Neq, Lt, Le, Gt, Ge,
    And, Or,
};

const char* binop_spelling(BinOp op);

struct Expr;
using ExprPtr = std::unique_ptr<Expr>;

struct IndexItem {
    ExprPtr expr;     // null for `*`
    Span span;
    // Filled by the checker: the 0-based index; -1 for `*`, -2 for an enclosing ∑'s (or an element-wise
    // definition's) index, -3 for a ℤ value known only when running (a_b with b ∈ ℤ).
    int value = 0;
    bool zero_based = false;  // -3: the value is an I♥LA `ℤ index` (counts from 0), not a position (from 1)
};

struct Expr {
    ExprKind kind;
    Span span;
    double number = 0;
    std::string text;  // number as written; the name for Name/Call
    Span name_span;
    Span word_span;    // Name/Call split out of a longer letter run: that run (see Token::word)
    BinOp op = BinOp::Add;
    std::vector<ExprPtr> args;
    std::vector<std::vector<ExprPtr>> rows;  // Matrix rows; Piecewise: {value, condition} per case
    std::vector<IndexItem> indices;          // Index
    std::vector<int> block_rows, block_cols; // Matrix: heights and widths of the block rows/columns
    ExprPtr otherwise;                       // Piecewise
    // Filled by the checker.
    Type type;
    int resolved = 0;  // sema's meaning for Name/Call/Binary (see sema/Check.h: Resolved)
    int aux = 0;       // with `resolved`: a builtin id, a function index, ...

    Expr(ExprKind k, Span s) : kind(k), span(s) {}
};

// A type as written in a declaration.
struct TypeSpec {
    enum Kind { Scalar, Integer, Vector, Matrix, Function } kind = Scalar;
    int rows = 1, cols = 1;
    std::string sym_rows, sym_cols;  // symbolic sizes (`ℝ^n`)
    ExprPtr rows_expr, cols_expr;    // sizes computed from symbolic ones (`ℝ^((p+1)×k)`): rows/cols are then 0
    std::vector<TypeSpec> params;    // Function
    std::unique_ptr<TypeSpec> result;
    Span span;
};

struct Interval {
    ExprPtr lo, hi;
    Span span;
};

struct Decl {
    std::vector<std::pair<std::string, Span>> names;
    // Per name: the index of a sequence (`x_i ∈ ℝ³` declares the sequence x, indexed by i), else "".
    std::vector<std::string> indices;
    TypeSpec type;
    bool zero_based = false;  // `b ∈ ℤ index`: I♥LA's index type, which counts from 0
    std::vector<Interval> bounds;  // `[a,b]x[c,d]`: one interval per component (type is then derived)
    ExprPtr default_value;
    Span default_span;
    std::string description;
    Span span;
};

// Assign: name = value. Function: name(params) = value. Return: a bare expression. Import: names from module.
// SeqInit: name_<index> = value (a sequence's first element). Recurrence: name_(var+1) = value for var ∈ lo..hi.
enum class StmtKind { Assign, Function, Return, Import, SeqInit, Recurrence };

struct Stmt {
    StmtKind kind = StmtKind::Assign;
    std::string name;  // Assign / Function
    Span name_span;
    std::vector<std::pair<std::string, Span>> params;  // Function
    ExprPtr value;
    std::vector<Decl> local_decls;  // Function: its own `where`
    std::vector<std::pair<std::string, Span>> imports;  // Import: names
    std::string from;                                   // Import: module
    Span from_span;
    ExprPtr index;                  // SeqInit / Recurrence: the subscript on the left
    // Assign with subscripts on the left: an element-wise definition, q_i = p_i² or B_ij = A_ij A_ij (one or
    // two index letters; the same letter twice, D_ii, defines a diagonal matrix).
    std::vector<std::pair<std::string, Span>> elem_indices;
    std::string loop_var;           // Recurrence: the index variable
    Span loop_var_span;
    ExprPtr range_lo, range_hi;     // Recurrence: var ∈ lo..hi
    Span span;
    std::string source_line;  // the statement as written, for comments in the generated code
};

enum class ModuleKind { Library, Shape, Material };

struct Module {
    ModuleKind kind = ModuleKind::Library;
    std::string name;
    Span span;
    std::vector<Stmt> stmts;
    std::vector<Decl> decls;
    // The first word of each line that failed to parse (dropped, its error reported): a dropped `D = …` is not
    // reported again as "does not assign 'D'".
    std::vector<std::string> dropped;
};

}  // namespace iqc::ast
