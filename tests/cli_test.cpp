// The command line: exit codes, output files, and every scene-level error path with its message and
// location (unknown shape or material, a shape without D, a material without C, TOML errors, a document
// without a scene block, an unreadable file).
#include <catch2/catch.hpp>

#include <chrono>
#include <cstdlib>
#include <vector>

#include "TestUtil.h"
#include "render/Png.h"
#include "render/Render.h"
#include "ir/Pipeline.h"

using namespace iqc::test;

static const char* kTorus = R"(❤: torus
```iheartla
shape
D = ‖q‖ - t_2
q = (‖(p_1, p_3)‖ - t_1, p_2)
where
p ∈ ℝ³
t ∈ [0,2]x[0,2] default = (0.77, 0.6)
```
)";

static RunResult compile_doc(const std::string& name, const std::string& text) {
    auto p = write_temp(name, text);
    return run_iqc(p.string());
}

TEST_CASE("help and version flags and usage errors", "[cli]") {
    RunResult h = run_iqc("--help");
    CHECK(h.exit_code == 0);
    CHECK_THAT(h.out, Catch::Contains("Exit codes"));
    RunResult v = run_iqc("--version");
    CHECK(v.exit_code == 0);
    CHECK_THAT(v.out, Catch::StartsWith("iqc "));
    CHECK(run_iqc("").exit_code == 2);
    CHECK(run_iqc("--no-such-flag x.md").exit_code == 2);
    CHECK(run_iqc("x.md --target nowhere").exit_code == 2);
    // An empty file name (`-o "$OUT"` with OUT unset) is a usage error, not standard output.
    auto ball = write_temp("usage_ball.iql", "shape\nD = ‖p‖ - 1\nwhere\np ∈ ℝ³\n");
    for (const char* opt : {"-o ''", "--meta ''", "--depfile ''", "-o x.frag --meta ''"}) {
        INFO(opt);
        RunResult r = run_iqc(ball.string() + " " + opt);
        CHECK(r.exit_code == 2);
        CHECK(r.out.empty());
        CHECK_THAT(r.err, Catch::Contains("an empty file name"));
    }
    RunResult png = run_iqc("render " + ball.string() + " -o ''");
    CHECK(png.exit_code == 2);
    CHECK_THAT(png.err, Catch::Contains("an empty file name"));
}

TEST_CASE("a successful compile writes the file and exits 0", "[cli]") {
    auto in = write_temp("ok.md", std::string(kTorus) + "```scene\n[[shapes]]\ntype = \"torus\"\n```\n");
    auto out = temp_dir() / "ok.frag";
    RunResult r = run_iqc(in.string() + " -o " + out.string());
    INFO(r.err);
    CHECK(r.exit_code == 0);
    std::string code = read_text(out);
    CHECK_THAT(code, Catch::Contains("void mainImage(out vec4 fragColor, in vec2 fragCoord)"));
    // Standard output when -o is absent, byte-identical (deterministic).
    RunResult s = run_iqc(in.string());
    CHECK(s.exit_code == 0);
    CHECK(s.out == code);
}

TEST_CASE("unknown shape and material", "[cli]") {
    RunResult r = compile_doc("unknown_shape.md", std::string(kTorus) + "```scene\n[[shapes]]\ntype = \"tours\"\n```\n");
    CHECK(r.exit_code == 1);
    CHECK_THAT(r.err, Catch::Contains("unknown_shape.md:12:8: error: unknown shape 'tours'"));
    CHECK_THAT(r.err, Catch::Contains("note: did you mean 'torus'?"));
    CHECK_THAT(r.err, Catch::Contains("  type = \"tours\"\n         ^~~~~~~"));
    RunResult m = compile_doc("unknown_material.md",
                              std::string(kTorus) + "```scene\n[[shapes]]\ntype = \"torus\"\nmaterial = \"phongg\"\n```\n");
    CHECK(m.exit_code == 1);
    CHECK_THAT(m.err, Catch::Contains("unknown_material.md:13:12: error: unknown material 'phongg'"));
}

