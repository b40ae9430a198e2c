// SPIR-V -> WGSL (see Wgsl.h). References: the SPIR-V specification 1.0 (structured control flow, §2.11),
// the GLSL.std.450 extended instruction set, and the WGSL specification (W3C, 2024: memory layout §14.4,
// statement behaviours §9.7, reserved words §15.3).
#define SPV_ENABLE_UTILITY_CODE
#include "glsl/Wgsl.h"

#include "glsl/Spirv.h"

#include <spirv_cross/GLSL.std.450.h>
#include <spirv_cross/spirv.hpp>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <cstdlib>
#include <limits>
#include <functional>
#include <map>
#include <set>
#include <stdexcept>
#include <unordered_map>
#include <unordered_set>

namespace iqc::glsl {
namespace {

struct Unsupported : std::runtime_error {
    using std::runtime_error::runtime_error;
};

[[noreturn]] void fail(const std::string& what) { throw Unsupported(what); }

// WGSL keywords, reserved words and the predeclared names this translation uses (types, built-in
// functions): an identifier from the SPIR-V module that equals one gets a suffix.
const std::unordered_set<std::string>& reserved_words() {
    static const std::unordered_set<std::string> words = {
        // keywords
        "alias", "break", "case", "const", "const_assert", "continue", "continuing", "default", "diagnostic",
        "discard", "else", "enable", "false", "fn", "for", "if", "let", "loop", "override", "requires", "return",
        "struct", "switch", "true", "var", "while",
        // reserved words
        "NULL", "Self", "abstract", "active", "alignas", "alignof", "as", "asm", "asm_fragment", "async",
        "attribute", "auto", "await", "become", "binding_array", "cast", "catch", "class", "co_await",
        "co_return", "co_yield", "coherent", "column_major", "common", "compile", "compile_fragment", "concept",
        "const_cast", "consteval", "constexpr", "constinit", "crate", "debugger", "decltype", "delete", "demote",
        "demote_to_helper", "do", "dynamic_cast", "enum", "explicit", "export", "extends", "extern", "external",
        "fallthrough", "filter", "final", "finally", "friend", "from", "fxgroup", "get", "goto", "groupshared",
        "highp", "impl", "implements", "import", "inline", "instanceof", "interface", "layout", "lowp", "macro",
        "macro_rules", "match", "mediump", "meta", "mod", "module", "move", "mut", "mutable", "namespace", "new",
        "nil", "noexcept", "noinline", "nointerpolation", "non_coherent", "noncoherent", "noperspective", "null",
        "nullptr", "of", "operator", "package", "packoffset", "partition", "pass", "patch", "pixelfragment",
        "precise", "precision", "premerge", "priv", "protected", "pub", "public", "readonly", "ref", "regardless",
        "register", "reinterpret_cast", "require", "resource", "restrict", "self", "set", "shared", "sizeof",
        "smooth", "snorm", "static", "static_assert", "static_cast", "std", "subroutine", "super", "target",
        "template", "this", "thread_local", "throw", "trait", "try", "type", "typedef", "typeid", "typename",
        "typeof", "union", "unless", "unorm", "unsafe", "unsized", "use", "using", "varying", "virtual",
        "volatile", "wgsl", "where", "with", "writeonly", "yield",
        // predeclared types and enumerants
        "bool", "f16", "f32", "i32", "u32", "vec2", "vec3", "vec4", "mat2x2", "mat2x3", "mat2x4", "mat3x2",
        "mat3x3", "mat3x4", "mat4x2", "mat4x3", "mat4x4", "array", "atomic", "ptr", "sampler", "texture_2d",
        "function", "private", "uniform", "storage", "workgroup", "read", "write", "read_write",
        "vec2f", "vec3f", "vec4f", "vec2i", "vec3i", "vec4i", "vec2u", "vec3u", "vec4u", "mat2x2f", "mat3x3f",
        "mat4x4f",
        // built-in functions
        "abs", "acos", "acosh", "all", "any", "asin", "asinh", "atan", "atan2", "atanh", "bitcast", "ceil",
        "clamp", "cos", "cosh", "cross", "degrees", "determinant", "distance", "dot", "dpdx", "dpdxCoarse",
        "dpdxFine", "dpdy", "dpdyCoarse", "dpdyFine", "exp", "exp2", "faceForward", "floor", "fma", "fract",
        "fwidth", "fwidthCoarse", "fwidthFine", "inverseSqrt", "ldexp", "length", "log", "log2", "max", "min",
        "mix", "normalize", "pow", "radians", "reflect", "refract", "round", "select", "sign", "sin", "sinh",
        "smoothstep", "sqrt", "step", "tan", "tanh", "textureLoad", "transpose", "trunc",
    };
    return words;
}

// Unique, valid WGSL identifiers from SPIR-V debug names ("torus(vf3;vf2;" -> "torus").
class Namer {
public:
    std::string take(std::string want) {
        size_t paren = want.find('(');
        if (paren != std::string::npos) want.resize(paren);
        std::string s;
        for (char c : want) {
            bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
            s += ok ? c : '_';
        }
        while (s.size() >= 2 && s[0] == '_' && s[1] == '_') s.erase(0, 1);  // "__" starts no WGSL identifier
        if (s.empty() || s == "_") s = "v";
        if (s[0] >= '0' && s[0] <= '9') s = "v" + s;
        if (reserved_words().count(s)) s += "_";
        std::string name = s;
        // suffixes go on from where this base's last one stopped: thousands of `param`s cost linear time
        int& next = next_[s];
        if (next == 0) next = 2;
        while (used_.count(name)) name = s + "_" + std::to_string(next++);
        used_.insert(name);
        return name;
    }

private:
    std::unordered_set<std::string> used_;
    std::unordered_map<std::string, int> next_;
};

struct Insn {
    spv::Op op{};
    uint32_t type = 0, result = 0;
    std::vector<uint32_t> ops;  // the operands after the result type and result id
};

struct Block {
    uint32_t label = 0;
    std::vector<size_t> body;   // instructions between the label and the merge/terminator
    size_t merge = SIZE_MAX;     // OpSelectionMerge or OpLoopMerge
    size_t term = SIZE_MAX;
};

struct Function {
    size_t def = 0;
    std::vector<size_t> params;
    std::vector<Block> blocks;
    std::unordered_map<uint32_t, size_t> index;  // label -> block
};

std::string str_operand(const std::vector<uint32_t>& ops, size_t from) {
    std::string s;
    for (size_t i = from; i < ops.size(); ++i)
        for (int b = 0; b < 4; ++b) {
            char c = char((ops[i] >> (8 * b)) & 0xff);
            if (c == 0) return s;
            s += c;
        }
    return s;
}

std::string f32_literal(uint32_t bits) {
    float f;
    std::memcpy(&f, &bits, 4);
    char buf[64];
    if (!std::isfinite(f)) {
        std::snprintf(buf, sizeof buf, "bitcast<f32>(0x%08xu)", bits);
        return buf;
    }
    auto r = std::to_chars(buf, buf + sizeof buf, f);
    std::string s(buf, r.ptr);
    // The shortest decimal that reads back as f can lie past the largest f32 (3.4028235e38 > 3.40282347e38), which
    // WGSL rejects ("value cannot be represented as 'f32'": a rolled log-sum-exp's first maximum): there the exact
    // value as a double.
    if (std::fabs(std::strtod(s.c_str(), nullptr)) > double(std::numeric_limits<float>::max())) {
        r = std::to_chars(buf, buf + sizeof buf, double(f));
        s.assign(buf, r.ptr);
    }
    s += "f";
    return s[0] == '-' ? "(" + s + ")" : s;
}

struct Layout {
    uint32_t size = 0, align = 0;
};

class Translator {
public:
    explicit Translator(const std::vector<uint32_t>& words) : w_(words) {}

private:
    // ---- parsing ---------------------------------------------------------------------------------------
    void parse() {
        if (w_.size() < 5 || w_[0] != spv::MagicNumber) fail("not a SPIR-V module");
        bound_ = w_[3];
        if (bound_ > 50'000'000) fail("id bound too large");
        def_.assign(bound_, SIZE_MAX);
        Function* fn = nullptr;
        Block* blk = nullptr;
        for (size_t at = 5; at < w_.size();) {
            uint32_t wc = w_[at] >> 16;
            auto op = spv::Op(w_[at] & 0xffff);
            if (wc == 0 || at + wc > w_.size()) fail("malformed instruction");
            bool has_result = false, has_type = false;
            spv::HasResultAndType(op, &has_result, &has_type);
            Insn in;
            in.op = op;
            size_t k = at + 1;
            if (has_type) in.type = w_[k++];
            if (has_result) in.result = w_[k++];
            in.ops.assign(w_.begin() + long(k), w_.begin() + long(at + wc));
            at += wc;
            size_t idx = insns_.size();
            if (in.result) {
                if (in.result >= bound_) fail("id out of bound");
                if (def_[in.result] != SIZE_MAX) fail("id %" + std::to_string(in.result) + " defined twice");
                def_[in.result] = idx;
            }
            insns_.push_back(std::move(in));
            const Insn& i = insns_.back();
            switch (op) {
                case spv::OpName:
                    names_[i.ops[0]] = str_operand(i.ops, 1);
                    break;
                case spv::OpMemberName:
                    member_debug_[{i.ops[0], i.ops[1]}] = str_operand(i.ops, 2);
                    break;
                case spv::OpDecorate:
                    deco_[i.ops[0]][i.ops[1]] = i.ops.size() > 2 ? i.ops[2] : 1;
                    break;
                case spv::OpMemberDecorate:
                    mdeco_[{i.ops[0], i.ops[1]}][i.ops[2]] = i.ops.size() > 3 ? i.ops[3] : 1;
                    break;
                case spv::OpExtInstImport:
                    if (str_operand(i.ops, 0) != "GLSL.std.450") fail("extended instruction set " + str_operand(i.ops, 0));
                    glsl_set_ = i.result;
                    break;
                case spv::OpEntryPoint:
                    if (entry_) fail("more than one entry point");
                    if (i.ops[0] != spv::ExecutionModelFragment) fail("not a fragment shader");
                    entry_ = i.ops[1];  // its interface: the Input/Output variables (global_vars)
                    break;
                case spv::OpExecutionMode:
                    if (i.ops[1] != spv::ExecutionModeOriginUpperLeft && i.ops[1] != spv::ExecutionModeDepthReplacing)
                        fail("execution mode " + std::to_string(i.ops[1]));
                    break;
                case spv::OpCapability:
                    if (i.ops[0] != spv::CapabilityShader) fail("capability " + std::to_string(i.ops[0]));
                    break;
                case spv::OpExtension: fail("extension " + str_operand(i.ops, 0));
                case spv::OpFunction:
                    functions_.emplace_back();
                    fn = &functions_.back();
                    fn->def = idx;
                    blk = nullptr;
                    break;
                case spv::OpFunctionParameter:
                    if (!fn) fail("parameter outside a function");
                    fn->params.push_back(idx);
                    break;
                case spv::OpFunctionEnd:
                    fn = nullptr;
                    blk = nullptr;
                    break;
                case spv::OpLabel:
                    if (!fn) fail("label outside a function");
                    fn->blocks.emplace_back();
                    blk = &fn->blocks.back();
                    blk->label = i.result;
                    fn->index[i.result] = fn->blocks.size() - 1;
                    break;
                case spv::OpSelectionMerge:
                case spv::OpLoopMerge:
                    if (!blk) fail("merge outside a block");
                    blk->merge = idx;
                    break;
                case spv::OpBranch:
                case spv::OpBranchConditional:
                case spv::OpSwitch:
                case spv::OpReturn:
                case spv::OpReturnValue:
                case spv::OpKill:
                case spv::OpUnreachable:
                    if (!blk) fail("terminator outside a block");
                    blk->term = idx;
                    blk = nullptr;
                    break;
                case spv::OpLine:
                case spv::OpNoLine:
                case spv::OpNop:
                case spv::OpSource:
                case spv::OpSourceExtension:
                case spv::OpSourceContinued:
                case spv::OpString:
                case spv::OpModuleProcessed:
                case spv::OpMemoryModel:
                    break;
                default:
                    if (blk) blk->body.push_back(idx);
                    else if (fn) fail("instruction outside a block");
                    else if (!((op >= spv::OpTypeVoid && op <= spv::OpTypeForwardPointer) ||
                               (op >= spv::OpConstantTrue && op <= spv::OpSpecConstantOp) || op == spv::OpVariable ||
                               op == spv::OpUndef))
                        fail("opcode " + std::to_string(int(op)) + " at module scope");
                    break;
            }
        }
        if (!entry_) fail("no entry point");
    }

