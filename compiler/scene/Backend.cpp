#include "scene/Backend.h"

#include <cmath>
#include <cstring>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <functional>

#include "glsl/Emit.h"

namespace iqc {

using glsl::GlobalStorage;
using ir::Global;
using Kind = GlobalStorage::Kind;

namespace {

constexpr int kMaxBlockBytes = 16384;   // WebGL2's guaranteed MAX_UNIFORM_BLOCK_SIZE
constexpr int kMaxBlocks = 11;          // of the 12 fragment uniform blocks WebGL2 guarantees, one left free
constexpr int kMaxUniformVectors = 224; // WebGL2's guaranteed MAX_FRAGMENT_UNIFORM_VECTORS
constexpr int kMinTableForBuffer = 64;  // compile-time tables this long leave the code for a buffer
constexpr int kTextureWidth = 1024;

int vec4_slots(const Type& t) { return t.is_matrix() && t.rows > 1 ? t.cols : 1; }

// std140: a member's base alignment and size (arrays: every element on a 16-byte stride).
int std140_align(const Type& t) {
    if (t.is_array() || (t.is_matrix() && t.rows > 1)) return 16;
    int n = t.components();
    return n == 1 ? 4 : n == 2 ? 8 : 16;
}
int std140_element_size(const Type& e) {
    if (e.is_matrix() && e.rows > 1) return 16 * e.cols;
    return 4 * e.components();
}
int std140_size(const Type& t) {
    if (!t.is_array()) return std140_element_size(t);
    int stride = (std140_element_size(t.element()) + 15) / 16 * 16;
    return stride * t.count;
}

// Byte offsets of an element's components (row-major order) relative to the element.
std::vector<int> component_offsets(const Type& e) {
    std::vector<int> off;
    if (e.is_matrix() && e.rows > 1) {
        for (int r = 0; r < e.rows; ++r)
            for (int c = 0; c < e.cols; ++c) off.push_back(16 * c + 4 * r);
    } else {
        for (int k = 0; k < std::max(1, e.components()); ++k) off.push_back(4 * k);
    }
    return off;
}

std::string base64(const uint8_t* data, size_t n) {
    static const char* a = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    out.reserve((n + 2) / 3 * 4);
    for (size_t i = 0; i < n; i += 3) {
        uint32_t v = uint32_t(data[i]) << 16 | (i + 1 < n ? uint32_t(data[i + 1]) << 8 : 0) | (i + 2 < n ? data[i + 2] : 0);
        out += a[(v >> 18) & 63];
        out += a[(v >> 12) & 63];
        out += i + 1 < n ? a[(v >> 6) & 63] : '=';
        out += i + 2 < n ? a[v & 63] : '=';
    }
    return out;
}

std::string join_values(const std::vector<double>& v) {
    if (v.size() == 1) return fmt::format("{}", v[0]);
    return fmt::format("({})", fmt::join(v, ", "));
}

const char* entry_comment(const std::string& name) {
    static const std::map<std::string, const char*> c = {
        {ir::names::kScene, "Distance to the nearest surface (x) and that instance's id (y)."},
        {ir::names::kGradient, "The gradient of instance `id`'s distance at p, derived by iqc (forward-mode differentiation)."},
        {ir::names::kDistanceOf, "Instance `id`'s own distance at p (what a finite-difference normal takes its taps of)."},
        {ir::names::kShade, "Colour of instance `id` at surface point p, unit normal N, seen from eye, that no light's shadow darkens."},
        {ir::names::kShadeLight, "Instance `id`'s colour from one light at P_L with colour C_L (the runtime adds one per light, times its shadow)."},
        {ir::names::kLightPosition, "Position of light l (a sun's: the direction toward it)."},
        {ir::names::kLightColor, "Colour of light l."},
        {ir::names::kReflectivity, "Reflectivity of instance `id` (its material's `k_r`)."},
        {ir::names::kTransmission, "Transmission (`k_t`) and index of refraction (`η`) of instance `id`'s material."},
        {ir::names::kSegmentGain, "Segment tracing: how many times iqc_scene's distance a step may go while it stays in the box [lo, hi] (1 / the largest rate of change along rd, by interval arithmetic on each instance's gradient)."},
        {ir::names::kSegmentClear, "Segment tracing: a lower bound of every instance's distance over the box [lo, hi] (interval arithmetic on each instance's distance): above the hit tolerance, nothing in the box can be hit."},
        {ir::names::kLipschitz, "The Lipschitz factor instance `id`'s distance was divided by (the hit test multiplies it back)."},
        {ir::names::kPrepare, "Transforms that change with sliders or time: inverted once per pixel, before any marching."},
        {ir::names::kBoxLo, "The scene's box, low corner: the box at the sliders' defaults while every slider is within 1/64 of its range of its default, else the box over their ranges."},
        {ir::names::kBoxHi, "The scene's box, high corner (as iqc_box_lo)."},
        {ir::names::kInstanceInverse, "I♥IQ's architecture (benchmark baseline): instance i's world → object transform, inverted here."},
        {ir::names::kInstanceDistance, "Instance i's object-space distance."},
    };
    auto it = c.find(name);
    return it == c.end() ? nullptr : it->second;
}

struct Layout {
    const ir::Module& m;
    const BackendOptions& o;
    std::vector<GlobalStorage> storage;
    std::vector<std::vector<int>> offsets;  // per global: byte offset (block) or float index (texture) of each component
    std::vector<int> block_of;              // per global: its block, or -1
    std::vector<int> block_at;              // per global in a block: its byte offset (members are declared in this order)
    SceneCode& code;