TEST_CASE("a shape without D and a material without C", "[cli]") {
    RunResult r = compile_doc("no_d.md", "❤: blob\n```iheartla\nshape\nd = ‖p‖ - 1\nwhere\np ∈ ℝ³\n```\n"
                                         "```scene\n[[shapes]]\ntype = \"blob\"\n```\n");
    CHECK(r.exit_code == 1);
    CHECK_THAT(r.err, Catch::Contains("no_d.md:3:1: error: shape 'blob' does not assign 'D' (its signed distance)"));
    RunResult m = compile_doc("no_c.md", std::string(kTorus) +
                                             "❤: flat\n```iheartla\nmaterial\ncolour = (1, 0, 0)\nwhere\np ∈ ℝ³\nN ∈ ℝ³\nI ∈ ℝ³\n```\n"
                                             "```scene\n[[shapes]]\ntype = \"torus\"\nmaterial = \"flat\"\n```\n");
    CHECK(m.exit_code == 1);
    CHECK_THAT(m.err, Catch::Contains("no_c.md:12:1: error: material 'flat' does not assign 'C' (its RGB colour)"));
    // A `D = …` that fails to parse is reported there, once: not also as missing (a trial's, stop 56: every parse error
    // in D was followed by "does not assign 'D'").
    RunResult p = compile_doc("bad_d.md", "❤: blob\n```iheartla\nshape\nD = |p_1 - 1\nwhere\np ∈ ℝ³\n```\n"
                                          "```scene\n[[shapes]]\ntype = \"blob\"\n```\n");
    CHECK(p.exit_code == 1);
    CHECK_THAT(p.err, Catch::Contains("bad_d.md:5:1: error: expected '|' to close the absolute value, found 'where'"));
    CHECK_THAT(p.err, !Catch::Contains("does not assign"));
}

TEST_CASE("a shape or material with a bare expression is an error located at the expression", "[cli][diag]") {
    // The fuzzer's find: a shape's bare ℝ³ expression replaced D as its value (internal error, exit 3).
    RunResult r = compile_doc("bare_shape.md", "❤: blob\n```iheartla\nshape\nq\nq = a\nD = ‖q‖\nwhere\np ∈ ℝ³\na ∈ ℝ³\n```\n"
                                               "```scene\n[[shapes]]\ntype = \"blob\"\n```\n");
    CHECK(r.exit_code == 1);
    CHECK_THAT(r.err, Catch::Contains("bare_shape.md:4:1: error: a shape has no bare value: its value is what it assigns to 'D' "
                                      "(write D = …)\n  q\n  ^"));
    RunResult m = compile_doc("bare_material.md", std::string(kTorus) +
                                                      "❤: flat\n```iheartla\nmaterial\nC = (1, 0, 0)\nN + I\nwhere\np ∈ ℝ³\nN ∈ ℝ³\nI ∈ ℝ³\n```\n"
                                                      "```scene\n[[shapes]]\ntype = \"torus\"\nmaterial = \"flat\"\n```\n");
    CHECK(m.exit_code == 1);
    CHECK_THAT(m.err, Catch::Contains("bare_material.md:14:1: error: a material has no bare value"));
}

TEST_CASE("an undefined name inside a module of a document", "[cli]") {
    RunResult r = compile_doc("undefined.md", "❤: ball\n```iheartla\nshape\nD = ‖p‖ - radius\nwhere\np ∈ ℝ³\n```\n"
                                              "```scene\n[[shapes]]\ntype = \"ball\"\n```\n");
    CHECK(r.exit_code == 1);
    CHECK_THAT(r.err, Catch::Contains("undefined.md:4:11: error: undefined name 'radius'"));
}

TEST_CASE("TOML syntax errors carry their line", "[cli]") {
    RunResult r = compile_doc("bad.iq", "title = \"x\"\n\n[[shapes]]\ntype = \"sphere\nmaterial = 1\n");
    CHECK(r.exit_code == 1);
    CHECK_THAT(r.err, Catch::Contains("bad.iq:4:"));
    CHECK_THAT(r.err, Catch::Contains("error: invalid TOML"));
    RunResult d = compile_doc("bad_doc.md", std::string(kTorus) + "```scene\n[[shapes]]\ntype = = \"torus\"\n```\n");
    CHECK(d.exit_code == 1);
    CHECK_THAT(d.err, Catch::Contains("bad_doc.md:12:8: error: invalid TOML"));
}

TEST_CASE("scene schema errors: unknown fields and wrong types", "[cli]") {
    RunResult r = compile_doc("schema.iq", "[[shapes]]\ntpye = \"torus\"\ntype = 3\n");
    CHECK(r.exit_code == 1);
    CHECK_THAT(r.err, Catch::Contains("schema.iq:2:1: error: unknown field 'tpye' in [[shapes]]"));
    CHECK_THAT(r.err, Catch::Contains("did you mean 'type'?"));
    CHECK_THAT(r.err, Catch::Contains("schema.iq:3:8: error: 'type' must be a string, not an integer"));
}

