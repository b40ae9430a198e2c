// The typed IR: what folding, dead-code removal, differentiation, range analysis, the double-precision
// evaluator and the GLSL backend all work on.
//
// A Module holds Functions and module-level values (Globals: the scene's parameters and the facts it
// computes once, such as inverted transforms). A Function's body is a list of instructions in SSA form:
// each instruction defines one value (its index in the body) from earlier values. Every operation is pure;
// `If` and `Switch` are lazy: only the chosen operand's computation runs (ir/Schedule.h says which
// instructions belong to which arm). Instructions keep the source name and span of the statement that
// defined them, so the backend can emit readable code (`float D = ...; // D = ‖q‖ - t_2`) and diagnostics can
// point at the math. `print()` gives a stable text form for tests and `--dump-ir` (ir/Parse.h reads it back);
// `verify()` checks types and SSA order.
//
// Matrices are stored row-major in constants and evaluator values (as they are written in math). ℤ values
// are exact integers (stored as doubles); arithmetic on two ℤ operands stays ℤ (array indices, instance ids).
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "sema/Type.h"
#include "source/Limits.h"
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
    X(Global, 0)      /* aux: index in Module::globals */                                \
    X(Index, 2)       /* array[i]: element i (ℤ, 0-based) of an array value */           \
    X(If, 3)          /* cond ? a : b, lazy: only the chosen operand is computed */      \
    X(Switch, -1)     /* args: selector (ℤ), default, cases; data: each case's [lo, hi) */ \
    X(IntDiv, 2)      /* ℤ ÷ ℤ rounded down (operands ≥ 0: GLSL's a / b) */              \
    X(IntMod, 2)      /* ℤ mod ℤ: a - b⌊a/b⌋ (operands ≥ 0: GLSL's a % b) */            \
    X(FloorInt, 1)    /* ℝ -> ℤ: ⌊x⌋ (GLSL's int(floor(x))); x within ±2³¹ */           \
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

// Thrown when one function's IR would exceed limits::kMaxFunctionInstructions; `span` is the expression
// being lowered (may be empty). Callers report it as a located error (limit_message()).
struct SizeLimit {
    Span span;
};
std::string size_limit_message();

struct FunctionParam {
    std::string name;
    Type type;
};

// What range analysis may assume about a parameter or a global: slider bounds per component (lo/hi
// empty: any value), or, for an input the renderer supplies (a query point, a normal), nothing.
struct ValueBounds {
    bool input = true;
    std::vector<double> lo, hi;
};

// A scene item's Lipschitz analysis (ir/passes/Lipschitz.h): the shape's object-space distance function to
// bound, where, and the item distance function whose result is divided by the bound.
struct LipschitzSpec {
    int object_fn = -1;          // (q ∈ ℝ³[, k ∈ ℤ]) -> the shape's distance, not yet divided by any factor
    ValueBounds region;          // q's box (3 components)
    double ball = 0;             // > 0: q also lies within this distance of the origin (a `bound` sphere)
    // The `bound` radii of the first members (one for a single instance; up to 8 for a group, member k's at
    // k): the pass checks that the shape stays inside its sphere there. Empty: no `bound`.
    std::vector<double> bounds;
    std::vector<Span> bound_where;  // per entry of `bounds`: where it is written (invalid: derived by the compiler)
    int group = 0;               // a group's size: k ∈ [0, group - 1] (0: no k)
    double declared = 0;         // `# lipschitz: K` of the shape (0: none)
    bool trusted = false;        // the shape says `# exact` or `# bound`: 1-Lipschitz by construction
    Span where;                  // the instance, for diagnostics
    std::vector<Span> member_where;  // a group's members' instances, up to 16 (member k's at k): its warnings name the steepest
    std::string shape;           // the shape module's name
    int factor_global = -1;      // >= 0: the Constant global that receives the factor applied (iqc_lipschitz reads it)
};

struct Function {
    std::string name;                  // qualified: "torus", "transformations.T", "scene.box_frame_1.transform"
    std::string glsl_name;             // preferred GLSL spelling (the backend still makes it unique)
    std::vector<FunctionParam> params;
    std::vector<ValueBounds> param_bounds;  // per parameter (empty: every parameter is an input)
    bool inline_hint = false;          // a building block of the scene functions: the inline pass inlines it
    bool entry = false;                // called from outside the IR (the runtime, the evaluator's user)
    // The body of a rolled ∑ (ir/Lower.cpp): the emitter may unroll it further to keep llvmpipe's loop budget
    // (glsl::Emitter::limit_loop_iterations). Not in the IR text.
    bool rolled_sum = false;
    LipschitzSpec lipschitz;           // an item distance function: divide its result by the shape's bound
    std::vector<Instr> body;
    ValueId result = 0;                // the primary output (D, C, or the bare expression)
    std::vector<std::pair<std::string, ValueId>> outputs;  // every assigned name, in source order
    Type result_type() const { return body.empty() ? Type{} : body[result].type; }

