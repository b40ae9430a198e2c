// The engine targets that go through SPIR-V (issue 14): `spirv` (Vulkan GLSL 4.50 compiled to a SPIR-V module)
// and `hlsl` (cross-compiled from it). Every example's output passes the command-line validators of other
// projects (spirv-val, glslangValidator's HLSL front end), its --meta gives the Vulkan layout, and the module
// draws the webgl2 target's picture: translated back to GLSL ES by SPIRV-Cross and drawn on the headless
// renderer with its uniform blocks filled from --meta alone (no Vulkan driver is needed).
#include <catch2/catch.hpp>

#include <cstring>
#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <spirv_glsl.hpp>

#include "TestUtil.h"
#include "glsl/Spirv.h"
#include "glsl/Wgsl.h"
#include "render/Png.h"

using namespace iqc;
using namespace iqc::test;
namespace fs = std::filesystem;

namespace {

std::vector<fs::path> example_inputs() {
    std::vector<fs::path> inputs;
    for (auto& e : fs::directory_iterator(fs::path(IQC_SOURCE_DIR) / "examples"))
        if ((e.path().extension() == ".iq" || e.path().extension() == ".md") && e.path().filename() != "README.md")
            inputs.push_back(e.path());
    std::sort(inputs.begin(), inputs.end());
    return inputs;
}

int shell(const std::string& cmd, std::string* out = nullptr) {
    std::string full = cmd + " 2>&1";
    std::string text;
    FILE* p = popen(full.c_str(), "r");
    if (!p) return -1;
    char buf[4096];
    size_t n;
    while ((n = fread(buf, 1, sizeof buf, p)) > 0) text.append(buf, n);
    int rc = pclose(p);
    if (out) *out = text;
    return WEXITSTATUS(rc);
}

// Pixels whose colours differ by more than 3/255 in some channel; `flip_a`: a's rows bottom to top (a Vulkan
// picture drawn by GL).
int differing_pixels(const render::Image& a, const render::Image& b, bool flip_a = false) {
    int n = 0;
    for (int y = 0; y < b.height; ++y)
        for (int x = 0; x < b.width; ++x) {
            const float* p = a.pixel(x, flip_a ? b.height - 1 - y : y);
            const float* q = b.pixel(x, y);
            float d = 0;
            for (int k = 0; k < 3; ++k) d = std::max(d, std::fabs(p[k] - q[k]));
            n += d > 3.0f / 255;
        }
    return n;
}

void put_floats(std::vector<uint8_t>& bytes, int offset, const std::vector<double>& v) {
    for (size_t i = 0; i < v.size(); ++i) {
        float f = float(v[i]);
        std::memcpy(&bytes[size_t(offset) + 4 * i], &f, 4);
    }
}

}  // namespace

TEST_CASE("spirv, hlsl and threejs targets: every example passes spirv-val, glslangValidator and node --check, with the layout in --meta",
          "[engine-targets]") {
    fs::path dir = temp_dir() / "engine_targets";
    fs::remove_all(dir);
    fs::create_directories(dir);
    for (const auto& in : example_inputs()) {
        std::string stem = in.stem().string();
        fs::path spv = dir / (stem + ".spv"), meta = dir / (stem + ".json"), hlsl = dir / (stem + ".hlsl");
        RunResult s = run_iqc(in.string() + " --target spirv -o " + spv.string() + " --meta " + meta.string());
        INFO(stem << ": " << s.err);
        REQUIRE(s.exit_code == 0);
        std::string bytes = read_text(spv);
        REQUIRE(bytes.size() > 20);
        REQUIRE(bytes.size() % 4 == 0);
        uint32_t magic = 0;
        std::memcpy(&magic, bytes.data(), 4);
        CHECK(magic == 0x07230203u);  // SPIR-V's magic number, little-endian
        std::string log;
        CHECK(shell("spirv-val --target-env vulkan1.0 " + spv.string(), &log) == 0);
        INFO(log);
        auto j = nlohmann::json::parse(read_text(meta));
        CHECK(j["target"] == "spirv");
        REQUIRE(j.contains("inputs_block"));
        CHECK(j["inputs_block"]["binding"] == 0);
        for (const auto& b : j["blocks"]) CHECK(b["binding"].get<int>() >= 1);
        if (j["texture"].is_object()) CHECK(j["texture"]["binding"].get<size_t>() == j["blocks"].size() + 1);
        for (const auto& p : j["parameters"]) CHECK(p["storage"] != "uniform");  // Vulkan has no plain uniforms
        REQUIRE(j["camera"]["defaults"]["iqc_camera_basis"].size() == 9);

        RunResult h = run_iqc(in.string() + " --target hlsl -o " + hlsl.string());
        INFO(h.err);
        REQUIRE(h.exit_code == 0);
        std::string text = read_text(hlsl);
        CHECK_THAT(text, Catch::Contains("cbuffer IqcInputs : register(b0)"));
        CHECK_THAT(text, Catch::Contains("SV_Depth"));
        CHECK(shell("glslangValidator -D -V -e main -S frag -o " + (dir / "hlsl.spv").string() + " " + hlsl.string(), &log) == 0);
        INFO(log);

        // threejs: an ES module node parses, holding the webgl2 shader (without #version) and --meta.
        fs::path mjs = dir / (stem + ".mjs");
        RunResult t = run_iqc(in.string() + " --target threejs -o " + mjs.string());
        INFO(t.err);
        REQUIRE(t.exit_code == 0);
        CHECK(shell("node --check " + mjs.string(), &log) == 0);
        INFO(log);
        std::string module = read_text(mjs);
        CHECK_THAT(module, Catch::Contains("import * as THREE from \"three\";"));
        CHECK_THAT(module, Catch::Contains("export function createMesh(camera"));
        CHECK(std::count_if(module.begin(), module.end(), [](char c) { return (unsigned char)c >= 0x80; }) == 0);  // ASCII: strings escaped
    }
    // A hostile title and description: the module still parses, and `meta` gives them back as written.
    {
        std::string title = "a */ b\n// c `${x}` </script> \u2028 \" ' \\";
        nlohmann::json t = title;
        auto in = write_temp("three_hostile.iq", "title = " + t.dump() + "\n[modules]\nball = \"\"\"\nshape\nD = ‖p‖ - r\nwhere\n"
                                                 "p ∈ ℝ³\nr ∈ [0,3] default = 1: */ `${alert(1)}` </script>\n\"\"\"\n[[shapes]]\ntype = \"ball\"\n");
        fs::path mjs = dir / "three_hostile.mjs";
        RunResult t3 = run_iqc(in.string() + " --target threejs -o " + mjs.string());
        INFO(t3.err);
        REQUIRE(t3.exit_code == 0);
        std::string log;
        CHECK(shell("node --check " + mjs.string(), &log) == 0);
        INFO(log);
        // Evaluate the module's `meta` (its import of three removed) and print what it holds.
        std::string module = read_text(mjs);
        size_t from = module.find("export const meta = "), to = module.find(";\n", from);
        REQUIRE(from != std::string::npos);
        auto js = write_temp("three_hostile_meta.js", "const meta = " + module.substr(from + 20, to - from - 20) +
                                                          ";\nprocess.stdout.write(JSON.stringify([meta.title, meta.parameters[0].description]));\n");
        std::string out;
        REQUIRE(shell("node " + js.string(), &out) == 0);
        auto back = nlohmann::json::parse(out);
        CHECK(back[0] == title);
        CHECK(back[1] == "*/ `${alert(1)}` </script>");
        CHECK(module.find("</script>") == std::string::npos);
    }
    // Binary output needs a file.
    RunResult none = run_iqc(example_inputs()[0].string() + " --target spirv");
    CHECK(none.exit_code == 2);
    CHECK_THAT(none.err, Catch::Contains("--target spirv writes a binary SPIR-V module: give the file with -o"));
}