TEST_CASE("a document without a scene block", "[cli]") {
    RunResult r = compile_doc("noscene.md", kTorus);
    CHECK(r.exit_code == 1);
    CHECK_THAT(r.err, Catch::Contains("noscene.md:1:1: error: the document has no scene block"));
}

TEST_CASE("an unreadable file", "[cli]") {
    RunResult r = run_iqc((temp_dir() / "does_not_exist.md").string());
    CHECK(r.exit_code == 1);
    CHECK_THAT(r.err, Catch::Contains("error: cannot read '"));
    CHECK_THAT(r.err, Catch::Contains("does_not_exist.md': No such file or directory"));
    RunResult d = run_iqc(temp_dir().string());
    CHECK(d.exit_code == 1);
    CHECK_THAT(d.err, Catch::Contains("it is a directory"));
}

TEST_CASE("transform errors: not a 4×4 matrix, singular", "[cli]") {
    RunResult r = compile_doc("tr.md", std::string(kTorus) + "```scene\n[[shapes]]\ntype = \"torus\"\ntransform = \"(1, 2, 3)\"\n```\n");
    CHECK(r.exit_code == 1);
    CHECK_THAT(r.err, Catch::Contains("tr.md:13:14: error: a transform must be a 4×4 matrix, but this is ℝ³"));
    RunResult s = compile_doc("sing.md", std::string(kTorus) +
                                             "```scene\n[[shapes]]\ntype = \"torus\"\ntransform = \"S((1, 0, 1))\"\n```\n");
    CHECK(s.exit_code == 1);
    CHECK_THAT(s.err, Catch::Contains("sing.md:13:14: error: the transform is singular"));
    // Invertible, but scales 10³⁰ apart: not "singular" (a trial found that word for it)
    RunResult c = compile_doc("cond.md", std::string(kTorus) +
                                             "```scene\n[[shapes]]\ntype = \"torus\"\ntransform = \"[1e30 0 0 0; 0 1 0 0; 0 0 1 0; 0 0 0 1]\"\n```\n");
    CHECK(c.exit_code == 1);
    CHECK_THAT(c.err, Catch::Contains("cond.md:13:14: error: the transform is too badly conditioned to invert: its condition number is 1.4e+30"));
    // The same scale on every axis is well conditioned: it compiles.
    RunResult u = compile_doc("uni.md", std::string(kTorus) +
                                            "```scene\n[[shapes]]\ntype = \"torus\"\ntransform = \"S((1e20, 1e20, 1e20))\"\n```\n");
    CHECK(u.exit_code == 0);
    RunResult ut = run_iqc((temp_dir() / "uni.md").string() + " -o -");
    CHECK_THAT(ut.out, Catch::Contains("torus_1_to_object = mat3(1.0e-20);"));
    // A translation with it: the adjugate's inverse offset is −L⁻¹t.
    RunResult t = compile_doc("unit.md", std::string(kTorus) + "```scene\n[[shapes]]\ntype = \"torus\"\ntransform = "
                                                              "\"T((1e20, 2e20, 0))⋅S((1e20, 1e20, 1e20))\"\n```\n");
    CHECK(t.exit_code == 0);
    RunResult tt = run_iqc((temp_dir() / "unit.md").string() + " -o -");
    CHECK_THAT(tt.out, Catch::Contains("vec3(-1.0, -2.0, 0.0)"));
    // Values the shader would compute with outside float32 (a trial's: silently flushed to 0 or clamped), and a
    // scale so small that the scene's reach squares to ∞ in object space: located errors.
    RunResult huge = compile_doc("huge.md", std::string(kTorus) + "```scene\n[[shapes]]\ntype = \"torus\"\ntransform = \"S((10^60, 10^60, 10^60))\"\n```\n");
    CHECK(huge.exit_code == 1);
    CHECK_THAT(huge.err, Catch::Contains("huge.md:13:14: error: the transform leaves float32's range, which shaders compute in: its inverse holds 1e-60"));
    RunResult far = compile_doc("far.md", std::string(kTorus) + "```scene\n[[shapes]]\ntype = \"torus\"\ntransform = \"T((3e38, 0, 0))T((3e38, 0, 0))\"\n```\n");
    CHECK(far.exit_code == 1);
    CHECK_THAT(far.err, Catch::Contains("far.md:13:14: error: the transform leaves float32's range"));
    RunResult tiny = compile_doc("tiny.md", std::string(kTorus) + "```scene\n[[shapes]]\ntype = \"torus\"\ntransform = \"S((1e-20, 1e-20, 1e-20))\"\n```\n");
    CHECK(tiny.exit_code == 1);
    CHECK_THAT(tiny.err, Catch::Contains("tiny.md:13:14: error: the transform maps the scene's reach (max_dist 100 around the camera) to object coordinates up to"));
    // Right-angle turns and a scale: products of rounding's coefficients (cos(π/2) = 6e-17) fall below float32's
    // range beside entries near 1 (4.6e-49 here); they are 0, not an error (a trial's: 18 of 280 turned transforms).
    for (const char* transform : {"`R_y`(π)⋅`R_x`(π/2)⋅`R_z`(π)⋅S((3, 3, 2))", "`R_z`(π)⋅`R_x`(π/2)⋅S((3, 3, 2))",
                                  "`R_x`(-π/2)⋅`R_y`(2π)⋅S((3, 2, 2))"}) {
        INFO(transform);
        RunResult turned = compile_doc("turned.md", std::string(kTorus) + "```scene\n[[shapes]]\ntype = \"torus\"\ntransform = \"" +
                                                        transform + "\"\n```\n");
        CHECK(turned.exit_code == 0);
        CHECK(turned.err.find("error") == std::string::npos);
    }
}