    const Insn& def(uint32_t id) const {
        if (id >= bound_ || def_[id] == SIZE_MAX) fail("undefined id %" + std::to_string(id));
        return insns_[def_[id]];
    }
    uint32_t deco(uint32_t id, spv::Decoration d, uint32_t otherwise = 0) const {
        auto it = deco_.find(id);
        if (it == deco_.end()) return otherwise;
        auto jt = it->second.find(d);
        return jt == it->second.end() ? otherwise : jt->second;
    }
    bool has_deco(uint32_t id, spv::Decoration d) const {
        auto it = deco_.find(id);
        return it != deco_.end() && it->second.count(d);
    }
    const std::map<uint32_t, uint32_t>* mdeco(uint32_t s, uint32_t m) const {
        auto it = mdeco_.find({s, m});
        return it == mdeco_.end() ? nullptr : &it->second;
    }
    uint32_t const_u32(uint32_t id) const {
        const Insn& c = def(id);
        if (c.op != spv::OpConstant || c.ops.size() != 1) fail("array length is not a 32-bit constant");
        return c.ops[0];
    }

    // ---- types -----------------------------------------------------------------------------------------
    std::string scalar(uint32_t t) const {
        const Insn& d = def(t);
        switch (d.op) {
            case spv::OpTypeBool: return "bool";
            case spv::OpTypeFloat:
                if (d.ops[0] != 32) fail("float width " + std::to_string(d.ops[0]));
                return "f32";
            case spv::OpTypeInt:
                if (d.ops[0] != 32) fail("integer width " + std::to_string(d.ops[0]));
                return d.ops[1] ? "i32" : "u32";
            default: fail("not a scalar type");
        }
    }

    // The WGSL type of values of SPIR-V type t (no explicit layout).
    std::string value_type(uint32_t t) const {
        const Insn& d = def(t);
        switch (d.op) {
            case spv::OpTypeBool:
            case spv::OpTypeFloat:
            case spv::OpTypeInt: return scalar(t);
            case spv::OpTypeVector: return "vec" + std::to_string(d.ops[1]) + "<" + scalar(d.ops[0]) + ">";
            case spv::OpTypeMatrix: {
                const Insn& col = def(d.ops[0]);
                return "mat" + std::to_string(d.ops[1]) + "x" + std::to_string(col.ops[1]) + "<" + scalar(col.ops[0]) + ">";
            }
            case spv::OpTypeArray:
                return "array<" + value_type(d.ops[0]) + ", " + std::to_string(const_u32(d.ops[1])) + ">";
            case spv::OpTypeStruct: return struct_name(t);
            case spv::OpTypeSampledImage:
            case spv::OpTypeImage: return "texture_2d<f32>";
            default: fail("type " + std::to_string(int(d.op)) + " as a value");
        }
    }

    const std::string& struct_name(uint32_t t) const {
        auto it = struct_names_.find(t);
        if (it == struct_names_.end()) fail("struct without a name");
        return it->second;
    }

    // WGSL's natural layout (size, alignment) of a host-shareable type.
    Layout natural(uint32_t t) const {
        const Insn& d = def(t);
        switch (d.op) {
            case spv::OpTypeFloat:
            case spv::OpTypeInt: return {4, 4};
            case spv::OpTypeVector: {
                uint32_t n = d.ops[1];
                return {4 * n, n == 2 ? 8u : 16u};
            }
            case spv::OpTypeMatrix: {
                Layout c = natural(d.ops[0]);
                uint32_t stride = (c.size + c.align - 1) / c.align * c.align;
                return {d.ops[1] * stride, c.align};
            }
            default: fail("no natural layout");
        }
    }

    // The storage representation of type t inside an explicitly laid-out block: `mstride` is the MatrixStride
    // that applies to matrices at this place (0: none). Returns the WGSL type and records its layout.
    struct Rep {
        std::string name;
        Layout layout;
    };
    Rep storage(uint32_t t, uint32_t mstride) {
        const Insn& d = def(t);
        switch (d.op) {
            case spv::OpTypeFloat:
            case spv::OpTypeInt:
            case spv::OpTypeVector: return {value_type(t), natural(t)};
            case spv::OpTypeMatrix: {
                Layout col = natural(d.ops[0]);
                uint32_t nat = (col.size + col.align - 1) / col.align * col.align;
                if (!mstride || mstride == nat) return {value_type(t), natural(t)};
                return {"array<" + stride_wrapper(value_type(d.ops[0]), col, mstride) + ", " + std::to_string(d.ops[1]) + ">",
                        {d.ops[1] * mstride, col.align}};
            }
            case spv::OpTypeArray: {
                uint32_t n = const_u32(d.ops[1]);
                Rep e = storage(d.ops[0], mstride);
                uint32_t nat = (e.layout.size + e.layout.align - 1) / e.layout.align * e.layout.align;
                uint32_t s = deco(t, spv::DecorationArrayStride, nat);
                if (s == nat) return {"array<" + e.name + ", " + std::to_string(n) + ">", {n * s, e.layout.align}};
                return {"array<" + stride_wrapper(e.name, e.layout, s) + ", " + std::to_string(n) + ">", {n * s, e.layout.align}};
            }
            case spv::OpTypeStruct: return {struct_name(t), declare_struct(t)};
            default: fail("type " + std::to_string(int(d.op)) + " in a uniform block");
        }
    }

    // A one-member struct that gives an element a stride WGSL would not: `struct W { @size(stride) v: E }`.
    std::string stride_wrapper(const std::string& elem, Layout e, uint32_t stride) {
        if (stride < e.size || stride % e.align) fail("array stride " + std::to_string(stride) + " below its element");
        auto key = elem + "@" + std::to_string(stride);
        auto it = wrappers_.find(key);
        if (it != wrappers_.end()) return it->second;
        std::string name = namer_.take("iqc_stride" + std::to_string(stride) + "_" + std::to_string(wrappers_.size()));
        wrappers_[key] = name;
        decls_ += "struct " + name + " {\n    @size(" + std::to_string(stride) + ") v: " + elem + ",\n}\n\n";
        return name;
    }
    bool array_wrapped(uint32_t t, uint32_t mstride) {
        const Insn& d = def(t);
        Rep e = storage(d.ops[0], mstride);
        uint32_t nat = (e.layout.size + e.layout.align - 1) / e.layout.align * e.layout.align;
        return deco(t, spv::DecorationArrayStride, nat) != nat;
    }
    bool matrix_padded(uint32_t t, uint32_t mstride) {
        if (!mstride) return false;
        Layout col = natural(def(t).ops[0]);
        return mstride != (col.size + col.align - 1) / col.align * col.align;
    }