    void decide() {
        size_t n = m.globals.size();
        storage.assign(n, {});
        offsets.assign(n, {});
        block_of.assign(n, -1);
        block_at.assign(n, -1);
        glsl::Namer names;
        for (size_t i = 0; i < n; ++i) storage[i].name = names.unique(m.globals[i].name);
        if (o.constants) {
            for (size_t i = 0; i < n; ++i)
                storage[i].kind = m.globals[i].kind == Global::Kind::Prepared ? Kind::Private : Kind::Const;
            return;
        }
        std::vector<size_t> data, plain;
        int vectors = 13;  // iResolution, iTime, iMouse, iFrame; the camera (position, basis 3, focal, projection 4)
        for (size_t i = 0; i < n; ++i) {
            const Global& g = m.globals[i];
            // A type GLSL has no name for (a matrix past mat4: the function emitter reports it at its use) has
            // no std140 or texel layout either: it is left out of the blocks and the texture, whose packing
            // would write past its element (a trial's ℝ^(7×7) parameter corrupted the heap on spirv).
            if (glsl::type_name(g.type).empty()) storage[i].kind = Kind::Const;
            else if (g.kind == Global::Kind::Prepared) storage[i].kind = Kind::Private;
            else if (g.kind == Global::Kind::Constant && (!g.type.is_array() || g.type.count < kMinTableForBuffer))
                storage[i].kind = Kind::Const;
            else if (g.kind == Global::Kind::Parameter && !g.type.is_array()) {
                plain.push_back(i);
                vectors += vec4_slots(g.type);
            } else {
                data.push_back(i);
            }
        }
        if (!o.blocks) {  // three.js: past WebGL2's uniform vectors, plain parameters go into the texture too
            if (vectors > kMaxUniformVectors) data.insert(data.end(), plain.begin(), plain.end());
            else
                for (size_t i : plain) storage[i].kind = Kind::Uniform;
            code.uniform_vectors = vectors > kMaxUniformVectors ? 13 : vectors;
            if (!data.empty()) pack_texture(data);
            return;
        }
        std::vector<size_t> block_members;
        if (vectors > kMaxUniformVectors || o.vulkan) block_members = plain;  // too many plain uniforms (or Vulkan): into blocks too
        else
            for (size_t i : plain) storage[i].kind = Kind::Uniform;
        code.uniform_vectors = vectors > kMaxUniformVectors ? 13 : vectors;
        // Arrays: blocks while they fit, else all of them in the data texture.
        std::vector<size_t> arrays = data;
        bool texture = false;
        {
            int blocks = 0, used = kMaxBlockBytes;
            for (size_t i : block_members) arrays.insert(arrays.begin(), i);
            for (size_t i : arrays) {
                int size = std140_size(m.globals[i].type);
                if (size > kMaxBlockBytes) texture = true;
                int at = (used + std140_align(m.globals[i].type) - 1) / std140_align(m.globals[i].type) * std140_align(m.globals[i].type);
                if (at + size > kMaxBlockBytes) {
                    ++blocks;
                    used = size;
                } else {
                    used = at + size;
                }
            }
            if (blocks > kMaxBlocks) texture = true;
        }
        if (texture) {
            // Plain parameters keep blocks while kMaxBlocks hold them; the rest go into the data texture with
            // the arrays (a trial's 300 instances of ten mat4 sliders made 13 blocks: past WebGL2's and
            // WebGPU's 12 per stage). No texture when nothing goes there.
            std::vector<size_t> in_blocks, in_texture = data;
            int blocks = 0, used = kMaxBlockBytes;
            for (size_t i : block_members) {
                int align = std140_align(m.globals[i].type), size = std140_size(m.globals[i].type);
                int at = (used + align - 1) / align * align;
                if (at + size > kMaxBlockBytes) {
                    if (blocks == kMaxBlocks) {
                        in_texture.push_back(i);
                        continue;
                    }
                    ++blocks;
                    at = 0;
                }
                used = at + size;
                in_blocks.push_back(i);
            }
            if (!in_texture.empty()) pack_texture(in_texture);
            pack_blocks(in_blocks);
        } else {
            pack_blocks(arrays);
        }
    }