TEST_CASE("parameter overrides name real parameters with the right size", "[cli]") {
    RunResult r = compile_doc("ov.md", std::string(kTorus) +
                                           "```scene\n[[shapes]]\ntype = \"torus\"\nshape_params = { r = 1, t = [1, 2, 3] }\n```\n");
    CHECK(r.exit_code == 1);
    CHECK_THAT(r.err, Catch::Contains("ov.md:13:18: error: shape 'torus' has no parameter 'r'"));
    CHECK_THAT(r.err, Catch::Contains("ov.md:13:25: error: 't' is ℝ² but the value has 3 components"));
}

TEST_CASE("a shader glslang rejects is an internal error: exit 3 and nothing written", "[cli]") {
    auto in = write_temp("fault.md", std::string(kTorus) + "```scene\n[[shapes]]\ntype = \"torus\"\n```\n");
    auto out = temp_dir() / "fault.frag";
    std::filesystem::remove(out);
    RunResult r = run_iqc(in.string() + " --inject-fault glslang -o " + out.string());
    CHECK(r.exit_code == 3);
    CHECK_THAT(r.err, Catch::Contains("internal compiler error: glslang rejected the generated shader (this is a bug in iqc"));
    CHECK_THAT(r.err, Catch::Contains("ERROR"));
    CHECK_FALSE(std::filesystem::exists(out));
}

TEST_CASE("an internal error in any pass is exit 3 with the bug message, for compile and eval", "[cli]") {
    auto in = write_temp("fault_pass.md", std::string(kTorus) + "```scene\n[[shapes]]\ntype = \"torus\"\n```\n");
    auto out = temp_dir() / "fault_pass.frag";
    for (const auto& p : iqc::ir::pipeline_passes()) {
        std::filesystem::remove(out);
        INFO(p.name);
        RunResult r = run_iqc(in.string() + " --inject-fault " + p.name + " -o " + out.string());
        CHECK(r.exit_code == 3);
        CHECK_THAT(r.err, Catch::Contains(std::string("internal compiler error: ") + p.name +
                                          ": injected fault (--inject-fault) (this is a bug in iqc; nothing was written)"));
        CHECK_FALSE(std::filesystem::exists(out));
        RunResult e = run_iqc("eval " + in.string() + " --module torus --inject-fault " + p.name);
        CHECK(e.exit_code == 3);
        CHECK_THAT(e.err, Catch::Contains(std::string("internal compiler error: ") + p.name + ": injected fault"));
        CHECK(e.out.empty());
    }
}

TEST_CASE("the IR after a named pass (--dump-ir=after-PASS), and an unknown pass is a usage error", "[cli]") {
    auto in = write_temp("dump_pass.md", std::string(kTorus) + "```scene\n[[shapes]]\ntype = \"torus\"\n```\n");
    RunResult lower = run_iqc(in.string() + " --dump-ir=after-lower -o " + (temp_dir() / "dump.frag").string());
    CHECK(lower.exit_code == 0);
    CHECK_THAT(lower.err, Catch::Contains("inline function iqc_distance.torus_1(p: ℝ³) -> ℝ {"));
    RunResult inl = run_iqc(in.string() + " --dump-ir=after-inline -o " + (temp_dir() / "dump.frag").string());
    CHECK(inl.exit_code == 0);
    CHECK_THAT(inl.err, Catch::Contains("Call torus %"));
    CHECK_THAT(inl.err, Catch::Contains("  ; torus_1"));
    RunResult last = run_iqc(in.string() + " --dump-ir -o " + (temp_dir() / "dump.frag").string());
    CHECK_THAT(last.err, !Catch::Contains("iqc_distance.torus_1"));  // inlined, then removed by dce
    CHECK_THAT(last.err, Catch::Contains("entry function iqc_scene(p: ℝ³) -> ℝ² {"));
    RunResult bad = run_iqc(in.string() + " --dump-ir=after-frobnicate");
    CHECK(bad.exit_code == 2);
    CHECK_THAT(bad.err, Catch::Contains("--dump-ir takes after-PASS with PASS one of lower, stable, lipschitz, inline, tables, fold"));
}