TEST_CASE("the spirv target draws the webgl2 target's picture, its blocks filled from --meta", "[engine-targets][render]") {
    const int W = 96, H = 54;
    // Parameters in a block; 120 spheres whose transforms read sliders: past WebGL2's 224 uniform vectors, so on
    // webgl2 too their parameters go into blocks (declared in offset order: they were declared in reverse, and
    // webgl2 drew the wrong spheres where distinct values met).
    std::string many = "[camera]\nposition = [0, 4, -14]\ntarget = [0, 0, 0]\n";
    for (int i = 0; i < 120; ++i)
        many += fmt::format("[[shapes]]\ntype = \"sphere\"\nshape_params = {{ r = {} }}\n"
                            "transform = \"\"\"T(X)\nwhere\nX ∈ ℝ³ default = ({}, {}, {})\"\"\"\n",
                            0.2 + 0.003 * i, (i % 12) - 5.5 + 0.01 * i, (i / 12) * 0.8 - 4, 0.05 * (i % 7));
    std::vector<fs::path> inputs = {fs::path(IQC_SOURCE_DIR) / "examples" / "lights_and_effects.iq",
                                    fs::path(IQC_SOURCE_DIR) / "examples" / "two_tori.md", write_temp("spheres_120.iq", many)};
    for (const auto& in : inputs) {
        INFO(in.filename().string());
        CompileOptions wo;
        wo.target = Target::WebGL2;
        Compiled web = compile_path(in, wo);
        REQUIRE(web.result.exit_code == 0);
        CompileOptions vo;
        vo.target = Target::SPIRV;
        Compiled vk = compile_path(in, vo);
        INFO(vk.diagnostics << vk.result.internal);
        REQUIRE(vk.result.exit_code == 0);
        REQUIRE(!vk.result.spirv.empty());
        auto meta = nlohmann::json::parse(vk.result.meta);
        // Back to GLSL ES 3.00 (the renderer's language); blocks keep their names.
        spirv_cross::CompilerGLSL glsl(vk.result.spirv);
        spirv_cross::CompilerGLSL::Options go;
        go.version = 300;
        go.es = true;
        glsl.set_common_options(go);
        std::string es = glsl.compile();
        // The host's work, from --meta only: IqcInputs by its member offsets, the parameter blocks' bytes.
        render::RenderOptions o;
        o.width = W;
        o.height = H;
        const auto& ib = meta["inputs_block"];
        std::vector<uint8_t> inputs((ib["bytes"].get<size_t>() + 15) / 16 * 16, 0);
        const auto& cam = meta["camera"]["defaults"];
        for (const auto& m : ib["members"]) {
            std::string name = m["name"];
            int at = m["offset"];
            if (name == "iqc_camera_basis")  // mat3: three columns on a 16-byte stride
                for (int c = 0; c < 3; ++c)
                    put_floats(inputs, at + 16 * c, {cam[name][size_t(3 * c)], cam[name][size_t(3 * c + 1)], cam[name][size_t(3 * c + 2)]});
            else if (name == "iqc_projection") put_floats(inputs, at, cam[name].get<std::vector<double>>());
            else if (name == "iqc_camera_position") put_floats(inputs, at, cam[name].get<std::vector<double>>());
            else if (name == "iqc_camera_focal") put_floats(inputs, at, {cam[name].get<double>()});
            else if (name == "iResolution") put_floats(inputs, at, {double(W), double(H), 1.0});
        }
        o.uniform_blocks.push_back({ib["name"], 0, inputs});
        for (const auto& b : vk.result.inputs.blocks) o.uniform_blocks.push_back({b.name, b.binding, b.bytes});
        o.data_texture = {vk.result.inputs.texture.name, vk.result.inputs.texture.width, vk.result.inputs.texture.height,
                          vk.result.inputs.texture.rgba};
        std::string err;
        static std::unique_ptr<render::Renderer> renderer = render::Renderer::create(&err);
        REQUIRE(renderer);
        render::RenderResult a = renderer->render(es, o);
        INFO(a.error);
        REQUIRE(a.ok);
        render::RenderResult b = render_compiled(web.result, W, H);
        INFO(b.error);
        REQUIRE(b.ok);
        // Vulkan's framebuffer origin is the top left: drawn by GL, the module's rows come out flipped.
        int differ = differing_pixels(a.image, b.image, true), lit = 0;
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x) {
                const float* q = b.image.pixel(x, y);
                if (q[0] + q[1] + q[2] > 0.05f) ++lit;
            }
        if (differ > W * H / 200) {
            std::ofstream(temp_dir() / ("spirv_" + in.stem().string() + ".frag")) << es;
            render::write_png((temp_dir() / ("spirv_" + in.stem().string() + ".png")).string(), a.image, nullptr);
            render::write_png((temp_dir() / ("webgl2_" + in.stem().string() + ".png")).string(), b.image, nullptr);
        }
        CHECK(differ <= W * H / 200);
        CHECK(lit > W * H / 20);  // a picture, not a blank
        // And webgl2 draws Shadertoy's picture (parameters as constants there).
        Compiled toy = compile_path(in, {});
        REQUIRE(toy.result.exit_code == 0);
        render::RenderResult c = render_compiled(toy.result, W, H);
        REQUIRE(c.ok);
        CHECK(differing_pixels(c.image, b.image) <= W * H / 200);
    }
}

TEST_CASE("matrix parameters as uniforms draw what Shadertoy's constants draw, and threejs refuses non-square ones",
          "[engine-targets][render]") {
    // Found by a new-user trial: a mat2 went to glUniform4fv (GL refused it) and a mat3x2 was never set, so
    // `iqc render --target webgl2` drew A = 0; the page sent matrices with uniform1fv; three.js read --meta's
    // rows as columns. --meta lists a matrix row by row (as written).
    std::string scene = "[modules]\nsheared = \"\"\"\nshape\nD = ‖(A (p_1, p_2), B p)‖ - 1\nwhere\np ∈ ℝ³\n"
                        "A ∈ ℝ^(2×2) default = [1 0.6; 0 1]\nB ∈ ℝ^(2×3) default = [0 0 1; 0.3 0 0.2]\n\"\"\"\n"
                        "[camera]\nposition = [0, 0.5, -4]\ntarget = [0, 0, 0]\n[[shapes]]\ntype = \"sheared\"\n";
    auto in = write_temp("matrices.iq", scene);
    const int W = 80, H = 45;
    Compiled toy = compile_path(in, {});
    REQUIRE(toy.result.exit_code == 0);
    CompileOptions wo;
    wo.target = Target::WebGL2;
    Compiled web = compile_path(in, wo);
    INFO(web.diagnostics);
    REQUIRE(web.result.exit_code == 0);
    auto meta = nlohmann::json::parse(web.result.meta);
    bool row_major = false;
    for (const auto& p : meta["parameters"])
        if (p["name"] == "A") row_major = p["default"] == nlohmann::json::array({1, 0.6, 0, 1});
    CHECK(row_major);
    render::RenderResult a = render_compiled(toy.result, W, H), b = render_compiled(web.result, W, H);
    REQUIRE(a.ok);
    INFO(b.error);
    REQUIRE(b.ok);
    int lit = 0;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x)
            if (std::fabs(a.image.pixel(x, y)[0] - a.image.pixel(0, 0)[0]) > 0.05f) ++lit;
    CHECK(differing_pixels(a.image, b.image) <= W * H / 200);
    CHECK(lit > W * H / 20);
    RunResult t = run_iqc(in.string() + " --target threejs -o " + (temp_dir() / "matrices.mjs").string());
    CHECK(t.exit_code == 1);
    CHECK_THAT(t.err, Catch::Contains("the threejs target cannot take sheared_1's parameter B (a mat3x2 uniform"));
}