    // Appends an instruction; past limits::kMaxFunctionInstructions throws SizeLimit (what local functions
    // and sums unroll to can grow exponentially: f(x) = g(x) + g(x), g(x) = h(x) + h(x), …).
    ValueId add(Instr in) {
        if (body.size() >= limits::kMaxFunctionInstructions) throw SizeLimit{in.span};
        body.push_back(std::move(in));
        return ValueId(body.size() - 1);
    }
    ValueId constant(Type t, std::vector<double> data);
    ValueId scalar(double v) { return constant(Type::scalar(), {v}); }
};

// Which instance parameter a global (or one element of an array global) is, for `--meta` and sliders.
struct GlobalParam {
    std::string instance;     // "ring_7", or the light's name
    std::string module;       // "torus" ("" for lights, "transform" for a transform's parameters)
    std::string role;         // "shape", "material", "transform", "light"
    std::string name;         // the parameter as written: "t", "k_d", "position"
    std::string description;
};

struct Global {
    // Parameter: a value the user may change (a slider; its storage is the target's choice: constants on
    // Shadertoy, uniforms elsewhere). Constant: a fact the compiler computed (always a constant).
    // Prepared: computed once per pixel by the function `iqc_prepare` (its output of the same name), before
    // any marching — a transform that depends on sliders or time.
    enum class Kind : uint8_t { Parameter, Constant, Prepared };
    std::string name;          // unique in the module, also the preferred GLSL spelling
    Type type;                 // may be an array: per-instance data of a group of instances
    Kind kind = Kind::Constant;
    std::vector<double> value; // row-major components, arrays element after element (Prepared: unused)
    ValueBounds bounds;        // per element component; `input` is false for parameters and constants
    std::vector<GlobalParam> params;  // Parameter: one per element of a per-member table, else one per instance it serves
    // Parameter: an array of one element per member of a group of instances (a table), not a sequence parameter
    // (x_i ∈ ℝ³, an array one instance owns whole; a sequence is never per member: GLSL ES has no arrays of arrays).
    bool per_member = false;
    std::string comment;       // what the value is (the declaration's comment)
    std::string owner;         // whose value it is, for grouping declarations: "floor_1: floor with lit"
};

struct Module {
    std::vector<Function> functions;
    std::vector<Global> globals;
    // The target makes parameters constants (Shadertoy): analyses may use their values, not their sliders'
    // ranges.
    bool constant_parameters = false;
    // Per instance id: the world box (lo x, y, z, hi x, y, z; ±1e30 on an open side) outside which the
    // instance's nearness exceeds the scene box's level (SceneIR::box, per instance). Segment tracing skips
    // the bounds of instances whose box the segment's misses. Not printed in the IR text.
    std::map<long long, std::array<double, 6>> instance_boxes;
    int find(const std::string& name) const;
    int find_global(const std::string& name) const;
    // Every global's index by name (views of the names: valid while `globals` is unchanged): for a lookup per
    // item, where find_global's search would make the lookups quadratic in instances.
    std::unordered_map<std::string_view, int> global_index() const;
};

// The scene's fixed function names: the runtime (runtime_templates/scene.glsl) calls these.
namespace names {
inline constexpr const char* kScene = "iqc_scene";              // (p: ℝ³) -> (distance, instance id as ℝ)
inline constexpr const char* kSceneUnbounded = "iqc_scene_unbounded";  // (p: ℝ³) -> iqc_scene without `bound` spheres
inline constexpr const char* kDistanceOf = "iqc_distance_of";   // (p: ℝ³, id: ℤ) -> that instance's distance
inline constexpr const char* kGradient = "iqc_gradient";        // (p: ℝ³, id: ℤ) -> ∇ of it (analytic normals)
inline constexpr const char* kShade = "iqc_shade";              // (id, p, N, eye) -> colour without lights
inline constexpr const char* kShadeLight = "iqc_shade_light";   // (id, p, N, eye, P_L, C_L) -> one light's term
inline constexpr const char* kLightPosition = "iqc_light_position";  // (l: ℤ) -> ℝ³
inline constexpr const char* kLightColor = "iqc_light_color";        // (l: ℤ) -> ℝ³
inline constexpr const char* kReflectivity = "iqc_reflectivity";    // (id) -> k_r as ℝ³
inline constexpr const char* kTransmission = "iqc_transmission";    // (id) -> (k_t, η)
inline constexpr const char* kSegmentGain = "iqc_segment_gain";  // (lo, hi, rd: ℝ³) -> how many times the scene distance a step may take within the box [lo, hi]
inline constexpr const char* kSegmentClear = "iqc_segment_clear";  // (lo, hi: ℝ³) -> a lower bound of the scene distance over the box [lo, hi]
inline constexpr const char* kLipschitz = "iqc_lipschitz";  // (id: ℤ) -> the factor dividing that instance's distance
inline constexpr const char* kPrepare = "iqc_prepare";         // () -> outputs named like Prepared globals
inline constexpr const char* kBoxLo = "iqc_box_lo";  // () -> the scene box's low corner where it follows the sliders
inline constexpr const char* kBoxHi = "iqc_box_hi";  // () -> its high corner
inline constexpr const char* kInstanceInverse = "iqc_instance_inverse";    // (i: ℤ) -> world→object ℝ^(4×4)
inline constexpr const char* kInstanceDistance = "iqc_instance_distance";  // (i: ℤ, q: ℝ³) -> object-space distance
}  // namespace names