TEST_CASE("scene keys: a Greek letter by its ASCII name, a name without its underscore, an unquoted θ", "[cli]") {
    // theta is θ: the same shader as the quoted key, and not the default's.
    auto quoted = write_temp("greek_q.iq", "[[shapes]]\ntype = \"capped_torus\"\nshape_params = { \"θ\" = 1.0 }\n");
    auto ascii = write_temp("greek_a.iq", "[[shapes]]\ntype = \"capped_torus\"\nshape_params = { theta = 1.0 }\n");
    auto plain = write_temp("greek_d.iq", "[[shapes]]\ntype = \"capped_torus\"\n");
    std::string out_q = (quoted.parent_path() / "greek_q.glsl").string(), out_a = (quoted.parent_path() / "greek_a.glsl").string(),
                out_d = (quoted.parent_path() / "greek_d.glsl").string();
    REQUIRE(run_iqc(quoted.string() + " -o " + out_q).exit_code == 0);
    REQUIRE(run_iqc(ascii.string() + " -o " + out_a).exit_code == 0);
    REQUIRE(run_iqc(plain.string() + " -o " + out_d).exit_code == 0);
    auto body = [](const std::string& path) {  // the shader without its header, which names the input file
        std::string t = read_text(path);
        return t.substr(t.find("// ---- settings"));
    };
    CHECK(body(out_a) == body(out_q));
    CHECK(body(out_a) != body(out_d));
    // kd is k_d: did you mean, at the key.
    RunResult kd = compile_doc("kd.iq", "[[shapes]]\ntype = \"torus\"\nmaterial = \"phong\"\nmaterial_params = { kd = [0.1, 0.2, 0.3] }\n");
    CHECK(kd.exit_code == 1);
    CHECK_THAT(kd.err, Catch::Contains("kd.iq:4:21: error: material 'phong' has no parameter 'kd'"));
    CHECK_THAT(kd.err, Catch::Contains("kd.iq:4:21: note: did you mean 'k_d'?"));
    // An unquoted θ is not a TOML key: say to quote it.
    RunResult th = compile_doc("theta.iq", "[[shapes]]\ntype = \"capped_torus\"\nshape_params = { θ = 1.0 }\n");
    CHECK(th.exit_code == 1);
    CHECK_THAT(th.err, Catch::Contains("theta.iq:3:18: error: invalid TOML"));
    CHECK_THAT(th.err, Catch::Contains("theta.iq:3:18: note: a TOML key with letters such as θ must be quoted (\"θ\" = 1); "
                                       "a Greek letter may also be written with its ASCII name (theta = 1)"));
}