    // Declares struct t (once); a struct with member Offsets keeps them exactly (@size on the member before
    // each gap). Returns its layout (for explicitly laid-out structs; {0,0} otherwise).
    Layout declare_struct(uint32_t t) {
        auto done = struct_layouts_.find(t);
        if (done != struct_layouts_.end()) return done->second;
        const Insn& d = def(t);
        const auto& members = d.ops;
        bool laid_out = !members.empty() && mdeco(t, 0) && mdeco(t, 0)->count(spv::DecorationOffset);
        std::vector<Rep> reps;
        std::vector<uint32_t> offsets;
        for (size_t m = 0; m < members.size(); ++m) {
            const auto* md = mdeco(t, uint32_t(m));
            if (md && md->count(spv::DecorationBuiltIn)) fail("built-in block member");
            if (md && md->count(spv::DecorationRowMajor)) fail("row-major matrix");
            if (laid_out) {
                if (!md || !md->count(spv::DecorationOffset)) fail("block member without an offset");
                uint32_t ms = md->count(spv::DecorationMatrixStride) ? md->at(spv::DecorationMatrixStride) : 0;
                reps.push_back(storage(members[m], ms));
                offsets.push_back(md->at(spv::DecorationOffset));
            } else {
                reps.push_back({value_type(members[m]), {}});
            }
        }
        std::string text = "struct " + struct_name(t) + " {\n";
        Layout layout;
        for (size_t m = 0; m < members.size(); ++m) {
            text += "    ";
            if (laid_out) {
                if (m == 0 && offsets[0] != 0) fail("first block member not at offset 0");
                if (offsets[m] % reps[m].layout.align) fail("block member offset below its alignment");
                if (m + 1 < members.size()) {
                    uint32_t span = offsets[m + 1] - offsets[m];
                    if (offsets[m + 1] < offsets[m] || span < reps[m].layout.size) fail("overlapping block members");
                    if (span != reps[m].layout.size) text += "@size(" + std::to_string(span) + ") ";
                }
                layout.align = std::max(layout.align, reps[m].layout.align);
            }
            text += member_names_[t][m] + ": " + reps[m].name + ",\n";
        }
        text += "}\n\n";
        if (laid_out) {
            uint32_t end = offsets.back() + reps.back().layout.size;
            layout.size = (end + layout.align - 1) / layout.align * layout.align;
        }
        decls_ += text;
        struct_layouts_[t] = layout;
        return layout;
    }

    // ---- names -----------------------------------------------------------------------------------------
    void name_things() {
        for (const char* n : {"fs_main", "vs_main", "iqc_FragmentOutput", "iqc_inverse2", "iqc_inverse3", "iqc_inverse4"})
            namer_.take(n);
        // structs first (their names are the host-visible block names), then globals, functions, the rest
        for (size_t i = 0; i < insns_.size(); ++i) {
            const Insn& in = insns_[i];
            if (in.op != spv::OpTypeStruct) continue;
            auto it = names_.find(in.result);
            struct_names_[in.result] = namer_.take(it != names_.end() && !it->second.empty() ? it->second : "S");
            Namer members;
            for (size_t m = 0; m < in.ops.size(); ++m) {
                auto jt = member_debug_.find({in.result, uint32_t(m)});
                member_names_[in.result].push_back(members.take(jt != member_debug_.end() ? jt->second : "m" + std::to_string(m)));
            }
        }
        for (size_t i = 0; i < insns_.size(); ++i) {
            const Insn& in = insns_[i];
            if (in.op == spv::OpTypeStruct) declare_struct(in.result);
        }
    }
    // An unnamed SSA value: `_` and its SPIR-V id (spirv-dis shows the same number).
    std::string temp(uint32_t id) {
        auto it = names_.find(id);
        if (it != names_.end() && !it->second.empty() && it->second != "_") return namer_.take(it->second);
        return namer_.take("_" + std::to_string(id));
    }
    std::string fresh(uint32_t id, const char* fallback) {
        auto it = names_.find(id);
        std::string want = it != names_.end() && !it->second.empty() && it->second != "_" ? it->second : fallback;
        return namer_.take(want);
    }

    // ---- values ----------------------------------------------------------------------------------------
    struct Ptr {
        std::string ref;      // a WGSL reference expression
        std::string pointer;  // the pointer value (a call argument)
        uint32_t pointee = 0;
        uint32_t mstride = 0;  // MatrixStride in effect (uniform blocks)
        bool laid_out = false;
    };

    std::string constant(uint32_t id) {
        auto it = const_text_.find(id);
        if (it != const_text_.end()) return it->second;
        const Insn& c = def(id);
        std::string s;
        switch (c.op) {
            case spv::OpConstantTrue: s = "true"; break;
            case spv::OpConstantFalse: s = "false"; break;
            case spv::OpConstant: {
                std::string sc = scalar(c.type);
                uint32_t bits = c.ops.at(0);
                if (sc == "f32") s = f32_literal(bits);
                else if (sc == "u32") s = std::to_string(bits) + "u";
                else {
                    int32_t v;
                    std::memcpy(&v, &bits, 4);
                    s = v == INT32_MIN ? "i32(-2147483648)" : v < 0 ? "(" + std::to_string(v) + "i)" : std::to_string(v) + "i";
                }
                break;
            }
            case spv::OpConstantNull: s = value_type(c.type) + "()"; break;
            case spv::OpConstantComposite: {
                s = value_type(c.type) + "(";
                for (size_t k = 0; k < c.ops.size(); ++k) s += (k ? ", " : "") + constant(c.ops[k]);
                s += ")";
                auto op = def(c.type).op;
                if (op == spv::OpTypeArray || op == spv::OpTypeStruct) {
                    std::string name = namer_.take("iqc_const_" + std::to_string(const_count_++));
                    globals_ += "const " + name + " = " + s + ";\n\n";
                    s = name;
                }
                break;
            }
            case spv::OpUndef: s = value_type(c.type) + "()"; break;
            default: fail("constant op " + std::to_string(int(c.op)));
        }
        const_text_[id] = s;
        return s;
    }

    uint32_t type_of(uint32_t id) const { return def(id).type; }

    // The text of a value id in the current function.
    std::string E(uint32_t id) {
        auto it = value_.find(id);
        if (it != value_.end()) return it->second;
        const Insn& d = def(id);
        switch (d.op) {
            case spv::OpConstant:
            case spv::OpConstantTrue:
            case spv::OpConstantFalse:
            case spv::OpConstantComposite:
            case spv::OpConstantNull:
            case spv::OpUndef: return constant(id);
            default: break;
        }
        if (ptr(id)) fail("a pointer used as a value");
        fail("value %" + std::to_string(id) + " used before its definition");
    }

    bool is_vector(uint32_t t) const { return def(t).op == spv::OpTypeVector; }
    uint32_t width_of(uint32_t t) const { return is_vector(t) ? def(t).ops[1] : 1; }
    std::string int_type(uint32_t like, bool is_signed) const {
        std::string s = is_signed ? "i32" : "u32";
        return is_vector(like) ? "vec" + std::to_string(width_of(like)) + "<" + s + ">" : s;
    }
    uint32_t scalar_of(uint32_t t) const { return is_vector(t) ? def(t).ops[0] : t; }
    bool is_signed_int(uint32_t t) const {
        const Insn& s = def(scalar_of(t));
        return s.op == spv::OpTypeInt && s.ops[1];
    }
    // Operand id as an integer of the given signedness (bitcast when its type has the other one).
    std::string as_int(uint32_t id, bool is_signed) {
        uint32_t t = type_of_value(id);
        if (is_signed_int(t) == is_signed) return E(id);
        return "bitcast<" + int_type(t, is_signed) + ">(" + E(id) + ")";
    }
    uint32_t type_of_value(uint32_t id) const {
        const Insn& d = def(id);
        return d.type;
    }

    // A pointer id: the function's own (variables, parameters, access chains) or a module-scope variable.
    const Ptr* ptr(uint32_t id) const {
        auto it = ptrs_.find(id);
        if (it != ptrs_.end()) return &it->second;
        auto jt = global_ptrs_.find(id);
        return jt == global_ptrs_.end() ? nullptr : &jt->second;
    }

    std::string load(const Ptr& p) { return load_rep(p.ref, p.pointee, p.mstride, p.laid_out); }
    std::string load_rep(const std::string& ref, uint32_t t, uint32_t mstride, bool laid_out) {
        if (!laid_out) return ref;
        const Insn& d = def(t);
        if (d.op == spv::OpTypeMatrix && matrix_padded(t, mstride)) {
            std::string s = value_type(t) + "(";
            for (uint32_t c = 0; c < d.ops[1]; ++c) s += (c ? ", " : "") + ref + "[" + std::to_string(c) + "].v";
            return s + ")";
        }
        if (d.op == spv::OpTypeArray && (array_wrapped(t, mstride) || needs_conversion(d.ops[0], mstride))) {
            uint32_t n = const_u32(d.ops[1]);
            if (n > 256) fail("a load of a whole laid-out array of " + std::to_string(n) + " elements");
            bool wrapped = array_wrapped(t, mstride);
            std::string s = value_type(t) + "(";
            for (uint32_t k = 0; k < n; ++k)
                s += (k ? ", " : "") + load_rep(ref + "[" + std::to_string(k) + "]" + (wrapped ? ".v" : ""), d.ops[0], mstride, true);
            return s + ")";
        }
        if (d.op == spv::OpTypeStruct && needs_conversion(t, mstride)) fail("a load of a whole block with strided members");
        return ref;
    }
    bool needs_conversion(uint32_t t, uint32_t mstride) {
        const Insn& d = def(t);
        if (d.op == spv::OpTypeMatrix) return matrix_padded(t, mstride);
        if (d.op == spv::OpTypeArray) return array_wrapped(t, mstride) || needs_conversion(d.ops[0], mstride);
        if (d.op == spv::OpTypeStruct) {
            for (size_t m = 0; m < d.ops.size(); ++m) {
                const auto* md = mdeco(t, uint32_t(m));
                uint32_t ms = md && md->count(spv::DecorationMatrixStride) ? md->at(spv::DecorationMatrixStride) : 0;
                if (needs_conversion(d.ops[m], ms)) return true;
            }
        }
        return false;
    }