TEST_CASE("threejs: plain parameters past WebGL2's uniform vectors go into the data texture and draw Shadertoy's picture",
          "[engine-targets][render]") {
    // The threejs target has no uniform blocks: it refused such a scene (a new-user trial's 150 slider spheres).
    std::string many = "[camera]\nposition = [0, 4, -14]\ntarget = [0, 0, 0]\n";
    for (int i = 0; i < 120; ++i)
        many += fmt::format("[[shapes]]\ntype = \"sphere\"\nshape_params = {{ r = {} }}\n"
                            "transform = \"\"\"T(X)\nwhere\nX ∈ ℝ³ default = ({}, {}, {})\"\"\"\n",
                            0.2 + 0.003 * i, (i % 12) - 5.5 + 0.01 * i, (i / 12) * 0.8 - 4, 0.05 * (i % 7));
    auto in = write_temp("three_spheres_120.iq", many);
    CompileOptions o;
    o.target = Target::ThreeJS;
    Compiled three = compile_path(in, o);
    INFO(three.diagnostics);
    REQUIRE(three.result.exit_code == 0);
    auto meta = nlohmann::json::parse(three.result.meta);
    int in_texture = 0;
    for (const auto& p : meta["parameters"]) in_texture += p["storage"] == "texture";
    CHECK(in_texture >= 120);
    CHECK(meta["blocks"].empty());
    const int W = 96, H = 54;
    Compiled toy = compile_path(in, {});
    REQUIRE(toy.result.exit_code == 0);
    render::RenderResult a = render_compiled(toy.result, W, H), b = render_compiled(three.result, W, H);
    REQUIRE(a.ok);
    INFO(b.error);
    REQUIRE(b.ok);
    CHECK(differing_pixels(a.image, b.image) <= W * H / 200);
    RunResult r = run_iqc(in.string() + " --target threejs -o " + (temp_dir() / "three_spheres_120.mjs").string());
    CHECK(r.exit_code == 0);
}

// ---- wgsl (issue 14): SPIR-V -> WGSL. Tint validates (node + Dawn's null backend); the browser test
// tests/browser/wgsl.test.mjs draws every example with Chromium's WebGPU and compares with iqc render.

namespace {

// Tint's verdict on WGSL files (tests/browser/wgsl-validate.mjs): "" when every file is accepted.
std::string tint_errors(const std::vector<fs::path>& files) {
    std::string cmd = "node '" + (fs::path(IQC_SOURCE_DIR) / "tests/browser/wgsl-validate.mjs").string() + "'";
    for (const auto& f : files) cmd += " '" + f.string() + "'";
    std::string out;
    int rc = shell(cmd, &out);
    return rc == 0 ? "" : out.empty() ? "wgsl-validate failed to run" : out;
}

std::string wgsl_of(const std::string& vulkan_glsl) {
    glsl::SpirvResult spv = glsl::compile_vulkan_fragment(vulkan_glsl);
    INFO(spv.log);
    REQUIRE(spv.ok);
    glsl::WgslResult w = glsl::spirv_to_wgsl(spv.words);
    INFO(w.log);
    REQUIRE(w.ok);
    return w.text;
}

// A Vulkan GLSL shader that uses what the translation must handle beyond the examples: every structured
// construct glslang writes (for/while/do-while loops, break, continue, switch, early return, discard,
// short-circuit && and || and ?: (OpPhi)), std140 strides WGSL does not have (mat2 and mat3x2 columns, float
// and vec2 arrays at 16 bytes), inverse of 2x2/3x3/4x4, integer and bit operations, derivatives, texelFetch.
const char* kConstructs = R"(#version 450
layout(std140, set = 0, binding = 0) uniform Inputs { mat2 m2; float f[4]; vec2 v2[3]; mat3x2 m32; int n; vec3 c; mat2 ms[2]; } u;
layout(set = 0, binding = 1) uniform sampler2D data;
layout(location = 0) out vec4 colour;
float g(inout float x, float y) { x += y; return x * y; }
float first_over(float limit) {
    for (int i = 0; ; ++i) {
        if (float(i) * 0.5 > limit) return float(i);
        if (i > 100) break;
    }
    return -1.0;
}
void main() {
    vec4 acc = vec4(0.0);
    for (int i = 0; i < u.n; ++i) {
        if (i == 2) continue;
        if (acc.x > 10.0) break;
        acc.x += u.f[i] + u.v2[i % 3].y;
        for (int j = 0; j < 3; j++) { if (j == i) break; acc.z += 1.0; }
    }
    int k = 0;
    do { k += 3; } while (k < 10);
    while (k > 20) k -= 5;
    switch (k) { case 1: acc.y = 1.0; break; case 12: case 13: acc.y = 2.0; break; default: acc.y = 3.0; }
    bool b = (acc.x > 1.0 && acc.y < 5.0) || u.c.z > 0.0;
    float t = b ? sin(acc.x) : g(acc.w, acc.y);
    vec2 w = u.m2 * vec2(1.0, 2.0) + u.m32 * vec3(1.0) + u.ms[1][0];
    mat2 i2 = inverse(u.m2);
    mat3 i3 = inverse(mat3(u.c, u.c.yzx, vec3(1.0)));
    mat4 i4 = inverse(mat4(2.0));
    vec4 tex = texelFetch(data, ivec2(k, 0), 0);
    float x = 1.0;
    float r = g(x, t) + first_over(t);
    uint bits = (uint(k) << 2u) | 1u;
    int s = -k >> 1;
    float dd = dFdx(t) + fwidth(w.x);
    if (gl_FragCoord.x < 0.0) discard;
    colour = vec4(acc.xy, w) + tex + vec4(i2[0], i3[1].xy) + i4[2] + vec4(r, float(bits), float(s), dd) +
             vec4(mod(t, 0.3), isnan(t) ? 1.0 : 0.0, float(u.n % 3), float(bits ^ 5u));
}
)";

}  // namespace

