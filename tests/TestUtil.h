// Helpers shared by the tests: temporary files, running the iqc binary, compiling and evaluating
// modules in process.
#pragma once

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <sys/wait.h>

#include "ir/Builder.h"
#include "ir/Eval.h"
#include "ir/Lower.h"
#include "render/Render.h"
#include "scene/Compile.h"
#include "scene/Modules.h"
#include "sema/Builtins.h"
#include "sema/Check.h"
#include "syntax/Parser.h"

namespace iqc::test {

inline std::string read_text(const std::filesystem::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::ostringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

// A directory of this process's own, one per test case: a file one case writes (a module `torus.iql`) must not
// be found by the next (a scene beside it whose `type = "torus"` would take that module for the standard
// library's: run in one process, "a bound too small…" failed after the eval tests had written their torus).
// The directory is removed when the process exits (ctest runs each case in a process of its own, and a suite
// run left ~330 directories, 1.7 GB after a few weeks of runs); IQC_KEEP_TEST_FILES=1 keeps it, to look at.
inline std::filesystem::path temp_dir() {
    struct Root {
        std::filesystem::path path = std::filesystem::temp_directory_path() / ("iqc_tests_" + std::to_string(::getpid()));
        ~Root() {
            std::error_code ec;
            if (!std::getenv("IQC_KEEP_TEST_FILES")) std::filesystem::remove_all(path, ec);
        }
    };
    static const Root root;
    std::string name = Catch::getResultCapture().getCurrentTestName();
    char tag[32];
    std::snprintf(tag, sizeof tag, "case_%016zx", std::hash<std::string>{}(name));
    auto d = root.path / tag;
    std::filesystem::create_directories(d);
    return d;
}

inline std::filesystem::path write_temp(const std::string& name, const std::string& text) {
    auto p = temp_dir() / name;
    std::ofstream(p, std::ios::binary) << text;
    return p;
}

struct RunResult {
    int exit_code = -1;
    std::string out, err;
};

// Runs the iqc binary with the given arguments (a shell-quoted string) and environment assignments.
inline RunResult run_iqc_env(const std::string& env, const std::string& args) {
    auto out = temp_dir() / "stdout.txt";
    auto err = temp_dir() / "stderr.txt";
    std::string cmd = env + " " + std::string(IQC_BINARY) + " " + args + " >" + out.string() + " 2>" + err.string() + " </dev/null";
    int status = std::system(cmd.c_str());
    RunResult r;
    r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = read_text(out);
    r.err = read_text(err);
    return r;
}

// Compiles a file in process; returns the result and the rendered diagnostics.
struct Compiled {
    CompileResult result;
    std::string diagnostics;
};
inline RunResult run_iqc(const std::string& args) { return run_iqc_env("", args); }

inline Compiled compile_path(const std::filesystem::path& p, const CompileOptions& opts = {}) {
    SourceManager sm;
    Diagnostics d(sm);
    Compiled c;
    c.result = compile_file(p.string(), sm, d, opts);
    c.diagnostics = d.render();
    return c;
}
inline Compiled compile_text(const std::string& name, const std::string& text) { return compile_path(write_temp(name, text)); }

// How many times `what` occurs in `text` (non-overlapping): "error:" in a compile's diagnostics.
inline size_t count_of(const std::string& text, const std::string& what) {
    size_t n = 0;
    for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + what.size())) ++n;
    return n;
}

// PSNR in dB of two images of one size over their 8-bit channels, as ImageMagick's `compare -metric PSNR` (1e9 where
// they are equal).
inline double psnr_8bit(const render::Image& a, const render::Image& b) {
    double se = 0;
    for (size_t i = 0; i < a.rgba.size() && i < b.rgba.size(); ++i) {
        const double d = std::round(a.rgba[i] * 255.0) - std::round(b.rgba[i] * 255.0);
        se += d * d;
    }
    const double mse = se / double(a.rgba.size()) / (255.0 * 255.0);
    return mse == 0 ? 1e9 : 10 * std::log10(1 / mse);
}

