#include "glsl/Names.h"

#include <cctype>
#include <cstring>
#include <fmt/format.h>
#include <set>

#include "source/Source.h"

namespace iqc::glsl {

namespace {

const char* greek(char32_t c) {
    static const char* lower[] = {"alpha", "beta", "gamma", "delta", "epsilon", "zeta", "eta", "theta",
                                  "iota", "kappa", "lambda", "mu", "nu", "xi", "omicron", "pi", "rho",
                                  "sigmaf", "sigma", "tau", "upsilon", "phi", "chi", "psi", "omega"};
    static const char* upper[] = {"Alpha", "Beta", "Gamma", "Delta", "Epsilon", "Zeta", "Eta", "Theta",
                                  "Iota", "Kappa", "Lambda", "Mu", "Nu", "Xi", "Omicron", "Pi", "Rho",
                                  "", "Sigma", "Tau", "Upsilon", "Phi", "Chi", "Psi", "Omega"};
    if (c >= 0x3B1 && c <= 0x3C9) return lower[c - 0x3B1];
    if (c >= 0x391 && c <= 0x3A9 && c != 0x3A2) return upper[c - 0x391];
    switch (c) {
        case 0x3D1: return "vartheta";
        case 0x3D5: return "varphi";
        case 0x3F5: return "varepsilon";
        case 0x2113: return "ell";
        default: return nullptr;
    }
}

const char* mark(char32_t c) {
    switch (c) {
        case 0x0302: return "hat";
        case 0x0303: return "tilde";
        case 0x0304: case 0x0305: return "bar";
        case 0x0307: return "dot";
        case 0x0308: return "ddot";
        case 0x0301: return "acute";
        case 0x0300: return "grave";
        case 0x030C: return "check";
        case 0x20D7: return "vec";
        default: return nullptr;
    }
}

}  // namespace

std::string identifier(const std::string& math) {
    std::string out;
    auto append_word = [&](const std::string& w) {
        if (!out.empty() && out.back() != '_') out += '_';
        out += w;
    };
    for (size_t i = 0; i < math.size();) {
        char32_t c = utf8::decode(math, i);
        if ((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9')) {
            out += char(c);
        } else if (c == '_' || c == ' ' || c == '-' || c == '.') {
            if (!out.empty() && out.back() != '_') out += '_';
        } else if (const char* g = greek(c)) {
            if (!out.empty() && out.back() != '_') out += '_';
            out += g;
        } else if (const char* m = mark(c)) {
            append_word(m);
        } else if (c == '\'' || c == 0x2032) {
            append_word("prime");
        } else if (c == 0x2033) {
            append_word("dprime");
        } else {
            append_word(fmt::format("u{:04X}", uint32_t(c)));
        }
    }
    // No double underscores (reserved in GLSL), no leading digit, never empty.
    std::string clean;
    for (char ch : out)
        if (!(ch == '_' && !clean.empty() && clean.back() == '_')) clean += ch;
    while (!clean.empty() && clean.back() == '_' && clean.size() > 1) clean.pop_back();
    if (clean.empty() || clean == "_") clean = "v";
    if (std::isdigit(static_cast<unsigned char>(clean[0]))) clean = "v" + clean;
    if (clean[0] == '_') clean = "v" + clean;
    // gl_ names are the language's; GL_ names are predefined macros (GL_ES, GL_FRAGMENT_PRECISION_HIGH) and
    // reserved for future ones: a macro would replace the identifier.
    // iqc_ and IQC_ are the runtime's: a user name with that start would be refused with every suffix.
    if (clean.rfind("gl_", 0) == 0 || clean.rfind("GL_", 0) == 0 || clean.rfind("iqc_", 0) == 0 || clean.rfind("IQC_", 0) == 0)
        clean = "v_" + clean;
    // At most kMaxIdentifier characters (glslang refuses names past 1,024, and nobody reads a longer one): a
    // longer name keeps its start and ends in a hash of the whole (FNV-1a), so different names stay apart.
    if (clean.size() > kMaxIdentifier) {
        uint32_t h = 2166136261u;
        for (char ch : clean) h = (h ^ uint8_t(ch)) * 16777619u;
        std::string head = clean.substr(0, kMaxIdentifier - 9);
        while (head.size() > 1 && head.back() == '_') head.pop_back();
        clean = fmt::format("{}_{:08x}", head, h);
    }
    return clean;
}

std::string comment_text(std::string_view text) {
    std::string out;
    out.reserve(text.size());
    bool space = false;
    for (size_t i = 0; i < text.size();) {
        size_t start = i;
        char32_t c = utf8::decode(text, i);
        // Invalid, overlong, surrogate or out-of-range sequences: U+FFFD (what they decode to is judged below).
        std::string canonical;
        utf8::append(canonical, c);
        bool invalid = canonical != text.substr(start, i - start) || (c >= 0xD800 && c <= 0xDFFF) || c > 0x10FFFF;
        bool blank = c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == 0x0B || c == 0x0C || c == 0x85 ||
                     c == 0x2028 || c == 0x2029;
        if (blank || c < 0x20 || c == 0x7F || (c >= 0x80 && c < 0xA0)) {  // white space, controls (NUL too)
            space = true;
            continue;
        }
        if (space && !out.empty()) out += ' ';
        space = false;
        // `/*` and `*/` are split with a space, so no block comment can open or close here.
        if ((c == '*' && !out.empty() && out.back() == '/') || (c == '/' && !out.empty() && out.back() == '*')) out += ' ';
        // Invisible format characters (bidirectional overrides and isolates, zero-width characters, a BOM)
        // are spelled out: a comment then reads in an editor as it is stored ("Trojan Source", CVE-2021-42574).
        // Also the other default-ignorable code points (soft hyphen, invisible operators, variation selectors,
        // Hangul fillers, tag characters of "ASCII smuggling") and noncharacters.
        bool format = (c >= 0x202A && c <= 0x202E) || (c >= 0x2060 && c <= 0x206F) || (c >= 0x200B && c <= 0x200F) ||
                      c == 0x061C || c == 0xFEFF || c == 0x180E || (c >= 0xFFF9 && c <= 0xFFFB) || c == 0x00AD ||
                      c == 0x034F || c == 0x115F || c == 0x1160 || c == 0x3164 || c == 0xFFA0 ||
                      (c >= 0x17B4 && c <= 0x17B5) || (c >= 0x180B && c <= 0x180F) || (c >= 0xFE00 && c <= 0xFE0F) ||
                      (c >= 0x1D173 && c <= 0x1D17A) || (c >= 0xE0000 && c <= 0xE0FFF) || (c >= 0xFDD0 && c <= 0xFDEF) ||
                      (c >= 0x1BCA0 && c <= 0x1BCA3) || (c & 0xFFFE) == 0xFFFE;
        if (invalid) utf8::append(out, 0xFFFD);
        else if (format) out += fmt::format("<U+{:04X}>", uint32_t(c));
        else out.append(text.substr(start, i - start));
    }
    while (!out.empty() && (out.back() == '\\' || out.back() == ' ')) out.pop_back();  // no line continuation
    return out;
}

bool is_reserved(const std::string& n) {
    static const std::set<std::string> words = {
        // keywords and reserved words (GLSL ES 3.00 and 3.30 core)
        "attribute", "const", "uniform", "varying", "layout", "centroid", "flat", "smooth", "noperspective",
        "break", "continue", "do", "for", "while", "switch", "case", "default", "if", "else", "in", "out",
        "inout", "float", "int", "void", "bool", "true", "false", "invariant", "discard", "return", "mat2",
        "mat3", "mat4", "mat2x2", "mat2x3", "mat2x4", "mat3x2", "mat3x3", "mat3x4", "mat4x2", "mat4x3",
        "mat4x4", "vec2", "vec3", "vec4", "ivec2", "ivec3", "ivec4", "bvec2", "bvec3", "bvec4", "uint",
        "uvec2", "uvec3", "uvec4", "lowp", "mediump", "highp", "precision", "sampler2D", "sampler3D",
        "samplerCube", "sampler2DShadow", "samplerCubeShadow", "sampler2DArray", "sampler2DArrayShadow",
        "isampler2D", "isampler3D", "isamplerCube", "isampler2DArray", "usampler2D", "usampler3D",
        "usamplerCube", "usampler2DArray", "struct", "asm", "class", "union", "enum", "typedef", "template",
        "this", "packed", "resource", "goto", "inline", "noinline", "volatile", "public", "static", "extern",
        "external", "interface", "long", "short", "double", "half", "fixed", "unsigned", "superp", "input",
        "output", "hvec2", "hvec3", "hvec4", "dvec2", "dvec3", "dvec4", "fvec2", "fvec3", "fvec4",
        "sampler3DRect", "filter", "image1D", "image2D", "image3D", "imageCube", "sizeof", "cast",
        "namespace", "using", "sampler1D", "sampler1DShadow", "sampler2DRect", "sampler2DRectShadow",
        "samplerBuffer", "patch", "sample", "subroutine", "common", "partition", "active", "main",
        // built-in functions
        "radians", "degrees", "sin", "cos", "tan", "asin", "acos", "atan", "sinh", "cosh", "tanh", "asinh",
        "acosh", "atanh", "pow", "exp", "log", "exp2", "log2", "sqrt", "inversesqrt", "abs", "sign",
        "floor", "trunc", "round", "roundEven", "ceil", "fract", "mod", "modf", "min", "max", "clamp", "mix",
        "step", "smoothstep", "isnan", "isinf", "floatBitsToInt", "floatBitsToUint", "intBitsToFloat",
        "uintBitsToFloat", "packSnorm2x16", "unpackSnorm2x16", "packUnorm2x16", "unpackUnorm2x16",
        "packHalf2x16", "unpackHalf2x16", "length", "distance", "dot", "cross", "normalize", "faceforward",
        "reflect", "refract", "matrixCompMult", "outerProduct", "transpose", "determinant", "inverse",
        "lessThan", "lessThanEqual", "greaterThan", "greaterThanEqual", "equal", "notEqual", "any", "all",
        "not", "texture", "textureSize", "textureProj", "textureLod", "textureOffset", "texelFetch",
        "texelFetchOffset", "textureProjOffset", "textureLodOffset", "textureProjLod", "textureProjLodOffset",
        "textureGrad", "textureGradOffset", "textureProjGrad", "textureProjGradOffset", "dFdx", "dFdy",
        "fwidth", "fma", "frexp", "ldexp",
        // Shadertoy's inputs and the runtime's names
        "mainImage", "fragColor", "fragCoord", "iResolution", "iTime", "iTimeDelta", "iFrame", "iFrameRate",
        "iChannelTime", "iChannelResolution", "iMouse", "iDate", "iSampleRate", "iChannel0", "iChannel1",
        "iChannel2", "iChannel3",
        // GLSL ES 3.10+ and 4.50 keywords (the spirv, hlsl and wgsl targets compile Vulkan GLSL 4.50; a trial's
        // instance named `sampler` was glslang's error: exit 3)
        "atomic_uint", "coherent", "readonly", "restrict", "writeonly", "shared", "buffer", "precise", "sampler",
        "samplerShadow", "subpassInput", "isubpassInput", "usubpassInput", "subroutine", "dmat2", "dmat3", "dmat4", "dmat2x2", "dmat2x3", "dmat2x4", "dmat3x2",
        "dmat3x3", "dmat3x4", "dmat4x2", "dmat4x3", "dmat4x4", "bvec", "demote", "terminate",
        // HLSL keywords, reserved words and types (SPIRV-Cross keeps the Vulkan shader's names, and glslang's HLSL
        // front end refused `float3`, `auto`, `new`, ... as names)
        "AppendStructuredBuffer", "asm_fragment", "BlendState", "Buffer", "ByteAddressBuffer", "cbuffer",
        "column_major", "compile", "compile_fragment", "CompileShader", "ComputeShader", "ConsumeStructuredBuffer",
        "DepthStencilState", "DepthStencilView", "DomainShader", "dword", "export", "fxgroup", "GeometryShader",
        "groupshared", "Hullshader", "HullShader", "InputPatch", "line", "lineadj", "linear", "LineStream", "matrix",
        "nointerpolation", "NULL", "OutputPatch", "packoffset", "pass", "pixelfragment", "PixelShader", "point",
        "PointStream", "RasterizerState", "RenderTargetView", "register", "row_major", "RWBuffer",
        "RWByteAddressBuffer", "RWStructuredBuffer", "RWTexture1D", "RWTexture1DArray", "RWTexture2D",
        "RWTexture2DArray", "RWTexture3D", "SamplerState", "SamplerComparisonState", "snorm", "stateblock",
        "stateblock_state", "string", "StructuredBuffer", "tbuffer", "technique", "technique10", "technique11",
        "Texture1D", "Texture1DArray", "Texture2D", "Texture2DArray", "Texture2DMS", "Texture2DMSArray",
        "Texture3D", "TextureCube", "TextureCubeArray", "triangle", "triangleadj", "TriangleStream", "unorm",
        "vector", "vertexfragment", "VertexShader", "globallycoherent", "auto", "catch", "char", "const_cast",
        "delete", "dynamic_cast", "explicit", "friend", "mutable", "new", "operator", "private", "protected",
        "reinterpret_cast", "signed", "static_cast", "throw", "try", "typename", "virtual", "min16float",
        "min10float", "min16int", "min12int", "min16uint",
        // HLSL intrinsics a module's name would shadow
        "saturate", "lerp", "frac", "rsqrt", "mul", "atan2", "fmod", "ddx", "ddy", "ddx_coarse", "ddy_coarse",
        "ddx_fine", "ddy_fine", "clip", "rcp", "sincos", "log10", "mad", "asfloat", "asint", "asuint", "asdouble",
        "countbits", "firstbithigh", "firstbitlow", "reversebits", "isfinite", "f16tof32", "f32tof16", "noise",
        "abort", "errorf", "printf", "dst", "lit", "msad4", "tex1D", "tex2D", "tex3D", "texCUBE",
    };
    if (words.count(n) > 0 || n.rfind("gl_", 0) == 0 || n.rfind("iqc_", 0) == 0 || n.rfind("IQC_", 0) == 0 ||
        n.find("__") != std::string::npos)
        return true;
    // Families: GLSL's opaque types (i/u + sampler, image, texture, subpassInput + a dimension), HLSL's vector and
    // matrix types (float3, half4x4, uint2, min16float3, ...).
    auto family = [&](const char* prefix) {
        size_t k = 0;
        if (!n.empty() && (n[0] == 'i' || n[0] == 'u') && n.compare(1, std::strlen(prefix), prefix) == 0) k = 1;
        if (n.compare(k, std::strlen(prefix), prefix) != 0) return false;
        size_t rest = k + std::strlen(prefix);
        // a dimension and its qualifiers (2D, CubeArray, 2DMSArray, Shadow): letters and digits only, so that the
        // renamed `image2D_2` is free (else Namer::unique never finds a name)
        if (rest >= n.size() || !(std::isdigit(static_cast<unsigned char>(n[rest])) || std::isupper(static_cast<unsigned char>(n[rest]))))
            return false;
        for (size_t c = rest; c < n.size(); ++c)
            if (!std::isalnum(static_cast<unsigned char>(n[c]))) return false;
        return true;
    };
    if (family("sampler") || family("image") || family("texture") || family("subpassInput")) return true;
    for (const char* t : {"bool", "int", "uint", "half", "float", "double", "dword", "min16float", "min10float", "min16int",
                          "min12int", "min16uint", "uint64_t", "int64_t", "float16_t", "int16_t", "uint16_t"}) {
        size_t l = std::strlen(t);
        if (n.compare(0, l, t) != 0 || n.size() == l) continue;
        const std::string rest = n.substr(l);
        if ((rest.size() == 1 && rest[0] >= '1' && rest[0] <= '4') ||
            (rest.size() == 3 && rest[0] >= '1' && rest[0] <= '4' && rest[1] == 'x' && rest[2] >= '1' && rest[2] <= '4'))
            return true;
    }
    return false;
}

bool Namer::taken(const std::string& name) const {
    return used_.count(name) > 0 || (parent_ && parent_->taken(name));
}

std::string Namer::unique(const std::string& math_name) {
    std::string base = identifier(math_name);
    // Suffixes are tried from where the last name of this base stopped (names are never freed, so every
    // smaller one is taken): thousands of `tmp`s in one function cost linear time, not quadratic.
    int& next = next_suffix_[base];
    std::string n = base;
    if (next == 0) {
        next = 2;
        if (!is_reserved(n) && !taken(n)) {
            used_.insert(n);
            return n;
        }
    }
    do n = fmt::format("{}_{}", base, next++);
    while (is_reserved(n) || taken(n));
    used_.insert(n);
    return n;
}

}  // namespace iqc::glsl