    void pack_blocks(const std::vector<size_t>& members) {
        ShaderInputs::Block* b = nullptr;
        int used = 0;
        for (size_t i : members) {
            const Global& g = m.globals[i];
            int align = std140_align(g.type), size = std140_size(g.type);
            int at = (used + align - 1) / align * align;
            if (!b || at + size > kMaxBlockBytes) {
                int binding = int(code.inputs.blocks.size()) + (o.vulkan ? 1 : 0);
                code.inputs.blocks.push_back({fmt::format("iqc_block_{}", code.inputs.blocks.size()), binding, {}});
                b = &code.inputs.blocks.back();
                at = 0;
            }
            storage[i].kind = Kind::BlockMember;
            block_of[i] = int(code.inputs.blocks.size() - 1);
            block_at[i] = at;
            b->bytes.resize(size_t(at + size), 0);
            Type e = g.type.is_array() ? g.type.element() : g.type;
            int stride = g.type.is_array() ? (std140_element_size(e) + 15) / 16 * 16 : 0;
            std::vector<int> comp = component_offsets(e);
            size_t per = size_t(std::max(1, e.components()));
            int count = g.type.is_array() ? g.type.count : 1;
            for (int k = 0; k < count; ++k)
                for (size_t c = 0; c < per; ++c) {
                    int off = at + k * stride + comp[c];
                    offsets[i].push_back(off);
                    double v = g.value[size_t(k) * per + c];
                    if (e.kind == Type::Integer) {
                        int32_t x = int32_t(std::llround(v));
                        std::memcpy(&b->bytes[size_t(off)], &x, 4);
                    } else {
                        float x = float(v);
                        std::memcpy(&b->bytes[size_t(off)], &x, 4);
                    }
                }
            used = at + size;
        }
    }

    // Arrays, and on targets without blocks plain parameters too (one element), into the data texture.
    static Type element_of(const Type& t) { return t.is_array() ? t.element() : t; }
    static int count_of(const Type& t) { return t.is_array() ? t.count : 1; }

    void pack_texture(const std::vector<size_t>& arrays) {
        int texels = 0;
        for (size_t i : arrays) {
            const Global& g = m.globals[i];
            Type e = element_of(g.type);
            int per = e.is_matrix() && e.rows > 1 ? e.cols : 1;
            storage[i].kind = Kind::Texture;
            storage[i].texel = texels;
            storage[i].texels = per;
            texels += per * count_of(g.type);
        }
        auto& t = code.inputs.texture;
        t.name = "iqc_data";
        t.width = std::min(texels, kTextureWidth);
        t.height = (texels + kTextureWidth - 1) / kTextureWidth;
        t.rgba.assign(size_t(t.width) * size_t(t.height) * 4, 0.0f);
        for (size_t i : arrays) {
            const Global& g = m.globals[i];
            Type e = element_of(g.type);
            size_t per = size_t(std::max(1, e.components()));
            bool mat = e.is_matrix() && e.rows > 1;
            for (int k = 0; k < count_of(g.type); ++k)
                for (size_t c = 0; c < per; ++c) {
                    // Row-major component c of element k: its column's texel, its row's channel.
                    int row = mat ? int(c) / e.cols : 0, col = mat ? int(c) % e.cols : 0;
                    int texel = storage[i].texel + k * storage[i].texels + col;
                    int index = texel * 4 + (mat ? row : int(c));
                    offsets[i].push_back(index);
                    t.rgba[size_t(index)] = float(g.value[size_t(k) * per + c]);
                }
        }
    }
};

struct Declarations {
    const ir::Module& m;
    const BackendOptions& o;
    const Layout& lay;
    SceneCode& code;