// The element-count of a Switch's cases and the range of case k: [lo, hi).
inline int switch_cases(const Instr& in) { return int(in.data.size() / 2); }

// Whether instruction `in` of a function whose instructions are `body` may be computed for values its lazy
// choice did not choose (speculatively): no array read at an index that is not a constant (a group's table at
// id - 1, out of range for another instance's id), no integer division by anything but a non-zero constant, no
// call or recurrence (whose bodies may do either). Used by if-conversion (ir/passes/IfConvert.h), merged calls'
// switched arguments (ir/passes/MergeCalls.h) and the GLSL backend's switch defaults.
inline bool speculatable(const std::vector<Instr>& body, const Instr& in) {
    switch (in.op) {
        case Op::Call: case Op::Loop: case Op::Member: return false;
        case Op::Index: return body[in.args[1]].op == Op::Const;
        case Op::IntDiv: case Op::IntMod: {
            const Instr& d = body[in.args[1]];
            return d.op == Op::Const && !d.data.empty() && d.data[0] != 0;
        }
        default: return true;
    }
}

// Whether value v of `body` and its operands, transitively (to `depth` operands; deeper: not known), are all
// speculatable, a lazy choice inside counting as not; a value `computed(v)` says already has a value (a GLSL
// variable) counts as safe without its operands. A merged call's switched-argument default (MergeCalls) and the
// GLSL backend's switch defaults, which run before the cases are told apart.
template <class Computed>
bool speculatable_expression(const std::vector<Instr>& body, ValueId v, Computed computed, int depth = 16) {
    if (computed(v)) return true;
    const Instr& in = body[v];
    if (!speculatable(body, in) || in.op == Op::If || in.op == Op::Switch) return false;
    if (in.args.empty()) return true;
    if (depth == 0) return false;
    for (ValueId a : in.args)
        if (!speculatable_expression(body, a, computed, depth - 1)) return false;
    return true;
}

// Stable text form, e.g. `%3 = ℝ Sub %1, %2  ; D`.
std::string print(const Function& f, const Module* m = nullptr);
std::string print(const Module& m);
std::string print(const Global& g, size_t index);

// Checks operand counts, SSA order and types; returns "" when valid, else a description of the first fault.
std::string verify(const Function& f, const Module& m);
std::string verify(const Module& m);

// A Loop runs its body function for k = lo..hi (lo in data; operands: hi, the initial states, the captured
// outer values): the body's parameters are (k, the states, the captured outer values) and its outputs
// are the next states, in order. The Loop's value is the tuple of final
// states; Member picks one. Bodies are functions of the module that are never called on their own.
//
// The result type of `op` applied to operands of the given types, or Invalid (the rules the verifier,
// the lowering and the folder share).
Type result_type(Op op, const std::vector<Type>& args, int aux);

// A loop body that accumulates into its state j (0-based; parameter j + 1): output j is `state + t` or `t + state`
// and t reads no state. Returns t, else none. (A rolled ∑'s body, ir/Lower.cpp; the analyses of loops in
// Intervals and the ranges pass, and the stable pass's log-sum-exp, read it so.)
std::optional<ValueId> accumulated_term(const Function& body, size_t j);
// A loop body that keeps one of its state j and a value t each step: output j is a Select (or If) of the state and
// t, whatever the condition, or max/min(state, t); t reads no state. Returns t, else none. (A rolled max_i x_i and
// its derivative, the stable log-sum-exp's shift: the state ends within the hull of its first value and t's.)
std::optional<ValueId> selected_term(const Function& body, size_t j);

// Marks fn and every function it calls or runs as a loop body, transitively, in `seen` (one entry per function
// of m; marked entries are not visited again).
void mark_reachable(const Module& m, int fn, std::vector<char>& seen);

// This thread's analysis work meter: evaluator steps (Evaluator::work's unit) plus kIntervalWork for each
// instruction the interval analysis has bounded, since the thread began. Compile-time analyses that repeat an
// estimate (the Lipschitz pass' slider cells) budget themselves by its differences: the same on every machine and
// under any load, unlike time.
uint64_t& analysis_work();
// An interval analysis' instruction costs about 16 evaluator steps (its symbolic forms and convex combinations):
// fitted on compile times where each dominates (a smooth subtraction's onion, 8.3·10⁶ interval instructions and
// 3·10⁶ steps: 0.75 s; the Mandelbulb, 3.8·10⁶ and 8.9·10⁷: 0.84 s), ~180·10⁶ steps a second in a release build.
constexpr uint64_t kIntervalWork = 16;

}  // namespace iqc::ir