    std::string swizzle(uint32_t k) const {
        if (k > 3) fail("vector component " + std::to_string(k));
        return std::string(".") + "xyzw"[k];
    }

    // ---- functions -------------------------------------------------------------------------------------
    struct Ctx {
        uint32_t stop = 0;          // reaching this label ends the sequence silently
        uint32_t brk = 0;           // `break` target (loop or switch merge)
        uint32_t loop_merge = 0;    // innermost loop's merge
        uint32_t cont = 0;          // innermost loop's continue target
        bool continuing = false;    // inside a continuing block
        uint32_t header = 0;        // the loop header a continuing block branches back to
    };

    Function* cur_ = nullptr;
    std::string body_;
    int depth_ = 1;
    std::unordered_set<uint32_t> hoisted_;
    std::unordered_map<uint32_t, std::vector<std::pair<uint32_t, uint32_t>>> phi_in_;  // pred label -> (phi, value)
    std::unordered_set<uint32_t> reachable_;

    void line(const std::string& s) {
        body_.append(size_t(4 * depth_), ' ');
        body_ += s;
        body_ += '\n';
    }

    // Ids an instruction reads (values and pointers; never labels or literals).
    std::vector<uint32_t> reads(const Insn& in) const {
        std::vector<uint32_t> r;
        auto all = [&](size_t from) {
            for (size_t k = from; k < in.ops.size(); ++k) r.push_back(in.ops[k]);
        };
        switch (in.op) {
            case spv::OpExtInst: all(2); break;
            case spv::OpCompositeExtract: r.push_back(in.ops[0]); break;
            case spv::OpCompositeInsert: r.push_back(in.ops[0]); r.push_back(in.ops[1]); break;
            case spv::OpVectorShuffle: r.push_back(in.ops[0]); r.push_back(in.ops[1]); break;
            case spv::OpPhi: break;  // read on the incoming edges
            case spv::OpSwitch:
            case spv::OpBranchConditional: r.push_back(in.ops[0]); break;
            case spv::OpBranch:
            case spv::OpSelectionMerge:
            case spv::OpLoopMerge: break;
            case spv::OpVariable: if (in.ops.size() > 1) r.push_back(in.ops[1]); break;
            case spv::OpLoad: r.push_back(in.ops[0]); break;
            case spv::OpStore: r.push_back(in.ops[0]); r.push_back(in.ops[1]); break;
            case spv::OpFunctionCall: all(1); break;
            case spv::OpImageFetch: r.push_back(in.ops[0]); r.push_back(in.ops[1]); all(3); break;
            default: all(0); break;
        }
        return r;
    }

    bool storable(uint32_t t) const {
        auto op = def(t).op;
        return op != spv::OpTypePointer && op != spv::OpTypeSampledImage && op != spv::OpTypeImage &&
               op != spv::OpTypeSampler && op != spv::OpTypeVoid;
    }

    void find_reachable(const Function& f) {
        reachable_ = {};
        std::vector<uint32_t> todo{f.blocks.at(0).label};
        while (!todo.empty()) {
            uint32_t l = todo.back();
            todo.pop_back();
            if (!reachable_.insert(l).second) continue;
            const Insn& t = insns_[f.blocks[f.index.at(l)].term];
            switch (t.op) {
                case spv::OpBranch: todo.push_back(t.ops[0]); break;
                case spv::OpBranchConditional: todo.push_back(t.ops[1]); todo.push_back(t.ops[2]); break;
                case spv::OpSwitch:
                    todo.push_back(t.ops[1]);
                    for (size_t k = 3; k < t.ops.size(); k += 2) todo.push_back(t.ops[k]);
                    break;
                default: break;
            }
        }
    }

    std::string function(Function& f) {
        cur_ = &f;
        body_.clear();
        depth_ = 1;
        // fresh containers, not clear(): clearing keeps (and wipes) every bucket a large function grew, per
        // function — quadratic in a module of thousands of functions
        hoisted_ = {};
        phi_in_ = {};
        if (f.blocks.empty()) fail("function without a body");
        for (const Block& b : f.blocks)
            if (b.term == SIZE_MAX) fail("block without a terminator");
        find_reachable(f);
        const Insn& fd = insns_[f.def];
        std::string fname = fn_name(fd.result);
        std::string sig = "fn " + fname + "(";
        for (size_t k = 0; k < f.params.size(); ++k) {
            const Insn& p = insns_[f.params[k]];
            std::string n = fresh(p.result, "arg");
            const Insn& pt = def(p.type);
            if (pt.op == spv::OpTypePointer) {
                std::string space = pt.ops[0] == spv::StorageClassFunction ? "function"
                                    : pt.ops[0] == spv::StorageClassPrivate ? "private"
                                                                             : "";
                if (space.empty()) fail("pointer parameter in storage class " + std::to_string(pt.ops[0]));
                sig += (k ? ", " : "") + n + ": ptr<" + space + ", " + value_type(pt.ops[1]) + ">";
                ptrs_[p.result] = {"(*" + n + ")", n, pt.ops[1], 0, false};
            } else {
                sig += (k ? ", " : "") + n + ": " + value_type(p.type);
                value_[p.result] = n;
            }
        }
        sig += ")";
        uint32_t ret = fd.type;
        if (def(ret).op != spv::OpTypeVoid) sig += " -> " + value_type(ret);

        // Which values another block reads (function-scope vars) and the phis' incoming edges.
        std::unordered_map<uint32_t, uint32_t> def_block;
        // Per id: the one block that reads it, or `many` (constant time per use: a function of thousands of
        // blocks reads the same globals in each).
        struct Uses {
            uint32_t block = 0;
            bool many = false;
            void add(uint32_t b) {
                if (!block) block = b;
                else if (block != b) many = true;
            }
            void add(const Uses& o) {
                if (o.block) add(o.block);
                many |= o.many;
            }
        };
        std::unordered_map<uint32_t, Uses> use_blocks;
        std::vector<size_t> chains;
        for (const Block& b : f.blocks) {
            std::vector<size_t> all = b.body;
            all.push_back(b.term);
            for (size_t i : all) {
                const Insn& in = insns_[i];
                if (in.result) def_block[in.result] = b.label;
                for (uint32_t id : reads(in)) use_blocks[id].add(b.label);
                if (in.op == spv::OpAccessChain || in.op == spv::OpInBoundsAccessChain || in.op == spv::OpCopyObject ||
                    in.op == spv::OpLoad || in.op == spv::OpImage || in.op == spv::OpSampledImage)
                    chains.push_back(i);
                if (in.op == spv::OpPhi)
                    for (size_t k = 0; k + 1 < in.ops.size(); k += 2) {
                        phi_in_[in.ops[k + 1]].push_back({in.result, in.ops[k]});
                        use_blocks[in.ops[k]].add(in.ops[k + 1]);
                    }
            }
        }
        // Pointers and images are inlined at their uses: their operands are read where they are used.
        for (auto it = chains.rbegin(); it != chains.rend(); ++it) {
            const Insn& in = insns_[*it];
            if (storable(in.type)) continue;
            Uses uses = use_blocks[in.result];
            for (uint32_t id : reads(in)) use_blocks[id].add(uses);
        }
        std::string decls;
        for (const Block& b : f.blocks) {
            for (size_t i : b.body) {
                const Insn& in = insns_[i];
                if (in.op == spv::OpVariable) {
                    if (in.ops[0] != spv::StorageClassFunction) fail("local variable in storage class " + std::to_string(in.ops[0]));
                    const Insn& pt = def(in.type);
                    std::string n = fresh(in.result, "v");
                    decls += "    var " + n + ": " + value_type(pt.ops[1]);
                    if (in.ops.size() > 1) decls += " = " + constant(in.ops[1]);
                    decls += ";\n";
                    ptrs_[in.result] = {n, "&" + n, pt.ops[1], 0, false};
                    continue;
                }
                if (!in.result || !storable(in.type) || in.op == spv::OpAccessChain) continue;
                bool phi = in.op == spv::OpPhi;
                const Uses& u = use_blocks[in.result];
                bool cross = u.many || (u.block && u.block != b.label);
                if (phi || cross) {
                    std::string n = phi ? fresh(in.result, "phi") : temp(in.result);
                    decls += "    var " + n + ": " + value_type(in.type) + ";\n";
                    value_[in.result] = n;
                    hoisted_.insert(in.result);
                }
            }
        }
        std::string out = sig + " {\n" + decls;
        Ctx ctx;
        seq(f.blocks[0].label, ctx);
        out += body_;
        out += "}\n\n";
        return out;
    }

    std::string fn_name(uint32_t id) {
        auto it = fn_names_.find(id);
        if (it != fn_names_.end()) return it->second;
        std::string n = fresh(id, "f");
        fn_names_[id] = n;
        return n;
    }

    const Block& block(uint32_t label) const {
        auto it = cur_->index.find(label);
        if (it == cur_->index.end()) fail("branch to an unknown label");
        return cur_->blocks[it->second];
    }

    // Emits the blocks from `label` on until the sequence ends (a return, a break/continue, or `ctx.stop`).
    void seq(uint32_t label, const Ctx& ctx) {
        for (int guard = 0;; ++guard) {
            if (guard > 1'000'000) fail("control flow does not end");
            if (label == ctx.stop) return;
            if (!reachable_.count(label)) return;
            const Block& b = block(label);
            const Insn& t = insns_[b.term];
            const Insn* merge = b.merge == SIZE_MAX ? nullptr : &insns_[b.merge];
            if (merge && merge->op == spv::OpLoopMerge) {
                loop(b, *merge);
                uint32_t next = 0;
                if (!jump(merge->ops[0], ctx, next)) return;
                label = next;
                continue;
            }
            for (size_t i : b.body) statement(insns_[i]);
            phis_for(b.label);
            if (merge && merge->op == spv::OpSelectionMerge) {
                uint32_t m = merge->ops[0];
                Ctx inner = ctx;
                inner.stop = m;
                if (t.op == spv::OpBranchConditional) {
                    uint32_t a = t.ops[1], c = t.ops[2];
                    if (a == c) {
                        line("{");
                        nested(a, inner);
                        line("}");
                    } else if (a == m) {
                        line("if !(" + E(t.ops[0]) + ") {");
                        nested(c, inner);
                        line("}");
                    } else {
                        line("if " + E(t.ops[0]) + " {");
                        nested(a, inner);
                        if (c != m) {
                            line("} else {");
                            nested(c, inner);
                        }
                        line("}");
                    }
                } else if (t.op == spv::OpSwitch) {
                    switch_(t, inner, m);
                } else {
                    fail("selection merge before an unconditional branch");
                }
                uint32_t next = 0;
                if (!jump(m, ctx, next)) return;
                label = next;
                continue;
            }
            uint32_t next = 0;
            if (!branch(t, ctx, next)) return;
            label = next;
        }
    }