// Renders a compiled shader of any target on the headless renderer with what its host sets (uniform
// defaults, uniform blocks, the data texture).
inline render::RenderResult render_compiled(const CompileResult& c, int w, int h, float time = 0) {
    render::RenderOptions o;
    o.width = w;
    o.height = h;
    o.time = time;
    for (const auto& u : c.inputs.all_uniforms()) {
        if (u.integer) o.int_uniforms.push_back({u.name, int(u.value[0])});
        else o.uniforms.push_back({u.name, std::vector<float>(u.value.begin(), u.value.end())});
    }
    for (const auto& b : c.inputs.blocks) o.uniform_blocks.push_back({b.name, b.binding, b.bytes});
    o.data_texture = {c.inputs.texture.name, c.inputs.texture.width, c.inputs.texture.height, c.inputs.texture.rgba};
    bool shadertoy = c.code.rfind("#version", 0) != 0;
    if (shadertoy) return render::render_shadertoy(c.code, o);
    static std::unique_ptr<render::Renderer> renderer;
    std::string err;
    if (!renderer) renderer = render::Renderer::create(&err);
    if (!renderer) {
        render::RenderResult r;
        r.error = err;
        return r;
    }
    return renderer->render(c.code, o);
}

// Parses, checks, lowers and evaluates a standalone module (a function library may import
// trigonometry); returns every output (assigned name or "ret") formatted as `iqc eval` prints values.
struct Evaluated {
    bool ok = false;
    std::string diagnostics;
    std::map<std::string, ir::Value> outputs;
    std::map<std::string, std::string> text;  // formatted
};
inline Evaluated eval_module(const std::string& source, const std::map<std::string, std::vector<double>>& set = {}) {
    SourceManager sm;
    Diagnostics d(sm);
    FileId f = sm.add("test.iql", source);
    ParseOptions po;
    for (const auto& n : known_names()) po.known_names.insert(n);
    ast::Module m = parse_module(sm, f, {{0, uint32_t(source.size())}}, "test", po, d);
    Evaluated e;
    if (d.has_errors()) {
        e.diagnostics = d.render();
        return e;
    }
    auto cm = check_module(std::move(m), nullptr, {}, d);
    if (d.has_errors()) {
        e.diagnostics = d.render();
        return e;
    }
    ir::Module irm;
    LowerContext ctx{irm, {}, {}};
    int fn = lower_module(*cm, "test", "test", ctx);
    std::string fault = ir::verify(irm.functions[size_t(fn)], irm);
    if (!fault.empty()) {
        e.diagnostics = "invalid IR: " + fault;
        return e;
    }
    std::vector<ir::Value> args;
    for (const auto& p : cm->params) {
        auto it = set.find(p.name);
        args.push_back({p.type, it != set.end() ? it->second : p.value});
    }
    auto all = ir::evaluate_all(irm, fn, args);
    const ir::Function& F = irm.functions[size_t(fn)];
    for (auto& [name, v] : F.outputs) {
        e.outputs[name] = all[v];
        e.text[name] = ir::format_value(all[v]);
    }
    if (cm->ret) {
        e.outputs["ret"] = all[F.result];
        e.text["ret"] = ir::format_value(all[F.result]);
    }
    e.ok = true;
    return e;
}

inline double scalar_of(const Evaluated& e, const std::string& name) { return e.outputs.at(name).v.at(0); }

// Shape module `text` (module `name`, file `path`) lowered into `m` with an object function q ∈ ℝ³ -> D(q),
// every other parameter at its default, appended last: its index, or -1 for a module that is not a shape.
// `seen`, when given, is called with the checked module (its pragmas: exactness, Lipschitz bound).
inline int lower_shape_object(ir::Module& m, const std::string& text, const std::string& name, const std::string& path = "",
                              const std::function<void(const CheckedModule&)>& seen = {}) {
    SourceManager sm;
    Diagnostics d(sm);
    FileId f = sm.add(path.empty() ? name + ".iql" : path, text);
    ModuleLibrary lib(sm, d, {});
    ModuleSource source{name, f, {{0, uint32_t(text.size())}}, {f, 0, 1}, "file"};  // the library keeps a pointer
    lib.add(source);
    const CheckedModule* cm = lib.get(name, {});
    if (!cm || cm->ast.kind != ast::ModuleKind::Shape) return -1;
    INFO(name << "\n" << d.render());
    REQUIRE(cm->ok);
    if (seen) seen(*cm);
    LowerContext ctx{m, {}, {}};
    int fn = lower_module(*cm, name, name, ctx);
    ir::Function w;
    w.name = "object";
    {
        ir::Builder b(m, w);
        ir::ValueId q = b.param("q", Type::vector(3));
        std::vector<ir::ValueId> args;
        for (const auto& p : cm->params) args.push_back(p.name == "p" ? q : b.constant(p.type, p.value));
        w.result = b.call(fn, args);
    }
    w.entry = true;
    m.functions.push_back(std::move(w));
    return int(m.functions.size()) - 1;
}

}  // namespace iqc::test