TEST_CASE("wgsl: every example's WGSL passes Tint, with --meta's layout and the header", "[engine-targets][wgsl]") {
    std::vector<fs::path> files;
    for (const auto& input : example_inputs()) {
        INFO(input.string());
        fs::path out = temp_dir() / ("wgsl_" + input.stem().string() + ".wgsl");
        fs::path meta = temp_dir() / ("wgsl_" + input.stem().string() + ".json");
        RunResult r = run_iqc(input.string() + " --target wgsl -q -o " + out.string() + " --meta " + meta.string());
        INFO(r.err);
        REQUIRE(r.exit_code == 0);
        std::string text = read_text(out);
        CHECK_THAT(text, Catch::Contains("(wgsl): Vulkan GLSL compiled to SPIR-V, translated to WGSL."));
        CHECK_THAT(text, Catch::Contains("@fragment\nfn fs_main(@builtin(position) "));
        CHECK_THAT(text, Catch::Contains("@vertex\nfn vs_main(@builtin(vertex_index) i: u32)"));
        CHECK_THAT(text, Catch::Contains("@group(0) @binding(0) var<uniform> IqcInputs_data: IqcInputs;"));
        CHECK_THAT(text, Catch::Contains("@builtin(frag_depth) gl_FragDepth: f32"));
        auto j = nlohmann::json::parse(read_text(meta));
        CHECK(j["target"] == "wgsl");
        CHECK(j["inputs_block"]["binding"] == 0);
        for (const auto& b : j["blocks"])
            CHECK_THAT(text, Catch::Contains(fmt::format("@group(0) @binding({}) var<uniform> {}_data: {};", int(b["binding"]),
                                                         std::string(b["name"]), std::string(b["name"]))));
        files.push_back(out);
    }
    REQUIRE(files.size() >= 9);
    CHECK(tint_errors(files).empty());
}

TEST_CASE("wgsl: control flow, std140 strides, inverses and integer operations translate to WGSL Tint accepts",
          "[engine-targets][wgsl]") {
    std::string w = wgsl_of(kConstructs);
    // structure: loops with continuing blocks, break if, switch with a shared case, phis as variables
    CHECK_THAT(w, Catch::Contains("loop {"));
    CHECK_THAT(w, Catch::Contains("continuing {"));
    CHECK_THAT(w, Catch::Contains("break if "));
    CHECK_THAT(w, Catch::Contains("case 12i, 13i: {"));
    CHECK_THAT(w, Catch::Contains("discard;"));
    CHECK_THAT(w, Catch::Contains("var phi: bool;"));
    // std140 kept: mat2 columns and float/vec2 elements at 16 bytes
    CHECK_THAT(w, Catch::Contains("@size(16) v: vec2<f32>,"));
    CHECK_THAT(w, Catch::Contains("@size(16) v: f32,"));
    CHECK_THAT(w, Catch::Contains("m2: array<iqc_stride16_"));
    CHECK_THAT(w, Catch::Contains("fn iqc_inverse2(m: mat2x2<f32>)"));
    CHECK_THAT(w, Catch::Contains("fn iqc_inverse3(m: mat3x3<f32>)"));
    CHECK_THAT(w, Catch::Contains("fn iqc_inverse4(m: mat4x4<f32>)"));
    CHECK_THAT(w, Catch::Contains("textureLoad("));
    CHECK_THAT(w, Catch::Contains("diagnostic(off, derivative_uniformity);"));
    CHECK(wgsl_of(kConstructs) == w);  // deterministic
    auto f = write_temp("constructs.wgsl", w);
    INFO(w);
    CHECK(tint_errors({f}).empty());
}

TEST_CASE("wgsl: the largest float is a literal Tint accepts", "[engine-targets][wgsl]") {
    // A trial: a smooth union of 40 points, -k log ∑_i e^(-d_i/k), is two loops (the stable pass: the largest term,
    // then the sum shifted by it), the first starting from the largest negative float, which the translation wrote
    // as -3.4028235e+38f: the shortest decimal that reads back as that float, but past it, and Tint refused it.
    std::string points;
    for (int k = 0; k < 40; ++k) points += fmt::format("{}({:.3f}, {:.3f}, 0)", k ? ", " : "", std::cos(0.1 * k), std::sin(0.1 * k));
    auto path = write_temp("lse_40.iql", "shape\nD = -0.1 log(∑_i exp(-(‖p - x_i‖ - 0.2)/0.1))\nwhere\np ∈ ℝ³\nx_i ∈ ℝ³ default = {" +
                                         points + "}\n");
    fs::path out = temp_dir() / "lse_40.wgsl";
    RunResult r = run_iqc(path.string() + " --target wgsl -q -o " + out.string());
    INFO(r.err);
    REQUIRE(r.exit_code == 0);
    std::string w = read_text(out);
    CHECK_THAT(w, Catch::Contains("3.4028234663852886e+38f"));
    CHECK_THAT(w, !Catch::Contains("3.4028235e+38f"));
    CHECK(tint_errors({out}).empty());
}

TEST_CASE("wgsl: names that are WGSL keywords or reserved words are renamed", "[engine-targets][wgsl]") {
    std::string w = wgsl_of(R"(#version 450
layout(location = 0) out vec4 colour;
float override(float target) { float loop = target * 2.0; float let = loop; return let; }
void main() { float fn = 1.0; float match = override(fn); colour = vec4(match); }
)");
    CHECK_THAT(w, Catch::Contains("fn override_("));
    CHECK_THAT(w, Catch::Contains("target_"));
    CHECK_THAT(w, Catch::Contains("loop_"));
    CHECK_THAT(w, Catch::Contains("let_"));
    CHECK_THAT(w, Catch::Contains("fn_"));
    auto f = write_temp("keywords.wgsl", w);
    CHECK(tint_errors({f}).empty());
}

TEST_CASE("wgsl: SPIR-V the translation does not know is an error, not WGSL", "[engine-targets][wgsl]") {
    // an implicit-LOD sample (a sampler WGSL would need next to the texture) is not translated
    glsl::SpirvResult spv = glsl::compile_vulkan_fragment(R"(#version 450
layout(set = 0, binding = 0) uniform sampler2D t;
layout(location = 0) out vec4 colour;
void main() { colour = texture(t, gl_FragCoord.xy); }
)");
    REQUIRE(spv.ok);
    glsl::WgslResult w = glsl::spirv_to_wgsl(spv.words);
    CHECK_FALSE(w.ok);
    CHECK_THAT(w.log, Catch::StartsWith("SPIR-V to WGSL: opcode 87"));
    CHECK(w.text.empty());
    CHECK_FALSE(glsl::spirv_to_wgsl({1, 2, 3}).ok);  // not a module
    // and through the driver: exit 3, the bug message, nothing written
    auto in = fs::path(IQC_SOURCE_DIR) / "examples" / "two_tori.md";
    auto out = temp_dir() / "fault.wgsl";
    fs::remove(out);
    RunResult r = run_iqc(in.string() + " --target wgsl --inject-fault wgsl -o " + out.string());
    CHECK(r.exit_code == 3);
    CHECK_THAT(r.err, Catch::Contains("internal compiler error: the shader's SPIR-V could not be translated to WGSL"));
    CHECK_THAT(r.err, Catch::Contains("SPIR-V to WGSL: opcode 106 at module scope"));
    CHECK_FALSE(fs::exists(out));
}