    std::string value_of(const Global& g) const {
        return g.type.is_array() && g.type.count >= 16 ? glsl::compact_constant(g.type, g.value) : glsl::constant(g.type, g.value);
    }

    std::string declare(size_t i) const {
        const Global& g = m.globals[i];
        const GlobalStorage& s = lay.storage[i];
        std::string tn = glsl::type_name(g.type);
        std::string arr = g.type.is_array() ? fmt::format("[{}]", g.type.count) : "";
        std::string comment = glsl::comment_text(g.comment);
        switch (s.kind) {
            case Kind::Const:
                return fmt::format("const {} {}{} = {};{}\n", tn, s.name, arr, value_of(g), comment.empty() ? "" : "  // " + comment);
            case Kind::Uniform:
                return fmt::format("uniform {} {};  // {}{}(default {})\n", tn, s.name, comment, comment.empty() ? "" : " ",
                                   join_values(g.value));
            case Kind::Private: return fmt::format("{} {};{}\n", tn, s.name, comment.empty() ? "" : "  // " + comment);
            case Kind::BlockMember: return fmt::format("    {} {}{};{}\n", tn, s.name, arr, comment.empty() ? "" : "  // " + comment);
            case Kind::Texture: return "";
        }
        return "";
    }

    // Declarations of `kind` with an owner line whenever the owner changes.
    std::string section(const std::string& title, const std::function<bool(size_t)>& in) const {
        std::string out, owner = "\x01";
        for (size_t i = 0; i < m.globals.size(); ++i) {
            if (!in(i)) continue;
            const Global& g = m.globals[i];
            if (g.owner != owner && !g.owner.empty()) out += "// " + glsl::comment_text(g.owner) + "\n";
            owner = g.owner;
            out += declare(i);
        }
        return out.empty() ? "" : "// ---- " + title + " ----\n" + out + "\n";
    }

    // The arrays in the data texture that some function reads whole (not only an element at a time), in order.
    std::vector<size_t> read_whole() const {
        std::vector<char> whole(m.globals.size(), 0);
        for (const auto& f : m.functions)
            for (const auto& in : f.body)
                for (size_t k = 0; k < in.args.size(); ++k) {
                    const ir::Instr& a = f.body[in.args[k]];
                    if (a.op != ir::Op::Global || !a.type.is_array()) continue;
                    if (lay.storage[size_t(a.aux)].kind != Kind::Texture) continue;
                    if (in.op == ir::Op::Index && k == 0) continue;
                    whole[size_t(a.aux)] = 1;
                }
        std::vector<size_t> out;
        for (size_t i = 0; i < whole.size(); ++i)
            if (whole[i]) out.push_back(i);
        return out;
    }