TEST_CASE("the depfile (--depfile) names the outputs and every file the compile read, as absolute paths", "[cli][depfile]") {
    namespace fs = std::filesystem;
    fs::path dir = temp_dir() / "depfile case";  // a space, escaped in the rule
    fs::remove_all(dir);
    fs::create_directories(dir / "mods");
    {
        std::ofstream(dir / "mods" / "ring.iql") << "shape\nD = ‖q‖ - r\nq = (‖(p_1, p_3)‖ - 1, p_2)\nwhere\np ∈ ℝ³\n"
                                                    "r ∈ [0,1] default = 0.25\n";
        std::ofstream(dir / "blob.iql") << "shape\nD = ‖p‖ - 0.5\nwhere\np ∈ ℝ³\n";  // looked up beside the scene
        std::ofstream(dir / "scene.iq") << "include = [\"mods/ring.iql\"]\n[[shapes]]\ntype = \"ring\"\n"
                                           "[[shapes]]\ntype = \"blob\"\n[[shapes]]\ntype = \"box\"\n";
    }
    std::string q = "'" + dir.string();
    RunResult r = run_iqc(q + "/scene.iq' -o " + q + "/out.frag' --meta " + q + "/out.json' --depfile " + q + "/out.d'");
    INFO(r.err);
    REQUIRE(r.exit_code == 0);
    std::string esc = dir.string();
    for (size_t k = 0; (k = esc.find(' ', k)) != std::string::npos; k += 2) esc.insert(k, "\\");
    std::string expected = esc + "/out.frag " + esc + "/out.json: \\\n  " + esc + "/scene.iq \\\n  " + esc +
                           "/mods/ring.iql \\\n  " + esc + "/blob.iql\n";
    CHECK(read_text(dir / "out.d") == expected);  // the standard library's `box` is inside iqc: not a file
    // Without an output file there is nothing to name: a usage error.
    RunResult u = run_iqc(q + "/scene.iq' --depfile " + q + "/x.d'");
    CHECK(u.exit_code == 2);
    CHECK_THAT(u.err, Catch::Contains("--depfile needs an output file (-o FILE)"));
    // A failed compile writes no depfile (the build keeps the last good one).
    fs::remove(dir / "out.d");
    std::ofstream(dir / "mods" / "ring.iql") << "shape\nD = ‖p‖ - nope\nwhere\np ∈ ℝ³\n";
    RunResult bad = run_iqc(q + "/scene.iq' -o " + q + "/out.frag' --depfile " + q + "/out.d'");
    CHECK(bad.exit_code == 1);
    CHECK_FALSE(fs::exists(dir / "out.d"));
}

TEST_CASE("outputs whose bytes did not change are left alone, and --quiet prints diagnostics only", "[cli][depfile]") {
    namespace fs = std::filesystem;
    auto in = write_temp("unchanged.md", std::string(kTorus) + "```scene\n[[shapes]]\ntype = \"torus\"\n```\n");
    fs::path out = temp_dir() / "unchanged.frag", meta = temp_dir() / "unchanged.json";
    fs::remove(out);
    RunResult first = run_iqc(in.string() + " -o " + out.string() + " --meta " + meta.string());
    REQUIRE(first.exit_code == 0);
    CHECK_THAT(first.err, Catch::Contains("iqc: wrote " + out.string()));
    auto old_time = fs::last_write_time(out);
    auto old_meta_time = fs::last_write_time(meta);
    fs::last_write_time(out, old_time - std::chrono::hours(1));  // any rewrite would move it forward again
    fs::last_write_time(meta, old_meta_time - std::chrono::hours(1));
    RunResult second = run_iqc(in.string() + " -o " + out.string() + " --meta " + meta.string());
    REQUIRE(second.exit_code == 0);
    CHECK_THAT(second.err, Catch::Contains("iqc: " + out.string() + " is unchanged"));
    CHECK(fs::last_write_time(out) == old_time - std::chrono::hours(1));
    CHECK(fs::last_write_time(meta) == old_meta_time - std::chrono::hours(1));
    // A changed output is rewritten; --quiet says nothing about it.
    RunResult third = run_iqc(in.string() + " --target webgl2 -o " + out.string() + " --quiet");
    REQUIRE(third.exit_code == 0);
    CHECK(third.err.empty());
    CHECK_THAT(read_text(out), Catch::StartsWith("#version 300 es"));
    // --quiet keeps warnings.
    auto warn = write_temp("quiet_warn.iq", "[[shapes]]\ntype = \"sphere\"\n[effects]\nshadows = \"soft\"\n");
    RunResult w = run_iqc(warn.string() + " -o " + (temp_dir() / "quiet_warn.frag").string() + " -q");
    CHECK(w.exit_code == 0);
    CHECK_THAT(w.err, Catch::Contains("warning:"));
    CHECK_THAT(w.err, !Catch::Contains("wrote"));
}

TEST_CASE("iqc render makes the output's folder, and says so when it cannot, and takes -q", "[cli][render]") {
    // `iqc render --frames 3 -o frames/a.png` failed when frames/ did not exist.
    auto dir = temp_dir() / "render_new_dir" / "frames";
    std::filesystem::remove_all(dir.parent_path());
    std::string scene = (std::filesystem::path(IQC_SOURCE_DIR) / "examples" / "two_tori.md").string();
    RunResult r = run_iqc("render " + scene + " --size 32x18 --frames 3 -o " + (dir / "a.png").string());
    INFO(r.err);
    CHECK(r.exit_code == 0);
    for (int k = 0; k < 3; ++k) CHECK(std::filesystem::exists(dir / ("a_000" + std::to_string(k) + ".png")));
    CHECK_THAT(r.err, Catch::Contains("iqc: rendered"));
    RunResult q = run_iqc("render " + scene + " --size 32x18 -q -o " + (dir / "q.png").string());
    CHECK(q.exit_code == 0);
    CHECK(q.err.empty());  // -q, as the compile command takes it
    // A folder that cannot be made: a path through a regular file.
    auto file = write_temp("render_not_a_dir", "x");
    RunResult bad = run_iqc("render " + scene + " --size 32x18 -o " + (file / "sub" / "a.png").string());
    CHECK(bad.exit_code == 1);
    CHECK_THAT(bad.err, Catch::Contains("iqc: error: cannot create the folder '" + (file / "sub").string() + "' for the PNG:"));
}