TEST_CASE("wgsl: a Shadertoy shader (.frag) translates to WGSL: its errors are located, other targets need a scene",
          "[engine-targets][wgsl][cli]") {
    auto ok = write_temp("toy.frag", "void mainImage(out vec4 c, in vec2 p) {\n    c = vec4(p / iResolution.xy, 0.5 + 0.5 * sin(iTime), 1.0);\n}\n");
    auto out = temp_dir() / "toy.wgsl", meta = temp_dir() / "toy.json";
    RunResult r = run_iqc(ok.string() + " --target wgsl -o " + out.string() + " --meta " + meta.string());
    INFO(r.err);
    REQUIRE(r.exit_code == 0);
    std::string text = read_text(out);
    CHECK_THAT(text, Catch::StartsWith("// toy.frag: a Shadertoy shader translated to WGSL by iqc"));
    CHECK_THAT(text, Catch::Contains("@group(0) @binding(0) var<uniform> ShadertoyInputs_data: ShadertoyInputs;"));
    auto j = nlohmann::json::parse(read_text(meta));
    CHECK(j["inputs_block"]["bytes"] == 64);
    CHECK(j["inputs_block"]["members"][5]["name"] == "iMouse");
    CHECK(j["inputs_block"]["members"][5]["offset"] == 32);
    CHECK(tint_errors({out}).empty());
    // A shader that declares the wrapper's names itself (a trial: `vec3 iqc_fragColor` was "redefinition", exit 1):
    // the wrapper takes others, and --meta names the block as declared.
    auto clash = write_temp("clash.frag", "vec3 iqc_fragColor = vec3(1.0, 0.5, 0.2);\nstruct ShadertoyInputs { float x; };\n"
                                          "float iqc_color = 0.5;\nvoid mainImage(out vec4 fragColor, in vec2 fragCoord) {\n"
                                          "    ShadertoyInputs s; s.x = iqc_color;\n    fragColor = vec4(iqc_fragColor * s.x, 1.0);\n}\n");
    auto clash_out = temp_dir() / "clash.wgsl", clash_meta = temp_dir() / "clash.json";
    RunResult c = run_iqc(clash.string() + " --target wgsl -o " + clash_out.string() + " --meta " + clash_meta.string());
    INFO(c.err);
    REQUIRE(c.exit_code == 0);
    CHECK(nlohmann::json::parse(read_text(clash_meta))["inputs_block"]["name"] == "ShadertoyInputs_2");
    CHECK_THAT(read_text(clash_out), Catch::Contains("Inputs: ShadertoyInputs_2 (@group(0) @binding(0)"));
    CHECK(tint_errors({clash_out}).empty());
    // a GLSL error: the file's own line, the message, the line shown; exit 1, nothing written
    auto bad = write_temp("bad.frag", "void mainImage(out vec4 c, in vec2 p) {\n    c = vec4(undeclared_thing);\n}\n");
    fs::remove(temp_dir() / "bad.wgsl");
    RunResult e = run_iqc(bad.string() + " --target wgsl -o " + (temp_dir() / "bad.wgsl").string());
    CHECK(e.exit_code == 1);
    // glslang gives no column: the caret goes under the name the message quotes
    CHECK_THAT(e.err, Catch::Contains(bad.string() + ":2:14: error: 'undeclared_thing' : undeclared identifier"));
    CHECK_THAT(e.err, Catch::Contains("      c = vec4(undeclared_thing);\n"
                                      "               ^~~~~~~~~~~~~~~~\n"));
    CHECK_FALSE(fs::exists(temp_dir() / "bad.wgsl"));
    // Shadertoy's textures are not declared: said so
    auto tex = write_temp("tex.frag", "void mainImage(out vec4 c, in vec2 p) { c = texture(iChannel0, p); }\n");
    RunResult t = run_iqc(tex.string() + " --target wgsl -o -");
    CHECK(t.exit_code == 1);
    CHECK_THAT(t.err, Catch::Contains("tex.frag:1:53: error: 'iChannel0' : undeclared identifier"));
    CHECK_THAT(t.err, Catch::Contains("iChannel textures are not declared"));
    // another target: a usage error
    RunResult u = run_iqc(ok.string() + " --target webgl2 -o -");
    CHECK(u.exit_code == 2);
    CHECK_THAT(u.err, Catch::Contains("is translated only with --target wgsl"));
}

TEST_CASE("plain parameters past 11 uniform blocks go into the data texture: no 13th block, no empty texture",
          "[engine-targets][wgsl][instancing]") {
    // 75 instances of a shape with 40 mat4 parameters, each instance moved by a slider (so none share a
    // table): 3,000 mat4 = 192 KB of plain parameters, more than 11 blocks of 16 KiB hold (a trial found
    // 13 blocks, past WebGL2's and WebGPU's 12 per stage, and a 0x0 texture in --meta).
    std::string sum, params;
    for (int k = 0; k < 40; ++k) {
        sum += fmt::format("{}`a{}`", k ? " + " : "", k);
        params += fmt::format("`a{}` ∈ ℝ^(4×4) default = [1 0 0 0; 0 1 0 0; 0 0 1 0; 0 0 0 1]\n", k);
    }
    std::string scene = "[modules]\nheavy = \"\"\"\nshape\nD = ‖p‖ - 0.3 - 0.001((" + sum + ")(1, 0, 0, 0))_1\nwhere\np ∈ ℝ³\n" +
                        params + "\"\"\"\n[camera]\nposition = [0, 15, -30]\n";
    for (int i = 0; i < 75; ++i)
        scene += fmt::format("[[shapes]]\ntype = \"heavy\"\ntransform = \"\"\"\nT(X)\nwhere\nX ∈ ℝ³ default = ({}, 0, {})\"\"\"\n",
                             i % 10 - 5, i / 10);
    auto in = write_temp("many_blocks.iq", scene);
    for (const char* target : {"webgl2", "wgsl"}) {
        INFO(target);
        auto out = temp_dir() / (std::string("many_blocks.") + target), meta = temp_dir() / (std::string("many_blocks_") + target + ".json");
        RunResult r = run_iqc(in.string() + " --target " + target + " -q -o " + out.string() + " --meta " + meta.string());
        INFO(r.err);
        REQUIRE(r.exit_code == 0);
        auto j = nlohmann::json::parse(read_text(meta));
        CHECK(j["blocks"].size() <= 11);
        REQUIRE(j["texture"].is_object());
        CHECK(int(j["texture"]["width"]) > 0);
        CHECK(int(j["texture"]["height"]) > 0);
        if (std::string(target) == "wgsl") CHECK(tint_errors({out}).empty());
    }
    // a scene whose arrays alone need the texture: every plain parameter keeps its block, the texture is not empty
    auto rings = temp_dir() / "rings_400_blocks.iq";
    // (tilted about two axes, each ring by its own angle about y: a whole matrix per ring, where a tilt about x alone
    // is two scalar tables, and tilts that repeat keep one period)
    REQUIRE(shell("bash '" + std::string(IQC_SOURCE_DIR) + "/bench/rings.sh' 400 irregular | awk '/`R_x`\\(/ { n++; sub(/`R_x`\\(/, "
                  "sprintf(\"`R_y`(%.4f)⋅`R_x`(\", 0.3 + 0.0007 * n)) } { print }' > '" + rings.string() + "'") == 0);
    RunResult r = run_iqc(rings.string() + " --target wgsl -q -o " + (temp_dir() / "r400.wgsl").string() + " --meta " +
                          (temp_dir() / "r400.json").string());
    REQUIRE(r.exit_code == 0);
    auto j = nlohmann::json::parse(read_text(temp_dir() / "r400.json"));
    CHECK(int(j["texture"]["height"]) > 0);
}