    std::string run() const {
        auto is = [&](size_t i, Kind k) { return lay.storage[i].kind == k; };
        auto light = [&](size_t i) { return !m.globals[i].params.empty() && m.globals[i].params[0].role == "light"; };
        std::string out;
        std::string params_title = o.constants ? "parameters (Shadertoy has no sliders: edit the values here)"
                                               : "parameters (uniforms; defaults in the comments and the --meta JSON)";
        out += section(params_title, [&](size_t i) {
            return m.globals[i].kind == Global::Kind::Parameter && !light(i) && (is(i, Kind::Const) || is(i, Kind::Uniform));
        });
        out += section("lights", [&](size_t i) { return light(i) && (is(i, Kind::Const) || is(i, Kind::Uniform)); });
        out += section("scene data (computed by iqc)", [&](size_t i) {
            return m.globals[i].kind == Global::Kind::Constant && is(i, Kind::Const);
        });
        for (size_t b = 0; b < code.inputs.blocks.size(); ++b) {
            // In the order of their offsets: std140 lays members out in declaration order.
            std::vector<size_t> in_block;
            for (size_t i = 0; i < m.globals.size(); ++i)
                if (lay.block_of[i] == int(b)) in_block.push_back(i);
            std::stable_sort(in_block.begin(), in_block.end(), [&](size_t x, size_t y) { return lay.block_at[x] < lay.block_at[y]; });
            std::string members;
            for (size_t i : in_block) members += declare(i);
            std::string layout = o.vulkan ? fmt::format("std140, set = 0, binding = {}", code.inputs.blocks[b].binding) : "std140";
            out += fmt::format("// ---- {}: a std140 uniform block the host fills (--meta: \"blocks\") ----\n"
                               "layout({}) uniform {} {{\n{}}};\n\n",
                               o.vulkan && b == 0 ? "parameters and per-instance data" : "per-instance data", layout,
                               code.inputs.blocks[b].name, members);
        }
        if (!code.inputs.texture.name.empty()) {
            const auto& t = code.inputs.texture;
            out += fmt::format("// ---- per-instance data: a {}×{} RGBA32F texture the host fills (--meta: \"texture\") ----\n"
                               "{}uniform highp sampler2D {};\n"
                               "vec4 iqc_fetch(int i) {{ return texelFetch({}, ivec2(i % {}, i / {}), 0); }}\n\n",
                               t.width, t.height,
                               o.vulkan ? fmt::format("layout(set = 0, binding = {}) ", code.inputs.blocks.size() + 1) : "", t.name,
                               t.name, t.width, t.width);
            // An array read whole (a module passes its sequence parameter on as one value): a function that
            // gathers it, element by element (a trial's sequence of 1,025 numbers, past a uniform block's
            // 16 KiB, was read by a name nothing declared).
            for (size_t i : read_whole()) {
                const Global& g = m.globals[i];
                const GlobalStorage& st = lay.storage[i];
                Type e = g.type.element();
                std::string tn = glsl::type_name(e);
                // One constructor of constant fetches, not a loop into a local array: llvmpipe took 25 s to compile
                // the loop's 1,025 dynamic stores; constant indices let LLVM keep the elements in registers.
                std::vector<std::string> items;
                for (int k = 0; k < g.type.count; ++k) items.push_back(glsl::texture_fetch(st, e, std::to_string(k), true));
                out += fmt::format("{}[{}] {}() {{  // {}\n    return {}[{}]({});\n}}\n\n", tn, g.type.count, st.name,
                                   g.comment.empty() ? "the sequence " + g.name : glsl::comment_text(g.comment), tn,
                                   g.type.count, fmt::join(items, ", "));
            }
        }
        out += section("computed once per pixel (iqc_prepare)", [&](size_t i) { return is(i, Kind::Private); });
        return out;
    }
};

nlohmann::ordered_json describe(const ir::Module& m, const Layout& lay, const ShaderInputs& in) {
    nlohmann::ordered_json list = nlohmann::ordered_json::array();
    for (size_t i = 0; i < m.globals.size(); ++i) {
        const Global& g = m.globals[i];
        if (g.kind != Global::Kind::Parameter) continue;
        const GlobalStorage& s = lay.storage[i];
        // A per-member table (a group's parameter): member k's element. A sequence parameter (x_i ∈ ℝ³, an array
        // one instance owns, or a group shares): one entry per element, named as the math subscripts it (x_1, x_2).
        const bool table = g.per_member && g.type.is_array();
        const bool sequence = !table && g.type.is_array();
        Type e = g.type.is_array() ? g.type.element() : g.type;
        size_t per = size_t(std::max(1, e.components()));
        for (size_t k = 0; k < g.params.size(); ++k) {
            for (int q = 0; q < (sequence ? g.type.count : 1); ++q) {
                const ir::GlobalParam& p = g.params[k];
                size_t elem = table ? k : sequence ? size_t(q) : 0;
                nlohmann::ordered_json j;
                j["instance"] = p.instance;
                j["module"] = p.module;
                j["role"] = p.role;
                j["name"] = sequence ? fmt::format("{}_{}", p.name, q + 1) : p.name;
                switch (s.kind) {
                    // A member of a group: its element of the array (a tool edits that one, as with a block's member).
                    case Kind::Const:
                        j["storage"] = "constant";
                        j["constant"] = g.type.is_array() ? fmt::format("{}[{}]", s.name, elem) : s.name;
                        break;
                    case Kind::Uniform:
                        j["storage"] = "uniform";
                        j["uniform"] = g.type.is_array() ? fmt::format("{}[{}]", s.name, elem) : s.name;
                        break;
                    case Kind::BlockMember:
                        j["storage"] = "block";
                        j["block"] = in.blocks[size_t(lay.block_of[i])].name;
                        j["member"] = g.type.is_array() ? fmt::format("{}[{}]", s.name, elem) : s.name;
                        j["offsets"] = std::vector<int>(lay.offsets[i].begin() + long(elem * per), lay.offsets[i].begin() + long((elem + 1) * per));
                        break;
                    case Kind::Texture:
                        j["storage"] = "texture";
                        j["texture"] = in.texture.name;
                        j["offsets"] = std::vector<int>(lay.offsets[i].begin() + long(elem * per), lay.offsets[i].begin() + long((elem + 1) * per));
                        break;
                    case Kind::Private: break;
                }
                j["type"] = glsl::type_name(e);
                j["components"] = e.components();
                if (!g.bounds.lo.empty()) {
                    nlohmann::ordered_json b = nlohmann::ordered_json::array();
                    // (a bounded sequence's bounds are every element's: this element's)
                    const bool each = sequence && g.bounds.lo.size() == size_t(g.type.components());
                    for (size_t c = each ? elem * per : 0; c < (each ? (elem + 1) * per : g.bounds.lo.size()); ++c)
                        b.push_back({g.bounds.lo[c], g.bounds.hi[c]});
                    j["bounds"] = b;
                } else {
                    j["bounds"] = nullptr;
                }
                j["default"] = std::vector<double>(g.value.begin() + long(elem * per), g.value.begin() + long((elem + 1) * per));
                j["description"] = p.description;
                list.push_back(j);
            }
        }
    }
    return list;
}

}  // namespace

SceneCode emit_scene(const SceneIR& scene, const BackendOptions& o, Diagnostics& d) {
    const ir::Module& m = scene.module;
    SceneCode code;
    Layout lay{m, o, {}, {}, {}, {}, code};
    lay.decide();
    code.declarations = Declarations{m, o, lay, code}.run();
    // Host inputs: plain uniforms (GLSL matrices are column-major).
    for (size_t i = 0; i < m.globals.size(); ++i) {
        const Global& g = m.globals[i];
        if (lay.storage[i].kind != Kind::Uniform) continue;
        std::vector<double> v = g.value;
        if (g.type.is_matrix())
            for (int r = 0; r < g.type.rows; ++r)
                for (int c = 0; c < g.type.cols; ++c) v[size_t(c * g.type.rows + r)] = g.value[size_t(r * g.type.cols + c)];
        code.inputs.uniforms.push_back({lay.storage[i].name, v, g.type.kind == Type::Integer});
    }
    for (const auto& b : code.inputs.blocks)
        code.blocks.push_back({{"name", b.name}, {"binding", b.binding}, {"bytes", b.bytes.size()}, {"data", base64(b.bytes.data(), b.bytes.size())}});
    if (!code.inputs.texture.name.empty()) {
        const auto& t = code.inputs.texture;
        code.texture = {{"name", t.name}, {"width", t.width}, {"height", t.height}, {"format", "RGBA32F"},
                        {"data", base64(reinterpret_cast<const uint8_t*>(t.rgba.data()), t.rgba.size() * 4)}};
        if (o.vulkan) code.texture["binding"] = code.inputs.blocks.size() + 1;  // a combined image sampler at set 0
    }
    code.parameters = describe(m, lay, code.inputs);
    // The lights, in the scene's order: name, type (point, sun, sky, bounce) and the uniforms of their
    // position, direction and colour.
    for (size_t i = 0; i < m.globals.size(); ++i) {
        const Global& g = m.globals[i];
        if (g.params.empty() || g.params[0].role != "light") continue;
        const auto& gp = g.params[0];
        nlohmann::ordered_json* jl = nullptr;
        for (auto& e : code.lights)
            if (e["name"] == gp.instance) jl = &e;
        if (!jl) {
            code.lights.push_back({{"name", gp.instance}, {"type", gp.module}});
            jl = &code.lights.back();
        }
        (*jl)[gp.name] = lay.storage[i].name;
    }
    // Functions: what the entry points need, callees first; entries under their fixed names.
    glsl::Namer names;
    for (const auto& s : lay.storage) names.reserve(s.name);
    glsl::Emitter em(m, names, d, &lay.storage);
    std::vector<int> roots;
    for (size_t i = 0; i < m.functions.size(); ++i) {
        const ir::Function& f = m.functions[i];
        if (!f.entry && f.name != ir::names::kPrepare) continue;
        roots.push_back(int(i));
        bool counted = o.instrument && f.name == ir::names::kScene;
        em.set_function_name(int(i), counted ? std::string(ir::names::kScene) + "_counted" : f.name);
    }
    em.limit_loop_iterations(roots, o.evaluations_per_pixel);
    std::string out;
    for (int fn : em.closure(roots)) {
        const ir::Function& f = m.functions[size_t(fn)];
        const char* entry = entry_comment(f.name);
        std::string comment = entry ? entry : o.comments.count(f.name) ? o.comments.at(f.name) : f.name;
        out += "\n" + (f.name == ir::names::kPrepare ? em.procedure(fn, comment) : em.function(fn, comment));
    }
    code.functions = out;
    return code;
}

}  // namespace iqc