    // A terminator without a merge: writes what leaves (return, discard, break, continue, `break if`, an if
    // around either) and returns false when the sequence ends, or returns true with `next` set where it goes on.
    bool branch(const Insn& t, const Ctx& ctx, uint32_t& next) {
        switch (t.op) {
            case spv::OpReturn: line("return;"); return false;
            case spv::OpReturnValue: line("return " + E(t.ops[0]) + ";"); return false;
            case spv::OpKill: line("discard;"); return false;
            case spv::OpUnreachable: return false;
            case spv::OpBranch: return jump(t.ops[0], ctx, next);
            case spv::OpBranchConditional: {
                std::string cond = E(t.ops[0]);
                uint32_t a = t.ops[1], c = t.ops[2];
                if (ctx.continuing && (a == ctx.header || c == ctx.header)) {
                    // the back edge of a loop: `break if` ends the continuing block
                    uint32_t other = a == ctx.header ? c : a;
                    if (other != ctx.loop_merge) fail("continuing block branches elsewhere than its loop");
                    line(a == ctx.header ? "break if !(" + cond + ");" : "break if " + cond + ";");
                    return false;
                }
                if (a == c) {
                    next = a;
                    return true;
                }
                bool exit_a = exits(a, ctx), exit_c = exits(c, ctx);
                if (exit_a && exit_c) {
                    line("if " + cond + " {");
                    leave(a, ctx);
                    line("} else {");
                    leave(c, ctx);
                    line("}");
                    return false;
                }
                if (!exit_a && !exit_c) fail("a conditional branch without a merge that leaves no construct");
                uint32_t out = exit_a ? a : c, stay = exit_a ? c : a;
                if (out == ctx.stop) {
                    // leaving the construct silently: the rest runs only on the other edge
                    line("if " + (exit_a ? "!(" + cond + ")" : cond) + " {");
                    nested(stay, ctx);
                    line("}");
                    return false;
                }
                line("if " + (exit_a ? cond : "!(" + cond + ")") + " {");
                leave(out, ctx);
                line("}");
                next = stay;
                return true;
            }
            default: fail("terminator " + std::to_string(int(t.op)));
        }
    }

    // The statement that leaves for `target` (break, continue, or nothing at the construct's end), one level in.
    void leave(uint32_t target, const Ctx& ctx) {
        ++depth_;
        uint32_t unused = 0;
        jump(target, ctx, unused);
        --depth_;
    }

    void nested(uint32_t label, const Ctx& ctx) {
        ++depth_;
        seq(label, ctx);
        --depth_;
    }

    bool exits(uint32_t target, const Ctx& ctx) const {
        return target == ctx.stop || (ctx.brk && target == ctx.brk) || (ctx.loop_merge && target == ctx.loop_merge) ||
               (ctx.cont && target == ctx.cont);
    }

    // A branch to `target`: writes the statement that leaves (break/continue) and returns false, or returns
    // true with `next` set when the sequence goes on at target.
    bool jump(uint32_t target, const Ctx& ctx, uint32_t& next) {
        if (target == ctx.stop) return false;
        if (ctx.brk && target == ctx.brk) {
            if (ctx.continuing) fail("break inside a continuing block");
            line("break;");
            return false;
        }
        if (ctx.loop_merge && target == ctx.loop_merge) fail("a branch out of a loop from inside a switch");
        if (ctx.cont && target == ctx.cont) {
            if (ctx.continuing) fail("continue inside a continuing block");
            line("continue;");
            return false;
        }
        next = target;
        return true;
    }

    // A loop: the header's instructions run on every iteration, inside `loop { }`; the continue construct is
    // the `continuing` block, whose back edge ends in `break if`. Edges into the header from before the loop
    // set its phis in their predecessor.
    void loop(const Block& header, const Insn& merge) {
        uint32_t m = merge.ops[0], c = merge.ops[1];
        line("loop {");
        ++depth_;
        for (size_t i : header.body) statement(insns_[i]);
        Ctx in;
        in.stop = c;
        in.brk = m;
        in.loop_merge = m;
        in.cont = c;
        const Insn& t = insns_[header.term];
        phis_for(header.label);
        Ctx cc;  // the continue construct: it ends at the back edge to the header
        cc.continuing = true;
        cc.header = header.label;
        cc.loop_merge = m;
        cc.stop = header.label;
        uint32_t next = 0;
        if (c == header.label) {
            // a single-block loop: the header is its own continue target, its terminator the back edge
            line("continuing {");
            ++depth_;
            branch(t, cc, next);
            --depth_;
            line("}");
        } else {
            // the header's terminator, then the body up to the continue target
            if (branch(t, in, next)) seq(next, in);
            if (reachable_.count(c)) {
                line("continuing {");
                ++depth_;
                seq(c, cc);
                --depth_;
                line("}");
            }
        }
        --depth_;
        line("}");
    }

    void switch_(const Insn& t, const Ctx& inner, uint32_t m) {
        Ctx sc = inner;
        sc.brk = m;
        std::string sel = E(t.ops[0]);
        bool is_signed = is_signed_int(type_of_value(t.ops[0]));
        std::map<uint32_t, std::vector<std::string>> cases;  // label -> literals
        std::vector<uint32_t> order;
        for (size_t k = 2; k + 1 < t.ops.size(); k += 2) {
            uint32_t l = t.ops[k + 1];
            if (!cases.count(l)) order.push_back(l);
            int32_t v;
            std::memcpy(&v, &t.ops[k], 4);
            cases[l].push_back(is_signed ? (v == INT32_MIN ? "i32(-2147483648)" : std::to_string(v) + "i") : std::to_string(t.ops[k]) + "u");
        }
        uint32_t dflt = t.ops[1];
        line("switch " + sel + " {");
        ++depth_;
        for (uint32_t l : order) {
            std::string lits;
            for (const auto& s : cases[l]) lits += (lits.empty() ? "" : ", ") + s;
            if (l == dflt) lits += ", default";
            line("case " + lits + ": {");
            nested(l, sc);
            line("}");
        }
        if (!cases.count(dflt)) {
            line("default: {");
            if (dflt != m) nested(dflt, sc);
            line("}");
        }
        --depth_;
        line("}");
    }

    // Sets the phi variables of the successors of `pred` (all incoming values read before any is written).
    void phis_for(uint32_t pred) {
        auto it = phi_in_.find(pred);
        if (it == phi_in_.end()) return;
        const auto& list = it->second;
        if (list.size() == 1) {
            line(value_.at(list[0].first) + " = " + E(list[0].second) + ";");
            return;
        }
        std::vector<std::string> tmp;
        for (const auto& [phi, v] : list) {
            std::string n = namer_.take("phi_in");
            line("let " + n + " = " + E(v) + ";");
            tmp.push_back(n);
        }
        for (size_t k = 0; k < list.size(); ++k) line(value_.at(list[k].first) + " = " + tmp[k] + ";");
    }

    void define(const Insn& in, const std::string& text) {
        if (hoisted_.count(in.result)) {
            line(value_.at(in.result) + " = " + text + ";");
            return;
        }
        std::string n = temp(in.result);
        line("let " + n + " = " + text + ";");
        value_[in.result] = n;
    }

    // A value built from a copy with one part replaced (OpCompositeInsert, OpVectorInsertDynamic).
    void define_modified(const Insn& in, const std::string& base, const std::string& part, const std::string& obj) {
        std::string n;
        if (hoisted_.count(in.result)) {
            n = value_.at(in.result);
            line(n + " = " + base + ";");
        } else {
            n = temp(in.result);
            line("var " + n + " = " + base + ";");
            value_[in.result] = n;
        }
        line(n + part + " = " + obj + ";");
    }

    std::string part_path(uint32_t type, const std::vector<uint32_t>& idx, size_t from) {
        std::string s;
        uint32_t t = type;
        for (size_t k = from; k < idx.size(); ++k) {
            const Insn& d = def(t);
            switch (d.op) {
                case spv::OpTypeVector: s += swizzle(idx[k]); t = d.ops[0]; break;
                case spv::OpTypeMatrix: s += "[" + std::to_string(idx[k]) + "]"; t = d.ops[0]; break;
                case spv::OpTypeArray: s += "[" + std::to_string(idx[k]) + "]"; t = d.ops[0]; break;
                case spv::OpTypeStruct: s += "." + member_names_.at(t).at(idx[k]); t = d.ops.at(idx[k]); break;
                default: fail("composite index into a scalar");
            }
        }
        return s;
    }