TEST_CASE("instances with sequence parameters read them in place, in a loop: no array is copied per evaluation",
          "[engine-targets][render]") {
    // A new user's trial: three instances of a shape whose distance sums over its own 300-point sequence took
    // llvmpipe 71 s for the first frame at 160x90 on webgl2 (62 ms as Shadertoy's constants): the finite-difference
    // normal's dispatch chose the hit instance's whole array into a local copy (`vec3 tmp[300] = m_1_shape_x; if
    // (id == 1) tmp = m_2_shape_x;`), every call copied the array from its uniform block into the function, and
    // the ∑ was unrolled into 300 loads. Now: calls that differ in an array are not merged (the pass `calls`), a
    // copy of the function reads its instance's array in place (`arrays`) and the sum is a loop.
    std::string points;
    for (int k = 0; k < 300; ++k) points += fmt::format("{}({}, {}, {})", k ? ", " : "", (k % 7) * 0.01, (k % 5) * 0.01, (k % 3) * 0.01);
    // (a sum that reads p: one that does not is computed once per pixel, before marching: the pass `hoist`)
    std::string text = "[modules]\nm = \"\"\"\nshape\nD = ‖p‖ - 0.3 - ∑_i ‖p - x_i‖ 1e-4\nwhere\np ∈ ℝ³\nx_i ∈ ℝ³ default = {" + points +
                       "}\n\"\"\"\n[camera]\nposition = [0.5, 0, -3]\ntarget = [0.5, 0, 0]\n";
    for (int k = 0; k < 3; ++k) text += fmt::format("[[shapes]]\ntype = \"m\"\ntransform = \"T(({}, 0, 0))\"\n", k * 0.5);
    auto path = write_temp("seq_300_x3.iq", text);
    CompileOptions o;
    o.target = Target::WebGL2;
    Compiled web = compile_path(path, o);
    INFO(web.diagnostics);
    REQUIRE(web.result.exit_code == 0);
    const std::string& code = web.result.code;
    CHECK_THAT(code, !Catch::Contains("vec3 tmp[300]"));     // no choice of arrays
    CHECK_THAT(code, !Catch::Contains("vec3 x[300]"));       // no array parameter (a copy per call)
    CHECK_THAT(code, Catch::Contains("m_2_shape_x[i]"));     // read in place, in the loop
    CHECK_THAT(code, !Catch::Contains("m_1_shape_x[299]"));  // not unrolled
    Compiled st = compile_path(path, {});
    REQUIRE(st.result.exit_code == 0);
    const int W = 48, H = 27;
    render::RenderResult a = render_compiled(web.result, W, H), b = render_compiled(st.result, W, H);
    INFO(a.error << b.error);
    REQUIRE(a.ok);
    REQUIRE(b.ok);
    CHECK(differing_pixels(a.image, b.image) == 0);
    // (and the sums shrink the balls: a ball of 0.3 alone differs)
    Compiled small = compile_path(write_temp("seq_300_ball.iq", "[camera]\nposition = [0.5, 0, -3]\ntarget = [0.5, 0, 0]\n"
                                             "[[shapes]]\ntype = \"sphere\"\nshape_params = { r = 0.3 }\n"), {});
    REQUIRE(small.result.exit_code == 0);
    render::RenderResult c = render_compiled(small.result, W, H);
    REQUIRE(c.ok);
    CHECK(differing_pixels(a.image, c.image) > 20);
}

TEST_CASE("a sum over pairs of a sequence's points draws on webgl2 as on Shadertoy", "[engine-targets][render]") {
    // A new user's trial: ∑_i ∑_j ‖x_i - x_j‖ over 40 points, two nested loops on webgl2, drew a wrong rim (306
    // pixels at 160x90): llvmpipe ends a shader invocation after 65,535 loop iterations in all, and 1,640 per
    // evaluation ran out on the rays that take the most steps. The inner sum is unrolled in the outer loop now.
    std::string points;
    for (int k = 0; k < 40; ++k) {
        double a = 2 * M_PI * k / 40;
        points += fmt::format("{}({:.4f}, {:.4f}, {:.4f})", k ? ", " : "", 1.2 * std::cos(a), 0.7 * std::sin(2 * a), 1.2 * std::sin(a));
    }
    auto path = write_temp("pairs_40.iq", "[modules]\nblob = \"\"\"\nshape\nD = ‖p‖ - 0.2 - s/1600\ns = ∑_i ∑_j ‖x_i - x_j‖\nwhere\n"
                                          "p ∈ ℝ³\nx_i ∈ ℝ³ default = {" + points + "}\n\"\"\"\n[camera]\nposition = [0, 1, -3]\n"
                                          "target = [0, 0, 0]\n[[shapes]]\ntype = \"blob\"\n");
    CompileOptions o;
    o.target = Target::WebGL2;
    Compiled web = compile_path(path, o), st = compile_path(path, {});
    REQUIRE(web.result.exit_code == 0);
    REQUIRE(st.result.exit_code == 0);
    CHECK_THAT(web.result.code, Catch::Contains("for (int i = 0; i <= 39; i++) {"));
    CHECK_THAT(web.result.code, !Catch::Contains("for (int j"));
    const int W = 96, H = 54;
    render::RenderResult a = render_compiled(web.result, W, H), b = render_compiled(st.result, W, H);
    REQUIRE(a.ok);
    REQUIRE(b.ok);
    CHECK(differing_pixels(a.image, b.image) == 0);
}