TEST_CASE("iqc render draws a Shadertoy shader as it is", "[cli][render]") {
    // A hand-written reference beside iqc's output: mainImage, as pasted into Shadertoy.
    auto frag = write_temp("hand.frag", "void mainImage(out vec4 fragColor, in vec2 fragCoord) {\n"
                                        "    fragColor = vec4(fragCoord.x < 0.5 * iResolution.x ? 1.0 : 0.0, 0.25, 0.0, 1.0);\n}\n");
    auto png = temp_dir() / "hand.png";
    RunResult r = run_iqc("render " + frag.string() + " -o " + png.string() + " --size 32x16");
    INFO(r.err);
    REQUIRE(r.exit_code == 0);
    iqc::render::Image img;
    REQUIRE(iqc::render::read_png(png.string(), img, nullptr));
    CHECK(img.width == 32);
    CHECK(img.pixel(4, 8)[0] > 0.99f);
    CHECK(img.pixel(28, 8)[0] < 0.01f);
    CHECK(img.pixel(28, 8)[1] == Approx(0.25).margin(0.01));
    // The driver's errors at the file's own lines and columns (FILE:LINE:COL, the line, a caret under the
    // name the message quotes); a scene's options are refused.
    auto bad = write_temp("bad.frag", "// a comment\nvoid mainImage(out vec4 c, in vec2 f) {\n\tc = vec4(undeclared);\n    c += nope(c);\n}\n");
    RunResult e = run_iqc("render " + bad.string() + " -o " + (temp_dir() / "bad.png").string());
    CHECK(e.exit_code == 1);
    CHECK_THAT(e.err, Catch::Contains(bad.string() + ":3:11: error: `undeclared' undeclared\n"
                                      "  \tc = vec4(undeclared);\n"
                                      "  \t         ^~~~~~~~~~\n"));  // (the caret's indent keeps the line's tab)
    CHECK_THAT(e.err, Catch::Contains(bad.string() + ":4:10: error: no function with name 'nope'\n"
                                      "      c += nope(c);\n"
                                      "           ^~~~\n"));
    CHECK_THAT(e.err, !Catch::Contains("0:3("));
    // The preprocessor's errors too (Mesa: `0:L(C): preprocessor error: …`).
    auto pre = write_temp("pre.frag", "// fine\n#error stop here\nvoid mainImage(out vec4 c, in vec2 f) { c = vec4(1.0); }\n");
    RunResult pe = run_iqc("render " + pre.string() + " -o " + (temp_dir() / "pre.png").string());
    CHECK(pe.exit_code == 1);
    CHECK_THAT(pe.err, Catch::Contains(pre.string() + ":2:1: error: #error stop here\n  #error stop here\n  ^"));
    // An error in no line of the file (Shadertoy's main calls a mainImage the file lacks): unlocated.
    auto nomain = write_temp("nomain.frag", "void main_image(out vec4 c, in vec2 f) { c = vec4(1.0); }\n");
    RunResult n = run_iqc("render " + nomain.string() + " -o " + (temp_dir() / "nomain.png").string());
    CHECK(n.exit_code == 1);
    CHECK_THAT(n.err, Catch::Contains("error: no function with name 'mainImage'"));
    RunResult s = run_iqc("render " + frag.string() + " -o " + png.string() + " --stats");
    CHECK(s.exit_code == 2);
    CHECK_THAT(s.err, Catch::Contains("--stats and --target need a scene"));
}