    void statement(const Insn& in) {
        auto bin = [&](const char* op) { define(in, E(in.ops[0]) + " " + op + " " + E(in.ops[1])); };
        auto ibin = [&](const char* op, bool is_signed) {
            std::string s = as_int(in.ops[0], is_signed) + " " + op + " " + as_int(in.ops[1], is_signed);
            if (is_signed_int(in.type) != is_signed) s = "bitcast<" + value_type(in.type) + ">(" + s + ")";
            define(in, s);
        };
        auto icmp = [&](const char* op, bool is_signed) {
            define(in, as_int(in.ops[0], is_signed) + " " + op + " " + as_int(in.ops[1], is_signed));
        };
        auto logical = [&](const char* scalar_op, const char* vector_op) {
            define(in, E(in.ops[0]) + " " + (is_vector(in.type) ? vector_op : scalar_op) + " " + E(in.ops[1]));
        };
        auto call = [&](const std::string& f, size_t from) {
            std::string s = f + "(";
            for (size_t k = from; k < in.ops.size(); ++k) s += (k > from ? ", " : "") + E(in.ops[k]);
            define(in, s + ")");
        };
        switch (in.op) {
            case spv::OpVariable: return;  // declared at the top of the function
            case spv::OpPhi: return;       // set on the incoming edges
            case spv::OpAccessChain:
            case spv::OpInBoundsAccessChain: {
                const Ptr* base = ptr(in.ops[0]);
                if (!base) fail("access chain from an unknown pointer");
                Ptr p = *base;
                for (size_t k = 1; k < in.ops.size(); ++k) {
                    uint32_t idx = in.ops[k];
                    const Insn& d = def(p.pointee);
                    switch (d.op) {
                        case spv::OpTypeStruct: {
                            uint32_t m = const_u32(idx);
                            const auto* md = mdeco(p.pointee, m);
                            p.ref += "." + member_names_.at(p.pointee).at(m);
                            p.mstride = md && md->count(spv::DecorationMatrixStride) ? md->at(spv::DecorationMatrixStride) : 0;
                            p.pointee = d.ops.at(m);
                            break;
                        }
                        case spv::OpTypeArray: {
                            bool wrapped = p.laid_out && array_wrapped(p.pointee, p.mstride);
                            p.ref += "[" + E(idx) + "]" + (wrapped ? ".v" : "");
                            p.pointee = d.ops[0];
                            break;
                        }
                        case spv::OpTypeMatrix: {
                            bool padded = p.laid_out && matrix_padded(p.pointee, p.mstride);
                            p.ref += "[" + E(idx) + "]" + (padded ? ".v" : "");
                            p.pointee = d.ops[0];
                            break;
                        }
                        case spv::OpTypeVector: {
                            const Insn& id = def(idx);
                            if (id.op == spv::OpConstant) p.ref += swizzle(id.ops[0]);
                            else p.ref += "[" + E(idx) + "]";
                            p.pointee = d.ops[0];
                            break;
                        }
                        default: fail("access chain into a scalar");
                    }
                }
                p.pointer = "&" + p.ref;
                ptrs_[in.result] = p;
                return;
            }
            case spv::OpLoad: {
                const Ptr* it = ptr(in.ops[0]);
                if (!it) fail("load through an unknown pointer");
                if (!storable(in.type)) {
                    value_[in.result] = it->ref;  // a texture: used by name
                    return;
                }
                define(in, load(*it));
                return;
            }
            case spv::OpStore: {
                const Ptr* it = ptr(in.ops[0]);
                if (!it) fail("store through an unknown pointer");
                if (it->laid_out) fail("store into a uniform block");
                line(it->ref + " = " + E(in.ops[1]) + ";");
                return;
            }
            case spv::OpCopyObject:
                if (const Ptr* q = ptr(in.ops[0])) ptrs_[in.result] = *q;
                else define(in, E(in.ops[0]));
                return;
            case spv::OpImage:
            case spv::OpSampledImage: value_[in.result] = E(in.ops[0]); return;
            case spv::OpImageFetch: {
                std::string lod = "0";
                if (in.ops.size() > 2) {
                    if (in.ops[2] != spv::ImageOperandsLodMask || in.ops.size() != 4) fail("image operands of a fetch");
                    lod = E(in.ops[3]);
                }
                define(in, "textureLoad(" + E(in.ops[0]) + ", " + E(in.ops[1]) + ", " + lod + ")");
                return;
            }
            case spv::OpFunctionCall: {
                std::string s = fn_name(in.ops[0]) + "(";
                for (size_t k = 1; k < in.ops.size(); ++k) {
                    const Ptr* q = ptr(in.ops[k]);
                    s += (k > 1 ? ", " : "") + (q ? q->pointer : E(in.ops[k]));
                }
                s += ")";
                if (def(in.type).op == spv::OpTypeVoid) line(s + ";");
                else define(in, s);
                return;
            }
            case spv::OpUndef: define(in, value_type(in.type) + "()"); return;
            case spv::OpCompositeConstruct: call(value_type(in.type), 0); return;
            case spv::OpCompositeExtract:
                define(in, E(in.ops[0]) + part_path(type_of_value(in.ops[0]), in.ops, 1));
                return;
            case spv::OpCompositeInsert:
                define_modified(in, E(in.ops[1]), part_path(in.type, in.ops, 2), E(in.ops[0]));
                return;
            case spv::OpVectorExtractDynamic: define(in, E(in.ops[0]) + "[" + E(in.ops[1]) + "]"); return;
            case spv::OpVectorInsertDynamic:
                define_modified(in, E(in.ops[0]), "[" + E(in.ops[2]) + "]", E(in.ops[1]));
                return;
            case spv::OpVectorShuffle: {
                uint32_t n1 = width_of(type_of_value(in.ops[0]));
                bool from_first = true;
                for (size_t k = 2; k < in.ops.size(); ++k) from_first &= in.ops[k] < n1;
                if (from_first) {
                    std::string s = E(in.ops[0]) + ".";
                    for (size_t k = 2; k < in.ops.size(); ++k) s += "xyzw"[in.ops[k]];
                    define(in, s);
                    return;
                }
                std::string s = value_type(in.type) + "(";
                for (size_t k = 2; k < in.ops.size(); ++k) {
                    uint32_t c = in.ops[k];
                    std::string part = c == 0xffffffffu ? value_type(scalar_of(in.type)) + "()"
                                       : c < n1         ? E(in.ops[0]) + swizzle(c)
                                                        : E(in.ops[1]) + swizzle(c - n1);
                    s += (k > 2 ? ", " : "") + part;
                }
                define(in, s + ")");
                return;
            }
            case spv::OpFAdd: bin("+"); return;
            case spv::OpFSub: bin("-"); return;
            case spv::OpFMul:
            case spv::OpVectorTimesScalar:
            case spv::OpMatrixTimesScalar:
            case spv::OpVectorTimesMatrix:
            case spv::OpMatrixTimesVector:
            case spv::OpMatrixTimesMatrix: bin("*"); return;
            case spv::OpFDiv: bin("/"); return;
            case spv::OpFRem: bin("%"); return;
            case spv::OpFMod: {
                // GLSL's mod: x - y floor(x / y) (the sign of y)
                std::string x = E(in.ops[0]), y = E(in.ops[1]);
                define(in, x + " - " + y + " * floor(" + x + " / " + y + ")");
                return;
            }
            case spv::OpFNegate: define(in, "-" + E(in.ops[0])); return;
            case spv::OpIAdd: ibin("+", is_signed_int(in.type)); return;
            case spv::OpISub: ibin("-", is_signed_int(in.type)); return;
            case spv::OpIMul: ibin("*", is_signed_int(in.type)); return;
            case spv::OpSDiv: ibin("/", true); return;
            case spv::OpUDiv: ibin("/", false); return;
            case spv::OpSRem: ibin("%", true); return;
            // glslang writes OpSMod for GLSL's integer %, whose result GLSL leaves undefined for negative operands
            case spv::OpSMod: ibin("%", true); return;
            case spv::OpUMod: ibin("%", false); return;
            case spv::OpSNegate: define(in, "-" + as_int(in.ops[0], true)); return;
            case spv::OpNot: define(in, "~" + E(in.ops[0])); return;
            case spv::OpBitwiseAnd: ibin("&", is_signed_int(in.type)); return;
            case spv::OpBitwiseOr: ibin("|", is_signed_int(in.type)); return;
            case spv::OpBitwiseXor: ibin("^", is_signed_int(in.type)); return;
            case spv::OpShiftLeftLogical:
            case spv::OpShiftRightLogical:
            case spv::OpShiftRightArithmetic: {
                bool is_signed = in.op == spv::OpShiftRightArithmetic ||
                                 (in.op == spv::OpShiftLeftLogical && is_signed_int(in.type));
                std::string s = as_int(in.ops[0], is_signed) + (in.op == spv::OpShiftLeftLogical ? " << " : " >> ") +
                                as_int(in.ops[1], false);
                if (is_signed_int(in.type) != is_signed) s = "bitcast<" + value_type(in.type) + ">(" + s + ")";
                define(in, s);
                return;
            }
            case spv::OpIEqual: icmp("==", is_signed_int(type_of_value(in.ops[0]))); return;
            case spv::OpINotEqual: icmp("!=", is_signed_int(type_of_value(in.ops[0]))); return;
            case spv::OpSLessThan: icmp("<", true); return;
            case spv::OpSLessThanEqual: icmp("<=", true); return;
            case spv::OpSGreaterThan: icmp(">", true); return;
            case spv::OpSGreaterThanEqual: icmp(">=", true); return;
            case spv::OpULessThan: icmp("<", false); return;
            case spv::OpULessThanEqual: icmp("<=", false); return;
            case spv::OpUGreaterThan: icmp(">", false); return;
            case spv::OpUGreaterThanEqual: icmp(">=", false); return;
            case spv::OpFOrdEqual:
            case spv::OpFUnordEqual: bin("=="); return;
            case spv::OpFOrdNotEqual:
            case spv::OpFUnordNotEqual: bin("!="); return;
            case spv::OpFOrdLessThan:
            case spv::OpFUnordLessThan: bin("<"); return;
            case spv::OpFOrdLessThanEqual:
            case spv::OpFUnordLessThanEqual: bin("<="); return;
            case spv::OpFOrdGreaterThan:
            case spv::OpFUnordGreaterThan: bin(">"); return;
            case spv::OpFOrdGreaterThanEqual:
            case spv::OpFUnordGreaterThanEqual: bin(">="); return;
            case spv::OpLogicalAnd: logical("&&", "&"); return;
            case spv::OpLogicalOr: logical("||", "|"); return;
            case spv::OpLogicalEqual: bin("=="); return;
            case spv::OpLogicalNotEqual: bin("!="); return;
            case spv::OpLogicalNot: define(in, "!" + E(in.ops[0])); return;
            case spv::OpSelect: define(in, "select(" + E(in.ops[2]) + ", " + E(in.ops[1]) + ", " + E(in.ops[0]) + ")"); return;
            case spv::OpAny: call("any", 0); return;
            case spv::OpAll: call("all", 0); return;
            case spv::OpIsNan: define(in, E(in.ops[0]) + " != " + E(in.ops[0])); return;
            case spv::OpIsInf: define(in, "abs(" + E(in.ops[0]) + ") > bitcast<f32>(0x7f7fffffu)"); return;
            case spv::OpDot: call("dot", 0); return;
            case spv::OpTranspose: call("transpose", 0); return;
            case spv::OpOuterProduct: {
                uint32_t n = width_of(type_of_value(in.ops[1]));
                std::string s = value_type(in.type) + "(";
                for (uint32_t c = 0; c < n; ++c) s += (c ? ", " : "") + E(in.ops[0]) + " * " + E(in.ops[1]) + swizzle(c);
                define(in, s + ")");
                return;
            }
            case spv::OpConvertFToS:
            case spv::OpConvertFToU:
            case spv::OpConvertSToF:
            case spv::OpConvertUToF:
            case spv::OpFConvert:
            case spv::OpSConvert:
            case spv::OpUConvert: call(value_type(in.type), 0); return;
            case spv::OpBitcast: define(in, "bitcast<" + value_type(in.type) + ">(" + E(in.ops[0]) + ")"); return;
            case spv::OpDPdx: derivatives_ = true; call("dpdx", 0); return;
            case spv::OpDPdy: derivatives_ = true; call("dpdy", 0); return;
            case spv::OpFwidth: derivatives_ = true; call("fwidth", 0); return;
            case spv::OpDPdxFine: derivatives_ = true; call("dpdxFine", 0); return;
            case spv::OpDPdyFine: derivatives_ = true; call("dpdyFine", 0); return;
            case spv::OpFwidthFine: derivatives_ = true; call("fwidthFine", 0); return;
            case spv::OpDPdxCoarse: derivatives_ = true; call("dpdxCoarse", 0); return;
            case spv::OpDPdyCoarse: derivatives_ = true; call("dpdyCoarse", 0); return;
            case spv::OpFwidthCoarse: derivatives_ = true; call("fwidthCoarse", 0); return;
            case spv::OpExtInst: ext(in); return;
            default: fail("opcode " + std::to_string(int(in.op)));
        }
    }