TEST_CASE("a sum that reads nothing of p is computed once per pixel before marching", "[engine-targets][render]") {
    // A trial: a blob centred on the weighted centroid of its 100 points, c = ∑_i w_i x_i / ∑_j w_j, ran both sums
    // at every step (two 100-trip loops per evaluation); a constant ∑_i ∑_j ∑_k over 100 points on webgl2 did not
    // draw in 120 s. The pass `hoist` makes c a prepared global that iqc_prepare computes: the scene function reads
    // it and holds no loop. The evaluator (iqc bench's reference) computes it the same way.
    const int n = 100;
    std::string points, weights;
    double sw = 0, sx[3] = {0, 0, 0};
    for (int k = 0; k < n; ++k) {
        double a = 2 * M_PI * k / n, x[3] = {0.3 * std::cos(a) + 0.2, 0.2 * std::sin(a), 0.1 * std::sin(3 * a)}, w = 1 + 0.5 * std::sin(k);
        points += fmt::format("{}({}, {}, {})", k ? ", " : "", x[0], x[1], x[2]);
        weights += fmt::format("{}{}", k ? ", " : "", w);
        sw += w;
        for (int c = 0; c < 3; ++c) sx[c] += w * x[c];
    }
    auto path = write_temp("centroid.iq", "[modules]\nblob = \"\"\"\nshape\nD = ‖p - c‖ - 0.5\nc = ∑_i w_i x_i / ∑_j w_j\nwhere\n"
                                          "p ∈ ℝ³\nx_i ∈ ℝ³ default = {" + points + "}\nw_i ∈ ℝ default = {" + weights + "}\n\"\"\"\n"
                                          "[camera]\nposition = [0, 0.5, -3]\ntarget = [0, 0, 0]\n[[shapes]]\ntype = \"blob\"\n");
    CompileOptions o;
    o.target = Target::WebGL2;
    Compiled web = compile_path(path, o), st = compile_path(path, {});
    REQUIRE(web.result.exit_code == 0);
    REQUIRE(st.result.exit_code == 0);
    for (const std::string* code : {&web.result.code, &st.result.code}) {
        const std::string& c = *code;
        size_t prepare = c.find("void iqc_prepare() {"), scene = c.find("vec2 iqc_scene(vec3 p) {");
        REQUIRE(prepare != std::string::npos);
        CHECK(c.find("for (", prepare) < c.find("\n}", prepare));  // the sums' loops are in iqc_prepare
        CHECK_THAT(c, Catch::Contains("pixel_c = "));
        REQUIRE(scene != std::string::npos);
        CHECK(c.find("for (", scene) > c.find("\n}", scene));  // and none in the scene's distance
    }
    // The reference (the evaluator, which runs iqc_prepare at the first read of a prepared global).
    REQUIRE(web.result.model);
    for (auto p : {std::array<double, 3>{0, 0, 0}, std::array<double, 3>{1, -0.5, 2}}) {
        double d = std::hypot(p[0] - sx[0] / sw, p[1] - sx[1] / sw, p[2] - sx[2] / sw) - 0.5;
        CHECK(web.result.model->distance(p) == Approx(d).epsilon(1e-12));
    }
    const int W = 64, H = 36;
    render::RenderResult a = render_compiled(web.result, W, H), b = render_compiled(st.result, W, H);
    REQUIRE(a.ok);
    REQUIRE(b.ok);
    CHECK(differing_pixels(a.image, b.image) == 0);
}

TEST_CASE("rolled sums are unrolled further where a pixel's evaluations would run out llvmpipe's loop budget",
          "[engine-targets]") {
    // llvmpipe ends an invocation after 65,535 loop iterations in all. A trial's 30 instances with two 40-point sums
    // each (2,400 iterations per scene evaluation) drew blocks of the blobs wrong. The emitter counts a pixel's
    // evaluations (the step cap here) and unrolls the sums' loops until their iterations fit.
    std::string points;
    for (int k = 0; k < 40; ++k) points += fmt::format("{}({}, 0, 0)", k ? ", " : "", 0.01 * k);
    auto scene = [&](int max_steps) {
        return "[render]\nmax_steps = " + std::to_string(max_steps) + "\n[modules]\nblob = \"\"\"\nshape\nD = ‖p‖ - 0.3 - ∑_i ‖p - x_i‖ 1e-4\nwhere\n"
               "p ∈ ℝ³\nx_i ∈ ℝ³ default = {" + points + "}\n\"\"\"\n[[shapes]]\ntype = \"blob\"\n[[shapes]]\ntype = \"blob\"\n"
               "transform = \"T((1, 0, 0))\"\nshape_params = { x = \"{" + points + "}\" }\n";
    };
    CompileOptions o;
    o.target = Target::WebGL2;
    Compiled few = compile_path(write_temp("budget_128.iq", scene(128)), o);
    Compiled many = compile_path(write_temp("budget_4000.iq", scene(4000)), o);
    REQUIRE(few.result.exit_code == 0);
    REQUIRE(many.result.exit_code == 0);
    // 128 steps: 80 iterations per evaluation fit (60,000 / 132); 4,000 steps: 15 per evaluation, so each sum's
    // loop runs 7 iterations of 6 terms.
    CHECK_THAT(few.result.code, Catch::Contains("for (int i = 0; i <= 39; i++) {"));
    CHECK_THAT(few.result.code, !Catch::Contains("(unrolled by"));
    CHECK_THAT(many.result.code, !Catch::Contains("for (int i = 0; i <= 39; i++) {"));
    CHECK_THAT(many.result.code, Catch::Contains("i0 += 6) {  // (unrolled by 6)"));
}

TEST_CASE("a sequence past a block's 16 KiB is read in place from the data texture, and matrices past mat4 are errors",
          "[engine-targets][wgsl][render]") {
    // A new user's trial: a sequence parameter of 1,025 numbers, passed whole to the module's function, went into
    // the data texture (16,400 bytes of std140: past a block's 16 KiB) and was read by a name nothing declared
    // (glslang rejected the shader: exit 3 on webgl2, spirv and wgsl). Then a function gathered it, texel by
    // texel into a local array per call (Mesa's compile of 1,025 vectors did not finish). Now the module's
    // function is a copy that reads the global (the pass `arrays`), and its ∑ is a loop fetching element i.
    std::string values;
    for (int k = 0; k < 1025; ++k) values += fmt::format("{}{}", k ? ", " : "", (k % 7) * 0.5);
    // (a scene with a fixed camera: a shape module alone is framed by its box, and balls of two radii look alike)
    auto scene = [](const std::string& distance, const std::string& params = "") {
        return "[modules]\nm = \"\"\"\nshape\n" + distance + "\nwhere\np ∈ ℝ³\n" + params + "\"\"\"\n[camera]\nposition = [0, 0, -3]\ntarget = [0, 0, 0]\n"
               "[[shapes]]\ntype = \"m\"\n";
    };
    auto seq = write_temp("seq_1025.iq", scene("D = ‖p‖ - 0.3 - ∑_i x_i 2e-4", "x_i ∈ ℝ default = {" + values + "}\n"));
    CompileOptions o;
    o.target = Target::WebGL2;
    Compiled web = compile_path(seq, o);
    INFO(web.diagnostics);
    REQUIRE(web.result.exit_code == 0);
    CHECK_THAT(web.result.code, Catch::Contains("iqc_fetch(i"));
    CHECK_THAT(web.result.code, Catch::Contains("for (int "));
    CHECK_THAT(web.result.code, !Catch::Contains("float[1025]"));    // no gathering function
    CHECK_THAT(web.result.code, !Catch::Contains("iqc_fetch(1024)")); // no unrolled fetches
    // It draws the ball of radius 0.3 + Σ x_k 2e-4 (0.6069): the texture's values are read. (Shadertoy's constant
    // table of 1,025 floats took Mesa's compiler past 3 GB, so the references are plain balls.)
    const int W = 32, H = 18;
    auto ball = [&](const char* name, const char* r) {
        Compiled c = compile_path(write_temp(name, scene(std::string("D = ‖p‖ - ") + r)), {});
        REQUIRE(c.result.exit_code == 0);
        render::RenderResult img = render_compiled(c.result, W, H);
        REQUIRE(img.ok);
        return img.image;
    };
    render::Image big_ball = ball("ball_06069.iq", "0.6069"), small_ball = ball("ball_03.iq", "0.3");
    render::RenderResult b = render_compiled(web.result, W, H);
    INFO(b.error);
    REQUIRE(b.ok);
    CHECK(differing_pixels(b.image, big_ball) == 0);
    CHECK(differing_pixels(b.image, small_ball) > 10);
    std::string zero_values;
    for (int k = 0; k < 1025; ++k) zero_values += k ? ", 0" : "0";
    auto zeros = write_temp("seq_1025_0.iq", scene("D = ‖p‖ - 0.3 - ∑_i x_i 2e-4", "x_i ∈ ℝ default = {" + zero_values + "}\n"));
    Compiled web0 = compile_path(zeros, o);
    REQUIRE(web0.result.exit_code == 0);
    render::RenderResult c = render_compiled(web0.result, W, H);
    REQUIRE(c.ok);
    CHECK(differing_pixels(c.image, small_ball) == 0);
    for (const char* target : {"spirv", "wgsl", "threejs"}) {
        INFO(target);
        RunResult r = run_iqc(seq.string() + " --target " + target + " -q -o " + (temp_dir() / (std::string("seq_1025.") + target)).string());
        INFO(r.err);
        CHECK(r.exit_code == 0);
        if (std::string(target) == "wgsl") CHECK(tint_errors({temp_dir() / "seq_1025.wgsl"}).empty());
    }

    // A matrix past mat4 has no std140 or texel layout: packing it wrote past its element (heap corruption,
    // exit 134, on spirv, hlsl and wgsl; a sequence of them on webgl2 too). The error, located, on every target.
    auto big = write_temp("mat7.iql", "shape\nD = ‖p‖ - 1\nwhere\np ∈ ℝ³\nC ∈ ℝ^(7×7)\n");
    std::string m7 = "[1 1 1 1 1 1 1";
    for (int r = 1; r < 7; ++r) m7 += "; 1 1 1 1 1 1 1";
    m7 += "]";
    auto big_seq = write_temp("mat7_seq.iql", "shape\nD = ‖p‖ - x_1,1,1\nwhere\np ∈ ℝ³\nx_i ∈ ℝ^(7×7) default = {" + m7 + ", " + m7 + ", " + m7 + "}\n");
    for (const auto& in : {big, big_seq})
        for (const char* target : {"shadertoy", "webgl2", "glsl330", "spirv", "hlsl", "wgsl", "threejs", "cpp", "html"}) {
            INFO(in.string() << " " << target);
            auto out = temp_dir() / (in.stem().string() + "." + target);
            fs::remove(out);
            RunResult r = run_iqc(in.string() + " --target " + target + " -o " + out.string());
            CHECK(r.exit_code == 1);
            CHECK_THAT(r.err, Catch::Contains(in.filename().string() + ":5:1: error: cannot generate GLSL: ℝ^(7×7) is larger than "
                                              "GLSL's largest matrix (mat4)"));
            CHECK_THAT(r.err, Catch::Contains("\n  ^"));
            CHECK_FALSE(fs::exists(out));
        }
}