TEST_CASE("every bench scene's hand-written reference draws iqc's picture (50 dB or more)", "[cli][render][handwritten]") {
    // bench/handwritten.sh times iqc against bench/reference/X.frag: a comparison only while both draw the same
    // picture. A change to iqc's pictures of the bench scenes fails here until the references follow it.
    namespace fs = std::filesystem;
    fs::path root = IQC_SOURCE_DIR;
    int n = 0;
    for (const auto& e : fs::directory_iterator(root / "bench" / "reference")) {
        if (e.path().extension() != ".frag") continue;
        fs::path scene = root / "bench" / (e.path().stem().string() + ".iq");
        INFO(e.path().string());
        REQUIRE(fs::exists(scene));
        auto a = temp_dir() / ("ref_iqc_" + e.path().stem().string() + ".png");
        auto b = temp_dir() / ("ref_hand_" + e.path().stem().string() + ".png");
        REQUIRE(run_iqc("render " + scene.string() + " --size 160x90 -q -o " + a.string()).exit_code == 0);
        REQUIRE(run_iqc("render " + e.path().string() + " --size 160x90 -q -o " + b.string()).exit_code == 0);
        iqc::render::Image ia, ib;
        REQUIRE(iqc::render::read_png(a.string(), ia, nullptr));
        REQUIRE(iqc::render::read_png(b.string(), ib, nullptr));
        REQUIRE(ia.rgba.size() == ib.rgba.size());
        const double psnr = psnr_8bit(ia, ib);
        INFO("PSNR " << psnr << " dB");
        CHECK(psnr >= 50);
        ++n;
    }
    CHECK(n >= 8);
}

TEST_CASE("bench/ablate's edited copies of iqc's shaders draw iqc's pictures", "[cli][render][ablate]") {
    // bench/ablate.sh times each copy against iqc's shader: a comparison only while they draw the same picture,
    // and only while the edits still find the code they change (a variant not written fails here).
    namespace fs = std::filesystem;
    const fs::path root = IQC_SOURCE_DIR;
    struct Case {
        const char* scene;
        std::vector<const char*> variants;  // the ones that must be written (each pixel as iqc's)
    };
    const std::vector<Case> cases = {
        {"bench/few_shapes.iq", {"hitid", "noid", "normal"}},
        {"bench/grazing_thin.iq", {"hitid", "noid", "normal"}},
        {"bench/displaced_torus.iq", {"hitid", "normal"}},  // (no noid: its nearness reads the instance's factor)
        {"golden/effects/shadows_soft.iq", {"hitid", "noid", "normal", "shadow"}},
        {"golden/effects/shadows_hard.iq", {"hitid", "noid", "normal", "shadow"}},
    };
    auto read = [](const fs::path& png) {
        iqc::render::Image im;
        REQUIRE(iqc::render::read_png(png.string(), im, nullptr));
        return im;
    };
    for (const Case& c : cases) {
        INFO(c.scene);
        const std::string stem = fs::path(c.scene).stem().string();
        const fs::path frag = temp_dir() / ("ablate_" + stem + ".frag"), png = temp_dir() / ("ablate_" + stem + ".png");
        REQUIRE(run_iqc((root / c.scene).string() + " -o " + frag.string()).exit_code == 0);
        const fs::path prefix = temp_dir() / ("ablate_" + stem);
        REQUIRE(std::system(("python3 '" + (root / "bench" / "ablate" / "variants.py").string() + "' '" + frag.string() + "' '" +
                             prefix.string() + "'").c_str()) == 0);
        REQUIRE(run_iqc("render " + frag.string() + " --size 160x90 -q -o " + png.string()).exit_code == 0);
        const iqc::render::Image ref = read(png);
        for (const char* v : c.variants) {
            INFO(v);
            const fs::path vf = prefix.string() + "_" + v + ".frag", vp = prefix.string() + "_" + v + ".png";
            REQUIRE(fs::exists(vf));
            REQUIRE(run_iqc("render " + vf.string() + " --size 160x90 -q -o " + vp.string()).exit_code == 0);
            const iqc::render::Image im = read(vp);
            CHECK(im.rgba == ref.rgba);
        }
    }
}

TEST_CASE("the hand-written references in bench/handwritten render without NaN", "[cli][render]") {
    // Shadertoy shaders written by hand for the examples (issue 15's blind ranking, issue 17's comparison).
    int n = 0;
    for (const auto& e : std::filesystem::directory_iterator(std::filesystem::path(IQC_SOURCE_DIR) / "bench" / "handwritten")) {
        if (e.path().extension() != ".frag") continue;
        INFO(e.path().string());
        iqc::render::RenderOptions o;
        o.width = 96;
        o.height = 54;
        auto r = iqc::render::render_shadertoy(read_text(e.path()), o);
        INFO(r.error);
        REQUIRE(r.ok);
        int nan = 0;
        for (float v : r.image.rgba) nan += !std::isfinite(v);
        CHECK(nan == 0);
        ++n;
    }
    CHECK(n >= 5);
}