    void ext(const Insn& in) {
        if (in.ops[0] != glsl_set_) fail("extended instruction from an unknown set");
        auto args = [&](size_t n) {
            if (in.ops.size() != 2 + n) fail("extended instruction arity");
            std::string s;
            for (size_t k = 0; k < n; ++k) s += (k ? ", " : "") + E(in.ops[2 + k]);
            return s;
        };
        auto f = [&](const char* name, size_t n) { define(in, std::string(name) + "(" + args(n) + ")"); };
        switch (GLSLstd450(in.ops[1])) {
            case GLSLstd450Round:
            case GLSLstd450RoundEven: f("round", 1); return;
            case GLSLstd450Trunc: f("trunc", 1); return;
            case GLSLstd450FAbs:
            case GLSLstd450SAbs: f("abs", 1); return;
            case GLSLstd450FSign:
            case GLSLstd450SSign: f("sign", 1); return;
            case GLSLstd450Floor: f("floor", 1); return;
            case GLSLstd450Ceil: f("ceil", 1); return;
            case GLSLstd450Fract: f("fract", 1); return;
            case GLSLstd450Radians: f("radians", 1); return;
            case GLSLstd450Degrees: f("degrees", 1); return;
            case GLSLstd450Sin: f("sin", 1); return;
            case GLSLstd450Cos: f("cos", 1); return;
            case GLSLstd450Tan: f("tan", 1); return;
            case GLSLstd450Asin: f("asin", 1); return;
            case GLSLstd450Acos: f("acos", 1); return;
            case GLSLstd450Atan: f("atan", 1); return;
            case GLSLstd450Sinh: f("sinh", 1); return;
            case GLSLstd450Cosh: f("cosh", 1); return;
            case GLSLstd450Tanh: f("tanh", 1); return;
            case GLSLstd450Asinh: f("asinh", 1); return;
            case GLSLstd450Acosh: f("acosh", 1); return;
            case GLSLstd450Atanh: f("atanh", 1); return;
            case GLSLstd450Atan2: f("atan2", 2); return;
            case GLSLstd450Pow: f("pow", 2); return;
            case GLSLstd450Exp: f("exp", 1); return;
            case GLSLstd450Log: f("log", 1); return;
            case GLSLstd450Exp2: f("exp2", 1); return;
            case GLSLstd450Log2: f("log2", 1); return;
            case GLSLstd450Sqrt: f("sqrt", 1); return;
            case GLSLstd450InverseSqrt: f("inverseSqrt", 1); return;
            case GLSLstd450Determinant: f("determinant", 1); return;
            case GLSLstd450MatrixInverse: {
                uint32_t n = def(in.type).ops[1];
                inverse_helper(n);
                f(n == 2 ? "iqc_inverse2" : n == 3 ? "iqc_inverse3" : "iqc_inverse4", 1);
                return;
            }
            case GLSLstd450FMin:
            case GLSLstd450UMin:
            case GLSLstd450SMin:
            case GLSLstd450NMin: f("min", 2); return;
            case GLSLstd450FMax:
            case GLSLstd450UMax:
            case GLSLstd450SMax:
            case GLSLstd450NMax: f("max", 2); return;
            case GLSLstd450FClamp:
            case GLSLstd450UClamp:
            case GLSLstd450SClamp:
            case GLSLstd450NClamp: f("clamp", 3); return;
            case GLSLstd450FMix: f("mix", 3); return;
            case GLSLstd450Step: f("step", 2); return;
            case GLSLstd450SmoothStep: f("smoothstep", 3); return;
            case GLSLstd450Fma: f("fma", 3); return;
            case GLSLstd450Ldexp: f("ldexp", 2); return;
            case GLSLstd450Length: f("length", 1); return;
            case GLSLstd450Distance: f("distance", 2); return;
            case GLSLstd450Cross: f("cross", 2); return;
            case GLSLstd450Normalize: f("normalize", 1); return;
            case GLSLstd450FaceForward: f("faceForward", 3); return;
            case GLSLstd450Reflect: f("reflect", 2); return;
            case GLSLstd450Refract: f("refract", 3); return;
            default: fail("GLSL.std.450 instruction " + std::to_string(in.ops[1]));
        }
    }

    // Matrix inverses (WGSL has none): the adjugate over the determinant (Cramer's rule).
    void inverse_helper(uint32_t n) {
        if (inverses_.count(n)) return;
        inverses_.insert(n);
        if (n == 2) {
            helpers_ +=
                "fn iqc_inverse2(m: mat2x2<f32>) -> mat2x2<f32> {\n"
                "    return mat2x2<f32>(m[1][1], -m[0][1], -m[1][0], m[0][0]) * (1.0f / determinant(m));\n"
                "}\n\n";
        } else if (n == 3) {
            helpers_ +=
                "fn iqc_inverse3(m: mat3x3<f32>) -> mat3x3<f32> {\n"
                "    let r0 = cross(m[1], m[2]);\n"
                "    let r1 = cross(m[2], m[0]);\n"
                "    let r2 = cross(m[0], m[1]);\n"
                "    return transpose(mat3x3<f32>(r0, r1, r2)) * (1.0f / dot(m[0], r0));\n"
                "}\n\n";
        } else if (n == 4) {
            // the 2x2 sub-determinants of the first two and last two columns (Laplace expansion)
            helpers_ +=
                "fn iqc_inverse4(m: mat4x4<f32>) -> mat4x4<f32> {\n"
                "    let a = m[0]; let b = m[1]; let c = m[2]; let d = m[3];\n"
                "    let s0 = a.x * b.y - b.x * a.y; let s1 = a.x * b.z - b.x * a.z; let s2 = a.x * b.w - b.x * a.w;\n"
                "    let s3 = a.y * b.z - b.y * a.z; let s4 = a.y * b.w - b.y * a.w; let s5 = a.z * b.w - b.z * a.w;\n"
                "    let c5 = c.z * d.w - d.z * c.w; let c4 = c.y * d.w - d.y * c.w; let c3 = c.y * d.z - d.y * c.z;\n"
                "    let c2 = c.x * d.w - d.x * c.w; let c1 = c.x * d.z - d.x * c.z; let c0 = c.x * d.y - d.x * c.y;\n"
                "    let inv = 1.0f / (s0 * c5 - s1 * c4 + s2 * c3 + s3 * c2 - s4 * c1 + s5 * c0);\n"
                "    return mat4x4<f32>(\n"
                "        vec4<f32>(b.y * c5 - b.z * c4 + b.w * c3, -a.y * c5 + a.z * c4 - a.w * c3,\n"
                "                  d.y * s5 - d.z * s4 + d.w * s3, -c.y * s5 + c.z * s4 - c.w * s3),\n"
                "        vec4<f32>(-b.x * c5 + b.z * c2 - b.w * c1, a.x * c5 - a.z * c2 + a.w * c1,\n"
                "                  -d.x * s5 + d.z * s2 - d.w * s1, c.x * s5 - c.z * s2 + c.w * s1),\n"
                "        vec4<f32>(b.x * c4 - b.y * c2 + b.w * c0, -a.x * c4 + a.y * c2 - a.w * c0,\n"
                "                  d.x * s4 - d.y * s2 + d.w * s0, -c.x * s4 + c.y * s2 - c.w * s0),\n"
                "        vec4<f32>(-b.x * c3 + b.y * c1 - b.z * c0, a.x * c3 - a.y * c1 + a.z * c0,\n"
                "                  -d.x * s3 + d.y * s1 - d.z * s0, c.x * s3 - c.y * s1 + c.z * s0)) * inv;\n"
                "}\n\n";
        } else {
            fail("inverse of a " + std::to_string(n) + "x" + std::to_string(n) + " matrix");
        }
    }