TEST_CASE("instances sharing a shape with sequence parameters compile on every target, with an --meta entry per element",
          "[engine-targets][wgsl][render]") {
    // A new user's trial: four instances of a shape with x_i ∈ ℝ³ became a group whose per-member table of sequences
    // was an array of arrays (invalid IR, exit 3, on every target but Shadertoy), and Shadertoy's --meta read past
    // the shared sequence (entries for x[2] and x[3] of a 2-element array, garbage defaults, different every run).
    std::string scene = "[modules]\nblob = \"\"\"\nshape\nD = ‖p‖ - r + 0.01(x_2,1 + w_1)\nwhere\np ∈ ℝ³\nr ∈ [0.05,0.5] default = 0.2\n"
                        "x_i ∈ ℝ³ default = {(1, 0, 0), (0, 1, 0)}\nw_j ∈ ℝ default = {0.5, 0.25, 0.125}\n\"\"\"\n";
    for (int i = 0; i < 4; ++i) scene += fmt::format("[[shapes]]\ntype = \"blob\"\ntransform = \"T(({}, 0, 6))\"\n", i - 2);
    auto in = write_temp("seq_group.iq", scene);
    for (const char* target : {"shadertoy", "webgl2", "glsl330", "spirv", "hlsl", "wgsl", "threejs", "cpp", "html"}) {
        INFO(target);
        auto out = temp_dir() / (std::string("seq_group.") + target), meta = temp_dir() / (std::string("seq_group_") + target + ".json");
        RunResult r = run_iqc(in.string() + " --target " + target + " -q -o " + out.string() + " --meta " + meta.string());
        INFO(r.err);
        REQUIRE(r.exit_code == 0);
        std::string first = read_text(meta);
        RunResult again = run_iqc(in.string() + " --target " + target + " -q -o " + out.string() + " --meta " + meta.string());
        REQUIRE(again.exit_code == 0);
        CHECK(read_text(meta) == first);
        auto j = nlohmann::json::parse(first);
        // per instance: r, x_1, x_2, w_1, w_2, w_3
        REQUIRE(j["parameters"].size() == 24);
        int x2 = 0;
        for (const auto& p : j["parameters"]) {
            if (p["name"] == "x_2") {
                ++x2;
                CHECK(p["type"] == "vec3");
                CHECK(p["default"] == nlohmann::json::array({0.0, 1.0, 0.0}));
            }
            CHECK(p["name"] != "x");
        }
        CHECK(x2 == 4);
        if (std::string(target) == "wgsl") CHECK(tint_errors({out}).empty());
    }
    CompileOptions o;
    o.target = Target::WebGL2;
    Compiled toy = compile_path(in, {}), web = compile_path(in, o);
    REQUIRE(toy.result.exit_code == 0);
    REQUIRE(web.result.exit_code == 0);
    render::RenderResult a = render_compiled(toy.result, 96, 54), b = render_compiled(web.result, 96, 54);
    REQUIRE(a.ok);
    REQUIRE(b.ok);
    CHECK(differing_pixels(a.image, b.image) == 0);
}

TEST_CASE("names that are keywords of GLSL 4.50, HLSL or their reserved words are renamed on every target", "[engine-targets][wgsl]") {
    // A new user's trial: an instance named `sampler`, a module `float3`, a parameter `shared` reached the Vulkan
    // GLSL or SPIRV-Cross's HLSL as they were, and glslang refused them (exit 3).
    for (const char* name : {"sampler", "shared", "coherent", "texture2D", "itexture3D", "subpassInput", "float3", "half4x4",
                             "auto", "new", "operator", "typename", "private", "globallycoherent", "lerp", "saturate", "matrix"}) {
        INFO(name);
        std::string scene = fmt::format("[modules]\n{0} = \"\"\"\nshape\nD = ‖p‖ - `{0}`\nwhere\np ∈ ℝ³\n`{0}` ∈ [0.1, 2] default = 1\n\"\"\"\n"
                                        "[[shapes]]\nname = \"{0}\"\ntype = \"{0}\"\n",
                                        name);
        auto in = write_temp(std::string("kw_") + name + ".iq", scene);
        for (const char* target : {"shadertoy", "glsl330", "spirv", "hlsl", "wgsl"}) {
            INFO(target);
            RunResult r = run_iqc(in.string() + " --target " + target + " -q -o " + (temp_dir() / (std::string("kw.") + target)).string());
            INFO(r.err);
            CHECK(r.exit_code == 0);
        }
    }
}