    // ---- module-scope variables and the entry point -----------------------------------------------------
    void global_vars() {
        for (size_t i = 0; i < insns_.size(); ++i) {
            const Insn& in = insns_[i];
            if (in.op != spv::OpVariable) continue;
            auto sc = spv::StorageClass(in.ops[0]);
            if (sc == spv::StorageClassFunction) continue;
            const Insn& pt = def(in.type);
            uint32_t t = pt.ops[1];
            switch (sc) {
                case spv::StorageClassInput:
                case spv::StorageClassOutput:
                case spv::StorageClassPrivate: {
                    std::string n = fresh(in.result, "g");
                    globals_ += "var<private> " + n + ": " + value_type(t);
                    if (in.ops.size() > 1) globals_ += " = " + constant(in.ops[1]);
                    globals_ += ";\n";
                    global_ptrs_[in.result] = {n, "&" + n, t, 0, false};
                    if (sc != spv::StorageClassPrivate) io_.push_back({in.result, n, t, sc});
                    break;
                }
                case spv::StorageClassUniform: {
                    if (!has_deco(t, spv::DecorationBlock)) fail("uniform variable that is not a block");
                    std::string n = fresh(in.result, (struct_name(t) + "_data").c_str());
                    globals_ += "@group(" + std::to_string(deco(in.result, spv::DecorationDescriptorSet)) + ") @binding(" +
                                std::to_string(deco(in.result, spv::DecorationBinding)) + ") var<uniform> " + n + ": " +
                                struct_name(t) + ";\n";
                    global_ptrs_[in.result] = {n, "&" + n, t, 0, true};
                    break;
                }
                case spv::StorageClassUniformConstant: {
                    const Insn& d = def(t);
                    uint32_t img = d.op == spv::OpTypeSampledImage ? d.ops[0] : t;
                    const Insn& it = def(img);
                    if (it.op != spv::OpTypeImage || it.ops[1] != spv::Dim2D || it.ops[2] == 1 || it.ops[3] || it.ops[4] ||
                        scalar(it.ops[0]) != "f32")
                        fail("an image other than a 2D float texture");
                    std::string n = fresh(in.result, "tex");
                    globals_ += "@group(" + std::to_string(deco(in.result, spv::DecorationDescriptorSet)) + ") @binding(" +
                                std::to_string(deco(in.result, spv::DecorationBinding)) + ") var " + n + ": texture_2d<f32>;\n";
                    global_ptrs_[in.result] = {n, n, t, 0, false};
                    break;
                }
                default: fail("global variable in storage class " + std::to_string(in.ops[0]));
            }
        }
        globals_ += "\n";
    }

    struct Io {
        uint32_t id;
        std::string name;
        uint32_t type;
        spv::StorageClass sc;
    };

    std::string entry() {
        std::string params, copy_in, out_members, out_values;
        for (const Io& io : io_) {
            std::string attr;
            if (has_deco(io.id, spv::DecorationBuiltIn)) {
                auto b = spv::BuiltIn(deco(io.id, spv::DecorationBuiltIn));
                if (b == spv::BuiltInFragCoord) attr = "@builtin(position)";
                else if (b == spv::BuiltInFrontFacing) attr = "@builtin(front_facing)";
                else if (b == spv::BuiltInFragDepth) attr = "@builtin(frag_depth)";
                else fail("built-in " + std::to_string(int(b)));
            } else if (has_deco(io.id, spv::DecorationLocation)) {
                attr = "@location(" + std::to_string(deco(io.id, spv::DecorationLocation)) + ")";
            } else {
                fail("an entry point interface variable without a location");
            }
            if (io.sc == spv::StorageClassInput) {
                params += (params.empty() ? "" : ", ") + attr + " " + io.name + "_in: " + value_type(io.type);
                copy_in += "    " + io.name + " = " + io.name + "_in;\n";
            } else {
                out_members += "    " + attr + " " + io.name + ": " + value_type(io.type) + ",\n";
                out_values += (out_values.empty() ? "" : ", ") + io.name;
            }
        }
        if (out_members.empty()) fail("a fragment shader without outputs");
        std::string s;
        s += "struct iqc_FragmentOutput {\n" + out_members + "}\n\n";
        s += "// The fragment shader: entry point fs_main.\n";
        s += "@fragment\nfn fs_main(" + params + ") -> iqc_FragmentOutput {\n" + copy_in + "    " + fn_name(entry_) +
             "();\n    return iqc_FragmentOutput(" + out_values + ");\n}\n\n";
        s += "// A full-screen triangle for fs_main: entry point vs_main, draw 3 vertices without buffers.\n";
        s += "@vertex\nfn vs_main(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {\n"
             "    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));\n"
             "    return vec4<f32>(uv * 2.0f - 1.0f, 0.0f, 1.0f);\n}\n";
        return s;
    }

public:
    std::string translate() {
        parse();
        name_things();
        global_vars();
        std::string fns;
        for (auto& f : functions_) {
            ptrs_base();
            fns += function(f);
        }
        std::string out;
        out += "// WGSL translated by iqc from the shader's SPIR-V: the same runtime as every other target.\n";
        if (derivatives_) out += "diagnostic(off, derivative_uniformity);\n";
        out += "\n";
        out += decls_;
        out += helpers_;
        out += globals_;
        out += fns;
        out += entry();
        return out;
    }

private:
    void ptrs_base() {
        ptrs_ = {};
        value_ = {};
    }

    const std::vector<uint32_t>& w_;
    uint32_t bound_ = 0;
    std::vector<Insn> insns_;
    std::vector<size_t> def_;
    std::vector<Function> functions_;
    std::unordered_map<uint32_t, std::string> names_;
    std::map<std::pair<uint32_t, uint32_t>, std::string> member_debug_;
    std::unordered_map<uint32_t, std::map<uint32_t, uint32_t>> deco_;
    std::map<std::pair<uint32_t, uint32_t>, std::map<uint32_t, uint32_t>> mdeco_;
    uint32_t glsl_set_ = 0, entry_ = 0;
    Namer namer_;
    std::unordered_map<uint32_t, std::string> struct_names_;
    std::unordered_map<uint32_t, std::vector<std::string>> member_names_;
    std::unordered_map<uint32_t, Layout> struct_layouts_;
    std::map<std::string, std::string> wrappers_;
    std::unordered_map<uint32_t, std::string> const_text_;
    int const_count_ = 0;
    std::unordered_map<uint32_t, std::string> value_;
    std::unordered_map<uint32_t, Ptr> ptrs_, global_ptrs_;
    std::unordered_map<uint32_t, std::string> fn_names_;
    std::set<uint32_t> inverses_;
    std::vector<Io> io_;
    bool derivatives_ = false;
    std::string decls_, helpers_, globals_;
};

}  // namespace

WgslResult spirv_to_wgsl(const std::vector<uint32_t>& words) {
    WgslResult r;
    try {
        Translator t(words);
        r.text = t.translate();
        r.ok = true;
    } catch (const Unsupported& e) {
        r.log = std::string("SPIR-V to WGSL: ") + e.what();
    } catch (const std::exception& e) {
        r.log = std::string("SPIR-V to WGSL: ") + e.what();
    }
    return r;
}

// `base`, or base_2, base_3, ...: the first that `code` does not contain as a whole word (a name the wrapper
// declares must not be one the shader declares: a trial's `vec3 iqc_fragColor` was "redefinition", exit 1).
static std::string unused_name(const std::string& code, const std::string& base) {
    auto word = [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; };
    auto used = [&](const std::string& n) {
        for (size_t at = code.find(n); at != std::string::npos; at = code.find(n, at + 1))
            if ((at == 0 || !word(code[at - 1])) && (at + n.size() >= code.size() || !word(code[at + n.size()]))) return true;
        return false;
    };
    std::string n = base;
    for (int k = 2; used(n); ++k) n = base + "_" + std::to_string(k);
    return n;
}

ShadertoyWgsl shadertoy_to_wgsl(const std::string& code) {
    ShadertoyWgsl r;
    r.inputs_block = unused_name(code, "ShadertoyInputs");
    const std::string out = unused_name(code, "iqc_fragColor"), colour = unused_name(code, "iqc_color");
    std::string src =
        "#version 450\n"
        "layout(std140, set = 0, binding = 0) uniform " + r.inputs_block + " {\n"
        "    vec3 iResolution; float iTime; float iTimeDelta; float iFrameRate; int iFrame; vec4 iMouse; vec4 iDate;\n"
        "};\n"
        "layout(location = 0) out vec4 " + out + ";\n"
        "#line 1\n" + code +
        "\nvoid main() {\n"
        "    vec4 " + colour + " = vec4(0.0, 0.0, 0.0, 1.0);\n"
        "    mainImage(" + colour + ", vec2(gl_FragCoord.x, iResolution.y - gl_FragCoord.y));\n"
        "    " + out + " = vec4(" + colour + ".rgb, 1.0);\n"
        "}\n";
    SpirvResult spv = compile_vulkan_fragment(src);
    if (!spv.ok) {
        r.user_error = true;
        r.log = spv.log;
        return r;
    }
    WgslResult w = spirv_to_wgsl(spv.words);
    r.ok = w.ok;
    r.log = w.log;
    r.text = w.text;
    return r;
}

}  // namespace iqc::glsl
